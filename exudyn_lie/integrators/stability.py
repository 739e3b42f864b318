"""Linear stability of the explicit Runge-Kutta tableaus of the catalogue.

Applied to ``y' = lambda y`` an explicit ``s``-stage method multiplies ``y`` by the
stability polynomial ``R(z) = 1 + sum_k (b^T A^(k-1) e) z^k`` per step, ``z = h lambda``.

* :func:`stability_coefficients` - the coefficients, exact (Fractions) for exact tableaus;
* :func:`stability_abs` - ``|R(i y)|`` on the imaginary axis (undamped oscillations);
* :func:`imaginary_axis_limit` - ``y_max = sup{y : |R(i y')| <= 1 on (0, y]}``;
* :func:`tolerance_limit` - the largest ``y`` at which an undamped oscillation grows by at
  most a given factor over a given number of periods;
* :func:`stability_radius` - the radius of the largest left half-disk on which
  ``|R(z)| <= 1 + tol``: a step size ``h <= radius / rho`` keeps every mode of a
  linearisation with spectral radius ``rho`` (oscillatory or damped) from growing by
  more than ``1 + tol`` per step.  Used to suggest a step after a blow-up.

A diagonally implicit method (``ButcherTableau.implicit``) has the rational stability function
``R(z) = 1 + z b^T (I - z A)^-1 e`` (:func:`stability_function`); the catalogue's are A-stable
(:func:`is_a_stable`), so no step limits them: :func:`stability_radius` is infinite.
"""
from __future__ import annotations

from fractions import Fraction
from functools import lru_cache

import numpy as np

from .tableau import get_method


def exact_tableau(tab):
    """(A, b) of a tableau as Fractions: the exact coefficients when the tableau was
    given exactly, else the exact binary values of its floats."""
    ex = getattr(tab, "_exact_coeffs", None)
    if ex is not None:
        A, b, _ = ex
        return [[Fraction(x) for x in row] for row in A], [Fraction(x) for x in b]
    return ([[Fraction(float(x)) for x in row] for row in np.asarray(tab.A)],
            [Fraction(float(x)) for x in np.asarray(tab.b)])


def stability_function(method, z, weights=None):
    """``R(z) = 1 + z w^T (I - z A)^-1 e`` for an array of complex ``z``, with the weights ``w``
    (default ``b``; ``b_hat`` for the embedded method): explicit and implicit tableaus alike."""
    tab = get_method(method)
    if tab.partitioned:
        raise ValueError(f"{tab.name} is partitioned: pair_growth, or first_order_part for its (A, b)")
    A = np.asarray(tab.A, float)
    w = np.asarray(tab.b if weights is None else weights, float)
    s = len(w)
    zs = np.atleast_1d(np.asarray(z, complex))
    flat = zs.ravel()
    # one batched solve of (I - z A) x = e for every z (a Python loop of small solves cost 20 ms per
    # 1,000 points, and is_a_stable takes 4,001 at every start of an implicit run)
    x = np.linalg.solve(np.eye(s) - flat[:, None, None] * A, np.ones((flat.size, s, 1), complex))[..., 0]
    return (1.0 + flat * (x @ w)).reshape(zs.shape)


def is_a_stable(method, weights=None):
    """A-stability of a diagonally implicit tableau: its poles ``1 / gamma`` lie in the right
    half-plane (gamma > 0), so by the maximum principle ``|R| <= 1`` on the left half-plane when it
    holds on the imaginary axis, checked on a dense logarithmic grid and at infinity."""
    tab = get_method(method)
    if not tab.implicit:
        return False
    if weights is None:
        return _a_stable(tab)
    return _a_stable_with(tab, weights)


@lru_cache(maxsize=None)
def _a_stable(tab):
    """(a tableau is frozen: its verdict is kept; the drop-in asks at every start and switch of a run)"""
    return _a_stable_with(tab, None)


def _a_stable_with(tab, weights):
    y = np.concatenate([np.geomspace(1e-4, 1e8, 4000), [1e12]])
    return bool(np.max(np.abs(stability_function(tab, 1j * y, weights))) <= 1.0 + 1e-12)


