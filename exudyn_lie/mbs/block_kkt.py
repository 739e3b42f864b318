"""Index-1 accelerations of generalised coordinates with a block-diagonal mass matrix
(eq. index1): ``[M C_q^T; C_q 0][a; lam] = [f; eta]``.

The kernel's body solve (:mod:`.index1`) takes 6 x 6 body blocks and rows that touch at
most two bodies.  This one takes any block sizes and rows of any width (flexible bodies,
coordinate constraints, a whole model evaluated elsewhere), stored densely, through the
same factorisations and the same rank rule (:mod:`.linalg`):

* every diagonal block of M is inverted once per call;
* the Schur complement ``S = C_q M^-1 C_q^T`` is assembled block by block, only between
  rows that share a block, straight into band storage in the reverse Cuthill-McKee order of
  the rows (rows adjacent when they act on the same block), so that for chains and trees
  the cost is linear in the number of blocks; it is factored by the band ``L D L^T``;
* a redundant row set (S only semi-definite at the first solve) switches to the
  rank-revealing Cholesky, whose dependent rows get ``lam = 0``;
* a row without any coordinate (an inactive connector, whose equation is ``lam = 0``)
  gets ``lam = 0``;
* a singular block of M (a coordinate whose mass is zero and that a constraint fixes)
  falls back to the whole KKT matrix, in least squares when the rows are redundant.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ..errors import ConstraintError, SimulationError
from .linalg import (REL_PIVOT_TOL, band_ldl_inplace, band_ldl_solve_inplace, lu_factor_inplace, lu_solve_inplace,
                     pivoted_cholesky_solve, rcm_order)

# statuses of schur_band_solve and dense_kkt_solve
KKT_OK, KKT_SINGULAR_BLOCK, KKT_SINGULAR_SCHUR, KKT_BEYOND_BAND, KKT_EMPTY_ROWS, KKT_SINGULAR = 0, 1, 2, 3, 4, 5

#: the whole KKT matrix up to this order is factored in the kernel (unblocked LU): below it,
#: numpy's LAPACK call costs more in its Python set-up (copies, the active rows) than in
#: flops; measured on one core, LU and solve: 8 unknowns 1.1 us (numpy 3.8), 32: 8.1 (9.5),
#: 64: 52 (27 plus about 30 of set-up), 128: 409 (121)
DENSE_IN_KERNEL_MAX = 64


@njit(cache=True, inline="always")
def invert_block(M, blk, p0, s, W):
    """``W[:s, s:2s]`` <- the inverse of the block ``M[blk[p0:p0+s], blk[p0:p0+s]]``
    (Gauss-Jordan with partial pivoting in ``W``, (>= s, >= 2s) scratch).  Returns False if
    a pivot is at most 1e-14 x the block's largest diagonal entry (singular block)."""
    for i in range(s):
        for k in range(s):
            W[i, k] = M[blk[p0 + i], blk[p0 + k]]
            W[i, s + k] = 1.0 if i == k else 0.0
    scale = 0.0
    for i in range(s):
        scale = max(scale, abs(W[i, i]))
    for c in range(s):
        piv = c
        for i in range(c + 1, s):
            if abs(W[i, c]) > abs(W[piv, c]):
                piv = i
        if scale == 0.0 or abs(W[piv, c]) <= 1e-14 * scale:
            return False
        if piv != c:
            for k in range(2 * s):
                tmp = W[c, k]
                W[c, k] = W[piv, k]
                W[piv, k] = tmp
        d = 1.0 / W[c, c]
        for k in range(2 * s):
            W[c, k] *= d
        for i in range(s):
            if i != c:
                g = W[i, c]
                if g != 0.0:
                    for k in range(2 * s):
                        W[i, k] -= g * W[c, k]
    return True


