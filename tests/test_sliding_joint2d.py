"""ObjectJointSliding2D on the Exudyn-evaluated path (bridge/evaluated_sliding.py), in the style of
Exudyn's ``ANCFslidingJoint2D.py``: a rigid body slides on a sagging ANCF cable pinned at both
ends, starts on the second element and crosses to the third (Exudyn's PostNewton switches the
joint's cable marker).  The reference is Exudyn's generalized-alpha at a 20 times finer step with
tight Newton tolerances."""
import numpy as np
import pytest

import exudyn as exu
from exudyn.itemInterface import (Cable2D, CoordinateConstraint, Force, Gravity, MarkerBodyCable2DCoordinates,
                                  MarkerBodyMass, MarkerBodyRigid, MarkerNodeCoordinate, MarkerNodePosition,
                                  NodeGenericData, NodePointGround, ObjectConnectorCoordinate, ObjectJointSliding2D,
                                  Point2DS1, Rigid2D, RigidBody2D, SensorNode, SensorObject)

import exudyn_lie as exl
from exudyn_lie.bridge.reader import BridgeError

H = 1e-4
T = 0.25
FINE = 20


def build(h=H, tEnd=T, axialForce=0.0, drive=False, **joint):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    L, rho, b, E, g, nElements = 2.0, 1000.0, 0.01, 2e8, 9.81, 4
    A, I = b * b, b ** 4 / 12
    lElem = L / nElements
    mGround = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0))
    nodes = [mbs.AddNode(Point2DS1(referenceCoordinates=[0, 0, 1, 0]))]
    cables = []
    for i in range(nElements):
        nodes.append(mbs.AddNode(Point2DS1(referenceCoordinates=[lElem * (i + 1), 0, 1, 0])))
        e = mbs.AddObject(Cable2D(physicsLength=lElem, physicsMassPerLength=rho * A, physicsBendingStiffness=E * I,
                                  physicsAxialStiffness=E * A, nodeNumbers=[nodes[-2], nodes[-1]]))
        cables.append(e)
        mbs.AddLoad(Gravity(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=e)), loadVector=[0, -g, 0]))
    for n in (nodes[0], nodes[-1]):                      # both ends pinned
        for c in (0, 1):
            mc = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=c))
            mbs.AddObject(CoordinateConstraint(markerNumbers=[mGround, mc]))
    m, sInit = 0.05, 1.3 * lElem
    nRigid = mbs.AddNode(Rigid2D(referenceCoordinates=[sInit, 0, 0], initialVelocities=[2.0, 0, 0]))
    oRigid = mbs.AddObject(RigidBody2D(physicsMass=m, inertia=m * 0.01, nodeNumber=nRigid))
    mbs.AddLoad(Force(markerNumber=mbs.AddMarker(MarkerNodePosition(nodeNumber=nRigid)), loadVector=[0, -m * g, 0]))
    markers = [mbs.AddMarker(MarkerBodyCable2DCoordinates(bodyNumber=e)) for e in cables]
    nData = mbs.AddNode(NodeGenericData(initialCoordinates=[1, sInit], numberOfDataCoordinates=2))
    oJoint = mbs.AddObject(ObjectJointSliding2D(name="slider", markerNumbers=[mbs.AddMarker(MarkerBodyRigid(
        bodyNumber=oRigid)), markers[1]], slidingMarkerNumbers=markers, slidingMarkerOffsets=[i * lElem for i in
                                                                                              range(nElements)],
        nodeNumber=nData, axialForce=axialForce, **joint))
    if drive:       # the slider's angle driven by an offset function (a row Exudyn differentiates in time)
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mGround, mbs.AddMarker(MarkerNodeCoordinate(
            nodeNumber=nRigid, coordinate=2))], offsetUserFunction=lambda mbs, t, i, off: 0.3 * np.sin(5 * t)))
    S = dict(position=mbs.AddSensor(SensorNode(nodeNumber=nRigid, storeInternal=True,
                                               outputVariableType=exu.OutputVariableType.Coordinates)),
             sliding=mbs.AddSensor(SensorObject(objectNumber=oJoint, storeInternal=True,
                                                outputVariableType=exu.OutputVariableType.SlidingCoordinate)),
             force=mbs.AddSensor(SensorObject(objectNumber=oJoint, storeInternal=True,
                                              outputVariableType=exu.OutputVariableType.Force)))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps = int(round(tEnd / h))
    ss.timeIntegration.endTime = tEnd
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = tEnd / 25
    return SC, mbs, ss, S, nData


_REFERENCES = {}


def solve(native, h=H, **kw):
    if native:          # a fine native run serves every test of its model (50,000 steps of a few seconds)
        key = (h, tuple(sorted(kw.items())))
        if key not in _REFERENCES:
            _REFERENCES[key] = _solve(native, h, **kw)
        return tuple(x.copy() if isinstance(x, np.ndarray) else {k: v.copy() for k, v in x.items()}
                     for x in _REFERENCES[key])
    return _solve(native, h, **kw)


