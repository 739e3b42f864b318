"""Diagonally implicit Munthe-Kaas stages, compiled: the implicit methods' side of the stepper.

An ESDIRK tableau (``integrators.tableau.IMPLICIT_METHODS``: ``a_11 = 0``, ``a_jj = gamma`` for
``j > 1``) run by :func:`~.stepper.mk_steps` as an :class:`~.methods.ImplicitMethod`: stage 1 is
the explicit stage at the step's start, every later stage ``j`` solves, per body in its own group
(eq. MK1 with the stage's own term)::

    Theta_j = P_j + h gamma dexp^-1_{-Theta_j} V_j,      P_j = h sum_{l<j} a_jl k_l
    V_j     = W_j + h gamma F(t + c_j h, g exp(Theta_j), V_j),   W_j = V + h sum_{l<j} a_jl Vdot_l

for the stage's algebra element ``Theta_j`` and velocity ``V_j``; then ``k_j = (Theta_j - P_j) / (h
gamma)`` and ``Vdot_j = (V_j - W_j) / (h gamma)``, so that the step ``g exp(h sum b_j k_j)`` of a
stiffly accurate method ends at the last stage.  The update is still ``exp`` of an element of the
body's algebra: a lower pair to the ground stays exact on SE3 (the paper's corollary 1).

**Simplified Newton.**  With ``dexp^-1 ~ I`` in the Newton matrix (its derivative is O(Theta), and
the iteration converges to the exact stage solution whatever the matrix) and ``D_V = dF/dV``,
``D_Theta = dF/dTheta`` at the step's start, the iteration solves::

    (I - h gamma D_V - (h gamma)^2 D_Theta) dV = -F2 - h gamma D_Theta F1,   dTheta = -F1 + h gamma dV

with the residuals ``F1 = Theta - P - h gamma dexp^-1 V`` and ``F2 = V - W - h gamma F``.  ``D_V`` and
``D_Theta`` are forward differences of the stepper's own stage right-hand side (``stage_rhs``, so
the compiled and the evaluated path alike, with every item the right-hand side holds), along each
axis of each body's algebra (``axes``); the matrix is factored once (LU) and reused over the
stages and steps while the iteration converges fast, refactored when ``h`` changes, and the
Jacobian recomputed at the next step's start when the contraction rate exceeded ``REFRESH_RATE``
or when a stage did not converge with an older one (that stage is then solved again).  A stage
that does not converge with a Jacobian of its own step is solved by Newton's own iteration (the
Jacobian at every iterate: a force that switches on inside the stage, a contact that closes, is not
in the Jacobian of the step's start); if that fails too, ``STATUS_NEWTON``: the simulator divides
the step (``Simulator._substeps``), adaptive steps reject it.

Convergence: ``d = max(|dV|_inf / (tol v), |dTheta|_inf / (tol h gamma v))`` (round-off floors
added, also absolute ones: a spring whose motion L-stability damped to 1e-150 leaves the round-off
of R and the denormals) with ``v`` the velocity scale of the step, the largest ``|V|`` and ``|W_j|`` (not the
accelerations: a stiff transient's ``h F`` would loosen the tolerance; the position error a run
accumulates is about ``T tol v``); converged when ``eta d <= 1`` with Hairer's ``eta = theta /
(1 - theta)`` from the contraction rate ``theta``, or ``d <= 1`` (Hairer & Wanner II, sec. IV.8).
"""
from collections import namedtuple

import numpy as np
from numba import njit
from numba.extending import overload

from ..groups import GROUPS
from ..groups.interface import algebra_axes
from . import stepper
from .bodies import body_dexpinv_stage, exp_compose
from .codes import INFO_BODY, STAGE_ARG_MAX2, STATUS_EXTERNAL, STATUS_NEWTON, STATUS_OK
from .band_order import BAND_MIN_N, band_worthwhile, bandwidths, rcm_numbering
from .linalg import band_lu_extents, band_lu_factor_inplace, band_lu_solve_extents, lu_factor_inplace, lu_solve_inplace
from .jacobian_groups import (FD_STEP, NEW_COUPLING, body_coupling, color_bodies, grouped_differences, probe_coupling,
                              restore_configuration)
from .methods import ImplicitMethod, needed_stages
from .rhs_address import rhs_at
from .stepper import copy_state, stage_rhs_at

