"""Never silently wrong: the three real scripts that returned another model's answer, in
the style of Exudyn's own scripts (written here), against native references at a fine step,
and the run-time check of the constraints (exudyn_lie/bridge/constraint_check.py) that stops
a model made wrong on purpose.

* Exudyn's ``Examples/slidercrankWithMassSpring.py``: a crank and a rod of tiny inertia
  (scaled by 1e-10), two ``MassPoint2D`` sliders held on y = 0 by ``CoordinateConstraint``s, a
  ``CoordinateSpringDamper`` between them, a torque on the crank angle, the initial state from
  ``SolveStatic`` and the crank's angle constraint switched off.  The rank rule relative to the
  largest diagonal of ``J M^-1 J^T`` took the rail row for redundant (the crank's rotation rows
  are 1e11 times larger) and the slider left its rail; the rule relative to each row's own
  diagonal (mbs/linalg.py) keeps it.
* Exudyn's ``TestModels/genericJointUserFunctionTest.py``: ``GenericJoint``s whose frames turn
  by ``offsetUserFunction``.  Exudyn's velocity-level equation of the joint leaves the offset
  out, so the evaluated path's eta held the joints at their t = 0 offset; eta of these rows now
  comes from the position level (bridge/evaluated.py, ``position_derived_rows``).
"""
import warnings

import numpy as np
import pytest

import exudyn as exu
from exudyn.utilities import (CoordinateConstraint, LoadCoordinate, MarkerBodyPosition, MarkerBodyRigid,
                              MarkerNodeCoordinate, MassPoint2D, NodePointGround, NodeRigidBodyEP, ObjectConnectorCoordinateSpringDamper,
                              ObjectGround, ObjectJointGeneric, ObjectRigidBody, ObjectRigidBody2D, Point2D, Rigid2D,
                              RevoluteJoint2D, SensorNode, Gravity, MarkerBodyMass)

import exudyn_lie as exl
from exudyn_lie.errors import ConstraintError

O = exu.OutputVariableType


