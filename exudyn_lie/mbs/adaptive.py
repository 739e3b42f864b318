"""The adaptive step controller of the one stepper, compiled.

``AdaptiveControl`` is a controller of :func:`~.stepper.mk_steps`'s seam: this module registers
its overloads of the seam functions (``stepper.step_begin``, ``control_step``, ...), so that
``mk_steps(sd, wk, adaptive_method(tab), AdaptiveControl(...), ...)`` runs adaptive steps
with the same stage loop (``mk_stage_state``, ``stage_rhs``, ``mk_stage_k``, ``mk_finish``;
eq. MK1) as the fixed steps, driven by the PI controller, HINIT and the Lie-algebra error norm
of :mod:`~exudyn_lie.integrators.control`.  The fixed steps' specialisation of ``mk_steps``
holds none of this code (the overloads are chosen by the controller's type at compile time),
so the paper's fixed-step runs stay bit-identical; ``tests/reference_mk_adaptive.py`` is its
oracle.

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
``fs`` (``FS_T`` time, ``FS_H`` next step, ``FS_TPREV``/``FS_HPREV`` the last accepted step,
``FS_TEND`` the end time of the call)
and the int array ``ist`` (``IS_HAVE0``: stage 1 available, ``IS_EXTRA``: extra stages of the
last step evaluated, ``IS_VALID``: the last step's dense data valid).  The last accepted
step's start state stays in ``R0, r0, V0`` and its stages in ``wk.K, wk.Vd``.
"""
from collections import namedtuple

import numpy as np
from numba import njit
from numba.extending import overload

from ..integrators import control as C
from .bodies import exp_compose
from .codes import STATUS_OK, STATUS_STEP_MIN
from .projection import (CT_N_PROJ, CT_POS, enforce_constraint_tolerance, is_stabilized, project_error_estimate,
                         project_state_if)
from .row_drives import update_row_drives
from .rotation_parameters import tracked_at
from . import stepper
from .methods import needed_stages
from .rhs_address import rhs_at
from .stepper import ACT_ACCEPT, ACT_RETRY, ACT_STOP, controller_is, copy_state, mk_stage_k, mk_stage_state

# A tableau as the adaptive loop uses it: the stage matrix and nodes extended by the dense
# extra stages, b (s), the stages of a step (b or bhat needs them), e = b - bhat, the dense
# polynomial coefficients (s + m, degree), the number s of stages of a step, FSAL flag.
AdaptiveMethod = namedtuple("AdaptiveMethod", ["A", "b", "c", "stages", "e", "P", "s", "fsal"])
# ... of a diagonally implicit pair, with its Newton iteration's arrays (mbs/implicit.py)
AdaptiveImplicitMethod = namedtuple("AdaptiveImplicitMethod", AdaptiveMethod._fields + ("gamma", "newton"))

# The controller's state (one tuple: its type selects the adaptive code of stepper.mk_steps):
# the controller's parameters and counters (integrators/control.py ``par``, ``S``), the
# tolerances, the constraint tolerance (projection.CT_*), ``fs`` / ``ist`` (below), the
# start of the last step ``R0, r0, V0``, scratch ``dPhi, dV, w``, the output times ``tout``.
AdaptiveControl = namedtuple("AdaptiveControl", ["par", "S", "tol", "ctol", "fs", "ist", "R0", "r0", "V0", "dPhi",
                                                 "dV", "w", "tout"])

FS_T, FS_H, FS_TPREV, FS_HPREV, FS_TEND = range(5)
FS_SIZE = 5
IS_HAVE0, IS_EXTRA, IS_VALID = range(3)
HAVE0_NONE, HAVE0_STAGE1, HAVE0_FSAL = 0, 1, 2


