"""``SolveDynamic`` for ordinary Exudyn scripts, and :class:`LieGroupSolver` (read once,
solve many times).

How it works: the model is read into a :class:`~exudyn_lie.mbs.Scene`
(:func:`~exudyn_lie.bridge.reader.SceneFromExudyn`) and integrated by the package's
:class:`~exudyn_lie.mbs.Simulator` *inside Exudyn's own time loop*: an
``exudyn.MainSolverImplicitSecondOrder`` runs with its Newton iteration replaced by a
hook (``SetUserFunctionNewton``) that advances the Munthe-Kaas integrator and writes the
state back into the nodes (:mod:`.nodes`).  Exudyn therefore does everything else as in
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

import math
import time
import warnings

import numpy as np

from .. import __version__
from ..compiling import compile_timer
from ..errors import SimulationError, raised_at_boundary
from ..integrators.mk_adaptive import resolve_pair
from ..integrators.tableau import ButcherTableau, method_names
from ..mbs.compiled import auto_groups
from ..mbs.rolling_disc_penalty_forces import D_DATA
from ..mbs.scene import SceneError
from ..mbs.simulator import Simulator
from ..userwarn import warn_user
from .constraint_check import ConstraintCheck, check_tolerance, kernel_explanation
from .fast import CHUNK_ROWS, AdaptiveOutputChunks, NodeTable, OutputChunks
from .moving_offsets import ParameterOffsets
from .params import ParameterWatch
from .settings import liegroup_argument, positive_float
from .solvertype import resolve_solver_type
from .run_plan import adaptive_settings, needs_accelerations, plan_substeps, time_settings
from .time_loop import TimeLoop, off_plan, update_initial_values
from .reader import BridgeError, ExudynScene, SceneFromExudyn



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


def loop_settings(ss, exudynSteps, info):
    """The settings of Exudyn's own time loop around the hook: a deep copy of ``ss`` (the
    user's object stays as it is) with ``exudynSteps`` fixed steps of its implicit solver,
    whose Newton iteration is the hook, and ``info`` appended to the solution file's header."""
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
    ti2.adaptiveStep = False
    ti2.automaticStepSize = False
    # contact items recommend a smaller step after an impact (PostNewton); the fixed steps
    # do not follow it (Exudyn would reduce its step below the planned outputs)
    ti2.discontinuous.useRecommendedStepSize = False
    # Exudyn's log would count its own (output) steps and Newton iterations (none): the
    # bridge logs the integration instead; the solution file's header says what ran
    ti2.verboseMode = 0
    userInfo = ss2.solution.file.information
    ss2.solution.file.information = f"{userInfo}; {info}" if userInfo else info
    return ss2


