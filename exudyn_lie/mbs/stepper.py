"""The one Munthe-Kaas stepper (eq. MK1), compiled: every path of the package runs it.

``mk_steps`` advances the state ``(R, r, V)`` of all bodies, each in its own group
(:mod:`.bodies`), with the tableau ``tab`` (:mod:`.methods`: a :class:`~.methods.Method`; an implicit
one: :class:`~.methods.ImplicitMethod`, the last section below; a partitioned one, velocity Verlet,
is a :class:`~.methods.Method` whose configurations have coefficients of their own, ``Aq, bq``
in place of ``A, b`` in the first and third lines below).  Its users: the
fixed-step loop of :class:`~exudyn_lie.mbs.Simulator` (``Advance`` / ``Run``), the
accelerations at a state (``nsteps = 0``), and the bridge's output chunks
(:class:`~exudyn_lie.bridge.fast.OutputChunks`), with or without forces evaluated in
Python.  (The Python reference stepper ``tests/reference_mk.py`` is kept as a test oracle.)

One step, per body::

    Psi_j = h sum_{l<j} a_jl k_l,   g_j = g exp(Psi_j),   V_j = V + h sum_{l<j} a_jl Vdot_l
    Vdot_j = F(t + c_j h, g_j, V_j)                                    (index-1 rhs)
    k_j = dexp^-1_{-Psi_j} V_j
    g+ = g exp(h sum_j b_j k_j),   V+ = V + h sum_j b_j Vdot_j

Only the stages in ``tab.stages`` are evaluated: a stage whose weight and all later
coefficients are zero cannot change the step (e.g. DOPRI5's 7th, FSAL stage; its
``k_j``, ``Vdot_j`` stay zero and the weighted sums are unchanged bit for bit).

Three seams (the third, the step observers after each accepted step, is :mod:`.step_observers`):

* the **right-hand side outside the compiled code** (:mod:`.external`): when
  ``sd.hasQext`` the stage calls the registered Python evaluator once
  (:func:`~.external.call`), which fills the extra generalised forces ``wk.Qext`` at the stage state
  (``EXTERNAL_FORCES``), or the whole ``Vdot`` (``EXTERNAL_RATES``: a problem evaluated outside the
  kernel, such as the bridge's evaluation of a whole model); no Python stage loop.  An exception there
  ends the call with ``STATUS_EXTERNAL``.
* the **step controller** (``ctl``): a namedtuple whose *type* is the controller.
  ``Control`` with ``CONTROL_FIXED`` (:func:`fixed_step_control`): fixed steps, every step
  accepted.  ``adaptive.AdaptiveControl``: adaptive steps (:mod:`.adaptive`, docs/ADAPTIVE.md):
  error estimate from ``tab``'s embedded weights, PI control, rejections undone from the
  step's start, FSAL, dense output at the output times.  ``mk_steps`` is compiled once per
  controller type, and the seam functions below (:func:`is_adaptive`, :func:`controller_start`,
  :func:`step_begin`, :func:`stage_needed`, :func:`stage_evaluated`, :func:`control_step`,
  :func:`step_accepted`) are numba overloads chosen by that type at compile time: the
  fixed-step specialisation holds none of the adaptive controller's code (same speed and
  compile time as a loop of its own), and a controller is its tuple type plus its overloads
  of these functions (the adaptive one registers them in :mod:`.adaptive`).

**The loop** (:func:`mk_steps`).

**Fixed steps** (``ctl`` a :class:`Control`): ``nsteps`` steps of size ``h`` from ``t0 + k0 h``
(step ``n`` at ``t0 + (k0 + n) h``: :mod:`.clock`).
``nsteps = 0`` evaluates the equations of motion once at the current state (the
first stage of a step): accelerations in ``wk.Vd[0]``, multipliers in ``wk.lam``.
(One call site of the inlined right-hand side serves both uses: a second one would
double the compile time.)
Outputs: with ``every > 0`` the state after every ``every``-th step goes to row
``o = (n + 1) / every - 1`` (:func:`record_output`); if ``Vdo`` has rows, the accelerations
and multipliers at that state go to ``Vdo[o], lamo[o]``.  They are the first stage of
the following step (explicit RK: stage 1 is evaluated at the step's initial state),
so recording them costs one extra evaluation per call, after the last step.  A failure
in that evaluation leaves ``Vdo[o, 0, 0]`` NaN.

**Adaptive steps** (``ctl`` an ``adaptive.AdaptiveControl``, ``tab`` an
``adaptive.AdaptiveMethod``): from ``ctl.fs[FS_T]`` with the next step ``ctl.fs[FS_H]``
until ``ctl.fs[FS_TEND]``, or until every output time ``ctl.tout`` is written to
``Ro, ro, Vo, Po`` (dense output); ``t0, k0, h, nsteps, every`` are not used and ``Vdo,
lamo`` have no rows.  Returns the number of outputs written (:mod:`.adaptive`).

**Implicit methods** (``tab`` an ``ImplicitMethod`` or ``adaptive.AdaptiveImplicitMethod``, carrying
Newton arrays): stage 1 as above, each later stage solved by :func:`implicit_stage`
(:mod:`.implicit`), the rest of the loop unchanged.
"""
from collections import namedtuple

