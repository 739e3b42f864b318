"""SE(2), the planar screw group, embedded in SE(3) as the motions in the x-y plane.

Elements and algebra use the shared signatures (:mod:`.interface`): ``(R, r)`` with
``R = Rz(theta)`` and a 6-vector ``X = (0, 0, theta, u1, u2, 0)``.  The planar algebra is
the axes :data:`ALGEBRA_AXES` of the 6-vector; components off the plane are not used by a
planar body (its velocity stays in the plane) -- the maps pass them through unchanged
(``dexp``/``dexpinv`` act as the identity there, ``exp`` as a z translation).

Velocity: body-fixed twist ``(omega_z, v_x, v_y)`` as for SE3 (``TWIST = "body"``).
Composition, inverse, ``Ad``, ``ad``, ``hat`` are the restriction of SE(3)'s (exact).

Closed forms (derived here, with ``J = [[0, -1], [1, 0]]``, ``ad_X (phi, w) = (0, theta J w
- phi J u)``; they are SE(3)'s maps restricted to the plane, where the 6x6 ``ad`` series
collapses to functions of the 2x2 ``theta J`` whose eigenvalues are ``+-i theta``):

    exp(X)      = (Rz(theta), V u),         V  = A I + theta B J
    dexp_X  (phi, w) = (phi, V w - phi W J u),          W = B I + theta C J
    dexpinv_X (phi, z) = (phi, Vi z + phi (J u / 2 + theta D u)),  Vi = (1 - theta^2 D) I - (theta/2) J

with SO(3)'s coefficients A = sin t/t, B = (1-cos t)/t^2, C = (t - sin t)/t^3,
D = (1 - (t/2) cot(t/2))/t^2 at t = |theta| (so the Taylor branches and switch points are
so3's, derived in ``_taylor``: C and D cancel, A and B do not).  ``Vi = V^-1`` because
(A + i t B)(1 - t^2 D - i t/2) = 1; the dexpinv translation follows from
``V^-1 W J u = (J/2 + t D) u`` (as functions of ``theta J``: f/g = (1 - z/(e^z - 1))/z).
"""
import math

import numpy as np
from numba import njit

from . import se3, so3
from ._taylor import FM as _FM

TWIST = "body"
ALGEBRA_AXES = (2, 3, 4)


@njit(cache=True, fastmath=_FM, forceinline=False)
def hat(X):
    return se3.hat(X)


@njit(cache=True, fastmath=_FM, forceinline=False)
def vee(M):
    return se3.vee(M)


@njit(cache=True, fastmath=_FM, forceinline=False)
def to_matrix(R, r):
    return se3.to_matrix(R, r)


@njit(cache=True, fastmath=_FM, forceinline=False)
def from_matrix(C):
    return se3.from_matrix(C)


@njit(cache=True, fastmath=_FM, forceinline=False)
def exp_into(X, R, r):
    """``(R, r) = exp(X)``: ``Rz(theta)``, ``V u`` (no allocation)."""
    th = X[2]
    A, B = so3.coef_AB(th * th)
    c = math.cos(th)
    s = math.sin(th)
    R[0, 0] = c
    R[0, 1] = -s
    R[0, 2] = 0.0
    R[1, 0] = s
    R[1, 1] = c
    R[1, 2] = 0.0
    R[2, 0] = 0.0
    R[2, 1] = 0.0
    R[2, 2] = 1.0
    tB = th * B
    r[0] = A * X[3] - tB * X[4]
    r[1] = tB * X[3] + A * X[4]
    r[2] = X[5]


@njit(cache=True, fastmath=_FM, forceinline=False)
def exp(X):
    R = np.empty((3, 3))
    r = np.empty(3)
    exp_into(X, R, r)
    return R, r


@njit(cache=True, fastmath=_FM, forceinline=False)
def log_into(R, r, X):
    """``X = log(R, r)``, ``|theta| <= pi``: ``theta = atan2``, ``u = V^-1 r``."""
    th = math.atan2(R[1, 0], R[0, 0])
    cc = 1.0 - th * th * so3.coef_D(th * th)
    h = 0.5 * th
    X[0] = 0.0
    X[1] = 0.0
    X[2] = th
    X[3] = cc * r[0] + h * r[1]
    X[4] = cc * r[1] - h * r[0]
    X[5] = r[2]


@njit(cache=True, fastmath=_FM, forceinline=False)
def log(R, r):
    X = np.empty(6)
    log_into(R, r, X)
    return X


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexp_apply_into(X, Y, out):
    """``out = dexp_X Y`` (right-trivialised); ``out`` may alias ``Y``."""
    th = X[2]
    A, B, C = so3.coef_ABC(th * th)
    tB = th * B
    tC = th * C
    u1 = X[3]
    u2 = X[4]
    ph = Y[2]
    w1 = Y[3]
    w2 = Y[4]
    out[0] = Y[0]
    out[1] = Y[1]
    out[2] = ph
    out[3] = A * w1 - tB * w2 + ph * (B * u2 + tC * u1)
    out[4] = tB * w1 + A * w2 + ph * (tC * u2 - B * u1)
    out[5] = Y[5]


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexpinv_apply_into(X, Y, out):
    """``out = dexp_X^-1 Y``; ``out`` may alias ``Y``."""
    th = X[2]
    D = so3.coef_D(th * th)
    tD = th * D
    cc = 1.0 - th * tD
    h = 0.5 * th
    u1 = X[3]
    u2 = X[4]
    ph = Y[2]
    z1 = Y[3]
    z2 = Y[4]
    out[0] = Y[0]
    out[1] = Y[1]
    out[2] = ph
    out[3] = cc * z1 + h * z2 + ph * (tD * u1 - 0.5 * u2)
    out[4] = cc * z2 - h * z1 + ph * (tD * u2 + 0.5 * u1)
    out[5] = Y[5]


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexp(X):
    M = np.zeros((6, 6))
    e = np.zeros(6)
    col = np.zeros(6)
    for k in range(6):
        e[:] = 0.0
        e[k] = 1.0
        dexp_apply_into(X, e, col)
        M[:, k] = col
    return M


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexpinv(X):
    M = np.zeros((6, 6))
    e = np.zeros(6)
    col = np.zeros(6)
    for k in range(6):
        e[:] = 0.0
        e[k] = 1.0
        dexpinv_apply_into(X, e, col)
        M[:, k] = col
    return M


@njit(cache=True, fastmath=_FM, forceinline=False)
def ad(X):
    return se3.ad(X)


@njit(cache=True, fastmath=_FM, forceinline=False)
def Ad_into(R, r, M):
    se3.Ad_into(R, r, M)


@njit(cache=True, fastmath=_FM, forceinline=False)
def Ad(R, r):
    return se3.Ad(R, r)


@njit(cache=True, fastmath=_FM, forceinline=False)
def compose_into(R1, r1, R2, r2, R, r):
    se3.compose_into(R1, r1, R2, r2, R, r)


@njit(cache=True, fastmath=_FM, forceinline=False)
def compose(R1, r1, R2, r2):
    return se3.compose(R1, r1, R2, r2)


@njit(cache=True, fastmath=_FM, forceinline=False)
def inverse_into(R, r, Ri, ri):
    se3.inverse_into(R, r, Ri, ri)


@njit(cache=True, fastmath=_FM, forceinline=False)
def inverse(R, r):
    return se3.inverse(R, r)
