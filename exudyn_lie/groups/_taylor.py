"""Exact Taylor coefficients, switch points and the generic ad-series.

Every scalar coefficient of the group maps is an even function of the rotation
angle t = |xi| and is evaluated as a polynomial in u = t**2 below a switch point
and by its closed form above it.  The coefficients are *derived* here with exact
rational power-series arithmetic (``fractions.Fraction``) from the series of
sin, cos and the Bernoulli numbers -- nothing is copied from a table -- and
converted to float64 tuples that numba freezes as compile-time constants.

Switch rule
-----------
Two conditions fix each switch point t_sw and the number N of kept terms:

1. The closed form is only used where its rounding error is amplified by at most
   AMP_MAX = 32 (5 bits).  A closed form with cancellation loses about K / t^p
   (the magnitude of the cancelling terms over the result, e.g. K=12, p=2 for
   (t - sin t)/t^3); so t_sw >= t_min = (K / AMP_MAX)^(1/p).  A map (e.g. SE3
   dexpinv, which needs D and E2) uses one t_sw = the max over its coefficients.
2. Below t_sw the polynomial must be exact to rounding: N is the smallest number
   of terms whose first dropped terms satisfy |c_k| t_sw^(2k) <= eps |c_0|.

For cancellation-free coefficients (sin t/t, atan(x)/x) rule 1 is void; there N
is fixed and t_sw is where the first dropped term is eps relative to the first:
t_sw = (eps |c_0/c_N|)^(1/(2N)).  The resulting numbers are module constants of
so3/se3 (T_SWITCH_*, N_*, NTERMS) and are listed by
``exudyn_lie.groups.switch_report()``.

Generic series
--------------
``ad_series(adM, coeffs, nterms)`` = sum_i coeffs[i] adM^i is shared by all
groups: with coeffs = 1/(i+1)! it is dexp (eq. dexp), with B_i/i! it is dexpinv
(eq. dexpInvSeries, B_1 = -1/2).
"""
from fractions import Fraction
from functools import lru_cache
from math import factorial

import numpy as np
from numba import njit

from .._memo import DiskMemo, arg_key

EPS = float(np.finfo(np.float64).eps)   # 2.220446049250313e-16

# numba fast-math flags of the hot-path code: FMA contraction only (no
# reassociation, no finite-math or signed-zero assumptions).  ~15% faster and
# at least as accurate; results may differ in the last bit from unfused code.
FM = {"contract"}
_FM = FM
# The group maps are decorated forceinline=False explicitly.  The kernel's stage functions are
# forceinline=True (LLVM inlines them into the time loop), and numba passes that flag on to a
# callee compiled on their behalf unless the callee sets it; inlined, LLVM decides the FMA
# contractions of these maps in the caller's context and their results change in the last bit
# (the same code, other roundings).  Kept as calls, they round exactly as before.


# ----------------------------------------------------------------------------
# exact power series in u = t^2, as lists of Fractions (truncated to n terms)
# ----------------------------------------------------------------------------
def _mul(a, b, n):
    out = [Fraction(0)] * n
    for i, ai in enumerate(a[:n]):
        if ai == 0:
            continue
        for j, bj in enumerate(b[: n - i]):
            out[i + j] += ai * bj
    return out


def _inv(a, n):
    """1/a as a power series (a[0] != 0)."""
    out = [Fraction(0)] * n
    out[0] = 1 / Fraction(a[0])
    for k in range(1, n):
        s = sum(a[j] * out[k - j] for j in range(1, min(k, len(a) - 1) + 1))
        out[k] = -s / a[0]
    return out


def _add(*terms):
    n = min(len(t) for t in terms)
    return [sum(t[k] for t in terms) for k in range(n)]


def _scale(a, s):
    return [s * x for x in a]


def _shift(a, m):
    """Divide by u^m (drop the first m coefficients, which must be zero)."""
    assert all(x == 0 for x in a[:m]), "series does not vanish to the required order"
    return a[m:]


