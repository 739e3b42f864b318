"""Exudyn's own time loop with its Newton iteration replaced: the one adapter of both paths.

An ``exudyn.MainSolverImplicitSecondOrder`` runs ``SolveSteps`` on the bridge's settings, and
its Newton iteration is a hook (``SetUserFunctionNewton``) that puts the integrator's state at
the Exudyn step's end time into mbs.  Exudyn therefore does everything else as in a native
solve: sensors, solution and restart files, pre/post-step user functions, PostNewton with its
discontinuous iteration, the renderer, ``mbs.sys['dynamicSolver']``.

:class:`TimeLoop` owns what is the same on both paths: ``mbs.sys`` entries put back when
``InitializeSolver`` fails, the hook (which step Exudyn asks for, a step repeated by the
discontinuous iteration, a state changed by a user function between steps, the progress
lines, the run-time constraint check at the outputs), ``FinalizeSolver``, the exception a
hook raised re-raised after Exudyn unwinds, and ``updateInitialValues``.  A *driver* (the
compiled :class:`~.solver.LieGroupSolver`, the Exudyn-evaluated
:class:`~.evaluated_solve.EvaluatedSolver`) says how the state is made:

* ``loop_begin(solver)``: after ``InitializeSolver`` (mbs holds the initial values);
* ``loop_advance(t0, t1, outputsLeft)``: the state at ``t1`` into mbs, from the step that
  starts at ``t0``; it raises :class:`NewtonFailed` for a step that Exudyn shall take as its
  own failed Newton iteration (and reduce, as its settings allow);
* ``loop_restart(t, repeat)``: continue from the state in mbs at ``t`` (``repeat``: Exudyn's
  discontinuous iteration repeats the step; else a user function changed the state);
* ``loop_end()``: after a successful ``SolveSteps`` (the final writes);
* optional ``loop_context()`` (a context manager around ``SolveSteps``) and
  ``loop_fast_hook(hook, loop)`` (a hook for the common case that falls back to ``hook``);
* optional ``hand_over(error, loop)``: a user function changed what the driver cannot follow
  (``params.FixedParameterChanged``); the driver that continues the run from the step's start
  (its ``loop_begin`` done), or None (the error stands).
"""
from __future__ import annotations

import contextlib
import time

import numpy as np

from .params import FixedParameterChanged
from .reader import BridgeError
from .settings import name_exudyn_setting
from .solve_timing import compile_seconds, record_loop

PROGRESS_FIRST = 2.0         # seconds before the first progress check (it measures the rate, prints nothing)
PROGRESS_EVERY = 2.0         # seconds between progress lines
#: ODE2 coordinates from which the state is read through Exudyn's views (copy=False): below, a copy
#: costs less than the view's binding (10 coordinates: 3.6 against 5.0 us for q and q_t; 1,000: 6.4
#: against 7.2 us; 10,000: 26 against 24 us; by hand)
VIEW_FROM = 4000


class NewtonFailed(Exception):
    """A driver's step did not converge, as Exudyn's own Newton iteration may not: the hook returns
    False, and Exudyn reduces its step (its adaptiveStep) and asks for the step again, or stops;
    then ``error`` is the run's error."""

    def __init__(self, error):
        super().__init__(str(error))
        self.error = error


class Progress:
    """A progress line every PROGRESS_EVERY seconds on long runs, with the time to go."""

    def __init__(self, t0, tEnd, show):
        now = time.perf_counter()
        self.show, self.t0, self.tEnd, self.tic = bool(show), t0, tEnd, now
        self.next = now + PROGRESS_FIRST if show else float("inf")
        self.rate0 = None

    def __call__(self, t):
        now = time.perf_counter()
        if now < self.next:
            return
        self.next = now + PROGRESS_EVERY
        # the rate is measured from the first progress check on (the first step may include
        # numba's one-off compilation, which says nothing about the remaining time), and that
        # check prints nothing: a short run whose first step compiled is not a long run
        if self.rate0 is None:
            self.rate0 = (now, t)
            return
        n0, ta = self.rate0
        rem = f"{(self.tEnd - t) * (now - n0) / (t - ta):.0f}" if t > ta else "?"
        frac = (t - self.t0) / (self.tEnd - self.t0)
        print(f"exudyn_lie: t = {t:.6g} / {self.tEnd:.6g} s ({100 * frac:.0f} %), {now - self.tic:.1f} s elapsed, "
              f"~{rem} s to go", flush=True)


