"""Bench section ``stiff``: the implicit ESDIRK3 through ``exl.SolveDynamic`` against Exudyn's own
generalized-alpha on stiff models, work against precision.

Models (Exudyn scripts built here, each run as a user runs it: the same ``mbs``, the same settings):

* ``chain``: ten rigid bodies, the first on a revolute joint to the ground, the others linked by
  stiff rigid-body spring-dampers (1e6 N/m, 1e4 Nm/rad, damped); the compiled path, SE3;
* ``cable``: a 2D ANCF cable of eight elements clamped at one end with a rigid 2D body pinned to
  its tip, under gravity; the Exudyn-evaluated path;
* ``coin``: a coin rolling on a penalty contact with dry friction (ObjectConnectorRollingDiscPenalty,
  contact stiffness 1e6, damping 1e4), started in contact; the compiled path.

For each model and step ``h`` (halved from the largest): the end state (all ODE2 coordinates)
against generalized-alpha at a step 64 times below the smallest (Exudyn's default Newton: full Newton
with tighter tolerances stalls at round-off on the chain at these steps),
and the time inside the solve call, the best of ``repeat`` warm runs.  Generalized-alpha runs with
Exudyn's defaults (spectral radius 0.8, modified Newton).  exudyn_lie runs with ``method=None``
(its own choice: ESDIRK3 where RK4 is unstable, said in the result).  ``report_lines`` gives the
ratio of times at equal error, interpolated log-log, at the errors 1e-3 ... 1e-6 both reach, as
measured, faster or not.
"""
import contextlib
import io
import time
import warnings

import numpy as np

MODELS = ("chain", "cable", "coin")
T_END = {"chain": 0.5, "cable": 0.5, "coin": 0.2}
STEPS = {"chain": (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4), "cable": (4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4),
         "coin": (1e-3, 5e-4, 2.5e-4, 1.25e-4)}
REF_FACTOR = 64
TARGETS = (1e-3, 1e-4, 1e-5, 1e-6)


# ------------------------------------------------------------------ models
def build_chain(mbs):
    import exudyn as exu
    from exudyn.utilities import RigidBodyInertia
    ground = mbs.CreateGround()
    prev = None
    for i in range(10):
        b = mbs.CreateRigidBody(inertia=RigidBodyInertia(mass=1.0, inertiaTensor=np.diag([0.01, 0.02, 0.03])),
                                referencePosition=[0.5 * (i + 1), 0, 0], initialAngularVelocity=[0, 0, 0.5 * (i % 3)],
                                nodeType=exu.NodeType.RotationRotationVector, gravity=[0, -9.81, 0])
        if prev is None:
            mbs.CreateRevoluteJoint(bodyNumbers=[ground, b], position=[0, 0, 0], axis=[0, 0, 1])
        else:
            mbs.CreateRigidBodySpringDamper(itemNumbers=[prev, b], localPosition0=[0.25, 0, 0],
                                            localPosition1=[-0.25, 0, 0],
                                            stiffness=np.diag([1e6, 1e6, 1e6, 1e4, 1e4, 1e4]),
                                            damping=np.diag([1e2, 1e2, 1e2, 1.0, 1.0, 1.0]))
        prev = b
    mbs.Assemble()


def build_cable(mbs):
    from exudyn.beams import GenerateStraightLineANCFCable2D
    from exudyn.utilities import (LoadMassProportional, MarkerBodyMass, MarkerBodyPosition, MarkerNodePosition,
                                  NodeRigidBody2D, ObjectANCFCable2D, ObjectJointRevolute2D, ObjectRigidBody2D)
    L, n = 1.0, 8
    cable = ObjectANCFCable2D(physicsMassPerLength=0.5, physicsBendingStiffness=2.0,
                              physicsAxialStiffness=1e5, useReducedOrderIntegration=1)
    nodes, objects, loads, constraints, _ = GenerateStraightLineANCFCable2D(
        mbs, positionOfNode0=[0, 0, 0], positionOfNode1=[L, 0, 0], numberOfElements=n, cableTemplate=cable,
        massProportionalLoad=[0, -9.81, 0], fixedConstraintsNode0=[1, 1, 1, 1], fixedConstraintsNode1=[0, 0, 0, 0])
    nb = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[L + 0.1, 0, 0]))
    ob = mbs.AddObject(ObjectRigidBody2D(physicsMass=0.2, physicsInertia=1e-3, nodeNumber=nb))
    mTip = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1]))
    mBody = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ob, localPosition=[-0.1, 0, 0]))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[mTip, mBody]))
    mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=ob)), loadVector=[0, -9.81, 0]))
    mbs.Assemble()


