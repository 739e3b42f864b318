"""Compiled pieces of the Exudyn-evaluated path (:mod:`.evaluated`, :mod:`.evaluated_problem`):
one numba call per stage before Exudyn evaluates the model, one after.

The Lie group nodes (``NodeRigidBodyRotVecLG``) are bodies with a group id of the
registry (SE3 / SO3xR3) of the one compiled stepper (:mod:`exudyn_lie.mbs.stepper`: eq. MK1,
``g_j = g exp(Psi_j)``, ``k_j = dexp^-1_{-Psi_j} V_j``), so both paths integrate the same ODE
with the same arithmetic.  Their state velocity is the kernel's: SE3 the body twist ``(omega, U)``,
``U = R^T rdot``; SO3xR3 ``(omega, rdot)``.  Exudyn's velocity coordinates of such a node are
``[rdot (global), omega (local)]`` (DESIGN.md, facts).

Every other ODE2 coordinate is a vector-space coordinate with ``qdot = v`` (mass points,
2D bodies, EP / Rxyz nodes, ANCF, GenericODE2, ...), integrated with the same tableau.
"""
import math

import numpy as np
from numba import njit

from ..groups import so3
from ..mbs.codes import uses_body_twist
from ..mbs.linalg import REL_PIVOT_TOL, band_ldl_inplace, band_ldl_solve_inplace, pivoted_cholesky_solve
from ..mbs.stepper import copy_state
from .nodes import rotvec_row


@njit(cache=True)
def _rotvec_continuous(R, prev, p):
    """Rotation vector of R on the branch nearest to ``prev`` (bridge/nodes.rotvec_row,
    whose continuity rule the compiled path uses for the same node type)."""
    z = np.zeros(3)
    pp = prev.copy()
    rotvec_row(R, z, z, pp, False, p, z.copy(), z.copy(), np.empty(4))


@njit(cache=True)
def write_exudyn_state(gid, R, r, V, lgIdx, lgRef, prev, q, qt, vecIdx, qv, vv, rv):
    """Exudyn's ODE2 coordinates ``q`` and velocities ``qt`` (mbs' Current views) of the
    state: a Lie group node writes ``log(R)`` minus the reference rotation vector (Exudyn:
    total = reference + current, componentwise), ``r`` minus the reference position,
    ``rdot = R U`` (SE3) or ``rdot`` (SO3xR3) and the local ``omega``; the vector-space
    coordinates are copied.  ``rv`` (nl, 3) scratch for the rotation vectors.  Returns
    ``max |qt|`` (the velocity scale of eta's differentiation step)."""
    for i in range(gid.shape[0]):
        _rotvec_continuous(R[i], prev[i], rv[i])
        Vi = V[i]
        body = uses_body_twist(gid[i])
        for k in range(3):
            q[lgIdx[i, k]] = r[i, k] - lgRef[i, k]
            q[lgIdx[i, 3 + k]] = rv[i, k] - lgRef[i, 3 + k]
            if body:
                qt[lgIdx[i, k]] = R[i, k, 0] * Vi[3] + R[i, k, 1] * Vi[4] + R[i, k, 2] * Vi[5]
            else:
                qt[lgIdx[i, k]] = Vi[3 + k]
            qt[lgIdx[i, 3 + k]] = Vi[k]
    for k in range(vecIdx.shape[0]):
        q[vecIdx[k]] = qv[k]
        qt[vecIdx[k]] = vv[k]
    vmax = 0.0
    for k in range(qt.shape[0]):
        vmax = max(vmax, abs(qt[k]))
    return vmax


@njit(cache=True)
def write_moved_positions(R, r, lgIdx, lgRef, prev, q, qt, vecIdx, qv, eps, ER, rv):
    """Exudyn's ODE2 coordinates of the configuration moved along the motion by ``eps``
    seconds at fixed velocities ``qt`` (for the acceleration term eta, :mod:`.evaluated`):
    a Lie group node ``R exp(eps omega)``, ``r + eps rdot`` (omega local, rdot global, read
    from ``qt``); vector coordinates ``q + eps v``."""
    w = np.empty(3)
    for i in range(R.shape[0]):
        for k in range(3):
            w[k] = eps * qt[lgIdx[i, 3 + k]]
        so3.exp_into(w, ER)
        Rm = R[i] @ ER
        _rotvec_continuous(Rm, prev[i], rv[i])
        for k in range(3):
            q[lgIdx[i, k]] = r[i, k] + eps * qt[lgIdx[i, k]] - lgRef[i, k]
            q[lgIdx[i, 3 + k]] = rv[i, k] - lgRef[i, 3 + k]
    for k in range(vecIdx.shape[0]):
        q[vecIdx[k]] = qv[k] + eps * qt[vecIdx[k]]