def finalize(mbs, solver, settings):
    """Exudyn's FinalizeSolver.  A user function's ``mbs.Modify*`` marks mbs as not assembled
    (``systemIsConsistent = False``) although it changed only live fields (the parameter watch
    stops the run otherwise); Exudyn's own solve finalizes such a run in C++ and leaves the flag
    False, but the Python FinalizeSolver refuses: it runs with the flag set, which is then put
    back."""
    consistent = mbs.systemIsConsistent
    if not consistent:
        mbs.systemIsConsistent = True
    try:
        solver.FinalizeSolver(mbs, settings)
    finally:
        if not consistent:
            mbs.systemIsConsistent = False


class TimeLoop:
    """One run of ``driver`` inside Exudyn's time loop (module docstring).

    ``settings`` the user's simulation settings (stored in ``mbs.sys`` as by
    ``exudyn.SolveDynamic``), ``loopSettings`` the bridge's copy Exudyn runs with
    (``solver.loop_settings``), ``nExudyn`` its number of steps; ``watch``: compare mbs'
    coordinates after each step with those written (a pre/post-step user function may change
    them); ``check(t, last)``: the run-time constraint check at an output (or None)."""

    def __init__(self, mbs, driver, settings, loopSettings, t0, tEnd, nExudyn, *, storeSolver=True,
                 showProgress=True, watch=False, check=None):
        self.mbs, self.driver = mbs, driver
        self.settings, self.loopSettings = settings, loopSettings
        self.t0, self.tEnd, self.nExudyn = t0, tEnd, nExudyn
        self.storeSolver, self.watch, self.check = storeSolver, watch, check
        self.progress = Progress(t0, tEnd, showProgress)
        self.hookError = None
        self.steps = [t0, t0]            # start and end time of the current Exudyn step
        self.count = 0                   # Exudyn steps done
        self.written = None              # (q, q_t) last written, as bytes, when watched
        self.nODE2 = mbs.systemData.ODE2Size()
        self.loopSeconds = 0.0

    # ------------------------------------------------------------------ the run
    def run(self):
        """InitializeSolver, SolveSteps with the hook, FinalizeSolver; returns True or raises."""
        import exudyn as exu
        mbs, driver = self.mbs, self.driver
        solver = exu.MainSolverImplicitSecondOrder()
        driver.solver = self.solver = solver
        self._initialize(solver)
        finalized = False
        try:
            driver.loop_begin(solver)
            self.check = getattr(driver, "loop_check", None) if self.check is None else self.check
            if self.watch:
                self._remember()
            self.it = solver.it              # Exudyn's iteration data (live), read once per step
            fast = getattr(driver, "loop_fast_hook", None)
            hook = (fast(self.hook, self) if fast is not None else None) or self.hook
            solver.SetUserFunctionNewton(mbs, hook)
            context = getattr(driver, "loop_context", None)
            tic, compiled0 = time.perf_counter(), compile_seconds()
            try:
                with (context() if context is not None else contextlib.nullcontext()):
                    ok = solver.SolveSteps(mbs, self.loopSettings)
                if ok:
                    self.driver.loop_end()        # (a driver that took over the run ends it)
            finally:
                self.loopSeconds = time.perf_counter() - tic
                record_loop(self.loopSeconds - (compile_seconds() - compiled0),
                            getattr(self.driver, "pathName", type(self.driver).__name__))
            finalized = True
            finalize(mbs, solver, self.loopSettings)
        except BaseException:
            if not finalized:
                try:
                    solver.FinalizeSolver(mbs, self.loopSettings)
                except Exception:           # noqa: BLE001 - the original error matters
                    pass
            if self.hookError is not None:
                raise self.hookError from None
            raise
        if not ok and self.hookError is not None:
            raise self.hookError            # (Exudyn took the hook's error for a failed step)
        if not ok:
            raise exu.SolverError(f"exudyn_lie: Exudyn's time loop terminated: {solver.GetErrorString()}")
        return True

    def _initialize(self, solver):
        """``mbs.sys`` entries as ``exudyn.SolveDynamic`` sets them (available from the start),
        then Exudyn's InitializeSolver; on a failure (e.g. a solution file that cannot be opened)
        ``mbs.sys`` as it was."""
        mbs = self.mbs
        stored = {}
        if self.storeSolver:
            sysd = mbs.sys
            stored = {key: (key in sysd, sysd.get(key)) for key in ("dynamicSolver", "simulationSettings",
                                                                     "lieGroupSolver")}
            sysd["dynamicSolver"] = solver
            sysd["simulationSettings"] = self.settings
            sysd["lieGroupSolver"] = self.driver
        try:
            ok = solver.InitializeSolver(mbs, self.loopSettings)
            if ok is False:
                raise BridgeError(f"Exudyn's InitializeSolver failed: {solver.GetErrorString()}")
        except BaseException:
            for key, (had, value) in stored.items():
                if had:
                    mbs.sys[key] = value
                else:
                    mbs.sys.pop(key, None)
            raise

    # ------------------------------------------------------------------ per Exudyn step
    def _coordinates(self):
        """mbs' Current q and q_t as bytes: copies below :data:`VIEW_FROM` coordinates, Exudyn's views from
        there on.  A change to any
        bit is a change (a user function that wrote the same values changed nothing; one that wrote
        -0.0 over 0.0 makes the driver read the same state again), and a NaN written again is none."""
        sd = self.mbs.systemData
        if self.nODE2 < VIEW_FROM:
            return sd.GetODE2Coordinates().tobytes() + sd.GetODE2Coordinates_t().tobytes()
        try:
            q, v = sd.GetODE2Coordinates(copy=False), sd.GetODE2Coordinates_t(copy=False)
        except TypeError:                  # (an Exudyn without copy=False)
            q, v = sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t()
        return np.asarray(q, float).tobytes() + np.asarray(v, float).tobytes()

    def _remember(self):
        self.written = self._coordinates()

    def _changed(self):
        return self.written is not None and self._coordinates() != self.written

    def hook(self, mainSolver, mbs, settings):
        """Exudyn's Newton iteration: the state at the step's end time into mbs."""
        try:
            t1 = self.it.currentTime
            steps, driver = self.steps, self.driver
            if self.count > 0 and t1 <= steps[1]:
                # Exudyn's discontinuous iteration calls the hook again for the same step, with
                # the ODE2 coordinates reset to the start of the step; after a failed one it
                # reduces the step (when its settings allow, bridge/solver.loop_settings): the
                # step from the same start ends earlier
                driver.loop_restart(steps[0], True)
                steps[1] = t1
            else:
                steps[0], steps[1] = steps[1], t1
                self.count += 1
                if self.watch and self._changed():
                    driver.loop_restart(steps[0], False)     # a user function changed the state
            try:
                driver.loop_advance(steps[0], t1, self.nExudyn - self.count + 1)
            except FixedParameterChanged as e:
                driver = self._hand_over(e)
                driver.loop_advance(steps[0], t1, self.nExudyn - self.count + 1)
            self.output(t1)
            if self.watch:
                self._remember()
            self.hookError = None
            return True
        except NewtonFailed as e:
            self.hookError = name_exudyn_setting(e.error)
            return False
        except BaseException as e:      # noqa: BLE001 - re-raised after Exudyn unwinds
            self.hookError = name_exudyn_setting(e)
            raise

    def _hand_over(self, error):
        """The driver that continues the run after ``error`` (see the module docstring), or the
        error again."""
        hand = getattr(self.driver, "hand_over", None)
        new = hand(error, self) if hand is not None else None
        if new is None:
            raise error
        self.driver = new
        if self.storeSolver:
            self.mbs.sys["lieGroupSolver"] = new
        self.check = getattr(new, "loop_check", None)
        self.watch = True                # (the new driver reads mbs' state when it changes)
        return new

    def output(self, t1):
        """After the state at ``t1`` is in mbs: the constraint check and the progress line."""
        if self.check is not None:
            self.check(t1, self.count >= self.nExudyn)
        if time.perf_counter() > self.progress.next:
            self.progress(t1)


def off_plan(t1, planned):
    """The error for an Exudyn step that does not end where the driver planned (both drivers)."""
    return BridgeError(f"Exudyn's time loop asks for the step ending at t = {t1!r} s, exudyn_lie planned its "
                       f"output at t = {planned!r} s: Exudyn changed its step size (after a failed discontinuous "
                       f"iteration or a step reduction), which exudyn_lie's steps do not follow; check "
                       f"timeIntegration.discontinuous and the step settings")


def update_initial_values(mbs):
    """``updateInitialValues``: the final state becomes the initial one (as Exudyn's own solve)."""
    import exudyn as exu
    sd = mbs.systemData
    sd.SetSystemState(systemStateList=sd.GetSystemState(), configuration=exu.ConfigurationType.Initial)
    sd.SetODE2Coordinates_tt(coordinates=sd.GetODE2Coordinates_tt(), configuration=exu.ConfigurationType.Initial)