def adaptive_method(tab, gid=None):
    """The :class:`AdaptiveMethod` of an embedded pair (a tableau with ``b_hat``); an
    :class:`AdaptiveImplicitMethod` for a diagonally implicit one, with the Newton arrays for the
    bodies of group ids ``gid``."""
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
    am = AdaptiveMethod(A=Aext, b=b, c=cext, stages=stages, e=b - bh, P=np.ascontiguousarray(P), s=s,
                        fsal=bool(tab.fsal))
    if tab.implicit:
        from .implicit import newton_arrays
        return AdaptiveImplicitMethod(*am, gamma=float(tab.gamma), newton=newton_arrays(gid))
    return am


@njit(cache=True, _nrt=False)
def dense_state(sd, wk, P, theta, h, R0, r0, V0, Ro, ro, Vo, w):
    """The dense output at ``t + theta h`` of the last accepted step (module docstring):
    ``Ro = g0 exp(h sum_j b_j(theta) k_j)``, ``Vo = V0 + h sum_j b_j(theta) Vdot_j`` (``P``: the
    method's dense polynomials, ``AdaptiveMethod.P``)."""
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
def extra_stages(sd, wk, A, c, s, t, h, R0, r0, V0, S):
    """The dense-only stages s..s+m-1 of the last accepted step (from its start state), through the one
    compiled copy of the stage right-hand side outside the stage loop (``stage_rhs_at`` through its
    address, mbs/rhs_address.py, as the implicit stages' Newton iteration calls it): an inlined copy here
    would be a second right-hand side in the adaptive kind's first compile (docs/BENCH.md), for stages
    evaluated only for outputs inside a step.  ``A``, ``c``, ``s``: the method's (``AdaptiveMethod``) as arrays, not the method tuple: these
    functions, the dense output's, are then compiled once for explicit and implicit pairs alike."""
    for j in range(s, A.shape[0]):
        st = mk_stage_state(sd, wk, A, j, h, R0, r0, V0)
        if st != STATUS_OK:
            return st
        st = rhs_at(sd, wk, t + c[j] * h, wk.Vd[j])
        S[C.S_N_RHS] += 1.0
        if st != STATUS_OK:
            return st
        mk_stage_k(sd, wk, j)
    return STATUS_OK


@njit(cache=True, _nrt=False)
def serve_outputs(sd, wk, A, c, P, s, ctol, fs, ist, R0, r0, V0, R, r, V, S, tout, k, Ro, ro, Vo, Po, w):
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
                if A.shape[0] > s:
                    st = extra_stages(sd, wk, A, c, s, tp, hp, R0, r0, V0, S)
                    if st != STATUS_OK:
                        return st, k
                ist[IS_EXTRA] = 1
            dense_state(sd, wk, P, (tout[k] - tp) / hp, hp, R0, r0, V0, Ro[k], ro[k], Vo[k], w)
            if ctol[CT_POS] > 0.0:                  # as Simbody's projectInterpolatedStates
                st = update_row_drives(wk.drive, tout[k])     # the rows' moving offsets at the output time
                if st == STATUS_OK:
                    st, _ = enforce_constraint_tolerance(sd, wk, ctol, Ro[k], ro[k], Vo[k])
                if st != STATUS_OK:
                    return st, k
        if Po.shape[0] > k:
            tracked_at(wk.track.trackCodes, wk.track.angleFrames, wk.path.bodyAngles, wk.path.bodyParameters, Ro[k],
                       Po[k])
        k += 1
    return STATUS_OK, k


# --------------------------------------------------------------------------- the controller
# (inlined into mk_steps' adaptive specialisation: a compiled function of its own that receives
# the SceneData / Work tuples costs compile time steeply, measured 77 -> 102 s cold)
@njit(cache=True, inline="always", _nrt=False)
def _last_step(t, h, tEnd):
    """The step from ``t`` is the last one (no sliver step before the end time)."""
    return t + h >= tEnd - 4.0 * 2.220446049250313e-16 * abs(tEnd)


@njit(cache=True, inline="always", _nrt=False)
def adaptive_start(sd, wk, am, ctl, R, r, V, Ro, ro, Vo, Po):
    """The outputs at or before the current time (a chunk served by the previous call's step)."""
    return serve_outputs(sd, wk, am.A, am.c, am.P, am.s, ctl.ctol, ctl.fs, ctl.ist, ctl.R0, ctl.r0, ctl.V0, R, r, V,
                         ctl.S, ctl.tout, 0, Ro, ro, Vo, Po, ctl.w)


