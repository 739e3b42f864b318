"""``SolveDynamic`` on the Exudyn-evaluated path: Exudyn evaluates the whole model
(:mod:`.evaluated`), exudyn_lie integrates it with the Munthe-Kaas method of the one
compiled stepper (:mod:`.evaluated_problem`: the model is the right-hand side of a
:class:`~exudyn_lie.mbs.Simulator`), inside Exudyn's own time loop (as the compiled path,
:mod:`.solver`): sensors, solution and restart files, pre/post-step user functions and the
renderer work as in a native solve.

Per Exudyn step the hook (``SetUserFunctionNewton``) advances one MK step (``substeps=k``:
``k``, for models without data coordinates; with adaptive steps, as many as the error control
needs, the last one ending at the Exudyn step's time) and writes
the end state (and, if something reads them, the accelerations and multipliers) into mbs'
Current configuration.  Between the stages of a step only the ODE2 / ODE1 coordinates and
the time change; data coordinates (contact states, friction, switching) keep their values
from the start of the step, as in Exudyn's own explicit solvers.  After the hook Exudyn runs
``PostNewton`` (its discontinuous iteration): it updates the data coordinates from the end
state and, if their error exceeds ``timeIntegration.discontinuous.iterationTolerance``, resets
the coordinates to the start of the step and calls the hook again; the hook then restarts
the step from its saved start state, now with the updated data coordinates (docs/EVALUATED.md).

Parameters changed by user functions need nothing here: Exudyn reads them itself at the
next evaluation.  A pre-step user function that changes the coordinates is seen (the hook
compares mbs' coordinates with those it wrote) and the run continues from them.
"""
from __future__ import annotations

import time

import numpy as np

from ..userwarn import warn_user
from .evaluated import EvaluatedModel, Layout
from .evaluated_items import check_model, constant_mass_matrix, parameter_offset_rows
from .moving_offsets import ParameterOffsets
from .params import MainSystemPatch
from .evaluated_problem import EvaluatedProblem
from .evaluated_initial import describe_rows, project_initial
from .evaluated_projection import StepProjection
from .evaluated_stiffness import KRYLOV_NOTE, check_step, choice_step
from .method_choice import auto_choice_text, stiff_choice, unstable_choice
from ..errors import StepSizeError, step_size_error
from ..mbs.codes import STATUS_BLOWUP
from .constraint_check import ConsistencyAccount, ConstraintCheck, check_tolerance
from .general_contact import general_contacts, use_full_search
from .reader import (EVALUATED_MBS_FUNCTIONS, UNHONOURED_MBS_FUNCTIONS, BridgeError, check_system_level,
                     mbs_user_function)
from .run_plan import adaptive_settings, needs_accelerations, plan_substeps, time_settings
from .solver import loop_settings
from .time_loop import NewtonFailed, TimeLoop, off_plan, update_initial_values

#: mbs-level user functions this path cannot honour (none of Exudyn's today: EVALUATED_MBS_FUNCTIONS)
UNHONOURED_HERE = {k: v for k, v in UNHONOURED_MBS_FUNCTIONS.items() if k not in EVALUATED_MBS_FUNCTIONS}
#: time of a stage measured at the start, per coordinate row (for the announced estimate)
ESTIMATE_EVALUATIONS = 5


