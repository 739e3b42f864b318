"""SE(3) = SO(3) |x R^3 (semidirect product): frame transformations C = (R, r).

Conventions (see ``exudyn_lie.groups``): X = (xi, eta), rotation first; twists
V = (omega, v) body-fixed; composition (R1, r1)(R2, r2) = (R1 R2, r1 + R1 r2)
(eq. MultSE3); hat(X) is the 4x4 matrix [[xi^, eta], [0, 0]].

    exp(X)     = (exp(xi^), dexp_xi eta)                         (eq. expX)
    log(R, r)  = (log R, dexpinv_xi r)
    ad_X       = [[xi^, 0], [eta^, xi^]]                         (eq. adse3)
    Ad_(R,r)   = [[R, 0], [r^ R, R]],   hat(Ad_C X) = C hat(X) C^-1
    dexp_X     = [[J, 0], [P, J]],       J = dexp_xi             (eq. dexpSE3)
    dexpinv_X  = [[J^-1, 0], [U, J^-1]]                         (eq. dexpInvSE3Park)

with, t = |xi|, k = xi.eta = h t^2 (h the pitch), W = xi^, N = eta^:

    P = B N + C (N W + W N) + k (Q3 W + Q4 W^2)
    U = -N/2 + D (N W + W N) + k E2 W^2

    Q3 = (alpha - beta)/t^2              = (A - 2B)/t^2
       = -1/12 + u/180 - u^2/6720 + u^3/453600 - ...
    Q4 = (beta/2 - 3(1 - alpha)/t^2)/t^2 = (B - 3C)/t^2
       = -1/60 + u/1260 - u^2/60480 + u^3/4989600 - ...
    E2 = (1/beta + gamma - 2)/t^4,  gamma = (t/2)cot(t/2)
       = 1/360 + u/7560 + u^2/201600 + u^3/5987520 + ...

(A, B, C, D as in so3; alpha = A, beta = 2B.)  These were derived from the
Frechet derivative of f(ad) with f(z) = (e^z-1)/z resp. z/(e^z-1), splitting
eta into its part along xi (which commutes) and the part orthogonal to xi
(for which W N W = 0, W^2 N + N W^2 = -t^2 N).  The paper's printed (P1) and
U differ: see the note at the end of this docstring.

Derivation is checked in the tests against the ad-series (eq. dexp, eq.
dexpInvSeries), against Selig's form (eq. dexpInvSE3) and by finite differences.

Switch points (rule in ``_taylor``): T_SWITCH_DEXP = (180/32)^(1/4) = 1.540
(B, C, Q3, Q4 with 10, 10, 10, 9 terms; driven by Q4's O(t^-4) cancellation),
T_SWITCH_DEXPINV = (1440/32)^(1/4) = 2.590 (D, E2 with 21, 23 terms; driven by
E2), T_SWITCH_SELIG = 2.590 (S2, S4: 22, 23 terms).  exp/log use the so3 switch
points.  dexpinv is singular at |xi| = 2 pi (the series converge for |xi| < 2 pi).

Note on the paper's formulas (eq. P1 and the U below eq. dexpInvSE3Park): as
printed, P has  h (alpha-beta)/|xi| xi^  and  h/|xi|^2 (beta/2 - 3(1-alpha)/|xi|) xi^2,
and U has  h/|xi|^3 (1/beta + gamma - 2) xi^2  with  gamma := (2/|xi|) cot(|xi|/2).
These are dimensionally inconsistent and do not reproduce dexp / dexpinv (the
printed P even diverges like 1/|xi| as xi -> 0).  The forms that agree with the
series are  h (alpha-beta) xi^,  h (beta/2 - 3(1-alpha)/|xi|^2) xi^2,
h/|xi|^2 (1/beta + gamma - 2) xi^2  with  gamma = (|xi|/2) cot(|xi|/2).
"""
import math

import numpy as np
from numba import njit