@lru_cache(maxsize=None)
def _bernoulli(n):
    return tuple(bernoulli(n))


def bernoulli(n):
    """Bernoulli numbers B_0..B_{n-1} with B_1 = -1/2 (generating fn z/(e^z-1))."""
    B = [Fraction(0)] * n
    B[0] = Fraction(1)
    for m in range(1, n):
        B[m] = -sum(Fraction(factorial(m + 1), factorial(k) * factorial(m + 1 - k)) * B[k]
                    for k in range(m)) / (m + 1)
    return B


# Elementary even series in u = t^2.
def s_sin_t(n):            # sin(t)/t = sum (-1)^k u^k/(2k+1)!
    return [Fraction((-1) ** k, factorial(2 * k + 1)) for k in range(n)]


def s_cos(n):              # cos(t) = sum (-1)^k u^k/(2k)!
    return [Fraction((-1) ** k, factorial(2 * k)) for k in range(n)]


def s_one_minus_cos(n):    # (1-cos t)/t^2 = sum (-1)^k u^k/(2k+2)!
    return [Fraction((-1) ** k, factorial(2 * k + 2)) for k in range(n)]


def s_t_minus_sin(n):      # (t-sin t)/t^3 = sum (-1)^k u^k/(2k+3)!
    return [Fraction((-1) ** k, factorial(2 * k + 3)) for k in range(n)]


def s_half_cot(n):
    """gamma(t) = (t/2) cot(t/2) = sum_k (-1)^k B_2k t^2k / (2k)!  (x cot x series)."""
    B = _bernoulli(2 * n + 2)
    return [(-1) ** k * B[2 * k] / factorial(2 * k) for k in range(n)]


def s_inv_beta(n):
    """1/beta = (t/2)^2 / sin^2(t/2) = ((x/sin x)^2, x = t/2)."""
    # sin(x)/x in u=t^2 with x = t/2:  sum (-1)^k (u/4)^k/(2k+1)!
    sx = [Fraction((-1) ** k, factorial(2 * k + 1) * 4 ** k) for k in range(n)]
    r = _inv(sx, n)
    return _mul(r, r, n)


# ----------------------------------------------------------------------------
# the coefficient functions used by the groups (series in u = t^2)
# ----------------------------------------------------------------------------
def series(name, n):
    """Exact Taylor coefficients c_0..c_{n-1} (in u = t^2) of a named coefficient."""
    return list(_series(name, n))


_MEMO = DiskMemo("taylor", __file__)


@lru_cache(maxsize=None)
def _series(name, n):
    """:func:`_series_exact`, kept on disk between processes (:mod:`exudyn_lie._memo`)."""
    return _MEMO.get(arg_key(name, n), lambda: _series_exact(name, n))