def node_groups(mbs, liegroup):
    """Group of every NodeRigidBodyRotVecLG node: ``liegroup`` 'SE3' / 'SO3xR3' for all; a
    mapping {ObjectRigidBody index: group} for those bodies' nodes; 'auto' (and nodes not in
    the mapping): SO3xR3 for the node of an ObjectRigidBody whose frame is at its COM and
    that no connector or constraint acts on (only loads), SE3 for every other node (as the
    compiled path's ``auto_groups``).  Returns ({node: group}, {node: reason})."""
    sd = mbs.systemData
    lg = [n for n in range(sd.NumberOfNodes()) if mbs.GetNode(n)["nodeType"] == "RigidBodyRotVecLG"]
    bodyOfNode, comAtNode = {}, {}
    for o in range(sd.NumberOfObjects()):
        d = mbs.GetObject(o)
        if d["objectType"] == "RigidBody":
            n = int(d["nodeNumber"])
            bodyOfNode[n] = o
            comAtNode[n] = not np.any(np.asarray(d.get("physicsCenterOfMass", [0, 0, 0]), float))
    # nodes / bodies some marker of a connector or constraint refers to
    tied = set()
    markerTarget = {}
    for m in range(sd.NumberOfMarkers()):
        d = mbs.GetMarker(m)
        markerTarget[m] = (("node", int(d["nodeNumber"])) if "nodeNumber" in d else
                           ("object", int(d["bodyNumber"])) if "bodyNumber" in d else None)
    for o in range(sd.NumberOfObjects()):
        d = mbs.GetObject(o)
        if "markerNumbers" in d:
            for m in d["markerNumbers"]:
                tgt = markerTarget.get(int(m))
                if tgt is not None:
                    tied.add(tgt)
        for key in ("nodeNumbers",):
            if key in d and d["objectType"] != "RigidBody":
                for n in d[key]:
                    tied.add(("node", int(n)))
    groups, why = {}, {}
    for n in lg:
        o = bodyOfNode.get(n)
        free = o is not None and comAtNode[n] and ("node", n) not in tied and ("object", o) not in tied
        groups[n] = "SO3xR3" if free else "SE3"
        why[n] = "auto: unconstrained, frame at COM" if free else (
            "auto: not an ObjectRigidBody's node" if o is None else
            "auto: " + ("constrained by joints/connectors" if not free and comAtNode[n] else "frame off the COM"))
    if isinstance(liegroup, str) and liegroup != "auto":
        for n in lg:
            groups[n], why[n] = liegroup, "all nodes"
    elif isinstance(liegroup, dict):
        nodeOfBody = {o: n for n, o in bodyOfNode.items()}
        for o, g in liegroup.items():
            if o not in nodeOfBody:
                raise BridgeError(f"liegroup mapping: object {o} is not an ObjectRigidBody on a NodeRigidBodyRotVecLG "
                                  f"of this mbs (such bodies: objects {sorted(nodeOfBody)})")
            groups[nodeOfBody[o]], why[nodeOfBody[o]] = g, "given"
    return groups, why


def check_system(mbs):
    """:func:`.reader.check_system_level` with what this path honours itself (a
    PostNewtonUserFunction: Exudyn calls it after every step; GeneralContact: bridge/general_contact.py)."""
    check_system_level(mbs, UNHONOURED_HERE, generalContact=True)


