"""What one stage of the Exudyn-evaluated path costs (``python -m exudyn_lie.apps.evaluated_cost``).

Models: a chain of ``n`` rigid bodies (RotVecLG nodes, spherical joints, gravity) whose last
body is pulled by one item the compiled kernel does not have (an ``ObjectConnectorGravity``
to a ground point), so that Exudyn evaluates the whole model.

Per stage it reports the integration time of a run / the number of evaluated stages (best
of several runs: the machine may be shared), and the time of Exudyn's calls of one stage
(M, f, C_q, the velocity-level constraints twice for eta, the dense copies
``GetSystemMassMatrix`` / ``GetSystemJacobian`` and the zeroing of the Jacobian, ``SetTime``), each
timed alone in a loop at the run's final state.  The difference is this package's overhead:
the Python stage loop, the compiled group maps and state writes, eta's two moved
configurations, the block-diagonal Schur solve.  Exudyn's dense copies are its interface: they grow
with the square of the number of coordinates.
"""
from __future__ import annotations

import time
import warnings

import numpy as np



def chain_with_foreign_item(n, mbs=None):
    """A chain of n rigid boxes on spherical joints, swinging under gravity, plus an
    ObjectConnectorGravity (not compiled) pulling the last body towards a ground point."""
    import exudyn as exu
    from exudyn.utilities import InertiaCuboid, MarkerBodyPosition, ObjectConnectorGravity, ObjectGround
    if mbs is None:
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        chain_with_foreign_item.keep = SC
    g = mbs.AddObject(ObjectGround(referencePosition=[0, 0, 0]))
    prev, L = g, 0.3
    for i in range(n):
        b = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [L, 0.05, 0.05]),
                                referencePosition=[(i + 0.5) * L, 0, 0], gravity=[0, -9.81, 0],
                                initialAngularVelocity=[0.3, 0, 0],
                                nodeType=exu.NodeType.RotationRotationVector)
        mbs.CreateSphericalJoint(itemNumbers=[prev, b], position=[i * L, 0, 0])
        prev = b
    mbs.AddObject(ObjectConnectorGravity(markerNumbers=[mbs.AddMarker(MarkerBodyPosition(bodyNumber=g,
                                                                                        localPosition=[0, -2, 0])),
                                                        mbs.AddMarker(MarkerBodyPosition(bodyNumber=prev))],
                                         mass0=1e9, mass1=1.0, minDistanceRegularization=0.1))
    mbs.Assemble()
    return mbs


def _run(mbs, ss):
    import exudyn as exu

    import exudyn_lie as exl
    from exudyn_lie.bridge.evaluated_solve import EvaluatedSolver
    mbs.systemData.SetSystemState(mbs.systemData.GetSystemState(exu.ConfigurationType.Initial),
                                  exu.ConfigurationType.Current)
    solver = EvaluatedSolver(mbs, exl.get_method("RK4"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        solver.Solve(ss, showProgress=False)
    return solver


def _best(f, n, repeats):
    """Smallest mean time of ``n`` calls of f over ``repeats`` tries (the machine is shared)."""
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n):
            f()
        best = min(best, (time.perf_counter() - t0) / n)
    return best


def exudyn_calls_per_stage(solver, repeats=7, n=200):
    """Seconds per stage spent in Exudyn's calls, each timed alone at the final state of the
    run (best of ``repeats``): what one stage calls, in the numbers one stage calls them."""
    model = solver.model
    s, mbs, sd = model.solver, model.mbs, model.sd
    t = sd.GetTime()
    calls = {
        "ComputeMassMatrix": (lambda: s.ComputeMassMatrix(mbs), 1),
        "GetSystemMassMatrix": (s.GetSystemMassMatrix, 1),
        "ComputeODE2RHS": (lambda: s.ComputeODE2RHS(mbs), 1),
        "GetSystemResidual": (s.GetSystemResidual, 3),
        "zero the system Jacobian": (model._zeroJ, 1),
        "ComputeJacobianAE": (lambda: s.ComputeJacobianAE(mbs), 1),
        "GetSystemJacobian": (s.GetSystemJacobian, 1),
        "ComputeAlgebraicEquations(velocityLevel=True)": (lambda: s.ComputeAlgebraicEquations(mbs, True), 2),
        "SetTime": (lambda: sd.SetTime(t), 3),
    }
    if model.m == 0:
        for k in ("zero the system Jacobian", "ComputeJacobianAE", "GetSystemJacobian",
                  "ComputeAlgebraicEquations(velocityLevel=True)"):
            calls.pop(k)
    out = {name: k * _best(f, n, repeats) for name, (f, k) in calls.items()}
    return out


def measure(n, steps=200, h=1e-3, repeats=5):
    """Microseconds per stage of the Exudyn-evaluated path on :func:`chain_with_foreign_item`
    (best of ``repeats`` runs): dict(total, exudyn, copies, overhead, nODE2, nAE, calls)."""
    import exudyn as exu
    mbs = chain_with_foreign_item(n)
    ss = exu.SimulationSettings()
    ss.solution.file.write = False
    ss.solution.sensors.active = False
    ss.timeIntegration.verboseMode = 0
    ss.timeIntegration.endTime = steps * h
    ss.timeIntegration.numberOfSteps = steps
    _run(mbs, ss)                                           # compile / warm up
    total, sol = float("inf"), None
    for _ in range(repeats):
        s_ = _run(mbs, ss)
        per = s_.timing["integration"] / s_.timing["evaluations"]
        if per < total:
            total, sol = per, s_
    calls = exudyn_calls_per_stage(sol)
    ex = sum(calls.values())
    cp = sum(v for k, v in calls.items() if k.startswith("Get") or k.startswith("zero"))
    return dict(total=1e6 * total, exudyn=1e6 * ex, copies=1e6 * cp, overhead=1e6 * (total - ex),
                nODE2=sol.model.n, nAE=sol.model.m, calls={k: 1e6 * v for k, v in calls.items()})


def main(sizes=(1, 10, 50)):
    rows = [(n, measure(n)) for n in sizes]
    print("bodies | ODE2 | AE | us/stage total | in Exudyn's calls | of it dense copies (Get*, zeroing) | "
          "overhead (Python, group maps, eta, Schur solve)")
    for n, r in rows:
        print(f"{n:6d} | {r['nODE2']:4d} | {r['nAE']:3d} | {r['total']:14.1f} | {r['exudyn']:17.1f} | "
              f"{r['copies']:18.1f} | {r['overhead']:8.1f}")
    print("\nExudyn's calls per stage, us (each timed alone, times the number of calls per stage):")
    names = list(rows[0][1]["calls"])
    print("call | " + " | ".join(f"{n} bodies" for n, _ in rows))
    for k in names:
        print(f"{k} | " + " | ".join(f"{r['calls'].get(k, 0.0):.1f}" for _, r in rows))


if __name__ == "__main__":
    main()
