"""Compile a scene once, run it many times: the Munthe-Kaas driver.

>>> sim = Simulator(scene, method="RK4", liegroup="SE3")
>>> res = sim.Run(endTime=8.0, stepSize=1e-3, outputEvery=10)
>>> res.jointViolation[:, 0]       # position violation of joint 0 over time

The time loop runs inside numba (``stepper.mk_steps``) between output points, also for a
scene with Python force callbacks (called from the compiled stages, :mod:`.external`).
"""
from __future__ import annotations

import numpy as np

from ..compiling import announce_cold_compile
from ..errors import ConstraintError, SimulationError, StepSizeError  # noqa: F401 (re-exported)
from ..groups import so3
from ..integrators.tableau import resolve_pair
from . import external, kernel
from .rolling_disc_penalty_forces import D_DATA
from .force_elements import write_row
from .rotation_parameters import record_tracked, update_tracked_bodies
from .step_observers import observe_initial_state, observed_at_start
from .coordinate_forces import COORD_SPRING_FORCE
from .compiled import compile_carried, compile_scene, full_carried, make_work, resolve_groups
from .linalg import REL_PIVOT_TOL, rows_in_null_space, schur_rank_and_null
from .row_drives import RowDrives
from .scene import Scene, SceneError
from .state import BodyStates, twist_to_world_velocity, world_velocity_to_twist
from .stepper import fixed_step_control
from . import implicit_run
from .entry import call
from .clock import StepClock
from .rhs_address import EXT_RHS, keep_rhs_address
from .adaptive_run import AdaptiveRun
from .initial_state import RowLevels, check_initial_state, check_redundancy
from .outputs import Result, run  # noqa: F401 (Result re-exported)
from . import step_errors, stiffness
from .diagnostics import constraint_jacobian, joint_rows_at, joint_violations, momentum, schur_complement
from .external_seams import ExternalSeams


