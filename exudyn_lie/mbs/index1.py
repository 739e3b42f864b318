"""The index-1 solve (eq. index1): ``[M J^T; J 0][Vdot; lambda] = [Q; eta]`` by the Schur
complement ``J M^-1 J^T`` (band Cholesky, or pivoted Cholesky for redundant rows; the tree
solve; or, for rows whose force direction C differs from J, the LU of ``J M^-1 C^T``,
:mod:`.oblique_solve`), and the stage right-hand side ``rhs`` that assembles forces, rows
and the solve."""
from collections import namedtuple

from numba import njit, types
from numba.extending import overload

from .bodies import apply_minv
from .codes import INFO_RANK, INFO_ROW, ROW_BODY_A, ROW_BODY_B, STATUS_OK, STATUS_SINGULAR
from .constraints import joints_rows
from .force_elements import compute_forces
from .linalg import band_ldl_inplace, band_ldl_solve_inplace, lu_factor_inplace, lu_solve_inplace, pivoted_cholesky_solve
from .oblique_solve import force_direction_rows
from .tree_solve import tree_correction, tree_solve


@njit(cache=True, inline="always", _nrt=False)
def _bodies_dot(aq, bq, al, bl, q, l, Jr, W):
    """(J M^-1 J^T)[q, l] = sum over the bodies shared by rows q (bodies aq, bq) and l (al, bl)."""
    s = 0.0
    if aq >= 0:
        if aq == al:
            for k in range(6):
                s += Jr[q, k] * W[l, k]
        if aq == bl:
            for k in range(6):
                s += Jr[q, k] * W[l, 6 + k]
    if bq >= 0:
        if bq == al:
            for k in range(6):
                s += Jr[q, 6 + k] * W[l, k]
        if bq == bl:
            for k in range(6):
                s += Jr[q, 6 + k] * W[l, 6 + k]
    return s


@njit(cache=True, inline="always", _nrt=False)
def _row_dot(rowIndex, q, l, Jr, W):
    """(J M^-1 J^T)[q, l] (:func:`_bodies_dot` with the rows' bodies from ``rowIndex``)."""
    return _bodies_dot(rowIndex[q, ROW_BODY_A], rowIndex[q, ROW_BODY_B], rowIndex[l, ROW_BODY_A],
                       rowIndex[l, ROW_BODY_B], q, l, Jr, W)


@njit(cache=True, inline="always", _nrt=False)
def rows_times(rowIndex, Jr, X, c, y, out):
    """``out = c y + J X`` for a per-body array X (nb, 6), from the row blocks of J."""
    for q in range(rowIndex.shape[0]):
        s = c * y[q]
        a = rowIndex[q, ROW_BODY_A]
        b = rowIndex[q, ROW_BODY_B]
        if a >= 0:
            for k in range(6):
                s += Jr[q, k] * X[a, k]
        if b >= 0:
            for k in range(6):
                s += Jr[q, 6 + k] * X[b, k]
        out[q] = s


@njit(cache=True, inline="always", _nrt=False)
def subtract_rows_transposed(rowIndex, W, lam, X):
    """``X -= W^T lam`` per body, W (m, 12) holding the two body blocks of each row."""
    for q in range(rowIndex.shape[0]):
        lq = lam[q]
        a = rowIndex[q, ROW_BODY_A]
        b = rowIndex[q, ROW_BODY_B]
        if a >= 0:
            for k in range(6):
                X[a, k] -= W[q, k] * lq
        if b >= 0:
            for k in range(6):
                X[b, k] -= W[q, 6 + k] * lq


def _is_tree(tree):
    """At compile time, from numba's type of ``tree`` (index1.TreeSolve): does the scene use
    the tree solve (its plan, an integer array)?  Work.tplan is None for the band solve, so a
    band scene's compiled time loop contains no tree code at all (with the tree branch present
    but not taken, the heavy top's step cost 3.3 instead of 2.85 us, measured)."""
    return isinstance(tree.types[0], types.Array)