# The Newton iteration's arrays and state (one per simulator: tab.newton)
Newton = namedtuple("Newton", [
    "E", "piv",            # (n, n) the factored Newton matrix, n = 6 nb; its row exchanges
    "Dv", "Dth",           # (n, n) dF/dV and dF/dTheta at the start of the step they were computed at
    "axes",                # (nb, 6) 1.0 on the axes of each body's algebra (the unknowns), 0.0 elsewhere
    "P", "W", "Th",        # (nb, 6) the stage's explicit parts and its algebra element Theta_j
    "F1", "Ap", "A1",      # (nb, 6) the residual F1, F at the iterate (A1: kept over a Jacobian there)
    "x",                   # (n,) the right-hand side of the Newton system, then the correction dV
    "k6", "m6",            # (6,) scratch
    "perm", "iperm",       # (n,) int: a band numbering of the unknowns (mbs/band_order.py) and its inverse
    "deg", "nbr",          # (n,) int: the ordering's scratch; after a band factorisation the extents of its
                           #   U rows and L columns (linalg.band_lu_extents)
    "lo", "hi",            # (n,) int: the first and last column of each row of Dth that is not zero (in the
                           #   band numbering where NS_BAND: of each row of Db, as band columns)
    "Db",                  # (n, n) Dth in the band numbering, row a's band (kl + ku + 1 columns) first
    "y",                   # (n,) the Newton system's right-hand side and correction in the band numbering
    "coupled",             # (nb, nb) uint8: bodies coupled in the last Jacobian made column by column
    "color", "claim",      # (nb,) int: the bodies' groups for the differences (mbs/jacobian_groups.py); scratch
    "eps",                 # (nb,) the groups' difference steps
    "st",                  # float state: NS_* below
    "par",                 # [tolerance, maximum iterations, of Newton's own iteration (0: not tried),
                           #  1: fixed steps' tolerance follows the local error (follow_local_error),
                           #  1: a band numbering where it pays (newton_band; 0: dense always),
                           #  1: Jacobians by groups of bodies where they pay (0: column by column)]
])
NS_STALE, NS_FRESH, NS_H, NS_JACOBIANS, NS_FACTORS, NS_ITERATIONS, NS_STAGES, NS_RETRIES, NS_RATE, NS_FULL, \
    NS_BAND, NS_KL, NS_KU, NS_COLORS, NS_GROUPED, NS_BY_GROUPS = range(16)
NP_TOL, NP_MAXIT, NP_MAXIT_FULL, NP_FOLLOW, NP_BAND, NP_GROUPS = range(6)

# the correction relative to the step's velocity scale (and h gamma times it).  The last stage's
# velocity is the step's (stiffly accurate), so its Newton error adds up over the steps: about
# N tol v after N steps: a fixed looser tolerance became the error floor of the stiff chain of
# tests/test_implicit.py at its smaller steps.  The first fixed step's tolerance, and the least that
# follow_local_error sets (below)
NEWTON_TOL = 1e-11
# simplified Newton contracts linearly: an ANCF cable swinging at a step with h |lambda| = 37 for
# its fastest mode (the cable of ANCFslidingJoint2D.py) contracted at rates 0.1-0.2 with the
# Jacobian of the step's start, and needed about 10 iterations to reach the tolerance; with 10 the
# stages fell back to a new Jacobian (2n evaluations) and Newton's own iteration (2n per iterate).
# An iteration predicted not to converge within the limit at its rate still stops early.
NEWTON_MAXIT = 20
# fixed steps: the tolerance follows the local error of the step before (follow_local_error): a
# hundredth of it, at most FIXED_TOL_MAX; the first step, and methods without an embedded estimate,
# NEWTON_TOL.  An ANCF cable with a sliding joint (ANCFslidingJoint2Drigid.py, ESDIRK3 at its step,
# 1,200 steps; by hand): 163 s with NEWTON_TOL throughout, 122 s with this, 99 s with FIXED_TOL_MAX =
# 1e-6, all about 2e-3 from the reference at a tenth of the step (generalized-alpha at the step: 1.7e-2).
# Not looser: the Newton matrix's forward differences keep the constraints only to about sqrt(eps) of
# their columns, so the last correction leaves a violation of about 1e-8 of the tolerance per step: at
# 1e-6 the pendulum pinned on SE2 of tests/test_implicit.py drifted 1.6e-15 per step (4e-13 over its
# 250), at 1e-9 it ends at 4.6e-16 (corollary 1: round-off).
FIXED_KAPPA = 1e-2
FIXED_TOL_MAX = 1e-9
NEWTON_MAXIT_FULL = 30     # Newton's own iteration (a Jacobian per iterate): quadratic only near the solution
REFRESH_RATE = 0.25        # a contraction rate above this: new Jacobian at the next step's start
GROUPS_BELOW = 0.75        # Jacobians by groups of bodies where there are fewer groups than this times the
                           # bodies (mbs/jacobian_groups.py: 12 evaluations per group against 12 per body)