class Simulator(ExternalSeams):
    """Explicit Munthe-Kaas integration of a constrained rigid multibody scene.

    Parameters
    ----------
    scene : Scene
    method : name of a Butcher tableau (``exudyn_lie.integrators.method_names()``) or a
        :class:`~exudyn_lie.integrators.ButcherTableau` of the user's own
    liegroup : ``'SE3'``, ``'SO3xR3'``, ``'auto'``, a per-body mapping or sequence
    stabilization : None (the paper's choice: no stabilisation), ``'velocity'``
        (project V onto ``J V = 0`` after every step) or ``'position'`` (additionally
        project the configuration onto ``h(g) = 0`` on the group, then the velocity).
    projectInitial : project inconsistent initial positions/velocities onto the
        constraints instead of raising :class:`ConstraintError`.
    startTime : the time of the initial state (rows with a moving offset are checked
        against it; mbs/row_drives.py).
    """

    def __init__(self, scene: Scene, method="RK4", liegroup="SE3", stabilization=None,
                 projectInitial=False, verbose=False, startTime=0.0):
        if not isinstance(scene, Scene):
            raise SceneError(f"Simulator needs an exudyn_lie Scene, got {type(scene).__name__}")
        self.scene = scene
        scene.validate()
        announce_cold_compile(kernel.mk_steps)      # one line on the first run on a machine (numba compiles)
        self.tableau = resolve_pair(method)          # the catalogue, or an embedded pair by name (BS3, Vern6)
        self.groups = resolve_groups(scene, liegroup)
        if stabilization not in (None, "none", "velocity", "position"):
            raise ValueError(f"unknown stabilization {stabilization!r}; use None, 'velocity' or 'position'")
        self.stabilization = None if stabilization == "none" else stabilization
        self.verbose = verbose
        self.sd, self.rowJoint = compile_scene(scene, self.groups, self.stabilization, full=self.tableau.implicit)
        self._carried = compile_carried(scene, self.sd)     # track plan, path state, probes: kept by every Work
        self.method = implicit_run.method_arrays_of(self.tableau, self.sd.gid)
        implicit_run.apply_fallbacks(self)
        self.control = fixed_step_control()
        self._extViews = None
        self._extToken = (0 if not self.sd.hasQext else
                          external.register(self, "_external_rates" if self.rates else "_external_forces"))
        self._drives = RowDrives(scene, self.sd)      # rows with a moving offset (mbs/row_drives.py)
        self._driveToken = external.register(self, "_row_drives") if self._drives else 0
        self.wk = self._make_work()
        self.gid = self.sd.gid
        self.projectInitial = projectInitial
        self.redundantJoints = []
        self.startTime = float(startTime)
        self.SetInitialState(t0=self.startTime)
        self._check_redundancy()
        self._check_initial_consistency()
        if verbose:
            for i, b in enumerate(scene.bodies):
                print(f"exudyn_lie: body {i} ({b.name}): {self.groups[i]}")

    def SetMethod(self, method):
        """Integrate with ``method`` (a name or a tableau) from now on; state, path state and solve stay
        (adaptive steps: call :meth:`SetAdaptive` again)."""
        self.tableau = resolve_pair(method)
        if self.tableau.implicit:
            self._compile_full()
        self.method = implicit_run.method_arrays_of(self.tableau, self.sd.gid)
        implicit_run.apply_fallbacks(self)
        self.wk = self._make_work()        # (a new Work keeps the path state: compile_carried)
        self._ad = None

    def _compile_full(self):
        """A lean scene full (ARCHITECTURE.md, "Lean scenes"): the full compile's tables where the lean SceneData
        has None, its own arrays else (loads and rows written since stay); state, path and solve stay."""
        if self.sd.rowsAll is None:
            full = compile_scene(self.scene, self.groups, self.stabilization, full=True)[0]
            self.sd = self.sd._replace(**{f: getattr(full, f) for f in self.sd._fields if getattr(self.sd, f) is None})
            self._carried = full_carried(self._carried)
            self.wk = self._make_work()

    @property
    def newtonCounters(self):
        """An implicit method's Newton work so far (``{'jacobians', 'factorizations', 'iterations', 'stages',
        'retries', 'fullNewton'}``; None for an explicit one)."""
        return implicit_run.newton_counters_of(self)

    def _make_work(self, solve="auto"):
        """New work arrays (``compiled.make_work``; ``solve``: see ``compiled.solve_plan``), with room for an
        embedded pair's dense-output extra stages.  Their types may differ from the old ones (the tree
        solve's plan is None for the band solve): the resolved compiled entry points go with them."""
        dense = self.tableau.dense
        extra = dense.extra_stages if (dense is not None and self.tableau.b_hat is not None) else 0
        wk = make_work(self.sd, len(self.method.b) + extra, solve, self._carried)
        wk.ext[0] = external.handle(self._extToken) if self._extToken else 0
        if self._driveToken:
            wk = wk._replace(drive=np.array([external.handle(self._driveToken)], np.int64))
        if self.tableau.implicit or getattr(self, "_ad", None) is not None:     # (mbs/rhs_address.py)
            keep_rhs_address(self.sd, wk)
        self._entries = {}
        return wk

    # ----------------------------------------------------------------- state
    def SetInitialState(self, R=None, r=None, omega=None, vel=None, t0=0.0):
        """Set the state from the scene's initial data (or the given arrays).  Everything
        is validated before anything is assigned, so a rejected call changes nothing."""
        sc = self.scene
        nb = len(sc.bodies)
        R = np.array([b.R0 for b in sc.bodies]) if R is None else np.asarray(R, float)
        r = np.array([b.r0 for b in sc.bodies]) if r is None else np.asarray(r, float)
        om = np.array([b.omega0 for b in sc.bodies]) if omega is None else np.asarray(omega, float)
        ve = np.array([b.vel0 for b in sc.bodies]) if vel is None else np.asarray(vel, float)
        for name, x, shape in (("R", R, (nb, 3, 3)), ("r", r, (nb, 3)), ("omega", om, (nb, 3)),
                               ("vel", ve, (nb, 3))):
            if x.shape != shape:
                raise SceneError(f"initial state {name} must have shape {shape}, got {x.shape}")
            if not np.all(np.isfinite(x)):
                bad = int(np.argwhere(~np.isfinite(x.reshape(nb, -1)))[0][0])
                raise SceneError(f"initial state {name} of {sc.describe_body(bad)} is not finite")
        for i in range(nb):
            if np.linalg.norm(R[i].T @ R[i] - np.eye(3)) > 1e-8 or np.linalg.det(R[i]) <= 0:
                raise SceneError(f"initial state R of {sc.describe_body(i)} is not a proper "
                                 f"rotation matrix (R^T R != I or det <= 0)")
        if not np.isfinite(t0):
            raise SceneError(f"initial time t0 = {t0} is not finite")
        self.R = np.ascontiguousarray(R).copy()
        self.r = np.ascontiguousarray(r).copy()
        self.V = np.ascontiguousarray(world_velocity_to_twist(self.gid, self.R, om, ve))
        self.t = float(t0)
        self._segmentStart = (self.t, self.R.copy(), self.r.copy(), self.V.copy())
        if len(sc.torsionalSprings):
            self.wk.path.torsionAngles[:] = 0.0
        for k, e in enumerate(sc.rollingDiscPenalties):     # data coordinates: as given
            self.wk.path.rollingDiscs[k, D_DATA:] = e.data0
        # the tracked angles (torsional springs, rotation coordinates, 2D bodies) at this state
        self._update_tracking()

    def _update_tracking(self):
        """The step observers that are set at an initial state (``step_observers.atStart``), at
        the current state.  A scene without any does not load that compiled entry point at
        all (its cache load and first-call typing are part of a warm first solve)."""
        sd, wk = self.sd, self.wk
        present = observed_at_start(sd, wk)
        if present == ["trackedBodies"]:
            # its update alone: the step loop's own callee, so a first run compiles no
            # separate entry taking the SceneData / Work tuples for it
            update_tracked_bodies(wk.track.trackCodes, wk.track.angleFrames, wk.path.bodyAngles,
                                  wk.path.bodyParameters, self.R)
        elif present:
            observe_initial_state(sd, wk, self.R, self.r, self.V)

    def states(self):
        omega, vel = twist_to_world_velocity(self.gid, self.R, self.V)
        return BodyStates(self.t, self.R.copy(), self.r.copy(), omega, vel)

    def WatchRotationEntries(self, bodies, i, j):
        """Monitor ``|R[b][i, j]|`` of the given bodies at every accepted step (e.g. the
        sine of the middle Tait-Bryan angle, entry (0, 2), between output points).  The
        running maxima are in :attr:`watchedMaxima`; :meth:`ResetWatch` clears them."""
        b = np.asarray(bodies, np.int64).reshape(-1)
        if len(b) and (b.min() < 0 or b.max() >= self.sd.nb):
            raise SceneError(f"WatchRotationEntries: body indices {b.tolist()} out of range 0..{self.sd.nb - 1}")
        if not (0 <= int(i) < 3 and 0 <= int(j) < 3):
            raise SceneError(f"WatchRotationEntries: entry ({i}, {j}) is not in a 3x3 matrix")
        entry = np.tile(np.array([[int(i), int(j)]], np.int64), (len(b), 1))
        c = self._carried
        self._carried = c._replace(track=c.track._replace(watchBody=b.copy(), watchEntry=entry),
                                   path=c.path._replace(watchMax=np.zeros(len(b))))
        self.wk = self.wk._replace(track=self._carried.track, path=self._carried.path)
        if self.wk.ext[EXT_RHS]:
            keep_rhs_address(self.sd, self.wk)
        self._entries = {}
        self.ResetWatch()

    @property
    def watchedMaxima(self):
        return self.wk.path.watchMax

    def ResetWatch(self):
        """Restart the watched maxima from the current state."""
        for w, b in enumerate(self.wk.track.watchBody):
            self.wk.path.watchMax[w] = abs(self.R[b, self.wk.track.watchEntry[w, 0], self.wk.track.watchEntry[w, 1]])

    # ----------------------------------------------------------------- constraints
    def jacobian(self, R=None, r=None, V=None):
        """(h, J, eta) at a state (at the time ``self.t``); J is dense (m, 6 nb) in the group
        velocity coordinates."""
        self._drives_at(self.t)
        return constraint_jacobian(self.sd, self.wk, self.R if R is None else R,
                                   self.r if r is None else r, self.V if V is None else V)

    def _joints_of_rows(self, rows):
        names = []
        for q in rows:
            j = self.scene.joints[int(self.rowJoint[q])]
            if j.name not in names:
                names.append(j.name)
        return names

    def _dependent_rows(self, R, r, V, forced=False):
        """``(rank, rows)``: the numerical rank of the constraints at the state (R, r, V)
        and the rows taking part in their linear dependencies, by the one rank rule of
        the kernel (:mod:`exudyn_lie.mbs.linalg`): Cholesky pivots of ``S = J M^-1 J^T``
        at or below ``REL_PIVOT_TOL`` times their row's diagonal; the rows are the support
        of the numerical null space of the Jacobi-scaled S (= that of J^T).  ``forced``: the kernel's band
        Cholesky met the rule at this state (then at least one dependency is named)."""
        if self.sd.nrows == 0:
            return 0, []
        h, S = schur_complement(self.sd, self.wk, R, r, V)
        rank, null = schur_rank_and_null(S, REL_PIVOT_TOL, forced=forced)
        return rank, rows_in_null_space(null)

    def _check_redundancy(self):
        """Redundant rows switch the kernel to its rank-revealing solve (:func:`.initial_state.check_redundancy`)."""
        check_redundancy(self)

    def _residuals_and_JV(self):
        """h(g, t) and J V - w(t) at the current state, row by row (``w``: the rows' drives, mbs/row_drives.py)."""
        return self.RowResiduals(self.R, self.r, self.V, self.t)

    def RowResiduals(self, R, r, V, t):
        """``(h, J V - w)``: every constraint row's position residual and velocity residual
        at the state ``(R, r, V)`` and time ``t`` (``w`` the velocity targets of the rows'
        moving offsets), in the kernel's row order (``rowJoint`` gives each row's joint)."""
        sd, wk = self.sd, self.wk
        self._drives_at(t)
        joint_rows_at(sd, wk, np.ascontiguousarray(R, dtype=float), np.ascontiguousarray(r, dtype=float),
                      np.ascontiguousarray(V, dtype=float), wk.h, wk.Jr, wk.eta)
        V = np.asarray(V, dtype=float)
        Vz = np.vstack([V, np.zeros((1, 6))])          # row -1: the ground
        a = sd.rowIndex[:, kernel.ROW_BODY_A]
        b = sd.rowIndex[:, kernel.ROW_BODY_B]
        JV = np.einsum("qk,qk->q", wk.Jr[:, :6], Vz[a]) + np.einsum("qk,qk->q", wk.Jr[:, 6:], Vz[b])
        return wk.h.copy(), JV - wk.rdrive[1]

    def _check_initial_consistency(self):
        """Raise for an inconsistent initial state, or (``projectInitial``) project it onto the constraints
        (:func:`.initial_state.check_initial_state`); ``self.initialProjection``: what was corrected (joints,
        residuals, size of the correction), None if nothing."""
        self.initialProjection = None
        if self.sd.nrows == 0:
            return
        R0, r0, V0 = self.R.copy(), self.r.copy(), self.V.copy()
        fixed = check_initial_state(RowLevels(self), self.projectInitial)
        if not fixed:
            return
        p = {}
        for level, rows, residual in fixed:
            key = "position" if level == "positions" else "velocity"
            p[f"{key}Joints"] = self._joints_of_rows(rows)
            p[f"max{key.capitalize()}Residual"] = residual
        p["maxPositionChange"] = float(np.max(np.linalg.norm(self.r - r0, axis=1)))
        p["maxRotationChange"] = float(max(np.linalg.norm(so3.log(R0[i].T @ self.R[i])) for i in range(len(self.R))))
        om0, ve0 = twist_to_world_velocity(self.gid, R0, V0)      # body-fixed omega, world velocity
        om1, ve1 = twist_to_world_velocity(self.gid, self.R, self.V)
        p["maxAngularVelocityChange"] = float(np.max(np.linalg.norm(om1 - om0, axis=1)))
        p["maxVelocityChange"] = float(np.max(np.linalg.norm(ve1 - ve0, axis=1)))
        self.initialProjection = p

    CheckInitialState = _check_initial_consistency

    @property
    def hasRowDrives(self):
        """True if rows have a moving offset (mbs/row_drives.py): then the initial check
        depends on the time (``CheckInitialState`` after setting ``t``)."""
        return bool(self._drives)

    def describe_initial_projection(self):
        """One sentence on the correction ``projectInitial`` made (None if none was made)."""
        p = self.initialProjection
        if not p:
            return None
        parts = []
        if "positionJoints" in p:
            parts.append(f"positions of joints {', '.join(p['positionJoints'])} (max |h| = "
                         f"{p['maxPositionResidual']:.3g}): bodies moved by up to {p['maxPositionChange']:.3g} m "
                         f"and turned by up to {p['maxRotationChange']:.3g} rad")
        if "velocityJoints" in p:
            parts.append(f"velocities of joints {', '.join(p['velocityJoints'])} (max |J V| = "
                         f"{p['maxVelocityResidual']:.3g}): velocities changed by up to "
                         f"{p['maxVelocityChange']:.3g} m/s and {p['maxAngularVelocityChange']:.3g} rad/s")
        return "; ".join(parts)

    def ProjectVelocities(self):
        """Mass-orthogonal projection of V onto J V = 0 (compiled, banded)."""
        self._project(kernel.STAB_VELOCITY)

    def ProjectPositions(self):
        """Project the configuration onto h(g) = 0 on the group (Gauss-Newton steps
        ``g <- g exp(-M^-1 J^T (J M^-1 J^T)^-1 h)``, J being the derivative of h along the
        left-trivialised perturbation g exp(delta) in each body's group), then the
        velocities onto J V = 0."""
        self._project(kernel.STAB_POSITION)

    def _project(self, level):
        self._drives_at(self.t)
        st = kernel.project_state(self.sd, self.wk, level, self.R, self.r, self.V)
        if st != kernel.STATUS_OK:
            self._raise_status(st, 0.0)

    # ----------------------------------------------------------------- stepping
    @property
    def vmax(self):
        """A velocity bound far beyond any physical motion of this scene (10^6 times the
        velocities when first asked for), then fixed: used only to stop a blowing-up
        integration before it produces inf/NaN."""
        if not hasattr(self, "_vmaxValue"):
            v0 = float(np.max(np.abs(self.V))) if self.V.size else 0.0
            self._vmaxValue = 1e6 * max(1.0, v0)
        return self._vmaxValue

    def Advance(self, nsteps, stepSize):
        """Integrate ``nsteps`` steps of size ``stepSize`` from the current state.

        On a failure (singular constraints, blow-up, a stage rotation |Psi_j| beyond
        ``kernel.STAGE_ARG_MAX`` (2 pi (1 - sqrt(eps)) = 2 pi - 9.4e-8), where dexp^-1 of the stage equation nears
        its singularity at 2 pi) the state is left at the last accepted step and the error
        says where and what to do."""
        h = float(stepSize)
        if not np.isfinite(h) or h <= 0:
            raise ValueError(f"step size must be positive and finite, got {stepSize}")
        if nsteps <= 0:
            return
        # the state this call starts from: restored on failure, and where a blow-up's
        # step suggestion linearises (the rejected state itself is far from the motion)
        self._segmentStart = (self.t, self.R.copy(), self.r.copy(), self.V.copy())
        st = implicit_run.advance(self, int(nsteps), h)     # (an implicit step that fails, in parts)
        if st != kernel.STATUS_OK:
            self._raise_status(st, h)

    #: steps done in parts so far (implicit methods, fixed steps: implicit_run.substeps)
    dividedSteps = 0
    #: the parts a fixed implicit step whose Newton iteration fails is tried in, in turn
    #: (:meth:`SetNewtonFallbacks`)
    newtonSubsteps = implicit_run.SUBSTEPS

    def SetNewtonFallbacks(self, on):
        """Whether an implicit stage whose simplified Newton iteration fails is solved by Newton's own
        iteration (a Jacobian at every iterate), and a fixed step that still fails is done again in
        parts (``implicit_run.SUBSTEPS``), as by default.  Off: the step fails at once with a
        StepSizeError whose ``newton`` is True, for a caller that reduces its steps itself and
        updates what the right-hand side holds fixed between them (the bridge's evaluated path)."""
        self.newtonSubsteps = implicit_run.SUBSTEPS if on else ()
        implicit_run.apply_fallbacks(self)

    def NoOutputs(self):
        """``mk_steps``' output arguments recording nothing: ``(0, Ro, ro, Vo, Po, Vdo, lamo)`` with no rows."""
        out = getattr(self, "_noOutputs", None)
        if out is None:
            nb, m = self.sd.nb, self.sd.nrows
            out = self._noOutputs = (0, np.zeros((0, nb, 3, 3)), np.zeros((0, nb, 3)), np.zeros((0, nb, 6)),
                                     np.zeros((0, nb, 4)), np.zeros((0, nb, 6)), np.zeros((0, m)))
        return out

    # the time: an origin plus whole steps (mbs/clock.py); setting it starts a new origin
    t = property(lambda self: self._clock.t, lambda self, t: setattr(self, "_clock", StepClock(t)))

    def _mk_steps(self, n, h, t=None, R=None, r=None, V=None):
        """``stepper.mk_steps`` through its resolved entry point (a plain call re-types the tuples, ~10 us);
        steps from the current time (``t`` None) take their times from the clock, which the caller advances."""
        t0, k0 = self._clock.start(h) if t is None and n > 0 else (float(self.t if t is None else t), 0)
        args = (self.sd, self.wk, self.method, self.control, t0, k0, float(h), int(n),
                self.R if R is None else R, self.r if r is None else r, self.V if V is None else V,
                float(self.vmax)) + self.NoOutputs()
        return call(self._entries, "fixed", kernel.mk_steps, args)
    def _raise_status(self, st, h):
        """Raise the error for a kernel status (public as :meth:`RaiseStatus`; mbs/step_errors.py)."""
        step_errors.raise_status(self, st, h)

    RaiseStatus = _raise_status

    def StageStiffness(self, h, nb=None):
        """Shampine's estimate of the fastest rate the last fixed step ``h`` met (:func:`.stiffness.stage_stiffness_of`)."""
        return stiffness.stage_stiffness_of(self, h, nb)

    def suggest_step(self, h):
        """A step size that should be stable (:func:`.stiffness.suggest_step`)."""
        return stiffness.suggest_step(self, h)

    def SpectralRadius(self, R=None, r=None, V=None, t=None, iterations=40, seed=0):
        """The linearised equations' spectral radius at a state (:func:`.stiffness.spectral_radius`)."""
        return stiffness.spectral_radius(self, R, r, V, t, iterations, seed)

    # ----------------------------------------------------------------- rows and tracked state (the bridge's API)
    nRows = property(lambda self: int(self.sd.nrows), doc="Number of constraint rows.")

    hasRedundantRows = property(lambda self: bool(self.sd.redundant),
                                doc="True if the constraints were found redundant (the rank-revealing solve runs).")

    @property
    def hasPythonStage(self):
        """True if every stage calls Python (forces or the whole right-hand side)."""
        return self.sd.hasQext != kernel.EXTERNAL_NONE

    def JointRows(self, j):
        """The kernel's rows of scene joint ``j`` (a range)."""
        r0, n = (int(x) for x in self.sd.jointIndex[j, 2:4])
        return range(r0, r0 + n)

    def TrackedParameters(self, out):
        """The angles and node rotation parameters tracked per body (nb, 4) into ``out``
        (mbs/rotation_parameters.py: what a write-back of node coordinates continues from)."""
        record_tracked(self.wk.track.trackCodes, self.wk.path.bodyAngles, self.wk.path.bodyParameters, out)

    def SetTrackedParameters(self, body, p):
        """Continue the tracked node rotation parameters of ``body`` from ``p`` (4)."""
        self.wk.path.bodyParameters[body] = p

    def TorsionAngle(self, k):
        """The tracked angle (turns included) of compiled torsional spring ``k``."""
        return float(self.wk.path.torsionAngles[k])

    def SetTorsionAngle(self, k, phi):
        self.wk.path.torsionAngles[k] = phi

    def SetContactData(self, k, data):
        """The data coordinates (stored slip, gap) of penalty rolling disc ``k``."""
        self.wk.path.rollingDiscs[k, D_DATA:] = data

    def SetProbeRow(self, i, row):
        """Row ``i`` of the Python items' probes (mbs/external_probes.py) after an item changed."""
        self.wk.probe[i] = row

    def LoadRow(self, k):
        """Writable views ``(vector, point, flags)`` of compiled load ``k`` (``SceneData.loadVectors``,
        ``loadIndex``: body, force / torque, bodyFixed); a value written takes effect at the next
        stage (a controller that sets a load every step writes here without a call)."""
        return self.sd.loadVectors[k, 0], self.sd.loadVectors[k, 1], self.sd.loadIndex[k]

    def WriteElementRow(self, element, scene, k, item):
        """Rewrite row ``k`` of a registered force element from a changed scene item
        (:func:`.force_elements.write_row`)."""
        write_row(element, scene, self.sd, self.wk, k, item)

    def SetCoordinateSpringForce(self, k, force):
        """The constant force of coordinate spring row ``k`` (a coordinate load on a node
        rotation parameter is such a row: force ``-load``)."""
        self.sd.coordSpringLaw[k, COORD_SPRING_FORCE] = force

    def Accelerations(self):
        """``(Vdot, lambda)`` at the current state (eq. index1): Vdot (nb, 6) in the group velocity coordinates."""
        st = self._evaluate(self.t, self.R, self.r, self.V)
        if st != kernel.STATUS_OK:
            self._raise_status(st, 0.0)
        return self.wk.Vd[0].copy(), self.wk.lam.copy()

    def _evaluate(self, t, R, r, V):
        """Equations of motion at one state (``mk_steps`` with no step) into ``wk.Vd[0]``, ``wk.lam``; a status."""
        st, _ = self._mk_steps(0, 0.0, t, R, r, V)
        return st

    # ----------------------------------------------------------------- diagnostics
    def Diagnostics(self, R=None, r=None, V=None, t=None):
        """(energy[3], residuals[m], joint position violation[nj], joint rotation violation[nj])
        at the current state (or at ``R, r, V``), the rows' moving offsets at ``t`` (default: the
        current time)."""
        e, h, wk = np.zeros((1, 3)), np.zeros((1, self.sd.nrows)), self.wk
        self._drives_at(self.t if t is None else t)
        one = lambda x, y: np.ascontiguousarray(x if y is None else y, dtype=float)[None]
        kernel.all_rows(self.sd, wk, one(self.R, R), one(self.r, r), one(self.V, V), h, wk.Jr, wk.eta, e)
        return (e[0], h[0]) + self.JointViolations(h[0])

    def JointViolations(self, h):
        """(position, rotation) violation of every joint, ``(..., nj)``, from the residuals ``h`` (..., m)."""
        return joint_violations(h, self.rowJoint, self.sd.rowIndex[:, kernel.ROW_KIND] == kernel.ROW_ROT,
                                len(self.scene.joints))

    def Momentum(self):
        """(linear momentum, angular momentum about the world origin), world frame."""
        return momentum(self.scene.bodies, self.gid, self.R, self.r, self.V)

    # ----------------------------------------------------------------- adaptive steps
    def SetAdaptive(self, rtol=1e-3, atol=1e-6, maxStep=np.inf, minStep=0.0, firstStep=None, safety=0.9,
                    maxIncrease=10.0, lengthScale=1.0, timeScale=1.0, constraintTolerance=None, acceptAtMinStep=False):
        """Prepare adaptive steps of the embedded pair (:mod:`.adaptive`) with the scaled
        error ``atol + rtol * size`` per physical kind (``integrators/control.py``: angles
        atol [rad], lengths atol L, angular velocities atol / T, velocities atol L / T with
        ``lengthScale`` L, ``timeScale`` T), the PI controller (safety factor ``safety``,
        growth per step at most ``maxIncrease``), steps in ``[minStep, maxStep]`` and the
        first step ``firstStep`` (None: Hairer's HINIT).  ``constraintTolerance`` (None: off),
        separate from the accuracy tolerances as in Simbody: after an accepted step whose
        constraint residual max |h(g)| exceeds it the state is projected on the group
        (positions, then velocities), and when max |J V| exceeds ``constraintTolerance / T``
        the velocities; the error estimate of every step is projected onto the tangent space of
        the constraint manifold (docs/ADAPTIVE.md, "Constraint tolerance").  The next
        :meth:`AdvanceTo` starts afresh from the current state.  ``acceptAtMinStep``: a step of
        ``minStep`` is accepted beyond the tolerance instead of stopping (``integrators/control.py``)."""
        self._compile_full()
        self._ad = AdaptiveRun(self, rtol, atol, maxStep, minStep, firstStep, safety, maxIncrease, lengthScale,
                               timeScale, constraintTolerance, acceptAtMinStep)

    @property
    def adaptiveRun(self):
        """The :class:`~.adaptive_run.AdaptiveRun` of the last :meth:`SetAdaptive` (None before)."""
        return getattr(self, "_ad", None)

    def RestartAdaptive(self):
        """Start the adaptive integration afresh at the next :meth:`AdvanceTo` (a new first
        step, no FSAL reuse): after the state was changed from outside."""
        if getattr(self, "_ad", None) is not None:
            self._ad.restart()

    def AdvanceTo(self, endTime, outputTimes=None):
        """Adaptive steps (after :meth:`SetAdaptive`) from the current time to ``endTime``
        (the last step clipped to it), with the states at ``outputTimes`` (sorted, in
        ``[t, endTime]``) by dense output on the group: the call returns once every output
        is written (the state may then be up to one step ahead of the last output).
        Returns ``(R, r, V)`` at the output times.  A step below the minimum raises
        :class:`StepSizeError` with ``.time`` and ``.step``; the state then is the last
        accepted step."""
        tout = np.ascontiguousarray(np.zeros(0) if outputTimes is None else outputTimes, dtype=np.float64)
        nb = self.sd.nb
        Ro, ro, Vo = np.zeros((tout.size, nb, 3, 3)), np.zeros((tout.size, nb, 3)), np.zeros((tout.size, nb, 6))
        st, k = self.AdvanceToInto(endTime, tout, Ro, ro, Vo)
        if st != kernel.STATUS_OK:
            self._raise_status(st, self._ad.step)
        return Ro[:k], ro[:k], Vo[:k]

    def AdvanceToInto(self, endTime, tout, Ro, ro, Vo, Po=None):
        """:meth:`AdvanceTo` writing into the given output rows (``Po``: also the tracked
        angles / node rotation parameters, mbs.rotation_parameters); returns ``(kernel status,
        outputs written)`` without raising for a failure (:meth:`RaiseStatus` does)."""
        ad = getattr(self, "_ad", None)
        if ad is None:
            raise RuntimeError("AdvanceTo needs SetAdaptive(rtol=..., atol=...) first")
        return ad.advance_into(endTime, tout, Ro, ro, Vo, Po)

    @property
    def adaptiveCounters(self):
        """(accepted steps, rejected steps, right-hand-side evaluations) since SetAdaptive
        or the last restart (HINIT's two evaluations and the dense extra stages included)."""
        return self._ad.counters

    @property
    def constraintProjections(self):
        """Projections the constraint tolerance triggered since SetAdaptive or the last restart."""
        return self._ad.projections

    def Run(self, endTime, stepSize=None, outputEvery=1, startTime=None, progress=False, *, rtol=None, atol=None,
            outputTimes=None, maxStep=None, minStep=0.0, firstStep=None, constraintTolerance=None):
        """Integrate from the current state to ``endTime``; returns a :class:`Result`.

        Fixed steps (the default): ``stepSize``, with ``outputEvery`` steps between stored
        outputs (diagnostics are evaluated there).

        Adaptive steps, in scipy's style, when ``rtol`` or ``atol`` is given (an embedded
        pair: DOPRI5, BS3 = ODE23, Vern6; scipy's defaults rtol = 1e-3, atol = 1e-6 for the
        one not given): error control on the group (:mod:`.adaptive`), steps in
        ``[minStep, maxStep]`` (default ``[0, endTime - startTime]``), first step
        ``firstStep`` (default: HINIT).  Outputs at ``outputTimes``, or else every
        ``stepSize * outputEvery`` (if ``stepSize`` is given; it does not bound the steps)
        and at ``endTime``, by dense output: exact times, no step shortened.  The result
        has ``steps`` (accepted), ``rejectedSteps`` and ``rhsEvaluations``; its
        ``stepSize`` is the first step.  ``constraintTolerance`` (adaptive steps only):
        projection on the group when the constraint drift exceeds it
        (:meth:`SetAdaptive`; ``Result.constraintProjections`` counts them).
        :func:`.outputs.run` is the loop."""
        return run(self, endTime, stepSize, outputEvery, startTime, progress, rtol=rtol, atol=atol,
                   outputTimes=outputTimes, maxStep=maxStep, minStep=minStep, firstStep=firstStep,
                   constraintTolerance=constraintTolerance)