def _is_oblique(tree):
    """At compile time: does the scene use the non-symmetric solve (Work.tplan an
    oblique_solve.ObliquePlan, a namedtuple)?  Only scenes with such rows compile it."""
    return isinstance(tree.types[0], types.BaseTuple)


def apply_correction(rowIndex, W, lam, X, tree):
    """``X -= M^-1 J^T lam`` after :func:`solve_multipliers`: from the row blocks ``W``, or
    the tree solve's per-body ``y`` (compiled per solve, see ``_is_tree``)."""
    raise NotImplementedError("compiled only")


# Both dispatchers are forceinlined: as calls, the chosen solve's ~17 arguments (most of them
# arrays, passed as their unpacked fields) were copied to the stack for every stage, about 120
# words, and the copies stalled on 4K aliasing (perf, per instruction address, heavy top).
# Inlined, together with the lean scenes, the heavy top's step went from 1.74-1.90 to 1.38-1.57 us
# (bench --sections perstep --quick, twice interleaved with the previous release; states
# bit-identical).
@overload(apply_correction, jit_options={"forceinline": True})
def _apply_correction(rowIndex, W, lam, X, tree):
    if _is_tree(tree):
        def by_tree(rowIndex, W, lam, X, tree):
            tree_correction(tree.plan, tree.Tw, X)
        return by_tree

    def by_rows(rowIndex, W, lam, X, tree):
        subtract_rows_transposed(rowIndex, W, lam, X)
    return by_rows


@njit(cache=True, inline="always", _nrt=False)
def minv_rows(gid, Minv, rowIndex, R, Jr, W, tmp12):
    """``W = M^-1 Jr^T`` as row blocks (W (m, 12): the two body blocks of each row), for the
    oblique solve.  schur_solve keeps its own copy of this loop: calling this helper there made
    the step slower, inline="always" (heavy top CPU time 2.9 -> 3.0 us) and forceinline alike
    (`bench --sections perstep --quick --models heavytop,doublependulum`, twice, interleaved:
    heavy top 1.72-1.78 -> 1.83 us, double pendulum 3.27-3.30 -> 3.44-3.47 us, states
    bit-identical), and the common path's code is meant to stay as it was."""
    for q in range(rowIndex.shape[0]):
        a = rowIndex[q, ROW_BODY_A]
        b = rowIndex[q, ROW_BODY_B]
        if a >= 0:
            apply_minv(gid[a], Minv[a], R[a], Jr[q, 0:6], W[q, 0:6], tmp12)
        else:
            for k in range(6):
                W[q, k] = 0.0
        if b >= 0:
            apply_minv(gid[b], Minv[b], R[b], Jr[q, 6:12], W[q, 6:12], tmp12)
        else:
            for k in range(6):
                W[q, 6 + k] = 0.0