class LieGroupSolver:
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

    def __init__(self, mbs, method="RK4", liegroup="auto", stabilization=None, projectInitial=True,
                 verbose=False, *, constraintTolerance=None, _configuration="initial", _scene=None):
        # _configuration='items' (internal, SolveDynamic): validate an mbs that is not assembled
        # yet from its item dictionaries; Solve() then re-reads it after mbs.Assemble().  _scene
        # (internal, SolveDynamic): the scene SceneFromExudyn just read of this mbs, used as it is
        self.mbs = mbs
        self._configuration = _configuration
        self.tableau = _check_method(method)
        self.method = self.tableau.name
        if stabilization not in (None, "none", "velocity", "position"):
            raise BridgeError(f"unknown stabilization {stabilization!r}; use None, 'velocity' or 'position'")
        self.stabilization = stabilization
        self.constraintTolerance = self._check_constraint_tolerance(constraintTolerance, stabilization)
        self.projectInitial = bool(projectInitial)
        self.verbose = bool(verbose)
        self._liegroup_arg = self._check_liegroup(liegroup)
        self.timing = {}
        self.scene = None
        self.sim = None
        self._compileSeconds = 0.0           # numba compilation in set-ups since the last run (cold start)
        self._prepareSeconds = 0.0           # wall time of those set-ups
        self._prepare(announce=self.verbose, scene=_scene)

    # ------------------------------------------------------------------ set-up
    def _check_liegroup(self, liegroup):
        return liegroup_argument(liegroup)

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

    def _solution_information(self, nsteps, h, t0, tEnd, k, adaptive=None):
        """What was integrated, for the solution file's header and the log."""
        groups = ", ".join(f"{g} ({self.groups.count(g)} {'body' if self.groups.count(g) == 1 else 'bodies'})"
                           for g in dict.fromkeys(self.groups))
        tab = self.tableau
        if adaptive is not None:
            return (f"exudyn_lie {__version__}: explicit Munthe-Kaas {tab.name} (order {tab.order}, {tab.stages} "
                    f"stages) with adaptive steps (error control on the group, absoluteTolerance = "
                    f"{adaptive['atol']:g}, relativeTolerance = {adaptive['rtol']:g}, step size <= {h:.6g} s, >= "
                    f"{adaptive['minStep']:g} s{self._constraint_tolerance_text()}), Lie group {groups or 'none'}, from t = {t0:g} to {tEnd:g} s; "
                    f"Exudyn's time loop made {nsteps // k} output steps (dense output at their exact times)")
        return (f"exudyn_lie {__version__}: explicit Munthe-Kaas {tab.name} (order {tab.order}, {tab.stages} stages), "
                f"Lie group {groups or 'none'}, step size h = {h:.6g} s, {nsteps} steps from t = {t0:g} to "
                f"{tEnd:g} s; Exudyn's time loop made {nsteps // k} steps of {k} integration step(s) each (the "
                f"header's 'number of time steps (planned)' counts those)")

    def _announce(self, why):
        sc = self.scene
        for b in range(sc.nBodies):
            print(f"exudyn_lie: body {sc.describe_body(b)}: {self.groups[b]} ({why[b]})")
        for what, reason in sc.skipped:
            print(f"exudyn_lie: skipped {what}: {reason}")
        if sc.pyItems:
            print(f"exudyn_lie: {len(sc.pyItems)} item(s) evaluated in Python: "
                  f"{', '.join(it.label for it in sc.pyItems)}")

    def _build_buffers(self):
        sc, sim = self.scene, self.sim
        # kernel rows of every joint, and their AE slots in Exudyn
        self._jrows = []
        for ji in sc.joints_info:
            r0, n = (int(x) for x in sim.sd.jint[ji.sceneJoint, 2:4])
            self._jrows.append((np.arange(r0, r0 + n), ji.aeRows))

    # ------------------------------------------------------------------ state <-> mbs
    def _views(self):
        """Writable zero-copy views of mbs' Current q, q_t, q_tt, AE coordinates (Exudyn
        >= 1.13 getters with ``copy=False``), checked to be live; None if unavailable."""
        sd = self.mbs.systemData
        cur = self._exu.ConfigurationType.Current
        try:
            views = (sd.GetODE2Coordinates(configuration=cur, copy=False),
                     sd.GetODE2Coordinates_t(configuration=cur, copy=False),
                     sd.GetODE2Coordinates_tt(configuration=cur, copy=False),
                     sd.GetAECoordinates(configuration=cur, copy=False) if sd.AEsize() else np.zeros(0))
        except TypeError:
            return None
        for v in views[:3]:
            if not (isinstance(v, np.ndarray) and v.dtype == np.float64 and v.flags.c_contiguous
                    and v.flags.writeable) or v.size == 0:
                return None
        q = views[0]
        old = q[0]
        q[0] = old + 1.0
        live = sd.GetODE2Coordinates(configuration=cur)[0] == old + 1.0
        q[0] = old
        return views if live else None

    def _init_buffers_from_mbs(self, t0=None):
        """Coordinate buffers: zero-copy views of mbs' Current configuration if possible
        (then nothing has to be copied per output step), else copies pushed with Set*.
        Called right after Exudyn's InitializeSolver (Current = the initial values)."""
        exu = self._exu
        sd = self.mbs.systemData
        cur = exu.ConfigurationType.Current
        self._nAE = sd.AEsize()
        views = self._views()
        self._live = views is not None
        if self._live:
            self._q, self._qt, self._qtt, self._ae = views
        else:
            self._q = np.array(sd.GetODE2Coordinates(configuration=cur), float)
            self._qt = np.array(sd.GetODE2Coordinates_t(configuration=cur), float)
            self._qtt = np.array(sd.GetODE2Coordinates_tt(configuration=cur), float)
            self._ae = np.array(sd.GetAECoordinates(configuration=cur), float) if self._nAE else np.zeros(0)
        if self._nAE:
            self._ae[self.scene.aeZero] = 0.0
        for kind in self.scene.nodeKinds:       # continuity starts from the initial parameters
            kind.read(np.array(self._q), np.array(self._qt))
        self._nodes = NodeTable(self.scene.nodeKinds, self.scene.kindBodies, self.sim.t if t0 is None else t0)
        jr = self._jrows
        self._jrow = np.concatenate([x[0] for x in jr]).astype(np.int64) if jr else np.zeros(0, np.int64)
        self._jae = np.concatenate([x[1] for x in jr]).astype(np.int64) if jr else np.zeros(0, np.int64)
        self._Vdot = np.zeros((self.scene.nBodies, 6))
        self._lam = np.zeros(self.sim.sd.nrows)
        self._hasJ = len(self._jrow) > 0

    def _watch_singular_nodes(self):
        """Nodes with singular coordinates (Rxyz) are watched at every internal step, so
        that passing near the singularity between two outputs is reported too."""
        nodes, bodies, limits, entry = [], [], [], None
        for kind, kb in zip(self.scene.nodeKinds, self.scene.kindBodies):
            if kind.singularity is not None:
                entry = kind.singularity[0]
                nodes += [(kind, k) for k in range(len(kind))]
                bodies += list(kb)
                limits += [kind.singularity[1]] * len(kind)
        self._watchNodes = nodes
        self._watchLimit = np.array(limits)
        if nodes:
            self.sim.WatchRotationEntries(bodies, *entry)

    def _warn_watched_nodes(self):
        """Warn (once per node) about watched nodes that came near their singularity
        since the last call."""
        if not self._watchNodes:
            return
        hit = self.sim.watchedMaxima > self._watchLimit
        if hit.any():
            self.sim.ResetWatch()
            for w in np.nonzero(hit)[0]:
                kind, k = self._watchNodes[w]
                kind.singular_warning(k)

    def _fill(self, accelerations):
        """Node and AE buffers from the simulator state (Python path)."""
        sim = self.sim
        lam = self._lam
        if accelerations:
            Vdot, lam = sim.Accelerations()
            self._Vdot[:] = Vdot
        return self._nodes.write(sim, self._Vdot, lam, accelerations, self._q, self._qt, self._qtt,
                                 (self._jrow, self._jae, self._ae))

    def _push(self, accelerations):
        """Copy the buffers into mbs' Current configuration (nothing to do for views)."""
        if not self._live:
            sd = self.mbs.systemData
            cur = self._exu.ConfigurationType.Current
            sd.SetODE2Coordinates(self._q, configuration=cur)
            sd.SetODE2Coordinates_t(self._qt, configuration=cur)
            if accelerations:
                sd.SetODE2Coordinates_tt(self._qtt, configuration=cur)
                if self._nAE:
                    sd.SetAECoordinates(self._ae, configuration=cur)
        if self._nodes.flags.any():
            self._nodes.warn_flags()

    def _write(self, accelerations):
        self._fill(accelerations)
        self._push(accelerations)

    def _next_output(self, t1, outputsLeft):
        """The compiled path: the buffers at Exudyn's time ``t1`` from the next row of the
        output chunk, integrating a new chunk when the last one is used up."""
        ch = self._chunks
        if ch.next == ch.rows:
            if ch.failure is not None:
                self.sim.RaiseStatus(ch.failure, ch.h)
            tic = time.perf_counter()
            rows, nflag = ch.refill(outputsLeft)
            sec = time.perf_counter() - tic
            ch.adapt(sec, rows)
            self.timing["integration"] += sec
            if nflag:
                self._nodes.warn_flags()
            self._warn_watched_nodes()
            if rows == 0:
                self.sim.RaiseStatus(ch.failure, ch.h)
        if not ch.on_plan(t1):
            raise off_plan(t1, ch.time_of_next())
        ch.pop()

    def _restart_from_mbs(self, t):
        """Continue from the state in mbs at time ``t`` (Exudyn's start of the step): a user
        function changed the coordinates, Exudyn's discontinuous iteration repeats the step
        (it resets the ODE2 coordinates to the start of the step), or changed parameters
        invalidate the outputs integrated ahead."""
        self._reread_current(t)
        ch = self._chunks
        if ch is not None:
            ch.rows = ch.next = 0
            ch.failure = None
            if isinstance(ch, AdaptiveOutputChunks):     # a new first step, no FSAL reuse
                ch.restart(t)
                self.sim.RestartAdaptive()

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

    def _reread_current(self, t):
        """A pre-step user function changed the coordinates: continue from them."""
        sd = self.mbs.systemData
        cur = self._exu.ConfigurationType.Current
        q = np.array(sd.GetODE2Coordinates(configuration=cur), float)
        qt = np.array(sd.GetODE2Coordinates_t(configuration=cur), float)
        nb = self.scene.nBodies
        R = np.zeros((nb, 3, 3))
        r = np.zeros((nb, 3))
        om = np.zeros((nb, 3))
        ve = np.zeros((nb, 3))
        for kind, bodies in zip(self.scene.nodeKinds, self.scene.kindBodies):
            R[bodies], r[bodies], om[bodies], ve[bodies] = kind.read(q, qt)
        U, _, Vt = np.linalg.svd(R)
        self.sim.SetInitialState(U @ Vt, r, om, ve, t0=t)
        for kind, bodies in zip(self.scene.nodeKinds, self.scene.kindBodies):
            for k, b in enumerate(bodies):          # the rotation parameters in mbs go on from here
                tr = kind.tracked(k)
                if tr is not None:
                    self.sim.wk.bparam[b] = tr[1]
        self._seed_torsion()
        self._seed_contact_data()
        self._nodes.prev[:] = NodeTable(self.scene.nodeKinds, self.scene.kindBodies, t).prev

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
        dependent = [objectOf[n] for n in sim.redundantJoints if n in objectOf] if sim.sd.redundant else None
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

        self._loopPlan = dict(k=k, h=h, tEnd=tEnd, adaptive=adaptive, needAcc=needAcc, since=ticTotal - pendingPrepare)
        self.timing = dict(integration=0.0, steps=nsteps, exudynSteps=nsteps // k, substeps=k)
        TimeLoop(self.mbs, self, ss, ss2, t0, tEnd, nsteps // k, storeSolver=storeSolver, showProgress=showProgress,
                 watch=self._watch).run()
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
        if adaptive is not None:
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
        plan, sim = self._loopPlan, self.sim
        self._init_buffers_from_mbs()
        vmax = sim.vmax
        self._write(True)                    # initial state with accelerations / multipliers
        # chunks of outputs from the one compiled stepper; one output per chunk if a user
        # function may change the state in between or Python forces (Exudyn user
        # functions) run, so that they are called in step with Exudyn's outputs
        bufs, jac = (self._q, self._qt, self._qtt, self._ae), (self._jrow, self._jae)
        maxRows = 1 if (self._watch or sim.sd.hasQext) else CHUNK_ROWS
        k, h, needAcc = plan["k"], plan["h"], plan["needAcc"]
        if plan["adaptive"] is None:
            self._chunks = OutputChunks(sim, self._nodes, vmax, bufs, jac, k, h, needAcc, maxRows=maxRows)
        else:
            sim.SetAdaptive(**plan["adaptive"])
            self._chunks = AdaptiveOutputChunks(sim, self._nodes, vmax, bufs, jac, k, h, needAcc, plan["tEnd"],
                                                maxRows=maxRows)
        self.loop_check = self._make_constraint_check(solver, plan["since"])
        self._params = ParameterWatch(self)
        self._offsets, self._actual = self._parameter_offsets(sim.t)

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

    def loop_end(self):
        if not self._loopPlan["needAcc"]:
            self._write(True)                # final accelerations, as a native solve leaves them
        self._write_torsion_data()           # the exact turned angles (Exudyn tracks per output)

    # ------------------------------------------------------------------ torsional springs' data nodes
    def _torsion_angles(self):
        """Exudyn's continuous angle of every torsional spring with a data node, at the
        simulator's state (compiled springs: the kernel's tracked angle + the folded turns)."""
        out = []
        st = None
        for td in self.scene.torsionData:
            if td.spring is not None:
                out.append(float(self.sim.wk.tphi[td.spring]) + 2.0 * math.pi * td.turns0)
            else:
                st = self.sim.states() if st is None else st
                out.append(float(td.item.angle(st)[0]))
        return out

    def _write_torsion_data(self):
        """Write the turned angles into the springs' data nodes (Current): Exudyn's own
        update after each of its steps takes the branch nearest to the last angle, which
        loses turns when a spring turns by more than pi between two outputs."""
        tds = self.scene.torsionData
        if not tds:
            return
        sd = self.mbs.systemData
        cur = self._exu.ConfigurationType.Current
        data = np.array(sd.GetDataCoordinates(configuration=cur), float)
        for td, angle in zip(tds, self._torsion_angles()):
            data[int(sd.GetNodeLTGData(td.dataNode)[0])] = angle
        sd.SetDataCoordinates(data, configuration=cur)

    def _seed_contact_data(self):
        """After the state was re-read from mbs: the penalty rolling discs' data coordinates
        (slip velocity, gap of the last step) as they are in mbs."""
        if not self.scene.rollingDiscData:
            return
        sd = self.mbs.systemData
        data = np.asarray(sd.GetDataCoordinates(configuration=self._exu.ConfigurationType.Current), float)
        for k, (_, node) in enumerate(self.scene.rollingDiscData):
            self.sim.wk.disc[k, D_DATA:] = data[np.asarray(sd.GetNodeLTGData(node), np.int64)]

    def _seed_torsion(self):
        """After the state was re-read from mbs: continue every tracked torsion angle from
        the angle in its data node, as Exudyn does (the simulator restarts its tracking from
        the principal angle)."""
        tds = self.scene.torsionData
        if not tds:
            return
        sd = self.mbs.systemData
        data = np.asarray(sd.GetDataCoordinates(configuration=self._exu.ConfigurationType.Current), float)
        tphi = self.sim.wk.tphi
        for td in tds:
            prev = float(data[int(sd.GetNodeLTGData(td.dataNode)[0])])
            if td.spring is not None:
                target = prev - 2.0 * math.pi * td.turns0           # in the kernel's frame
                phi = float(tphi[td.spring])
                tphi[td.spring] = phi + 2.0 * math.pi * round((target - phi) / (2.0 * math.pi))
            else:
                td.item.prev = prev

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


def _check_index2_rotvec_constraints(mbs, typeName, settings):
    """Exudyn's index-2 solves (TrapezoidalIndex2, generalizedAlpha.useIndex2Constraints) hold a
    ConnectorCoordinate at velocity level, Exudyn's e_k: on a RotVecLG rotation coordinate that
    is omega_k = 0, another model than the position-level theta_k = const (index 3, Exudyn's
    default) that exudyn_lie integrates (mbs/node_coordinates.py).  Refused (reads only)."""
    from .evaluated import _describe_object, _rotvec_coordinate_marker
    if not (typeName == "TrapezoidalIndex2" or settings.timeIntegration.generalizedAlpha.useIndex2Constraints):
        return
    for o in range(mbs.systemData.NumberOfObjects()):
        d = mbs.GetObject(o)
        if d["objectType"] == "ConnectorCoordinate" and d.get("activeConnector", True) \
                and _rotvec_coordinate_marker(mbs, d):
            raise BridgeError(f"{_describe_object(mbs, o, d)}: on a rotation coordinate of a NodeRigidBodyRotVecLG, "
                              f"Exudyn's index-2 solve ({'TrapezoidalIndex2' if typeName == 'TrapezoidalIndex2' else 'generalizedAlpha.useIndex2Constraints=True'}) "
                              f"holds omega_k = 0, not the coordinate; exudyn_lie integrates the position-level "
                              f"(index-3) model: use Exudyn's default index-3 setting, or solve with exudyn.SolveDynamic")


@raised_at_boundary((SceneError, SimulationError))
def SolveDynamic(mbs, simulationSettings=None, solverType=None, updateInitialValues=False, storeSolver=True,
                 showHints=False, showCausingItems=True, autoAssemble=True, *, method=None, liegroup="auto",
                 stabilization="auto", projectInitial=True, verbose=False, showProgress=True, substeps=None,
                 accelerations=None, constraintTolerance=None, evaluation="auto", constraintCheck=True):
    """Drop-in for ``exudyn.SolveDynamic``: integrate ``mbs`` with an explicit Munthe-Kaas
    Lie group method inside Exudyn's time loop; returns True.

    The positional arguments are Exudyn's.  ``solverType`` (else
    ``timeIntegration.solverType``, as Exudyn reads them): an explicit type selects its
    tableau (RK44 -> RK4, ODE23 -> BS3, ...), GeneralizedAlpha is replaced by ``method``,
    TrapezoidalIndex2 too but with a warning, VelocityVerlet and DVERK6 are refused
    (:mod:`exudyn_lie.bridge.solvertype`); ``showHints`` / ``showCausingItems`` are accepted for
    compatibility.  Keyword-only extras: ``method`` (default RK4 or the explicit solverType's
    tableau; :func:`exudyn_lie.method_names` or a
    :class:`~exudyn_lie.integrators.ButcherTableau` of the user's own; it must agree with an
    explicit solverType),
    ``liegroup`` ('SE3', 'SO3xR3', 'auto' or {rigid-body object index: group}),
    ``stabilization`` (default 'auto': 'position' on the compiled path, so that joints hold
    to round-off as Exudyn's generalized-alpha holds them to its Newton tolerance; its cost:
    ``bench --sections stabilization``; None with ``constraintTolerance``, which projects by its own rule, and
    on the Exudyn-evaluated path, which does not project; None: the paper's unstabilised
    methods; 'velocity'), ``projectInitial`` (default True: an inconsistent initial state is
    projected onto the constraints with a warning; False: ConstraintError), ``verbose``
    (print the group per body, the plan and the time spent), ``showProgress`` (a progress line every 2 s on runs longer than about 4 s, with
    the time to go),
    ``substeps`` (internal steps per Exudyn step; default: one Exudyn step per output
    period), ``accelerations`` (write q_tt / multipliers; default: when something reads
    them), ``constraintTolerance`` (adaptive steps only; default None: off): project on the
    group when the constraint drift exceeds it, the error estimate projected onto the
    constraint manifold's tangent space (Simbody's scheme; docs/ADAPTIVE.md),
    ``evaluation`` ('auto': the compiled kernel when it has every item of the model,
    else Exudyn evaluates the whole model, :mod:`.evaluated_solve`, with one warning naming
    the items; 'compiled' / 'exudyn' force a path), ``constraintCheck`` (default True:
    Exudyn's own position-level residuals of the constraints at the outputs, within 2 % of
    the run's time (its set-up included) and always at the first and the last, with a tolerance of 1e-5 times the model's size; a residual above it that the integrator's own
    account does not explain stops the run with a ConstraintError naming the item, one it
    explains, the drift of an unstabilised method, is reported once per item as a warning;
    a float sets the tolerance in the rows' units, False switches the check off;
    :mod:`.constraint_check`).

    Honours ``timeIntegration.startTime / endTime / numberOfSteps``, sensors (stored and
    files), the solution and restart files, pre/post-step user functions,
    ``updateInitialValues`` and ``storeSolver`` (``mbs.sys['dynamicSolver']``,
    ``mbs.sys['lieGroupSolver']``).  ``simulationSettings`` is not changed, not even
    during the run (see :meth:`LieGroupSolver.Solve`).

    Bad input raises before ``mbs`` is touched: the arguments, the settings and the whole
    model (items, initial state, and with ``projectInitial=False`` the initial constraint
    consistency) are checked first; with
    ``autoAssemble`` and an mbs that is not assembled, the model is checked from its item
    dictionaries (what ``mbs.Assemble()`` will set) and only then assembled."""
    import exudyn as exu
    check_tolerance(constraintCheck)
    auto = stabilization == "auto"
    settings = exu.SimulationSettings() if simulationSettings is None else simulationSettings
    # solverType (argument, else the setting, as Exudyn reads them) -> the tableau (bridge/solvertype.py)
    method, typeName, replaced = resolve_solver_type(solverType, settings.timeIntegration.solverType, method,
                                                     _check_method)
    assemble = not mbs.systemIsConsistent and autoAssemble
    if evaluation not in ("auto", "compiled", "exudyn"):
        raise BridgeError(f"evaluation must be 'auto', 'compiled' or 'exudyn', got {evaluation!r}")
    scene = None                         # the model as the compiled reader read it (read once)
    if evaluation != "compiled":
        from .evaluated_dispatch import evaluated_path
        path, scene = evaluated_path(mbs, evaluation, assemble, method=method, liegroup=liegroup,
                                     stabilization=None if auto else stabilization, projectInitial=projectInitial,
                                     verbose=verbose, settings=settings, substeps=substeps)
        if path is not None:
            if constraintTolerance is not None:
                raise BridgeError("exudyn_lie.SolveDynamic: constraintTolerance is available on the compiled path only "
                                  "(adaptive steps); this model is evaluated by Exudyn: leave constraintTolerance=None")
            if replaced:
                warn_user(f"exudyn_lie.SolveDynamic: DynamicSolverType.{typeName} (Exudyn's implicit solver) is "
                          f"replaced, like GeneralizedAlpha, by the explicit Munthe-Kaas method {path.tableau.name}; "
                          f"method= or an explicit solverType chooses the method, liegroup= the groups")
            if assemble:
                warn_user("exudyn_lie.SolveDynamic: mbs is not assembled; calling mbs.Assemble()")
                mbs.Assemble()
            return path.Solve(simulationSettings, updateInitialValues=updateInitialValues, storeSolver=storeSolver,
                              showProgress=showProgress, substeps=substeps, accelerations=accelerations,
                              constraintCheck=constraintCheck)
    if auto:      # the drop-in holds joints as native does (README, "Options that matter")
        stabilization = None if constraintTolerance is not None else "position"
    solver = LieGroupSolver(mbs, method=method, liegroup=liegroup, stabilization=stabilization,
                            projectInitial=projectInitial, verbose=verbose, constraintTolerance=constraintTolerance,
                            _configuration="items" if assemble else "initial", _scene=scene)
    solver._check_run(settings, substeps)
    _check_index2_rotvec_constraints(mbs, typeName, settings)
    if replaced:
        groups = ", ".join(f"{g} ({solver.groups.count(g)})" for g in dict.fromkeys(solver.groups)) or "none"
        warn_user(f"exudyn_lie.SolveDynamic: DynamicSolverType.{typeName} (Exudyn's implicit solver) is replaced, "
                  f"like GeneralizedAlpha, by the explicit Munthe-Kaas method {solver.tableau.name} on the Lie "
                  f"groups {groups} (bodies per group); method= or an explicit solverType chooses the method, "
                  f"liegroup= the groups")
    if assemble:
        warn_user("exudyn_lie.SolveDynamic: mbs is not assembled; calling mbs.Assemble()")
        mbs.Assemble()
    return solver.Solve(simulationSettings, updateInitialValues=updateInitialValues, storeSolver=storeSolver,
                        showProgress=showProgress, substeps=substeps, accelerations=accelerations, refresh=assemble,
                        constraintCheck=constraintCheck)