def slider_crank():
    """Exudyn's slider-crank with a mass-spring (its example, written again here)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    nGround = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mGround = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nGround, coordinate=0))
    oGround = mbs.AddObject(ObjectGround(referencePosition=[0, 0, 0]))
    mG0 = mbs.AddMarker(MarkerBodyPosition(bodyNumber=oGround, localPosition=[0, 0, 0]))
    L1, L2, L3 = 0.3, 0.6, 0.2
    s1, s2 = 0.5 * L1, 0.5 * L2
    m1, m2, m3, m4 = 0.36, 0.15, 0.1, 0.7
    J1 = m1 / 12 * L1 ** 2 * 1e-10                  # the example's nearly massless rotations
    J2 = m2 / 12 * L2 ** 2 * 1e-10
    n1 = mbs.AddNode(Rigid2D(referenceCoordinates=[s1, 0, 0]))
    o1 = mbs.AddObject(ObjectRigidBody2D(physicsMass=m1, physicsInertia=J1, nodeNumber=n1))
    n2 = mbs.AddNode(Rigid2D(referenceCoordinates=[L1 + s2, 0, 0]))
    o2 = mbs.AddObject(ObjectRigidBody2D(physicsMass=m2, physicsInertia=J2, nodeNumber=n2))
    n3 = mbs.AddNode(Point2D(referenceCoordinates=[L1 + L2, 0]))
    o3 = mbs.AddObject(MassPoint2D(physicsMass=m3, nodeNumber=n3))
    n4 = mbs.AddNode(Point2D(referenceCoordinates=[L1 + L2 + L3, 0]))
    mbs.AddObject(MassPoint2D(physicsMass=m4, nodeNumber=n4))
    m1L = mbs.AddMarker(MarkerBodyPosition(bodyNumber=o1, localPosition=[-s1, 0, 0]))
    m1R = mbs.AddMarker(MarkerBodyPosition(bodyNumber=o1, localPosition=[s1, 0, 0]))
    m2L = mbs.AddMarker(MarkerBodyPosition(bodyNumber=o2, localPosition=[-s2, 0, 0]))
    m2R = mbs.AddMarker(MarkerBodyPosition(bodyNumber=o2, localPosition=[s2, 0, 0]))
    m3P = mbs.AddMarker(MarkerBodyPosition(bodyNumber=o3, localPosition=[0, 0, 0]))
    mbs.AddObject(RevoluteJoint2D(markerNumbers=[mG0, m1L]))
    mbs.AddObject(RevoluteJoint2D(markerNumbers=[m1R, m2L]))
    mbs.AddObject(RevoluteJoint2D(markerNumbers=[m2R, m3P]))
    mX3 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n3, coordinate=0))
    mY3 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n3, coordinate=1))
    mX4 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n4, coordinate=0))
    mY4 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n4, coordinate=1))
    mbs.AddObject(CoordinateConstraint(markerNumbers=[mGround, mY3]))
    mbs.AddObject(CoordinateConstraint(markerNumbers=[mGround, mY4]))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mX3, mX4], stiffness=1000))
    mTheta = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n1, coordinate=2))
    angle = mbs.AddObject(CoordinateConstraint(markerNumbers=[mTheta, mGround], offset=-np.pi / 2))
    mbs.AddLoad(LoadCoordinate(markerNumber=mTheta, load=1.0))
    sensor = mbs.AddSensor(SensorNode(nodeNumber=n3, storeInternal=True, outputVariableType=O.Position))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    mbs.SolveStatic(ss)                                  # the crank at -90 degrees
    mbs.systemData.SetSystemState(mbs.systemData.GetSystemState(), configuration=exu.ConfigurationType.Initial)
    mbs.SetObjectParameter(angle, "activeConnector", False)
    return mbs, n3, n4, sensor


def settings(steps, T, sensorPeriod=None):
    """The scripts' settings: ``steps`` steps to ``T``, no solution file, generalized-alpha's
    spectral radius 0.6 (both scripts set it)."""
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = T
    ss.timeIntegration.numberOfSteps = steps
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    if sensorPeriod is not None:
        ss.solution.sensors.writePeriod = sensorPeriod
    ss.timeIntegration.generalizedAlpha.spectralRadius = 0.6
    return ss


def slider_settings(steps, T=0.5):
    return settings(steps, T, T / 100)


def generic_settings(steps, T=1.0):
    return settings(steps, T)


@pytest.fixture(scope="module")
def slider_reference():
    """Native generalized-alpha at h = 2.5e-6 s (the example's step 5e-3 s / 2000)."""
    mbs, n3, n4, _ = slider_crank()
    mbs.SolveDynamic(slider_settings(200000))
    return np.array(mbs.GetNodeOutput(n3, O.Position)), np.array(mbs.GetNodeOutput(n4, O.Position))


def test_slider_crank_of_tiny_inertia_keeps_its_sliders_on_the_rail(slider_reference):
    """At a tenth of the example's step the sliders' x agree with the fine native reference to
    1e-5 m, and the sliders stay on y = 0 at every output (the slider left it by 1.82 m)."""
    mbs, n3, n4, sensor = slider_crank()
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        assert exl.SolveDynamic(mbs, slider_settings(1000), showProgress=False) is True
    assert not any("redundant" in str(w.message) or "drift" in str(w.message) for w in rec)
    y = np.asarray(mbs.GetSensorStoredData(sensor))[:, 2]
    assert np.max(np.abs(y)) < 1e-9
    p3, p4 = np.array(mbs.GetNodeOutput(n3, O.Position)), np.array(mbs.GetNodeOutput(n4, O.Position))
    ref3, ref4 = slider_reference
    assert abs(p3[0] - ref3[0]) < 1e-5 and abs(p4[0] - ref4[0]) < 1e-5, (p3, ref3, p4, ref4)


def test_rows_dropped_as_redundant_must_hold(monkeypatch):
    """A test hook makes the rank rule drop rows that are not redundant (the slider-crank's
    independent rail and joint rows, with a pivot tolerance of 1e-4): the run-time check stops
    at the first output, naming the item whose rows were dropped, instead of returning a
    slider off its rail."""
    import exudyn_lie.mbs.compiled as compiled
    import exudyn_lie.mbs.simulator as simulator
    monkeypatch.setattr(compiled, "REL_PIVOT_TOL", 1e-4)
    monkeypatch.setattr(simulator, "REL_PIVOT_TOL", 1e-4)
    mbs, *_ = slider_crank()
    with pytest.warns(RuntimeWarning, match="redundant constraints"):
        with pytest.raises(ConstraintError, match=r"object \d+ .* were taken for redundant, but they do not hold"):
            # the unstabilised method: the default position projection would stop first, as
            # unable to satisfy the rows the hook dropped (also a stop, but not the check's)
            exl.SolveDynamic(mbs, slider_settings(100), showProgress=False, stabilization=None)


# ----------------------------------------------------------------------------- moving joint offsets
def offset(mbs, t, itemIndex, param):
    """The joint frames turn about x and z, and move along y, from rest at t = 0."""
    s = 0.5 * (1.0 - np.cos(t * 2 * np.pi / 4))
    return [0, 0.05 * s, 0, -0.5 * np.pi * s / 3, 0, -2 * np.pi * s / 3]


def offset_t(mbs, t, itemIndex, param):
    return [0, 0, 0, 0, 0, 0]        # read only by Exudyn's index-2 solve, which refuses it


def generic_joint_chain(withRate=False):
    """Three NodeRigidBodyEP bodies in a chain of GenericJoints (genericJointUserFunctionTest's
    style); the first two joints move by offsetUserFunction."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    sx = 0.3
    oGround = mbs.AddObject(ObjectGround(referencePosition=[0, 0, 0]))
    mLast = mbs.AddMarker(MarkerBodyRigid(bodyNumber=oGround, localPosition=[-sx, 0, 0]))
    for i in range(3):
        n = mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[i * 2 * sx, 0, 0, 1, 0, 0, 0]))
        o = mbs.AddObject(ObjectRigidBody(physicsMass=2, physicsInertia=[6, 1, 6, 0, 0, 0], nodeNumber=n))
        mbs.AddLoad(Gravity(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=o)), loadVector=[0, -9.81, 0]))
        mPos = mbs.AddMarker(MarkerBodyRigid(bodyNumber=o, localPosition=[-sx, 0, 0]))
        kw = dict(offsetUserFunction=offset, offsetUserFunctionParameters=[0] * 6) if i < 2 else {}
        if i < 2 and withRate:
            kw["offsetUserFunction_t"] = offset_t
        mbs.AddObject(ObjectJointGeneric(markerNumbers=[mPos, mLast], constrainedAxes=[int(i > 0), 1, 1, 1, 1, 1],
                                         **kw))
        mLast = mbs.AddMarker(MarkerBodyRigid(bodyNumber=o, localPosition=[sx, 0, 0]))
    mbs.Assemble()
    return mbs, o


@pytest.fixture(scope="module")
def generic_reference():
    """Native index-3 generalized-alpha at h = 1e-5 s."""
    mbs, o = generic_joint_chain()
    mbs.SolveDynamic(generic_settings(100000))
    return np.array(mbs.GetObjectOutputBody(o, O.Position, localPosition=[0, 0, 0]))


@pytest.mark.parametrize("withRate", [False, True])
def test_moving_generic_joint_offsets_follow_the_offset_function(generic_reference, withRate):
    """The last body converges to the fine native reference at RK4's order: its error falls
    by more than 100 (4^4 = 256) from h = 1e-3 s to 2.5e-4 s, to below 5e-5 m (before, it was
    metres off at any step: the joints held their offset of t = 0).  With
    offsetUserFunction_t, Exudyn cannot evaluate the velocity level at all, and every row's
    eta comes from the position level."""
    err = []
    for steps in (1000, 4000):
        mbs, o = generic_joint_chain(withRate)
        with pytest.warns(RuntimeWarning, match="offsetUserFunction"):
            assert exl.SolveDynamic(mbs, generic_settings(steps), showProgress=False) is True
        p = np.array(mbs.GetObjectOutputBody(o, O.Position, localPosition=[0, 0, 0]))
        err.append(float(np.max(np.abs(p - generic_reference))))
    assert err[1] < 5e-5 and err[0] / err[1] > 100, err


def test_check_stops_a_velocity_level_that_leaves_the_offset_out(monkeypatch):
    """A test hook restores the old defect (eta of the moving joints from Exudyn's velocity
    level, which leaves their offset out): the run-time check stops the run, naming the
    joint; with constraintCheck=False the same run returns True with the wrong answer."""
    from exudyn_lie.bridge import evaluated
    monkeypatch.setattr(evaluated, "position_derived_rows", lambda mbs: (np.zeros(0, np.int64), False))
    mbs, o = generic_joint_chain()
    with pytest.warns(RuntimeWarning, match="offsetUserFunction"):
        with pytest.raises(ConstraintError, match=r"object [24] .*ObjectJointGeneric do not hold .* not what the "
                                                  r"velocity-level equations"):
            exl.SolveDynamic(mbs, generic_settings(1000), showProgress=False)
    mbs, o = generic_joint_chain()
    with pytest.warns(RuntimeWarning, match="offsetUserFunction"):
        assert exl.SolveDynamic(mbs, generic_settings(1000), showProgress=False, constraintCheck=False) is True


def test_check_stops_a_compiled_row_that_differs_from_exudyns(monkeypatch):
    """A test hook moves one joint's point on its body in the compiled scene (the kernel then
    holds another constraint than Exudyn's): the check stops at the first output that shows
    it, naming Exudyn's object; the unchanged model runs with the check on."""
    from exudyn_lie.bridge import reader
    original = reader.SceneFromExudyn

    def shifted(*a, **kw):
        sc = original(*a, **kw)
        j = sc.joints[0]
        j.posB = np.asarray(j.posB, float) + np.array([0.0, 0.02, 0.0])
        return sc

    mbs2, o2 = pendulum_pair()
    assert exl.SolveDynamic(mbs2, generic_settings(200, 0.2), showProgress=False) is True
    monkeypatch.setattr(reader, "SceneFromExudyn", shifted)
    from exudyn_lie.bridge import evaluated_dispatch, solver as solver_module
    monkeypatch.setattr(solver_module, "SceneFromExudyn", shifted)
    monkeypatch.setattr(evaluated_dispatch, "SceneFromExudyn", shifted)      # the path choice's reading is used
    mbs2, o2 = pendulum_pair()
    with pytest.raises(ConstraintError, match=r"object \d+ .* do not hold .* exudyn_lie's own rows of it are at"):
        exl.SolveDynamic(mbs2, generic_settings(200, 0.2), showProgress=False)


def pendulum_pair():
    """Two bodies on spherical joints (the compiled path)."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    oGround = mbs.AddObject(ObjectGround(referencePosition=[0, 0, 0]))
    mLast = mbs.AddMarker(MarkerBodyRigid(bodyNumber=oGround, localPosition=[0, 0, 0]))
    for i in range(2):
        n = mbs.AddNode(NodeRigidBodyEP(referenceCoordinates=[0.5 + i, 0, 0, 1, 0, 0, 0]))
        o = mbs.AddObject(ObjectRigidBody(physicsMass=1, physicsInertia=[0.01, 0.1, 0.1, 0, 0, 0], nodeNumber=n))
        mbs.AddLoad(Gravity(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=o)), loadVector=[0, -9.81, 0]))
        mA = mbs.AddMarker(MarkerBodyRigid(bodyNumber=o, localPosition=[-0.5, 0, 0]))
        mbs.AddObject(ObjectJointGeneric(markerNumbers=[mLast, mA], constrainedAxes=[1, 1, 1, 0, 0, 0]))
        mLast = mbs.AddMarker(MarkerBodyRigid(bodyNumber=o, localPosition=[0.5, 0, 0]))
    mbs.Assemble()
    return mbs, o


def test_constraint_check_keyword_is_validated():
    mbs, o = pendulum_pair()
    with pytest.raises(ValueError, match="constraintCheck"):
        exl.SolveDynamic(mbs, generic_settings(10, 0.01), constraintCheck=-1.0)


# ----------------------------------------------------------------------------- offsets moved by a pre-step function
def trolley(nSteps):
    """A trolley (MassPoint2D) whose x a CoordinateConstraint drives through its ``offset``,
    moved by a pre-step function as Exudyn's craneReevingSystem.py moves its winch, with a
    pendulum (RigidBody2D on a RevoluteJoint2D) hanging from it."""
    from exudyn.utilities import SmoothStep
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    nGround = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mGround = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nGround, coordinate=0))
    nT = mbs.AddNode(Point2D(referenceCoordinates=[0, 0]))
    oT = mbs.AddObject(MassPoint2D(physicsMass=2.0, nodeNumber=nT))
    mX = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nT, coordinate=0))
    mY = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nT, coordinate=1))
    cc = mbs.AddObject(CoordinateConstraint(markerNumbers=[mGround, mX], offset=0))
    mbs.AddObject(CoordinateConstraint(markerNumbers=[mGround, mY]))
    nP = mbs.AddNode(Rigid2D(referenceCoordinates=[0, -0.5, 0]))
    oP = mbs.AddObject(ObjectRigidBody2D(physicsMass=1.0, physicsInertia=1.0 / 12 * 1.0, nodeNumber=nP))
    mbs.AddLoad(Gravity(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=oP)), loadVector=[0, -9.81, 0]))
    mbs.AddObject(RevoluteJoint2D(markerNumbers=[mbs.AddMarker(MarkerBodyPosition(bodyNumber=oT)),
                                                 mbs.AddMarker(MarkerBodyPosition(bodyNumber=oP,
                                                                                  localPosition=[0, 0.5, 0]))]))

    def PreStepUserFunction(mbs, t):
        mbs.SetObjectParameter(cc, "offset", SmoothStep(t, 0.1, 0.6, 0, 0.4))
        return True
    mbs.SetPreStepUserFunction(PreStepUserFunction)
    mbs.Assemble()
    ss = generic_settings(nSteps, 1.0)
    return mbs, nT, nP, ss


@pytest.mark.parametrize("evaluation", ["compiled", "exudyn"])
def test_offset_moved_by_a_pre_step_function_is_followed(evaluation):
    """On both paths the trolley follows the offset that the pre-step function moves (Exudyn
    calls it with the step's end time and its index-3 solve holds the offset there).  Against
    native at 1e-5 s: 8e-9 rad (evaluated) and 1.1e-8 (compiled) at the script's step of
    1e-3 s, where native itself at that step is 3.5e-6 off, and 1.1e-10 / 1.6e-10 at 2.5e-4 s
    (below the reference's own error).  Before, the velocity level did not know the offset
    moved and the trolley stayed where it was (the compiled path stopped); with a rate from
    the last three offsets alone, its jumps from step to step stayed in the velocity (first
    order: 6.7e-4 rad at 1e-3 s)."""
    mbs, nT, nP, ss = trolley(100000)
    mbs.SolveDynamic(ss)
    ref = np.array(mbs.GetNodeOutput(nP, O.Coordinates))
    err = []
    for steps in (1000, 4000):
        mbs, nT, nP, ss = trolley(steps)
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always")
            assert exl.SolveDynamic(mbs, ss, showProgress=False, evaluation=evaluation) is True
        assert not any("drift" in str(w.message) for w in rec)
        compiled = type(mbs.sys["lieGroupSolver"]).__name__ == "LieGroupSolver"
        assert compiled == (evaluation == "compiled")
        assert abs(mbs.GetNodeOutput(nT, O.Position)[0] - 0.4) < 1e-9          # the trolley arrived
        err.append(float(np.max(np.abs(np.array(mbs.GetNodeOutput(nP, O.Coordinates)) - ref))))
    assert err[0] < 1e-7 and err[1] < 1e-8, err


def test_checked_items_are_joints_and_node_equations():
    """The check watches each constraint once: the joints, and each EP node's own equation as
    the node's (Exudyn lists it under the body too); a free axis' equation (lambda = 0) is not
    watched.  Its tolerance is 1e-5 of the model's size (here the box of 0 ... 2 m)."""
    from exudyn_lie.bridge.constraint_check import ConstraintCheck
    mbs, o = pendulum_pair()
    assert exl.SolveDynamic(mbs, generic_settings(10, 0.01), showProgress=False) is True
    check = mbs.sys["lieGroupSolver"].constraintCheck
    kinds = {(k, mbs.GetObject(i)["objectType"] if k == "object" else mbs.GetNode(i)["nodeType"])
             for k, i, _ in check.items}
    assert kinds == {("object", "JointGeneric"), ("node", "RigidBodyEP")}
    assert len(check.items) == 4 and all(len(rows) == (3 if k == "object" else 1) for k, _, rows in check.items)
    assert 1e-5 * 1.9 < check.tol < 1e-5 * 2.3
    assert isinstance(check, ConstraintCheck) and check.checks >= 1


def test_offset_of_a_velocity_level_row_moved_on_the_compiled_path_stops():
    """A velocity-level row's offset is its velocity target, which the compiled row holds
    fixed: a pre-step function that moves it stops the run when it does, naming the item and
    the time (no answer of another model)."""
    from exudyn_lie.bridge.reader import BridgeError
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    nGround = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mGround = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nGround, coordinate=0))
    nT = mbs.AddNode(Point2D(referenceCoordinates=[0, 0]))
    mbs.AddObject(MassPoint2D(physicsMass=2.0, nodeNumber=nT))
    mX = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nT, coordinate=0))
    cc = mbs.AddObject(CoordinateConstraint(markerNumbers=[mGround, mX], offset=0, velocityLevel=True))

    def PreStepUserFunction(mbs, t):
        mbs.SetObjectParameter(cc, "offset", 0.0 if t < 0.1 else 1.0)
        return True
    mbs.SetPreStepUserFunction(PreStepUserFunction)
    mbs.Assemble()
    with pytest.raises(BridgeError, match=r"object 1 .*ObjectConnectorCoordinate.*parameter 'offset' changed during "
                                          r"the solve at t = 0\.099 s.*position-level row"):
        exl.SolveDynamic(mbs, generic_settings(1000, 1.0), showProgress=False)