def _series_exact(name, n):
    m = n + 4   # working length (enough for the shifts below)
    if name == "A":       # sin t / t                                  (exp SO3)
        return s_sin_t(n)
    if name == "B":       # (1 - cos t)/t^2 = beta/2                   (exp, dexp SO3)
        return s_one_minus_cos(n)
    if name == "C":       # (t - sin t)/t^3 = (1-alpha)/t^2            (dexp SO3)
        return s_t_minus_sin(n)
    if name == "D":       # (1 - (t/2)cot(t/2))/t^2 = (1-gamma)/t^2    (dexpinv SO3)
        g = s_half_cot(m)
        return _shift(_add([Fraction(1)] + [Fraction(0)] * (m - 1), _scale(g, -1)), 1)[:n]
    if name == "Q3":      # (alpha - beta)/t^2 = (A - 2B)/t^2          (P of dexp SE3)
        return _shift(_add(s_sin_t(m), _scale(s_one_minus_cos(m), -2)), 1)[:n]
    if name == "Q4":      # (beta/2 - 3(1-alpha)/t^2)/t^2 = (B - 3C)/t^2
        return _shift(_add(s_one_minus_cos(m), _scale(s_t_minus_sin(m), -3)), 1)[:n]
    if name == "E2":      # (1/beta + gamma - 2)/t^4                   (U of dexpinv SE3)
        two = [Fraction(2)] + [Fraction(0)] * (m - 1)
        return _shift(_add(s_inv_beta(m), s_half_cot(m), _scale(two, -1)), 2)[:n]
    if name == "S2":      # Selig: 2/t^2 + (t + 3 sin t)/(4 t (cos t - 1))
        # = (8B - 1 - 3A) / (4 B t^2)
        num = _add(_scale(s_one_minus_cos(m), 8), _scale(s_sin_t(m), -3),
                   [Fraction(-1)] + [Fraction(0)] * (m - 1))
        return _mul(_shift(num, 1), _inv(_scale(s_one_minus_cos(m), 4), m), m)[:n]
    if name == "S4":      # Selig: 1/t^4 + (t + sin t)/(4 t^3 (cos t - 1))
        # = (4B - 1 - A) / (4 B t^4)
        num = _add(_scale(s_one_minus_cos(m), 4), _scale(s_sin_t(m), -1),
                   [Fraction(-1)] + [Fraction(0)] * (m - 1))
        return _mul(_shift(num, 2), _inv(_scale(s_one_minus_cos(m), 4), m), m)[:n]
    if name == "ATAN":    # atan(x)/x = sum (-1)^k x^2k/(2k+1)      (log via quaternion)
        return [Fraction((-1) ** k, 2 * k + 1) for k in range(n)]
    raise KeyError(name)


# ----------------------------------------------------------------------------
# switch rule
# ----------------------------------------------------------------------------
# Rounding-error amplification of each closed form, K / t^p: the size of the
# terms that cancel divided by the size of the result (leading order), e.g.
# C = (t - sin t)/t^3 subtracts two O(t) numbers to get t^3/6: K = 12, p = 2.
# None = cancellation-free (the series branch only avoids 0/0 and underflow).
CANCELLATION = {
    "A": None,          # 2 sin(t/2) cos(t/2) / t
    "B": None,          # 2 sin^2(t/2) / t^2
    "C": (12.0, 2),     # (t - sin t)/t^3:         2 t       -> t^3/6
    "D": (12.0, 2),     # (1 - gamma)/t^2:         1         -> t^2/12
    "Q3": (24.0, 2),    # (A - 2B)/t^2:            1 + 1     -> t^2/12
    "Q4": (180.0, 4),   # (B - 3C)/t^2:  3C carries (12/t^2) eps/2 -> t^2/60
    "E2": (1440.0, 4),  # (1/beta + gamma - 2)/t^4: t^2 terms -> t^6/1440
    "S2": (48.0, 2),    # 2/t^2 + ... : 4/t^2      -> 1/12
    "S4": (1440.0, 4),  # 1/t^4 + ... : 2/t^4      -> 1/720
    "ATAN": None,       # atan2(s, c)/s
}
# A closed form is used only where it loses at most log2(AMP_MAX) = 5 bits.
AMP_MAX = 32.0


def t_min(name):
    """Smallest angle at which the closed form of `name` is trusted (K/t^p <= AMP_MAX)."""
    kp = CANCELLATION[name]
    if kp is None:
        return 0.0
    K, p = kp
    return (K / AMP_MAX) ** (1.0 / p)


def nterms_for(name, t):
    """Smallest N such that the dropped terms c_k t^2k (k = N, N+1, N+2) are <= eps |c_0|."""
    c = [float(x) for x in series(name, 48)]
    for N in range(1, 45):
        if all(abs(c[k]) * t ** (2 * k) <= EPS * abs(c[0]) for k in range(N, N + 3)):
            return N
    raise ValueError("series does not converge fast enough at t=%g" % t)


