"""Theory and oracles for the stress suite (``python -m exudyn_lie stress``).

* Linear stability of the tableaus (re-exported from :mod:`exudyn_lie.integrators.stability`):
  the stability polynomial, the imaginary-axis boundary ``y_max`` and the step a
  spring-mass oscillator tolerates under a given energy-growth criterion.
* Extended-precision (``np.longdouble``) oracles for the group maps: the matrix
  exponential (scaling and squaring of a Taylor series) and the ``ad``-series of dexp and
  dexpinv.  They share no code with :mod:`exudyn_lie.groups` and are accurate to about
  1e-18 on x86-64, far below the float64 errors they judge.
"""
from __future__ import annotations

from fractions import Fraction
from math import factorial

import numpy as np

from ..integrators.stability import (energy_growth, exact_tableau, imaginary_axis_limit,  # noqa: F401
                                     stability_abs, stability_coefficients, tolerance_limit)

LD = np.longdouble


# --------------------------------------------------------------------------- group oracles
def _hat3(x):
    return np.array([[0, -x[2], x[1]], [x[2], 0, -x[0]], [-x[1], x[0], 0]], dtype=LD)


def _ld(x):
    return np.asarray(x, dtype=LD)


def expm_ld(M):
    """Matrix exponential in extended precision: scaling and squaring of a Taylor series."""
    M = _ld(M)
    n = M.shape[0]
    nrm = float(np.max(np.sum(np.abs(M), axis=1)))
    k = max(0, int(np.ceil(np.log2(max(nrm, 1e-300) / 0.25)))) if nrm > 0.25 else 0
    S = M / LD(2.0) ** k
    E = np.eye(n, dtype=LD)
    term = np.eye(n, dtype=LD)
    for j in range(1, 40):
        term = term @ S / LD(j)
        E = E + term
        if float(np.max(np.abs(term))) < 1e-40:
            break
    for _ in range(k):
        E = E @ E
    return E


def se3_hat4(X):
    M = np.zeros((4, 4), dtype=LD)
    M[:3, :3] = _hat3(_ld(X[:3]))
    M[:3, 3] = _ld(X[3:6])
    return M


def exp_oracle(group, X):
    """(R, r) = exp(X) in extended precision (SE3 via the 4x4 matrix exponential)."""
    X = _ld(X)
    if group == "SO3":
        return expm_ld(_hat3(X)), None
    if group == "SE3":
        E = expm_ld(se3_hat4(X))
        return E[:3, :3], E[:3, 3]
    if group == "SO3xR3":
        return expm_ld(_hat3(X[:3])), X[3:6].copy()
    raise ValueError(group)


def ad_ld(group, X):
    X = _ld(X)
    if group == "SO3":
        return _hat3(X)
    M = np.zeros((6, 6), dtype=LD)
    W = _hat3(X[:3])
    M[:3, :3] = W
    if group == "SE3":
        M[3:, 3:] = W
        M[3:, :3] = _hat3(X[3:6])
    return M


def _bernoulli_over_factorial(n):
    """B_k / k! (B_1 = -1/2) as exact Fractions, k < n."""
    B = [Fraction(0)] * n
    B[0] = Fraction(1)
    for m in range(1, n):
        B[m] = -sum(Fraction(factorial(m + 1), factorial(k) * factorial(m + 1 - k)) * B[k]
                    for k in range(m)) / (m + 1)
    return [B[k] / factorial(k) for k in range(n)]


_BF = None


def dexp_oracle(group, X, inverse=False, nterms=None):
    """dexp_X = sum ad^i/(i+1)! or dexpinv_X = sum B_i/i! ad^i, extended precision.

    The dexpinv series converges for |xi| < 2 pi; the number of terms is chosen so that
    the tail is below 1e-22 of the leading term."""
    global _BF
    a = ad_ld(group, X)
    n = a.shape[0]
    t = float(np.linalg.norm(np.asarray(X[:3], float)))
    if nterms is None:
        if inverse:
            # |B_k/k!| ~ 2 / (2 pi)^k: terms ~ k (t / 2 pi)^k (k from the nilpotent part)
            q = max(t / (2 * np.pi), 1e-3)
            if q >= 0.97:
                raise ValueError("dexpinv series oracle needs |xi| < 0.97 * 2 pi")
            nterms = int(np.ceil((np.log(1e-24) - 2 * np.log(max(8.0, 1 / (1 - q)))) / np.log(q))) + 8
            nterms = min(max(nterms, 12), 2000)
        else:
            nterms = 60
    if inverse:
        if _BF is None or len(_BF) < nterms:
            _BF = [LD(f.numerator) / LD(f.denominator) for f in _bernoulli_over_factorial(nterms)]
        coef = _BF
    else:
        coef = [LD(1) / LD(factorial(i + 1)) for i in range(nterms)]
    out = np.zeros((n, n), dtype=LD)
    P = np.eye(n, dtype=LD)
    for i in range(nterms):
        if coef[i] != 0:
            out = out + coef[i] * P
        P = P @ a
    return out


def rel_err(A, B):
    """max|A - B| / max(1, max|B|), computed in extended precision."""
    A = _ld(A)
    B = _ld(B)
    return float(np.max(np.abs(A - B)) / max(LD(1), np.max(np.abs(B))))