from . import _taylor
from ._taylor import FM as _FM
from . import so3
from ._taylor import ad_series, horner, mm, DEXP_SERIES_COEFFS, DEXPINV_SERIES_COEFFS

TWIST = "body"      # velocity representation of a body on this group (interface.TWISTS)

# ---------------------------------------------------------------- switch points
T_SWITCH_DEXP, _NP = _taylor.plan(("B", "C", "Q3", "Q4"))
U_SWITCH_DEXP = T_SWITCH_DEXP ** 2
_PB = _taylor.coeffs("B", _NP["B"])
_PC = _taylor.coeffs("C", _NP["C"])
_PQ3 = _taylor.coeffs("Q3", _NP["Q3"])
_PQ4 = _taylor.coeffs("Q4", _NP["Q4"])

T_SWITCH_DEXPINV, _NU = _taylor.plan(("D", "E2"))
U_SWITCH_DEXPINV = T_SWITCH_DEXPINV ** 2
_UD = _taylor.coeffs("D", _NU["D"])
_UE2 = _taylor.coeffs("E2", _NU["E2"])

T_SWITCH_SELIG, _NS = _taylor.plan(("S2", "S4"))
U_SWITCH_SELIG = T_SWITCH_SELIG ** 2
_S2 = _taylor.coeffs("S2", _NS["S2"])
_S4 = _taylor.coeffs("S4", _NS["S4"])

NTERMS = {"dexp": dict(_NP), "dexpinv": dict(_NU), "selig": dict(_NS)}


# ------------------------------------------------------------ scalar coefficients
@njit(cache=True, fastmath=_FM, forceinline=False)
def series_dexp(u):
    return horner(_PB, u), horner(_PC, u), horner(_PQ3, u), horner(_PQ4, u)


@njit(cache=True, fastmath=_FM, forceinline=False)
def closed_dexp(u):
    t = math.sqrt(u)
    s = math.sin(0.5 * t)
    c = math.cos(0.5 * t)
    sint = 2.0 * s * c
    A = sint / t
    B = 2.0 * s * s / u
    C = (t - sint) / (u * t)
    return B, C, (A - 2.0 * B) / u, (B - 3.0 * C) / u


@njit(cache=True, fastmath=_FM, forceinline=False)
def coef_dexp(u):
    """(B, C, Q3, Q4) at u = |xi|^2."""
    if u < U_SWITCH_DEXP:
        return series_dexp(u)
    return closed_dexp(u)


@njit(cache=True, fastmath=_FM, forceinline=False)
def series_dexpinv(u):
    return horner(_UD, u), horner(_UE2, u)


@njit(cache=True, fastmath=_FM, forceinline=False)
def closed_dexpinv(u):
    t = math.sqrt(u)
    h = 0.5 * t
    g = h / math.tan(h)                        # gamma = (t/2) cot(t/2)
    # 1/beta = h^2/sin^2 h = h^2 + gamma^2, so 1/beta + gamma - 2 = h^2 + (gamma+2)(gamma-1)
    return (1.0 - g) / u, (h * h + (g + 2.0) * (g - 1.0)) / (u * u)


@njit(cache=True, fastmath=_FM, forceinline=False)
def coef_dexpinv(u):
    """(D, E2) at u = |xi|^2."""
    if u < U_SWITCH_DEXPINV:
        return series_dexpinv(u)
    return closed_dexpinv(u)


@njit(cache=True, fastmath=_FM, forceinline=False)
def series_selig(u):
    return horner(_S2, u), horner(_S4, u)


@njit(cache=True, fastmath=_FM, forceinline=False)
def closed_selig(u):
    t = math.sqrt(u)
    s = math.sin(0.5 * t)
    c = math.cos(0.5 * t)
    sint = 2.0 * s * c
    cm1 = -2.0 * s * s                         # cos t - 1
    return (2.0 / u + (t + 3.0 * sint) / (4.0 * t * cm1),
            1.0 / (u * u) + (t + sint) / (4.0 * u * t * cm1))