import numpy as np
from numba import njit, types
from numba.extending import overload

from .bodies import body_dexpinv_stage, exp_compose
from .codes import (EXTERNAL_RATES, INFO_BODY, STAGE_ARG_MAX2, STATUS_BLOWUP, STATUS_NONFINITE,
                    STATUS_OK, STATUS_STAGE_ARG, STATUS_STIFF)
from .diagnostics import stage_rate, stage_rates
from .methods import config_coefficients
from .external_calls import external_forces, external_rates
from .rotation_parameters import record_tracked
from .index1 import rhs
from .projection import is_stabilized, project_state_if
from .row_drives import update_row_drives
from .step_observers import after_accepted_step

# Step controller: kind, parameters, state (CONTROL_FIXED: none)
Control = namedtuple("Control", ["kind", "par", "state"])
CONTROL_FIXED = 0


def fixed_step_control():
    """The controller of fixed steps; ``par = [radius, nb]``: with ``radius > 0``, a step that shows a
    mode beyond it (``h |lambda|`` of the first ``nb`` bodies, :func:`fixed_step_watch`) is undone with
    STATUS_STIFF (mbs/stiffness.watch_stages)."""
    return Control(kind=CONTROL_FIXED, par=np.zeros(2), state=np.zeros(0))


KINK_MIN = 0.1       # the last stage alone shows h rho beyond this fraction of the radius ...
KINK_RATIO = 2.0     # ... and this multiple of every earlier stage's rate: the step's end is checked
KINK_EPS = 1e-3      # the end's rate is differenced over this fraction of the last stage's motion


@njit(cache=True, inline="always", _nrt=False)
def fixed_step_watch(sd, wk, tab, ctl, t, h, R, r, V):
    """STATUS_STIFF for a fixed step from ``t`` to the end state ``(R, r, V)`` that met a mode beyond
    the stability radius ``ctl.par[0]`` (of the first ``ctl.par[1]`` bodies): by its stages
    (:func:`~.diagnostics.stage_rates`), or, where the last stage alone shows a rate (a contact that
    it barely touches), by the rate at the end state, differenced along the last stage's motion
    (``KINK_EPS`` of it; two more evaluations).  RK4 onto a floor load of 1e8 N/m at h omega = 10:
    the stages showed h rho = 1.9 and the step kicked the ball with h/6 of the last stage's force,
    0.68 m/s where the contact had taken 0.06 m/s; the next step was flagged, too late where an
    output followed at once (half the rebound lost).  The end and the last stage share the
    position in that step (RK4 with a constant force before the contact), so a secant between
    them sees the damping only."""
    radius = ctl.par[0]
    nb = int(ctl.par[1])
    Aq = config_coefficients(tab)[0]
    rho, last, before = stage_rates(tab.A, Aq, h, tab.stages, wk.K, wk.Vd, nb)
    if h * rho > radius:
        return STATUS_STIFF
    if tab.stages.shape[0] > 2 and h * last > KINK_MIN * radius and last > KINK_RATIO * before:
        j = tab.stages[tab.stages.shape[0] - 1]
        copy_state(R, r, V, wk.Rs, wk.rs, wk.Vs)
        st = stage_rhs_at(sd, wk, t + h, wk.Ve[0])
        if st == STATUS_OK:
            st = method_stage_state(sd, wk, tab, j, KINK_EPS * h, R, r, V)      # the end moved on
        if st == STATUS_OK:
            st = stage_rhs_at(sd, wk, t + h, wk.Ve[1])
        if st != STATUS_OK:
            return st
        if h * stage_rate(Aq[j], tab.A[j], j, KINK_EPS * h, wk.K, wk.Vd, wk.Ve[0], wk.Ve[1], nb) > radius:
            return STATUS_STIFF
    return STATUS_OK


