"""The index-1 solve in linear time for tree-structured constraint graphs.

The Schur complement ``S = J A J^T`` (``A = M^-1`` in the bodies' velocity coordinates,
eq. index1) couples every pair of rows that share a body, so a body carrying many joints
(the hub of a star) makes ``S`` dense and its band Cholesky cubic.  The augmented system
``[A^-1 ...]`` is sparse instead: when the bodies and the joints between two bodies form a
forest with at most one body on the ground in each tree, it can be eliminated from the
leaves to the root without fill-in (D. Baraff, "Linear-time dynamics
using Lagrange multipliers", SIGGRAPH 1996).  Here the elimination is written with the
mobility ``A`` (not ``M``), so it also serves the singular ``A`` of point masses and
planar bodies, and it solves exactly ``S lam = b`` (the same ``lam`` as the band Cholesky,
to round-off).

Unknowns: ``lam`` and ``y = A J^T lam`` (per body ``y_i = A_i sum_q J_qi^T lam_q``);
equations ``J y = b``.  Tree: each body ``i`` has a parent edge ``E`` (all rows between
``i`` and its parent body ``p``), ground rows ``G`` (rows between ``i`` and the ground) and
child edges.  Leaves first (forward pass), each subtree is condensed into its root body:

* child edge ``j`` to child ``c`` (already condensed, ``y_c = Phi_c J_jc^T lam_j + y0_c``):
  ``S_j = J_jc Phi_c J_jc^T``, ``lam_j = w_j - S_j^-1 J_ji y_i`` with
  ``w_j = S_j^-1 (b_j - J_jc y0_c)``; on ``i`` it acts as ``J_ji^T lam_j = -K_j y_i + beta_j``,
  ``K_j = J_ji^T S_j^-1 J_ji = Z^T Z`` (``Z = L_j^-1 J_ji``), ``beta_j = J_ji^T w_j``;
* body ``i`` with ``K = sum K_j``, ``beta = sum beta_j`` and the force ``g`` of its parent
  edge: ``y_i = Psi (g + beta + J_G^T lam_G)``, ``Psi = (I + A K)^-1 A`` (symmetric PSD,
  ``(M + K)^-1`` when ``M`` exists; ``I + A K`` is regular for PSD ``A``, ``K``);
* ground rows: ``T = J_G Psi J_G^T = L L^T``, ``P~ = L^-1 J_G Psi``,
  ``lam_G = L^-T (L^-1 b_G - P~ (g + beta))``, hence ``y_i = Phi_i g + y0_i`` with
  ``Phi_i = Psi - P~^T P~`` and ``y0_i = Psi beta + P~^T (L^-1 b_G - P~ beta)``.

The backward pass (root first) recovers ``y`` and ``lam`` edge by edge.  Cost per body:
a few 6x6 products and factorisations of blocks of the size of one joint, independent of
the number of bodies.  A pivot at or below ``pivotTol`` times its own row's diagonal in
its block returns ``STATUS_SINGULAR`` (row in ``failInfo[INFO_ROW]``), as the band Cholesky does.

The plan (which body is whose parent, the rows of each edge, offsets of the factor
blocks) is made once by :func:`tree_plan` when the scene is compiled; the stage does no
allocation.  Graphs with loops (also through the ground) return ``None`` there and keep the
band solve.
"""
import numpy as np
from numba import njit

from .codes import INFO_ROW, ROW_BODY_A, ROW_BODY_B, STATUS_OK, STATUS_SINGULAR, uses_body_twist

# columns of the plan table (max(nb + 1, rows), 8); row nb holds the ends of the CSR ranges
# and, in P_ORDER, the number of bodies in the elimination order; column P_ROWS lists the
# rows of the CSR ranges P_E0, P_G0.  One int table and one flat float work array
# (``work_size``) keep the kernel's argument tuples short: numba passes every array of
# SceneData / Work into the compiled time loop, and six more arrays cost the heavy top
# ~0.3 us per step (measured) although it never uses them
P_ORDER, P_PARENT, P_E0, P_G0, P_EL, P_GL, P_NCHILD, P_ROWS = 0, 1, 2, 3, 4, 5, 6, 7


