"""Adaptive Munthe-Kaas steps with error control on the group, compiled (issue 18).

The adaptive kind of the stepper's controller seam (:mod:`.stepper`): the same stage
functions (``mk_stage_state``, ``stage_rhs``, ``mk_stage_k``, ``mk_finish``; eq. MK1),
driven by the PI controller, HINIT and the Lie-algebra error norm of
:mod:`~exudyn_lie.integrators.control`.  It is a loop of its own, so the fixed-step loop
``stepper.mk_steps`` is untouched (not one instruction more per fixed step, and the
paper's fixed-step runs stay bit-identical); ``integrators/mk_adaptive.py`` is its oracle.

One attempt from ``(t, g, V)`` with step ``h`` (eq. MK1 per body)::

    Psi_j = h sum_{l<j} a_jl k_l,  Vdot_j = F(t + c_j h, g exp(Psi_j), V_j),  k_j = dexp^-1_{-Psi_j} V_j
    g+ = g exp(h sum b_j k_j),  V+ = V + h sum b_j Vdot_j                (local extrapolation)
    err = || (h sum (b_j - bhat_j) k_j,  h sum (b_j - bhat_j) Vdot_j) ||  (both increments at g:
                                                                            no chart, control.py)

* **FSAL** (last row of A = b, e.g. DOPRI5): the last stage is evaluated at the step's end;
  its ``Vdot`` is the next step's first stage (copied at the start of the next attempt, so
  that the accepted step's stages stay intact for dense output).  After a rejection stage 1
  is reused as it is (same state and time).
* **Rejection** restores the start-of-step copy ``(R0, r0, V0)``.  A stage argument beyond
  STAGE_ARG_MAX or a non-finite state is a rejection with the largest decrease (err = inf).
* **Minimum step**: ``STATUS_STEP_MIN`` when the controller asks for a retry below
  ``h_min`` (or below the time's resolution); the caller raises ``StepSizeError``.
* **Dense output on the group** (continuous extension ``b_j(theta)`` of the tableau, e.g.
  Shampine's for DOPRI5): ``g(t + theta h) = g exp(h sum b_j(theta) k_j)``,
  ``V(t + theta h) = V + h sum b_j(theta) Vdot_j``.  Output times are met exactly without
  shortening a step; only the last step is clipped to ``tEnd``.  Extra dense stages (Vern6)
  are evaluated only in steps with an output inside them.

State kept between calls (so a caller may take outputs a chunk at a time): the float array
``fs`` (``FS_T`` time, ``FS_H`` next step, ``FS_TPREV``/``FS_HPREV`` the last accepted step)
and the int array ``ist`` (``IS_HAVE0``: stage 1 available, ``IS_EXTRA``: extra stages of the
last step evaluated, ``IS_VALID``: the last step's dense data valid).  The last accepted
step's start state stays in ``R0, r0, V0`` and its stages in ``wk.K, wk.Vd``.
"""
from collections import namedtuple

import numpy as np
from numba import njit

from ..integrators import control as C
from .bodies import exp_compose
from .codes import STAB_NONE, STATUS_OK, STATUS_STEP_MIN
from .forces import update_torsion_tracking
from .projection import CT_N_PROJ, CT_POS, enforce_constraint_tolerance, project_error_estimate, project_state
from .row_drives import update_row_drives
from .rotation_parameters import tracked_at
from .stepper import (copy_state, mk_finish, mk_stage_k, mk_stage_state, needed_stages, stage_rhs, state_is_finite,
                      watch_rotation_entries)

# A tableau as the adaptive loop uses it: the stage matrix and nodes extended by the dense
# extra stages, b (s), the stages of a step (b or bhat needs them), e = b - bhat, the dense
# polynomial coefficients (s + m, degree), the number s of stages of a step, FSAL flag.
AdaptiveMethod = namedtuple("AdaptiveMethod", ["A", "b", "c", "stages", "e", "P", "s", "fsal"])

FS_T, FS_H, FS_TPREV, FS_HPREV = range(4)
IS_HAVE0, IS_EXTRA, IS_VALID = range(3)
HAVE0_NONE, HAVE0_STAGE1, HAVE0_FSAL = 0, 1, 2


def adaptive_method(tab):
    """The :class:`AdaptiveMethod` of an embedded pair (a tableau with ``b_hat``)."""
    if tab.b_hat is None:
        raise ValueError(f"method '{tab.name}' has no embedded weights (b_hat): adaptive steps need an "
                         f"embedded pair (DOPRI5, BS3 = ODE23, Vern6)")
    A, b, c = tab.arrays()
    bh = np.array(tab.b_hat, dtype=np.float64)
    s = len(b)
    # the stages b or b_hat needs (DOPRI5's 7th: b_7 = 0, bhat_7 = 1/40)
    stages = needed_stages(A, np.abs(b) + np.abs(bh))
    m = 0 if tab.dense is None else tab.dense.extra_stages
    Aext = np.zeros((s + m, s + m))
    Aext[:s, :s] = A
    cext = np.zeros(s + m)
    cext[:s] = c
    if m:
        Aext[s:, :] = np.asarray(tab.dense.A_extra, dtype=np.float64)
        cext[s:] = np.asarray(tab.dense.c_extra, dtype=np.float64)
    P = np.zeros((s + m, 1)) if tab.dense is None else np.asarray(tab.dense.P, dtype=np.float64).copy()
    return AdaptiveMethod(A=Aext, b=b, c=cext, stages=stages, e=b - bh, P=np.ascontiguousarray(P), s=s,
                          fsal=bool(tab.fsal))


