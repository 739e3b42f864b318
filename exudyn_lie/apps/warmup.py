"""``python -m exudyn_lie warmup``: compile the solver variants real models need, once per
machine, with progress, so that no script meets a compile pause later.

numba compiles the solver once per kind of model (the bodies' groups, planar bodies, point
masses, Python user functions, stabilisation, adaptive steps, the Exudyn-evaluated path,
...) and caches it for every copy of the package on the machine
(``exudyn_lie/_numba_cache.py``).  Each line below builds a small Exudyn model of one kind
and solves ten steps through ``exudyn_lie.SolveDynamic``; a kind already compiled costs a
fraction of a second."""
from __future__ import annotations

import argparse
import sys
import time
import warnings


def _system():
    import exudyn as exu
    SC = exu.SystemContainer()
    return SC, SC.AddSystem()


def _settings(steps=10, end=0.01, solverType=None):
    import exudyn as exu
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps = steps
    ss.timeIntegration.endTime = end
    ss.timeIntegration.verboseMode = 0
    ss.solutionSettings.writeSolutionToFile = False
    if solverType is not None:
        ss.timeIntegration.solverType = solverType
    return ss


def _pendulum(**kw):
    from exudyn.utilities import InertiaCuboid
    SC, mbs = _system()
    g = mbs.CreateGround()
    b = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [1, 0.1, 0.1]), referencePosition=[0.5, 0, 0],
                            gravity=[0, -9.81, 0])
    mbs.CreateRevoluteJoint(itemNumbers=[g, b], position=[0, 0, 0], axis=[0, 0, 1])
    mbs.Assemble()
    return SC, mbs


def _planar():
    from exudyn.utilities import (CoordinateConstraint, MarkerBodyPosition, MarkerNodeCoordinate, MassPoint2D,
                                  NodePointGround, ObjectRigidBody2D, Point2D, RevoluteJoint2D, Rigid2D)
    SC, mbs = _system()
    nG = mbs.AddNode(NodePointGround())
    mG = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nG, coordinate=0))
    oG = mbs.CreateGround()
    n1 = mbs.AddNode(Rigid2D(referenceCoordinates=[0.5, 0, 0]))
    o1 = mbs.AddObject(ObjectRigidBody2D(mass=1, inertia=0.1, nodeNumber=n1))
    n2 = mbs.AddNode(Point2D(referenceCoordinates=[1, 0]))
    o2 = mbs.AddObject(MassPoint2D(mass=1, nodeNumber=n2))
    mbs.AddObject(RevoluteJoint2D(markerNumbers=[mbs.AddMarker(MarkerBodyPosition(bodyNumber=oG)),
                                                 mbs.AddMarker(MarkerBodyPosition(bodyNumber=o1,
                                                                                  localPosition=[-0.5, 0, 0]))]))
    mbs.AddObject(RevoluteJoint2D(markerNumbers=[mbs.AddMarker(MarkerBodyPosition(bodyNumber=o1,
                                                                                  localPosition=[0.5, 0, 0])),
                                                 mbs.AddMarker(MarkerBodyPosition(bodyNumber=o2))]))
    mbs.AddObject(CoordinateConstraint(markerNumbers=[mG, mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n2,
                                                                                             coordinate=1))]))
    mbs.Assemble()
    return SC, mbs


def _mass_springs():
    SC, mbs = _system()
    g = mbs.CreateGround()
    a = mbs.CreateMassPoint(referencePosition=[1, 0, 0], physicsMass=1, gravity=[0, -9.81, 0])
    b = mbs.CreateMassPoint(referencePosition=[2, 0, 0], physicsMass=1, gravity=[0, -9.81, 0])
    mbs.CreateSpringDamper(bodyNumbers=[g, a], stiffness=1e3, damping=1)
    mbs.CreateSpringDamper(bodyNumbers=[a, b], stiffness=1e3, damping=1)
    mbs.Assemble()
    return SC, mbs


def _stiff_springs():
    """Point masses on springs of 1e8 N/m: h omega = 10 at the step of 1e-3 s, beyond RK4's radius,
    so that SolveDynamic takes the implicit ESDIRK3 by itself."""
    SC, mbs = _mass_springs()
    for k in range(mbs.systemData.NumberOfObjects()):
        if "stiffness" in mbs.GetObject(k):
            mbs.SetObjectParameter(k, "stiffness", 1e8)
    return SC, mbs


def _python_load():
    from exudyn.utilities import InertiaCuboid, LoadForceVector, MarkerBodyRigid
    SC, mbs = _system()
    b = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [1, 0.1, 0.1]), referencePosition=[0, 0, 0])
    m = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b))
    mbs.AddLoad(LoadForceVector(markerNumber=m, loadVector=[0, 0, 0],
                                loadVectorUserFunction=lambda mbs, t, load: [0, 10 * t, 0]))
    mbs.Assemble()
    return SC, mbs


def _evaluated(stiffness=100.0):
    from exudyn.utilities import NodeGenericODE2, ObjectGenericODE2
    SC, mbs = _pendulum()
    n = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0], initialCoordinates=[0.1], initialCoordinates_t=[0.0],
                                    numberOfODE2Coordinates=1))
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[n], massMatrix=[[1.0]], stiffnessMatrix=[[stiffness]]))
    mbs.Assemble()
    return SC, mbs


def _evaluated_stiff():
    return _evaluated(stiffness=1e8)


def cases():
    """``[(what, build, keywords of SolveDynamic, settings)]``."""
    import exudyn as exu
    dopri = exu.DynamicSolverType.DOPRI5
    return [
        ("3D rigid bodies with joints (RK4, SE3)", _pendulum, {}, _settings()),
        ("the same with adaptive steps (DOPRI5)", _pendulum, {}, _settings(solverType=dopri)),
        ("planar bodies, point masses, coordinate constraints", _planar, {}, _settings()),
        ("3D point masses on springs", _mass_springs, {}, _settings()),
        ("a stiff model (the implicit ESDIRK3, chosen by itself)", _stiff_springs, {}, _settings()),
        # the steps ESDIRK3 takes after an event made RK4 unstable during a run (method_choice.py)
        ("3D rigid bodies with joints, ESDIRK3 with adaptive steps (after an impact)", _pendulum,
         {"method": "ESDIRK3"}, _settings()),
        ("a Python load user function", _python_load, {}, _settings()),
        ("the Exudyn-evaluated path (an item the kernel does not have)", _evaluated, {}, _settings()),
        ("the same, stiff (ESDIRK3)", _evaluated_stiff, {}, _settings()),
    ]


def warmup(log=print):
    import exudyn_lie as exl
    todo = cases()
    total = time.perf_counter()
    for k, (what, build, kw, ss) in enumerate(todo, 1):
        tic = time.perf_counter()
        SC, mbs = build()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            exl.SolveDynamic(mbs, ss, showProgress=False, **kw)
        log(f"[{k}/{len(todo)}] {what}: {time.perf_counter() - tic:.1f} s")
    log(f"exudyn_lie warmup: {len(todo)} kinds of model ready in {time.perf_counter() - total:.1f} s")


def main(argv=None):
    argparse.ArgumentParser(prog="python -m exudyn_lie warmup", description=__doc__.split("\n\n")[0]).parse_args(
        argv)
    warmup(lambda s: print(s, flush=True))
    return 0


if __name__ == "__main__":
    sys.exit(main())