def tree_plan(nb, rowIndex):
    """The elimination plan of the tree solve, or ``None`` if the rows close a loop
    between bodies or through the ground (then the band solve is kept).

    Returns the int table (``P_*`` columns): the elimination order, parents, the row
    indices of each body's parent edge and ground rows (CSR ranges ``P_E0``, ``P_G0`` into
    column ``P_ROWS``), the offsets of their Cholesky factors (``P_EL``, ``P_GL``)."""
    m = rowIndex.shape[0]
    ground = [[] for _ in range(nb)]
    pairs = {}
    for q in range(m):
        a, b = int(rowIndex[q, ROW_BODY_A]), int(rowIndex[q, ROW_BODY_B])
        if a < 0 and b < 0 or a == b:
            return None
        if a < 0 or b < 0:
            ground[max(a, b)].append(q)
        else:
            pairs.setdefault((min(a, b), max(a, b)), []).append(q)
    # a forest iff no edge joins two bodies already connected (union-find), the ground
    # counting as one more body (node nb): two grounded bodies in one component close a loop
    # through the ground (the four-bar), where eliminating from one grounded end meets
    # singular pivots although S is regular; such graphs keep the band solve
    root = list(range(nb + 1))

    def find(x):
        while root[x] != x:
            root[x] = root[root[x]]
            x = root[x]
        return x

    adj = [[] for _ in range(nb)]
    links = [(a, b, rows) for (a, b), rows in pairs.items()] + [(i, nb, None) for i in range(nb) if ground[i]]
    for a, b, rows in links:
        ra, rb = find(a), find(b)
        if ra == rb:
            return None
        root[ra] = rb
        if rows is not None:
            adj[a].append((b, rows))
            adj[b].append((a, rows))
    # root each component at its grounded body (else its best connected body), then
    # breadth first: parents precede children, so the reversed order eliminates leaves first
    used = [i for i in range(nb) if ground[i] or adj[i]]
    parent = [-1] * nb
    edge = [[] for _ in range(nb)]
    bfs = []
    seen = set()
    for start in sorted(used, key=lambda i: (not ground[i], -len(adj[i]), i)):
        if start in seen:
            continue
        seen.add(start)
        queue = [start]
        k = 0
        while k < len(queue):
            v = queue[k]
            k += 1
            for w, rows in adj[v]:
                if w not in seen:
                    seen.add(w)
                    parent[w] = v
                    edge[w] = rows
                    queue.append(w)
        bfs += queue
    order = bfs[::-1]
    plan = np.zeros((max(nb + 1, m), 8), np.int64)
    plan[:, P_ORDER] = -1
    plan[:len(order), P_ORDER] = order
    plan[nb, P_ORDER] = len(order)
    plan[:nb, P_PARENT] = parent
    trows = []
    for i in range(nb):
        plan[i, P_E0] = len(trows)
        trows += edge[i]
    plan[nb, P_E0] = len(trows)
    for i in range(nb):
        plan[i, P_G0] = len(trows)
        trows += ground[i]
    plan[nb, P_G0] = len(trows)
    nflat = 0
    for i in range(nb):
        plan[i, P_EL] = nflat
        nflat += len(edge[i]) ** 2
        plan[i, P_GL] = nflat
        nflat += len(ground[i]) ** 2
    plan[nb, P_EL] = plan[nb, P_GL] = nflat
    for i in range(nb):
        if parent[i] >= 0:
            plan[parent[i], P_NCHILD] += 1
    plan[:len(trows), P_ROWS] = trows
    return plan


def work_size(nb, m, plan):
    """Length of the flat work array of :func:`tree_solve` (``Work.Tw``)."""
    return nb * (3 * 36 + 4 * 6) + m * 7 + int(plan[nb, P_EL])