@njit(cache=True, fastmath=_FM, forceinline=False)
def coef_selig(u):
    """Selig's ad^2 and ad^4 coefficients (eq. dexpInvSE3) at u = |xi|^2."""
    if u < U_SWITCH_SELIG:
        return series_selig(u)
    return closed_selig(u)


# ------------------------------------------------------------------- hat / vee
@njit(cache=True, fastmath=_FM, forceinline=False)
def hat(X):
    """4x4 [[xi^, eta], [0, 0]]."""
    M = np.zeros((4, 4))
    M[0, 1] = -X[2]
    M[0, 2] = X[1]
    M[1, 0] = X[2]
    M[1, 2] = -X[0]
    M[2, 0] = -X[1]
    M[2, 1] = X[0]
    M[0, 3] = X[3]
    M[1, 3] = X[4]
    M[2, 3] = X[5]
    return M


@njit(cache=True, fastmath=_FM, forceinline=False)
def vee(M):
    out = np.empty(6)
    out[0] = 0.5 * (M[2, 1] - M[1, 2])
    out[1] = 0.5 * (M[0, 2] - M[2, 0])
    out[2] = 0.5 * (M[1, 0] - M[0, 1])
    out[3] = M[0, 3]
    out[4] = M[1, 3]
    out[5] = M[2, 3]
    return out


@njit(cache=True, fastmath=_FM, forceinline=False)
def to_matrix(R, r):
    """4x4 homogeneous matrix of (R, r) (eq. C)."""
    C = np.zeros((4, 4))
    C[0:3, 0:3] = R
    C[0:3, 3] = r
    C[3, 3] = 1.0
    return C


@njit(cache=True, fastmath=_FM, forceinline=False)
def from_matrix(C):
    return np.ascontiguousarray(C[0:3, 0:3]), np.ascontiguousarray(C[0:3, 3])


# ------------------------------------------------------------------- exp / log
@njit(cache=True, fastmath=_FM, forceinline=False)
def exp_into(X, R, r):
    """R[:], r[:] = exp(X) (eq. expX), no allocation."""
    x0 = X[0]
    x1 = X[1]
    x2 = X[2]
    e0 = X[3]
    e1 = X[4]
    e2 = X[5]
    a00 = x0 * x0
    a11 = x1 * x1
    a22 = x2 * x2
    A, B, C = so3.coef_ABC(a00 + a11 + a22)
    b01 = B * x0 * x1
    b02 = B * x0 * x2
    b12 = B * x1 * x2
    R[0, 0] = 1.0 - B * (a11 + a22)
    R[1, 1] = 1.0 - B * (a00 + a22)
    R[2, 2] = 1.0 - B * (a00 + a11)
    R[0, 1] = b01 - A * x2
    R[1, 0] = b01 + A * x2
    R[0, 2] = b02 + A * x1
    R[2, 0] = b02 - A * x1
    R[1, 2] = b12 - A * x0
    R[2, 1] = b12 + A * x0
    # r = dexp_xi eta = eta + B xi x eta + C xi x (xi x eta)
    c0 = x1 * e2 - x2 * e1
    c1 = x2 * e0 - x0 * e2
    c2 = x0 * e1 - x1 * e0
    r[0] = e0 + B * c0 + C * (x1 * c2 - x2 * c1)
    r[1] = e1 + B * c1 + C * (x2 * c0 - x0 * c2)
    r[2] = e2 + B * c2 + C * (x0 * c1 - x1 * c0)


@njit(cache=True, fastmath=_FM, forceinline=False)
def exp(X):
    R = np.empty((3, 3))
    r = np.empty(3)
    exp_into(X, R, r)
    return R, r