@njit(cache=True)
def unpack_state(gid, R, r, V, nvb, lgIdx, lgRef, prev, q, qt, vecIdx, qv, vv, y, rv):
    """Exudyn's ``q``, ``qt`` (and the ODE1 coordinates ``y``) of a state of the problem's
    bodies (:mod:`.evaluated_problem`): the first ``nl = gid.size`` bodies are the Lie group
    nodes (:func:`write_exudyn_state`), the next ``nvb`` hold the vector-space ODE2
    coordinates three by three (position ``r``, velocity ``V[3:6]``), the rest the ODE1
    coordinates three by three (``V[3:6]``).  ``qv``, ``vv`` receive the vector coordinates.
    Returns ``max |qt|``."""
    nl = gid.shape[0]
    nv = qv.shape[0]
    for k in range(nv):
        b = nl + k // 3
        qv[k] = r[b, k % 3]
        vv[k] = V[b, 3 + k % 3]
    for k in range(y.shape[0]):
        y[k] = V[nl + nvb + k // 3, 3 + k % 3]
    return write_exudyn_state(gid, R[:nl], r[:nl], V[:nl], lgIdx, lgRef, prev, q, qt, vecIdx, qv, vv, rv)


@njit(cache=True)
def pack_rates(gid, R, V, acc, lgIdx, vecIdx, ydot, nvb, Vdot):
    """``Vdot`` of the problem's bodies from Exudyn's accelerations ``acc`` (nODE2) and ODE1
    rates ``ydot``: per Lie group node the group velocity rates (SO3xR3: ``(omegadot,
    rddot)``; SE3: ``(omegadot, R^T rddot - omega x U)``, from ``rdot = R U``), per vector
    body ``(0, vdot)``, per ODE1 body ``(0, ydot)``; padding rows 0."""
    nl = gid.shape[0]
    for i in range(Vdot.shape[0]):
        for k in range(6):
            Vdot[i, k] = 0.0
    for i in range(nl):
        Vdi = Vdot[i]
        for k in range(3):
            Vdi[k] = acc[lgIdx[i, 3 + k]]
        if uses_body_twist(gid[i]):
            w = V[i]
            Ri = R[i]
            for k in range(3):
                Vdi[3 + k] = (Ri[0, k] * acc[lgIdx[i, 0]] + Ri[1, k] * acc[lgIdx[i, 1]] + Ri[2, k] * acc[lgIdx[i, 2]])
            Vdi[3] -= w[1] * w[5] - w[2] * w[4]
            Vdi[4] -= w[2] * w[3] - w[0] * w[5]
            Vdi[5] -= w[0] * w[4] - w[1] * w[3]
        else:
            for k in range(3):
                Vdi[3 + k] = acc[lgIdx[i, k]]
    for k in range(vecIdx.shape[0]):
        Vdot[nl + k // 3, 3 + k % 3] = acc[vecIdx[k]]
    for k in range(ydot.shape[0]):
        Vdot[nl + nvb + k // 3, 3 + k % 3] = ydot[k]


@njit(cache=True)
def pack_state(gid, Rl, rl, Vl, qv, vv, y, nvb, R, r, V):
    """The problem's body state from the Lie group nodes' ``Rl, rl, Vl``, the vector
    coordinates ``qv, vv`` and the ODE1 coordinates ``y`` (the layout of
    :func:`unpack_state`; padding and the ODE1 bodies' positions 0, the packed bodies'
    rotations I)."""
    nl = gid.shape[0]
    for i in range(nl, R.shape[0]):
        for a in range(3):
            r[i, a] = 0.0
            for c in range(3):
                R[i, a, c] = 1.0 if a == c else 0.0
        for k in range(6):
            V[i, k] = 0.0
    copy_state(Rl, rl, Vl, R[:nl], r[:nl], V[:nl])
    for k in range(qv.shape[0]):
        r[nl + k // 3, k % 3] = qv[k]
        V[nl + k // 3, 3 + k % 3] = vv[k]
    for k in range(y.shape[0]):
        V[nl + nvb + k // 3, 3 + k % 3] = y[k]


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
def block_kkt_solve(M, f, Cq, eta, blk, blkPtr, Minv, X, S, lam, a, nzIdx, nzCnt, pivoted, perm, yw):
    """Index-1 accelerations ``[M Cq^T; Cq 0][a; lam] = [f; eta]`` (eq. index1) with M
    block diagonal: blocks ``blk[blkPtr[b]:blkPtr[b+1]]`` (coordinate indices).  Each block
    is inverted (Gauss-Jordan with partial pivoting, stored in ``Minv``, dense n x n but only
    the blocks are touched); ``X = M^-1 Cq^T`` only on the blocks a row touches;
    ``S = Cq X`` over the nonzero columns of each row (``nzIdx``, ``nzCnt``: scratch); ``S lam = Cq M^-1 f - eta``; ``a = M^-1 (f - Cq^T lam)``.
    ``pivoted``: redundant constraints (S only semi-definite): the rank-revealing Cholesky
    of the compiled kernel (:func:`~exudyn_lie.mbs.linalg.pivoted_cholesky_solve`; multipliers
    of dependent rows 0), with the workspaces ``perm``, ``yw``.
    Returns 0, or 1 if a block of M is singular, 2 if S is singular (not pivoted)."""
    n = f.shape[0]
    m = eta.shape[0]
    nb = blkPtr.shape[0] - 1
    # invert every block
    for bI in range(nb):
        p0 = blkPtr[bI]
        s = blkPtr[bI + 1] - p0
        W = np.empty((s, 2 * s))
        if not invert_block(M, blk, p0, s, W):
            return 1
        for i in range(s):
            for k in range(s):
                Minv[blk[p0 + i], blk[p0 + k]] = W[i, s + k]
    # a0 = M^-1 f (blockwise)
    for bI in range(nb):
        p0 = blkPtr[bI]
        p1 = blkPtr[bI + 1]
        for i in range(p0, p1):
            acc = 0.0
            for k in range(p0, p1):
                acc += Minv[blk[i], blk[k]] * f[blk[k]]
            a[blk[i]] = acc
    if m == 0:
        return 0
    # X = M^-1 Cq^T (n x m), blockwise; S = Cq X; rhs = Cq a0 - eta
    for c in range(m):
        for i in range(n):
            X[i, c] = 0.0
        for bI in range(nb):
            p0 = blkPtr[bI]
            p1 = blkPtr[bI + 1]
            touched = False
            for k in range(p0, p1):
                if Cq[c, blk[k]] != 0.0:
                    touched = True
                    break
            if not touched:
                continue
            for i in range(p0, p1):
                acc = 0.0
                for k in range(p0, p1):
                    acc += Minv[blk[i], blk[k]] * Cq[c, blk[k]]
                X[blk[i], c] = acc
    for r_ in range(m):
        cnt = 0
        acc = 0.0
        for k in range(n):
            ck = Cq[r_, k]
            if ck != 0.0:
                nzIdx[r_, cnt] = k
                cnt += 1
                acc += ck * a[k]
        nzCnt[r_] = cnt
        lam[r_] = acc - eta[r_]
    for r_ in range(m):
        for c in range(r_, m):
            acc = 0.0
            for kk in range(nzCnt[r_]):
                k = nzIdx[r_, kk]
                acc += Cq[r_, k] * X[k, c]
            S[r_, c] = acc
            S[c, r_] = acc
    if pivoted:
        pivoted_cholesky_solve(S, m, lam, perm, yw, REL_PIVOT_TOL)
    elif not cholesky_solve_inplace(S, m, lam):
        return 2
    # a = a0 - X lam
    for i in range(n):
        acc = 0.0
        for c in range(m):
            acc += X[i, c] * lam[c]
        a[i] -= acc
    return 0


@njit(cache=True)
def cholesky_solve_inplace(S, m, x):
    """``S x = rhs`` (x holds rhs on entry) by Cholesky in place; False if a pivot is
    ``<= REL_PIVOT_TOL S_cc``, its own diagonal (the kernel's rank rule, mbs/linalg.py)."""
    for c in range(m):
        d = S[c, c]
        for k in range(c):
            d -= S[c, k] * S[c, k]
        if d <= REL_PIVOT_TOL * S[c, c]:
            return False
        d = math.sqrt(d)
        S[c, c] = d
        for i in range(c + 1, m):
            v = S[i, c]
            for k in range(c):
                v -= S[i, k] * S[c, k]
            S[i, c] = v / d
    for i in range(m):
        v = x[i]
        for k in range(i):
            v -= S[i, k] * x[k]
        x[i] = v / S[i, i]
    for i in range(m - 1, -1, -1):
        v = x[i]
        for k in range(i + 1, m):
            v -= S[k, i] * x[k]
        x[i] = v / S[i, i]
    return True


@njit(cache=True)
def invert_blocks(M, blk, blkPtr, blkOff, MinvB, W):
    """The inverse of every diagonal block of M (Gauss-Jordan, partial pivoting) into the
    flat storage ``MinvB[blkOff[b]:]`` (row-major s x s); ``W`` (smax, 2 smax) scratch.
    Returns False if a block is singular."""
    for bI in range(blkPtr.shape[0] - 1):
        p0 = blkPtr[bI]
        s = blkPtr[bI + 1] - p0
        if not invert_block(M, blk, p0, s, W):
            return False
        o = blkOff[bI]
        for i in range(s):
            for k in range(s):
                MinvB[o + i * s + k] = W[i, s + k]
    return True


@njit(cache=True)
def schur_band_solve(M, f, Cq, eta, blk, blkPtr, blkOff, blockOf, pos, bw, MinvB, W, a, lam, nzIdx, nzCnt,
                     rowBlk, rowBlkCnt, bRowPtr, bRows, cnt, Y, Band, x, T, d0):
    """Index-1 accelerations ``[M Cq^T; Cq 0][a; lam] = [f; eta]`` (eq. index1) in time
    linear in the number of bodies for tree-like mechanisms, with Exudyn's dense M and C_q:

    * M block diagonal (``blk``, ``blkPtr``; ``blockOf`` coordinate -> block): each block
      inverted once per call;
    * the Schur complement ``S = C_q M^-1 C_q^T`` assembled block by block, only between
      rows that share a block, straight into band storage in the reverse Cuthill-McKee order
      ``pos`` (row -> position, bandwidth ``bw``, fixed at set-up: :meth:`~.evaluated.
      EvaluatedModel._order_rows`), and factored by the compiled kernel's band Cholesky
      (:mod:`exudyn_lie.mbs.linalg`, its rank rule);
    * ``a = M^-1 (f - C_q^T lam)`` block by block.

    A row without any coordinate (an inactive connector: its equation is ``lam = 0``) gets
    ``lam = 0`` (then the return value is 4; ``nzCnt`` tells which).  Returns 0; 1 if a block of M is singular;
    2 if S is singular (redundant constraints: the caller switches to the rank-revealing
    path); 3 if two rows sharing a block lie beyond the band (the pattern changed: the
    caller orders the rows again)."""
    n = f.shape[0]
    m = eta.shape[0]
    nb = blkPtr.shape[0] - 1
    if not invert_blocks(M, blk, blkPtr, blkOff, MinvB, W):
        return 1
    # a0 = M^-1 f
    for bI in range(nb):
        p0 = blkPtr[bI]
        s = blkPtr[bI + 1] - p0
        o = blkOff[bI]
        for i in range(s):
            acc = 0.0
            for k in range(s):
                acc += MinvB[o + i * s + k] * f[blk[p0 + k]]
            a[blk[p0 + i]] = acc
    if m == 0:
        return 0
    # nonzero columns and blocks of every row; rhs = Cq a0 - eta (in band order)
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
    # rows of every block (CSR)
    bRowPtr[0] = 0
    for bI in range(nb):
        bRowPtr[bI + 1] = bRowPtr[bI] + cnt[bI]
        cnt[bI] = 0
    for r in range(m):
        for q in range(rowBlkCnt[r]):
            bk = rowBlk[r, q]
            bRows[bRowPtr[bk] + cnt[bk]] = r
            cnt[bk] += 1
    # S in band storage: Band[i, i - j] = S[perm i, perm j]
    for i in range(m):
        for k in range(bw + 1):
            Band[i, k] = 0.0
    for bI in range(nb):
        r0 = bRowPtr[bI]
        nr = bRowPtr[bI + 1] - r0
        if nr == 0:
            continue
        p0 = blkPtr[bI]
        s = blkPtr[bI + 1] - p0
        o = blkOff[bI]
        for q in range(nr):              # Y[q] = M_B^-1 Cq[row q, B]^T
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
                    return 3
                acc = 0.0
                for i in range(s):
                    acc += Cq[r, blk[p0 + i]] * Y[q2, i]
                Band[pr, pr - pc] += acc
    empty = False
    for r in range(m):
        if nzCnt[r] == 0:                # lam = 0 for a row without coordinates
            Band[pos[r], 0] = 1.0
            x[pos[r]] = 0.0
            empty = True
    if band_ldl_inplace(Band, m, bw, REL_PIVOT_TOL, d0) >= 0:
        return 2
    band_ldl_solve_inplace(Band, m, bw, x)
    for r in range(m):
        lam[r] = x[pos[r]]
    # a = a0 - M^-1 Cq^T lam, block by block
    for bI in range(nb):
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
    return 4 if empty else 0