# --------------------------------------------------------------------------- small dense blocks
@njit(cache=True, _nrt=False)
def _chol(L, off, n, rel_tol):
    """Cholesky of the n x n block stored row-major at ``L[off:]`` (in place, lower).
    Returns -1, or the index of the first pivot ``<= rel_tol`` times its own diagonal entry
    (the rank rule of mbs/linalg.py; row i's diagonal is still unchanged when it is reached)."""
    for i in range(n):
        for j in range(i + 1):
            s = L[off + i * n + j]
            for k in range(j):
                s -= L[off + i * n + k] * L[off + j * n + k]
            if j == i:
                if s <= rel_tol * L[off + i * n + i]:
                    return i
                L[off + i * n + i] = np.sqrt(s)
            else:
                L[off + i * n + j] = s / L[off + j * n + j]
    return -1


@njit(cache=True, inline="always", _nrt=False)
def _lower_solve_rows(L, off, n, rows, r0, X, c0, c1):
    """``X[rows] <- L^-1 X[rows]`` on the columns c0..c1-1 of the per-row array X."""
    for a in range(n):
        qa = rows[r0 + a]
        d = L[off + a * n + a]
        for c in range(c0, c1):
            s = X[qa, c]
            for k in range(a):
                s -= L[off + a * n + k] * X[rows[r0 + k], c]
            X[qa, c] = s / d


@njit(cache=True, inline="always", _nrt=False)
def _upper_solve_vec(L, off, n, x):
    """``x <- L^-T x`` for a length-n vector."""
    for a in range(n - 1, -1, -1):
        s = x[a]
        for k in range(a + 1, n):
            s -= L[off + k * n + a] * x[k]
        x[a] = s / L[off + a * n + a]


@njit(cache=True, inline="always", _nrt=False)
def _side(rowIndex, q, i):
    """Column offset (0 or 6) of body i's block in row q."""
    return 0 if rowIndex[q, ROW_BODY_A] == i else 6


@njit(cache=True, _nrt=False)
def _mobility(gid, Minv, R, A):
    """``A = M^-1`` in the body's velocity coordinates (SO3xR3: ``D M^-1 D^T``, D = diag(I, R))."""
    if uses_body_twist(gid):
        for a in range(6):
            for c in range(6):
                A[a, c] = Minv[a, c]
        return
    for a in range(3):
        for c in range(3):
            A[a, c] = Minv[a, c]
            s = 0.0
            t = 0.0
            u = 0.0
            for k in range(3):
                s += Minv[a, 3 + k] * R[c, k]          # (A12 R^T)[a, c]
                t += R[a, k] * Minv[3 + k, c]          # (R A21)[a, c]
            A[a, 3 + c] = s
            A[3 + a, c] = t
            for k in range(3):
                for l in range(3):
                    u += R[a, k] * Minv[3 + k, 3 + l] * R[c, l]
            A[3 + a, 3 + c] = u


@njit(cache=True, inline="always", _nrt=False)
def _mobility_of(gid, Minv, Tb, i):
    """Body i's ``A``: ``Minv`` itself for body twists, else ``Tb[i, 2]`` (``_mobility``)."""
    if uses_body_twist(gid[i]):
        return Minv[i]
    return Tb[i, 2]


@njit(cache=True, inline="always", _nrt=False)
def _psi_of(gid, Minv, Tb, plan, i):
    """Body i's ``Psi``: ``Tb[i, 0]``, or ``A`` itself for a body without children."""
    if plan[i, P_NCHILD] > 0:
        return Tb[i, 0]
    return _mobility_of(gid, Minv, Tb, i)


@njit(cache=True, _nrt=False)
def tree_correction(plan, Tw, X):
    """``X -= A J^T lam`` = ``y`` of the last :func:`tree_solve` (bodies in the plan)."""
    nb = X.shape[0]
    Tv = Tw[nb * 108:nb * 132].reshape((nb, 4, 6))
    for k in range(plan[nb, P_ORDER]):
        i = plan[k, P_ORDER]
        for a in range(6):
            X[i, a] -= Tv[i, 2, a]