def _solve(native, h=H, **kw):
    SC, mbs, ss, S, nData = build(h=h, **kw)
    if native:
        ss.timeIntegration.newton.relativeTolerance = 1e-12
        ss.timeIntegration.newton.absoluteTolerance = 1e-12
        mbs.SolveDynamic(ss)
    else:
        with pytest.warns(RuntimeWarning, match="ObjectJointSliding2D"):
            exl.SolveDynamic(mbs, ss, showProgress=False)
    out = {k: np.asarray(mbs.GetSensorStoredData(s))[:, 1:] for k, s in S.items()}
    return out, np.asarray(mbs.systemData.GetDataCoordinates())


@pytest.mark.parametrize("axialForce, drive, classical", [(0.0, False, True), (0.2, False, True), (0.0, True, True),
                                                        (0.0, False, False), (0.0, True, False)])
def test_sliding_joint_follows_the_fine_native_run_across_elements(axialForce, drive, classical):
    """The slider's position, its sliding coordinate (Exudyn's SlidingCoordinate output: data node
    plus the AE unknown) and the joint's force (Exudyn's Force output: the AE unknowns) against
    generalized-alpha at h/20.  exudyn_lie at h: within 1e-5 m; the force (up to 2.8 N) within
    2e-3 N, after t = 0: at t = 0 Exudyn's output of the force along the curve is 0 (its initial
    accelerations leave axialForce out), exudyn_lie's is axialForce from the start.  Both runs end
    on the third element (data node: marker index 2).  With ``drive`` the slider's angle follows the
    offset function of a ConnectorCoordinate (position: x, y and the angle): the joint makes every
    row's eta come from the position level, which holds the function's time dependence already
    (it was added a second time before).

    ``classical=False``: Exudyn's useClassicalFormulation=False (rows: a dummy, the normal row,
    the closest-point row of s; its force output (0, lam_1)).  It is the same motion, so the motion's
    reference is the classical formulation's fine run: Exudyn's generalized-alpha adds the
    Jacobian's row of s times the step's increment of s to the forces, a term of the order of the
    step, which is small in the classical formulation (that row holds the joint's force) but not in
    this one (it holds the slope): at h/20 its run is 1.03e-5 m from exudyn_lie, at h/40 4.3e-6 m,
    while the classical formulation's is 3.7e-7 m at h/20.  The force is compared with its own fine
    run."""
    kw = dict(axialForce=axialForce, drive=drive, useClassicalFormulation=classical)
    ref, refData = solve(True, H / FINE, **dict(kw, useClassicalFormulation=True))
    if not classical:
        ref["force"] = solve(True, H / FINE, **kw)[0]["force"]
    ours, data = solve(False, **kw)
    assert refData[0] == 2.0 and data[0] == 2.0            # the switch to the next element happened
    dPos = np.abs(ours["position"] - ref["position"]).max()
    dS = np.abs(ours["sliding"] - ref["sliding"]).max()
    dF = np.abs(ours["force"][1:] - ref["force"][1:]).max()
    if drive:
        assert np.ptp(ref["position"][:, 2]) > 0.2         # the angle moved (0.3 sin(5 t) to 0.28 rad)
    print(f"axialForce {axialForce}, drive {drive}, classical {classical}: position {dPos:.3g} m, sliding coordinate {dS:.3g} m, force {dF:.3g} N "
          f"(max |force| {np.abs(ref['force']).max():.3g} N) from generalized-alpha at h/{FINE}")
    assert np.ptp(ref["sliding"]) > 0.3                     # it slid
    assert dPos < 1e-5 and dS < 1e-5
    assert dF < 2e-3


def test_sliding_joint_switched_off_during_the_run_stops_it():
    """Only the joints active at the start have their sliding coordinate taken from the positions:
    one switched off by a user function stops the run with an error that says so."""
    SC, mbs, ss, S, nData = build()
    o = next(i for i in range(mbs.systemData.NumberOfObjects()) if mbs.GetObject(i)["objectType"] == "JointSliding2D")

    def pre(mbs, t):
        if t > 0.01:
            mbs.SetObjectParameter(o, "activeConnector", False)
        return True
    mbs.SetPreStepUserFunction(pre)
    with pytest.warns(RuntimeWarning), pytest.raises(BridgeError, match="switched on or off during the run"):
        exl.SolveDynamic(mbs, ss, showProgress=False)


@pytest.mark.parametrize("classical", [True, False])
def test_constrained_rotation_is_refused(classical):
    SC, mbs, ss, S, nData = build(constrainRotation=True, useClassicalFormulation=classical)
    match = "constrainRotation=True"
    with pytest.raises(BridgeError, match=r"object \d+ \('slider'\) ObjectJointSliding2D: " + match):
        exl.SolveDynamic(mbs, ss, showProgress=False)
