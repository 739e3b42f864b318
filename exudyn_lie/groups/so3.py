"""SO(3): rotation matrices R (body -> world), so(3) as 3-vectors x (hat(x) = x^).

Closed forms (paper, appendix A), t = |xi|, W = hat(xi), u = t^2:

    exp(xi)     = I + A W + B W^2                       (eq. expSO3)
    dexp_xi     = I + B W + C W^2                       (eq. dexpSO3, right-trivialised)
    dexpinv_xi  = I - W/2 + D W^2                       (eq. dexpInvSO3)

    A = sin t / t            = 1 - u/6 + u^2/120 - u^3/5040 + ...
    B = (1 - cos t)/t^2      = 1/2 - u/24 + u^2/720 - u^3/40320 + ...
    C = (t - sin t)/t^3      = 1/6 - u/120 + u^2/5040 - u^3/362880 + ...
    D = (1 - (t/2)cot(t/2))/t^2
                             = 1/12 + u/720 + u^2/30240 + u^3/1209600 + ...

(series derived exactly in ``_taylor.series``; D comes from x cot x =
sum (-1)^k B_2k (2x)^2k/(2k)!).  Closed forms are evaluated with the half angle,
s = sin(t/2), c = cos(t/2): A = 2sc/t, B = 2s^2/t^2 (no cancellation, no 1-cos).

Convention: dexp is RIGHT-trivialised, d/de exp(x + e y) = hat(dexp_x y) exp(x);
the body-fixed angular velocity of R = exp(xi(t)) is omega = dexp_{-xi} xidot.
dexpinv_xi is singular at |xi| = 2 pi (dexp_xi is: its smallest singular value is
|sin(t/2)|/(t/2)); the Munthe-Kaas stepper refuses stage arguments that close to
2 pi (:data:`DEXP_ANGLE_MAX`, used by the reference stepper ``tests/reference_mk.py`` and the
compiled time loop ``mbs.kernel`` alike).

Group operations: compose = R1 R2, inverse = R^T, Ad_R = R (hat(R x) = R hat(x) R^T);
each has an allocation-free ``*_into`` variant, as have exp and log.

Switch points (rule in ``_taylor``): exp/dexp share T_SWITCH_EXP (driven by C:
K=12, p=2 -> sqrt(12/32) = 0.612; A, B, C keep 8, 7, 7 terms), dexpinv uses
T_SWITCH_DEXPINV (D: K=12, p=2 -> 0.612, 8 terms), log uses T_SWITCH_LOG =
0.0145 on x = |q|/q0 (4 terms of atan(x)/x; cancellation-free).

log(R) goes through the unit quaternion (Shepperd's method, q0 >= 0) and
t = 2 atan2(|q|, q0): robust at and near pi (no division by sin t).  Result has
|xi| <= pi; at exactly pi (q0 == 0) the sign is such that the largest
component of the axis is positive.
"""
import math

import numpy as np
from numba import njit

from . import _taylor
from ._taylor import FM as _FM
from ._taylor import ad_series, horner, mm, DEXP_SERIES_COEFFS, DEXPINV_SERIES_COEFFS

#: Largest rotation angle t = |xi| at which dexp_xi^-1 is used (the Munthe-Kaas stage
#: equation k_j = dexp^-1_{-Psi_j} V_j, eq. MK1).  dexp_xi is singular at t = 2 pi: its
#: singular values are 1 (along xi) and |sin(t/2)|/(t/2) (across), so its condition number
#: is kappa(t) = (t/2)/|sin(t/2)|.  The rule: accept t while kappa <= 1/sqrt(eps), i.e. at
#: most half of the digits of a stage velocity are lost; with t = 2 pi - d,
#: kappa ~ 2 pi / d, so the bound is 2 pi (1 - sqrt(eps)) = 2 pi - 9.4e-8.
DEXP_ANGLE_MAX = 2.0 * np.pi * (1.0 - np.sqrt(np.finfo(np.float64).eps))

# ---------------------------------------------------------------- switch points
T_SWITCH_EXP, _NE = _taylor.plan(("A", "B", "C"))
U_SWITCH_EXP = T_SWITCH_EXP ** 2
N_A, N_B, N_C = _NE["A"], _NE["B"], _NE["C"]
_CA = _taylor.coeffs("A", N_A)
_CB = _taylor.coeffs("B", N_B)
_CC = _taylor.coeffs("C", N_C)