@njit(cache=True, _nrt=False)
def _articulated(A, K, Psi, t6):
    """``Psi = (I + A K)^-1 A`` (Gaussian elimination with partial pivoting; ``K`` is
    overwritten by ``I + A K`` and then its factors), symmetrised."""
    for c in range(6):
        for a in range(6):
            s = 0.0
            for k in range(6):
                s += A[a, k] * K[k, c]
            t6[a] = s
        for a in range(6):
            K[a, c] = t6[a] + (1.0 if a == c else 0.0)
    for a in range(6):
        for c in range(6):
            Psi[a, c] = A[a, c]
    for col in range(6):
        p = col
        best = abs(K[col, col])
        for a in range(col + 1, 6):
            if abs(K[a, col]) > best:
                best = abs(K[a, col])
                p = a
        if p != col:
            for c in range(6):
                tmp = K[col, c]
                K[col, c] = K[p, c]
                K[p, c] = tmp
                tmp = Psi[col, c]
                Psi[col, c] = Psi[p, c]
                Psi[p, c] = tmp
        d = K[col, col]
        for a in range(col + 1, 6):
            f = K[a, col] / d
            if f != 0.0:
                for c in range(col, 6):
                    K[a, c] -= f * K[col, c]
                for c in range(6):
                    Psi[a, c] -= f * Psi[col, c]
    for a in range(5, -1, -1):
        for c in range(6):
            s = Psi[a, c]
            for k in range(a + 1, 6):
                s -= K[a, k] * Psi[k, c]
            Psi[a, c] = s / K[a, a]
    for a in range(6):
        for c in range(a):
            s = 0.5 * (Psi[a, c] + Psi[c, a])
            Psi[a, c] = s
            Psi[c, a] = s


@njit(cache=True, inline="always", _nrt=False)
def _factor_rows(i, trows, r0, n, rowIndex, Jr, Tr, Tl, off, pivotTol, failInfo):
    """``L L^T`` of the ``n`` rows ``trows[r0:r0 + n]`` of body i: the lower triangle of
    ``Tr J^T`` (``Tr`` holds each row times the body's matrix) into ``Tl[off:]``, factored in
    place.  Returns a status code (``failInfo[INFO_ROW]``: the failing row)."""
    for a in range(n):
        qa = trows[r0 + a]
        for b in range(a + 1):
            qb = trows[r0 + b]
            ob = _side(rowIndex, qb, i)
            s = 0.0
            for d in range(6):
                s += Tr[qa, d] * Jr[qb, ob + d]
            Tl[off + a * n + b] = s
    fail = _chol(Tl, off, n, pivotTol)
    if fail >= 0:
        failInfo[INFO_ROW] = trows[r0 + fail]
        return STATUS_SINGULAR
    return STATUS_OK


@njit(cache=True, inline="always", _nrt=False)
def _condense_ground_rows(i, plan, trows, rowIndex, Jr, Psi, Phi, beta, y0, lam, Tr, Tl, pivotTol, failInfo):
    """Body i's rows to the ground: ``T = J_G Psi J_G^T = L L^T``, ``P~ = L^-1 J_G Psi``,
    ``Phi = Psi - P~^T P~``; the rows' right-hand sides become ``L^-1 b - P~ beta`` and their
    share of ``y0`` is added.  Returns a status code."""
    g0 = plan[i, P_G0]
    ng = plan[i + 1, P_G0] - g0
    off = plan[i, P_GL]
    for a in range(ng):
        q = trows[g0 + a]
        o = _side(rowIndex, q, i)
        for c in range(6):
            s = 0.0
            for d in range(6):
                s += Jr[q, o + d] * Psi[d, c]
            Tr[q, c] = s
        Tr[q, 6] = lam[q]
    if _factor_rows(i, trows, g0, ng, rowIndex, Jr, Tr, Tl, off, pivotTol, failInfo) != STATUS_OK:
        return STATUS_SINGULAR
    _lower_solve_rows(Tl, off, ng, trows, g0, Tr, 0, 7)
    for a in range(6):
        for c in range(6):
            s = Psi[a, c]
            for b in range(ng):
                q = trows[g0 + b]
                s -= Tr[q, a] * Tr[q, c]
            Phi[a, c] = s
    for b in range(ng):
        q = trows[g0 + b]
        s = Tr[q, 6]
        for d in range(6):
            s -= Tr[q, d] * beta[d]
        Tr[q, 6] = s
        for d in range(6):
            y0[d] += Tr[q, d] * s
    return STATUS_OK