PROBE_MIN_BODIES = 8       # the pattern probed (nb evaluations) from this many bodies on; below, the first
                           # Jacobian is made column by column


def implicit_method(tableau, gid, tol=NEWTON_TOL, maxIterations=NEWTON_MAXIT):
    """The :class:`~.methods.ImplicitMethod` of a diagonally implicit tableau for the bodies of group
    ids ``gid``, with its Newton arrays."""
    if not tableau.implicit:
        raise ValueError(f"{tableau.name} is explicit")
    A, b, c = tableau.arrays()
    bh = np.zeros(0) if tableau.b_hat is None else np.array(tableau.b_hat, dtype=np.float64)
    return ImplicitMethod(A=A, b=b, c=c, stages=needed_stages(A, b), bhat=bh, gamma=float(tableau.gamma),
                          newton=newton_arrays(gid, tol, maxIterations))


def newton_tolerance(rtol):
    """The Newton tolerance of adaptive steps with the relative tolerance ``rtol``: a hundredth of it,
    within [NEWTON_TOL / 10, 1e-5]."""
    return float(min(1e-5, max(0.1 * NEWTON_TOL, 1e-2 * float(rtol))))


def newton_arrays(gid, tol=NEWTON_TOL, maxIterations=NEWTON_MAXIT):
    """The :class:`Newton` arrays for the bodies of group ids ``gid``."""
    nb = len(gid)
    n = 6 * nb
    names = list(GROUPS)
    axes = np.zeros((nb, 6))
    for i, g in enumerate(gid):
        axes[i, list(algebra_axes(GROUPS[names[int(g)]]))] = 1.0
    z = lambda: np.zeros((nb, 6))      # noqa: E731
    st = np.zeros(16)
    st[NS_STALE] = 1.0
    iz = lambda: np.zeros(n, np.int64)      # noqa: E731
    nband = n if n >= BAND_MIN_N else 0      # (Db: only where a band numbering may be taken)
    return Newton(E=np.zeros((n, n)), Db=np.zeros((nband, nband)), piv=iz(), Dv=np.zeros((n, n)), Dth=np.zeros((n, n)),
                  axes=axes, P=z(), W=z(), Th=z(), F1=z(), Ap=z(), A1=z(), x=np.zeros(n), k6=np.zeros(6),
                  m6=np.zeros(6), perm=iz(), iperm=iz(), deg=iz(), nbr=iz(), lo=iz(), hi=np.full(n, n - 1, np.int64),
                  y=np.zeros(n), coupled=np.zeros((nb, nb), np.uint8), color=np.zeros(nb, np.int64),
                  claim=np.zeros(nb, np.int64), eps=np.zeros(nb), st=st, par=np.array([float(tol), float(maxIterations), float(NEWTON_MAXIT_FULL),
                                         1.0 if tol == NEWTON_TOL else 0.0, 1.0, 1.0]))


def newton_counters(nw):
    """``{'jacobians', 'groupedJacobians', 'factorizations', 'iterations', 'stages', 'retries', 'fullNewton'}``
    so far: Jacobians (of them made by groups of bodies, mbs/jacobian_groups.py), stages solved again
    with a Jacobian of their step (retries) and by Newton's own iteration (fullNewton)."""
    s = nw.st
    return {"jacobians": int(s[NS_JACOBIANS]), "groupedJacobians": int(s[NS_GROUPED]),
            "factorizations": int(s[NS_FACTORS]),
            "iterations": int(s[NS_ITERATIONS]), "stages": int(s[NS_STAGES]), "retries": int(s[NS_RETRIES]),
            "fullNewton": int(s[NS_FULL])}


# --------------------------------------------------------------------------- the Newton matrix
@njit(cache=True, _nrt=False)
def _difference_column(Ap, A0, e, D, col):
    nb = Ap.shape[0]
    for i in range(nb):
        for k in range(6):
            D[6 * i + k, col] = (Ap[i, k] - A0[i, k]) / e