@njit(cache=True, fastmath=_FM, forceinline=False)
def log_into(R, r, X):
    """X[:] = log(R, r) = (log R, dexpinv_xi r) (inverse of eq. expX), |xi| <= pi;
    no allocation (X[3:6] is a view)."""
    so3.log_into(R, X)                          # X[0:3] = xi
    so3.dexpinv_apply_into(X, r, X[3:6])        # eta = dexp_xi^-1 r (eq. dexpInvSO3)


@njit(cache=True, fastmath=_FM, forceinline=False)
def log(R, r):
    """X = (xi, eta) with exp(X) = (R, r), |xi| <= pi."""
    X = np.empty(6)
    log_into(R, r, X)
    return X


# ------------------------------------------------------------ dexp / dexpinv
@njit(cache=True, fastmath=_FM, forceinline=False)
def dexp_apply_into(X, Y, out):
    """out[:] = dexp_X @ Y without forming the matrix; out may alias Y."""
    x0 = X[0]
    x1 = X[1]
    x2 = X[2]
    n0 = X[3]
    n1 = X[4]
    n2 = X[5]
    y0 = Y[0]
    y1 = Y[1]
    y2 = Y[2]
    z0 = Y[3]
    z1 = Y[4]
    z2 = Y[5]
    B, C, Q3, Q4 = coef_dexp(x0 * x0 + x1 * x1 + x2 * x2)
    k = x0 * n0 + x1 * n1 + x2 * n2
    # P y + J z = B f + C (eta x a + xi x f) + k (Q3 a + Q4 b) + z, with
    # a = xi x y, b = xi x a, f = eta x y + xi x z
    a0 = x1 * y2 - x2 * y1
    a1 = x2 * y0 - x0 * y2
    a2 = x0 * y1 - x1 * y0
    b0 = x1 * a2 - x2 * a1
    b1 = x2 * a0 - x0 * a2
    b2 = x0 * a1 - x1 * a0
    f0 = (n1 * y2 - n2 * y1) + (x1 * z2 - x2 * z1)
    f1 = (n2 * y0 - n0 * y2) + (x2 * z0 - x0 * z2)
    f2 = (n0 * y1 - n1 * y0) + (x0 * z1 - x1 * z0)
    g0 = (n1 * a2 - n2 * a1) + (x1 * f2 - x2 * f1)
    g1 = (n2 * a0 - n0 * a2) + (x2 * f0 - x0 * f2)
    g2 = (n0 * a1 - n1 * a0) + (x0 * f1 - x1 * f0)
    kq3 = k * Q3
    kq4 = k * Q4
    out[0] = y0 + B * a0 + C * b0
    out[1] = y1 + B * a1 + C * b1
    out[2] = y2 + B * a2 + C * b2
    out[3] = z0 + B * f0 + C * g0 + kq3 * a0 + kq4 * b0
    out[4] = z1 + B * f1 + C * g1 + kq3 * a1 + kq4 * b1
    out[5] = z2 + B * f2 + C * g2 + kq3 * a2 + kq4 * b2


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexpinv_apply_into(X, Y, out):
    """out[:] = dexpinv_X @ Y without forming the matrix; out may alias Y."""
    x0 = X[0]
    x1 = X[1]
    x2 = X[2]
    n0 = X[3]
    n1 = X[4]
    n2 = X[5]
    y0 = Y[0]
    y1 = Y[1]
    y2 = Y[2]
    z0 = Y[3]
    z1 = Y[4]
    z2 = Y[5]
    D, E2 = coef_dexpinv(x0 * x0 + x1 * x1 + x2 * x2)
    k = x0 * n0 + x1 * n1 + x2 * n2
    # U y + J^-1 z = -f/2 + D (eta x a + xi x f) + k E2 b + z, with
    # a = xi x y, b = xi x a, f = eta x y + xi x z
    a0 = x1 * y2 - x2 * y1
    a1 = x2 * y0 - x0 * y2
    a2 = x0 * y1 - x1 * y0
    b0 = x1 * a2 - x2 * a1
    b1 = x2 * a0 - x0 * a2
    b2 = x0 * a1 - x1 * a0
    f0 = (n1 * y2 - n2 * y1) + (x1 * z2 - x2 * z1)
    f1 = (n2 * y0 - n0 * y2) + (x2 * z0 - x0 * z2)
    f2 = (n0 * y1 - n1 * y0) + (x0 * z1 - x1 * z0)
    g0 = (n1 * a2 - n2 * a1) + (x1 * f2 - x2 * f1)
    g1 = (n2 * a0 - n0 * a2) + (x2 * f0 - x0 * f2)
    g2 = (n0 * a1 - n1 * a0) + (x0 * f1 - x1 * f0)
    ke = k * E2
    out[0] = y0 - 0.5 * a0 + D * b0
    out[1] = y1 - 0.5 * a1 + D * b1
    out[2] = y2 - 0.5 * a2 + D * b2
    out[3] = z0 - 0.5 * f0 + D * g0 + ke * b0
    out[4] = z1 - 0.5 * f1 + D * g1 + ke * b1
    out[5] = z2 - 0.5 * f2 + D * g2 + ke * b2


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexp_P(X):
    """Lower-left block P of dexp_X (eq. P1, corrected; see module doc)."""
    xi = X[0:3]
    eta = X[3:6]
    B, C, Q3, Q4 = coef_dexp(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2])
    k = xi[0] * eta[0] + xi[1] * eta[1] + xi[2] * eta[2]
    W = so3.hat(xi)
    N = so3.hat(eta)
    return B * N + C * (mm(N, W) + mm(W, N)) + k * (Q3 * W + Q4 * mm(W, W))


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexpinv_U(X):
    """Lower-left block U of dexpinv_X (eq. dexpInvSE3Park, corrected)."""
    xi = X[0:3]
    eta = X[3:6]
    D, E2 = coef_dexpinv(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2])
    k = xi[0] * eta[0] + xi[1] * eta[1] + xi[2] * eta[2]
    W = so3.hat(xi)
    N = so3.hat(eta)
    return -0.5 * N + D * (mm(N, W) + mm(W, N)) + (k * E2) * mm(W, W)


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexp(X):
    """6x6 dexp_X (eq. dexpSE3)."""
    xi = X[0:3]
    B, C, Q3, Q4 = coef_dexp(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2])
    W = so3.hat(xi)
    J = np.eye(3) + B * W + C * mm(W, W)
    M = np.zeros((6, 6))
    M[0:3, 0:3] = J
    M[3:6, 3:6] = J
    M[3:6, 0:3] = dexp_P(X)
    return M


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexpinv(X):
    """6x6 dexp_X^-1 (eq. dexpInvSE3Park)."""
    xi = X[0:3]
    D, E2 = coef_dexpinv(xi[0] * xi[0] + xi[1] * xi[1] + xi[2] * xi[2])
    W = so3.hat(xi)
    Ji = np.eye(3) - 0.5 * W + D * mm(W, W)
    M = np.zeros((6, 6))
    M[0:3, 0:3] = Ji
    M[3:6, 3:6] = Ji
    M[3:6, 0:3] = dexpinv_U(X)
    return M


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexpinv_selig(X):
    """Selig's closed form (eq. dexpInvSE3): I - ad/2 + S2 ad^2 + S4 ad^4."""
    S2, S4 = coef_selig(X[0] * X[0] + X[1] * X[1] + X[2] * X[2])
    a = ad(X)
    a2 = mm(a, a)
    return np.eye(6) - 0.5 * a + S2 * a2 + S4 * mm(a2, a2)


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexp_series(X, nterms):
    """sum_{i<nterms} ad_X^i/(i+1)! (eq. dexp), cross-check."""
    return ad_series(ad(X), DEXP_SERIES_COEFFS, nterms)


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexpinv_series(X, nterms):
    """sum_{i<nterms} B_i/i! ad_X^i (eq. dexpInvSeries), cross-check."""
    return ad_series(ad(X), DEXPINV_SERIES_COEFFS, nterms)


