"""SO(3) x R^3 (direct product): configurations C = (R, r), mixed velocities.

Conventions (see ``exudyn_lie.groups``): X = (xi, r), rotation first; velocity
V^m = (omega body-fixed, rdot spatial); composition (R1, r1)(R2, r2) =
(R1 R2, r1 + r2) (eq. MultDirectProduct).

hat(X) is the paper's faithful 7x7 representation (eq. Matrixso3xR3):

    hat(X) = [[xi^, 0, 0], [0, 0, r], [0, 0, 0]],   to_matrix(R, r) = [[R, 0, 0], [0, I, r], [0, 0, 1]]

(eq. MatrixSO3xR3); the matrix exponential of hat(X) is to_matrix(*exp(X)) and
the group product is the matrix product -- used by the tests as an oracle.

    exp(X)    = (exp(xi^), r)                     (eq. expSO3xR3)
    log(R, r) = (log R, r)
    ad_X      = [[xi^, 0], [0, 0]]                (eq. adso3xr3)
    Ad_(R,r)  = [[R, 0], [0, I]]
    dexp_X    = blockdiag(dexp_xi, I)             (eq. dexpSO3xR3, Vhdexp)
    dexpinv_X = blockdiag(dexpinv_xi, I)

Coefficients and switch points are those of ``so3``.
"""
import numpy as np
from numba import njit

from . import so3
from ._taylor import ad_series, DEXP_SERIES_COEFFS, DEXPINV_SERIES_COEFFS

TWIST = "mixed"     # velocity representation of a body on this group (interface.TWISTS)


@njit(cache=True)
def hat(X):
    """7x7 [[xi^, 0, 0], [0, 0, r], [0, 0, 0]] (eq. Matrixso3xR3)."""
    M = np.zeros((7, 7))
    M[0, 1] = -X[2]
    M[0, 2] = X[1]
    M[1, 0] = X[2]
    M[1, 2] = -X[0]
    M[2, 0] = -X[1]
    M[2, 1] = X[0]
    M[3, 6] = X[3]
    M[4, 6] = X[4]
    M[5, 6] = X[5]
    return M


@njit(cache=True)
def vee(M):
    out = np.empty(6)
    out[0] = 0.5 * (M[2, 1] - M[1, 2])
    out[1] = 0.5 * (M[0, 2] - M[2, 0])
    out[2] = 0.5 * (M[1, 0] - M[0, 1])
    out[3] = M[3, 6]
    out[4] = M[4, 6]
    out[5] = M[5, 6]
    return out


@njit(cache=True)
def to_matrix(R, r):
    """7x7 [[R, 0, 0], [0, I, r], [0, 0, 1]] (eq. MatrixSO3xR3)."""
    C = np.zeros((7, 7))
    C[0:3, 0:3] = R
    for i in range(3, 7):
        C[i, i] = 1.0
    C[3:6, 6] = r
    return C


@njit(cache=True)
def from_matrix(C):
    return np.ascontiguousarray(C[0:3, 0:3]), np.ascontiguousarray(C[3:6, 6])


@njit(cache=True)
def exp_into(X, R, r):
    """R[:], r[:] = exp(X) (eq. expSO3xR3), no allocation."""
    # the rotation part as a slice: the kernel's exp_compose (mbs/bodies.py) runs this
    # specialisation of so3.exp_into, whose fused multiply-adds fix the bits of every SO3xR3 run
    so3.exp_into(X[0:3], R)
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
    """X[:] = log(R, r) = (log R, r) (inverse of eq. expSO3xR3), no allocation."""
    so3.log_into(R, X)      # writes X[0:3] only
    X[3] = r[0]
    X[4] = r[1]
    X[5] = r[2]


@njit(cache=True)
def log(R, r):
    X = np.empty(6)
    log_into(R, r, X)
    return X


@njit(cache=True)
def dexp_apply_into(X, Y, out):
    """out[:] = dexp_X @ Y; out may alias Y."""
    so3.dexp_apply_into(X, Y, out)     # first three components
    out[3] = Y[3]
    out[4] = Y[4]
    out[5] = Y[5]


@njit(cache=True)
def dexpinv_apply_into(X, Y, out):
    """out[:] = dexpinv_X @ Y; out may alias Y."""
    so3.dexpinv_apply_into(X[0:3], Y[0:3], out[0:3])      # (slices: as exp_into)
    out[3] = Y[3]
    out[4] = Y[4]
    out[5] = Y[5]


@njit(cache=True)
def dexp(X):
    M = np.eye(6)
    M[0:3, 0:3] = so3.dexp(X[0:3])
    return M


@njit(cache=True)
def dexpinv(X):
    M = np.eye(6)
    M[0:3, 0:3] = so3.dexpinv(X[0:3])
    return M


@njit(cache=True)
def ad(X):
    M = np.zeros((6, 6))
    M[0:3, 0:3] = so3.hat(X[0:3])
    return M


@njit(cache=True)
def Ad_into(R, r, M):
    """M[:] = Ad_(R,r) = blockdiag(R, I) (6x6), no allocation (r is not used: the
    translation part of a direct product acts trivially)."""
    for i in range(6):
        for j in range(6):
            M[i, j] = 0.0
    so3.Ad_into(R, M)       # M[0:3, 0:3] = R
    M[3, 3] = 1.0
    M[4, 4] = 1.0
    M[5, 5] = 1.0


@njit(cache=True)
def Ad(R, r):
    M = np.empty((6, 6))
    Ad_into(R, r, M)
    return M


@njit(cache=True)
def dexp_series(X, nterms):
    return ad_series(ad(X), DEXP_SERIES_COEFFS, nterms)


@njit(cache=True)
def dexpinv_series(X, nterms):
    return ad_series(ad(X), DEXPINV_SERIES_COEFFS, nterms)


@njit(cache=True)
def compose_into(R1, r1, R2, r2, R, r):
    """(R, r) = (R1 R2, r1 + r2) (eq. MultDirectProduct), no allocation; outputs may
    alias inputs."""
    so3.compose_into(R1, R2, R)
    for i in range(3):
        r[i] = r1[i] + r2[i]


@njit(cache=True)
def compose(R1, r1, R2, r2):
    """(R1 R2, r1 + r2) (eq. MultDirectProduct)."""
    R = np.empty((3, 3))
    r = np.empty(3)
    compose_into(R1, r1, R2, r2, R, r)
    return R, r


@njit(cache=True)
def inverse_into(R, r, Ri, ri):
    """(Ri, ri) = (R^T, -r), no allocation; outputs may alias inputs."""
    so3.inverse_into(R, Ri)
    for i in range(3):
        ri[i] = -r[i]


@njit(cache=True)
def inverse(R, r):
    Ri = np.empty((3, 3))
    ri = np.empty(3)
    inverse_into(R, r, Ri, ri)
    return Ri, ri