@njit(cache=True, _nrt=False)
def stage_rhs_at(sd, wk, t, Vdot):
    """:func:`stage_rhs` as a call, for its call sites outside the stage loop: :func:`fixed_step_watch`,
    and through its address (:mod:`.rhs_address`: compiled once, not again inside each caller) the
    implicit stages' Newton iteration and the adaptive steps' dense-only stages."""
    return stage_rhs_llvm_inlined(sd, wk, t, Vdot)


# --------------------------------------------------------------------------- the stages
@njit(cache=True, inline="always", _nrt=False)
def stage_state(gid, A, Aq, j, h, R, r, V, K, Vd, Psi, Rs, rs, Vs, ER, Er):
    """Stage configuration ``g exp(Psi_j)`` and velocity ``V + h sum a_jl Vdot_l`` (eq. MK1); the
    configuration with its own coefficients ``Aq`` (``A`` itself but for a partitioned method, whose
    diagonal ``aq_jj`` makes ``Psi_j = h aq_jj V_j``: integrators/partitioned.py).

    Returns -1, or the first body whose stage argument has ``|rotation part of Psi_j|``
    beyond STAGE_ARG_MAX (dexpinv_{-Psi_j} of the stage is singular at 2 pi); then the
    stage is not evaluated."""
    for i in range(gid.shape[0]):
        Pi = Psi[i]
        for k in range(6):
            ps = 0.0
            vs = V[i, k]
            for l in range(j):
                ps += Aq[j, l] * K[l, i, k]
                vs += h * A[j, l] * Vd[l, i, k]
            if Aq[j, j] != 0.0:          # (a partitioned method only: an implicit stage is not formed here)
                ps += Aq[j, j] * vs
            Pi[k] = h * ps
            Vs[i, k] = vs
        if j == 0:
            for a in range(3):
                rs[i, a] = r[i, a]
                for b in range(3):
                    Rs[i, a, b] = R[i, a, b]
        else:
            if Pi[0] * Pi[0] + Pi[1] * Pi[1] + Pi[2] * Pi[2] > STAGE_ARG_MAX2:   # (NaN: state_is_finite)
                return i
            exp_compose(gid[i], R[i], r[i], Pi, Rs[i], rs[i], ER, Er)
    return -1


@njit(cache=True, forceinline=True, _nrt=False)
def stage_k(gid, j, Psi, Vs, K, tmp6):
    """``k_j = dexp^-1_{-Psi_j} V_j`` (eq. MK1), per body in its own group.  (Compiled on its
    own, with the group dispatch inlined: one call per stage; inlining it into mk_steps
    as well cost 2.5 s of mk_steps' compile time and no speed.)"""
    for i in range(gid.shape[0]):
        Kj = K[j, i]
        if j == 0:
            for k in range(6):
                Kj[k] = Vs[i, k]
        else:
            for k in range(6):
                tmp6[k] = -Psi[i, k]
            body_dexpinv_stage(gid[i], tmp6, Vs[i], Kj)


