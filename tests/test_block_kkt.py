"""The index-1 solve for block-diagonal generalised coordinates (mbs/block_kkt.py), which
the Exudyn-evaluated path uses, against the whole KKT matrix solved by numpy."""
import numpy as np
import pytest

from exudyn_lie.errors import ConstraintError, SimulationError
from exudyn_lie.mbs.block_kkt import DENSE_IN_KERNEL_MAX, BlockKKT


def _blocks_of(sizes):
    ptr = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    return lambda M: (np.arange(ptr[-1], dtype=np.int64), ptr)


def _chain(rng, sizes, rowsPerJoint=2):
    """M block diagonal (SPD blocks), rows joining neighbouring blocks (a chain) and one
    row fixing block 0."""
    n = int(sum(sizes))
    ptr = np.concatenate([[0], np.cumsum(sizes)])
    M = np.zeros((n, n))
    for b, s in enumerate(sizes):
        A = rng.normal(size=(s, s))
        M[ptr[b]:ptr[b + 1], ptr[b]:ptr[b + 1]] = A @ A.T + s * np.eye(s)
    rows = []
    r = np.zeros(n)
    r[ptr[0]:ptr[1]] = rng.normal(size=sizes[0])
    rows.append(r)
    for b in range(len(sizes) - 1):
        for _ in range(rowsPerJoint):
            r = np.zeros(n)
            r[ptr[b]:ptr[b + 1]] = rng.normal(size=sizes[b])
            r[ptr[b + 1]:ptr[b + 2]] = rng.normal(size=sizes[b + 1])
            rows.append(r)
    return M, np.array(rows), rng.normal(size=n)


def _kkt(M, Cq, f, eta):
    n, m = M.shape[0], Cq.shape[0]
    K = np.block([[M, Cq.T], [Cq, np.zeros((m, m))]])
    x = np.linalg.solve(K, np.concatenate([f, eta]))
    return x[:n], x[n:]


def _no_empty(Cq, empty):
    assert not np.any(empty)


@pytest.mark.parametrize("seed", range(5))
def test_chain_matches_the_whole_kkt_matrix(seed):
    rng = np.random.default_rng(seed)
    sizes = rng.integers(1, 8, size=12)
    M, Cq, f = _chain(rng, sizes, rowsPerJoint=1)
    eta = rng.normal(size=Cq.shape[0])
    kkt = BlockKKT(M.shape[0], Cq.shape[0], _blocks_of(sizes), _no_empty)
    a, lam = _kkt(M, Cq, f, eta)
    for _ in range(2):                       # the second call reuses the set-up
        kkt.solve(M, f, Cq, eta)
        assert np.allclose(kkt.a, a, rtol=1e-9, atol=1e-9 * np.abs(a).max())
        assert np.allclose(kkt.lam, lam, rtol=1e-9, atol=1e-9 * np.abs(lam).max())
    assert not kkt.pivoted and not kkt.dense
    assert kkt._bw <= 2                      # the chain's rows in band order: a narrow band


def test_a_block_of_m_that_changes_is_inverted_again_and_one_that_does_not_keeps_its_inverse():
    """The inverses of M's blocks are kept while a block is equal bit for bit (a constant mass
    matrix: ANCF elements, points); a block that changes (a rigid body's rotation) is inverted
    again, also one that changes in one pair of entries only."""
    rng = np.random.default_rng(7)
    sizes = np.array([3, 6, 2, 5])
    M, Cq, f = _chain(rng, sizes, rowsPerJoint=1)
    eta = rng.normal(size=Cq.shape[0])
    kkt = BlockKKT(M.shape[0], Cq.shape[0], _blocks_of(sizes), _no_empty)
    kkt.solve(M, f, Cq, eta)
    inverses = kkt._MinvB.copy()
    kkt.solve(M.copy(), f, Cq, eta)
    assert np.array_equal(kkt._MinvB, inverses)
    M2 = M.copy()
    M2[3:9, 3:9] += np.eye(6)                # block 1 changes
    M2[9, 10] += 1e-3                        # block 2 changes in one pair of entries
    M2[10, 9] += 1e-3
    kkt.solve(M2, f, Cq, eta)
    a, lam = _kkt(M2, Cq, f, eta)
    assert np.allclose(kkt.a, a, rtol=1e-10, atol=1e-10 * np.abs(a).max())
    assert np.allclose(kkt.lam, lam, rtol=1e-10, atol=1e-10 * np.abs(lam).max())
    kkt.solve(M, f, Cq, eta)                 # back to M: its own solution again
    a, lam = _kkt(M, Cq, f, eta)
    assert np.allclose(kkt.a, a, rtol=1e-10, atol=1e-10 * np.abs(a).max())
    kkt.constantM = M                        # the caller's constant M: not compared while it is passed
    kkt.solve(M, f, Cq, eta)
    assert np.allclose(kkt.a, a, rtol=1e-10, atol=1e-10 * np.abs(a).max())
    kkt.solve(M2, f, Cq, eta)                # another array: compared, and inverted again
    a2, _ = _kkt(M2, Cq, f, eta)
    assert np.allclose(kkt.a, a2, rtol=1e-10, atol=1e-10 * np.abs(a2).max())


