"""Bench section ``particles``: a particle system of Exudyn's ``GeneralContact``, the kind of model its
users integrate with explicit methods (Exudyn's ``particleClusters.py`` runs explicit Euler).

``python -m exudyn_lie bench --sections particles``.  The model: 27 spheres (r = 0.05 m, 0.1 kg,
mass points) in a 3 x 3 x 3 block with random initial velocities (seed 1, up to 0.5 m/s) fall
under gravity onto a large fixed sphere (r = 10 m: nearly a plane), contact stiffness 1e4 N/m,
damping 2 Ns/m, no friction; T = 0.2 s (they land and collide).  At each step h, inside the solve
call, best of three runs (exudyn_lie: after one more, whose numba compilation, if any, is not counted):

* ``exl``: ``exl.SolveDynamic`` with RK4 (the Exudyn-evaluated path; GeneralContact with the law of
  Exudyn's explicit solvers, bridge/general_contact.py);
* ``RK44`` and ``ExplicitEuler``: Exudyn's own explicit solvers.

Explicit Euler runs at smaller steps (``STEPS_EULER``) so that its errors reach the others'.  Error:
max over the end state's ODE2 coordinates against Exudyn's RK44 at h = 1e-6 s (the contacts' kinks
make every method first order here).  The time per step, and the time of exudyn_lie over each native
solver at equal error (interpolated log-log along its curve; '-' where the errors do not overlap).
"""
from __future__ import annotations

import contextlib
import io
import time
import warnings

import numpy as np

from .bench_stiff import curve, time_at

T_END = 0.2
STEPS = (4e-4, 2e-4, 1e-4, 5e-5)
#: explicit Euler is first order and its error constant is larger: smaller steps reach the others' errors
STEPS_EULER = (2e-5, 1e-5, 5e-6, 2.5e-6)
REF_H = 1e-6
SOLVERS = ("exl", "RK44", "ExplicitEuler")
TARGETS = (4e-4, 2e-4, 1e-4)


def build(mbs):
    """The 27 particles on the ground sphere (module docstring)."""
    from exudyn.itemInterface import Force, MarkerBodyRigid, MarkerNodePosition, MassPoint, NodePoint
    rng = np.random.default_rng(1)
    r, m = 0.05, 0.1
    gc = mbs.AddGeneralContact()
    gc.SetFrictionPairings(np.zeros((1, 1)))        # (friction needs markers with an orientation)
    gc.SetSearchTreeCellSize(numberOfCells=[6, 6, 6])
    gc.SetSearchTreeBox([-1, -1, -0.2], [1, 1, 1])
    ground = mbs.CreateGround()
    mG = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, -10.0]))
    gc.AddSphereWithMarker(mG, radius=10.0, contactStiffness=1e4, contactDamping=2.0, frictionMaterialIndex=0)
    for i in range(3):
        for j in range(3):
            for k in range(3):
                v = rng.uniform(-0.5, 0.5, 3)
                n = mbs.AddNode(NodePoint(referenceCoordinates=[0.11 * (i - 1), 0.11 * (j - 1), 0.1 + 0.11 * k],
                                          initialVelocities=list(v)))
                mbs.AddObject(MassPoint(physicsMass=m, nodeNumber=n))
                mk = mbs.AddMarker(MarkerNodePosition(nodeNumber=n))
                mbs.AddLoad(Force(markerNumber=mk, loadVector=[0, 0, -9.81 * m]))
                gc.AddSphereWithMarker(mk, radius=r, contactStiffness=1e4, contactDamping=2.0,
                                       frictionMaterialIndex=0)
    mbs.Assemble()


def _settings(h):
    import exudyn as exu
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = T_END
    ss.timeIntegration.numberOfSteps = int(round(T_END / h))
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = T_END
    ss.displayComputationTime = False
    ss.displayStatistics = False
    ss.timeIntegration.explicitIntegration.computeEndOfStepAccelerations = False
    return ss


def run_once(h, solver):
    """``(end state q, seconds inside the solve call)``; solver 'exl' or an Exudyn DynamicSolverType name."""
    import exudyn as exu
    import exudyn_lie as exl
    mbs = exu.SystemContainer().AddSystem()
    build(mbs)
    ss = _settings(h)
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        tic = time.perf_counter()
        if solver == "exl":
            exl.SolveDynamic(mbs, ss, showProgress=False, method="RK4", constraintCheck=False)
        else:
            exu.SolveDynamic(mbs, ss, solverType=getattr(exu.DynamicSolverType, solver))
        sec = time.perf_counter() - tic
    return np.array(mbs.systemData.GetODE2Coordinates(configuration=exu.ConfigurationType.Current)), sec


def run_section(cfg, log):
    quick = getattr(cfg, "quick", False)
    repeat = 1 if quick else 3
    log(f"particles: reference (Exudyn's RK44 at h = {REF_H:g} s)")
    qref, _ = run_once(REF_H, "RK44")
    rows = []
    runs = [(h, s) for h in STEPS for s in SOLVERS[:2]] + [(h, "ExplicitEuler") for h in STEPS_EULER]
    if quick:
        runs = runs[:4] + runs[-1:]
    for h, solver in runs:
        best, q = np.inf, None
        for _ in range(repeat + (solver == "exl")):             # exudyn_lie: one more (compile)
            q, sec = run_once(h, solver)
            best = min(best, sec)
        err = float(np.max(np.abs(q - qref)))
        n = int(round(T_END / h))
        rows.append(dict(h=h, solver=solver, error=err, seconds=best, perStep=best / n))
        log(f"particles: h = {h:g}: {solver:13s} error {err:.3g}, {best:.4g} s ({1e6 * best / n:.1f} us/step)")
    return dict(rows=rows, coordinates=int(qref.size))


def report_lines(res):
    rows = res["rows"]
    L = ["## A particle system (GeneralContact) against Exudyn's explicit solvers", "",
         f"`python -m exudyn_lie bench --sections particles` (module `exudyn_lie/apps/bench_particles.py`: the "
         f"model, {res['coordinates']} coordinates, the reference and the timing).  Error: max over the end "
         f"state's coordinates against Exudyn's RK44 at h = {REF_H:g} s; time: inside the solve call, best of "
         "runs (exudyn_lie after one more).", "",
         "| h [s] | solver | error | time [s] | per step [us] |", "|---|---|---|---|---|"]
    L += [f"| {r['h']:g} | {r['solver']} | {r['error']:.3g} | {r['seconds']:.4g} | {1e6 * r['perStep']:.1f} |"
          for r in rows]
    ours = curve(rows, "exl")
    for other in SOLVERS[1:]:
        theirs = curve(rows, other)
        L += ["", f"Time of exudyn_lie / {other} at equal error (interpolated; '-': the curves do not overlap):", ""]
        for e in TARGETS:
            ta, tb = time_at(ours, e), time_at(theirs, e)
            L.append(f"* error {e:g}: " + ("-" if ta is None or tb is None else
                                          f"{ta / tb:.2f} ({'faster' if ta < tb else 'slower'})"))
    return L + [""]