@njit(cache=True, inline="always", _nrt=False)
def finish(gid, stages, bq, b, h, R, r, V, K, Vd, Psi, Rn, C, rn, Er):
    """``g <- g exp(h sum bq_j k_j)``, ``V <- V + h sum b_j Vdot_j`` over the evaluated
    stages (``bq`` is ``b`` but for a partitioned method); re-orthonormalise R with one Newton step ``R <- R (3 I - R^T R) / 2``
    (changes R by O(eps) only)."""
    ns = stages.shape[0]
    for i in range(gid.shape[0]):
        Phi = Psi[i]
        for k in range(6):
            ph = 0.0
            vv = 0.0
            for jj in range(ns):
                j = stages[jj]
                ph += bq[j] * K[j, i, k]
                vv += b[j] * Vd[j, i, k]
            Phi[k] = h * ph
            V[i, k] += h * vv
        exp_compose(gid[i], R[i], r[i], Phi, Rn, rn, C, Er)
        # Newton orthonormalisation: C = (3 I - Rn^T Rn) / 2
        for a in range(3):
            for c in range(3):
                g = 0.0
                for k in range(3):
                    g += Rn[k, a] * Rn[k, c]
                C[a, c] = -0.5 * g
            C[a, a] += 1.5
        for a in range(3):
            r[i, a] = rn[a]
            for c in range(3):
                R[i, a, c] = Rn[a, 0] * C[0, c] + Rn[a, 1] * C[1, c] + Rn[a, 2] * C[2, c]


# the stages on the scene tuples (inlined into mk_steps; callable from Python, e.g. by the
# stress suite's collection of group-map arguments)
@njit(cache=True, inline="always", _nrt=False)
def mk_stage_state(sd, wk, A, j, h, R, r, V):
    """:func:`stage_state` on the scene tuples; a stage argument out of the domain of
    dexpinv gives STATUS_STAGE_ARG with the body in ``wk.failInfo[INFO_BODY]``."""
    return _stage_state_status(wk, stage_state(sd.gid, A, A, j, h, R, r, V, wk.K, wk.Vd, wk.Psi, wk.Rs, wk.rs, wk.Vs,
                                               wk.m3[0], wk.v3[0]))


@njit(cache=True, inline="always", _nrt=False)
def method_stage_state(sd, wk, tab, j, h, R, r, V):
    """:func:`mk_stage_state` with the configuration's coefficients of ``tab`` (:func:`config_coefficients`)."""
    Aq = config_coefficients(tab)[0]
    return _stage_state_status(wk, stage_state(sd.gid, tab.A, Aq, j, h, R, r, V, wk.K, wk.Vd, wk.Psi, wk.Rs, wk.rs,
                                               wk.Vs, wk.m3[0], wk.v3[0]))


@njit(cache=True, inline="always", _nrt=False)
def _stage_state_status(wk, bad):
    if bad >= 0:
        wk.failInfo[INFO_BODY] = bad
        return STATUS_STAGE_ARG
    return STATUS_OK


@njit(cache=True, inline="always", _nrt=False)
def mk_stage_k(sd, wk, j):
    stage_k(sd.gid, j, wk.Psi, wk.Vs, wk.K, wk.tmp6)


@njit(cache=True, inline="always", _nrt=False)
def mk_finish(sd, wk, tab, h, R, r, V):
    finish(sd.gid, tab.stages, config_coefficients(tab)[1], tab.b, h, R, r, V, wk.K, wk.Vd, wk.Psi, wk.m3[1],
           wk.m3[0], wk.v3[1], wk.v3[0])


@njit(cache=True, inline="always", _nrt=False)
def stage_rhs(sd, wk, t, Vdot):
    """``Vdot_j = F(t, g_j, V_j)`` at the stage state ``wk.Rs, wk.rs, wk.Vs``: the
    external part first (if the scene has one: Python forces; the rows' moving offsets at
    ``t``, :mod:`.row_drives`), then the compiled index-1 rhs."""
    st = update_row_drives(wk.drive, t)      # no code in a lean scene (wk.drive None)
    if st != STATUS_OK:
        return st
    # A run-time branch, compiled in every scene (about 0.4 s of a first run; the probes inside
    # compile only when read), on purpose: compiled out (presence.guarded), the heavy top's step
    # became 0.2-0.3 us slower and the double pendulum's 0.3-0.4 us (1.13-1.35 -> 1.45-1.62 us
    # and 2.56-2.62 -> 2.94-3.09 us: the minimum over many short Simulator.Advance runs, three
    # runs interleaved, states bit-identical): LLVM lays out the stage loop differently
    # without the call.
    if sd.hasQext:
        if sd.hasQext == EXTERNAL_RATES:
            return external_rates(wk.ext[0], t, wk.Qext, Vdot, wk.ext)
        st = external_forces(wk.ext[0], sd.gid, t, wk.Rs, wk.rs, wk.Vs, wk.Vw, wk.Qext, wk.ext, wk.probe)
        if st != STATUS_OK:
            return st
    return rhs(sd, wk, t, wk.Rs, wk.rs, wk.Vs, wk.Qext, Vdot)


