""":class:`LieGroupSolver` (read once, solve many times), the compiled path of
``SolveDynamic`` (:mod:`.solve_dynamic`) for ordinary Exudyn scripts; its state in and out
of mbs is :mod:`.state_io`.

How it works: the model is read into a :class:`~exudyn_lie.mbs.Scene`
(:func:`~exudyn_lie.bridge.reader.SceneFromExudyn`) and integrated by the package's
:class:`~exudyn_lie.mbs.Simulator` *inside Exudyn's own time loop*: an
``exudyn.MainSolverImplicitSecondOrder`` runs with its Newton iteration replaced by a
hook (``SetUserFunctionNewton``) that advances the Munthe-Kaas integrator and writes the
state back into the nodes (:mod:`.node_writers`).  Exudyn therefore does everything else as in
a native solve: sensors (stored and files), the solution file, pre/post-step user
functions, the renderer, ``mbs.sys['dynamicSolver']`` and the final state left in
``mbs``.

Sub-stepping: one Exudyn step is one *output period* of ``k`` integration steps
(:mod:`.run_plan`), so outputs happen at exactly the times of a native solve.

Chunks (:class:`~.fast.OutputChunks`): on the compiled path the simulator integrates up
to a few hundred output periods in one kernel call, recording the state at each output,
and the hook only copies the output's row of node coordinates into mbs; per output that
costs about a microsecond instead of two compiled calls (~5 us of argument unboxing).
With a pre- or post-step user function (which may change the state) a chunk is one
output long; with forces evaluated in Python (user functions of connectors and loads)
the hook advances the simulator one output at a time.

Parameters changed by user functions during the run (:mod:`.params`): the changed items are
re-read before the next step; outputs integrated ahead with the old values are dropped and
the run continues from the state in mbs.  The same restart serves a user function that set
the state, and Exudyn's discontinuous iteration calling the hook again for the same step.
"""
from __future__ import annotations

import time
import warnings

import numpy as np

from .. import __version__
from ..compiling import compile_timer
from ..integrators.tableau import resolve_pair
from ..integrators.tableau import ButcherTableau, method_names
from ..mbs.compiled import auto_groups
from ..mbs.simulator import Simulator
from ..userwarn import warn_user
from .constraint_check import ConstraintCheck, check_tolerance, kernel_explanation
from .fast import CHUNK_ROWS, AdaptiveOutputChunks, OutputChunks
from . import stage_state
from .method_choice import choose_at_start, replace_after_failure, warn_steps_at_minimum
from .moving_offsets import ParameterOffsets
from .params import ParameterWatch
from .settings import liegroup_argument, positive_float
from .run_plan import adaptive_settings, needs_accelerations, plan_substeps, time_settings
from .time_loop import TimeLoop, update_initial_values
from .reader import BridgeError, ExudynScene, SceneFromExudyn
from .state_io import StateIO


def _check_method(method):
    """A catalogue method name (case-insensitive, aliases: ``get_method``) or a user's own
    ButcherTableau."""
    if isinstance(method, ButcherTableau):
        return method
    if isinstance(method, str):
        try:
            return resolve_pair(method)          # the catalogue, or an embedded pair (BS3 = ODE23, Vern6)
        except ValueError as e:
            raise BridgeError(f"unknown method {method!r}; available: {str(e).partition('available: ')[2]} or an "
                              f"exudyn_lie.integrators.ButcherTableau") from None
    raise BridgeError(f"unknown method {method!r}; available: {', '.join(method_names())} or an "
                      f"exudyn_lie.integrators.ButcherTableau")


