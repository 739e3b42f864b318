"""Unit quaternions / Euler parameters Q = (q0, q1, q2, q3), scalar first.

Paper, appendix "Dual quaternions" / "Euler parameters" (eqs. DE, Hh):

    Q^+ = [[q0, -q^T], [q, q0 I + q^]]   Q P = Q^+ P       (hamilton_plus)
    Q^- = [[q0, -q^T], [q, q0 I - q^]]   P Q = Q^- P       (hamilton_minus)
    D(Q) = [-q, q0 I + q^],  E(Q) = [-q, q0 I - q^]       (3x4, eq. DE)
    R = D E^T = (q0^2 - q.q) I + 2 q q^T + 2 q0 q^        (Hamilton product,
                                                          active rotation)
    Q = (cos(t/2), sin(t/2) xi/t) <-> R = exp(xi^)

Angular velocity (checked by finite differences in tests/test_quaternions.py):
with these definitions the BODY-FIXED angular velocity (omega^ = R^T Rdot) is

    omega_body = 2 E(Q) Qdot,         Qdot = 1/2 E(Q)^T omega = 1/2 Q (0, omega),

while 2 D(Q) Qdot = R omega_body is the SPATIAL angular velocity.  The paper's
eq. Hh writes  V^m = 2 [[D, 0], [0, I]] (Qdot, rdot); since V^m = (omega body,
rdot) (eq. hybridvel), the consistent map is

    Hm(Q) = [[2 E(Q), 0], [0, I]]   (6x7, acting on (Qdot, rdot)),

i.e. E instead of D, and no factor 2 on the translational identity block.
"""
import math

import numpy as np
from numba import njit

from . import so3
from ._taylor import mv


@njit(cache=True)
def hamilton_plus(Q):
    """Q^+ : Q P = Q^+ P."""
    q0, q1, q2, q3 = Q[0], Q[1], Q[2], Q[3]
    M = np.empty((4, 4))
    M[0, 0] = q0
    M[0, 1] = -q1
    M[0, 2] = -q2
    M[0, 3] = -q3
    M[1, 0] = q1
    M[1, 1] = q0
    M[1, 2] = -q3
    M[1, 3] = q2
    M[2, 0] = q2
    M[2, 1] = q3
    M[2, 2] = q0
    M[2, 3] = -q1
    M[3, 0] = q3
    M[3, 1] = -q2
    M[3, 2] = q1
    M[3, 3] = q0
    return M


@njit(cache=True)
def hamilton_minus(Q):
    """Q^- : P Q = Q^- P."""
    q0, q1, q2, q3 = Q[0], Q[1], Q[2], Q[3]
    M = np.empty((4, 4))
    M[0, 0] = q0
    M[0, 1] = -q1
    M[0, 2] = -q2
    M[0, 3] = -q3
    M[1, 0] = q1
    M[1, 1] = q0
    M[1, 2] = q3
    M[1, 3] = -q2
    M[2, 0] = q2
    M[2, 1] = -q3
    M[2, 2] = q0
    M[2, 3] = q1
    M[3, 0] = q3
    M[3, 1] = q2
    M[3, 2] = -q1
    M[3, 3] = q0
    return M


@njit(cache=True)
def _DE(Q, sgn):
    """[-q, q0 I + sgn q^]."""
    q0, q1, q2, q3 = Q[0], Q[1], Q[2], Q[3]
    M = np.empty((3, 4))
    M[0, 0] = -q1
    M[1, 0] = -q2
    M[2, 0] = -q3
    M[0, 1] = q0
    M[1, 2] = q0
    M[2, 3] = q0
    M[0, 2] = -sgn * q3
    M[0, 3] = sgn * q2
    M[1, 1] = sgn * q3
    M[1, 3] = -sgn * q1
    M[2, 1] = -sgn * q2
    M[2, 2] = sgn * q1
    return M


@njit(cache=True)
def D(Q):
    """3x4 [-q, q0 I + q^] (eq. DE); D Q = 0, D(Q) P = vec(P Q*)."""
    return _DE(Q, 1.0)


@njit(cache=True)
def E(Q):
    """3x4 [-q, q0 I - q^] (eq. DE); E Q = 0, E(Q) P = vec(Q* P)."""
    return _DE(Q, -1.0)


@njit(cache=True)
def multiply(Q, P):
    """Hamilton product Q P = (q0 p0 - q.p, q0 p + p0 q + q x p)."""
    out = np.empty(4)
    q0, q1, q2, q3 = Q[0], Q[1], Q[2], Q[3]
    p0, p1, p2, p3 = P[0], P[1], P[2], P[3]
    out[0] = q0 * p0 - q1 * p1 - q2 * p2 - q3 * p3
    out[1] = q0 * p1 + p0 * q1 + q2 * p3 - q3 * p2
    out[2] = q0 * p2 + p0 * q2 + q3 * p1 - q1 * p3
    out[3] = q0 * p3 + p0 * q3 + q1 * p2 - q2 * p1
    return out


