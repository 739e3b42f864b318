"""Small allocation-free factorisations for the index-1 solve (eq. index1).

The Schur complement ``S = J M^-1 J^T`` of a multibody system is banded once its
constraint rows are ordered along the joint graph (reverse Cuthill-McKee, done at
compile time), so a band Cholesky costs ``O(m b^2)`` instead of ``O(m^3)``; it is computed
in its square-root-free form ``L D L^T`` (:func:`band_ldl_inplace`).  A
redundant constraint set (e.g. a planar four-bar closed by four revolute joints) makes
``S`` only positive *semi*-definite; the rank-revealing path is a Cholesky with
diagonal (complete) pivoting that drops the dependent rows.

Band storage: ``B[i, k] = S[i, i-k]`` for ``k = 0..bw`` (lower band, row-wise).

The rank rule (one rule for the set-up check, the time loop and the error messages)
---------------------------------------------------------------------------------
The constraints are numerically dependent at a state when a Cholesky pivot of
``S = J M^-1 J^T`` (the mass-weighted Schur complement, in the bodies' group velocity
coordinates) is ``<= REL_PIVOT_TOL * S_ii``, its own row's diagonal: the pivot is what is
left of ``S_ii`` once the rows before it are eliminated, so the rule asks whether row i
is (nearly) a combination of them, whatever the scale of the other rows.  This is the rule
``pivot <= REL_PIVOT_TOL`` on the Jacobi-scaled ``D^-1/2 S D^-1/2`` (D = diag S; unit
diagonal, entries of size at most 1), which the row scaling of a model cannot change.  A
rule relative to ``max(diag S)`` is not: a body with a tiny inertia (scaled by 1e-10 in
a slider-crank example) makes its rotation rows 1e11 times larger than a point
mass's rail row, and that rail row, independent of every other row, was taken for
redundant and dropped.

* the time loop's band Cholesky (no pivoting) applies it to its pivots and stops with
  ``STATUS_SINGULAR`` (the Simulator raises ConstraintError naming the joints);
* the rank-revealing path (redundant constraints) applies it to the complete-pivoted
  Cholesky: the rows whose pivots fall below it are dropped (:func:`pivoted_cholesky_solve`);
* the set-up check (``Simulator``) runs the time loop's own band Cholesky at the initial
  state.  If that meets the rule, the rank is the complete-pivoted one (same rule),
  the joints are named from the null space of S (:func:`schur_rank_and_null`), and the
  simulator switches to the rank-revealing path.  So a start that the time loop would
  reject at its first stage never passes construction, and a start that passes runs
  the band path with every pivot above the threshold.

Every Cholesky pivot of an SPD matrix is ``>= lambda_min``, so a band pivot meeting the
rule implies ``lambda_min(D^-1/2 S D^-1/2) <= REL_PIVOT_TOL``: the eigenvectors of the scaled
S with eigenvalues below that bound, which name the joints involved, always exist.
"""
import numpy as np
from numba import njit

# a pivot below REL_PIVOT_TOL * (its row's diagonal of S) is treated as zero.  The terms
# subtracted from S_ii are each at most S_ii (Cauchy-Schwarz), so a dependent row's pivot
# is round-off, about m eps S_ii (2e-14 for 100 rows): 1e-12 is 50 times above that.  It
# stays below regular but ill-conditioned mechanisms: the ratio is the squared sine of the
# angle between row i of J M^-1/2 and the rows before it, which a body of tiny inertia
# makes small.  A slider-crank example (crank and rod inertias scaled by 1e-10) has
# pivots down to 1.3e-10 S_ii and a smallest eigenvalue of the scaled S of 3e-11 over its
# run: a rule at 1e-10 stopped it at t = 0.29 s as "singular".  A redundant joint whose
# dependency a position drift d (relative to the mechanism's size) breaks has a pivot of
# about d^2 S_ii: still found for d up to 1e-6.
REL_PIVOT_TOL = 1e-12


@njit(cache=True, _nrt=False)
def max_abs(x):
    """``max |x_i|`` of a 1-D array, NaN if any entry is NaN, 0 for an empty one: numpy's
    ``np.max(np.abs(x))`` for the small vectors of Python code that runs once per step (its
    reduction machinery costs ten times this call on a vector of ten entries)."""
    m = 0.0
    for k in range(x.shape[0]):
        a = abs(x[k])
        if not a <= m:                   # (a NaN stays: nothing compares above it)
            m = a
            if a != a:
                return a
    return m