def build_coin(mbs):
    from exudyn.utilities import (MarkerBodyRigid, NodeGenericData, ObjectConnectorRollingDiscPenalty, ObjectGround,
                                  RigidBodyInertia, RotationMatrixY, Skew)
    r, phi0 = 0.05, 10.0 / 180.0 * np.pi
    R0 = RotationMatrixY(phi0)
    omega0 = [20.0, 0.0, 2.0]
    p0 = [r * np.sin(phi0), 0, r * np.cos(phi0) - 1e-4]          # started 0.1 mm in contact
    v0 = Skew(omega0) @ R0 @ [0, 0, r]
    b = mbs.CreateRigidBody(inertia=RigidBodyInertia(mass=1.0, inertiaTensor=np.diag([0.5 * r ** 2, 0.25 * r ** 2,
                                                                                           0.25 * r ** 2])),
                            referencePosition=p0, referenceRotationMatrix=R0, initialVelocity=list(v0),
                            initialAngularVelocity=omega0, gravity=[0, 0, -9.81])
    ground = mbs.AddObject(ObjectGround())
    mG = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground))
    mB = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b))
    nData = mbs.AddNode(NodeGenericData(initialCoordinates=[0, 0, -1e-4], numberOfDataCoordinates=3))
    mbs.AddObject(ObjectConnectorRollingDiscPenalty(markerNumbers=[mG, mB], nodeNumber=nData, discRadius=r,
                                                    dryFriction=[0.5, 0.5], dryFrictionProportionalZone=0.05,
                                                    contactStiffness=1e6, contactDamping=1e4))
    mbs.Assemble()


BUILD = {"chain": build_chain, "cable": build_cable, "coin": build_coin}


# ------------------------------------------------------------------ runs
def _settings(T, h):
    import exudyn as exu
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = T
    ss.timeIntegration.numberOfSteps = int(round(T / h))
    ss.timeIntegration.verboseMode = 0
    ss.solutionSettings.writeSolutionToFile = False
    ss.solutionSettings.sensorsWritePeriod = T
    ss.displayComputationTime = False
    ss.displayStatistics = False
    ss.timeIntegration.adaptiveStep = False
    return ss


def run_once(model, h, solver):
    """``(end state q, seconds inside the solve call, what ran)``; solver 'native', 'ref' or 'exl'."""
    import exudyn as exu
    import exudyn_lie as exl
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    BUILD[model](mbs)
    T = T_END[model]
    ss = _settings(T, h)
    out = io.StringIO()
    with warnings.catch_warnings(), contextlib.redirect_stdout(out):
        warnings.simplefilter("ignore")
        tic = time.perf_counter()
        try:
            if solver == "exl":
                exl.SolveDynamic(mbs, ss, showProgress=False, constraintCheck=False)
            else:
                exu.SolveDynamic(mbs, ss)
        except Exception as e:          # noqa: BLE001 - a solver that fails at a step is a result
            if solver == "ref":
                raise
            return None, np.nan, f"failed ({type(e).__name__})"
        sec = time.perf_counter() - tic
    what = "generalized-alpha"
    if solver == "exl":
        what = mbs.sys["lieGroupSolver"].tableau.name if "lieGroupSolver" in mbs.sys else (
            "ESDIRK3" if "ESDIRK3" in out.getvalue() else "RK4")
    q = np.array(mbs.systemData.GetODE2Coordinates(configuration=exu.ConfigurationType.Current))
    return q, sec, what


