"""The band factorisation of the index-1 solve (mbs/linalg.py): ``S = L D L^T`` in band
storage, its solve, and the pivot rule it shares with the rank-revealing path.

Checked against numpy on random SPD band matrices: the solution's backward error, the band
storage it leaves (unit L, 1 / D), and the pivots D, which must be the squares of the
diagonal of numpy's Cholesky factor (the quantity the rank rule reads).
"""
import numpy as np
import pytest
from numba import njit

from exudyn_lie.mbs.linalg import REL_PIVOT_TOL, band_ldl_inplace, band_ldl_solve_inplace, max_abs


@njit(cache=False)
def _factor_and_solve(B, m, bw, tol, x):
    fail = band_ldl_inplace(B, m, bw, tol, np.zeros(m))
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
    the row whose pivot falls below REL_PIVOT_TOL * S_33, as the time loop reports it."""
    J = rng.standard_normal((5, 8))
    J[3] = J[1]
    S = J @ J.T
    B = _band(S, 4)
    assert _factor_and_solve(B, 5, 4, REL_PIVOT_TOL, np.ones(5)) == 3


def _scaled_rows(rng, scales, dependent=None):
    """S = J J^T for rows of J of the given scales; ``dependent = (i, k)``: row i a multiple
    of row k."""
    J = rng.standard_normal((len(scales), 9))
    if dependent is not None:
        J[dependent[0]] = J[dependent[1]]
    J *= np.asarray(scales, float)[:, None]
    return J @ J.T


@pytest.mark.parametrize("scale", [1e-12, 1e-6, 1.0, 1e6])
def test_rank_rule_ignores_the_scale_of_independent_rows(rng, scale):
    """Rows of very different sizes (a body of tiny inertia beside a point mass on a rail:
    Exudyn's slider-crank example) are independent whatever their scale: the band
    factorisation, the rank-revealing solve and the set-up check keep every row."""
    from exudyn_lie.mbs.linalg import pivoted_cholesky_solve, schur_rank_and_null
    m = 5
    S = _scaled_rows(rng, [1e6, 1.0, scale, 1e6, 1.0])
    x = np.ones(m)
    assert _factor_and_solve(_band(S, m - 1), m, m - 1, REL_PIVOT_TOL, x) == -1
    assert np.linalg.norm(S @ x - 1.0) <= 1e-9 * np.linalg.norm(S, 2) * np.linalg.norm(x)
    y = np.ones(m)
    assert pivoted_cholesky_solve(S.copy(), m, y, np.zeros(m, np.int64), np.zeros(m), REL_PIVOT_TOL) == m
    assert np.allclose(y, x, rtol=1e-6, atol=0)
    rank, null = schur_rank_and_null(S)
    assert rank == m and null.shape[1] == 0


@pytest.mark.parametrize("scale", [1e-12, 1.0, 1e6])
def test_rank_rule_finds_a_dependent_row_of_any_scale(rng, scale):
    """A row that repeats another (scaled) is dependent, also when it is 1e12 times smaller
    or larger than the rest: every path finds it and names it."""
    from exudyn_lie.mbs.linalg import pivoted_cholesky_solve, rows_in_null_space, schur_rank_and_null
    m = 5
    S = _scaled_rows(rng, [1.0, 1e6, 1.0, scale, 1.0], dependent=(3, 0))
    assert _factor_and_solve(_band(S, m - 1), m, m - 1, REL_PIVOT_TOL, np.ones(m)) == 3
    y = np.ones(m)
    assert pivoted_cholesky_solve(S.copy(), m, y, np.zeros(m, np.int64), np.zeros(m), REL_PIVOT_TOL) == m - 1
    rank, null = schur_rank_and_null(S)
    assert rank == m - 1 and null.shape[1] == 1
    assert rows_in_null_space(null) == [0, 3]


@pytest.mark.parametrize("m,kl,ku", [(1, 0, 0), (7, 2, 1), (30, 3, 5), (30, 29, 29), (50, 1, 0), (64, 6, 6)])
def test_band_lu_with_pivoting_solves_like_numpy(m, kl, ku, rng):
    """Band LU with partial pivoting (linalg.band_lu_factor_inplace): a band of half-widths kl,
    ku with small diagonal entries (the pivots come from below), the fill region zero on entry,
    everything outside it NaN (not read)."""
    from exudyn_lie.mbs.linalg import band_lu_extents, band_lu_factor_inplace, band_lu_solve_extents
    A = rng.standard_normal((m, m))
    A[np.tril_indices(m, -kl - 1)] = 0.0
    A[np.triu_indices(m, ku + 1)] = 0.0
    A[np.diag_indices(m)] *= 1e-3
    E = A.copy()
    E[np.tril_indices(m, -kl - 1)] = np.nan              # outside the band and its fill: never read
    E[np.triu_indices(m, kl + ku + 1)] = np.nan
    fill = np.triu(np.ones((m, m), bool), ku + 1) & ~np.triu(np.ones((m, m), bool), kl + ku + 1)
    E[fill] = 0.0
    piv = np.zeros(m, np.int64)
    assert band_lu_factor_inplace(E, m, kl, ku, piv) == -1
    b = rng.standard_normal(m)
    x = b.copy()                          # over the whole band
    ks = np.arange(m)
    band_lu_solve_extents(E, m, piv, np.minimum(ks + kl, m - 1), np.minimum(ks + kl + ku, m - 1), x)
    assert np.all(np.isfinite(x))
    lend, uend = np.zeros(m, np.int64), np.zeros(m, np.int64)      # up to the factors' extents: the same sums
    band_lu_extents(E, m, kl, ku, lend, uend)
    assert np.all(lend <= np.minimum(ks + kl, m - 1)) and np.all(uend <= np.minimum(ks + kl + ku, m - 1))
    xe = b.copy()
    band_lu_solve_extents(E, m, piv, lend, uend, xe)
    assert np.array_equal(xe, x)
    # backward stable: the residual is round-off of |A| |x|
    assert np.abs(A @ x - b).max() <= 1e-12 * (np.abs(A).max() * np.abs(x).max() * m + np.abs(b).max())


def test_reverse_cuthill_mckee_finds_the_band_of_a_shuffled_one(rng):
    """A tridiagonal block pattern (blocks of 6) numbered at random: the numbering of
    band_order.rcm_numbering is a permutation and brings the half-widths back to the order of the
    blocks (the shuffled pattern spans nearly the whole matrix)."""
    from exudyn_lie.mbs.band_order import bandwidths, rcm_numbering
    n = 120
    D = np.zeros((n, n))
    for blk in range(n // 6):
        for other in (blk - 1, blk, blk + 1):
            if 0 <= other < n // 6:
                D[6 * blk:6 * blk + 6, 6 * other:6 * other + 6] = rng.standard_normal((6, 6))
    p = rng.permutation(n)
    Ds = D[np.ix_(p, p)]
    Z = np.zeros((n, n))
    ident = np.arange(n)
    assert max(bandwidths(Ds, Z, n, ident)) > n // 2
    perm, iperm, deg, nbr = (np.zeros(n, np.int64) for _ in range(4))
    rcm_numbering(Ds, Z, n, perm, iperm, deg, nbr)
    assert sorted(perm) == list(range(n)) and np.all(iperm[perm] == ident)
    assert max(bandwidths(Ds, Z, n, iperm)) <= 17


def test_max_abs_is_numpys_max_of_abs_with_nan_and_empty(rng):
    """The per-step tests of the evaluated path's projection and check (mbs/linalg.max_abs) decide
    as ``np.max(np.abs(x))``: the same value, a NaN anywhere gives NaN (a blown-up state must not
    read as converged), an empty vector 0; views with a stride too."""
    for n in (1, 2, 7, 50):
        x = rng.standard_normal(n) * 10.0 ** rng.integers(-12, 12, n)
        assert max_abs(x) == np.max(np.abs(x))
        assert max_abs(x[::2]) == np.max(np.abs(x[::2]))
        for k in (0, n - 1):
            y = x.copy()
            y[k] = np.nan
            assert np.isnan(max_abs(y))
    assert max_abs(np.array([-np.inf, 1.0])) == np.inf
    assert max_abs(np.zeros(0)) == 0.0
