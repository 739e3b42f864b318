"""R^3, the vector-space group of point masses (Exudyn's ``NodePoint``, ``NodePoint2D`` and the
translational ``Node1D`` masses), in the shared interface of :mod:`.interface`.

An element is the pair ``(I, r)``: the rotation factor is the identity and stays so (a point
mass has no orientation); the algebra vector is ``X = (0, 0, 0, r)`` and the velocity is
``V = (0, v)`` with ``v = rdot`` spatial.  The group is abelian, so

    exp(X)    = (I, X[3:6])           log(I, r) = (0, r)
    ad_X      = 0                     Ad_(I, r) = identity
    dexp_X    = dexpinv_X = identity  (the MK stage map k_j = V_j, eq. MK1, is trivial)
    (I, r1)(I, r2) = (I, r1 + r2)

and a Munthe-Kaas method on R^3 is the underlying Runge-Kutta method.  Only the translation
part of the algebra is a coordinate of the group: :data:`ALGEBRA_AXES` names it (the interface
laws are tested on vectors in that subspace); the rotation part of an argument is ignored by ``exp`` and
``log`` returns 0 there.  ``hat`` is the 4x4 homogeneous matrix [[0, r], [0, 0]].

The kernel (:mod:`exudyn_lie.mbs.bodies`) keeps the rotation rows of such a body at zero: its
``M^-1`` has a zero rotation block, so ``omega`` stays 0 and ``R`` stays ``I``.
"""
import numpy as np
from numba import njit

#: velocity representation (interface.TWISTS): v = rdot spatial, as SO3xR3
TWIST = "mixed"
#: the axes of the 6-vector that are coordinates of this group (rotation first)
ALGEBRA_AXES = (3, 4, 5)


@njit(cache=True)
def hat(X):
    M = np.zeros((4, 4))
    M[0, 3] = X[3]
    M[1, 3] = X[4]
    M[2, 3] = X[5]
    return M


@njit(cache=True)
def vee(M):
    out = np.zeros(6)
    out[3] = M[0, 3]
    out[4] = M[1, 3]
    out[5] = M[2, 3]
    return out


@njit(cache=True)
def to_matrix(R, r):
    C = np.eye(4)
    for i in range(3):
        C[i, 3] = r[i]
    return C


@njit(cache=True)
def from_matrix(C):
    return np.eye(3), C[:3, 3].copy()


@njit(cache=True, _nrt=False)
def exp_into(X, R, r):
    for i in range(3):
        for j in range(3):
            R[i, j] = 1.0 if i == j else 0.0
        r[i] = X[3 + i]


@njit(cache=True)
def exp(X):
    R = np.empty((3, 3))
    r = np.empty(3)
    exp_into(X, R, r)
    return R, r


@njit(cache=True, _nrt=False)
def log_into(R, r, X):
    for i in range(3):
        X[i] = 0.0
        X[3 + i] = r[i]


@njit(cache=True)
def log(R, r):
    X = np.empty(6)
    log_into(R, r, X)
    return X


@njit(cache=True, _nrt=False)
def dexp_apply_into(X, Y, out):
    for i in range(6):
        out[i] = Y[i]


@njit(cache=True, _nrt=False)
def dexpinv_apply_into(X, Y, out):
    for i in range(6):
        out[i] = Y[i]


@njit(cache=True)
def dexp(X):
    return np.eye(6)


@njit(cache=True)
def dexpinv(X):
    return np.eye(6)


@njit(cache=True)
def ad(X):
    return np.zeros((6, 6))


@njit(cache=True, _nrt=False)
def Ad_into(R, r, M):
    for i in range(6):
        for j in range(6):
            M[i, j] = 1.0 if i == j else 0.0


@njit(cache=True)
def Ad(R, r):
    return np.eye(6)


@njit(cache=True, _nrt=False)
def compose_into(R1, r1, R2, r2, R, r):
    for i in range(3):
        r[i] = r1[i] + r2[i]
        for j in range(3):
            R[i, j] = 1.0 if i == j else 0.0


@njit(cache=True)
def compose(R1, r1, R2, r2):
    R = np.empty((3, 3))
    r = np.empty(3)
    compose_into(R1, r1, R2, r2, R, r)
    return R, r


@njit(cache=True, _nrt=False)
def inverse_into(R, r, Ri, ri):
    for i in range(3):
        ri[i] = -r[i]
        for j in range(3):
            Ri[i, j] = 1.0 if i == j else 0.0


@njit(cache=True)
def inverse(R, r):
    Ri = np.empty((3, 3))
    ri = np.empty(3)
    inverse_into(R, r, Ri, ri)
    return Ri, ri