@njit(cache=True, _nrt=False)
def newton_jacobian(sd, wk, nw, t, R, r, V, A0):
    """``Dv = dF/dV`` and ``Dth = dF/dTheta`` at ``(t, g, V)`` where ``F = A0``, by forward differences
    of the stage right-hand side along each algebra axis; returns a status."""
    gid = sd.gid
    nb = gid.shape[0]
    copy_state(R, r, V, wk.Rs, wk.rs, wk.Vs)
    X = nw.m6
    for i in range(nb):
        for k in range(6):
            col = 6 * i + k
            if nw.axes[i, k] == 0.0:
                for row in range(6 * nb):
                    nw.Dv[row, col] = 0.0
                    nw.Dth[row, col] = 0.0
                continue
            e = FD_STEP * max(1.0, abs(V[i, k]))
            wk.Vs[i, k] = V[i, k] + e
            st = rhs_at(sd, wk, t, nw.Ap)
            wk.Vs[i, k] = V[i, k]
            if st != STATUS_OK:
                nw.st[NS_STALE] = 1.0        # Dv, Dth partly overwritten: the next stage makes them anew
                return st
            _difference_column(nw.Ap, A0, e, nw.Dv, col)
            for m in range(6):
                X[m] = 0.0
            X[k] = FD_STEP
            exp_compose(gid[i], R[i], r[i], X, wk.Rs[i], wk.rs[i], wk.m3[0], wk.v3[0])
            st = rhs_at(sd, wk, t, nw.Ap)
            restore_configuration(i, R, r, wk.Rs, wk.rs)
            if st != STATUS_OK:
                nw.st[NS_STALE] = 1.0
                return st
            _difference_column(nw.Ap, A0, FD_STEP, nw.Dth, col)
    nw.st[NS_JACOBIANS] += 1.0
    nw.st[NS_BY_GROUPS] = 0.0
    if nw.par[NP_GROUPS] != 0.0:
        body_coupling(nw.Dv, nw.Dth, nb, nw.coupled)
        ncol = color_bodies(nw.coupled, nb, nw.color, nw.claim)
        nw.st[NS_COLORS] = ncol if ncol < GROUPS_BELOW * nb else -1     # (-1: column by column from now on)
    newton_band(nw, 6 * nb)
    return STATUS_OK


@njit(cache=True, _nrt=False)
def newton_jacobian_grouped(sd, wk, nw, t, R, r, V, A0):
    """:func:`newton_jacobian` by groups of bodies (mbs/jacobian_groups.py) where the pattern of the
    last Jacobian made column by column, or else one found by ``probe_coupling``, gives fewer groups
    than ``GROUPS_BELOW`` times the bodies; column by column otherwise, or where a coupling outside
    the pattern appeared.  Returns a status."""
    nb = sd.gid.shape[0]
    if nw.par[NP_GROUPS] == 0.0 or nw.st[NS_COLORS] < 0.0:
        return newton_jacobian(sd, wk, nw, t, R, r, V, A0)
    if nw.st[NS_COLORS] == 0.0 and nb >= PROBE_MIN_BODIES:
        st = probe_coupling(sd, wk, t, R, r, V, A0, nw.Ap, nw.axes, nw.coupled, nw.m6)
        if st != STATUS_OK:
            nw.st[NS_STALE] = 1.0
            return st
        ncol = color_bodies(nw.coupled, nb, nw.color, nw.claim)
        nw.st[NS_COLORS] = ncol if ncol < GROUPS_BELOW * nb else -1
    ncol = int(nw.st[NS_COLORS])
    if ncol > 0:
        st = grouped_differences(sd, wk, t, R, r, V, A0, nw.Ap, nw.axes, nw.coupled, nw.color, ncol, nw.eps,
                                 nw.claim, nw.m6, nw.Dv, nw.Dth)
        if st == STATUS_OK:
            nw.st[NS_JACOBIANS] += 1.0
            nw.st[NS_GROUPED] += 1.0
            nw.st[NS_BY_GROUPS] = 1.0
            newton_band(nw, nw.Dv.shape[0])
            return STATUS_OK
        if st != NEW_COUPLING:
            nw.st[NS_STALE] = 1.0
            return st
    return newton_jacobian(sd, wk, nw, t, R, r, V, A0)