def loop_settings(ss, exudynSteps, info, followSteps=False):
    """The settings of Exudyn's own time loop around the hook: a deep copy of ``ss`` (the
    user's object stays as it is) with ``exudynSteps`` steps of its implicit solver, whose
    Newton iteration is the hook, and ``info`` appended to the solution file's header.  The
    steps are fixed unless ``followSteps`` (a driver that takes any step Exudyn asks for): then
    Exudyn reduces them after a failed discontinuous iteration as the user set it (adaptiveStep,
    discontinuous.useRecommendedStepSize), as in its own solve."""
    import copy

    import exudyn as exu
    ss2 = copy.deepcopy(ss)
    ti2 = ss2.timeIntegration
    ga = ti2.generalizedAlpha
    ti2.numberOfSteps = exudynSteps
    ti2.solverType = exu.DynamicSolverType.GeneralizedAlpha
    ga.computeInitialAccelerations = False
    ga.useNewmark = False
    ga.useIndex2Constraints = False
    ti2.automaticStepSize = False
    if not followSteps:
        ti2.adaptiveStep = False
        # contact items recommend a smaller step after an impact (PostNewton); fixed steps
        # do not follow it (Exudyn would reduce its step below the planned outputs)
        ti2.discontinuous.useRecommendedStepSize = False
    # Exudyn's log would count its own (output) steps and Newton iterations (none): the
    # bridge logs the integration instead; the solution file's header says what ran
    ti2.verboseMode = 0
    userInfo = ss2.solution.file.information
    ss2.solution.file.information = f"{userInfo}; {info}" if userInfo else info
    return ss2