@njit(cache=True)
def invert_blocks(M, blk, blkPtr, blkOff, MinvB, W, MB, MBok, unchanged):
    """The inverse of every diagonal block of M into the flat storage ``MinvB[blkOff[b]:]``
    (row-major s x s); ``W`` (smax, 2 smax) scratch.  Returns False if a block is singular.

    ``MB`` (``MinvB``'s layout) holds the blocks last inverted and ``MBok[b]`` whether
    ``MinvB`` is their inverse: a block equal to it bit for bit keeps its inverse.  The mass
    matrix of most items is constant (ANCF elements, points, 2D bodies), and the s^3 inversion
    of a large block (a cable's nodes share one) cost more than the rest of a stage's evaluation
    of the model; the s^2 comparison does not change any result.  ``unchanged``: the caller
    passes the same, unchanged M as last time (a constant mass matrix evaluated once): no
    comparison either."""
    for bI in range(blkPtr.shape[0] - 1):
        if unchanged and MBok[bI] != 0:
            continue
        p0 = blkPtr[bI]
        s = blkPtr[bI + 1] - p0
        o = blkOff[bI]
        same = MBok[bI] != 0
        for i in range(s):
            for k in range(s):
                v = M[blk[p0 + i], blk[p0 + k]]
                if MB[o + i * s + k] != v:
                    same = False
                    MB[o + i * s + k] = v
        if same:
            continue
        MBok[bI] = 0
        if not invert_block(M, blk, p0, s, W):
            return False
        for i in range(s):
            for k in range(s):
                MinvB[o + i * s + k] = W[i, s + k]
        MBok[bI] = 1
    return True


@njit(cache=True)
def _rows_of_blocks(Cq, eta, a, blockOf, pos, nzIdx, nzCnt, rowBlk, rowBlkCnt, bRowPtr, bRows, cnt, x):
    """The nonzero columns (``nzIdx``, ``nzCnt``) and blocks (``rowBlk``, ``rowBlkCnt``) of
    every row, the rows of every block (CSR ``bRowPtr``, ``bRows``) and the right-hand side
    ``x = C_q a0 - eta`` in band order."""
    n = Cq.shape[1]
    m = Cq.shape[0]
    nb = bRowPtr.shape[0] - 1
    for bI in range(nb):
        cnt[bI] = 0
    for r in range(m):
        c_ = 0
        nbk = 0
        acc = 0.0
        for k in range(n):
            ck = Cq[r, k]
            if ck != 0.0:
                nzIdx[r, c_] = k
                c_ += 1
                acc += ck * a[k]
                bk = blockOf[k]
                new = True
                for q in range(nbk):
                    if rowBlk[r, q] == bk:
                        new = False
                        break
                if new:
                    rowBlk[r, nbk] = bk
                    nbk += 1
                    cnt[bk] += 1
        nzCnt[r] = c_
        rowBlkCnt[r] = nbk
        x[pos[r]] = acc - eta[r]
    bRowPtr[0] = 0
    for bI in range(nb):
        bRowPtr[bI + 1] = bRowPtr[bI] + cnt[bI]
        cnt[bI] = 0
    for r in range(m):
        for q in range(rowBlkCnt[r]):
            bk = rowBlk[r, q]
            bRows[bRowPtr[bk] + cnt[bk]] = r
            cnt[bk] += 1


@njit(cache=True)
def _assemble_band(Cq, blk, blkPtr, blkOff, pos, bw, MinvB, bRowPtr, bRows, Y, Band):
    """``Band[i, i - j] = S[perm i, perm j]``, ``S = C_q M^-1 C_q^T`` block by block; False if
    two rows that share a block lie beyond the band."""
    m = Band.shape[0]
    for i in range(m):
        for k in range(bw + 1):
            Band[i, k] = 0.0
    for bI in range(blkPtr.shape[0] - 1):
        r0 = bRowPtr[bI]
        nr = bRowPtr[bI + 1] - r0
        if nr == 0:
            continue
        p0 = blkPtr[bI]
        s = blkPtr[bI + 1] - p0
        o = blkOff[bI]
        for q in range(nr):              # Y[q] = M_B^-1 C_q[row q, B]^T
            c = bRows[r0 + q]
            for i in range(s):
                acc = 0.0
                for k in range(s):
                    acc += MinvB[o + i * s + k] * Cq[c, blk[p0 + k]]
                Y[q, i] = acc
        for q1 in range(nr):
            r = bRows[r0 + q1]
            pr = pos[r]
            for q2 in range(nr):
                c = bRows[r0 + q2]
                pc = pos[c]
                if pc > pr:
                    continue
                if pr - pc > bw:
                    return False
                acc = 0.0
                for i in range(s):
                    acc += Cq[r, blk[p0 + i]] * Y[q2, i]
                Band[pr, pr - pc] += acc
    return True


@njit(cache=True)
def _subtract_reactions(Cq, lam, blk, blkPtr, blkOff, MinvB, bRowPtr, bRows, T, a):
    """``a -= M^-1 C_q^T lam``, block by block."""
    for bI in range(blkPtr.shape[0] - 1):
        r0 = bRowPtr[bI]
        nr = bRowPtr[bI + 1] - r0
        if nr == 0:
            continue
        p0 = blkPtr[bI]
        s = blkPtr[bI + 1] - p0
        o = blkOff[bI]
        for i in range(s):
            acc = 0.0
            for q in range(nr):
                r = bRows[r0 + q]
                acc += Cq[r, blk[p0 + i]] * lam[r]
            T[i] = acc
        for i in range(s):
            acc = 0.0
            for k in range(s):
                acc += MinvB[o + i * s + k] * T[k]
            a[blk[p0 + i]] -= acc