@njit(cache=True, forceinline=True, _nrt=False)
def schur_solve(gid, Minv, rowIndex, bw, redundant, pivotTol, R, Jr, W, lam, Sb, Sd, perm, ytmp, failInfo, tmp12):
    """``W = M^-1 J^T`` (row blocks) and ``lam <- (J M^-1 J^T)^-1 lam``: the Schur
    complement shared by the index-1 solve and the projections.  ``S`` is banded (band
    Cholesky); with redundant rows the pivoted Cholesky drops the dependent ones.
    Returns a status code (failInfo[INFO_ROW] = failing row, failInfo[INFO_RANK] = rank if redundant)."""
    m = rowIndex.shape[0]
    for q in range(m):
        a = rowIndex[q, ROW_BODY_A]
        b = rowIndex[q, ROW_BODY_B]
        if a >= 0:
            apply_minv(gid[a], Minv[a], R[a], Jr[q, 0:6], W[q, 0:6], tmp12)
        else:
            for k in range(6):
                W[q, k] = 0.0
        if b >= 0:
            apply_minv(gid[b], Minv[b], R[b], Jr[q, 6:12], W[q, 6:12], tmp12)
        else:
            for k in range(6):
                W[q, 6 + k] = 0.0
    if redundant:
        for q in range(m):
            for l in range(q + 1):
                v = _row_dot(rowIndex, q, l, Jr, W)
                Sd[q, l] = v
                Sd[l, q] = v
        failInfo[INFO_RANK] = pivoted_cholesky_solve(Sd, m, lam, perm, ytmp, pivotTol)
        return STATUS_OK
    for q in range(m):
        l0 = q - bw
        if l0 < 0:
            l0 = 0
        # row q's bodies read once per row (Sb's stores may alias rowIndex for LLVM, which then
        # reloads them per entry): heavy top 1.25-1.35 -> 1.02-1.09 us per step, double pendulum
        # 2.27-2.32 -> 2.16-2.21 us (bench --sections perstep --quick --models
        # heavytop,doublependulum, twice interleaved; states bit-identical)
        aq = rowIndex[q, ROW_BODY_A]
        bq = rowIndex[q, ROW_BODY_B]
        for l in range(l0, q + 1):
            Sb[q, q - l] = _bodies_dot(aq, bq, rowIndex[l, ROW_BODY_A], rowIndex[l, ROW_BODY_B], q, l, Jr, W)
    fail = band_ldl_inplace(Sb, m, bw, pivotTol, ytmp)
    if fail >= 0:
        failInfo[INFO_ROW] = fail
        return STATUS_SINGULAR
    band_ldl_solve_inplace(Sb, m, bw, lam)
    return STATUS_OK


@njit(cache=True, _nrt=False)
def oblique_schur_solve(gid, Minv, rowIndex, pivotTol, R, Jr, W, lam, plan, failInfo, tmp12):
    """``W = M^-1 C^T`` (row blocks; C the force-direction rows, :mod:`.oblique_solve`) and
    ``lam <- (J M^-1 C^T)^-1 lam`` by a dense LU with partial pivoting: the non-symmetric
    index-1 solve of rows whose force direction C differs from their gradient J (a coordinate
    constraint on a rotation-vector parameter, parametrisation 'rotationVector').  A pivot at or below
    ``pivotTol * max |diag S|`` is STATUS_SINGULAR (failInfo[INFO_ROW] = its column)."""
    force_direction_rows(plan, Jr)
    minv_rows(gid, Minv, rowIndex, R, plan.Cr, W, tmp12)
    m = rowIndex.shape[0]
    S = plan.S
    dmax = 0.0
    for q in range(m):
        for l in range(m):
            S[q, l] = _row_dot(rowIndex, q, l, Jr, W)
        if abs(S[q, q]) > dmax:
            dmax = abs(S[q, q])
    fail = lu_factor_inplace(S, m, plan.piv, pivotTol * dmax)
    if fail >= 0:
        failInfo[INFO_ROW] = fail
        return STATUS_SINGULAR
    lu_solve_inplace(S, m, plan.piv, lam)
    return STATUS_OK


def solve_multipliers(gid, Minv, rowIndex, bw, redundant, pivotTol, R, Jr, W, lam, Sb, Sd, perm, ytmp, failInfo,
                      tmp12, tree):
    """``lam <- (J M^-1 J^T)^-1 lam`` by the solve the scene was compiled for: the tree solve
    (:mod:`.tree_solve`: leaves-to-root elimination, linear in the bodies; it needs no ``W``,
    its correction is ``y`` per body, ``apply_correction``) or :func:`schur_solve` (band or,
    with redundant rows, pivoted Cholesky).  Chosen at compile time (``_is_tree``)."""
    raise NotImplementedError("compiled only")