@njit(cache=True, _nrt=False)
def dense_state(sd, wk, am, theta, h, R0, r0, V0, Ro, ro, Vo, w):
    """The dense output at ``t + theta h`` of the last accepted step (module docstring):
    ``Ro = g0 exp(h sum_j b_j(theta) k_j)``, ``Vo = V0 + h sum_j b_j(theta) Vdot_j``."""
    P = am.P
    ns = P.shape[0]
    for j in range(ns):
        acc = 0.0
        th = theta
        for k in range(P.shape[1]):
            acc += P[j, k] * th
            th *= theta
        w[j] = acc
    sig = wk.tmp6
    for i in range(sd.gid.shape[0]):
        for k in range(6):
            p = 0.0
            v = 0.0
            for j in range(ns):
                if w[j] != 0.0:
                    p += w[j] * wk.K[j, i, k]
                    v += w[j] * wk.Vd[j, i, k]
            sig[k] = h * p
            Vo[i, k] = V0[i, k] + h * v
        exp_compose(sd.gid[i], R0[i], r0[i], sig, Ro[i], ro[i], wk.m3[0], wk.v3[0])


@njit(cache=True, _nrt=False)
def extra_stages(sd, wk, am, t, h, R0, r0, V0, S):
    """The dense-only stages s..s+m-1 of the last accepted step (from its start state)."""
    for j in range(am.s, am.A.shape[0]):
        st = mk_stage_state(sd, wk, am.A, j, h, R0, r0, V0)
        if st != STATUS_OK:
            return st
        st = stage_rhs(sd, wk, t + am.c[j] * h, wk.Vd[j])
        S[C.S_N_RHS] += 1.0
        if st != STATUS_OK:
            return st
        mk_stage_k(sd, wk, j)
    return STATUS_OK


@njit(cache=True, _nrt=False)
def serve_outputs(sd, wk, am, ctol, fs, ist, R0, r0, V0, R, r, V, S, tout, k, Ro, ro, Vo, Po, w):
    """Outputs ``tout[k:]`` inside the last accepted step ``(tprev, t]``: the end state at
    ``t`` itself, dense output inside (projected on the group when its constraint drift
    exceeds the constraint tolerance ``ctol``, as Simbody projects interpolated states); if ``Po``
    has rows, the tracked angles and node rotation parameters at each (rotation_parameters:
    inside the step, nearest those at its end).
    Returns (status, next k)."""
    t, tp, hp = fs[FS_T], fs[FS_TPREV], fs[FS_HPREV]
    while k < tout.shape[0] and tout[k] <= t:
        if tout[k] == t or ist[IS_VALID] == 0:
            copy_state(R, r, V, Ro[k], ro[k], Vo[k])
        else:
            if ist[IS_EXTRA] == 0:
                if am.A.shape[0] > am.s:
                    st = extra_stages(sd, wk, am, tp, hp, R0, r0, V0, S)
                    if st != STATUS_OK:
                        return st, k
                ist[IS_EXTRA] = 1
            dense_state(sd, wk, am, (tout[k] - tp) / hp, hp, R0, r0, V0, Ro[k], ro[k], Vo[k], w)
            if ctol[CT_POS] > 0.0:                  # as Simbody's projectInterpolatedStates
                st = update_row_drives(wk.drive, tout[k])     # the rows' moving offsets at the output time
                if st == STATUS_OK:
                    st, _ = enforce_constraint_tolerance(sd, wk, ctol, Ro[k], ro[k], Vo[k])
                if st != STATUS_OK:
                    return st, k
        if Po.shape[0] > k:
            tracked_at(wk.btrack, wk.bframe, wk.bangle, wk.bparam, Ro[k], Po[k])
        k += 1
    return STATUS_OK, k