@njit(cache=True, inline="always", _nrt=False)
def _condense_parent_edge(i, p, plan, trows, rowIndex, Jr, Phi, y0, lam, Tr, Tl, Tb, Tv, pivotTol, failInfo):
    """The edge from body i to its parent p: ``S = J_c Phi J_c^T = L L^T``,
    ``w = S^-1 (b - J_c y0)``, ``Z = L^-1 J_p``; adds ``Z^T Z`` to the parent's K and
    ``J_p^T w`` to its beta.  Returns a status code."""
    e0 = plan[i, P_E0]
    ne = plan[i + 1, P_E0] - e0
    off = plan[i, P_EL]
    for a in range(ne):
        q = trows[e0 + a]
        o = _side(rowIndex, q, i)
        s = lam[q]
        for c in range(6):
            t = 0.0
            for d in range(6):
                t += Jr[q, o + d] * Phi[d, c]
            Tr[q, c] = t
            s -= Jr[q, o + c] * y0[c]
        Tr[q, 6] = s
    if _factor_rows(i, trows, e0, ne, rowIndex, Jr, Tr, Tl, off, pivotTol, failInfo) != STATUS_OK:
        return STATUS_SINGULAR
    for a in range(ne):
        q = trows[e0 + a]
        o = 6 - _side(rowIndex, q, i)
        for c in range(6):
            Tr[q, c] = Jr[q, o + c]
    _lower_solve_rows(Tl, off, ne, trows, e0, Tr, 0, 7)
    # w = L^-T (L^-1 r): the back substitution on column 6
    for a in range(ne - 1, -1, -1):
        qa = trows[e0 + a]
        s = Tr[qa, 6]
        for b in range(a + 1, ne):
            s -= Tl[off + b * ne + a] * Tr[trows[e0 + b], 6]
        Tr[qa, 6] = s / Tl[off + a * ne + a]
    Kp = Tb[p, 1]
    bp = Tv[p, 0]
    for a in range(ne):
        q = trows[e0 + a]
        o = 6 - _side(rowIndex, q, i)
        w = Tr[q, 6]
        for c in range(6):
            bp[c] += Jr[q, o + c] * w
            z = Tr[q, c]
            for d in range(6):
                Kp[c, d] += z * Tr[q, d]
    return STATUS_OK


@njit(cache=True, inline="always", _nrt=False)
def _back_substitute(i, plan, trows, rowIndex, Jr, Psi, Tv, Tr, Tl, lam):
    """Body i, its parent's ``y`` known: the multipliers of its parent edge and of its ground
    rows, and its own ``y_i = Psi u`` (into ``Tv[i, 2]``)."""
    u = Tv[i, 2]
    g = Tv[i, 1]                        # the parent edge's force on i (y0 is spent)
    for a in range(6):
        g[a] = 0.0
    p = plan[i, P_PARENT]
    if p >= 0:
        e0 = plan[i, P_E0]
        ne = plan[i + 1, P_E0] - e0
        off = plan[i, P_EL]
        yp = Tv[p, 2]
        t = Tv[i, 3]
        for a in range(ne):
            q = trows[e0 + a]
            s = 0.0
            for d in range(6):
                s += Tr[q, d] * yp[d]
            t[a] = s
        _upper_solve_vec(Tl, off, ne, t)
        for a in range(ne):
            q = trows[e0 + a]
            lq = Tr[q, 6] - t[a]
            lam[q] = lq
            o = _side(rowIndex, q, i)
            for d in range(6):
                g[d] += Jr[q, o + d] * lq
    for a in range(6):
        u[a] = g[a] + Tv[i, 0, a]
    g0 = plan[i, P_G0]
    ng = plan[i + 1, P_G0] - g0
    if ng > 0:
        off = plan[i, P_GL]
        t = Tv[i, 3]
        for a in range(ng):
            q = trows[g0 + a]
            s = Tr[q, 6]
            for d in range(6):
                s -= Tr[q, d] * g[d]
            t[a] = s
        _upper_solve_vec(Tl, off, ng, t)
        for a in range(ng):
            q = trows[g0 + a]
            lam[q] = t[a]
            o = _side(rowIndex, q, i)
            for d in range(6):
                u[d] += Jr[q, o + d] * t[a]
    # y_i = Psi u (into Tv[i, 2] through the scratch row g)
    for a in range(6):
        s = 0.0
        for d in range(6):
            s += Psi[a, d] * u[d]
        g[a] = s
    for a in range(6):
        u[a] = g[a]