def test_rows_that_change_blocks_are_ordered_again():
    rng = np.random.default_rng(7)
    sizes = [3] * 10
    M, Cq, f = _chain(rng, sizes, rowsPerJoint=1)
    eta = rng.normal(size=Cq.shape[0])
    kkt = BlockKKT(M.shape[0], Cq.shape[0], _blocks_of(sizes), _no_empty)
    kkt.solve(M, f, Cq, eta)
    bw = kkt._bw
    Cq2 = Cq.copy()
    Cq2[1, 27:30] = rng.normal(size=3)       # row 1 now acts on the last block too
    kkt.solve(M, f, Cq2, eta)
    a, lam = _kkt(M, Cq2, f, eta)
    assert kkt._bw > bw
    assert np.allclose(kkt.a, a, rtol=1e-9, atol=1e-9) and np.allclose(kkt.lam, lam, rtol=1e-9, atol=1e-9)


def test_redundant_rows_during_the_set_up_take_the_rank_revealing_path():
    rng = np.random.default_rng(3)
    sizes = [4, 5, 3, 6]
    M, Cq, f = _chain(rng, sizes)
    Cq = np.vstack([Cq, 2.0 * Cq[2] - Cq[4]])          # a dependent row
    eta = rng.normal(size=Cq.shape[0] - 1)
    eta = np.append(eta, 2.0 * eta[2] - eta[4])        # consistent
    kkt = BlockKKT(M.shape[0], Cq.shape[0], _blocks_of(sizes), _no_empty)
    kkt.solve(M, f, Cq, eta)
    assert kkt.pivoted
    a, _ = _kkt(M, Cq[:-1], f, eta[:-1])               # the accelerations are unique
    assert np.allclose(kkt.a, a, rtol=1e-8, atol=1e-8)
    assert np.allclose(M @ kkt.a + Cq.T @ kkt.lam, f, atol=1e-8)
    assert np.count_nonzero(np.abs(kkt.lam) < 1e-300) >= 1          # a dependent row's multiplier is 0


def test_rows_that_become_dependent_during_the_run_raise():
    rng = np.random.default_rng(4)
    sizes = [4, 5, 3]
    M, Cq, f = _chain(rng, sizes)
    eta = rng.normal(size=Cq.shape[0])
    kkt = BlockKKT(M.shape[0], Cq.shape[0], _blocks_of(sizes), _no_empty)
    kkt.solve(M, f, Cq, eta)
    kkt.settle()                             # the set-up is done: the run starts
    Cq2 = Cq.copy()
    Cq2[3] = Cq2[1]
    with pytest.raises(ConstraintError, match="singular constraint Jacobian"):
        kkt.solve(M, f, Cq2, eta)


def test_rows_that_become_dependent_before_the_set_up_is_done_switch():
    """An initial projection's solves come before settle(): rows found dependent there take the
    rank-revealing path, as at the first solve."""
    rng = np.random.default_rng(9)
    sizes = [4, 5, 3]
    M, Cq, f = _chain(rng, sizes)
    eta = rng.normal(size=Cq.shape[0])
    kkt = BlockKKT(M.shape[0], Cq.shape[0], _blocks_of(sizes), _no_empty)
    kkt.solve(M, f, Cq, eta)
    assert not kkt.pivoted
    Cq2 = Cq.copy()
    Cq2[3] = Cq2[1]
    eta2 = eta.copy()
    eta2[3] = eta2[1]
    kkt.solve(M, f, Cq2, eta2)
    assert kkt.pivoted
    assert np.allclose(M @ kkt.a + Cq2.T @ kkt.lam, f, atol=1e-8) and np.allclose(Cq2 @ kkt.a, eta2, atol=1e-8)