@njit(cache=True, forceinline=True, _nrt=False)
def band_ldl_inplace(B, m, bw, rel_tol, d0):
    """Factor ``S = L D L^T`` (unit lower L; the square-root-free Cholesky) in band storage:
    B's strict band becomes L, ``B[i, 0]`` becomes ``1 / D[i]``.  ``d0`` (length >= m) is
    scratch: it keeps the diagonal of S for the rank rule (module docstring).

    Right-looking: once column j is final, every entry of the trailing band it updates is
    independent of the others, so the dependency chain per column is one division and one
    multiply-subtract.  (The row-oriented L L^T before it chained every entry of a row on the
    previous one and paid a square root and a division per column.)  The pivot ``D[i]`` is the
    square of L L^T's, so the rank rule reads the same quantity.

    Returns -1 on success, otherwise the row index whose pivot ``D[i]`` was
    ``<= rel_tol * S_ii`` (a row without coordinates, ``S_ii = 0``, fails too)."""
    for j in range(m):
        d0[j] = B[j, 0]
    for j in range(m):
        d = B[j, 0]
        if d <= rel_tol * d0[j]:
            return j
        rd = 1.0 / d
        B[j, 0] = rd
        i1 = j + bw
        if i1 > m - 1:
            i1 = m - 1
        for i in range(j + 1, i1 + 1):
            # S[i, l] -= L[i, j] D[j] L[l, j] = S[i, j] L[l, j] (S[i, j] the entry before scaling)
            sij = B[i, i - j]
            lij = sij * rd
            B[i, i - j] = lij
            for l in range(j + 1, i):
                B[i, i - l] -= sij * B[l, l - j]
            B[i, 0] -= sij * lij
    return -1


@njit(cache=True, forceinline=True, _nrt=False)
def band_ldl_solve_inplace(B, m, bw, x):
    """Solve ``L D L^T x = x`` in place with the factor from :func:`band_ldl_inplace`
    (both triangular sweeps right-looking, as the factorisation)."""
    for j in range(m):
        xj = x[j]
        i1 = j + bw
        if i1 > m - 1:
            i1 = m - 1
        for i in range(j + 1, i1 + 1):
            x[i] -= B[i, i - j] * xj
    for j in range(m):
        x[j] *= B[j, 0]
    for k in range(m - 1, 0, -1):
        xk = x[k]
        i0 = k - bw
        if i0 < 0:
            i0 = 0
        for i in range(i0, k):
            x[i] -= B[k, k - i] * xk


@njit(cache=True, _nrt=False)
def pivoted_cholesky_solve(S, m, x, perm, y, rel_tol):
    """Rank-revealing solve of the PSD system S y = x (S overwritten).

    Cholesky with complete (diagonal) pivoting on the Jacobi-scaled S (module docstring):
    the pivot is the row with the largest remaining diagonal relative to its own diagonal
    of S, and the factorisation stops when that ratio is ``<= rel_tol``.  Rows beyond the
    numerical rank are redundant: their multipliers are set to zero, which gives one valid
    set of Lagrange multipliers (the accelerations do not depend on the choice as long as
    the redundant equations are consistent).  ``perm`` (int) and ``y`` (float) are
    length-m workspaces (``y`` holds diag S during the factorisation).  Returns the
    numerical rank.
    """
    for i in range(m):
        perm[i] = i
        y[i] = S[i, i]
    rank = m
    for k in range(m):
        # choose the pivot: largest remaining diagonal relative to its row's diagonal
        p = k
        best = -1.0
        for i in range(k, m):
            pi = perm[i]
            d0 = y[pi]
            ratio = S[pi, pi] / d0 if d0 > 0.0 else 0.0
            if ratio > best:
                best = ratio
                p = i
        if best <= rel_tol:
            rank = k
            break
        tmp = perm[k]
        perm[k] = perm[p]
        perm[p] = tmp
        pk = perm[k]
        piv = np.sqrt(S[pk, pk])
        S[pk, pk] = piv
        for i in range(k + 1, m):
            pi = perm[i]
            S[pi, pk] = S[pi, pk] / piv
        for i in range(k + 1, m):
            pi = perm[i]
            lik = S[pi, pk]
            for j in range(k + 1, i + 1):
                pj = perm[j]
                S[pi, pj] -= lik * S[pj, pk]
                if j != i:
                    S[pj, pi] = S[pi, pj]
    # forward/back substitution on the leading rank x rank block (L stored at [perm[i], perm[k]])
    for i in range(rank):
        pi = perm[i]
        s = x[pi]
        for k in range(i):
            s -= S[pi, perm[k]] * y[k]
        y[i] = s / S[pi, pi]
    for i in range(rank - 1, -1, -1):
        pi = perm[i]
        s = y[i]
        for k in range(i + 1, rank):
            s -= S[perm[k], pi] * y[k]
        y[i] = s / S[pi, pi]
    for i in range(m):
        x[i] = 0.0
    for i in range(rank):
        x[perm[i]] = y[i]
    return rank