def plan(names, t_floor=0.0):
    """Switch angle shared by one map's coefficients and the number of terms of each.

    t_switch = max(t_floor, max_i t_min(name_i)); N_i = nterms_for(name_i, t_switch).
    """
    t_sw = max([t_floor] + [t_min(n) for n in names])
    return t_sw, {n: nterms_for(n, t_sw) for n in names}


def first_dropped_switch(name, nterms):
    """For cancellation-free coefficients with a fixed number of terms: the angle at
    which the first dropped term equals eps relative to the leading one."""
    c = series(name, nterms + 4)
    k = nterms
    while c[k] == 0:
        k += 1
    return float((EPS * abs(float(c[0]) / float(c[k]))) ** (1.0 / (2 * k)))


def coeffs(name, nterms):
    """float64 tuple of the first nterms Taylor coefficients (in u = t^2)."""
    return tuple(float(x) for x in series(name, nterms))


# ----------------------------------------------------------------------------
# coefficients of the generic (cross-check) series
# ----------------------------------------------------------------------------
SERIES_MAX_TERMS = 64
# dexp:    sum_i ad^i/(i+1)!                                 (eq. dexp)
DEXP_SERIES_COEFFS = np.array([1.0 / factorial(i + 1) for i in range(SERIES_MAX_TERMS)])
# dexpinv: sum_i B_i/i! ad^i, B_1 = -1/2                      (eq. dexpInvSeries)
# (Bernoulli numbers in Fractions: kept in the disk memo like the series above, 7 ms of an import)
DEXPINV_SERIES_COEFFS = np.array(_MEMO.get(arg_key("dexpinv coefficients", SERIES_MAX_TERMS), lambda: [
    float(b / factorial(i)) for i, b in enumerate(bernoulli(SERIES_MAX_TERMS))]))


@njit(cache=True, inline="always", fastmath=_FM)
def horner(c, u):
    """sum_k c[k] u^k for a tuple/array c (len >= 1).

    Evaluated as even(u^2) + u odd(u^2), two independent Horner chains, which
    halves the FMA latency of the long (~20-term) dexpinv polynomials.
    Inlined at numba-IR level: with a module-global tuple c the loops are then
    fully constant-folded (a plain call passes the tuple by value, ~4x slower).
    """
    n = len(c)
    u2 = u * u
    ne = (n + 1) // 2
    no = n // 2
    se = c[2 * (ne - 1)]
    for k in range(ne - 2, -1, -1):
        se = se * u2 + c[2 * k]
    if no == 0:
        return se
    so = c[2 * no - 1]
    for k in range(no - 2, -1, -1):
        so = so * u2 + c[2 * k + 1]
    return se + u * so


@njit(cache=True, fastmath=_FM, forceinline=False)
def ad_series(adM, cf, nterms):
    """sum_{i < nterms} cf[i] adM^i (square adM); shared by dexp/dexpinv series of all groups."""
    n = adM.shape[0]
    out = np.zeros((n, n))
    P = np.eye(n)
    for i in range(nterms):
        out += cf[i] * P
        P = mm(adM, P)
    return out


# ----------------------------------------------------------------------------
# tiny dense helpers (numba's np.dot / @ needs scipy's BLAS, which is not a
# dependency of this package)
# ----------------------------------------------------------------------------
@njit(cache=True, fastmath=_FM, forceinline=False)
def mm(A, B):
    """Matrix product A @ B."""
    n, k = A.shape
    m = B.shape[1]
    C = np.zeros((n, m))
    for i in range(n):
        for l in range(k):
            a = A[i, l]
            if a != 0.0:
                for j in range(m):
                    C[i, j] += a * B[l, j]
    return C


@njit(cache=True, fastmath=_FM, forceinline=False)
def mv(A, x):
    """Matrix-vector product A @ x."""
    n, k = A.shape
    y = np.zeros(n)
    for i in range(n):
        s = 0.0
        for l in range(k):
            s += A[i, l] * x[l]
        y[i] = s
    return y