@njit(cache=True, _nrt=False)
def mk_adaptive_steps(sd, wk, am, par, S, tol, ctol, fs, ist, tEnd, R, r, V, R0, r0, V0, dPhi, dV, w, vmax,
                      tout, Ro, ro, Vo, Po):
    """Adaptive MK steps from ``fs[FS_T]`` with the next step ``fs[FS_H]`` until ``tEnd``, or
    until every output time ``tout`` (sorted, at most tEnd) is written to ``Ro, ro, Vo``.
    ``ctol`` (:mod:`.projection`, ``CT_*``): with a constraint tolerance (``ctol[CT_POS] > 0``)
    the error estimate is projected onto the constraint manifold's tangent space and an
    accepted state whose drift exceeds the tolerance is projected on the group.
    Returns (status, outputs written).  On a failure (R, r, V) hold the last accepted step."""
    A, c, stages, s = am.A, am.c, am.stages, am.s
    ns = stages.shape[0]
    nt = tout.shape[0]
    st, k = serve_outputs(sd, wk, am, ctol, fs, ist, R0, r0, V0, R, r, V, S, tout, 0, Ro, ro, Vo, Po, w)
    if st != STATUS_OK:
        return st, k
    eps4 = 4.0 * 2.220446049250313e-16 * abs(tEnd)
    while fs[FS_T] < tEnd and not (nt > 0 and k >= nt):
        t = fs[FS_T]
        h = fs[FS_H]
        last = t + h >= tEnd - eps4                 # no sliver step before the end time
        htry = tEnd - t if last else h
        if ist[IS_HAVE0] == HAVE0_FSAL:             # the previous step's last stage is stage 1
            for i in range(V.shape[0]):
                for q in range(6):
                    wk.Vd[0, i, q] = wk.Vd[s - 1, i, q]
            ist[IS_HAVE0] = HAVE0_STAGE1
        copy_state(R, r, V, R0, r0, V0)
        ist[IS_VALID] = 0                           # K, Vd and R0 now belong to this attempt
        ok = True
        for jj in range(ns):
            j = stages[jj]
            st = mk_stage_state(sd, wk, A, j, htry, R, r, V)
            if st != STATUS_OK:                     # stage argument beyond STAGE_ARG_MAX
                ok = False
                break
            if not (j == 0 and ist[IS_HAVE0] == HAVE0_STAGE1):
                st = stage_rhs(sd, wk, t + c[j] * htry, wk.Vd[j])
                S[C.S_N_RHS] += 1.0
                if st != STATUS_OK:
                    return st, k
                if j == 0:
                    ist[IS_HAVE0] = HAVE0_STAGE1
            mk_stage_k(sd, wk, j)
        err = np.inf
        if ok:
            mk_finish(sd, wk, am, htry, R, r, V)
            if state_is_finite(sd.gid, R, r, V, vmax) == STATUS_OK:
                if ctol[CT_POS] > 0.0:              # drift is the constraint tolerance's business
                    C.increment_difference(am.e, htry, wk.K[:s], wk.Vd[:s], dPhi, dV)
                    st = project_error_estimate(sd, wk, R, r, V, dPhi, dV)
                    if st != STATUS_OK:
                        copy_state(R0, r0, V0, R, r, V)
                        return st, k
                    err = C.weighted_rms(dPhi, dV, r0, r, V0, V, tol)
                else:
                    err = C.embedded_error_norm(am.e, htry, wk.K[:s], wk.Vd[:s], r0, r, V0, V, tol, dPhi, dV)
        status = C.control_step(par, S, htry, err)
        if status != C.STATUS_ACCEPT:
            copy_state(R0, r0, V0, R, r, V)         # stage 1 stays valid (same state and time)
            if status == C.STATUS_H_MIN or S[C.S_H] <= 1e-14 * max(1.0, abs(t)):
                fs[FS_H] = S[C.S_H]
                return STATUS_STEP_MIN, k
            fs[FS_H] = S[C.S_H]
            continue
        projected = False
        st = STATUS_OK
        if sd.stabilization != STAB_NONE or ctol[CT_POS] > 0.0:
            st = update_row_drives(wk.drive, t + htry)        # the rows' moving offsets at the step's end
        if st == STATUS_OK and sd.stabilization != STAB_NONE:
            st = project_state(sd, wk, sd.stabilization, R, r, V)
            projected = True
        elif st == STATUS_OK and ctol[CT_POS] > 0.0:
            st, projected = enforce_constraint_tolerance(sd, wk, ctol, R, r, V)
            if projected:
                ctol[CT_N_PROJ] += 1.0
        if st != STATUS_OK:
            copy_state(R0, r0, V0, R, r, V)
            return st, k
        update_torsion_tracking(sd, wk, R, r, V)
        if wk.watchBody.shape[0] > 0:
            watch_rotation_entries(wk.watchBody, wk.watchEntry, wk.watchMax, R)
        fs[FS_TPREV] = t
        fs[FS_HPREV] = htry
        fs[FS_T] = tEnd if last else t + htry
        fs[FS_H] = S[C.S_H]
        ist[IS_VALID] = 1
        ist[IS_EXTRA] = 0
        # FSAL: the last stage was evaluated at the step's end (not after a projection)
        ist[IS_HAVE0] = HAVE0_FSAL if (am.fsal and not projected) else HAVE0_NONE
        st, k = serve_outputs(sd, wk, am, ctol, fs, ist, R0, r0, V0, R, r, V, S, tout, k, Ro, ro, Vo, Po, w)
        if st != STATUS_OK:
            return st, k
    return STATUS_OK, k