def run_section(cfg, log):
    repeat = 1 if getattr(cfg, "quick", False) else 3
    res = {}
    for model in MODELS:
        steps = STEPS[model][:3] if getattr(cfg, "quick", False) else STEPS[model]
        log(f"stiff: {model}: reference (generalized-alpha at h = {steps[-1] / REF_FACTOR:g} s)")
        qref, _, _ = run_once(model, steps[-1] / REF_FACTOR, "ref")
        rows = []
        for h in steps:
            for solver in ("native", "exl"):
                best, q, what = np.inf, None, ""
                for _ in range(repeat + (solver == "exl")):          # exudyn_lie: one more (compile)
                    q, sec, what = run_once(model, h, solver)
                    best = min(best, sec)
                    if q is None:
                        break
                err = float(np.max(np.abs(q - qref))) if q is not None else float("nan")
                rows.append(dict(h=h, solver=solver, method=what, error=err, seconds=best))
                log(f"stiff: {model} h = {h:g}: {solver:6s} ({what}) error {err:.3g}, {best:.4g} s")
        res[model] = rows
    return res


def curve(rows, solver):
    """``(error, seconds)`` of ``solver``'s rows, sorted by error (finite, positive errors: a log-log curve)."""
    pts = sorted(((r["error"], r["seconds"]) for r in rows if r["solver"] == solver and np.isfinite(r["error"])
                  and r["error"] > 0), key=lambda p: p[0])
    return np.array(pts)


def time_at(pts, err):
    """The time at the error ``err`` interpolated log-log along the curve (None outside it)."""
    if len(pts) < 2 or not (pts[0, 0] <= err <= pts[-1, 0]):
        return None
    return float(np.exp(np.interp(np.log(err), np.log(pts[:, 0]), np.log(pts[:, 1]))))


def report_lines(res, figures=()):
    L = ["## Stiff models: implicit ESDIRK3 against Exudyn's generalized-alpha", "",
         "`python -m exudyn_lie bench --sections stiff` (module `exudyn_lie/apps/bench_stiff.py`: models, "
         "reference and timing).  Error: max over the end state's ODE2 coordinates against generalized-alpha "
         f"at a step {REF_FACTOR} times below the smallest; time: inside the solve call, best of warm runs.", ""]
    for model, rows in res.items():
        L += [f"### {model}", "", "| h [s] | solver | method | error | time [s] |", "|---|---|---|---|---|"]
        L += [f"| {r['h']:g} | {r['solver']} | {r['method']} | {r['error']:.3g} | {r['seconds']:.4g} |" for r in rows]
        L += ["", "(nan: the solver stopped at this step.)"] if any(not np.isfinite(r["error"]) for r in rows) else []
        a, b = curve(rows, "exl"), curve(rows, "native")
        L += ["", "Time of exudyn_lie / generalized-alpha at equal error (interpolated; '-': outside a curve):", ""]
        for e in TARGETS:
            ta, tb = time_at(a, e), time_at(b, e)
            ratio = "-" if ta is None or tb is None else f"{ta / tb:.2f} ({'faster' if ta < tb else 'slower'})"
            L.append(f"* error {e:g}: {ratio}")
        L.append("")
    for f in figures:
        L += [f"![stiff work-precision]({f})", ""]
    return L


def plot(res, figdir):
    import os
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(res), figsize=(5 * len(res), 4.2))
    for ax, (model, rows) in zip(np.atleast_1d(axes), res.items()):
        nat = [(r["error"], r["seconds"]) for r in rows if r["solver"] == "native" and np.isfinite(r["error"])]
        ax.loglog([p[0] for p in nat], [p[1] for p in nat], "s-", color="C0", label="Exudyn generalized-alpha")
        exl = [r for r in rows if r["solver"] == "exl" and np.isfinite(r["error"])]
        ax.loglog([r["error"] for r in exl], [r["seconds"] for r in exl], "-", color="C1")
        for method, marker in (("ESDIRK3", "o"), ("RK4", "^")):
            pts = [r for r in exl if r["method"] == method]
            if pts:
                ax.loglog([r["error"] for r in pts], [r["seconds"] for r in pts], marker, color="C1",
                          label=f"exudyn_lie, no method named: {method}")
        ax.set_title(f"{model}, T = {T_END[model]:g} s, steps {min(STEPS[model]):g} ... {max(STEPS[model]):g} s")
        ax.set_xlabel("error of the end state")
        ax.set_ylabel("time inside the solve [s]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, framealpha=0.6)
    fig.tight_layout()
    os.makedirs(figdir, exist_ok=True)
    path = os.path.join(figdir, "wp_stiff.png")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return [path]