T_SWITCH_DEXPINV, _ND = _taylor.plan(("D",))
U_SWITCH_DEXPINV = T_SWITCH_DEXPINV ** 2
N_D = _ND["D"]
_CD = _taylor.coeffs("D", N_D)

N_ATAN = 4
T_SWITCH_LOG = _taylor.first_dropped_switch("ATAN", N_ATAN)
_CATAN = _taylor.coeffs("ATAN", N_ATAN)


# ------------------------------------------------------------ scalar coefficients
@njit(cache=True, fastmath=_FM, forceinline=False)
def series_ABC(u):
    return horner(_CA, u), horner(_CB, u), horner(_CC, u)


@njit(cache=True, fastmath=_FM, forceinline=False)
def closed_ABC(u):
    t = math.sqrt(u)
    s = math.sin(0.5 * t)
    c = math.cos(0.5 * t)
    sint = 2.0 * s * c
    return sint / t, 2.0 * s * s / u, (t - sint) / (u * t)


@njit(cache=True, fastmath=_FM, forceinline=False)
def coef_ABC(u):
    """(A, B, C) at u = |xi|^2."""
    if u < U_SWITCH_EXP:
        return series_ABC(u)
    return closed_ABC(u)


@njit(cache=True, fastmath=_FM, forceinline=False)
def coef_AB(u):
    """(A, B) at u = |xi|^2 (exp)."""
    if u < U_SWITCH_EXP:
        return horner(_CA, u), horner(_CB, u)
    t = math.sqrt(u)
    s = math.sin(0.5 * t)
    c = math.cos(0.5 * t)
    return 2.0 * s * c / t, 2.0 * s * s / u


@njit(cache=True, fastmath=_FM, forceinline=False)
def coef_BC(u):
    """(B, C) at u = |xi|^2 (dexp)."""
    if u < U_SWITCH_EXP:
        return horner(_CB, u), horner(_CC, u)
    t = math.sqrt(u)
    s = math.sin(0.5 * t)
    c = math.cos(0.5 * t)
    return 2.0 * s * s / u, (t - 2.0 * s * c) / (u * t)


@njit(cache=True, fastmath=_FM, forceinline=False)
def series_D(u):
    return horner(_CD, u)


@njit(cache=True, fastmath=_FM, forceinline=False)
def closed_D(u):
    t = math.sqrt(u)
    h = 0.5 * t
    return (1.0 - h / math.tan(h)) / u


@njit(cache=True, fastmath=_FM, forceinline=False)
def coef_D(u):
    """D = (1 - (t/2)cot(t/2))/t^2 at u = t^2 (dexpinv)."""
    if u < U_SWITCH_DEXPINV:
        return horner(_CD, u)
    return closed_D(u)


# ------------------------------------------------------------------- hat / vee
@njit(cache=True, fastmath=_FM, forceinline=False)
def hat(x):
    W = np.zeros((3, 3))
    W[0, 1] = -x[2]
    W[0, 2] = x[1]
    W[1, 0] = x[2]
    W[1, 2] = -x[0]
    W[2, 0] = -x[1]
    W[2, 1] = x[0]
    return W


@njit(cache=True, fastmath=_FM, forceinline=False)
def vee(W):
    """Inverse of hat (uses the skew part, so it is exact for skew input)."""
    out = np.empty(3)
    out[0] = 0.5 * (W[2, 1] - W[1, 2])
    out[1] = 0.5 * (W[0, 2] - W[2, 0])
    out[2] = 0.5 * (W[1, 0] - W[0, 1])
    return out


# ------------------------------------------------------------------------ exp
@njit(cache=True, fastmath=_FM, forceinline=False)
def exp_into(x, R):
    """R[:] = exp(hat(x)) (eq. expSO3), no allocation."""
    x0 = x[0]
    x1 = x[1]
    x2 = x[2]
    a00 = x0 * x0
    a11 = x1 * x1
    a22 = x2 * x2
    A, B = coef_AB(a00 + a11 + a22)
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


@njit(cache=True, fastmath=_FM, forceinline=False)
def exp(x):
    R = np.empty((3, 3))
    exp_into(x, R)
    return R