@njit(cache=True, _nrt=False)
def stage_rhs_llvm_inlined(sd, wk, t, Vdot):
    """:func:`stage_rhs` typed and lowered by numba once per kind of scene (its SceneData and Work
    types), and inlined by LLVM where it is called: into the stage loop of each explicit kind of
    time loop, and into :func:`stage_rhs_at`.  LLVM ``alwaysinline`` by name (``exudyn_lie/_noinline.py``),
    not numba's ``forceinline``, which the functions compiled on its behalf would inherit (numba's
    ``inherit_if_not_set``): the right-hand side's callees stay what they were, and compile faster than
    with ``forceinline`` (docs/BENCH.md).  Inlined by numba instead (``stage_rhs``
    is ``inline="always"``), every kind of time loop typed and lowered the whole right-hand side
    again (docs/BENCH.md); LLVM's inlining gives the same states to the bit."""
    return stage_rhs(sd, wk, t, Vdot)


# --------------------------------------------------------------------------- the step controller seam
# Python stubs: the implementations are numba overloads, one per controller type (the
# fixed steps' below, the adaptive controller's in mbs/adaptive.py).  The fixed ones are
# never reached (mk_steps branches on the compile-time constant is_adaptive) but type the
# dead branch.
ACT_RETRY, ACT_ACCEPT, ACT_STOP = 0, 1, 2      # control_step's verdict on an attempted step


def carries_newton(tab):
    """At compile time: the method tuple ``tab`` (a numba type) holds Newton arrays (field ``newton``):
    an implicit method, fixed or adaptive (mbs/implicit.py)."""
    return isinstance(tab, types.BaseNamedTuple) and "newton" in tab.instance_class._fields


def controller_is(ctl, cls):
    """At compile time: ``ctl`` (a numba type) is the namedtuple type ``cls``."""
    return isinstance(ctl, types.BaseNamedTuple) and ctl.instance_class is cls


def is_adaptive(ctl):
    """True if the controller varies the step (a compile-time constant)."""


def is_implicit(tab):
    """True if the stages after the first are implicit (a compile-time constant: mbs/implicit.py)."""


def evaluate_stage(sd, wk, tab, t, Vdot):
    """``stage_rhs`` as the method's specialisation of ``mk_steps`` calls it: inlined by LLVM for an
    explicit method (:func:`stage_rhs_llvm_inlined`), through a call for an implicit one
    (:func:`stage_rhs_at`, which the Newton iteration calls through its address, :mod:`.rhs_address`:
    each copy of the right-hand side in a compiled function costs seconds of compile time)."""


def implicit_stage(sd, wk, tab, j, h, t, R, r, V):
    """Solve implicit stage ``j`` of the step ``(t, h)`` from ``(R, r, V)``: ``wk.K[j]``, ``wk.Vd[j]``;
    a status (mbs/implicit.py)."""


def controller_start(sd, wk, tab, ctl, R, r, V, Ro, ro, Vo, Po):
    """Outputs due before the first step: ``(status, outputs written)``."""


def step_begin(wk, tab, ctl, R, r, V, n):
    """``(go on, t, h)`` of the next attempted step (``n``: outputs written so far)."""


def stage_needed(ctl, j):
    """False if stage ``j`` is already evaluated (stage 1 reused: FSAL, or after a rejection)."""


def stage_evaluated(ctl, j, st):
    """Bookkeeping after the evaluation of stage ``j`` with status ``st``."""


def control_step(sd, wk, tab, ctl, R, r, V, h, ok, st, t):
    """The verdict on the attempted step of size ``h`` from ``t`` (``ok``: every stage
    evaluated; ``st``: the state check): ``(ACT_*, status)``; a retried or stopped step is
    undone."""


def step_accepted(sd, wk, tab, ctl, R, r, V, t, h, Ro, ro, Vo, Po, n):
    """After an accepted step: the controller's state and the outputs it covers,
    ``(status, outputs written)``."""


@overload(is_adaptive, inline="always")
def _fixed_is_adaptive(ctl):
    if controller_is(ctl, Control):
        return lambda ctl: False


