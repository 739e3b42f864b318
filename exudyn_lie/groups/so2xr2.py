"""SO(2) x R^2, the planar decoupled group, embedded in SO(3) x R^3 as the motions in the
x-y plane.

Elements ``(Rz(theta), r)``, algebra ``X = (0, 0, theta, x, y, 0)`` (axes
:data:`ALGEBRA_AXES`), mixed velocity ``(omega_z, rdot_x, rdot_y)`` as for SO3xR3
(``TWIST = "mixed"``).  The group is abelian, so (eq. dexpSO3xR3 restricted to the plane)

    exp(X) = (Rz(theta), (x, y)),   dexp_X = dexpinv_X = I,   ad_X = 0 on the plane,

and no Taylor branch is needed.  Off-plane components pass through (``dexp`` identity);
``hat``, ``Ad``, ``ad``, composition and inverse are SO3xR3's, restricted.
"""
import math

import numpy as np
from numba import njit

from . import so3xr3
# abelian: dexp and its inverse are the identity, the same maps as the vector space R3's
from .rn import dexp, dexp_apply_into, dexpinv, dexpinv_apply_into  # noqa: F401

TWIST = "mixed"
ALGEBRA_AXES = (2, 3, 4)


@njit(cache=True)
def hat(X):
    return so3xr3.hat(X)


@njit(cache=True)
def vee(M):
    return so3xr3.vee(M)


@njit(cache=True)
def to_matrix(R, r):
    return so3xr3.to_matrix(R, r)


@njit(cache=True)
def from_matrix(C):
    return so3xr3.from_matrix(C)


@njit(cache=True)
def exp_into(X, R, r):
    """``(R, r) = (Rz(theta), (x, y, z))`` (no allocation)."""
    c = math.cos(X[2])
    s = math.sin(X[2])
    R[0, 0] = c
    R[0, 1] = -s
    R[0, 2] = 0.0
    R[1, 0] = s
    R[1, 1] = c
    R[1, 2] = 0.0
    R[2, 0] = 0.0
    R[2, 1] = 0.0
    R[2, 2] = 1.0
    r[0] = X[3]
    r[1] = X[4]
    r[2] = X[5]


@njit(cache=True)
def exp(X):
    R = np.empty((3, 3))
    r = np.empty(3)
    exp_into(X, R, r)
    return R, r


@njit(cache=True)
def log_into(R, r, X):
    X[0] = 0.0
    X[1] = 0.0
    X[2] = math.atan2(R[1, 0], R[0, 0])
    X[3] = r[0]
    X[4] = r[1]
    X[5] = r[2]


@njit(cache=True)
def log(R, r):
    X = np.empty(6)
    log_into(R, r, X)
    return X


@njit(cache=True)
def ad(X):
    """Zero on the plane (abelian); SO3xR3's for off-plane components."""
    M = so3xr3.ad(X)
    return M


@njit(cache=True)
def Ad_into(R, r, M):
    so3xr3.Ad_into(R, r, M)


@njit(cache=True)
def Ad(R, r):
    return so3xr3.Ad(R, r)


@njit(cache=True)
def compose_into(R1, r1, R2, r2, R, r):
    so3xr3.compose_into(R1, r1, R2, r2, R, r)


@njit(cache=True)
def compose(R1, r1, R2, r2):
    return so3xr3.compose(R1, r1, R2, r2)


@njit(cache=True)
def inverse_into(R, r, Ri, ri):
    so3xr3.inverse_into(R, r, Ri, ri)


@njit(cache=True)
def inverse(R, r):
    return so3xr3.inverse(R, r)