def schur_rank_and_null(S, rel_tol=REL_PIVOT_TOL, forced=False):
    """The rank rule on a dense ``S = J M^-1 J^T`` (module docstring).

    Returns ``(rank, null)``: ``rank`` from the complete-pivoted Cholesky with the
    kernel's tolerance, ``null`` (m, k) orthonormal vectors spanning the numerical null
    space of the Jacobi-scaled S (whose support names the same rows as S's): the
    eigenvectors with eigenvalues ``<= rel_tol``, at least ``m - rank`` of them.  ``forced``: the band Cholesky met the rule at this
    state, so at least one null vector is returned (the smallest eigenvalue's)."""
    S = np.array(S, dtype=float)
    m = S.shape[0]
    if m == 0:
        return 0, np.zeros((0, 0))
    S = 0.5 * (S + S.T)
    rank = int(pivoted_cholesky_solve(np.ascontiguousarray(S.copy()), m, np.zeros(m), np.zeros(m, np.int64),
                                      np.zeros(m), float(rel_tol)))
    d = np.diag(S).copy()
    s = np.where(d > 0.0, 1.0 / np.sqrt(np.where(d > 0.0, d, 1.0)), 0.0)
    w, U = np.linalg.eigh(s[:, None] * S * s[None, :])     # the scaled S of the rank rule
    k = max(int(np.sum(w <= rel_tol)), m - rank, 1 if forced else 0)
    return rank, U[:, :k]


def rows_in_null_space(null, rel=1e-6):
    """Rows taking part in the dependencies spanned by the null vectors ``null`` (m, k):
    those with a weight above ``rel`` times the largest."""
    if null.size == 0:
        return []
    weight = np.linalg.norm(null, axis=1)
    return [int(q) for q in np.nonzero(weight > rel * weight.max())[0]]


def rcm_order(n, edges):
    """Reverse Cuthill-McKee ordering of an undirected graph with ``n`` nodes."""
    adj = [[] for _ in range(n)]
    for a, b in edges:
        if a != b:
            adj[a].append(b)
            adj[b].append(a)
    deg = [len(set(x)) for x in adj]
    seen = [False] * n
    order = []
    for start in sorted(range(n), key=lambda i: deg[i]):
        if seen[start]:
            continue
        seen[start] = True
        queue = [start]
        while queue:
            v = queue.pop(0)
            order.append(v)
            for w in sorted(set(adj[v]), key=lambda i: deg[i]):
                if not seen[w]:
                    seen[w] = True
                    queue.append(w)
    return order[::-1]


@njit(cache=True, _nrt=False)
def lu_factor_inplace(E, m, piv, tol):
    """LU with partial pivoting of the leading ``m x m`` block of ``E`` in place (``L`` unit lower,
    ``U`` upper; whole rows exchanged, recorded in ``piv``).  Returns -1, or the first column whose
    pivot is at or below ``tol`` (the factorisation stops there).  For the non-symmetric systems:
    the oblique rows' index-1 solve (mbs/index1.py) and the implicit stages' Newton matrix
    (mbs/implicit.py)."""
    for k in range(m):
        p = k
        big = abs(E[k, k])
        for i in range(k + 1, m):
            if abs(E[i, k]) > big:
                big = abs(E[i, k])
                p = i
        if big <= tol:
            return k
        piv[k] = p
        if p != k:
            for c in range(m):
                E[k, c], E[p, c] = E[p, c], E[k, c]
        inv = 1.0 / E[k, k]
        for i in range(k + 1, m):
            f = E[i, k] * inv
            if f != 0.0:
                E[i, k] = f
                for c in range(k + 1, m):
                    E[i, c] -= f * E[k, c]
    return -1