@njit(cache=True, inline="always", _nrt=False)
def adaptive_step_begin(wk, am, ctl, R, r, V, k):
    """``(go on, t, h)``: stop at the end time or when every output is written; else the
    FSAL stage becomes stage 1, the start state is kept in ``R0, r0, V0`` (for a rejection
    and the dense output) and the last step is clipped to the end time."""
    fs, ist = ctl.fs, ctl.ist
    tEnd = fs[FS_TEND]
    nt = ctl.tout.shape[0]
    if not (fs[FS_T] < tEnd and not (nt > 0 and k >= nt)):
        return False, 0.0, 0.0
    t = fs[FS_T]
    h = fs[FS_H]
    htry = tEnd - t if _last_step(t, h, tEnd) else h
    if ist[IS_HAVE0] == HAVE0_FSAL:             # the previous step's last stage is stage 1
        s = am.s
        for i in range(V.shape[0]):
            for q in range(6):
                wk.Vd[0, i, q] = wk.Vd[s - 1, i, q]
        ist[IS_HAVE0] = HAVE0_STAGE1
    copy_state(R, r, V, ctl.R0, ctl.r0, ctl.V0)
    ist[IS_VALID] = 0                           # K, Vd and R0 now belong to this attempt
    return True, t, htry


@njit(cache=True, inline="always", _nrt=False)
def adaptive_control(sd, wk, am, ctl, R, r, V, htry, ok, st, t):
    """Error estimate (module docstring; projected with a constraint tolerance), the PI
    controller's verdict, a rejection undone from ``R0, r0, V0`` (``STATUS_STEP_MIN`` below
    the minimum step), and for an accepted step the projection (stabilisation, or the
    constraint tolerance) and whether its last stage serves the next step (FSAL)."""
    s = am.s
    par, S, tol, ctol, fs, ist = ctl.par, ctl.S, ctl.tol, ctl.ctol, ctl.fs, ctl.ist
    R0, r0, V0, dPhi, dV = ctl.R0, ctl.r0, ctl.V0, ctl.dPhi, ctl.dV
    err = np.inf                                # a stage argument or a state out of bounds: reject
    if ok and st == STATUS_OK:
        if ctol[CT_POS] > 0.0:                  # drift is the constraint tolerance's business
            C.increment_difference(am.e, htry, wk.K[:s], wk.Vd[:s], dPhi, dV)
            st = project_error_estimate(sd, wk, R, r, V, dPhi, dV)
            if st != STATUS_OK:
                copy_state(R0, r0, V0, R, r, V)
                return ACT_STOP, st
            err = C.weighted_rms(dPhi, dV, r0, r, V0, V, tol)
        else:
            err = C.embedded_error_norm(am.e, htry, wk.K[:s], wk.Vd[:s], r0, r, V0, V, tol, dPhi, dV)
    status = C.control_step(par, S, htry, err)
    if status != C.STATUS_ACCEPT:
        copy_state(R0, r0, V0, R, r, V)         # stage 1 stays valid (same state and time)
        fs[FS_H] = S[C.S_H]
        if status == C.STATUS_H_MIN or S[C.S_H] <= 1e-14 * max(1.0, abs(t)):
            return ACT_STOP, STATUS_STEP_MIN
        return ACT_RETRY, STATUS_OK
    projected = False
    st = STATUS_OK
    if is_stabilized(sd.stabilization) or ctol[CT_POS] > 0.0:
        st = update_row_drives(wk.drive, t + htry)        # the rows' moving offsets at the step's end
    if st == STATUS_OK and is_stabilized(sd.stabilization):
        st = project_state_if(sd.stabilization, sd, wk, sd.stabilization, R, r, V)
        projected = True
    elif st == STATUS_OK and ctol[CT_POS] > 0.0:
        st, projected = enforce_constraint_tolerance(sd, wk, ctol, R, r, V)
        if projected:
            ctol[CT_N_PROJ] += 1.0
    if st != STATUS_OK:
        copy_state(R0, r0, V0, R, r, V)
        return ACT_STOP, st
    # FSAL: the last stage was evaluated at the step's end (not after a projection)
    ist[IS_HAVE0] = HAVE0_FSAL if (am.fsal and not projected) else HAVE0_NONE
    return ACT_ACCEPT, STATUS_OK


