"""Compiled pieces of the Exudyn-evaluated path (:mod:`.evaluated`, :mod:`.evaluated_stepper`):
one numba call per stage before Exudyn evaluates the model, one after.

The Lie group nodes (``NodeRigidBodyRotVecLG``) are "bodies" with a group id of the
registry (SE3 / SO3xR3) and go through the *same* stage functions as the compiled kernel
(:func:`~exudyn_lie.mbs.stepper.stage_state`, :func:`~exudyn_lie.mbs.stepper.stage_k`,
:func:`~exudyn_lie.mbs.stepper.finish`: eq. MK1, ``g_j = g exp(Psi_j)``,
``k_j = dexp^-1_{-Psi_j} V_j``), so both paths integrate the same ODE with the same
arithmetic.  Their state velocity is the kernel's: SE3 the body twist ``(omega, U)``,
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
from ..mbs.stepper import finish, stage_k, stage_state
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
def lg_stage(gid, A, j, h, R, r, V, K, Vd, Psi, Rs, rs, Vs, ER, Er, vq, vv, QK, VK, qs, vs):
    """Stage state of eq. MK1: the Lie group nodes through the compiled kernel's
    ``stage_state``; the vector coordinates ``q_j = q + h sum a_jl qdot_l``,
    ``v_j = v + h sum a_jl vdot_l``.  Returns -1 or the node whose stage argument left the
    domain of dexp^-1 (as the compiled kernel)."""
    bad = stage_state(gid, A, j, h, R, r, V, K, Vd, Psi, Rs, rs, Vs, ER, Er)
    for k in range(vq.shape[0]):
        a = vq[k]
        b = vv[k]
        for l in range(j):
            a += h * A[j, l] * QK[l, k]
            b += h * A[j, l] * VK[l, k]
        qs[k] = a
        vs[k] = b
    return bad


@njit(cache=True)
def lg_stage_rates(gid, j, Rs, Vs, acc, lgIdx, Psi, K, Vd, tmp6, vecIdx, vs, QK, VK):
    """After Exudyn's accelerations ``acc`` (nODE2) of stage j: the group velocity rates
    ``Vdot_j`` per Lie group node (SO3xR3: ``(omegadot, rddot)``; SE3:
    ``(omegadot, R^T rddot - omega x U)``, from ``rdot = R U``), the MK stage map
    ``k_j = dexp^-1_{-Psi_j} V_j`` (compiled kernel's ``stage_k``), and the vector
    coordinates' rates ``qdot_j = v_j``, ``vdot_j = acc``."""
    for i in range(gid.shape[0]):
        Vdi = Vd[j, i]
        for k in range(3):
            Vdi[k] = acc[lgIdx[i, 3 + k]]
        if uses_body_twist(gid[i]):
            w = Vs[i]
            R = Rs[i]
            for k in range(3):
                Vdi[3 + k] = (R[0, k] * acc[lgIdx[i, 0]] + R[1, k] * acc[lgIdx[i, 1]] + R[2, k] * acc[lgIdx[i, 2]])
            Vdi[3] -= w[1] * w[5] - w[2] * w[4]
            Vdi[4] -= w[2] * w[3] - w[0] * w[5]
            Vdi[5] -= w[0] * w[4] - w[1] * w[3]
        else:
            for k in range(3):
                Vdi[3 + k] = acc[lgIdx[i, k]]
    stage_k(gid, j, Psi, Vs, K, tmp6)
    for k in range(vecIdx.shape[0]):
        QK[j, k] = vs[k]
        VK[j, k] = acc[vecIdx[k]]


@njit(cache=True)
def lg_finish(gid, stages, b, h, R, r, V, K, Vd, Psi, Rn, C, rn, Er, vq, vv, QK, VK, vlimit):
    """``g <- g exp(h sum b_j k_j)`` (compiled kernel's ``finish``, with its
    re-orthonormalisation), ``V <- V + h sum b_j Vdot_j``; vector coordinates likewise.
    Returns 0, 1 if the new state is not finite, 2 if a velocity exceeds ``vlimit``
    (a blow-up)."""
    finish(gid, stages, b, h, R, r, V, K, Vd, Psi, Rn, C, rn, Er)
    for k in range(vq.shape[0]):
        a = 0.0
        c = 0.0
        for jj in range(stages.shape[0]):
            j = stages[jj]
            a += b[j] * QK[j, k]
            c += b[j] * VK[j, k]
        vq[k] += h * a
        vv[k] += h * c
    big = False
    for i in range(gid.shape[0]):
        for k in range(6):
            if not math.isfinite(V[i, k]):
                return 1
            if abs(V[i, k]) > vlimit:
                big = True
        for k in range(3):
            if not math.isfinite(r[i, k]):
                return 1
    for k in range(vq.shape[0]):
        if not (math.isfinite(vq[k]) and math.isfinite(vv[k])):
            return 1
        if abs(vv[k]) > vlimit:
            big = True
    return 2 if big else 0


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


@njit(cache=True)
def stiffness_estimate(A, h, jl, K, Vd, QK, VK):
    """An estimate of the fastest rate |lambda| the last step met (Shampine's idea, for
    second-order equations): between the first and the last evaluated stage ``jl`` the
    configuration moved by ``dq = h sum_l a_jl qdot_l`` (Lie group nodes in the algebra,
    ``k_l``) and the acceleration changed by ``da``; ``rho = sqrt(|da| / |dq|)``.  For
    ``a = -K q - D v`` it gives omega for a stiffness-dominated mode (``da = -K dq``) and c for a
    damping-dominated one (``da = -c dv``, ``dv = c dq``); ``h rho`` beyond the method's
    stability radius means the step amplifies that mode."""
    num = 0.0
    den = 0.0
    for i in range(K.shape[1]):
        for k in range(6):
            dq = 0.0
            for l in range(jl):
                dq += A[jl, l] * K[l, i, k]
            den += (h * dq) ** 2
            num += (Vd[jl, i, k] - Vd[0, i, k]) ** 2
    for k in range(QK.shape[1]):
        dq = 0.0
        for l in range(jl):
            dq += A[jl, l] * QK[l, k]
        den += (h * dq) ** 2
        num += (VK[jl, k] - VK[0, k]) ** 2
    if den == 0.0 or num == 0.0:
        return 0.0
    return math.sqrt(math.sqrt(num / den))