@njit(cache=True, _nrt=False)
def newton_band(nw, n):
    """A band numbering of the Newton matrix from the pattern of the Jacobians where it makes
    the factorisation cheaper (mbs/band_order.py): ``NS_BAND`` and its half-widths; and the
    extent (``lo``, ``hi``) of each row the iteration's product reads: of ``Db`` in the band
    numbering, of ``Dth`` otherwise."""
    nw.st[NS_BAND] = 0.0
    if n >= BAND_MIN_N and nw.par[NP_BAND] != 0.0:
        rcm_numbering(nw.Dv, nw.Dth, n, nw.perm, nw.iperm, nw.deg, nw.nbr)
        kl, ku = bandwidths(nw.Dv, nw.Dth, n, nw.iperm)
        if band_worthwhile(n, kl, ku):
            nw.st[NS_BAND] = 1.0
            nw.st[NS_KL] = kl
            nw.st[NS_KU] = ku
            for a in range(n):          # contiguous rows for the iteration's product (the band numbering
                row = nw.perm[a]        # scatters a row of Dth over the whole of it)
                lo, hi = n, -1
                for c in range(max(0, a - kl), min(n - 1, a + ku) + 1):
                    v = nw.Dth[row, nw.perm[c]]
                    nw.Db[a, c - a + kl] = v
                    if v != 0.0:
                        lo = min(lo, c)
                        hi = c
                nw.lo[a] = lo
                nw.hi[a] = hi
            return
    for row in range(n):
        lo, hi = n, -1
        for col in range(n):
            if nw.Dth[row, col] != 0.0:
                lo = min(lo, col)
                hi = col
        nw.lo[row] = lo
        nw.hi[row] = hi


@njit(cache=True, _nrt=False)
def newton_factor(nw, hg):
    """``E = I - hg Dv - hg^2 Dth``, factored (in the band numbering where ``NS_BAND``); returns a
    status."""
    n = nw.E.shape[0]
    hg2 = hg * hg
    if nw.st[NS_BAND] != 0.0:
        kl, ku = int(nw.st[NS_KL]), int(nw.st[NS_KU])
        for a in range(n):
            ra = nw.perm[a]
            for c in range(max(0, a - kl), min(n - 1, a + kl + ku) + 1):
                if c > a + ku:                # the fill of the row exchanges
                    nw.E[a, c] = 0.0
                    continue
                rc = nw.perm[c]
                v = -hg * nw.Dv[ra, rc] - hg2 * nw.Dth[ra, rc]
                if c == a:
                    v += 1.0
                nw.E[a, c] = v
        nw.st[NS_FACTORS] += 1.0
        if band_lu_factor_inplace(nw.E, n, kl, ku, nw.piv) >= 0:
            return STATUS_NEWTON
        band_lu_extents(nw.E, n, kl, ku, nw.nbr, nw.deg)
        return STATUS_OK
    for a in range(n):
        for c in range(n):
            nw.E[a, c] = -hg * nw.Dv[a, c] - hg2 * nw.Dth[a, c]
        nw.E[a, a] += 1.0
    nw.st[NS_FACTORS] += 1.0
    if lu_factor_inplace(nw.E, n, nw.piv, 0.0) >= 0:
        return STATUS_NEWTON
    return STATUS_OK