# ---------------------------------------------------------------- ad, Ad, group
@njit(cache=True, fastmath=_FM, forceinline=False)
def ad(X):
    """6x6 [[xi^, 0], [eta^, xi^]] (eq. adse3)."""
    M = np.zeros((6, 6))
    W = so3.hat(X[0:3])
    M[0:3, 0:3] = W
    M[3:6, 3:6] = W
    M[3:6, 0:3] = so3.hat(X[3:6])
    return M


@njit(cache=True, fastmath=_FM, forceinline=False)
def Ad_into(R, r, M):
    """M[:] = Ad_(R,r) = [[R, 0], [r^ R, R]] (6x6): hat(Ad_C X) = C hat(X) C^-1 with C
    the 4x4 matrix of eq. C; no allocation, M must not alias R or r."""
    for i in range(3):
        for j in range(3):
            a = R[i, j]
            M[i, j] = a
            M[i + 3, j + 3] = a
            M[i, j + 3] = 0.0
    r0 = r[0]
    r1 = r[1]
    r2 = r[2]
    for j in range(3):                          # column j of r^ R = r x (R e_j)
        M[3, j] = r1 * R[2, j] - r2 * R[1, j]
        M[4, j] = r2 * R[0, j] - r0 * R[2, j]
        M[5, j] = r0 * R[1, j] - r1 * R[0, j]