def test_check_stops_a_joint_marker_moved_on_the_evaluated_path():
    """A pre-step function moves the marker of a joint (its localPosition on the ground).
    Exudyn's position level sees the joint point move, its velocity level does not, and the
    evaluated path does not honour it (docs/EVALUATED.md, audit): the check stops the run at
    the first step, naming the joint, instead of returning a pendulum on the old point."""
    mbs, o = pendulum_pair()

    def PreStepUserFunction(mbs, t):
        mbs.SetMarkerParameter(0, "localPosition", [0, 0.2 * t, 0])
        return True
    mbs.SetPreStepUserFunction(PreStepUserFunction)
    with pytest.raises(ConstraintError, match=r"object 2 .*ObjectJointGeneric do not hold at t = 0\.001 s"):
        exl.SolveDynamic(mbs, generic_settings(1000, 1.0), showProgress=False, evaluation="exudyn")


def _double_pendulum():
    from test_bridge_common import double_pendulum
    return double_pendulum()




@pytest.mark.parametrize("evaluation", ["compiled", "exudyn"])
def test_drift_warning_names_what_holds_it_on_each_path(evaluation):
    """An unstabilised RK4 run on SO3xR3 at a coarse step (the README's double pendulum, h = 20 ms):
    the joints drift past the tolerance, the integrator's own account explains it, and the warning
    (once per item) names what holds it, on both paths: stabilization='position' (the default, which
    the Exudyn-evaluated path has too: tests/test_evaluated_projection.py) or a smaller step."""
    remedy = "stabilization='position' or a smaller step"
    mbs = _double_pendulum()
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps, ss.timeIntegration.endTime = 100, 2.0
    ss.solution.file.write = False
    ss.timeIntegration.verboseMode = 0
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        exl.SolveDynamic(mbs, ss, method="RK4", liegroup="SO3xR3", stabilization=None, evaluation=evaluation,
                         showProgress=False)
    drift = [str(w.message) for w in rec if "drift: Exudyn's residual" in str(w.message)]
    assert drift and all("explains it: the drift of index-1 integration" in m and remedy in m for m in drift), drift
    assert len(drift) == len(set(m.split(" drift:")[0] for m in drift))          # once per item