def test_a_row_without_coordinates_gets_lam_zero_and_is_reported():
    rng = np.random.default_rng(5)
    sizes = [3, 3, 3]
    M, Cq, f = _chain(rng, sizes)
    Cq[2] = 0.0
    eta = rng.normal(size=Cq.shape[0])
    seen = []
    kkt = BlockKKT(M.shape[0], Cq.shape[0], _blocks_of(sizes), lambda C, empty: seen.append(np.nonzero(empty)[0]))
    kkt.solve(M, f, Cq, eta)
    kkt.solve(M, f, Cq, eta)
    keep = np.arange(Cq.shape[0]) != 2
    a, lam = _kkt(M, Cq[keep], f, eta[keep])
    assert kkt.lam[2] == 0.0
    assert np.allclose(kkt.a, a, atol=1e-9) and np.allclose(kkt.lam[keep], lam, atol=1e-9)
    assert all(list(s) == [2] for s in seen) and len(seen) >= 2


def test_a_singular_block_of_m_falls_back_to_the_whole_kkt_matrix():
    rng = np.random.default_rng(6)
    sizes = [3, 2, 3]
    M, Cq, f = _chain(rng, sizes)
    M[3:5, 3:5] = np.diag([1.0, 0.0])                  # a massless coordinate ...
    row = np.zeros(M.shape[0])
    row[4] = 1.0                                       # ... that a constraint fixes
    Cq = np.vstack([Cq, row])
    eta = rng.normal(size=Cq.shape[0])
    kkt = BlockKKT(M.shape[0], Cq.shape[0], _blocks_of(sizes), _no_empty)
    kkt.solve(M, f, Cq, eta)
    assert kkt.dense
    a, lam = _kkt(M, Cq, f, eta)
    assert np.allclose(kkt.a, a, atol=1e-9) and np.allclose(kkt.lam, lam, atol=1e-9)


@pytest.mark.parametrize("nBlocks", [3, 20])
def test_the_whole_kkt_matrix_in_the_kernel_and_by_lapack_agree_with_a_direct_solve(nBlocks):
    """The dense fallback below DENSE_IN_KERNEL_MAX unknowns (the kernel's LU) and above it (numpy's
    LAPACK), with an inactive row (no coordinates: lam = 0, its equation checked) and a
    massless coordinate that a constraint fixes."""
    rng = np.random.default_rng(9)
    sizes = [3] * nBlocks
    M, Cq, f = _chain(rng, sizes, rowsPerJoint=1)
    M[3:6, 3:6] = np.diag([2.0, 0.0, 1.0])
    fix = np.zeros(M.shape[0])
    fix[4] = 1.0
    Cq = np.vstack([Cq, fix, np.zeros(M.shape[0])])
    eta = rng.normal(size=Cq.shape[0])
    seen = []
    kkt = BlockKKT(M.shape[0], Cq.shape[0], _blocks_of(sizes), lambda C, empty: seen.append(np.nonzero(empty)[0]))
    assert (M.shape[0] + Cq.shape[0] <= DENSE_IN_KERNEL_MAX) == (nBlocks == 3)
    for _ in range(2):
        kkt.solve(M, f, Cq, eta)
    assert kkt.dense
    keep = np.arange(Cq.shape[0]) != Cq.shape[0] - 1
    a, lam = _kkt(M, Cq[keep], f, eta[keep])
    assert kkt.lam[-1] == 0.0
    assert np.allclose(kkt.a, a, rtol=1e-10, atol=1e-10) and np.allclose(kkt.lam[keep], lam, rtol=1e-10, atol=1e-10)
    assert len(seen) >= 2 and all(list(s) == [Cq.shape[0] - 1] for s in seen)
    Cq[:, 4] = 0.0                                     # the massless coordinate free: singular
    Cq[-2, 0] = 1.0
    with pytest.raises(SimulationError, match="KKT matrix .* is singular"):
        kkt.solve(M, f, Cq, eta)


def test_no_rows():
    rng = np.random.default_rng(8)
    sizes = [2, 4]
    M, _, f = _chain(rng, sizes)
    kkt = BlockKKT(M.shape[0], 0, _blocks_of(sizes), _no_empty)
    kkt.solve(M, f, np.zeros((0, M.shape[0])), np.zeros(0))
    assert np.allclose(kkt.a, np.linalg.solve(M, f))
