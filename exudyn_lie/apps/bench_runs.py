"""Timed runs for ``python -m exudyn_lie bench``: one *case* = one model, one solver,
one step size (or tolerance), repeated; run in parallel through Exudyn's own
``exudyn.processing.ParameterVariation`` (multiprocessing).

A case is a plain dict (picklable, so that it can travel to the worker processes):

* ``kind``: ``'exl'`` (exudyn_lie: the Exudyn model read by ``SceneFromExudyn``, the
  compiled :class:`~exudyn_lie.mbs.Simulator`) or ``'native'`` (Exudyn's own solver on
  the same Exudyn model);
* ``model``: a key of :data:`BENCH_MODELS` or ``'chain<N>'`` (N boxes in a chain of
  spherical joints, :func:`build_chain`);
* ``solver``: a method of :mod:`exudyn_lie.integrators` (exl) or one of
  :data:`NATIVE_SOLVERS` (native); ``group`` (exl): ``SE3``, ``SO3xR3``, ``auto``;
* ``T`` end time, ``nsteps`` (fixed step ``h = T / nsteps``) or ``tol`` (native DOPRI5,
  which is always error controlled in Exudyn 1.13.6); ``repeat``.

What is timed (the same part of the work on both sides):

* exl: ``Simulator.Advance(nsteps, h)`` - the compiled time loop; building the scene
  and the :class:`Simulator` (compile-once set-up) is measured separately (``setup``);
* native: ``solver.SolveSteps(mbs, settings)`` - Exudyn's time loop; ``InitializeSolver``
  (including the initial accelerations) and ``FinalizeSolver`` are measured separately
  (``setup``).  Solution file off, sensors off, no output between steps.

The result of a case holds every repetition's time, their median, the final body states
(rotation, position of the body frame = Exudyn node frame, body-fixed angular velocity,
world velocity) and solver counters (Newton iterations, steps).
"""
from __future__ import annotations

import os
import re
import time
import traceback
import warnings

import numpy as np

# name in the bench -> module in models/
BENCH_MODELS = {
    "heavytop": "heavy_top",
    "doublependulum": "spherical_double_pendulum",
    "fourbar": "planar_four_bar",
    "rp": "rp_mechanism",
    "cardan": "cardan_shaft",
    "threebar": "spherical_three_bar",
    "sphfourbar": "spherical_four_bar",
    "freecomrot": "free_body_com_rotation",
    "freecomtrans": "free_body_com_translation",
    "freeoffrot": "free_body_offset_rotation",
    "freeoffscrew": "free_body_offset_screw",
}

# native solver name -> (DynamicSolverType name, implicit?, description)
NATIVE_SOLVERS = {
    "GeneralizedAlpha": ("GeneralizedAlpha", True,
                         "index 3, rho_inf = 0.9, full Newton, tol 1e-10"),
    "GeneralizedAlpha-mN": ("GeneralizedAlpha", True,
                            "index 3, rho_inf = 0.9, modified Newton (Exudyn's default), tol 1e-10"),
    "TrapezoidalIndex2": ("TrapezoidalIndex2", True,
                          "index 2 (velocity-level constraints), Newmark trapezoidal, full Newton, tol 1e-10"),
    "RK44": ("RK44", False, "explicit RK4, Lie group update of RotVecLG nodes, fixed step"),
    "RK67": ("RK67", False, "explicit RK6 (7 stages), Lie group update, fixed step"),
    "DOPRI5": ("DOPRI5", False, "explicit Dormand-Prince 5(4), always error controlled (tolerance sweep)"),
}


def resolve_model(name):
    """Bench key for a bench key or a ``models/`` module name (``heavy_top``...)."""
    key = name.strip().lower().replace("-", "").replace(" ", "")
    if key in BENCH_MODELS:
        return key
    for k, v in BENCH_MODELS.items():
        if key == v or key == v.replace("_", ""):
            return k
    if re.fullmatch(r"chain\d+", key):
        return key
    raise KeyError(f"unknown bench model {name!r}; available: {', '.join(BENCH_MODELS)} (or chain<N>)")


