"""The band factorisation of the index-1 solve (mbs/linalg.py): ``S = L D L^T`` in band
storage, its solve, and the pivot rule it shares with the rank-revealing path.

Checked against numpy on random SPD band matrices: the solution's backward error, the band
storage it leaves (unit L, 1 / D), and the pivots D, which must be the squares of the
diagonal of numpy's Cholesky factor (the quantity the rank rule reads).
"""
import numpy as np
import pytest
from numba import njit

from exudyn_lie.mbs.linalg import REL_PIVOT_TOL, band_ldl_inplace, band_ldl_solve_inplace


@njit(cache=False)
def _factor_and_solve(B, m, bw, tol, x):
    fail = band_ldl_inplace(B, m, bw, tol)
    if fail < 0:
        band_ldl_solve_inplace(B, m, bw, x)
    return fail


def _band(S, bw):
    m = S.shape[0]
    B = np.zeros((m, bw + 1))
    for i in range(m):
        for k in range(min(i, bw) + 1):
            B[i, k] = S[i, i - k]
    return B


def _random_spd_band(rng, m, bw):
    A = rng.standard_normal((m, m))
    for i in range(m):
        for j in range(m):
            if abs(i - j) > bw // 2:
                A[i, j] = 0.0
    S = A @ A.T + 0.1 * np.eye(m)          # band of A A^T: 2 (bw // 2) <= bw
    return S


@pytest.mark.parametrize("m,bw", [(1, 0), (3, 2), (6, 5), (6, 2), (12, 4), (30, 5), (30, 29), (40, 1)])
def test_band_ldl_solves_and_factors_like_numpy(m, bw, rng):
    S = _random_spd_band(rng, m, bw)
    b = rng.standard_normal(m)
    B = _band(S, bw)
    x = b.copy()
    assert _factor_and_solve(B, m, bw, 0.0, x) == -1
    # backward error at round-off: |S x - b| / (|S| |x|)
    assert np.linalg.norm(S @ x - b) <= 1e-14 * np.linalg.norm(S, 2) * np.linalg.norm(x)
    # the storage: unit lower L in the strict band, 1 / D on the diagonal; L D L^T = S
    L = np.eye(m)
    for i in range(m):
        for k in range(1, min(i, bw) + 1):
            L[i, i - k] = B[i, k]
    D = 1.0 / B[:, 0]
    assert np.allclose(L @ np.diag(D) @ L.T, S, rtol=0, atol=1e-13 * np.abs(S).max())
    # the pivots are the squared diagonal of the Cholesky factor (what the rank rule reads)
    assert np.allclose(D, np.diag(np.linalg.cholesky(S)) ** 2, rtol=1e-12, atol=0)


def test_band_ldl_reports_the_first_pivot_below_the_rule(rng):
    """A rank-deficient S (row 3 a copy of row 1 in J): the factorisation stops at row 3,
    the row whose pivot falls below REL_PIVOT_TOL * max(diag S), as the time loop reports it."""
    J = rng.standard_normal((5, 8))
    J[3] = J[1]
    S = J @ J.T
    B = _band(S, 4)
    tol = REL_PIVOT_TOL * np.max(np.diag(S))
    assert _factor_and_solve(B, 5, 4, tol, np.ones(5)) == 3