class LieGroupSolver(StateIO):
    """Integrate an Exudyn ``mbs`` with explicit Munthe-Kaas Lie group methods.

    Parameters
    ----------
    mbs : an assembled ``exudyn.MainSystem``
    method : a method of :func:`exudyn_lie.integrators.method_names` (``'RK4'``, ...) or a
        :class:`~exudyn_lie.integrators.ButcherTableau` of the user's own
    liegroup : ``'SE3'``, ``'SO3xR3'``, ``'auto'`` or a mapping ``{object index of an
        ObjectRigidBody: 'SE3' | 'SO3xR3'}`` (bodies not in the mapping use ``'auto'``).
        ``'auto'``: SO3xR3 for an unconstrained body whose frame is at its COM, SE3 for
        every other body.
    stabilization : None (the paper: none), ``'velocity'`` or ``'position'``
    projectInitial : True (default, as Exudyn's own solvers, which accept an inconsistent
        initial state): project inconsistent initial positions and velocities onto the
        constraints, with a warning naming the joints and the size of the correction;
        False: raise :class:`~exudyn_lie.mbs.ConstraintError` instead
    verbose : print the group of every body, skipped items, the run plan and the time
        spent (numba's one-off compilation separately)

    ``Solve(simulationSettings)`` runs inside Exudyn's time loop (sensors, files, user
    functions); ``Run(endTime, stepSize)`` is the fast path without any Exudyn output
    (returns a :class:`~exudyn_lie.mbs.Result`).  Both re-read the model from ``mbs``
    (cheap) so that changed parameters or initial values are used.
    """
    pathName = "compiled"          # as solve_timing reports it

    def __init__(self, mbs, method="RK4", liegroup="auto", stabilization=None, projectInitial=True,
                 verbose=False, *, constraintTolerance=None, autoImplicit=False, handOver=False,
                 _configuration="initial", _scene=None):
        # _configuration='items' (internal, SolveDynamic): validate an mbs that is not assembled
        # yet from its item dictionaries; Solve() then re-reads it after mbs.Assemble().  _scene
        # (internal, SolveDynamic): the scene SceneFromExudyn just read of this mbs, used as it is
        self.mbs = mbs
        self._configuration = _configuration
        self.tableau = _check_method(method)
        self.method = self.tableau.name
        # autoImplicit: at the start of each fixed-step Solve, ESDIRK3 in place of the explicit method when
        # that is not stable at the step (bridge/method_choice.py)
        self.autoImplicit = bool(autoImplicit) and not self.tableau.implicit
        self._explicit = self.tableau
        # handOver (SolveDynamic's evaluation='auto' with its default stabilization): a change the
        # kernel cannot follow continues the run on the Exudyn-evaluated path (hand_over)
        self.handOver = bool(handOver)
        if stabilization not in (None, "none", "velocity", "position"):
            raise BridgeError(f"unknown stabilization {stabilization!r}; use None, 'velocity' or 'position'")
        self.stabilization = stabilization
        self.constraintTolerance = self._check_constraint_tolerance(constraintTolerance, stabilization)
        self.projectInitial = bool(projectInitial)
        self.verbose = bool(verbose)
        self._liegroup_arg = liegroup_argument(liegroup)
        self.timing = {}
        self.scene = None
        self.sim = None
        self._compileSeconds = 0.0           # numba compilation in set-ups since the last run (cold start)
        self._prepareSeconds = 0.0           # wall time of those set-ups
        self._prepare(announce=self.verbose, scene=_scene)

    # ------------------------------------------------------------------ set-up
    def _groups(self, sc: ExudynScene):
        auto = auto_groups(sc)
        tied = set(sc.pyConnectedBodies)
        for it in sc.joints + sc.connectors():
            tied.update([it.bodyA, it.bodyB])
        why = {}
        for b in range(sc.nBodies):
            if b in sc.pyConnectedBodies and auto[b] == "SO3xR3":
                auto[b] = "SE3"
            if auto[b] == "SO3xR3":
                why[b] = "auto: unconstrained, frame at COM"
            else:
                why[b] = "auto: " + ("constrained by joints/connectors" if b in tied else "frame off the COM")
        arg = self._liegroup_arg
        if isinstance(arg, str):
            groups = auto if arg == "auto" else [arg] * sc.nBodies
            if arg != "auto":
                why = {b: "all bodies" for b in range(sc.nBodies)}
        else:
            groups = list(auto)
            for o, g in arg.items():
                b = sc.body_of_object(o)
                if b is None:
                    raise BridgeError(f"liegroup mapping: object {o} is not an ObjectRigidBody of this mbs "
                                      f"(rigid bodies: objects {sc.bodyObject})")
                groups[b] = g
                why[b] = "given"
        for b, body in enumerate(sc.bodies):
            if body.isPoint:                 # a point mass has one group (compiled.resolve_groups)
                groups[b], why[b] = "R3", "point mass"
        return groups, why

    def _prepare(self, announce=False, startTime=0.0, scene=None):
        """(Re-)read the model (unless ``scene`` is its reading) and build the simulator from
        mbs' initial configuration (checked against the constraints at ``startTime``: rows with a
        moving offset)."""
        tic = time.perf_counter()
        sc = SceneFromExudyn(self.mbs, self._configuration) if scene is None else scene
        groups, why = self._groups(sc)
        with warnings.catch_warnings(), compile_timer() as ct:
            warnings.simplefilter("ignore", DeprecationWarning)
            sim = Simulator(sc, self.tableau, groups, self.stabilization, self.projectInitial, verbose=False,
                            startTime=startTime)
        self._compileSeconds += ct.seconds
        self._prepareSeconds += time.perf_counter() - tic
        self.scene, self.sim, self.groups = sc, sim, groups
        self._watch_singular_nodes()
        self._fresh = True
        self._build_buffers()
        if announce:
            self._announce(why)

    def _warn_projection(self):
        """The warning for an initial state that ``projectInitial`` corrected (once per run)."""
        what = self.sim.describe_initial_projection()
        if what:
            warn_user(f"exudyn_lie: the initial state does not satisfy the constraints; projected onto them: "
                      f"{what} (Exudyn's own solvers start from it unchanged; pass projectInitial=False to "
                      f"raise instead)")

    def _constraint_tolerance_text(self):
        ct = self.constraintTolerance
        return "" if ct is None else f", projection on the group when the constraint drift exceeds {ct:g}"

    def _kind(self):
        return "implicit" if self.tableau.implicit else "explicit"

    def _solution_information(self, nsteps, h, t0, tEnd, k, adaptive=None):
        """What was integrated, for the solution file's header and the log."""
        groups = ", ".join(f"{g} ({self.groups.count(g)} {'body' if self.groups.count(g) == 1 else 'bodies'})"
                           for g in dict.fromkeys(self.groups))
        tab = self.tableau
        if adaptive is not None:
            return (f"exudyn_lie {__version__}: {self._kind()} Munthe-Kaas {tab.name} (order {tab.order_label}, {tab.stages} "
                    f"stages) with adaptive steps (error control on the group, absoluteTolerance = "
                    f"{adaptive['atol']:g}, relativeTolerance = {adaptive['rtol']:g}, step size <= {h:.6g} s, >= "
                    f"{adaptive['minStep']:g} s{self._constraint_tolerance_text()}), Lie group {groups or 'none'}, from t = {t0:g} to {tEnd:g} s; "
                    f"Exudyn's time loop made {nsteps // k} output steps (dense output at their exact times)")
        return (f"exudyn_lie {__version__}: {self._kind()} Munthe-Kaas {tab.name} (order {tab.order_label}, {tab.stages} stages), "
                f"Lie group {groups or 'none'}, step size h = {h:.6g} s, {nsteps} steps from t = {t0:g} to "
                f"{tEnd:g} s; Exudyn's time loop made {nsteps // k} steps of {k} integration step(s) each (the "
                f"header's 'number of time steps (planned)' counts those)")

    def _choose_method(self, h):
        choose_at_start(self, h)

    def _replace_after_failure(self, status, h, t):
        return replace_after_failure(self, status, h, t, self._loopPlan)

    def _announce(self, why):
        sc = self.scene
        for b in range(sc.nBodies):
            print(f"exudyn_lie: body {sc.describe_body(b)}: {self.groups[b]} ({why[b]})")
        for what, reason in sc.skipped:
            print(f"exudyn_lie: skipped {what}: {reason}")
        if sc.pyItems:
            print(f"exudyn_lie: {len(sc.pyItems)} item(s) evaluated in Python: "
                  f"{', '.join(it.label for it in sc.pyItems)}")
    def _apply_parameters(self, t):
        """Parameters changed by user functions since the last step: the simulator must not
        be ahead of Exudyn (outputs integrated with the old values are dropped), then only
        the changed items are re-read (:class:`~.params.ParameterWatch`)."""
        ch = self._chunks
        if ch is not None and ch.next < ch.rows:
            self._restart_from_mbs(t)
        self._params.apply(t)

    def _parameter_offsets(self, t0):
        """``(ParameterOffsets, actual)`` of the rows whose offset a step function may move
        (bridge/moving_offsets.py; ``(None, None)`` without): each row's tag is its
        MovableOffset, which takes the step's curve."""
        sc, sim = self.scene, self.sim
        if not sc.movableOffsets:
            return None, None
        objects = []
        for ji in sc.joints_info:
            drive = sc.movableOffsets.get(ji.objectIndex)
            if drive is not None:
                objects.append((ji.objectIndex, [int(q) for q in np.flatnonzero(sim.rowJoint == ji.sceneJoint)], drive))
        rowDrive = {rows[0]: drive for _, rows, drive in objects}

        def actual():
            # the row is h = x - c(t) with the offset c the step ran with: x = h + c, xdot = (J V - cdot) + cdot
            h, gv = sim.RowResiduals(sim.R, sim.r, sim.V, sim.t)

            def at(q, v):
                c, cd, _ = rowDrive[q].value_rate_acceleration(sim.t)
                return h[q] + c, gv[q] + cd
            return at
        return ParameterOffsets(self.mbs, t0, objects), actual
    # ------------------------------------------------------------------ planning (bridge/run_plan.py)
    def _plan(self, ss, nsteps, h, substeps):
        return plan_substeps(self.mbs, ss, nsteps, h, substeps)

    def _needs_accelerations(self, ss, userStep):
        """Accelerations / multipliers are written only if something can read them (joint
        outputs are the multipliers)."""
        return needs_accelerations(self.mbs, ss, userStep, {ji.objectIndex for ji in self.scene.joints_info})

    # ------------------------------------------------------------------ adaptive steps
    @staticmethod
    def _check_constraint_tolerance(ct, stabilization):
        """The keyword ``constraintTolerance`` (Exudyn has no setting of this meaning: its
        implicit solvers meet the constraints to the Newton tolerance, its explicit ones have
        no joints), checked: None or a positive number, not together with ``stabilization``."""
        if ct is None:
            return None
        ct = positive_float(ct, BridgeError(f"constraintTolerance must be a positive number (or None: off), "
                                            f"got {ct!r}"))
        if stabilization not in (None, "none"):
            raise BridgeError(f"constraintTolerance projects when the constraint drift exceeds it, stabilization="
                              f"{stabilization!r} after every step: give one of them")
        return ct

    def _adaptive_settings(self, ss, h):
        return adaptive_settings(self.tableau, ss, h, self.constraintTolerance)

    # ------------------------------------------------------------------ solve
    _time_settings = staticmethod(time_settings)

    def _check_run(self, ss, substeps):
        """Raise for settings a run with ``Solve(ss, substeps=...)`` would refuse (changes
        nothing; SolveDynamic calls it before it assembles mbs)."""
        nsteps, t0, tEnd, h = self._time_settings(ss)
        self._plan(ss, nsteps, h, substeps)
        self._adaptive_settings(ss, h)

    def _use_assembled(self):
        """After SolveDynamic validated an unassembled mbs ('items') and assembled it: read
        the assembled model (Exudyn's AE indices) from now on."""
        if self._configuration == "items":
            self._configuration = "initial"
            return True
        return False

    def Solve(self, simulationSettings=None, updateInitialValues=False, storeSolver=True, showProgress=True,
              substeps=None, accelerations=None, refresh=True, constraintCheck=True):
        """Solve from ``startTime`` to ``endTime`` in ``numberOfSteps`` steps of the
        simulation settings, inside Exudyn's time loop; returns True.

        ``constraintCheck`` (default True): Exudyn's own residuals of the constraints at the
        outputs (within a time budget), judged against the kernel's (:mod:`.constraint_check`);
        a float is the tolerance, False switches the check off.

        ``accelerations``: write ``q_tt`` and the joint multipliers every output step
        (None: only if a sensor, the solution or restart file or a user function can read
        them).

        ``simulationSettings`` is never changed, not even during the run: Exudyn's time
        loop runs on a deep copy with the bridge's settings (``numberOfSteps`` = number of
        output periods, the implicit solver type whose Newton iteration is replaced, ...),
        so user functions reading ``mbs.sys['simulationSettings']`` (the object passed in,
        as with ``exudyn.SolveDynamic``) see the user's values.  The flip side: changes a
        user function makes to that object during the run are not seen by the run.

        With ``storeSolver``, ``mbs.sys['dynamicSolver' / 'simulationSettings' /
        'lieGroupSolver']`` are set for the run (as by ``exudyn.SolveDynamic``); if Exudyn's
        ``InitializeSolver`` fails (e.g. a solution file that cannot be opened) the previous
        entries are put back."""
        self._constraintCheck = check_tolerance(constraintCheck)
        with compile_timer() as ct:
            ok = self._solve(simulationSettings, updateInitialValues, storeSolver, showProgress, substeps,
                             accelerations, refresh, ct)
        return ok

    def _make_constraint_check(self, solver, since):
        """The run-time check (:mod:`.constraint_check`) with the kernel's rows of each item,
        or None when it is off or the model has no constraint."""
        tol = getattr(self, "_constraintCheck", True)
        if tol is None or not self.mbs.systemData.AEsize():
            return None
        tic = time.perf_counter()
        sim, sc = self.sim, self.scene
        objectOf = {sc.joints[ji.sceneJoint].name: ji.objectIndex for ji in sc.joints_info
                    if ji.sceneJoint is not None}
        dependent = [objectOf[n] for n in sim.redundantJoints if n in objectOf] if sim.hasRedundantRows else None
        check = ConstraintCheck(self.mbs, solver, tol, dependent)
        sceneJoint = {ji.objectIndex: ji.sceneJoint for ji in sc.joints_info}
        rows = []
        for kind, i, _ in check.items:
            j = sceneJoint.get(i) if kind == "object" else None
            rows.append(None if j is None else np.nonzero(sim.rowJoint == j)[0])
        at, explain = kernel_explanation(sim, rows)
        ch = self._chunks

        def at_output(t, last):
            if check.due(last) and ch.next > 0:
                # the kernel state of the row just written
                check.timed_check(t, explain, lambda: at(ch, ch.next - 1, t))
        check.start(since, tic)
        self.constraintCheck = check
        return at_output

    def _solve(self, simulationSettings, updateInitialValues, storeSolver, showProgress, substeps,
               accelerations, refresh, ct):
        import exudyn as exu
        self._exu = exu
        ticTotal = time.perf_counter()
        ss = exu.SimulationSettings() if simulationSettings is None else simulationSettings
        nsteps, t0, tEnd, h = self._time_settings(ss)
        # set-ups before this call (SolveDynamic builds the solver first) count to this run
        pendingCompile, pendingPrepare = self._compileSeconds, self._prepareSeconds
        if self._use_assembled() or refresh or not self._fresh:
            self._prepare(announce=False, startTime=t0)
        elif self.sim.hasRowDrives and self.sim.startTime != t0:      # moving offsets: checked at another time
            self._prepare(announce=False, startTime=t0)
        self._fresh = False
        self._warn_projection()
        ticLoop, compileSetUp = time.perf_counter(), ct.seconds
        sim = self.sim
        sim.t = t0
        k, userStep = self._plan(ss, nsteps, h, substeps)
        needAcc = self._needs_accelerations(ss, userStep) if accelerations is None else bool(accelerations)
        self._watch = userStep          # a pre/post-step function may change the state
        adaptive = self._adaptive_settings(ss, h)
        if self.autoImplicit and adaptive is None:
            self._choose_method(h)
            sim = self.sim
        info = self._solution_information(nsteps, h, t0, tEnd, k, adaptive)
        log = self.verbose or ss.timeIntegration.verboseMode >= 1
        if log:
            print(f"{info}; accelerations {'written' if needAcc else 'not needed'}")
        # Exudyn runs nsteps / k steps of its implicit solver, whose Newton iteration is the
        # hook, with these settings: on a deep copy (the user's object stays as it is)
        ss2 = loop_settings(ss, nsteps // k, info)
        if self.scene.rollingDiscPenalties:
            # the kernel updates the contacts' data coordinates after every step (their
            # PostNewtonStep); Exudyn's PostNewton after each output recomputes the same values
            # from the written state: one pass, and its "error" (data of the previous output)
            # must not make Exudyn repeat the step
            disc = ss2.timeIntegration.discontinuous
            disc.maxIterations = 1
            disc.ignoreMaxIterations = True

        self._loopPlan = dict(k=k, h=h, tEnd=tEnd, adaptive=adaptive, needAcc=needAcc, since=ticTotal - pendingPrepare,
                              ss=ss)
        self.timing = dict(integration=0.0, steps=nsteps, exudynSteps=nsteps // k, substeps=k)
        loop = TimeLoop(self.mbs, self, ss, ss2, t0, tEnd, nsteps // k, storeSolver=storeSolver,
                        showProgress=showProgress, watch=self._watch)
        loop.run()
        self.handedOverTo = loop.driver if loop.driver is not self else None
        if self.handedOverTo is not None:
            self.timing["integration"] += self.handedOverTo._integration
        if updateInitialValues:
            update_initial_values(self.mbs)
        now = time.perf_counter()
        loop, setUp = now - ticLoop, (ticLoop - ticTotal) + pendingPrepare
        compiled, compileLoop = ct.seconds + pendingCompile, ct.seconds - compileSetUp
        self._compileSeconds = self._prepareSeconds = 0.0
        loopNet = max(loop - compileLoop, 0.0)           # the time loop without numba's compilation
        integ = self.timing["integration"]
        self.timing.update(total=setUp + loop, setUp=setUp, loop=loop, compile=compiled,
                           bridgeOverhead=max(loopNet - integ, 0.0) / loopNet if loopNet > 0 else 0.0)
        adaptive = self._loopPlan["adaptive"]          # (also after a switch to ESDIRK3)
        if adaptive is not None:
            warn_steps_at_minimum(sim)
            acc, rej, nrhs = sim.adaptiveCounters
            self.timing.update(adaptive=True, accepted=acc, rejected=rej, rhsEvaluations=nrhs, steps=acc,
                               constraintProjections=sim.constraintProjections)
            nsteps = acc
        if log:
            print(f"exudyn_lie: {nsteps} steps in {setUp + loop:.3g} s: set-up {setUp:.3g} s (reading the model, "
                  f"building the simulator), time loop {loop:.3g} s (integration {integ:.3g} s = "
                  f"{1e6 * integ / max(nsteps, 1):.3g} us/step, bridge + Exudyn output "
                  f"{100 * self.timing['bridgeOverhead']:.1f} %)"
                  + (f"; numba compilation {compiled:.3g} s of it (first run on this machine, cached from now on)"
                     if compiled > 0.05 else ""))
        return True

    # ------------------------------------------------------------------ the driver of the time loop
    def loop_begin(self, solver):
        """After InitializeSolver (bridge/time_loop.py): buffers on mbs' coordinates, the initial
        state with accelerations, the output chunks of the one compiled stepper."""
        self._init_buffers_from_mbs()
        stage_state.install(self)
        self._write(True)                    # initial state with accelerations / multipliers
        self._chunks = self._new_chunks()
        self.loop_check = self._make_constraint_check(solver, self._loopPlan["since"])
        self._params = ParameterWatch(self)
        self._offsets, self._actual = self._parameter_offsets(self.sim.t)

    def _new_chunks(self):
        """Chunks of outputs from the one compiled stepper, fixed or adaptive steps by the plan; one
        output per chunk if a user function may change the state in between or Python forces (Exudyn
        user functions) run, so that they are called in step with Exudyn's outputs."""
        plan, sim = self._loopPlan, self.sim
        bufs, jac = (self._q, self._qt, self._qtt, self._ae), (self._jrow, self._jae)
        maxRows = 1 if (self._watch or sim.hasPythonStage) else CHUNK_ROWS
        args = (sim, self._nodes, sim.vmax, bufs, jac, plan["k"], plan["h"], plan["needAcc"])
        if plan["adaptive"] is None:
            return OutputChunks(*args, maxRows=maxRows)
        sim.SetAdaptive(**plan["adaptive"])
        return AdaptiveOutputChunks(*args, plan["tEnd"], maxRows=maxRows, clip=self._watch)

    def loop_context(self):
        return self._params                  # Set*Parameter / Modify* recorded during the loop

    def loop_restart(self, t, repeat):
        self._restart_from_mbs(t)

    def loop_advance(self, t0, t1, outputsLeft):
        """The next output row at ``t1`` into mbs (a new chunk when the last one is used up),
        after the parameters a user function changed and the moving offsets of the step."""
        params = self._params
        if params.marks or params.late:
            self._apply_parameters(t0)
        if self._offsets:
            for _, curve, drive in self._offsets.record(t0, t1, self._actual):
                drive.curve = curve
        params.busy = True                   # force user functions run inside: changes refused
        try:
            self._next_output(t1, outputsLeft)
        finally:
            params.busy = False
        if params.late:
            params.apply(t1)                 # refused: changed inside the step
        if not self._live:
            self._push(self._loopPlan["needAcc"])

    def loop_fast_hook(self, hook, loop):
        """The common case, kept to a few operations per output (the bridge-overhead bench):
        the next row of the current chunk goes into the live coordinate views; refilling a
        chunk, a time off the plan (the error) and everything else go through ``hook``.
        ch.on_plan and ch.pop are inlined here: the three method calls cost 1-2 % of a heavy-top
        run with a sensor every 10 steps; keep the two in step with OutputChunks."""
        ch = self._chunks
        if ch is None or not self._live or self._watch:
            return None
        q, qt, qtt, ae = self._q, self._qt, self._qtt, self._ae
        Qr, Qtr, Qttr, AEr = ch.rowViews
        doacc, hasAE = ch.doacc, ae.size > 0
        dtOut, tolOut = ch.nsub * ch.h, 1e-6 * ch.nsub * ch.h
        marks, it, steps = self._params.marks, loop.it, loop.steps
        check, progress, perf, nExudyn = loop.check, loop.progress, time.perf_counter, loop.nExudyn

        def fast_hook(mainSolver, mbs, settings):
            o = ch.next
            if o >= ch.rows or marks:
                return hook(mainSolver, mbs, settings)
            t1 = it.currentTime
            if abs(ch.tStart + (o + 1) * dtOut - t1) > tolOut + 1e-12 * abs(t1):
                return hook(mainSolver, mbs, settings)       # raises the planning error
            q[:] = Qr[o]
            qt[:] = Qtr[o]
            if doacc:
                qtt[:] = Qttr[o]
                if hasAE:
                    ae[:] = AEr[o]
            ch.next = o + 1
            loop.count += 1
            steps[0] = steps[1]
            steps[1] = t1
            if check is not None:
                check(t1, loop.count >= nExudyn)
            if perf() > progress.next:
                progress(t1)
            return True
        return fast_hook

    def hand_over(self, error, loop):
        """The driver that continues the run after ``error`` (evaluated_solve.hand_over_from), or None."""
        from .evaluated_solve import hand_over_from
        return hand_over_from(self, error, loop) if self.handOver else None

    def loop_end(self):
        if not self._loopPlan["needAcc"]:
            self._write(True)                # final accelerations, as a native solve leaves them
        self._write_torsion_data()           # the exact turned angles (Exudyn tracks per output)
    # ------------------------------------------------------------------ fast path
    def Run(self, endTime, stepSize, outputEvery=1, startTime=0.0, writeBack=True, progress=False,
            refresh=True):
        """Integrate without Exudyn's output machinery; returns a
        :class:`~exudyn_lie.mbs.Result`.  ``writeBack``: leave the final state (with
        accelerations) in mbs' Current configuration."""
        import exudyn as exu
        self._exu = exu
        if self._use_assembled() or refresh or not self._fresh:
            self._prepare(announce=False, startTime=float(startTime))
        self._fresh = False
        self._warn_projection()
        self.sim.t = float(startTime)
        if stage_state.needed(self):
            self._init_buffers_from_mbs(t0=float(startTime))
            stage_state.install(self)
        tic = time.perf_counter()
        res = self.sim.Run(endTime, stepSize, outputEvery=outputEvery, startTime=float(startTime),
                           progress=progress)
        self.timing = dict(integration=res.cpuTime, total=time.perf_counter() - tic)
        self._compileSeconds = self._prepareSeconds = 0.0
        self._warn_watched_nodes()
        if writeBack:
            self._watch = False
            self._init_buffers_from_mbs(t0=float(startTime))      # mbs still holds the start state
            self._write(True)
            self._write_torsion_data()
            self.mbs.systemData.SetTime(self.sim.t)
        return res