@overload(solve_multipliers, jit_options={"forceinline": True})
def _solve_multipliers(gid, Minv, rowIndex, bw, redundant, pivotTol, R, Jr, W, lam, Sb, Sd, perm, ytmp, failInfo,
                       tmp12, tree):
    if _is_tree(tree):
        def by_tree(gid, Minv, rowIndex, bw, redundant, pivotTol, R, Jr, W, lam, Sb, Sd, perm, ytmp, failInfo, tmp12,
                    tree):
            return tree_solve(gid, Minv, rowIndex, R, Jr, lam, tree.plan, tree.Tw, pivotTol, failInfo)
        return by_tree
    if _is_oblique(tree):
        def by_oblique(gid, Minv, rowIndex, bw, redundant, pivotTol, R, Jr, W, lam, Sb, Sd, perm, ytmp, failInfo,
                       tmp12, tree):
            return oblique_schur_solve(gid, Minv, rowIndex, pivotTol, R, Jr, W, lam, tree.plan, failInfo, tmp12)
        return by_oblique

    def by_schur(gid, Minv, rowIndex, bw, redundant, pivotTol, R, Jr, W, lam, Sb, Sd, perm, ytmp, failInfo, tmp12,
                 tree):
        return schur_solve(gid, Minv, rowIndex, bw, redundant, pivotTol, R, Jr, W, lam, Sb, Sd, perm, ytmp, failInfo,
                           tmp12)
    return by_schur


@njit(cache=True, inline="always", _nrt=False)
def schur_correct(gid, Minv, rowIndex, bw, redundant, pivotTol, R, X, c, y, Jr, W, lam, Sb, Sd, perm, ytmp, failInfo,
                  tmp12, tree):
    """``X -= M^-1 J^T lambda`` with ``(J M^-1 J^T) lambda = c y + J X``: the correction that
    makes ``J X = -c y``.  The index-1 solve (eq. index1) is ``X = Vdot = M^-1 Q``,
    ``c y = -eta``; the velocity projection ``X = V``, ``c = 0``.  Returns a status code."""
    rows_times(rowIndex, Jr, X, c, y, lam)
    st = solve_multipliers(gid, Minv, rowIndex, bw, redundant, pivotTol, R, Jr, W, lam, Sb, Sd, perm, ytmp, failInfo,
                           tmp12, tree)
    if st != STATUS_OK:
        return st
    apply_correction(rowIndex, W, lam, X, tree)
    return STATUS_OK


# the tree solve's plan (Work.tplan; None: the band solve) and work (Work.Tw)
TreeSolve = namedtuple("TreeSolve", ["plan", "Tw"])


@njit(cache=True, inline="always", _nrt=False)
def tree_of(sd, wk):
    return TreeSolve(wk.tplan, wk.Tw)


@njit(cache=True, inline="always", _nrt=False)
def free_accelerations(gid, Minv, R, Q, Vdot, tmp12):
    """``Vdot = M^-1 Q`` body by body."""
    for i in range(gid.shape[0]):
        apply_minv(gid[i], Minv[i], R[i], Q[i], Vdot[i], tmp12)


@njit(cache=True, inline="always", _nrt=False)
def rhs(sd, wk, t, R, r, V, Qext, Vdot):
    """Stage right-hand side ``Vdot = F(g, V)`` (eq. ODE2a).  ``Qext`` holds extra
    generalised forces (from Python callbacks), zeros otherwise."""
    Q = wk.Q
    compute_forces(sd, wk, t, R, r, V, Q)
    if sd.hasQext:
        for i in range(sd.nb):
            for k in range(6):
                Q[i, k] += Qext[i, k]
    free_accelerations(sd.gid, sd.Minv, R, Q, Vdot, wk.tmp12)
    if sd.nrows == 0:
        return STATUS_OK
    joints_rows(sd.gid, sd.jointIndex, sd.jointPoints, sd.jointFrames, sd.jointParams, sd.rowIndex, sd.rowsAll,
                wk.path.bodyParameters, wk.path.jointAngles, R, r, V, wk.h, wk.Jr, wk.eta, wk.rdrive,
                wk.v3, wk.ident, wk.zero3, wk.zero6)
    return schur_correct(sd.gid, sd.Minv, sd.rowIndex, sd.bandwidth, sd.redundant, sd.pivotTol, R, Vdot, -1.0, wk.eta,
                         wk.Jr, wk.W, wk.lam, wk.Sb, wk.Sd, wk.perm, wk.ytmp, wk.failInfo, wk.tmp12, tree_of(sd, wk))