@njit(cache=True)
def schur_band_solve(M, f, Cq, eta, blk, blkPtr, blkOff, blockOf, pos, bw, pivoted, MinvB, W, MB, MBok, unchanged,
                     a, lam, nzIdx, nzCnt, rowBlk, rowBlkCnt, bRowPtr, bRows, cnt, Y, Band, x, T, Sd, perm, yw):
    """``a``, ``lam`` of ``[M C_q^T; C_q 0][a; lam] = [f; eta]`` (module docstring).

    M is block diagonal (``blk``, ``blkPtr``; ``blockOf`` coordinate -> block); ``pos`` is
    the rows' band order (row -> position) and ``bw`` the bandwidth of S in it.  With
    ``pivoted`` (bandwidth m - 1) S is copied to ``Sd`` and solved by the rank-revealing
    Cholesky (``perm``, ``yw``).  Returns KKT_OK; KKT_EMPTY_ROWS if some rows have no
    coordinate (``nzCnt`` tells which; their ``lam`` is 0); KKT_SINGULAR_BLOCK;
    KKT_SINGULAR_SCHUR (not pivoted); KKT_BEYOND_BAND if two rows sharing a block lie beyond
    the band (the pattern changed: order the rows again)."""
    m = eta.shape[0]
    nb = blkPtr.shape[0] - 1
    if not invert_blocks(M, blk, blkPtr, blkOff, MinvB, W, MB, MBok, unchanged):
        return KKT_SINGULAR_BLOCK
    for bI in range(nb):                 # a0 = M^-1 f
        p0 = blkPtr[bI]
        s = blkPtr[bI + 1] - p0
        o = blkOff[bI]
        for i in range(s):
            acc = 0.0
            for k in range(s):
                acc += MinvB[o + i * s + k] * f[blk[p0 + k]]
            a[blk[p0 + i]] = acc
    if m == 0:
        return KKT_OK
    _rows_of_blocks(Cq, eta, a, blockOf, pos, nzIdx, nzCnt, rowBlk, rowBlkCnt, bRowPtr, bRows, cnt, x)
    if not _assemble_band(Cq, blk, blkPtr, blkOff, pos, bw, MinvB, bRowPtr, bRows, Y, Band):
        return KKT_BEYOND_BAND
    empty = False
    for r in range(m):
        if nzCnt[r] == 0:                # lam = 0 for a row without coordinates
            Band[pos[r], 0] = 1.0
            x[pos[r]] = 0.0
            empty = True
    if pivoted:
        for i in range(m):
            for j in range(i + 1):
                v = Band[i, i - j]
                Sd[i, j] = v
                Sd[j, i] = v
        pivoted_cholesky_solve(Sd, m, x, perm, yw, REL_PIVOT_TOL)
    else:
        if band_ldl_inplace(Band, m, bw, REL_PIVOT_TOL, yw) >= 0:
            return KKT_SINGULAR_SCHUR
        band_ldl_solve_inplace(Band, m, bw, x)
    for r in range(m):
        lam[r] = x[pos[r]]
    _subtract_reactions(Cq, lam, blk, blkPtr, blkOff, MinvB, bRowPtr, bRows, T, a)
    return KKT_EMPTY_ROWS if empty else KKT_OK


@njit(cache=True)
def dense_kkt_solve(M, f, Cq, eta, K, piv, x, active, a, lam):
    """``a``, ``lam`` of the whole KKT matrix by LU with partial pivoting (small systems,
    :data:`DENSE_IN_KERNEL_MAX`); rows without coordinates are left out (``lam = 0``).
    Returns KKT_OK, KKT_EMPTY_ROWS when such rows exist (the caller checks their equations), or
    KKT_SINGULAR on an exactly zero pivot (numpy's LAPACK rule)."""
    n = M.shape[0]
    m = Cq.shape[0]
    k = 0
    for r in range(m):
        for c in range(n):
            if Cq[r, c] != 0.0:
                active[k] = r
                k += 1
                break
    N = n + k
    for i in range(n):
        for j in range(n):
            K[i, j] = M[i, j]
        x[i] = f[i]
    for p in range(k):
        r = active[p]
        for j in range(n):
            K[n + p, j] = Cq[r, j]
            K[j, n + p] = Cq[r, j]
        for q in range(k):
            K[n + p, n + q] = 0.0
        x[n + p] = eta[r]
    if lu_factor_inplace(K, N, piv, 0.0) >= 0:
        return KKT_SINGULAR
    lu_solve_inplace(K, N, piv, x)
    for i in range(n):
        a[i] = x[i]
    for r in range(m):
        lam[r] = 0.0
    for p in range(k):
        lam[active[p]] = x[n + p]
    return KKT_EMPTY_ROWS if k < m else KKT_OK


