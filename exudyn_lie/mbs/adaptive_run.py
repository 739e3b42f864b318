"""Adaptive runs of the one stepper: what the adaptive controller (:mod:`.adaptive`) keeps
between calls of ``mk_steps``, and the calls themselves.

:class:`AdaptiveRun` holds the embedded pair, the scaled tolerances, the PI controller's
parameters and state, the step's start (for a rejection and the dense output), the
constraint tolerance and its projection count; :meth:`AdaptiveRun.advance_into` runs
``mk_steps`` with the adaptive controller up to an end time, writing the states at the output
times.  A :class:`~.simulator.Simulator` has one after ``SetAdaptive`` (docs/ADAPTIVE.md).
"""
from __future__ import annotations

import numpy as np

from ..integrators import control as _control
from . import adaptive as _adaptive
from . import implicit as _implicit
from . import kernel
from . import projection as _projection
from .bodies import exp_compose
from .entry import call
from .rhs_address import keep_rhs_address


class AdaptiveRun:
    """Adaptive steps of ``sim``'s embedded pair (the keywords of ``Simulator.SetAdaptive``)."""

    def __init__(self, sim, rtol=1e-3, atol=1e-6, maxStep=np.inf, minStep=0.0, firstStep=None, safety=0.9,
                 maxIncrease=10.0, lengthScale=1.0, timeScale=1.0, constraintTolerance=None, acceptAtMinStep=False):
        tab = sim.tableau
        keep_rhs_address(sim.sd, sim.wk)      # the dense output's extra stages (mbs/rhs_address.py)
        maxStep = float(np.inf if maxStep is None else maxStep)
        minStep = float(0.0 if minStep is None else minStep)
        if not maxStep > 0:
            raise ValueError(f"maxStep must be positive, got {maxStep}")
        if not (minStep >= 0 and minStep < maxStep):
            raise ValueError(f"minStep must be >= 0 and below maxStep, got {minStep} (maxStep {maxStep})")
        if firstStep is not None and not (np.isfinite(firstStep) and firstStep > 0):
            raise ValueError(f"firstStep must be positive and finite, got {firstStep}")
        ctol = np.zeros(3)                   # mbs/projection.py CT_*: off
        if constraintTolerance is not None:
            ct = float(constraintTolerance)
            if not (np.isfinite(ct) and ct > 0):
                raise ValueError(f"constraintTolerance must be positive and finite (or None: off), got "
                                 f"{constraintTolerance}")
            if sim.stabilization is not None:
                raise ValueError(f"constraintTolerance projects when the drift exceeds it; stabilization="
                                 f"{sim.stabilization!r} projects after every step: use one of them")
            ctol[_projection.CT_POS] = ct
            ctol[_projection.CT_VEL] = ct / float(timeScale)
        nb = sim.sd.nb
        self.sim = sim
        self.method = _adaptive.adaptive_method(tab, sim.sd.gid)
        if tab.implicit:                     # Newton's corrections well below the error the control allows
            self.method.newton.par[_implicit.NP_TOL] = _implicit.newton_tolerance(rtol)
        self.tol = _control.tolerances(atol, rtol, lengthScale, timeScale)
        self.par = _control.controller_params(tab.order_hat, safety=safety, fac_max=maxIncrease, h_min=minStep,
                                              h_max=maxStep, accept_min=acceptAtMinStep)
        self.S = _control.controller_state()           # the PI controller's state and counters
        self.fs = np.zeros(_adaptive.FS_SIZE)           # time, step, end time (mbs/adaptive.py FS_*)
        self.ist = np.zeros(3, np.int64)                # flags (mbs/adaptive.py IS_*)
        self.R0, self.r0, self.V0 = np.zeros((nb, 3, 3)), np.zeros((nb, 3)), np.zeros((nb, 6))   # step's start
        self.dPhi, self.dV = np.zeros((nb, 6)), np.zeros((nb, 6))
        self.w = np.zeros(self.method.A.shape[0])
        self.firstStep, self.rtol, self.atol, self.ctol = firstStep, rtol, atol, ctol
        self.started = False
        self.hInitial = None

    # ------------------------------------------------------------------ start
    def restart(self):
        """A new first step (no FSAL reuse) at the next call: the state was changed from outside."""
        self.started = False

    def drop_fsal(self):
        """The next step evaluates its stage 1 anew, the step size and its controller kept: the
        state of the last accepted step was projected from outside (as the loop's own projection
        does, mbs/adaptive.py: the last stage is no longer the state's)."""
        if self.started and self.ist[_adaptive.IS_HAVE0] == _adaptive.HAVE0_FSAL:
            self.ist[_adaptive.IS_HAVE0] = _adaptive.HAVE0_NONE

    def _hinit(self):
        """Hairer's HINIT on the group (``integrators/control.py``; as ``tests/reference_mk_adaptive.initial_step``):
        two evaluations; the first is kept as the first step's stage 1."""
        sim, tol, P = self.sim, self.tol, self.par
        R, r, V, t = sim.R, sim.r, sim.V, sim.t
        st = sim._evaluate(t, R, r, V)
        if st != kernel.STATUS_OK:
            sim.RaiseStatus(st, 0.0)
        Vd0 = sim.wk.Vd[0].copy()
        size = np.zeros_like(V)
        size[:, 0] = 1.0                                     # a rotation's size: 1 rad
        size[:, 3:] = r
        d0 = _control.weighted_rms(size, V, r, r, V, V, tol)
        d1 = _control.weighted_rms(V, Vd0, r, r, V, V, tol)
        h0 = min(_control.hinit_first(d0, d1), P[_control.P_H_MAX])
        R1, r1 = np.empty_like(R), np.empty_like(r)         # explicit Euler probe (g exp(h0 V), V + h0 Vdot)
        ER, Er = np.zeros((3, 3)), np.zeros(3)
        for i in range(sim.sd.nb):
            exp_compose(int(sim.gid[i]), R[i], r[i], h0 * V[i], R1[i], r1[i], ER, Er)
        V1 = V + h0 * Vd0
        st = sim._evaluate(t + h0, R1, r1, V1)
        if st != kernel.STATUS_OK:
            sim.RaiseStatus(st, 0.0)
        d2 = _control.weighted_rms(V1 - V, sim.wk.Vd[0] - Vd0, r, r, V, V, tol) / h0
        sim.wk.Vd[0] = Vd0
        self.S[_control.S_N_RHS] += 2
        return _control.hinit_second(h0, d1, d2, P[_control.P_Q], P[_control.P_H_MAX])

    def _start(self):
        self.S[:] = _control.controller_state()
        self.ctol[_projection.CT_N_PROJ] = 0.0
        fs, ist = self.fs, self.ist
        ist[:] = 0
        h = self.firstStep
        if h is None:
            h = self._hinit()                                # leaves stage 1 in wk.Vd[0]
            ist[_adaptive.IS_HAVE0] = _adaptive.HAVE0_STAGE1
        P = self.par
        fs[_adaptive.FS_T] = self.sim.t
        fs[_adaptive.FS_H] = max(min(float(h), P[_control.P_H_MAX]), P[_control.P_H_MIN])
        self.hInitial = float(fs[_adaptive.FS_H])
        self.started = True

    # ------------------------------------------------------------------ steps
    def advance_into(self, endTime, tout, Ro, ro, Vo, Po=None):
        """Adaptive steps from the current time to ``endTime`` (the last step clipped to it),
        the states at ``tout`` written into the output rows (``Po``: also the tracked angles and
        node rotation parameters); returns ``(kernel status, outputs written)`` without raising."""
        sim = self.sim
        tEnd = float(endTime)
        if tEnd < sim.t:
            raise ValueError(f"endTime {tEnd} is before the current time {sim.t}")
        if tout.size and (np.any(np.diff(tout) < 0) or tout[-1] > tEnd):
            raise ValueError("outputTimes must be sorted and at most endTime")
        if not self.started:
            if tout.size and tout[0] < sim.t:
                raise ValueError("outputTimes before the current time")
            self._start()
        self.fs[_adaptive.FS_TEND] = tEnd
        ctl = _adaptive.AdaptiveControl(self.par, self.S, self.tol, self.ctol, self.fs, self.ist, self.R0, self.r0,
                                        self.V0, self.dPhi, self.dV, self.w, tout)
        noOut = sim.NoOutputs()
        # the one stepper with the adaptive controller (t0, k0, h, nsteps, every unused; no accelerations)
        args = (sim.sd, sim.wk, self.method, ctl, 0.0, 0, 0.0, 0, sim.R, sim.r, sim.V, float(sim.vmax), 0, Ro, ro, Vo,
                noOut[4] if Po is None else Po, noOut[5], noOut[6])
        st, k = call(sim._entries, "adaptive", kernel.mk_steps, args)
        sim.t = float(self.fs[_adaptive.FS_T])
        return st, k

    @property
    def step(self):
        """The next step size the controller proposes."""
        return float(self.fs[_adaptive.FS_H])

    @property
    def counters(self):
        """(accepted steps, rejected steps, right-hand-side evaluations) since the start (HINIT's
        two evaluations and the dense extra stages included)."""
        S = self.S
        return int(S[_control.S_N_ACCEPT]), int(S[_control.S_N_REJECT]), int(S[_control.S_N_RHS])

    @property
    def stepsAtMinStep(self):
        """Steps accepted at the minimum step beyond the tolerance (``acceptAtMinStep``)."""
        return int(self.S[_control.S_N_FLOOR])

    @property
    def projections(self):
        """Projections the constraint tolerance triggered since the start."""
        return int(self.ctol[_projection.CT_N_PROJ])

    def raise_step_min(self):
        S = self.S
        _control.raise_step_size_error(self.sim.t, S[_control.S_H], self.par[_control.P_H_MIN], S[_control.S_ERR],
                                       self.sim.tableau.name)