@njit(cache=True, inline="always", _nrt=False)
def adaptive_step_accepted(sd, wk, am, ctl, R, r, V, t, htry, Ro, ro, Vo, Po, k):
    """The accepted step ``(t, t + htry]`` becomes the last step (its dense data valid) and
    serves the outputs inside it."""
    fs, ist = ctl.fs, ctl.ist
    tEnd = fs[FS_TEND]
    last = _last_step(t, fs[FS_H], tEnd)
    fs[FS_TPREV] = t
    fs[FS_HPREV] = htry
    fs[FS_T] = tEnd if last else t + htry
    fs[FS_H] = ctl.S[C.S_H]
    ist[IS_VALID] = 1
    ist[IS_EXTRA] = 0
    return serve_outputs(sd, wk, am.A, am.c, am.P, am.s, ctl.ctol, fs, ist, ctl.R0, ctl.r0, ctl.V0, R, r, V,
                         ctl.S, ctl.tout, k, Ro, ro, Vo, Po, ctl.w)


@njit(cache=True, inline="always", _nrt=False)
def adaptive_stage_evaluated(ctl, j, st):
    ctl.S[C.S_N_RHS] += 1.0
    if j == 0 and st == STATUS_OK:
        ctl.ist[IS_HAVE0] = HAVE0_STAGE1


# the seam functions of stepper.mk_steps for this controller
@overload(stepper.is_adaptive, inline="always")
def _is_adaptive(ctl):
    if controller_is(ctl, AdaptiveControl):
        return lambda ctl: True


@overload(stepper.controller_start, inline="always")
def _controller_start(sd, wk, tab, ctl, R, r, V, Ro, ro, Vo, Po):
    if controller_is(ctl, AdaptiveControl):
        return lambda sd, wk, tab, ctl, R, r, V, Ro, ro, Vo, Po: adaptive_start(sd, wk, tab, ctl, R, r, V, Ro, ro,
                                                                                 Vo, Po)


@overload(stepper.step_begin, inline="always")
def _step_begin(wk, tab, ctl, R, r, V, n):
    if controller_is(ctl, AdaptiveControl):
        return lambda wk, tab, ctl, R, r, V, n: adaptive_step_begin(wk, tab, ctl, R, r, V, n)


@overload(stepper.stage_needed, inline="always")
def _stage_needed(ctl, j):
    if controller_is(ctl, AdaptiveControl):
        return lambda ctl, j: not (j == 0 and ctl.ist[IS_HAVE0] == HAVE0_STAGE1)


@overload(stepper.stage_evaluated, inline="always")
def _stage_evaluated(ctl, j, st):
    if controller_is(ctl, AdaptiveControl):
        return lambda ctl, j, st: adaptive_stage_evaluated(ctl, j, st)


@overload(stepper.control_step, inline="always")
def _control_step(sd, wk, tab, ctl, R, r, V, h, ok, st, t):
    if controller_is(ctl, AdaptiveControl):
        return lambda sd, wk, tab, ctl, R, r, V, h, ok, st, t: adaptive_control(sd, wk, tab, ctl, R, r, V, h, ok, st,
                                                                                 t)


@overload(stepper.step_accepted, inline="always")
def _step_accepted(sd, wk, tab, ctl, R, r, V, t, h, Ro, ro, Vo, Po, n):
    if controller_is(ctl, AdaptiveControl):
        return lambda sd, wk, tab, ctl, R, r, V, t, h, Ro, ro, Vo, Po, n: adaptive_step_accepted(
            sd, wk, tab, ctl, R, r, V, t, h, Ro, ro, Vo, Po, n)