class EvaluatedSolver:
    """Integrate any Exudyn model that Exudyn can evaluate with explicit Munthe-Kaas
    methods: Exudyn computes M, f, C_q and the velocity-level constraints at every stage.

    ``liegroup``, ``method`` (a ButcherTableau), ``verbose`` as for
    :class:`~.solver.LieGroupSolver`; ``reasons``: the items that force this path (for the
    one warning; None when the user chose the path)."""
    pathName = "evaluated"         # as solve_timing reports it

    def __init__(self, mbs, tableau, liegroup="auto", verbose=False, reasons=None, projectInitial=True,
                 autoImplicit=False, stabilization="position"):
        self.mbs = mbs
        self.stabilization = None if stabilization == "none" else stabilization    # bridge/evaluated_projection.py
        self.autoImplicit = bool(autoImplicit) and not tableau.implicit     # bridge/method_choice.py
        self._explicit = tableau
        self.projectInitial = bool(projectInitial)
        self.tableau = tableau
        self.liegroup = liegroup
        self.verbose = bool(verbose)
        self.reasons = reasons
        check_system(mbs)
        check_model(mbs)
        self.timing = {}
        self._marks = []                         # objects changed during the loop (loop_context)
        self._takeOver = None                    # the time this driver took over a run (hand_over_from)

    def check_run(self, ss, substeps):
        """Raise for settings this path refuses (changes nothing)."""
        nsteps, t0, tEnd, h = time_settings(ss)
        k, _ = plan_substeps(self.mbs, ss, nsteps, h, substeps)
        if adaptive_settings(self.tableau, ss, h) is not None and substeps is not None and k > 1:
            raise BridgeError(f"substeps={substeps}: with adaptive steps the error control chooses the steps "
                              f"within each Exudyn step; use substeps=None or 1")

    def _post_newton_items(self):
        """What needs Exudyn's PostNewton after every MK step (one MK step per Exudyn step):
        data coordinates (contact, friction, hysteresis states) or an mbs-level
        PostNewtonUserFunction; '' if nothing."""
        mbs = self.mbs
        what = []
        if mbs.systemData.DataSize() > 0:
            what.append(f"{mbs.systemData.DataSize()} data coordinates")
        if mbs_user_function(mbs, "PostNewtonUserFunction") is not None:
            what.append("the PostNewtonUserFunction")
        return " and ".join(what)

    # ------------------------------------------------------------------ plan
    def describe_plan(self, layout, groups, why, h, k, nsteps):
        L = layout
        lines = [f"exudyn_lie: Exudyn evaluates the whole model (M, f, C_q, velocity-level constraints) at every "
                 f"stage; {self.tableau.name} ({len(self.problem.stages)} evaluated stages) with "
                 + (f"adaptive steps of at most {h:.6g} s, {nsteps} Exudyn steps" if self._adaptive else
                    f"h = {h:.6g} s, {nsteps} steps, {k} per Exudyn step")]
        for i, n in enumerate(L.lgNodes):
            lines.append(f"exudyn_lie: node {n} (NodeRigidBodyRotVecLG): {groups[n]} ({why[n]})")
        lines.append(f"exudyn_lie: {len(L.vecIdx)} ODE2 coordinates in vector space (qdot = v), {L.nODE1} ODE1 "
                     f"coordinates, {L.nAE} algebraic equations (index-1: eta by central differences of the "
                     f"velocity-level constraints), {L.nData} data coordinates (updated by Exudyn's PostNewton "
                     f"after each step)")
        nb = len(self.model.blkPtr) - 1 if self.model.blkPtr is not None else 0
        lines.append("exudyn_lie: linear solve: "
                     + ("dense KKT (the mass matrix has a singular block)" if self.model.dense else
                        f"block-diagonal M ({nb} blocks, largest {int(np.max(np.diff(self.model.blkPtr))) if nb else 0}"
                        f") and the Schur complement C_q M^-1 C_q^T ({L.nAE} x {L.nAE})"))
        return "\n".join(lines)

    # ------------------------------------------------------------------ solve
    def Solve(self, simulationSettings=None, updateInitialValues=False, storeSolver=True, showProgress=True,
              substeps=None, accelerations=None, constraintCheck=True):
        """As :meth:`LieGroupSolver.Solve <exudyn_lie.bridge.solver.LieGroupSolver.Solve>`; the
        run-time check of the constraints (:mod:`.constraint_check`) judges Exudyn's residuals
        by the velocity-level equations integrated here."""
        import exudyn as exu
        tolCheck = check_tolerance(constraintCheck)
        mbs = self.mbs
        ticTotal = time.perf_counter()
        ss = exu.SimulationSettings() if simulationSettings is None else simulationSettings
        self.check_run(ss, substeps)
        ss2, k, nsteps, t0, tEnd = self._plan(ss, substeps, accelerations, tolCheck, ticTotal)
        loop = TimeLoop(mbs, self, ss, ss2, t0, tEnd, nsteps // k, storeSolver=storeSolver, showProgress=showProgress,
                        watch=True)
        loop.run()
        if updateInitialValues:
            update_initial_values(mbs)
        self._timing(loop.loopSeconds, ticTotal, nsteps)
        return True

    def _plan(self, ss, substeps, accelerations, tolCheck, ticTotal, start=None, needAcc=None):
        """The run's plan (``_loopPlan``) and the settings of Exudyn's loop; ``start``: from this time
        (a run this path takes over, :meth:`take_over`), else the settings' startTime."""
        mbs = self.mbs
        nsteps, t0, tEnd, h = time_settings(ss)
        k, userStep = plan_substeps(mbs, ss, nsteps, h, substeps)
        if start is not None:
            t0, nsteps = start, max(int(round((tEnd - start) / h)), 1)
        # one MK step per Exudyn step by default: Exudyn's per-step work (InitializeStep,
        # PostNewton with the data coordinates of contacts, search trees) then runs after
        # every step as in its own solvers; it costs a few us against the stages' tens.
        # (With several MK steps per Exudyn step, GeneralContact's results did not depend on h:
        # its state is updated per Exudyn step.)  substeps=k > 1 only without post-Newton items.
        postNewton = self._post_newton_items()
        if substeps is None:
            k = 1
        elif postNewton and k > 1:
            raise BridgeError(f"substeps={substeps}: {postNewton} need Exudyn's PostNewton after every step "
                              f"(their data coordinates change between steps); use substeps=None or 1")
        # object outputs may read the multipliers
        if needAcc is None:
            needAcc = needs_accelerations(mbs, ss, userStep) if accelerations is None else bool(accelerations)
        groups, why = node_groups(mbs, self.liegroup)
        tab = self.tableau = self._explicit
        adaptive = self._adaptive = adaptive_settings(tab, ss, h)
        name = auto_choice_text(tab) if (self.autoImplicit and adaptive is None) else tab.name
        if adaptive is not None:
            k = 1                          # the error control chooses the steps within each Exudyn step
            info = (f"exudyn_lie: explicit Munthe-Kaas {tab.name} (order {tab.order}) with adaptive steps (error "
                    f"control on the group, absoluteTolerance = {adaptive['atol']:g}, relativeTolerance = "
                    f"{adaptive['rtol']:g}, step size <= {h:.6g} s) on the Exudyn-evaluated model, from t = {t0:g} to "
                    f"{tEnd:g} s in {nsteps} Exudyn steps")
        else:
            info = (f"exudyn_lie: Munthe-Kaas {name} (order {tab.order_label}) on the Exudyn-evaluated model, "
                    f"step size h = {h:.6g} s, {nsteps} steps from t = {t0:g} to {tEnd:g} s")
        # Exudyn reduces its steps only after a failed discontinuous iteration, which needs items
        # with a PostNewton (GeneralContact's active sets too); without them the steps stay fixed,
        # t = t0 + i h as on the compiled path
        follow = k == 1 and bool(postNewton or mbs.NumberOfGeneralContacts())
        ss2 = loop_settings(ss, nsteps // k, info, followSteps=follow)
        # ... and after a failed Newton iteration, where the user's adaptiveStep lets it: its steps
        # (PostNewton between them) then replace the simulator's own division of the step
        # (mbs/implicit_run.substeps), which keeps the data coordinates of the step's start: a
        # friction contact that sticks inside the step has no solution in its slipping mode
        reduces = follow and bool(ss.timeIntegration.adaptiveStep)
        # a Python function between Exudyn's steps (constraint_check.ConsistencyAccount: the drift excuses nothing)
        betweenSteps = userStep or mbs_user_function(mbs, "PostNewtonUserFunction") is not None
        self._loopPlan = dict(k=k, h=h, t0=t0, tEnd=tEnd, nsteps=nsteps, needAcc=needAcc, groups=groups, why=why,
                              exudynReduces=reduces, betweenSteps=betweenSteps,
                              tolCheck=tolCheck, ticTotal=ticTotal, log=self.verbose or ss.timeIntegration.verboseMode >= 1,
                              reuseMass=bool(ss.timeIntegration.reuseConstantMassMatrix))
        self._integration = 0.0
        return ss2, k, nsteps, t0, tEnd

    def take_over(self, loop, ss, k, needAcc, tolCheck, t):
        """Continue a run of the compiled path inside its time loop (bridge/time_loop.py) from
        the state in mbs at ``t``, with its ``k`` integration steps per Exudyn step; returns False
        where this path cannot (post-Newton items with k > 1, adaptive steps with k > 1)."""
        if k > 1 and (self._post_newton_items() or adaptive_settings(self.tableau, ss, time_settings(ss)[3])):
            return False
        ticTotal = time.perf_counter()
        self._plan(ss, k, None, tolCheck, ticTotal, start=t, needAcc=needAcc)
        # a connector switched off: its equations are lam = 0 (Exudyn's Newton makes them so at the
        # next step; their residual is the multiplier the compiled path wrote)
        import exudyn as exu
        sd = self.mbs.systemData
        if sd.AEsize():
            ae = sd.GetAECoordinates(configuration=exu.ConfigurationType.Current, copy=False)
            for o in range(sd.NumberOfObjects()):
                if not self.mbs.GetObject(o).get("activeConnector", True):
                    ae[np.asarray(sd.GetObjectLTGAE(o), np.int64)] = 0.0
        self.loop_begin(loop.solver)
        return True

    def _timing(self, loopSeconds, ticTotal, nsteps):
        nev, integ = self.model.evaluations, self._integration
        self.timing = dict(total=time.perf_counter() - ticTotal, loop=loopSeconds, integration=integ,
                           steps=nsteps, evaluations=nev, perStage=integ / max(nev, 1), perStep=integ / max(nsteps, 1))
        if self._adaptive is not None:
            acc, rej, nrhs = self.problem.sim.adaptiveCounters
            self.timing.update(adaptive=True, accepted=acc, rejected=rej, rhsEvaluations=nrhs)
        if self._loopPlan["log"]:
            print(f"exudyn_lie: {nsteps} steps in {self.timing['total']:.3g} s (integration {integ:.3g} s = "
                  f"{1e6 * self.timing['perStep']:.3g} us/step, {nev} evaluations of {1e6 * self.timing['perStage']:.3g}"
                  f" us)")

    # ------------------------------------------------------------------ the driver of the time loop
    def loop_begin(self, solver):
        """After InitializeSolver (bridge/time_loop.py): the model and its problem on mbs'
        coordinates, the initial projection, the stability of the step, the initial
        accelerations, the plan's announcement and the run-time constraint check."""
        import exudyn as exu
        P, mbs, tab = self._loopPlan, self.mbs, self.tableau
        t0, h, k, nsteps = P["t0"], P["h"], P["k"], P["nsteps"]
        sd = mbs.systemData
        if general_contacts(mbs):
            self._explicitSolver = use_full_search(mbs, t0, P["tEnd"])     # the law of Exudyn's explicit solvers
        cur = exu.ConfigurationType.Current
        q = sd.GetODE2Coordinates(configuration=cur, copy=False)
        qt = sd.GetODE2Coordinates_t(configuration=cur, copy=False)
        self._qtt = sd.GetODE2Coordinates_tt(configuration=cur, copy=False)
        layout = Layout(mbs, P["groups"])
        self._ae = sd.GetAECoordinates(configuration=cur, copy=False) if layout.nAE else np.zeros(0)
        y = (np.array(sd.GetODE1Coordinates(configuration=cur), float) if layout.nODE1 else np.zeros(0))
        model = self.model = EvaluatedModel(mbs, solver, layout, q, qt, verbose=self.verbose)
        model.constantMass = P["reuseMass"] and constant_mass_matrix(mbs)
        problem = self.problem = EvaluatedProblem(model, tab)
        if P["exudynReduces"]:
            problem.sim.SetNewtonFallbacks(False)
        problem.read_state(q, qt, y, t0)
        self._project = (StepProjection(model, problem, self.stabilization, lambda rows: describe_rows(mbs, rows))
                         if self.stabilization and model.m else None)
        fixed = project_initial(model, problem, t0, self.projectInitial)
        if fixed and self._takeOver is not None:
            warn_user(f"exudyn_lie: at the hand-over to the Exudyn-evaluated path (t = {self._takeOver:.6g} s) the "
                      f"state does not satisfy the constraints as changed; projected onto them: {fixed} (Exudyn's "
                      f"own solvers pull it onto them in their Newton iteration)")
        elif fixed:
            warn_user(f"exudyn_lie: the initial state does not satisfy the constraints; projected onto them: "
                      f"{fixed} (Exudyn's own solvers start from it unchanged; pass projectInitial=False to "
                      f"raise instead)")
        problem.write()
        # stability of the step at the initial state (stiff items at the script's step); adaptive
        # steps find a stable step themselves
        tab, rate, stable, exact = self._stability_at_start(tab, h, nsteps)
        if self._adaptive is not None:
            problem.sim.SetAdaptive(**self._adaptive)
        # the initial accelerations (and a measured estimate of the cost per step)
        problem.write()
        model.accelerations(t0, problem.R, problem.r, problem.prev, problem.qv, True)    # first call: set-up
        model.kkt.settle()                   # redundant rows are found up to here (BlockKKT)
        tic = time.perf_counter()
        for _ in range(ESTIMATE_EVALUATIONS):
            model.accelerations(t0, problem.R, problem.r, problem.prev, problem.qv, True)
        perStage = (time.perf_counter() - tic) / ESTIMATE_EVALUATIONS
        perStep = perStage * len(problem.stages)
        model.evaluations = 0
        if P["needAcc"]:
            self._write_accelerations()
        if self.reasons:
            warn_user(f"exudyn_lie.SolveDynamic: {'; '.join(self.reasons)}: the compiled kernel does not have "
                      f"{'this item' if len(self.reasons) == 1 else 'these items'}, so Exudyn evaluates the "
                      f"whole model (M, f, C_q) at every stage; expected cost {1e6 * perStep:.0f} us per step "
                      f"({len(problem.stages)} stages of {1e6 * perStage:.0f} us, measured at the initial state; "
                      f"{1e-6 * perStep * nsteps * 1e6:.3g} s for {nsteps} steps)")
        if P["log"]:
            print(self.describe_plan(layout, P["groups"], P["why"], h, k, nsteps))
            print(f"exudyn_lie: fastest linearised mode |lambda| {'=' if exact else '>='} {rate:.4g} 1/s: stable up "
                  f"to h = {'' if exact else 'at most '}{stable:.3g} s; "
                  f"one stage costs {1e6 * perStage:.1f} us (Exudyn's evaluation, its dense copies of M "
                  f"and the Jacobian, the solve)")
        problem.write()                      # the initial state and time, for Exudyn's initial outputs
        sd.SetTime(t0)
        self._offsets = ParameterOffsets(mbs, t0, parameter_offset_rows(mbs))
        self.loop_check = None
        if P["tolCheck"] is not None and layout.nAE:
            ticCheck = time.perf_counter()
            dependent = range(sd.NumberOfObjects()) if model.pivoted else None
            check = self.constraintCheck = ConstraintCheck(mbs, solver, P["tolCheck"], dependent,
                                                           () if model.sliding is None else model.sliding.slots)
            account = ConsistencyAccount(check, weighMethodError=not P["betweenSteps"])
            account.step(t0, model.velocity_constraints(t0, problem.R, problem.r, problem.prev, problem.qv),
                         np.max(np.abs(qt)) if qt.size else 0.0)
            check.start(P["ticTotal"], ticCheck, everyOutput=True)
            tEnd = P["tEnd"]
            projected = None
            if self._project is not None:
                self._project.account = account      # (it accounts every step, before and after projecting)
                projected = account.unexplained

            def at_output(t1, last):
                if model.pivoted and check.dependent is None:
                    check.dependent = set(range(sd.NumberOfObjects()))
                # (model._vmax: max |q_t| of the state the step wrote, problem.write)
                if account.t != t1:
                    account.step(t1, model.velocity_constraints(t1, problem.R, problem.r, problem.prev, problem.qv),
                                 model._vmax)
                check.at_output(t1, account.explain, t1 >= tEnd - 1e-9 * max(1.0, abs(tEnd)), projected)
            self.loop_check = at_output

    def _stability_at_start(self, tab, h, nsteps):
        """The check of the step at the initial state: the drop-in's own choice of its method where the
        user named none (fixed steps), else the StepSizeError of a named explicit method beyond its
        stable step; returns (tableau, fastest rate, largest stable step, whether that step is exact)."""
        model, problem = self.model, self.problem
        if not (self.autoImplicit and self._adaptive is None):
            return (tab, *check_step(model, tab, h, self._adaptive is None, nsteps=nsteps), True)
        rate, stable, exact = choice_step(model, tab, h, nsteps=nsteps)
        problem.watch_stiffness(strict=True)
        chosen, line = stiff_choice(tab, h, stable, rate, "Exudyn's linearisation at the initial state"
                                    + ("" if exact else KRYLOV_NOTE))
        if line:
            self._switch(chosen, line)
            tab = chosen
        return tab, rate, stable, exact

    def _write_accelerations(self):
        """Exudyn's q_tt and multipliers at the state in mbs (written there)."""
        problem, model = self.problem, self.model
        model.accelerations(problem.t, problem.R, problem.r, problem.prev, problem.qv, True)
        self._qtt[:] = model.a
        if self._ae.size:
            self._ae[:] = model.ae_solution()

    def _actual_coordinates(self):
        # Exudyn's residual g = x - offset holds the new offset already: x = g + offset
        g, gv = self.model.raw_residuals()
        return lambda r, v: (g[r] + v, gv[r])

    def loop_context(self):
        """Objects changed by user functions during the loop are recorded (``_marks``): the rows'
        offset functions and levels are read again before the next step."""
        return ObjectChanges(self.mbs, self._marks)

    def loop_restart(self, t, repeat):
        """Exudyn's discontinuous iteration repeats the step: from the step's start again (the
        data coordinates PostNewton updated are Exudyn's); a user function set the state: from it."""
        if repeat:
            self.problem.restore(self._snap)
            self._recheck_stiffness(t)
        else:
            m = self.model
            self.problem.read_state(m.q, m.qt, None, t)

    def loop_advance(self, t0, t1, outputsLeft):
        """One Exudyn step: ``k`` MK steps (or adaptive ones) from ``t0`` to ``t1``, the end state
        (with accelerations and multipliers when something reads them) into mbs."""
        P, problem, model = self._loopPlan, self.problem, self.model
        k, h = P["k"], P["h"]
        self._snap = problem.snapshot()          # the step's start (a repeat of the step restores it)
        model.start_step()
        if self._marks:
            changed = changed_objects(self._marks)
            del self._marks[:]
            model.read_rows(changed)
        if self._offsets:
            problem.write()                      # the step's start state into mbs
            model.set_parameter_offsets(self._offsets.record(t0, t1, self._actual_coordinates))
        tic = time.perf_counter()
        if abs((t1 - t0) / k - h) > 1e-9 * h:
            if k > 1:
                raise off_plan(t1, t0 + k * h)
            # Exudyn reduced its step (a failed discontinuous iteration, loop_settings' followSteps)
            # or shortened the last one, or grows it back: MK steps of at most h to its end
            k = max(1, int(np.ceil((t1 - t0) / h * (1.0 - 1e-9))))
            h = (t1 - t0) / k
        try:
            self._advance(t0, t1, k, h)
        except StepSizeError as e:
            if not (getattr(e, "newton", False) and P["exudynReduces"]):
                raise
            problem.restore(self._snap)
            # (the run's error if Exudyn cannot reduce the step further)
            raise NewtonFailed(step_size_error(
                problem.tableau.name, h, t0, "the Newton iteration of an implicit stage did not converge "
                "(with a Jacobian of this step, then at each iterate)", "Exudyn reduced its step after each "
                "failure (adaptiveStep) down to this one", "decrease timeIntegration.minimumStepSize or the "
                "step size")) from None
        if self._project is None:
            problem.write()
        else:
            self._project(t1)                    # (it writes the state, and again where it changed it)
        if P["needAcc"]:
            self._write_accelerations()
        elif model.sliding is not None:
            model.sliding.project(t1, model.aeCur)     # for Exudyn's PostNewton (its data nodes)
        self.mbs.systemData.SetTime(t1)
        self._integration += time.perf_counter() - tic

    def _recheck_stiffness(self, t):
        """Exudyn repeats a step after its PostNewton changed the data coordinates (a contact that
        closed): a mode that the check at the start could not see may be stiff now.  The explicit
        method the user did not name is checked again, by Exudyn's linearisation with the new data,
        before the step is done again: the stages' watch sees such a mode only once the explicit
        method has amplified it, and the state it then restarts from is already off."""
        problem, h = self.problem, self._loopPlan["h"]
        if not self._may_switch():
            return
        problem.write()
        rate, stable, exact = choice_step(self.model, problem.tableau, h)
        tab, line = stiff_choice(problem.tableau, h, stable, rate, f"Exudyn's linearisation at t = {t:.6g} s, "
                                 f"after its PostNewton changed the data coordinates" + ("" if exact else KRYLOV_NOTE))
        if line:
            self._switch(tab, line)

    def _may_switch(self):
        """Whether the run may still replace its explicit method (the user named none; fixed steps)."""
        return self.autoImplicit and self._adaptive is None and not self.problem.tableau.implicit

    def _switch(self, tab, line):
        """Integrate with ``tab`` from now on, and say why (``line``)."""
        self.problem.set_method(tab)
        self.tableau = tab
        print(line)

    def _advance(self, t0, t1, k, h):
        """The MK steps of one Exudyn step; the explicit method the user did not name, unstable,
        replaced by the implicit one (bridge/method_choice.py) for this step from its start on."""
        problem = self.problem
        try:
            problem.advance(t0, t1, k, h, self._adaptive is not None)
        except StepSizeError as e:
            if not self._may_switch():
                raise
            problem.restore(self._snap)
            stiff = hasattr(e, "stiffStages")
            self._switch(*unstable_choice(problem.tableau, h, t0, None if stiff else STATUS_BLOWUP,
                                          getattr(e, "stiffWhat", None)))
            problem.advance(t0, t1, k, h, False)

    def loop_end(self):
        if not self._loopPlan["needAcc"]:
            self._write_accelerations()          # the final ones, as a native solve leaves them


def hand_over_from(compiled, error, loop):
    """A user function changed a parameter the compiled kernel holds fixed (``error``, a
    params.FixedParameterChanged) in a run of ``compiled`` (a LieGroupSolver of SolveDynamic's
    evaluation='auto'): the Exudyn-evaluated driver that continues it from the step's start (the
    state in mbs; it reads every item as Exudyn has it now), or None where this path cannot take
    the model."""
    plan = compiled._loopPlan
    if compiled.scene.rollingDiscPenalties:
        # the compiled path runs Exudyn's loop with one PostNewton pass for their data (solver.py);
        # the evaluated path needs Exudyn's discontinuous iteration as the user set it
        error.args = (f"{error.args[0]} (the Exudyn-evaluated path cannot take over the run: the model has "
                      f"ObjectConnectorRollingDiscPenalty items)",)
        return None
    try:
        ev = EvaluatedSolver(compiled.mbs, compiled._explicit, liegroup=compiled._liegroup_arg,
                             verbose=compiled.verbose, autoImplicit=compiled.autoImplicit,
                             projectInitial=compiled.projectInitial, stabilization=compiled.stabilization)
        ev._takeOver = error.t
        if not ev.take_over(loop, loop.settings, plan["k"], plan["needAcc"],
                            getattr(compiled, "_constraintCheck", True), error.t):
            return None
    except BridgeError as e:
        error.args = (f"{error.args[0]} (the Exudyn-evaluated path cannot take over the run: {e})",)
        return None
    warn_user(f"exudyn_lie: {error.what} was changed by a user function at t = {error.t:.6g} s, which the compiled "
              f"kernel cannot follow; the run continues from there on the Exudyn-evaluated path (Exudyn evaluates "
              f"the whole model at every stage)")
    if compiled._chunks is not None:
        compiled._chunks.rows = 0            # the compiled driver's fast hook defers to the loop's hook
    ev._marks = compiled._params.marks       # (its watch stays on for the rest of the loop)
    return ev


def changed_objects(marks):
    """The object indices among ``marks``: :class:`ObjectChanges` records indices; after a hand-over
    from the compiled path its parameter watch's marks, ``(kind, index, field, value)`` (params.py)."""
    out = set()
    for mark in marks:
        if isinstance(mark, tuple):
            if mark[0] == "object":
                out.add(int(mark[1]))
        elif mark is not None:
            out.add(int(mark))
    return out


class ObjectChanges(MainSystemPatch):
    """While Exudyn's loop runs, ``SetObjectParameter`` / ``ModifyObject`` on ``mbs`` append the
    object's index to ``marks``."""
    patched = ("SetObjectParameter", "ModifyObject")

    def __init__(self, mbs, marks):
        self.mbs, self.marks = mbs, marks

    def wrap(self, orig, name):
        target, marks = self.mbs, self.marks

        def wrapped(mbs, *args, **kw):
            out = orig(mbs, *args, **kw)
            if mbs is target:
                marks.append(args[0] if args else kw.get("objectNumber"))
            return out
        return wrapped