# --------------------------------------------------------------------------- models
def build_chain(n, mbs=None, nodeType=None, omega=None):
    """Exudyn model: ``n`` aluminium boxes 0.05 x 0.1 x 0.2 m (the double pendulum's
    links, long side along z) in a chain of spherical joints, hanging straight down from
    the ground at the origin, in gravity, starting as a rigid pendulum that rotates at
    ``omega`` rad/s about the world x axis through the top joint (consistent initial
    velocities), so that the chain swings and whips; default ``omega = 2 / max(1, L)``
    for a chain of length ``L = 0.2 n`` m (the tip starts at <= 2 m/s).  Returns
    ``(mbs, SC, nodes)``."""
    import exudyn as exu
    from exudyn.utilities import InertiaCuboid
    if nodeType is None:
        nodeType = exu.NodeType.RotationRotationVector
    SC = None
    if mbs is None:
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
    a = 0.2
    if omega is None:
        omega = 2.0 / max(1.0, n * a)
    inertia = InertiaCuboid(density=2700.0, sideLengths=[0.05, 0.1, 0.2])
    prev = mbs.CreateGround(referencePosition=[0, 0, 0])
    w = np.array([omega, 0.0, 0.0])
    nodes = []
    for i in range(n):
        xc = np.array([0.0, 0.0, -(i + 0.5) * a])
        d = mbs.CreateRigidBody(inertia=inertia, referencePosition=list(xc), initialVelocity=list(np.cross(w, xc)),
                                initialAngularVelocity=list(w), gravity=[0, 0, -9.81], nodeType=nodeType,
                                returnDict=True)
        mbs.CreateSphericalJoint(itemNumbers=[prev, d["bodyNumber"]], position=[0, 0, -i * a])
        prev = d["bodyNumber"]
        nodes.append(int(d["nodeNumber"]))
    return mbs, SC, nodes


class _Model:
    """An Exudyn model for the bench, with the node of every body (body order)."""

    def __init__(self, name, T):
        self.name = name
        self.T = float(T)
        if name.startswith("chain"):
            self.mbs, self.SC, self.nodes = build_chain(int(name[5:]))
            self.constrained = True
            self.redundant = False
            self.info = None
        else:
            from exudyn_lie import models
            self.mbs, self.info = models.build(BENCH_MODELS[name], endTime=T)
            self.SC = self.info.SC
            self.nodes = list(self.info.nodes)
            self.constrained = self.info.constrained
            self.redundant = bool(self.info.redundantConstraints)
        self.mbs.Assemble()


def model_summary(name):
    """(title, number of bodies, joints, constrained, redundant) of a bench model."""
    m = _Model(name, 1.0)
    nj = 0 if m.info is None else len(m.info.joints)
    title = f"chain of {len(m.nodes)} boxes, spherical joints" if m.info is None else m.info.title
    return title, len(m.nodes), nj, m.constrained, m.redundant


# --------------------------------------------------------------------------- exudyn_lie runs
def _run_exl(case):
    from ..bridge import SceneFromExudyn
    from ..mbs import Simulator
    tic = time.perf_counter()
    m = _Model(case["model"], case["T"])
    scene = SceneFromExudyn(m.mbs)
    tBuild = time.perf_counter() - tic
    N = int(case["nsteps"])
    h = case["T"] / N
    # compile-once set-up (scene arrays, consistency and redundancy checks), then the
    # timed time loop, repeated from the initial state
    tic = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = Simulator(scene, case["solver"], case["group"])
    setup = time.perf_counter() - tic
    times = []
    for rep in range(int(case.get("repeat", 1))):
        sim.SetInitialState()
        tic = time.perf_counter()
        sim.Advance(N, h)
        times.append(time.perf_counter() - tic)
    from ..mbs.state import twist_to_world_velocity
    om, ve = twist_to_world_velocity(sim.gid, sim.R, sim.V)
    return dict(times=times, setup=setup, build=tBuild, steps=N, h=h,
                R=sim.R.copy(), r=sim.r.copy(), omega=om, vel=ve, groups=list(sim.groups),
                stages=int(len(sim.method.stages)))   # stages evaluated per step