@njit(cache=True)
def conjugate(Q):
    out = np.empty(4)
    out[0] = Q[0]
    out[1] = -Q[1]
    out[2] = -Q[2]
    out[3] = -Q[3]
    return out


@njit(cache=True)
def normalize(Q):
    n = math.sqrt(Q[0] * Q[0] + Q[1] * Q[1] + Q[2] * Q[2] + Q[3] * Q[3])
    return Q / n


@njit(cache=True)
def to_matrix(Q):
    """R = D E^T = (q0^2 - q.q) I + 2 q q^T + 2 q0 q^  (Q assumed unit)."""
    q0, q1, q2, q3 = Q[0], Q[1], Q[2], Q[3]
    R = np.empty((3, 3))
    c = q0 * q0 - q1 * q1 - q2 * q2 - q3 * q3
    R[0, 0] = c + 2.0 * q1 * q1
    R[1, 1] = c + 2.0 * q2 * q2
    R[2, 2] = c + 2.0 * q3 * q3
    R[0, 1] = 2.0 * (q1 * q2 - q0 * q3)
    R[1, 0] = 2.0 * (q1 * q2 + q0 * q3)
    R[0, 2] = 2.0 * (q1 * q3 + q0 * q2)
    R[2, 0] = 2.0 * (q1 * q3 - q0 * q2)
    R[1, 2] = 2.0 * (q2 * q3 - q0 * q1)
    R[2, 1] = 2.0 * (q2 * q3 + q0 * q1)
    return R


@njit(cache=True)
def from_matrix(R):
    """Unit quaternion of R, q0 >= 0 (Shepperd's method, see so3.quat_from_matrix)."""
    return so3.quat_from_matrix(R)


@njit(cache=True)
def from_rotvec(xi):
    """Q = (cos(t/2), sin(t/2)/t xi).  sin(t/2)/t = A(t/2)/2, A = sin(x)/x (so3 series)."""
    u = xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2]
    Q = np.empty(4)
    uh = 0.25 * u
    if uh < so3.U_SWITCH_EXP:
        A, B = so3.coef_AB(uh)
        Q[0] = 1.0 - uh * B             # cos x = 1 - x^2 (1 - cos x)/x^2
        f = 0.5 * A
    else:
        t = math.sqrt(u)
        Q[0] = math.cos(0.5 * t)
        f = math.sin(0.5 * t) / t
    Q[1] = f * xi[0]
    Q[2] = f * xi[1]
    Q[3] = f * xi[2]
    return Q


@njit(cache=True)
def to_rotvec(Q):
    """Rotation vector with |xi| <= pi (Q and -Q give the same result)."""
    if Q[0] < 0.0:
        return so3.rotvec_from_quat(-Q)
    return so3.rotvec_from_quat(Q)


@njit(cache=True)
def qdot_from_omega(Q, omega):
    """Qdot = 1/2 E(Q)^T omega = 1/2 Q (0, omega), omega BODY-fixed."""
    q0, q1, q2, q3 = Q[0], Q[1], Q[2], Q[3]
    w0, w1, w2 = omega[0], omega[1], omega[2]
    out = np.empty(4)
    out[0] = 0.5 * (-q1 * w0 - q2 * w1 - q3 * w2)
    out[1] = 0.5 * (q0 * w0 + q2 * w2 - q3 * w1)
    out[2] = 0.5 * (q0 * w1 + q3 * w0 - q1 * w2)
    out[3] = 0.5 * (q0 * w2 + q1 * w1 - q2 * w0)
    return out


@njit(cache=True)
def omega_from_qdot(Q, Qdot):
    """omega_body = 2 E(Q) Qdot."""
    return 2.0 * mv(E(Q), Qdot)


@njit(cache=True)
def Hm(Q):
    """6x7 mixed-velocity map (eq. Hh, corrected): (omega_body, rdot) = Hm(Q) (Qdot, rdot)."""
    M = np.zeros((6, 7))
    M[0:3, 0:4] = 2.0 * E(Q)
    M[3, 4] = 1.0
    M[4, 5] = 1.0
    M[5, 6] = 1.0
    return M


@njit(cache=True)
def rate_from_mixed(Q, Vm):
    """(Qdot, rdot) from V^m = (omega_body, rdot): a right inverse of Hm(Q) (unit Q),
    tangent to |Q| = 1 (Q . Qdot = 0)."""
    out = np.empty(7)
    out[0:4] = qdot_from_omega(Q, Vm[0:3])
    out[4:7] = Vm[3:6]
    return out