@overload(is_implicit, inline="always")
def _explicit_is_implicit(tab):
    if not carries_newton(tab):
        return lambda tab: False


@overload(evaluate_stage, inline="always")
def _explicit_evaluate_stage(sd, wk, tab, t, Vdot):
    if not carries_newton(tab):
        return lambda sd, wk, tab, t, Vdot: stage_rhs_llvm_inlined(sd, wk, t, Vdot)


@overload(implicit_stage, inline="always")
def _explicit_implicit_stage(sd, wk, tab, j, h, t, R, r, V):
    if not carries_newton(tab):
        return lambda sd, wk, tab, j, h, t, R, r, V: STATUS_OK


@overload(controller_start, inline="always")
def _fixed_controller_start(sd, wk, tab, ctl, R, r, V, Ro, ro, Vo, Po):
    if controller_is(ctl, Control):
        return lambda sd, wk, tab, ctl, R, r, V, Ro, ro, Vo, Po: (STATUS_OK, 0)


@overload(step_begin, inline="always")
def _fixed_step_begin(wk, tab, ctl, R, r, V, n):
    if controller_is(ctl, Control):
        return lambda wk, tab, ctl, R, r, V, n: (False, 0.0, 0.0)


@overload(stage_needed, inline="always")
def _fixed_stage_needed(ctl, j):
    if controller_is(ctl, Control):
        return lambda ctl, j: True


@overload(stage_evaluated, inline="always")
def _fixed_stage_evaluated(ctl, j, st):
    if controller_is(ctl, Control):
        return lambda ctl, j, st: None


@overload(control_step, inline="always")
def _fixed_control_step(sd, wk, tab, ctl, R, r, V, h, ok, st, t):
    if controller_is(ctl, Control):
        return lambda sd, wk, tab, ctl, R, r, V, h, ok, st, t: (ACT_ACCEPT, st)


@overload(step_accepted, inline="always")
def _fixed_step_accepted(sd, wk, tab, ctl, R, r, V, t, h, Ro, ro, Vo, Po, n):
    if controller_is(ctl, Control):
        return lambda sd, wk, tab, ctl, R, r, V, t, h, Ro, ro, Vo, Po, n: (STATUS_OK, n)


# --------------------------------------------------------------------------- state helpers
@njit(cache=True, inline="always", _nrt=False)
def state_is_finite(gid, R, r, V, vmax):
    """0 if finite and bounded, STATUS_NONFINITE / STATUS_BLOWUP otherwise."""
    for i in range(gid.shape[0]):
        for k in range(6):
            x = V[i, k]
            if not np.isfinite(x):
                return STATUS_NONFINITE
            if abs(x) > vmax:
                return STATUS_BLOWUP
        for k in range(3):
            if not np.isfinite(r[i, k]):
                return STATUS_NONFINITE
    return STATUS_OK


@njit(cache=True, inline="always", _nrt=False)
def copy_state(R, r, V, Rto, rto, Vto):
    for i in range(R.shape[0]):
        for a in range(3):
            rto[i, a] = r[i, a]
            for c in range(3):
                Rto[i, a, c] = R[i, a, c]
        for k in range(6):
            Vto[i, k] = V[i, k]


@njit(cache=True, inline="always", _nrt=False)
def record_accelerations(wk, Vdo, lamo):
    """An output row's accelerations and multipliers: the first stage of the next step."""
    for i in range(Vdo.shape[0]):
        for k in range(6):
            Vdo[i, k] = wk.Vd[0, i, k]
    for k in range(lamo.shape[0]):
        lamo[k] = wk.lam[k]


@njit(cache=True, inline="always", _nrt=False)
def record_output(wk, R, r, V, Ro, ro, Vo, Po, o):
    """Output row ``o``: the state and, if ``Po`` has rows, the tracked angles and node
    rotation parameters (rotation_parameters.record_tracked)."""
    copy_state(R, r, V, Ro[o], ro[o], Vo[o])
    if Po.shape[0] > 0:
        record_tracked(wk.track.trackCodes, wk.path.bodyAngles, wk.path.bodyParameters, Po[o])


