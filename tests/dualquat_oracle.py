"""Unit dual quaternions Qh = (Q, Qe) (8-vector) as global coordinates on SE(3): a test oracle
(the vector-space formulation ODEvec2 of tests/vector_space_oracle.py uses them).

Paper, appendix "Proper rigid body motions in terms of dual quaternions":

    Qh Ph = Qh^+ Ph = Ph^- Qh,   Qh^+- = [[Q^+-, 0], [Qe^+-, Q^+-]]
    (R, r) -> Q = quaternion of R,  Qe = 1/2 (0, r) Q        (so Q . Qe = 0)
    (0, r) = 2 (Q^-)^T Qe = 2 Qe Q*                          (eq. Qpos)

so the dual-quaternion product represents the SE(3) product (eq. MultSE3).

Velocities (derived from Qh* Qhdot, checked numerically in the tests), with the
body twist V = (omega, v), v = R^T rdot, and the mixed V^m = (omega, rdot):

    Qhdot = 1/2 Qh (0, omega ; 0, v)                         (qhdot_from_twist)
    V   = H(Qh)  Qhdot,  H  = [[2E(Q), 0], [-2 E(Q) D(Q)^T D(Qe), 2E(Q)]]
    V^m = Hm(Qh) Qhdot,  Hm = [[2E(Q), 0], [-2 D(Qe), 2 D(Q)]]

Compared with the paper (eqs. Hdual, Hhdual): the paper's H lacks the factor 2
(its Hm has it), and both use D(Q) in the upper-left block, which gives the
SPATIAL angular velocity 2 D(Q) Qdot = R omega; E(Q) gives the body-fixed omega
that V and V^m contain.  The lower rows agree with the paper.

The rate map Qhdot = 1/2 Qh Vh keeps |Q| = 1 and Q . Qe = 0 exactly (it is
tangent to the constraint manifold), and H(Qh) Qhdot = V for unit Qh.
"""
import numpy as np
from numba import njit

from exudyn_lie.groups import quaternion as quat
from exudyn_lie.groups import se3
from exudyn_lie.groups._taylor import mm, mv


@njit(cache=True)
def plus(Qh):
    M = np.zeros((8, 8))
    P = quat.hamilton_plus(Qh[0:4])
    M[0:4, 0:4] = P
    M[4:8, 4:8] = P
    M[4:8, 0:4] = quat.hamilton_plus(Qh[4:8])
    return M


@njit(cache=True)
def minus(Qh):
    M = np.zeros((8, 8))
    P = quat.hamilton_minus(Qh[0:4])
    M[0:4, 0:4] = P
    M[4:8, 4:8] = P
    M[4:8, 0:4] = quat.hamilton_minus(Qh[4:8])
    return M


@njit(cache=True)
def multiply(Qh, Ph):
    """(Q P, Q Pe + Qe P)."""
    out = np.empty(8)
    Q = Qh[0:4]
    P = Ph[0:4]
    out[0:4] = quat.multiply(Q, P)
    out[4:8] = quat.multiply(Q, Ph[4:8]) + quat.multiply(Qh[4:8], P)
    return out


@njit(cache=True)
def conjugate(Qh):
    out = np.empty(8)
    out[0:4] = quat.conjugate(Qh[0:4])
    out[4:8] = quat.conjugate(Qh[4:8])
    return out


@njit(cache=True)
def from_pose(R, r):
    """Qh of (R, r): Q from R (q0 >= 0), Qe = 1/2 (0, r) Q."""
    out = np.empty(8)
    Q = quat.from_matrix(R)
    out[0:4] = Q
    pr = np.zeros(4)
    pr[1:4] = r
    out[4:8] = 0.5 * quat.multiply(pr, Q)
    return out


@njit(cache=True)
def to_pose(Qh):
    """(R, r): R = D E^T, (0, r) = 2 (Q^-)^T Qe (eq. Qpos)."""
    Q = Qh[0:4]
    R = quat.to_matrix(Q)
    p = 2.0 * mv(np.ascontiguousarray(quat.hamilton_minus(Q).T), Qh[4:8])
    return R, np.ascontiguousarray(p[1:4])


@njit(cache=True)
def from_screw(X):
    """Dual quaternion of exp(X) in SE(3)."""
    R, r = se3.exp(X)
    return from_pose(R, r)


@njit(cache=True)
def to_screw(Qh):
    """Screw coordinates X = se3.log(to_pose(Qh)) (|xi| <= pi)."""
    R, r = to_pose(Qh)
    return se3.log(R, r)


@njit(cache=True)
def H(Qh):
    """6x8 body-twist map V = H(Qh) Qhdot (eq. Hdual, corrected; see module doc)."""
    Q = Qh[0:4]
    EQ = quat.E(Q)
    M = np.zeros((6, 8))
    M[0:3, 0:4] = 2.0 * EQ
    M[3:6, 4:8] = 2.0 * EQ
    M[3:6, 0:4] = -2.0 * mm(EQ, mm(np.ascontiguousarray(quat.D(Q).T), quat.D(Qh[4:8])))
    return M


@njit(cache=True)
def Hm(Qh):
    """6x8 mixed-velocity map V^m = Hm(Qh) Qhdot (eq. Hhdual, corrected)."""
    Q = Qh[0:4]
    M = np.zeros((6, 8))
    M[0:3, 0:4] = 2.0 * quat.E(Q)
    M[3:6, 4:8] = 2.0 * quat.D(Q)
    M[3:6, 0:4] = -2.0 * quat.D(Qh[4:8])
    return M


@njit(cache=True)
def qhdot_from_twist(Qh, V):
    """Qhdot = 1/2 Qh (0, omega ; 0, v) for the body twist V = (omega, v)."""
    Vh = np.zeros(8)
    Vh[1:4] = V[0:3]
    Vh[5:8] = V[3:6]
    return 0.5 * multiply(Qh, Vh)


@njit(cache=True)
def qhdot_from_mixed(Qh, Vm):
    """Qhdot for the mixed velocity V^m = (omega, rdot): v = R^T rdot."""
    R = quat.to_matrix(Qh[0:4])
    V = np.empty(6)
    V[0:3] = Vm[0:3]
    V[3:6] = mv(np.ascontiguousarray(R.T), Vm[3:6])
    return qhdot_from_twist(Qh, V)