@njit(cache=True, _nrt=False)
def newton_correction(nw, n, hg, Vs, W, Ap, F1, x):
    """``x = E^-1 (-F2 - hg Dth F1)``, in the band numbering where ``NS_BAND`` (the product from
    ``Db``).  Otherwise the product reads each row of ``Dth`` from its first to its last entry that
    is not zero (the sum is the whole row's: the zeros add nothing)."""
    axes = nw.axes
    if nw.st[NS_BAND] == 0.0:
        for row in range(n):
            i, k = row // 6, row % 6
            s = 0.0
            for col in range(nw.lo[row], nw.hi[row] + 1):
                s += nw.Dth[row, col] * F1[col // 6, col % 6]
            x[row] = (-(Vs[i, k] - W[i, k] - hg * Ap[i, k]) - hg * s) * axes[i, k]
        lu_solve_inplace(nw.E, n, nw.piv, x)
        return
    kl = int(nw.st[NS_KL])
    perm, y = nw.perm, nw.y
    for c in range(n):                  # x: F1 in the band numbering, y: the right-hand side
        col = perm[c]
        x[c] = F1[col // 6, col % 6]
    for a in range(n):
        row = perm[a]
        i, k = row // 6, row % 6
        s = 0.0
        for c in range(nw.lo[a], nw.hi[a] + 1):
            s += nw.Db[a, c - a + kl] * x[c]
        y[a] = (-(Vs[i, k] - W[i, k] - hg * Ap[i, k]) - hg * s) * axes[i, k]
    band_lu_solve_extents(nw.E, n, nw.piv, nw.nbr, nw.deg, y)
    for a in range(n):
        x[perm[a]] = y[a]


# --------------------------------------------------------------------------- one stage
@njit(cache=True, _nrt=False)
def explicit_parts(A, j, h, V, K, Vd, P, W):
    """``P_j = h sum_{l<j} a_jl k_l`` and ``W_j = V + h sum_{l<j} a_jl Vdot_l``."""
    for i in range(V.shape[0]):
        for k in range(6):
            p = 0.0
            w = V[i, k]
            for l in range(j):
                p += A[j, l] * K[l, i, k]
                w += h * A[j, l] * Vd[l, i, k]
            P[i, k] = h * p
            W[i, k] = w


@njit(cache=True, _nrt=False)
def newton_iterate(sd, wk, nw, j, jprev, hg, tj, R, r, V, vscale, full):
    """The simplified Newton iteration of stage ``j`` (module docstring), from the predictor
    ``V_j = W_j + hg Vdot_jprev``, ``Theta_j = P_j + hg k_jprev``; the stage's ``V_j`` in ``wk.Vs``,
    ``Theta_j`` in ``nw.Th``.  With ``full``, Newton's own iteration: the Jacobian at every iterate
    (a force that switches on inside the stage, such as a contact that closes, is not in the
    Jacobian of the step's start).  Returns a status (STATUS_NEWTON: no convergence, also when an
    iterate's rotation leaves the domain of dexpinv)."""
    gid = sd.gid
    nb = gid.shape[0]
    Th, P, W, F1, x, Ap, axes = nw.Th, nw.P, nw.W, nw.F1, nw.x, nw.Ap, nw.axes
    tol = nw.par[NP_TOL]
    maxit = int(nw.par[NP_MAXIT_FULL]) if full else int(nw.par[NP_MAXIT])
    tscale = hg * vscale
    eps8 = 8.0 * 2.220446049250313e-16
    for i in range(nb):
        for k in range(6):
            wk.Vs[i, k] = W[i, k] + hg * wk.Vd[jprev, i, k] * axes[i, k]
            Th[i, k] = (P[i, k] + hg * wk.K[jprev, i, k]) * axes[i, k]
    dprev = 0.0
    rate = 0.0
    for it in range(maxit):
        for i in range(nb):
            Ti = Th[i]
            if not Ti[0] * Ti[0] + Ti[1] * Ti[1] + Ti[2] * Ti[2] <= STAGE_ARG_MAX2:
                wk.failInfo[INFO_BODY] = i
                return STATUS_NEWTON
            exp_compose(gid[i], R[i], r[i], Ti, wk.Rs[i], wk.rs[i], wk.m3[0], wk.v3[0])
        st = rhs_at(sd, wk, tj, Ap)
        nw.st[NS_ITERATIONS] += 1.0
        if st == STATUS_EXTERNAL and wk.ext[1] != 0:     # non-finite rates outside: the iterate diverged
            wk.ext[1] = 0
            return STATUS_NEWTON
        if st != STATUS_OK:
            return st
        if full:                         # the Jacobian at this iterate (wk.Rb, rb, Vb: free during the stages)
            copy_state(wk.Rs, wk.rs, wk.Vs, wk.Rb, wk.rb, wk.Vb)
            for i in range(nb):
                for k in range(6):
                    nw.A1[i, k] = Ap[i, k]
            st = newton_jacobian(sd, wk, nw, tj, wk.Rb, wk.rb, wk.Vb, nw.A1)
            if st == STATUS_OK:
                st = newton_factor(nw, hg)
            if st != STATUS_OK:
                return st
            copy_state(wk.Rb, wk.rb, wk.Vb, wk.Rs, wk.rs, wk.Vs)
            for i in range(nb):
                for k in range(6):
                    Ap[i, k] = nw.A1[i, k]
        for i in range(nb):
            for k in range(6):
                nw.m6[k] = -Th[i, k]
            body_dexpinv_stage(gid[i], nw.m6, wk.Vs[i], nw.k6)
            for k in range(6):
                F1[i, k] = (Th[i, k] - P[i, k] - hg * nw.k6[k]) * axes[i, k]
        newton_correction(nw, 6 * nb, hg, wk.Vs, W, Ap, F1, x)
        d = 0.0
        for i in range(nb):
            for k in range(6):
                if axes[i, k] == 0.0:
                    continue
                dv = x[6 * i + k]
                dt = -F1[i, k] + hg * dv
                wk.Vs[i, k] += dv
                Th[i, k] += dt
                # round-off floors, relative to the values and absolute (1 rad, 1 length unit per
                # second or per step): increments carry the round-off of R and r themselves, and a
                # motion damped to 1e-150 by L-stability reaches the denormals
                d = max(d, abs(dv) / (tol * vscale + eps8 * max(abs(wk.Vs[i, k]), vscale, 1.0)),
                        abs(dt) / (tol * tscale + eps8 * max(abs(Th[i, k]), 1.0)))
        if not np.isfinite(d):
            return STATUS_NEWTON
        if it > 0:
            rate = d / dprev if dprev > 0.0 else 0.0
            nw.st[NS_RATE] = max(nw.st[NS_RATE], rate)
            if rate >= 1.0 and d > 1.0 and not (full and rate < 4.0):
                return STATUS_NEWTON
            if rate < 1.0 and rate / (1.0 - rate) * d <= 1.0:
                return STATUS_OK
            # what the remaining iterations can reach at this rate (Hairer & Wanner II, (8.24)); Newton's
            # own iteration converges faster near the solution than its rate far from it predicts
            if not full and rate < 1.0 and rate ** (maxit - 1 - it) / (1.0 - rate) * d > 1.0:
                return STATUS_NEWTON
        if d <= 1.0:
            return STATUS_OK
        dprev = d
    return STATUS_NEWTON


@njit(cache=True, _nrt=False)
def solve_stage(sd, wk, A, c, gamma, nw, stages, j, h, t, R, r, V):
    """Stage ``j`` of an ESDIRK step of size ``h`` from ``(t, g, V)``: ``k_j`` into ``wk.K[j]``,
    ``Vdot_j`` into ``wk.Vd[j]``.  At the first implicit stage the Newton matrix is brought up to
    date (Jacobian if stale, factorisation if ``h`` changed); a stage that does not converge with an
    older Jacobian is solved again with one of this step."""
    hg = h * gamma
    jprev = stages[0]
    for jj in range(stages.shape[0]):
        if stages[jj] == j:
            break
        jprev = stages[jj]
    if jprev == stages[0]:                 # the first implicit stage: a new step
        nw.st[NS_FRESH] = 0.0
        nw.st[NS_RATE] = 0.0
        if nw.st[NS_STALE] != 0.0:
            st = newton_jacobian_grouped(sd, wk, nw, t, R, r, V, wk.Vd[stages[0]])
            if st != STATUS_OK:
                return st
            nw.st[NS_STALE] = 0.0
            nw.st[NS_FRESH] = 1.0
            nw.st[NS_H] = 0.0
        if nw.st[NS_H] != hg:
            st = newton_factor(nw, hg)
            if st != STATUS_OK:
                return st
            nw.st[NS_H] = hg
    explicit_parts(A, j, h, V, wk.K, wk.Vd, nw.P, nw.W)
    vscale = 1e-300
    for i in range(V.shape[0]):
        for k in range(6):
            vscale = max(vscale, abs(V[i, k]), abs(nw.W[i, k]))
    st = newton_iterate(sd, wk, nw, j, jprev, hg, t + c[j] * h, R, r, V, vscale, False)
    if st == STATUS_NEWTON and (nw.st[NS_FRESH] == 0.0 or nw.st[NS_BY_GROUPS] != 0.0):
        # an older Jacobian, or one of this step by groups (a coupling outside its pattern between two
        # bodies of one group is not seen by its check): one of this step, column by column
        nw.st[NS_RETRIES] += 1.0
        st = newton_jacobian(sd, wk, nw, t, R, r, V, wk.Vd[stages[0]])
        if st != STATUS_OK:
            return st
        nw.st[NS_FRESH] = 1.0
        st = newton_factor(nw, hg)
        if st != STATUS_OK:
            return st
        nw.st[NS_H] = hg
        st = newton_iterate(sd, wk, nw, j, jprev, hg, t + c[j] * h, R, r, V, vscale, False)
    if st == STATUS_NEWTON and nw.par[NP_MAXIT_FULL] > 0.0:
        nw.st[NS_FULL] += 1.0
        st = newton_iterate(sd, wk, nw, j, jprev, hg, t + c[j] * h, R, r, V, vscale, True)
        nw.st[NS_H] = 0.0                # (the matrix of the last iterate serves this step's later stages;
        nw.st[NS_STALE] = 1.0            #  the next step starts with a Jacobian at its start)
    if st != STATUS_OK:
        nw.st[NS_STALE] = 1.0
        return st
    nw.st[NS_STAGES] += 1.0
    if nw.st[NS_RATE] > REFRESH_RATE:
        nw.st[NS_STALE] = 1.0
        if nw.st[NS_FRESH] != 0.0 and nw.st[NS_BY_GROUPS] != 0.0:
            nw.st[NS_COLORS] = 0.0       # slow with this step's own Jacobian by groups: a coupling outside
                                         # its pattern, perhaps (the next finds the pattern anew)
    Kj = wk.K[j]
    Vdj = wk.Vd[j]
    for i in range(V.shape[0]):
        for k in range(6):
            Kj[i, k] = (nw.Th[i, k] - nw.P[i, k]) / hg
            Vdj[i, k] = (wk.Vs[i, k] - nw.W[i, k]) / hg
    return STATUS_OK


@njit(cache=True, _nrt=False)
def follow_local_error(b, bhat, stages, nw, h, V, Vd):
    """Fixed steps: the Newton tolerance of the next step, ``FIXED_KAPPA`` times this step's local
    error estimated by the embedded weights (``|h sum (b_j - bhat_j) Vdot_j|`` relative to the
    velocity scale), within [``NEWTON_TOL``, ``FIXED_TOL_MAX``] (Hairer & Wanner II, sec. IV.8: the
    iteration error well below the method's own, as adaptive steps hold it with ``newton_tolerance``).
    A method without embedded weights keeps ``NEWTON_TOL``; so does a tolerance set by the user
    (``par[NP_FOLLOW] = 0``: :func:`~.implicit_run.set_newton_tolerance`)."""
    if bhat.shape[0] == 0 or nw.par[NP_FOLLOW] == 0.0:
        return
    nw_axes = nw.axes
    est = 0.0
    vscale = 1e-300
    for i in range(V.shape[0]):
        for k in range(6):
            if nw_axes[i, k] == 0.0:
                continue
            vscale = max(vscale, abs(nw.W[i, k]))       # (the last stage's scale, as solve_stage's)
            e = 0.0
            for jj in range(stages.shape[0]):
                j = stages[jj]
                e += (b[j] - bhat[j]) * Vd[j, i, k]
            est = max(est, abs(h * e))
            vscale = max(vscale, abs(V[i, k]))
    nw.par[NP_TOL] = min(FIXED_TOL_MAX, max(NEWTON_TOL, FIXED_KAPPA * est / vscale))


# --------------------------------------------------------------------------- the stepper's seam
@overload(stepper.is_implicit, inline="always")
def _implicit_is_implicit(tab):
    if stepper.carries_newton(tab):
        return lambda tab: True


@overload(stepper.evaluate_stage, inline="always")
def _implicit_evaluate_stage(sd, wk, tab, t, Vdot):
    if stepper.carries_newton(tab):
        return lambda sd, wk, tab, t, Vdot: stage_rhs_at(sd, wk, t, Vdot)     # (the time loop's direct call)


@overload(stepper.implicit_stage, inline="always")
def _implicit_stage(sd, wk, tab, j, h, t, R, r, V):
    if not stepper.carries_newton(tab):
        return None
    if "bhat" in tab.instance_class._fields:        # fixed steps (ImplicitMethod): the tolerance follows the step
        def fixed(sd, wk, tab, j, h, t, R, r, V):
            st = solve_stage(sd, wk, tab.A, tab.c, tab.gamma, tab.newton, tab.stages, j, h, t, R, r, V)
            if st == STATUS_OK and j == tab.stages[tab.stages.shape[0] - 1]:
                follow_local_error(tab.b, tab.bhat, tab.stages, tab.newton, h, V, wk.Vd)
            return st
        return fixed

    def impl(sd, wk, tab, j, h, t, R, r, V):
        return solve_stage(sd, wk, tab.A, tab.c, tab.gamma, tab.newton, tab.stages, j, h, t, R, r, V)
    return impl
