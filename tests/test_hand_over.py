"""A parameter the compiled kernel holds fixed, changed by a user function during the solve: with
SolveDynamic's default evaluation='auto' the run continues on the Exudyn-evaluated path from that
step (bridge/time_loop.py, LieGroupSolver.hand_over).  The model is Exudyn's
``switchingConstraintsPendulum.py`` with gravity: a pendulum carries a mass point through two
ConnectorCoordinates; a pre-step function switches them off at t = 0.1 s and the pendulum's
revolute joint at t = 0.3 s.  The reference is Exudyn's generalized-alpha at a 20 times finer step."""
import numpy as np
import pytest

import exudyn as exu
from exudyn.itemInterface import (CoordinateConstraint, Force, MarkerBodyPosition, MarkerNodeCoordinate,
                                  MarkerNodePosition, MassPoint2D, ObjectGround, Point2D, RevoluteJoint2D, Rigid2D,
                                  RigidBody2D, SensorNode)

import warnings

import exudyn_lie as exl
from exudyn_lie.bridge.reader import BridgeError

H, T, FINE = 1e-3, 0.5, 20


def build(h=H):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    g, a, m, mp, w0 = 9.81, 0.5, 12.0, 2.0, 4.0
    oGround = mbs.AddObject(ObjectGround())
    nRigid = mbs.AddNode(Rigid2D(referenceCoordinates=[-0.5, 0, 0], initialVelocities=[0, w0 * a, w0]))
    oRigid = mbs.AddObject(RigidBody2D(physicsMass=m, inertia=m / 12 * (2 * a) ** 2, nodeNumber=nRigid))
    oJoint = mbs.AddObject(RevoluteJoint2D(markerNumbers=[
        mbs.AddMarker(MarkerBodyPosition(bodyNumber=oGround, localPosition=[-0.5 - a, 0, 0])),
        mbs.AddMarker(MarkerBodyPosition(bodyNumber=oRigid, localPosition=[-0.5, 0, 0]))]))
    nMass = mbs.AddNode(Point2D(referenceCoordinates=[-0.5, 0], initialVelocities=[0, w0 * a]))
    mbs.AddObject(MassPoint2D(physicsMass=mp, nodeNumber=nMass))
    cons = [mbs.AddObject(CoordinateConstraint(markerNumbers=[
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nMass, coordinate=c)),
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nRigid, coordinate=c))])) for c in (0, 1)]
    for n, mass in ((nRigid, m), (nMass, mp)):
        mbs.AddLoad(Force(markerNumber=mbs.AddMarker(MarkerNodePosition(nodeNumber=n)), loadVector=[0, -mass * g, 0]))

    def switch(mbs, t):
        if t > 0.3:
            mbs.SetObjectParameter(oJoint, "activeConnector", False)
        if t > 0.1:
            for c in cons:
                mbs.SetObjectParameter(c, "activeConnector", False)
        return True

    mbs.SetPreStepUserFunction(switch)
    sensors = [mbs.AddSensor(SensorNode(nodeNumber=n, storeInternal=True,
                                        outputVariableType=exu.OutputVariableType.Position)) for n in (nRigid, nMass)]
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps = int(round(T / h))
    ss.timeIntegration.endTime = T
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = 0.02
    return mbs, ss, sensors


def positions(mbs, sensors):
    return np.hstack([np.asarray(mbs.GetSensorStoredData(s))[:, 1:3] for s in sensors])


def test_switched_constraints_continue_on_the_evaluated_path():
    """The run hands over at t = 0.1 s (one warning naming the connector), the evaluated path then
    follows the joint switched off at t = 0.3 s as Exudyn evaluates it.  The bodies' positions equal
    those of evaluation='exudyn' from the start to 1e-9 m (the hand-over loses nothing), and are
    within 1e-4 m of the fine native run, closer than native at h (printed; the runs switch at the
    first step start after 0.1 s and 0.3 s of their own grids, so the fine run is not a tight
    reference); mbs.sys['lieGroupSolver'] is the evaluated driver."""
    mbs, ss, sensors = build(H / FINE)
    ss.timeIntegration.newton.relativeTolerance = 1e-12
    mbs.SolveDynamic(ss)
    ref = positions(mbs, sensors)
    mbs, ss, sensors = build()
    mbs.SolveDynamic(ss)
    native = positions(mbs, sensors)
    mbs, ss, sensors = build()
    with pytest.warns(RuntimeWarning, match=r"object \d+ .*ObjectConnectorCoordinate: parameter 'activeConnector' "
                                            r"was changed by a user function at t = 0\.1"):
        exl.SolveDynamic(mbs, ss, showProgress=False)
    ours = positions(mbs, sensors)
    assert type(mbs.sys["lieGroupSolver"]).__name__ == "EvaluatedSolver"
    mbs, ss, sensors = build()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, ss, showProgress=False, evaluation="exudyn")
    evaluated = positions(mbs, sensors)
    e, en, ee = np.abs(ours - ref).max(), np.abs(native - ref).max(), np.abs(ours - evaluated).max()
    print(f"positions from generalized-alpha at h/{FINE}: exudyn_lie {e:.3g} m, generalized-alpha at h {en:.3g} m; "
          f"from evaluation='exudyn': {ee:.3g} m")
    assert np.ptp(ref[:, 3]) > 0.3                      # the mass point fell away
    assert ee < 1e-9
    assert e < 1e-4 and e < en


def test_compiled_evaluation_keeps_the_error():
    """evaluation='compiled' does not hand over: the change stops the run with the error that names it."""
    mbs, ss, sensors = build()
    with pytest.raises(BridgeError, match=r"parameter 'activeConnector' changed during the solve at t = 0\.1"):
        exl.SolveDynamic(mbs, ss, showProgress=False, evaluation="compiled")


def test_changed_objects_reads_both_kinds_of_marks():
    """The evaluated path's loop reads again the objects a user function changed: its own marks are
    object indices; after a hand-over they are the compiled path's (kind, index, field, value)."""
    from exudyn_lie.bridge.evaluated_solve import changed_objects
    marks = [3, None, ("object", 5, "velocityLevel", None), ("load", 2, "load", None), ("object", 3, None, None)]
    assert changed_objects(marks) == {3, 5}