_SINGULAR_KKT = ("the KKT matrix [M Cq^T; Cq 0] is singular (a coordinate without mass that no constraint "
                 "fixes?); exudyn_lie cannot compute accelerations")


class BlockKKT:
    """The solve of the module docstring for ``n`` coordinates and ``m`` rows, with its
    workspace.  ``blocks(M)`` gives the block structure ``(blk, blkPtr)`` at the first
    solve (coordinate indices of every block; the caller knows which coordinates belong
    together); ``check_rows(Cq, empty)`` is told of rows without coordinates (it raises if
    their equation is not ``lam = 0``).  ``a`` and ``lam`` hold the last solution.  Until
    :meth:`settle`, a singular Schur complement means redundant rows (the rank-revealing
    solve from then on); after it, a ConstraintError."""

    def __init__(self, n, m, blocks, check_rows, verbose=False):
        self.n, self.m = n, m
        self._blocks, self._check_rows = blocks, check_rows
        self.verbose = verbose
        self.a = np.zeros(n)
        self.lam = np.zeros(m)
        self.pivoted = False          # redundant rows: rank-revealing Cholesky
        self.dense = False            # a singular block of M: the whole KKT matrix
        self.settled = False          # set-up done: redundant rows from now on are an error
        self.blk = None
        self.constantM = None         # the caller's M that never changes (its blocks are not compared)
        self._nzIdx = np.zeros((m, n), np.int64)
        self._nzCnt = np.zeros(m, np.int64)
        self._perm = np.zeros(m, np.int64)
        self._yw = np.zeros(m)
        self._K = None                # dense_kkt_solve's workspace

    def _set_up(self, M):
        n, m = self.n, self.m
        self.blk, self.blkPtr = self._blocks(M)
        sizes = np.diff(self.blkPtr)
        nb = len(sizes)
        self.blockOf = np.zeros(n, np.int64)
        for b in range(nb):
            self.blockOf[self.blk[self.blkPtr[b]:self.blkPtr[b + 1]]] = b
        self.blkOff = np.concatenate([[0], np.cumsum(sizes * sizes)]).astype(np.int64)
        smax = int(sizes.max()) if nb else 1
        self._MinvB = np.zeros(int(self.blkOff[-1]))
        self._MB = np.zeros(int(self.blkOff[-1]))
        self._MBok = np.zeros(nb, np.int64)
        self._W = np.zeros((smax, 2 * smax))
        self._T = np.zeros(smax)
        self._rowBlk = np.zeros((m, max(nb, 1)), np.int64)
        self._rowBlkCnt = np.zeros(m, np.int64)
        self._bRowPtr = np.zeros(nb + 1, np.int64)
        self._bRows = np.zeros(max(m * nb, 1), np.int64)
        self._cnt = np.zeros(max(nb, 1), np.int64)
        self._Y = np.zeros((max(m, 1), smax))
        self._x = np.zeros(m)
        self._Sd = np.zeros((0, 0))
        self._pos = np.arange(m, dtype=np.int64)
        self._bw = 0
        self._band = np.zeros((m, 1))

    def _order_rows(self, Cq):
        """Reverse Cuthill-McKee order of the rows (adjacent when they act on the same block
        of M) and the bandwidth of S in it; the whole band when pivoted."""
        m = self.m
        if self.pivoted:
            self._pos = np.arange(m, dtype=np.int64)
            self._bw = max(m - 1, 0)
        else:
            rowsOf = {}
            for r in range(m):
                for b in np.unique(self.blockOf[np.nonzero(Cq[r])[0]]):
                    rowsOf.setdefault(int(b), []).append(r)
            edges = [(r, c) for rows in rowsOf.values() for r in rows for c in rows if r < c]
            order = rcm_order(m, edges)
            self._pos = np.zeros(m, np.int64)
            self._pos[np.asarray(order, np.int64)] = np.arange(m)
            self._bw = int(max((abs(self._pos[r] - self._pos[c]) for r, c in edges), default=0))
        self._band = np.zeros((m, self._bw + 1))

    def _band_solve(self, M, f, Cq, eta):
        if self.pivoted and self._Sd.shape[0] != self.m:
            self._Sd = np.zeros((self.m, self.m))
        unchanged = self.constantM is not None and M is self.constantM
        return schur_band_solve(M, f, Cq, eta, self.blk, self.blkPtr, self.blkOff, self.blockOf, self._pos,
                                self._bw, self.pivoted, self._MinvB, self._W, self._MB, self._MBok, unchanged, self.a,
                                self.lam, self._nzIdx, self._nzCnt, self._rowBlk, self._rowBlkCnt, self._bRowPtr,
                                self._bRows, self._cnt, self._Y, self._band, self._x, self._T, self._Sd, self._perm,
                                self._yw)

    def solve(self, M, f, Cq, eta):
        """``a``, ``lam`` of ``[M C_q^T; C_q 0][a; lam] = [f; eta]`` (M n x n, C_q m x n)."""
        first = self.blk is None
        if first:
            self._set_up(M)
            if self.m:
                self._check_rows(Cq, ~np.any(Cq != 0.0, axis=1))
                self._order_rows(Cq)
        if self.dense:
            return self._dense_solve(M, f, Cq, eta)
        for _ in range(2):
            st = self._band_solve(M, f, Cq, eta)
            if st != KKT_BEYOND_BAND:
                break
            self._order_rows(Cq)          # rows act on other blocks now: a new order
        if st == KKT_SINGULAR_SCHUR and not self.settled:
            # redundant constraints at the initial state (e.g. a closed planar loop)
            self.pivoted = True
            if self.verbose:
                print("exudyn_lie: the constraints are redundant (J M^-1 J^T is singular at the initial state); "
                      "rank-revealing Cholesky from now on (multipliers of dependent rows 0)")
            self._order_rows(Cq)
            st = self._band_solve(M, f, Cq, eta)
        if st == KKT_OK:
            return
        if st == KKT_EMPTY_ROWS:
            self._check_rows(Cq, self._nzCnt == 0)
            return
        if st == KKT_SINGULAR_SCHUR:
            raise ConstraintError("singular constraint Jacobian: the constraints became linearly dependent "
                                  f"(a Cholesky pivot of J M^-1 J^T fell to {REL_PIVOT_TOL:g} x its row's "
                                  f"diagonal or below: a singular configuration); check the joint frames")
        if st == KKT_SINGULAR_BLOCK:
            self.dense = True
            if self.verbose:
                print("exudyn_lie: the mass matrix has a singular block; solving the dense KKT system from now on")
            return self._dense_solve(M, f, Cq, eta)
        raise SimulationError(f"internal: Schur solve status {st}")

    def settle(self):
        """The set-up is done (initial projection, first accelerations): rows that are
        dependent from now on make the constraint Jacobian singular (ConstraintError) instead of
        switching to the rank-revealing solve."""
        self.settled = True

    def _dense_solve(self, M, f, Cq, eta):
        n = self.n
        if n + self.m <= DENSE_IN_KERNEL_MAX and not self.pivoted:
            if self._K is None:
                N = n + self.m
                self._K, self._piv, self._xK = np.zeros((N, N)), np.zeros(N, np.int64), np.zeros(N)
                self._active = np.zeros(max(self.m, 1), np.int64)
            st = dense_kkt_solve(M, f, Cq, eta, self._K, self._piv, self._xK, self._active, self.a, self.lam)
            if st == KKT_OK:
                return
            if st == KKT_SINGULAR:
                raise SimulationError(_SINGULAR_KKT)
            self._check_rows(Cq, ~np.any(Cq != 0.0, axis=1))
            return
        empty = ~np.any(Cq != 0.0, axis=1)
        if self.m:
            self._check_rows(Cq, empty)
        active = np.nonzero(~empty)[0]
        C = Cq[active]
        k = len(active)
        K = np.zeros((n + k, n + k))
        K[:n, :n] = M
        K[:n, n:] = C.T
        K[n:, :n] = C
        rhs = np.concatenate([f, eta[active]])
        try:
            x = np.linalg.lstsq(K, rhs, rcond=1e-12)[0] if self.pivoted else np.linalg.solve(K, rhs)
        except np.linalg.LinAlgError:
            raise SimulationError(_SINGULAR_KKT) from None
        self.a[:] = x[:n]
        self.lam[:] = 0.0
        self.lam[active] = x[n:]