def pair_growth(method, z):
    """A partitioned method's (integrators/partitioned.py) growth per step of the mode pair ``z,
    conj(z)`` (``z = h lambda``): the spectral radius of its step on ``q'' = -|z|^2 q + 2 Re(z) q'``
    (``h = 1``), the damped oscillator with those eigenvalues; a real ``z`` is the critically damped
    one, which bounds an overdamped pair's growth from above (conservative).  The configurations and
    the velocities have different coefficients, so no scalar ``R(z)`` describes the method on
    second-order equations."""
    tab = get_method(method)
    A, b, Aq, bq = (np.asarray(x, float) for x in (tab.A, tab.b, tab.Aq, tab.bq))
    s = len(b)
    zs = np.atleast_1d(np.asarray(z, complex))
    k, c = np.abs(zs.ravel()) ** 2, -2.0 * zs.ravel().real
    M = np.empty((k.size, 2, 2))
    for col, (q, v) in enumerate(((1.0, 0.0), (0.0, 1.0))):      # the step is linear in (q, v)
        Vs, acc = np.zeros((s, k.size)), np.zeros((s, k.size))
        for j in range(s):
            Vs[j] = v + A[j, :j] @ acc[:j]
            Q = q + Aq[j, :j] @ Vs[:j] + Aq[j, j] * Vs[j]
            acc[j] = -k * Q - c * Vs[j]
        M[:, 0, col] = q + bq @ Vs
        M[:, 1, col] = v + b @ acc
    half = 0.5 * (M[:, 0, 0] + M[:, 1, 1])
    root = np.sqrt(half.astype(complex) ** 2 - (M[:, 0, 0] * M[:, 1, 1] - M[:, 0, 1] * M[:, 1, 0]))
    return np.maximum(np.abs(half + root), np.abs(half - root)).reshape(zs.shape)


def stability_coefficients(method):
    """Coefficients ``[1, g1, ..., gs]`` (Fractions when the tableau is exact) of the
    stability polynomial ``R(z) = sum g_k z^k``, ``g_k = b^T A^(k-1) e``, of an explicit method
    (an implicit one has a rational function: :func:`stability_function`)."""
    if get_method(method).implicit:
        raise ValueError(f"{get_method(method).name} is implicit: its stability function is rational "
                         "(stability_function), not a polynomial")
    if get_method(method).partitioned:
        raise ValueError(f"{get_method(method).name} is partitioned: no scalar stability function on "
                         "second-order equations (pair_growth); its first-order part: first_order_part")
    A, b = exact_tableau(get_method(method))
    s = len(b)
    coeffs = [Fraction(1)]
    v = [Fraction(1)] * s                 # A^(k-1) e
    for k in range(1, s + 1):
        coeffs.append(sum((b[i] * v[i] for i in range(s)), Fraction(0)))
        v = [sum((A[i][l] * v[l] for l in range(s)), Fraction(0)) for i in range(s)]
    while len(coeffs) > 1 and coeffs[-1] == 0:
        coeffs.pop()
    return coeffs