@njit(cache=True, _nrt=False)
def tree_solve(gid, Minv, rowIndex, R, Jr, lam, plan, Tw, pivotTol, failInfo):
    """``lam <- S^-1 lam``, ``S = J A J^T``, by the leaves-to-root elimination (module
    docstring), and ``y = A J^T lam`` per body in ``Tv[:, 2]`` (the correction the callers
    subtract, :func:`tree_correction`).  Work ``Tw`` (flat, ``work_size``), viewed as
    ``Tb`` (nb, 3, 6, 6) = Psi, K then Phi, A; ``Tv`` (nb, 4, 6) = beta, y0, y, scratch;
    ``Tr`` (m, 7) = per row Z or P~ (6) and w or L^-1 b - P~ beta; ``Tl`` the factors.
    Returns a status code."""
    nb = gid.shape[0]
    m = rowIndex.shape[0]
    Tb = Tw[0:nb * 108].reshape((nb, 3, 6, 6))
    Tv = Tw[nb * 108:nb * 132].reshape((nb, 4, 6))
    Tr = Tw[nb * 132:nb * 132 + m * 7].reshape((m, 7))
    Tl = Tw[nb * 132 + m * 7:]
    trows = plan[:, P_ROWS]
    n = plan[nb, P_ORDER]
    for k in range(n):
        i = plan[k, P_ORDER]
        if plan[i, P_NCHILD] > 0:
            for a in range(6):
                Tv[i, 0, a] = 0.0
                for c in range(6):
                    Tb[i, 1, a, c] = 0.0
    # ---- forward: condense each subtree into its root body, leaves first
    for k in range(n):
        i = plan[k, P_ORDER]
        Psi = _psi_of(gid, Minv, Tb, plan, i)
        Phi = Tb[i, 1]
        beta = Tv[i, 0]
        y0 = Tv[i, 1]
        leaf = plan[i, P_NCHILD] == 0
        if not uses_body_twist(gid[i]):
            _mobility(gid[i], Minv[i], R[i], Tb[i, 2])
        if leaf:
            for a in range(6):
                y0[a] = 0.0
                beta[a] = 0.0
        else:
            _articulated(_mobility_of(gid, Minv, Tb, i), Phi, Psi, Tv[i, 2])
            for a in range(6):
                s = 0.0
                for c in range(6):
                    s += Psi[a, c] * beta[c]
                y0[a] = s
        if plan[i + 1, P_G0] > plan[i, P_G0]:
            if _condense_ground_rows(i, plan, trows, rowIndex, Jr, Psi, Phi, beta, y0, lam, Tr, Tl, pivotTol,
                                     failInfo) != STATUS_OK:
                return STATUS_SINGULAR
        else:
            Phi = Psi
        p = plan[i, P_PARENT]
        if p >= 0 and _condense_parent_edge(i, p, plan, trows, rowIndex, Jr, Phi, y0, lam, Tr, Tl, Tb, Tv, pivotTol,
                                            failInfo) != STATUS_OK:
            return STATUS_SINGULAR
    # ---- backward: root first, y and lam edge by edge
    for k in range(n - 1, -1, -1):
        i = plan[k, P_ORDER]
        _back_substitute(i, plan, trows, rowIndex, Jr, _psi_of(gid, Minv, Tb, plan, i), Tv, Tr, Tl, lam)
    return STATUS_OK