# --------------------------------------------------------------------------- native runs
def native_settings(case, redundant=False, sparse=False):
    """Exudyn SimulationSettings of a native case: fixed step (or the tolerance of
    DOPRI5), no solution file, no sensors, single thread.  Implicit solvers follow
    /tmp/facts (spectral radius 0.9, Newton tolerances 1e-10,
    ``lieGroupSimplifiedKinematicRelations`` for RotVecLG nodes); the explicit ones keep
    the Lie group update of RotVecLG nodes and skip the optional end-of-step
    accelerations (an extra right-hand side per step that the bench does not need)."""
    import exudyn as exu
    solver = case["solver"]
    stype, implicit, _ = NATIVE_SOLVERS[solver]
    s = exu.SimulationSettings()
    ti = s.timeIntegration
    T = float(case["T"])
    ti.startTime = 0.0
    ti.endTime = T
    ti.verboseMode = 0
    ti.stepInformation = 0
    s.show.statistics = False
    s.show.computationTime = False
    s.solution.file.write = False
    s.solution.sensors.active = False
    s.solution.sensors.writePeriod = 1e30
    s.solution.restart.write = False
    s.parallel.numberOfThreads = 1
    if sparse:
        s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    if redundant:
        s.linearSolver.solverType = exu.LinearSolverType.EigenDense
        s.linearSolver.ignoreSingularJacobian = True
    if implicit:
        ti.numberOfSteps = int(case["nsteps"])
        ti.automaticStepSize = False
        ti.adaptiveStep = False
        ga = ti.generalizedAlpha
        ga.spectralRadius = 0.9
        ga.lieGroupSimplifiedKinematicRelations = True
        ga.computeInitialAccelerations = True
        nw = ti.newton
        nw.useModifiedNewton = solver.endswith("-mN")
        nw.relativeTolerance = 1e-10
        nw.absoluteTolerance = 1e-10
        if sparse:
            # Exudyn refuses the Lie group tangent operator with EigenSparse; the Newton
            # iteration then uses the simplified Jacobian (same converged solution)
            ga.lieGroupAddTangentOperator = False
        if stype == "TrapezoidalIndex2":
            ga.useNewmark = True
            ga.useIndex2Constraints = True
    else:
        ex = ti.explicit
        ex.useLieGroupIntegration = True
        ex.computeEndOfStepAccelerations = False
        if stype == "DOPRI5":
            tol = float(case["tol"])
            ti.automaticStepSize = True
            ti.adaptiveStep = True
            ti.absoluteTolerance = tol
            ti.relativeTolerance = tol
            ti.numberOfSteps = max(1, int(round(T / 0.01)))    # maximum step 0.01 s
            ti.initialStepSize = 1e-4
            ti.minimumStepSize = 1e-12
        else:
            ti.numberOfSteps = int(case["nsteps"])
            ti.automaticStepSize = False
            ti.adaptiveStep = False
    return s, stype, implicit


def _node_states(mbs, nodes):
    import exudyn as exu
    ovt = exu.OutputVariableType
    nb = len(nodes)
    R = np.zeros((nb, 3, 3))
    r = np.zeros((nb, 3))
    om = np.zeros((nb, 3))
    ve = np.zeros((nb, 3))
    for i, n in enumerate(nodes):
        r[i] = mbs.GetNodeOutput(n, ovt.Position)
        R[i] = np.asarray(mbs.GetNodeOutput(n, ovt.RotationMatrix)).reshape(3, 3)
        om[i] = mbs.GetNodeOutput(n, ovt.AngularVelocityLocal)
        ve[i] = mbs.GetNodeOutput(n, ovt.Velocity)
    return R, r, om, ve


def _run_native(case):
    """A native case; with ``tolFallback`` (large chains) a Newton failure at the
    tolerance 1e-10 is retried at 1e-8 and 1e-6 (the tolerance used is returned):
    for a few thousand coordinates Exudyn's Newton residual cannot reach 1e-10."""
    if not case.get("tolFallback"):
        return _run_native_tol(case, None)
    err = None
    for tol in (1e-10, 1e-8, 1e-6):
        try:
            return _run_native_tol(case, tol)
        except RuntimeError as e:
            err = e
    raise err