@njit(cache=True, inline="always", _nrt=False)
def project_step_end(sd, wk, t, R, r, V):
    """The projection after a fixed step (``sd.stabilization``) with the rows' moving offsets
    at the step's end ``t``."""
    st = update_row_drives(wk.drive, t)
    if st == STATUS_OK:
        st = project_state_if(sd.stabilization, sd, wk, sd.stabilization, R, r, V)
    return st


# --------------------------------------------------------------------------- the loop
@njit(cache=True, _nrt=False)
def mk_steps(sd, wk, tab, ctl, t0, k0, h, nsteps, R, r, V, vmax, every, Ro, ro, Vo, Po, Vdo, lamo):
    """Advance MK steps in place.  Returns (status, steps done / outputs written); on a
    failure (R, r, V) hold the last accepted step (the rejected one is undone).  Its arguments and
    outputs, fixed and adaptive steps: the module docstring's "The loop"."""
    c = tab.c
    stages = tab.stages
    ns = stages.shape[0]
    adaptive = is_adaptive(ctl)
    implicit = is_implicit(tab)
    acc = Vdo.shape[0] > 0
    pending = -1                         # output row whose accelerations are still due
    n = 0
    st = STATUS_OK
    if adaptive:
        st, n = controller_start(sd, wk, tab, ctl, R, r, V, Ro, ro, Vo, Po)
        if st != STATUS_OK:
            return st, n
    while True:
        if adaptive:
            go, t, hs = step_begin(wk, tab, ctl, R, r, V, n)
            if not go:
                return STATUS_OK, n
            evalOnly = False
        else:
            t = t0 + (k0 + n) * h       # one product from the origin (mbs/clock.py)
            hs = h
            evalOnly = n >= nsteps
            if evalOnly and nsteps > 0 and pending < 0:
                return STATUS_OK, nsteps
        ok = True
        for jj in range(ns):
            j = stages[jj]
            solved = implicit and jj > 0     # an implicit stage (mbs/implicit.py; the first is explicit)
            if solved:
                st = implicit_stage(sd, wk, tab, j, hs, t, R, r, V)
            else:
                st = method_stage_state(sd, wk, tab, j, hs, R, r, V)
            if st != STATUS_OK:          # only for j >= 1: any pending output is written
                if adaptive:             # a rejection with the largest decrease
                    ok = False
                    break
                return st, n
            if solved:
                continue
            if stage_needed(ctl, j):
                st = evaluate_stage(sd, wk, tab, t + c[j] * hs, wk.Vd[j])
                stage_evaluated(ctl, j, st)
                if st != STATUS_OK:
                    if pending >= 0:
                        Vdo[pending, 0, 0] = np.nan
                    return st, n
            if pending >= 0:
                record_accelerations(wk, Vdo[pending], lamo[pending])
                pending = -1
            if evalOnly:
                return STATUS_OK, nsteps
            mk_stage_k(sd, wk, j)
        if not adaptive:                 # (the adaptive controller keeps the step's start itself)
            copy_state(R, r, V, wk.Rb, wk.rb, wk.Vb)
        if ok:
            mk_finish(sd, wk, tab, hs, R, r, V)
            st = state_is_finite(sd.gid, R, r, V, vmax)
        if adaptive:
            act, st = control_step(sd, wk, tab, ctl, R, r, V, hs, ok, st, t)
            if act == ACT_RETRY:
                continue
            if act == ACT_STOP:
                return st, n
        else:
            if st == STATUS_OK and ctl.par[0] > 0.0:
                st = fixed_step_watch(sd, wk, tab, ctl, t, hs, R, r, V)
            if st != STATUS_OK:
                copy_state(wk.Rb, wk.rb, wk.Vb, R, r, V)
                return st, n
            if is_stabilized(sd.stabilization):
                st = project_step_end(sd, wk, t + hs, R, r, V)
                if st != STATUS_OK:
                    copy_state(wk.Rb, wk.rb, wk.Vb, R, r, V)
                    return st, n
        after_accepted_step(sd, wk, R, r, V)
        if adaptive:
            st, n = step_accepted(sd, wk, tab, ctl, R, r, V, t, hs, Ro, ro, Vo, Po, n)
            if st != STATUS_OK:
                return st, n
            continue
        n += 1
        if every > 0 and n % every == 0:
            o = n // every - 1
            record_output(wk, R, r, V, Ro, ro, Vo, Po, o)
            if acc:
                pending = o