# ----------------------------------------------------------------------- dexp
@njit(cache=True, fastmath=_FM, forceinline=False)
def dexp_apply_into(x, y, out):
    """out[:] = dexp_x @ y = y + B x*y + C x*(x*y); out may alias y."""
    x0 = x[0]
    x1 = x[1]
    x2 = x[2]
    y0 = y[0]
    y1 = y[1]
    y2 = y[2]
    B, C = coef_BC(x0 * x0 + x1 * x1 + x2 * x2)
    c0 = x1 * y2 - x2 * y1
    c1 = x2 * y0 - x0 * y2
    c2 = x0 * y1 - x1 * y0
    d0 = x1 * c2 - x2 * c1
    d1 = x2 * c0 - x0 * c2
    d2 = x0 * c1 - x1 * c0
    out[0] = y0 + B * c0 + C * d0
    out[1] = y1 + B * c1 + C * d1
    out[2] = y2 + B * c2 + C * d2


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexpinv_apply_into(x, y, out):
    """out[:] = dexpinv_x @ y = y - x*y/2 + D x*(x*y); out may alias y."""
    x0 = x[0]
    x1 = x[1]
    x2 = x[2]
    y0 = y[0]
    y1 = y[1]
    y2 = y[2]
    D = coef_D(x0 * x0 + x1 * x1 + x2 * x2)
    c0 = x1 * y2 - x2 * y1
    c1 = x2 * y0 - x0 * y2
    c2 = x0 * y1 - x1 * y0
    d0 = x1 * c2 - x2 * c1
    d1 = x2 * c0 - x0 * c2
    d2 = x0 * c1 - x1 * c0
    out[0] = y0 - 0.5 * c0 + D * d0
    out[1] = y1 - 0.5 * c1 + D * d1
    out[2] = y2 - 0.5 * c2 + D * d2


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexp(x):
    """3x3 dexp matrix (eq. dexpSO3)."""
    B, C = coef_BC(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
    W = hat(x)
    return np.eye(3) + B * W + C * mm(W, W)


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexpinv(x):
    """3x3 inverse dexp matrix (eq. dexpInvSO3)."""
    D = coef_D(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
    W = hat(x)
    return np.eye(3) - 0.5 * W + D * mm(W, W)


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexp_series(x, nterms):
    """sum_{i<nterms} ad_x^i/(i+1)! (eq. dexp), cross-check."""
    return ad_series(hat(x), DEXP_SERIES_COEFFS, nterms)


@njit(cache=True, fastmath=_FM, forceinline=False)
def dexpinv_series(x, nterms):
    """sum_{i<nterms} B_i/i! ad_x^i (eq. dexpInvSeries), cross-check."""
    return ad_series(hat(x), DEXPINV_SERIES_COEFFS, nterms)


# ------------------------------------------------------------------------ log
@njit(cache=True, fastmath=_FM, forceinline=False)
def _quat_tuple(R):
    """(q0, q1, q2, q3) of R as scalars (Shepperd's method), q0 >= 0, unit; no allocation.

    If q0 == 0 exactly (rotation by pi), the largest |q_i| is positive.
    """
    r00 = R[0, 0]
    r11 = R[1, 1]
    r22 = R[2, 2]
    tr = r00 + r11 + r22
    if tr >= r00 and tr >= r11 and tr >= r22:
        q0 = 0.5 * math.sqrt(max(1.0 + tr, 0.0))
        f = 0.25 / q0
        q1 = (R[2, 1] - R[1, 2]) * f
        q2 = (R[0, 2] - R[2, 0]) * f
        q3 = (R[1, 0] - R[0, 1]) * f
    elif r00 >= r11 and r00 >= r22:
        q1 = 0.5 * math.sqrt(max(1.0 + r00 - r11 - r22, 0.0))
        f = 0.25 / q1
        q0 = (R[2, 1] - R[1, 2]) * f
        q2 = (R[0, 1] + R[1, 0]) * f
        q3 = (R[0, 2] + R[2, 0]) * f
    elif r11 >= r22:
        q2 = 0.5 * math.sqrt(max(1.0 - r00 + r11 - r22, 0.0))
        f = 0.25 / q2
        q0 = (R[0, 2] - R[2, 0]) * f
        q1 = (R[0, 1] + R[1, 0]) * f
        q3 = (R[1, 2] + R[2, 1]) * f
    else:
        q3 = 0.5 * math.sqrt(max(1.0 - r00 - r11 + r22, 0.0))
        f = 0.25 / q3
        q0 = (R[1, 0] - R[0, 1]) * f
        q1 = (R[0, 2] + R[2, 0]) * f
        q2 = (R[1, 2] + R[2, 1]) * f
    n = math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    if q0 < 0.0:
        n = -n
    return q0 / n, q1 / n, q2 / n, q3 / n


@njit(cache=True, fastmath=_FM, forceinline=False)
def quat_from_matrix(R):
    """Unit quaternion (q0, q1, q2, q3), q0 >= 0, of R (Shepperd's method).

    If q0 == 0 exactly (rotation by pi), the largest |q_i| is positive.
    """
    q = np.empty(4)
    q[0], q[1], q[2], q[3] = _quat_tuple(R)
    return q


@njit(cache=True, fastmath=_FM, forceinline=False)
def _rotvec_factor(q0, s):
    """f with xi = f q, f = 2 atan2(s, q0)/s, s = |q| (vector part), q0 >= 0."""
    if s < T_SWITCH_LOG * q0:
        # 2 atan(x)/(x q0) with x = s/q0, atan(x)/x = 1 - x^2/3 + x^4/5 - x^6/7
        x = s / q0
        return 2.0 * horner(_CATAN, x * x) / q0
    return 2.0 * math.atan2(s, q0) / s


@njit(cache=True, fastmath=_FM, forceinline=False)
def rotvec_from_quat(q):
    """xi = 2 atan2(|q|, q0) q/|q| for q0 >= 0 (|xi| <= pi); q need not be unit."""
    f = _rotvec_factor(q[0], math.sqrt(q[1] * q[1] + q[2] * q[2] + q[3] * q[3]))
    out = np.empty(3)
    out[0] = f * q[1]
    out[1] = f * q[2]
    out[2] = f * q[3]
    return out


@njit(cache=True, fastmath=_FM, forceinline=False)
def log_into(R, x):
    """x[0:3] = log(R), |xi| <= pi, no allocation (x may be longer: only x[0:3] is written)."""
    q0, q1, q2, q3 = _quat_tuple(R)
    f = _rotvec_factor(q0, math.sqrt(q1 * q1 + q2 * q2 + q3 * q3))
    x[0] = f * q1
    x[1] = f * q2
    x[2] = f * q3


@njit(cache=True, fastmath=_FM, forceinline=False)
def log(R):
    """Rotation vector xi, |xi| <= pi, with exp(xi) = R."""
    x = np.empty(3)
    log_into(R, x)
    return x


# ---------------------------------------------------------------- ad, Ad, group
@njit(cache=True, fastmath=_FM, forceinline=False)
def ad(x):
    return hat(x)


@njit(cache=True, fastmath=_FM, forceinline=False)
def Ad_into(R, M):
    """M[0:3, 0:3] = Ad_R = R (hat(R x) = R hat(x) R^T), no allocation."""
    for i in range(3):
        for j in range(3):
            M[i, j] = R[i, j]


@njit(cache=True, fastmath=_FM, forceinline=False)
def Ad(R):
    M = np.empty((3, 3))
    Ad_into(R, M)
    return M


@njit(cache=True, fastmath=_FM, forceinline=False)
def compose_into(R1, R2, R):
    """R[:] = R1 R2, no allocation; R may alias R1 and/or R2 (R2 is read first,
    then R1 row by row)."""
    b00 = R2[0, 0]
    b01 = R2[0, 1]
    b02 = R2[0, 2]
    b10 = R2[1, 0]
    b11 = R2[1, 1]
    b12 = R2[1, 2]
    b20 = R2[2, 0]
    b21 = R2[2, 1]
    b22 = R2[2, 2]
    for i in range(3):
        a0 = R1[i, 0]
        a1 = R1[i, 1]
        a2 = R1[i, 2]
        R[i, 0] = a0 * b00 + a1 * b10 + a2 * b20
        R[i, 1] = a0 * b01 + a1 * b11 + a2 * b21
        R[i, 2] = a0 * b02 + a1 * b12 + a2 * b22


@njit(cache=True, fastmath=_FM, forceinline=False)
def compose(R1, R2):
    R = np.empty((3, 3))
    compose_into(R1, R2, R)
    return R


@njit(cache=True, fastmath=_FM, forceinline=False)
def inverse_into(R, Ri):
    """Ri[:] = R^-1 = R^T, no allocation; Ri may alias R (in-place transpose)."""
    a01 = R[0, 1]
    a02 = R[0, 2]
    a12 = R[1, 2]
    Ri[0, 0] = R[0, 0]
    Ri[1, 1] = R[1, 1]
    Ri[2, 2] = R[2, 2]
    Ri[0, 1] = R[1, 0]
    Ri[0, 2] = R[2, 0]
    Ri[1, 2] = R[2, 1]
    Ri[1, 0] = a01
    Ri[2, 0] = a02
    Ri[2, 1] = a12


@njit(cache=True, fastmath=_FM, forceinline=False)
def inverse(R):
    Ri = np.empty((3, 3))
    inverse_into(R, Ri)
    return Ri