def _run_native_tol(case, newtonTol):
    import exudyn as exu
    tic = time.perf_counter()
    m = _Model(case["model"], case["T"])
    tBuild = time.perf_counter() - tic
    s, stype, implicit = native_settings(case, m.redundant, case.get("sparse", False))
    if newtonTol is not None and implicit:
        s.timeIntegration.newton.relativeTolerance = newtonTol
        s.timeIntegration.newton.absoluteTolerance = newtonTol
    times, setups, newton, steps = [], [], [], []
    for rep in range(int(case.get("repeat", 1))):
        solver = exu.MainSolverImplicitSecondOrder() if implicit else exu.MainSolverExplicit()
        s.timeIntegration.solverType = getattr(exu.DynamicSolverType, stype)
        tic = time.perf_counter()
        solver.InitializeSolver(m.mbs, s)
        tInit = time.perf_counter() - tic
        tic = time.perf_counter()
        ok = solver.SolveSteps(m.mbs, s)
        times.append(time.perf_counter() - tic)
        tic = time.perf_counter()
        solver.FinalizeSolver(m.mbs, s)
        setups.append(tInit + time.perf_counter() - tic)
        tEnd = m.mbs.systemData.GetTime()
        if ok is False or abs(tEnd - case["T"]) > 1e-9 * max(1.0, case["T"]):
            raise RuntimeError(f"Exudyn {case['solver']} stopped at t = {tEnd:.6g} s "
                               f"(SolveSteps returned {ok})")
        newton.append(int(solver.it.newtonStepsCount) if implicit else 0)
        steps.append(int(solver.it.currentStepIndex) - 1)
    R, r, om, ve = _node_states(m.mbs, m.nodes)
    N = int(np.median(steps))
    return dict(times=times, setup=float(np.median(setups)), build=tBuild, steps=N,
                h=case["T"] / N if N else np.nan, newton=int(np.median(newton)), R=R, r=r, omega=om, vel=ve,
                newtonTol=float(s.timeIntegration.newton.relativeTolerance) if implicit else np.nan)


def run_case(case):
    """Run one case; returns a dict with ``ok``, ``message``, ``time`` (median over
    the repetitions), ``times`` and the final state (see the module docstring)."""
    out = dict(case=dict(case), ok=False, message="", time=np.nan, times=[])
    try:
        res = _run_exl(case) if case["kind"] == "exl" else _run_native(case)
        out.update(res)
        out["time"] = float(np.median(res["times"]))
        fin = all(np.all(np.isfinite(res[k])) for k in ("R", "r", "omega", "vel"))
        out["ok"] = bool(fin)
        if not fin:
            out["message"] = "non-finite final state"
    except Exception as e:  # a failed run is a data point ("did not run"), not a crash
        msg = str(e).strip().splitlines()
        out["message"] = f"{type(e).__name__}: {msg[0][:300] if msg else ''}"
        if os.environ.get("EXUDYN_LIE_BENCH_DEBUG"):
            out["message"] += "\n" + traceback.format_exc()
    out["pid"] = os.getpid()
    return out


# --------------------------------------------------------------------------- the parallel sweep
def _parameter_function(parameterSet):
    """The ``parameterFunction`` handed to ``ParameterVariation``: one case per index."""
    cases = parameterSet["functionData"]["cases"]
    return run_case(cases[int(parameterSet["case"])])


def sweep(cases, jobs=None, showProgress=False):
    """Run the cases (a list of case dicts) through Exudyn's
    ``exudyn.processing.ParameterVariation`` with ``useMultiProcessing=True`` on
    ``jobs`` worker processes (default: all cores); ``jobs=1`` runs them in this
    process.  Returns the results in the order of ``cases``.

    Every case is one job; put long cases first for a good load balance (the pool
    hands out jobs in list order)."""
    if not cases:
        return []
    from exudyn.processing import ParameterVariation
    jobs = (os.cpu_count() or 1) if jobs is None else int(jobs)
    jobs = max(1, min(jobs, len(cases)))
    _warm_up()
    [_, values] = ParameterVariation(parameterFunction=_parameter_function,
                                     parameters={"case": list(range(len(cases)))},
                                     parameterFunctionData={"cases": list(cases)},
                                     useMultiProcessing=jobs > 1, numberOfThreads=jobs,
                                     showProgress=showProgress)
    return list(values)


_WARM = False


def _warm_up():
    """Load the compiled kernel (numba cache) once in the parent so that the forked
    workers inherit it instead of each loading it again."""
    global _WARM
    if _WARM:
        return
    from ..mbs import GROUND, Scene, Simulator
    sc = Scene(gravity=[0, 0, -9.81])
    b = sc.AddBody(1.0, np.eye(3) * 0.01, r0=[0.5, 0, 0])
    sc.AddSphericalJoint(GROUND, b, [0, 0, 0])
    sc.AddSpringDamper(GROUND, [1, 0, 0], b, [0, 0, 0], stiffness=1.0)
    Simulator(sc, "RK4", "SE3").Advance(1, 1e-3)
    _WARM = True