def test_check_stops_a_marker_moved_on_a_swinging_body_at_a_coarse_step():
    """A pre-step function moves the marker of the second joint on the first (swinging) bar at RK4's
    coarse step of the evaluated path's projection test (h = 0.1 s, omega h ~ 0.3).  The moved marker
    moves Exudyn's velocity level too (omega x dp), as the method's own error does, so the velocity
    level's drift does not excuse growth where a Python function runs between steps
    (constraint_check.ConsistencyAccount): the check stops the run early, naming the joint; the same
    run without the pre-step function runs to the end (tests/test_evaluated_projection.py)."""
    from test_bridge_common import double_pendulum
    mbs = double_pendulum(swinging=True)
    joint2 = 4
    mA = mbs.GetObject(joint2)["markerNumbers"][0]
    p0 = np.array(mbs.GetMarker(mA)["localPosition"], float)

    def PreStepUserFunction(mbs, t):
        mbs.SetMarkerParameter(mA, "localPosition", list(p0 + [0.0, 0.5 * t, 0.0]))
        return True
    mbs.SetPreStepUserFunction(PreStepUserFunction)
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps, ss.timeIntegration.endTime = 20, 2.0
    ss.solution.file.write = False
    ss.timeIntegration.verboseMode = 0
    with pytest.raises(ConstraintError, match=r"object 4 .* do not hold at t = 0\.[1-3] s.* not what the velocity-level"):
        exl.SolveDynamic(mbs, ss, method="RK4", evaluation="exudyn", showProgress=False)