@njit(cache=True, _nrt=False)
def lu_solve_inplace(E, m, piv, x):
    """``x <- E_original^-1 x`` with the factors of :func:`lu_factor_inplace`: the row exchanges,
    then forward elimination and back substitution, both along rows of ``E`` (contiguous: a
    column of a 1,728 x 1,728 matrix is 1,728 cache lines, and the Newton iteration of the implicit
    stages solves many times per factorisation).  The forward sums subtract in the order of a
    factorisation that carries ``x`` along (``k = 0, 1, ...``), as a column sweep would."""
    for k in range(m):
        p = piv[k]
        if p != k:
            x[k], x[p] = x[p], x[k]
    for i in range(1, m):
        s = x[i]
        for k in range(i):
            f = E[i, k]
            if f != 0.0:
                s -= f * x[k]
        x[i] = s
    for k in range(m - 1, -1, -1):
        s = x[k]
        for c in range(k + 1, m):
            s -= E[k, c] * x[c]
        x[k] = s / E[k, k]


@njit(cache=True, _nrt=False)
def band_lu_factor_inplace(E, m, kl, ku, piv):
    """LU with partial pivoting of the leading ``m x m`` block of ``E`` when it is a band matrix
    of lower bandwidth ``kl`` and upper ``ku`` (dense storage; entries outside the band are not
    read).  The row exchanges give ``U`` the upper bandwidth ``kl + ku``: those entries of ``E``
    must be zero on entry.  As LAPACK's gbtrf, each step exchanges only the columns from its own
    on and the multipliers stay where they were computed, so :func:`band_lu_solve_extents`
    applies the exchanges and the eliminations in turn.  ``m kl (kl + ku)`` operations against
    ``m^3 / 3`` for :func:`lu_factor_inplace`.  Returns -1, or the first column with a zero
    pivot."""
    ku2 = kl + ku
    for k in range(m):
        last = min(m - 1, k + kl)
        p = k
        big = abs(E[k, k])
        for i in range(k + 1, last + 1):
            if abs(E[i, k]) > big:
                big = abs(E[i, k])
                p = i
        if big == 0.0:
            return k
        piv[k] = p
        cend = min(m - 1, k + ku2)
        if p != k:
            for c in range(k, cend + 1):
                E[k, c], E[p, c] = E[p, c], E[k, c]
        inv = 1.0 / E[k, k]
        for i in range(k + 1, last + 1):
            f = E[i, k] * inv
            E[i, k] = f
            if f != 0.0:
                for c in range(k + 1, cend + 1):
                    E[i, c] -= f * E[k, c]
    return -1


@njit(cache=True, _nrt=False)
def band_lu_extents(E, m, kl, ku, lend, uend):
    """The last entry that is not zero of each column of ``L`` (``lend[k]``, a row) and of each
    row of ``U`` (``uend[a]``, a column) of :func:`band_lu_factor_inplace`'s factors: a matrix of
    separate mechanisms is block diagonal inside its band, and the solve need not run over the
    band's zeros."""
    for k in range(m):
        last = k
        for i in range(k + 1, min(m - 1, k + kl) + 1):
            if E[i, k] != 0.0:
                last = i
        lend[k] = last
        last = k
        for c in range(k + 1, min(m - 1, k + kl + ku) + 1):
            if E[k, c] != 0.0:
                last = c
        uend[k] = last


@njit(cache=True, _nrt=False)
def band_lu_solve_extents(E, m, piv, lend, uend, x):
    """``x <- E_original^-1 x`` with the factors of :func:`band_lu_factor_inplace`, running over
    each column of ``L`` and row of ``U`` up to its extent (:func:`band_lu_extents`; or the band's
    own, ``k + kl`` and ``k + kl + ku``, capped at ``m - 1``)."""
    for k in range(m):
        p = piv[k]
        if p != k:
            x[k], x[p] = x[p], x[k]
        xk = x[k]
        if xk != 0.0:
            for i in range(k + 1, lend[k] + 1):
                x[i] -= E[i, k] * xk
    for k in range(m - 1, -1, -1):
        s = x[k]
        for c in range(k + 1, uend[k] + 1):
            s -= E[k, c] * x[c]
        x[k] = s / E[k, k]
