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
coordinates) is ``<= REL_PIVOT_TOL * max(diag S)``:

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

Every Cholesky pivot of an SPD matrix is ``>= lambda_min(S)``, so a band pivot meeting
the rule implies ``lambda_min(S) <= REL_PIVOT_TOL * max(diag S)``: the eigenvectors of S
with eigenvalues below that bound, which name the joints involved, always exist.
"""
import numpy as np
from numba import njit

# a pivot below REL_PIVOT_TOL * (largest diagonal of S) is treated as zero: with
# entries of S computed to ~1e-16 relative, 1e-10 leaves a wide margin for
# ill-conditioned but regular systems while catching genuine rank loss.  (S is J M^-1 J^T,
# so this is sigma_min / sigma_max ~ 1e-5 for the mass-weighted J M^-1/2.)
REL_PIVOT_TOL = 1e-10


@njit(cache=True, forceinline=True, _nrt=False)
def band_ldl_inplace(B, m, bw, tol):
    """Factor ``S = L D L^T`` (unit lower L; the square-root-free Cholesky) in band storage:
    B's strict band becomes L, ``B[i, 0]`` becomes ``1 / D[i]``.

    Right-looking: once column j is final, every entry of the trailing band it updates is
    independent of the others, so the dependency chain per column is one division and one
    multiply-subtract.  (The row-oriented L L^T before it chained every entry of a row on the
    previous one and paid a square root and a division per column.)  The pivot ``D[i]`` is the
    square of L L^T's, so the rank rule reads the same quantity.

    Returns -1 on success, otherwise the row index whose pivot ``D[i]`` was <= tol."""
    for j in range(m):
        d = B[j, 0]
        if d <= tol:
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

    Cholesky with complete (diagonal) pivoting; stops when the largest remaining
    diagonal drops below ``rel_tol * max(diag S)``.  Rows beyond the numerical rank
    are redundant: their multipliers are set to zero, which gives one valid set of
    Lagrange multipliers (the accelerations do not depend on the choice as long as
    the redundant equations are consistent).  ``perm`` (int) and ``y`` (float) are
    length-m workspaces.  Returns the numerical rank.
    """
    for i in range(m):
        perm[i] = i
    dmax = 0.0
    for i in range(m):
        if S[i, i] > dmax:
            dmax = S[i, i]
    tol = rel_tol * dmax
    rank = m
    for k in range(m):
        # choose the pivot: largest remaining diagonal
        p = k
        best = S[perm[k], perm[k]]
        for i in range(k + 1, m):
            d = S[perm[i], perm[i]]
            if d > best:
                best = d
                p = i
        if best <= tol:
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
    space of S (of J^T): the eigenvectors with eigenvalues ``<= rel_tol * max(diag S)``,
    at least ``m - rank`` of them.  ``forced``: the band Cholesky met the rule at this
    state, so at least one null vector is returned (the smallest eigenvalue's)."""
    S = np.array(S, dtype=float)
    m = S.shape[0]
    if m == 0:
        return 0, np.zeros((0, 0))
    S = 0.5 * (S + S.T)
    dmax = float(np.max(np.diag(S)))
    rank = int(pivoted_cholesky_solve(np.ascontiguousarray(S.copy()), m, np.zeros(m), np.zeros(m, np.int64),
                                      np.zeros(m), float(rel_tol)))
    w, U = np.linalg.eigh(S)
    k = max(int(np.sum(w <= rel_tol * dmax)), m - rank, 1 if forced else 0)
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