@njit(cache=True, fastmath=_FM, forceinline=False)
def Ad(R, r):
    """6x6 [[R, 0], [r^ R, R]]: hat(Ad_C X) = C hat(X) C^-1."""
    M = np.empty((6, 6))
    Ad_into(R, r, M)
    return M


@njit(cache=True, fastmath=_FM, forceinline=False)
def compose_into(R1, r1, R2, r2, R, r):
    """(R, r) = (R1 R2, r1 + R1 r2) (eq. MultSE3), no allocation; the outputs may alias
    the inputs (e.g. in-place update g := g exp(X): R is R1, r is r1)."""
    x0 = r2[0]
    x1 = r2[1]
    x2 = r2[2]
    s0 = r1[0] + R1[0, 0] * x0 + R1[0, 1] * x1 + R1[0, 2] * x2
    s1 = r1[1] + R1[1, 0] * x0 + R1[1, 1] * x1 + R1[1, 2] * x2
    s2 = r1[2] + R1[2, 0] * x0 + R1[2, 1] * x1 + R1[2, 2] * x2
    so3.compose_into(R1, R2, R)
    r[0] = s0
    r[1] = s1
    r[2] = s2


@njit(cache=True, fastmath=_FM, forceinline=False)
def compose(R1, r1, R2, r2):
    """(R1, r1)(R2, r2) = (R1 R2, r1 + R1 r2) (eq. MultSE3)."""
    R = np.empty((3, 3))
    r = np.empty(3)
    compose_into(R1, r1, R2, r2, R, r)
    return R, r


@njit(cache=True, fastmath=_FM, forceinline=False)
def inverse_into(R, r, Ri, ri):
    """(Ri, ri) = (R, r)^-1 = (R^T, -R^T r), no allocation; outputs may alias inputs."""
    x0 = r[0]
    x1 = r[1]
    x2 = r[2]
    s0 = -(R[0, 0] * x0 + R[1, 0] * x1 + R[2, 0] * x2)
    s1 = -(R[0, 1] * x0 + R[1, 1] * x1 + R[2, 1] * x2)
    s2 = -(R[0, 2] * x0 + R[1, 2] * x1 + R[2, 2] * x2)
    so3.inverse_into(R, Ri)
    ri[0] = s0
    ri[1] = s1
    ri[2] = s2


@njit(cache=True, fastmath=_FM, forceinline=False)
def inverse(R, r):
    Ri = np.empty((3, 3))
    ri = np.empty(3)
    inverse_into(R, r, Ri, ri)
    return Ri, ri