def _abs2_minus_one_poly(coeffs):
    """``|R(i y)|^2 - 1`` as exact coefficients of a polynomial in ``s = y^2``."""
    # R(iy) = sum g_k i^k y^k: real part from even k, imaginary part from odd k
    n = len(coeffs) - 1
    out = [Fraction(0)] * (n + 1)
    for j in range(n + 1):
        for k in range(n + 1):
            if (j + k) % 2:
                continue
            # i^j conj(i^k) = i^(j-k); real for j-k even: (-1)^((j-k)/2)
            sign = 1 if ((j - k) // 2) % 2 == 0 else -1
            out[(j + k) // 2] += sign * coeffs[j] * coeffs[k]
    out[0] -= 1
    return out            # out[m] multiplies s^m = y^(2m)


def stability_abs(method, y):
    """``|R(i y)|`` for an array of ``y``."""
    c = [float(x) for x in stability_coefficients(method)]
    z = 1j * np.asarray(y, float)
    return np.abs(np.polyval(c[::-1], z))


def imaginary_axis_limit(method):
    """``y_max``: the largest ``y`` with ``|R(i y')| <= 1`` for all ``0 < y' <= y``
    (0.0 when the method is unstable for every nonzero imaginary ``z``)."""
    p = _abs2_minus_one_poly(stability_coefficients(method))
    while len(p) > 1 and p[-1] == 0:
        p.pop()
    # lowest nonzero term decides the sign near s = 0+
    k0 = next((m for m, x in enumerate(p) if x != 0), None)
    if k0 is None:
        return float("inf")
    if p[k0] > 0:
        return 0.0
    q = [float(x) for x in p[k0:]]           # divided by s^k0; q(0) < 0
    if len(q) == 1:
        return float("inf")
    roots = np.roots(q[::-1])
    real = sorted(r.real for r in roots if abs(r.imag) < 1e-9 * max(1.0, abs(r)) and r.real > 0)
    # the first sign change of q from negative to positive
    for r in real:
        s = _refine_root(p[k0:], r)
        eps = 1e-7 * s
        if _eval(p[k0:], s + eps) > 0:
            return float(np.sqrt(s))
    return float("inf")


def _eval(p, s):
    return sum(float(c) * s ** m for m, c in enumerate(p))


def _refine_root(p, s0):
    """Newton polish of a root of sum p[m] s^m (float)."""
    s = float(s0)
    dp = [m * float(c) for m, c in enumerate(p)][1:]
    for _ in range(50):
        f = _eval(p, s)
        d = sum(c * s ** m for m, c in enumerate(dp))
        if d == 0:
            break
        ds = f / d
        s -= ds
        if abs(ds) <= 1e-16 * abs(s):
            break
    return s


def energy_growth(method, y, nsteps):
    """Energy ratio ``E_n / E_0 = |R(i y)|^(2 n)`` of the linear oscillator after n steps."""
    return float(stability_abs(method, [y])[0]) ** (2 * nsteps)


def tolerance_limit(method, periods, growth, ymax_search=10.0):
    """The largest ``y = omega h`` with energy ratio ``<= growth`` after ``periods``
    oscillation periods (``n = ceil(2 pi periods / y)`` steps), by bisection on the
    theory: the exact counterpart of the measured criterion of the stress suite."""
    def ok(y):
        n = int(np.ceil(2 * np.pi * periods / y))
        a = float(stability_abs(method, [y])[0])
        return 2 * n * np.log(a) <= np.log(growth)

    lo, hi = 1e-9, ymax_search
    if ok(hi):
        return hi
    # the criterion is monotone for the catalogue methods in the range of interest:
    # bracket from below along a geometric grid first (robust to a non-monotone tail)
    grid = np.geomspace(1e-6, ymax_search, 400)
    good = [y for y in grid if ok(y)]
    if not good:
        return 0.0
    lo = good[-1]
    hi = grid[np.searchsorted(grid, lo) + 1]
    for _ in range(200):
        mid = np.sqrt(lo * hi)
        if ok(mid):
            lo = mid
        else:
            hi = mid
        if hi / lo - 1 < 1e-12:
            break
    return lo


def stability_radius(method, tol=1e-3, nangles=181):
    """Largest ``r`` with ``|R(z)| <= 1 + tol`` for every ``z`` in the closed left half-disk
    of radius ``r`` (sampled on ``nangles`` rays).  ``tol > 0`` gives methods whose
    region misses the imaginary axis (Euler, the two-stage order-2 methods, Butcher's RK6)
    a practical, slowly growing limit instead of zero.

    ``method``: a catalogue name or any :class:`~exudyn_lie.integrators.ButcherTableau`
    (a user's own too): the radius is computed from the tableau's coefficients.  An A-stable
    implicit method: infinite."""
    if get_method(method).implicit:
        if is_a_stable(method):
            return float("inf")
        raise ValueError(f"{get_method(method).name}: implicit but not A-stable")
    if get_method(method).partitioned:       # second-order modes: the pair's growth (pair_growth)
        return _partitioned_radius(get_method(method), float(tol), int(nangles))
    coeffs = tuple(float(x) for x in stability_coefficients(method))
    return _stability_radius_of_polynomial(coeffs, float(tol), int(nangles))


@lru_cache(maxsize=None)
def _partitioned_radius(tab, tol, nangles):
    return _stability_radius_of(lambda zs: pair_growth(tab, zs), tol, nangles)


@lru_cache(maxsize=None)
def _stability_radius_of_polynomial(coeffs, tol, nangles):
    c = np.array(coeffs[::-1])
    return _stability_radius_of(lambda zs: np.abs(np.polyval(c, zs)), tol, nangles)


def _stability_radius_of(growth, tol, nangles):
    theta = np.linspace(0.5 * np.pi, 1.5 * np.pi, nangles)
    rays = np.exp(1j * theta)

    def ok(r):
        return bool(np.max(growth(r * rays)) <= 1.0 + tol)

    grid = np.geomspace(1e-4, 20.0, 300)
    bad = [r for r in grid if not ok(r)]
    if not bad:
        return float(grid[-1])
    hi = bad[0]
    lo = grid[np.searchsorted(grid, hi) - 1] if hi > grid[0] else 0.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return float(lo)
