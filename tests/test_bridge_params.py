"""Parameters changed during a solve, refused system-level features, repeated hook calls.

Models in the style of Exudyn's TestModels (``serialRobotTest``, ``movingGroundRobotTest``,
``Examples/serialRobotTSD``): user functions set item parameters while Exudyn's time loop
runs.  Every run is compared with Exudyn's own generalized-alpha solve of the same script
at a fine step.  The controllers are *sampled* (a new value every ``TS`` seconds, held in
between), so the model does not depend on the step size: a native run at a fine step then
is the truth of that model, and exudyn_lie at any step that divides ``TS`` must converge to
it (set at a step's start time, a value acts on the whole step in both solvers: Exudyn
calls the pre-step function before the step's Newton iteration).
"""
import numpy as np
import pytest

import exudyn as exu
from exudyn.utilities import (InertiaCuboid, LoadForceVector, MarkerBodyRigid, MarkerNodePosition, NodePointGround,
                              ObjectConnectorSpringDamper, ObjectGround, SensorBody, SensorLoad, SensorObject,
                              SensorUserFunction)

import exudyn_lie as exl
from exudyn_lie.bridge import BridgeError
from exudyn_lie.bridge.params import FIELDS, IGNORED, field_status

O = exu.OutputVariableType
TS = 1e-3                 # sampling period of the controllers [s]


def settings(T, h, sensors=True):
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = T
    ss.timeIntegration.numberOfSteps = int(round(T / h))
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = TS
    ss.timeIntegration.newton.relativeTolerance = 1e-9
    ss.timeIntegration.newton.absoluteTolerance = 1e-10
    ss.timeIntegration.generalizedAlpha.spectralRadius = 0.6      # damps the start-up error after a jump
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    ss.show.statistics = False
    ss.show.computationTime = False
    return ss


def sampled(t):
    """Pre-step functions get the end time t of the step about to be computed: the sampling
    instant at or before the step's start (a value computed there is held for the period)."""
    return (np.ceil(t / TS - 1e-6) - 1) * TS


def sampled_after(t):
    """Post-step functions get the end time t of the step just computed: the sampling
    instant at or before t (the next step starts there)."""
    return np.floor(t / TS + 1e-6) * TS


def solve(build, T, h, native, **kw):
    mbs, out = build()
    mbs.Assemble()
    ss = settings(T, h)
    if native:
        mbs.SolveDynamic(ss)
    else:
        exl.SolveDynamic(mbs, ss, showProgress=False, **kw)
    return mbs, {k: mbs.GetSensorStoredData(s) for k, s in out.items()}


# ----------------------------------------------------------------------------- models
def pd_robot():
    """serialRobotTest: a 6-link robot (exudyn.robotics, redundant coordinates), joint torques
    of 12 LoadTorqueVectors set by a PD controller with static-torque compensation in a
    pre-step function (sampled every TS)."""
    from exudyn.robotics import Robot, RobotBase, RobotLink, RobotTool, StdDH2HT
    from exudyn.robotics.motion import ProfileConstantAcceleration, Trajectory
    from exudyn.rigidBodyUtilities import HT2translation, HTtranslate
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    robot = Robot(gravity=[0, 0, 9.81], base=RobotBase(), tool=RobotTool(HT=HTtranslate([0, 0, 0.1])),
                  referenceConfiguration=[])
    for m, com, J, dh in ((20, [0, 0, 0], [1e-8, 0.35, 1e-8], [0, 0, 0, np.pi / 2]),
                          (17.4, [-0.3638, 0.006, 0.2275], [0.13, 0.524, 0.539], [0, 0, 0.4318, 0]),
                          (4.8, [-0.0203, -0.0141, 0.07], [0.066, 0.086, 0.0125], [0, 0.15, 0.0203, -np.pi / 2]),
                          (0.82, [0, 0.019, 0], [0.0018, 0.0013, 0.0018], [0, 0.4318, 0, np.pi / 2]),
                          (0.34, [0, 0, 0], [0.0003, 0.0004, 0.0003], [0, 0, 0, -np.pi / 2]),
                          (0.09, [0, 0, 0.032], [0.00015, 0.00015, 4e-5], [0, 0, 0, 0])):
        robot.AddLink(RobotLink(mass=m, COM=com, inertia=np.diag(J), localHT=StdDH2HT(dh)))
    traj = Trajectory([0] * 6, 0)
    traj.Add(ProfileConstantAcceleration([0, np.pi / 8, np.pi * 0.25, 0, np.pi / 8, 0], 0.25))
    P = np.array([40000, 40000, 40000, 100, 100, 10])
    D = np.array([400, 400, 100, 1, 1, 0.05])
    g = mbs.AddObject(ObjectGround(referencePosition=HT2translation(robot.GetBaseHT())))
    base = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g, localPosition=[0, 0, 0]))
    rd = robot.CreateRedundantCoordinateMBS(mbs, baseMarker=base)
    joints, u0, u1 = rd["jointList"], rd["unitTorque0List"], rd["unitTorque1List"]
    l0, l1 = rd["jointTorque0List"], rd["jointTorque1List"]
    last = [-1.0]

    def pre_step(mbs, t):
        ts = sampled(t)            # the step (t - h, t] starts in sampling period ts
        if ts == last[0]:
            return True
        last[0] = ts
        q = [mbs.GetObjectOutput(j, O.Rotation)[2] for j in joints]
        static = robot.StaticTorques(robot.JointHT(q))
        for i, j in enumerate(joints):
            om = mbs.GetObjectOutput(j, O.AngularVelocityLocal)[2]
            u, v, a = traj.EvaluateCoordinate(ts, i)
            tau = -(P[i] * (q[i] - u) + D[i] * (om - v)) - static[i]
            mbs.SetLoadParameter(l0[i], "loadVector", list(tau * u0[i]))
            mbs.SetLoadParameter(l1[i], "loadVector", list(tau * u1[i]))
        return True

    mbs.SetPreStepUserFunction(pre_step)
    out = {f"rot{i}": mbs.AddSensor(SensorObject(objectNumber=j, storeInternal=True, outputVariableType=O.Rotation))
           for i, j in enumerate(joints)}
    out.update({f"tau{i}": mbs.AddSensor(SensorLoad(loadNumber=l, storeInternal=True)) for i, l in enumerate(l0)})
    return mbs, out


def pendulum(mbs, nodeType=exu.NodeType.RotationRotationVector):
    """A rigid bar hanging from a revolute joint about the world z axis (gravity along -y)."""
    g = mbs.CreateGround()
    b = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.4, 0.05, 0.05]), referencePosition=[0.2, 0, 0],
                            gravity=[0, -9.81, 0], nodeType=nodeType)
    j = mbs.CreateRevoluteJoint(itemNumbers=[g, b], position=[0, 0, 0], axis=[0, 0, 1])
    return g, b, j


def torsional_offset():
    """serialRobotTSD: a torsional spring whose offset, velocityOffset and torque are moved by
    a pre-step function (sampled every TS)."""
    mbs = exu.SystemContainer().AddSystem()
    g, b, j = pendulum(mbs)
    tsd = mbs.CreateTorsionalSpringDamper(itemNumbers=[g, b], position=[0, 0, 0], axis=[0, 0, 1], stiffness=200,
                                          damping=2)

    def pre_step(mbs, t):
        ts = sampled(t)
        mbs.SetObjectParameter(tsd, "offset", 0.8 * np.sin(20 * ts))
        mbs.SetObjectParameter(tsd, "velocityOffset", 16 * np.cos(20 * ts))
        mbs.SetObjectParameter(tsd, "torque", 0.5 * np.cos(7 * ts))
        return True

    mbs.SetPreStepUserFunction(pre_step)
    out = {"pos": mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position,
                                           localPosition=[0.2, 0, 0])),
           "vel": mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.AngularVelocity))}
    return mbs, out


def switched_spring():
    """A spring switched off and on through activeConnector (post-step function), and a
    Cartesian spring whose stiffness changes."""
    mbs = exu.SystemContainer().AddSystem()
    g, b, j = pendulum(mbs, exu.NodeType.RotationEulerParameters)
    sp = mbs.CreateSpringDamper(itemNumbers=[g, b], localPosition0=[0.3, 0.3, 0], localPosition1=[0.2, 0, 0],
                                stiffness=4000, damping=5, referenceLength=0.2)
    cs = mbs.CreateCartesianSpringDamper(itemNumbers=[g, b], localPosition0=[0.4, -0.1, 0],
                                         localPosition1=[0.2, 0, 0], stiffness=[100, 100, 100], damping=[1, 1, 1])

    def post_step(mbs, t):
        ms = int(round(sampled_after(t) / TS))
        mbs.SetObjectParameter(sp, "activeConnector", not (30 <= ms < 70 or 100 <= ms < 130))
        mbs.SetObjectParameter(cs, "stiffness", [100 + 1000 * (ms >= 50), 100, 100])
        return True

    mbs.SetPostStepUserFunction(post_step)
    out = {"pos": mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position,
                                           localPosition=[0.2, 0, 0]))}
    return mbs, out


def switched_rigid_spring():
    """A RigidBodySpringDamper (compiled) whose stiffness and offset a post-step function
    changes, and which it switches off and on."""
    mbs = exu.SystemContainer().AddSystem()
    g, b, j = pendulum(mbs, exu.NodeType.RotationEulerParameters)
    rs = mbs.CreateRigidBodySpringDamper(itemNumbers=[g, b], localPosition0=[0.3, 0.2, 0], localPosition1=[0.2, 0, 0],
                                         stiffness=np.diag([3000, 3000, 3000, 20, 20, 20.0]),
                                         damping=np.diag([5, 5, 5, 0.1, 0.1, 0.1]), useIntrinsicFormulation=True)

    def post_step(mbs, t):
        ms = int(round(sampled_after(t) / TS))
        mbs.SetObjectParameter(rs, "activeConnector", not (30 <= ms < 70))
        mbs.SetObjectParameter(rs, "stiffness", np.diag([3000 + 2000 * (ms >= 50), 3000, 3000, 20, 20, 20.0]))
        mbs.SetObjectParameter(rs, "offset", [0, 0.05 * (ms >= 100), 0, 0, 0, 0.1 * (ms >= 120)])
        return True

    mbs.SetPostStepUserFunction(post_step)
    out = {"pos": mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position,
                                           localPosition=[0.2, 0, 0]))}
    return mbs, out


def moving_ground():
    """movingGroundRobotTest: ground markers that move (a MarkerBodyRigid's localPosition on
    an ObjectGround, a ground node's referenceCoordinates and an ObjectGround's
    referencePosition), each pulling the pendulum through a spring."""
    mbs = exu.SystemContainer().AddSystem()
    g, b, j = pendulum(mbs)
    mB = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b, localPosition=[0.2, 0, 0]))
    mG = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g, localPosition=[0.5, 0.2, 0]))
    n = mbs.AddNode(NodePointGround(referenceCoordinates=[0.2, -0.4, 0]))
    mN = mbs.AddMarker(MarkerNodePosition(nodeNumber=n))
    g2 = mbs.AddObject(ObjectGround(referencePosition=[-0.3, 0, 0]))
    mG2 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g2, localPosition=[0, 0, 0]))
    for m, k in ((mG, 3000), (mN, 1500), (mG2, 800)):
        mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[m, mB], stiffness=k, damping=3, referenceLength=0.1))
    lf = mbs.AddLoad(LoadForceVector(markerNumber=mG, loadVector=[0, 0, 0]))       # on ground: no effect

    def pre_step(mbs, t):
        ts = sampled(t)
        mbs.SetMarkerParameter(mG, "localPosition", [0.5, 0.2 + 0.1 * np.sin(30 * ts), 0])
        mbs.SetNodeParameter(n, "referenceCoordinates", [0.2 + 0.1 * np.sin(20 * ts), -0.4, 0])
        mbs.SetObjectParameter(g2, "referencePosition", [-0.3, 0.1 * ts, 0])
        mbs.SetLoadParameter(lf, "loadVector", [ts, 0, 0])
        return True

    mbs.SetPreStepUserFunction(pre_step)
    out = {"pos": mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position,
                                           localPosition=[0.2, 0, 0]))}
    return mbs, out


def python_items():
    """Items evaluated in Python: a torsional spring with a springTorqueUserFunction whose
    offset is changed through ModifyObject, and a load with a loadVectorUserFunction whose
    loadVector (scaled by the function) is set, by a pre-step function."""
    mbs = exu.SystemContainer().AddSystem()
    g, b, j = pendulum(mbs)

    def torque(mbs, t, itemNumber, rotation, angularVelocity, stiffness, damping, offset):
        return stiffness * (rotation - offset) + damping * angularVelocity + 0.1 * np.sin(rotation)

    tsd = mbs.CreateTorsionalSpringDamper(itemNumbers=[g, b], position=[0, 0, 0], axis=[0, 0, 1], stiffness=200,
                                          damping=2, springTorqueUserFunction=torque)
    f = mbs.CreateForce(itemNumber=b, localPosition=[0.4, 0, 0], loadVector=[0, 0, 0],
                        loadVectorUserFunction=lambda mbs, t, v: [2 * v[0], 2 * v[1], 0])

    def pre_step(mbs, t):
        ts = sampled(t)
        mbs.ModifyObject(tsd, {"offset": 0.8 * np.sin(20 * ts)})
        mbs.SetLoadParameter(f, "loadVector", [0, 5 * np.cos(15 * ts), 0])
        return True

    mbs.SetPreStepUserFunction(pre_step)
    out = {"pos": mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position,
                                           localPosition=[0.2, 0, 0]))}
    return mbs, out


def sensor_switch():
    """No pre- or post-step function: a sensor user function (evaluated by Exudyn at every
    output, here every TS) moves a torsional spring's offset; the bridge integrates several
    outputs ahead on its compiled path, and must go back when the offset changes."""
    mbs = exu.SystemContainer().AddSystem()
    g, b, j = pendulum(mbs)
    tsd = mbs.CreateTorsionalSpringDamper(itemNumbers=[g, b], position=[0, 0, 0], axis=[0, 0, 1], stiffness=200,
                                          damping=2)
    sp = mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position,
                                  localPosition=[0.2, 0, 0]))

    def moving_offset(mbs, t, sensorNumbers, factors, configuration):
        k = int(round(t / TS))
        if k % 7 == 3:                   # not at every output: the chunk must be cut where it changes
            mbs.SetObjectParameter(tsd, "offset", 0.5 * np.sin(0.03 * k))
        return [k]

    out = {"pos": sp, "uf": mbs.AddSensor(SensorUserFunction(sensorNumbers=[sp], storeInternal=True,
                                                             sensorUserFunction=moving_offset))}
    return mbs, out


def native_truth(build, T, h):
    """Exudyn's generalized-alpha at steps 2h and h, extrapolated to step 0.  The sampled
    values jump, and after a jump generalized-alpha's algorithmic accelerations carry an
    O(h) error (measured: halving h halves the native difference to exudyn_lie), so the
    two fine runs are combined as Richardson's first-order extrapolation ``2 y(h) - y(2h)``."""
    _, coarse = solve(build, T, 2 * h, native=True)
    _, fine = solve(build, T, h, native=True)
    return {k: np.hstack([fine[k][:, :1], 2 * fine[k][:, 1:] - coarse[k][:, 1:]]) for k in fine}


def _compare(build, T, hLie, hNative, tol, **kw):
    """Every stored sensor value over the run: ``|exudyn_lie - native| <= tol(key) * scale``
    (``tol`` a number or a function of the sensor's key)."""
    ref = native_truth(build, T, hNative)
    mbs, got = solve(build, T, hLie, native=False, **kw)
    for k in ref:
        assert got[k].shape == ref[k].shape
        np.testing.assert_allclose(got[k][:, 0], ref[k][:, 0], atol=1e-12)
        err = np.max(np.abs(got[k][:, 1:] - ref[k][:, 1:]))
        scale = max(1.0, np.max(np.abs(ref[k][:, 1:])))
        print(f"{build.__name__} {k}: max |exudyn_lie - native| = {err:.3g} (scale {scale:.3g})")
        assert err <= (tol(k) if callable(tol) else tol) * scale, (k, err, scale)
    return mbs, ref, got


# ----------------------------------------------------------------------------- honoured changes
@pytest.mark.parametrize("method", [None, "DOPRI5"])
def test_pd_robot_load_vectors_set_every_step_match_native(method):
    """Joint angles to 1e-8 rad; the torques are the PD law of them, P = 4e4 N m / rad.  The default
    switches to ESDIRK3 at 0.8 ms (the PD gains make RK4 unstable at 1e-4 s), with adaptive steps
    (bridge/method_choice.py); with DOPRI5 adaptive steps from the start.  Adaptive steps end at each
    Exudyn step here (bridge/fast.AdaptiveOutputChunks, ``clip``): the controller changes the loads
    there and the run continues from that state; from the dense output instead, the joint angles
    were 2.2e-7 rad off with ESDIRK3 and 1.5e-6 with DOPRI5 (9.8e-11 and 1.3e-9 now)."""
    kw = {} if method is None else dict(method=method)
    mbs, ref, got = _compare(pd_robot, 0.1, 1e-4, 1e-5, lambda k: 4e4 * 1e-8 if k.startswith("tau") else 1e-8, **kw)
    # the controller moved the robot: the test would fail with frozen loads
    assert np.max(np.abs(ref["rot1"][:, 3])) > 0.05
    solver = mbs.sys["lieGroupSolver"]
    # only the 12 loads set by the controller were re-read: 11 of the 12 are compiled rows
    # (one acts on ground), once per sampling period
    assert solver._params.updates == 12 * 100


def test_torsional_spring_offset_moved_every_step_matches_native():
    _compare(torsional_offset, 0.2, 1e-4, 1e-5, 1e-6)


def test_spring_switched_off_and_on_matches_native():
    mbs, ref, got = _compare(switched_spring, 0.2, 1e-4, 1e-5, 1e-6)


def test_compiled_rigid_body_spring_changed_and_switched_matches_native():
    mbs, ref, got = _compare(switched_rigid_spring, 0.2, 1e-4, 1e-5, 1e-6)
    assert mbs.sys["lieGroupSolver"]._params.updates > 0


def test_moving_ground_markers_match_native():
    _compare(moving_ground, 0.2, 1e-4, 1e-5, 1e-6)


def test_python_items_changed_through_modify_and_set_match_native():
    _compare(python_items, 0.2, 1e-4, 1e-5, 1e-6)


def test_change_from_a_sensor_user_function_cuts_the_chunk_integrated_ahead():
    mbs, ref, got = _compare(sensor_switch, 0.2, 1e-4, 1e-5, 1e-6)
    assert mbs.sys["lieGroupSolver"]._params.updates == len([k for k in range(201) if k % 7 == 3])


def test_without_the_change_the_result_differs():
    """The comparison can fail: freezing the controller's first values gives another motion."""
    _, ref = solve(torsional_offset, 0.1, 1e-4, native=False)
    mbs, out = torsional_offset()
    mbs.SetPreStepUserFunction(0)
    mbs.Assemble()
    exl.SolveDynamic(mbs, settings(0.1, 1e-4), showProgress=False)
    assert np.max(np.abs(mbs.GetSensorStoredData(out["pos"])[:, 1:] - ref["pos"][:, 1:])) > 1e-3


# ----------------------------------------------------------------------------- a changed structure stops the run
def _stop_at(change, t_change=0.05):
    """The torsional model with ``change(mbs, items)`` made by a pre-step function from
    t_change on, on the compiled path (evaluation='auto' continues on the Exudyn-evaluated path,
    tests/test_hand_over.py); returns the BridgeError's message and the time Exudyn reached."""
    mbs = exu.SystemContainer().AddSystem()
    g, b, j = pendulum(mbs)
    tsd = mbs.CreateTorsionalSpringDamper(itemNumbers=[g, b], position=[0, 0, 0], axis=[0, 0, 1], stiffness=200)

    def pre_step(mbs, t):
        if t > t_change + 1e-9:
            change(mbs, dict(g=g, b=b, j=j, tsd=tsd))
        return True

    mbs.SetPreStepUserFunction(pre_step)
    mbs.Assemble()
    with pytest.raises(BridgeError) as e:
        exl.SolveDynamic(mbs, settings(0.1, 1e-3), showProgress=False, evaluation="compiled")
    return str(e.value), mbs.systemData.GetTime()


def test_joint_switched_off_stops_the_solve_naming_item_and_field():
    msg, t = _stop_at(lambda mbs, it: mbs.SetObjectParameter(it["j"], "activeConnector", False))
    assert "ObjectJointRevoluteZ" in msg and "'activeConnector'" in msg and "t = 0.05" in msg
    assert t == pytest.approx(0.051)         # stopped in the step (0.05, 0.051] whose pre-step function changed it


@pytest.mark.filterwarnings("ignore:ObjectRigidBody:DeprecationWarning")      # physicsMass: an alias of 'mass'
@pytest.mark.parametrize("change, words", [
    (lambda mbs, it: mbs.SetObjectParameter(it["b"], "physicsMass", 2.0), ("ObjectRigidBody", "'mass'")),
    (lambda mbs, it: mbs.SetMarkerParameter(mbs.GetObject(it["j"])["markerNumbers"][0], "localPosition",
                                            [0, 0.01, 0]), ("ObjectJointRevoluteZ", "moved")),
    (lambda mbs, it: mbs.ModifyObject(it["tsd"], {"markerNumbers": mbs.GetObject(it["j"])["markerNumbers"]}),
     ("ObjectConnectorTorsionalSpringDamper", "'markerNumbers'")),
    (lambda mbs, it: mbs.SetNodeParameter(0, "referenceCoordinates", [0.3, 0, 0, 0, 0, 0]),
     ("NodeRigidBodyRotVecLG", "'referenceCoordinates'")),
])
def test_structural_changes_stop_the_solve(change, words):
    msg, t = _stop_at(change)
    for w in words:
        assert w in msg, msg
    assert t == pytest.approx(0.051)


def test_change_inside_a_force_user_function_is_refused():
    mbs = exu.SystemContainer().AddSystem()
    g, b, j = pendulum(mbs)
    tsd = mbs.CreateTorsionalSpringDamper(itemNumbers=[g, b], position=[0, 0, 0], axis=[0, 0, 1], stiffness=200)

    def uf(mbs, t, load):
        mbs.SetObjectParameter(tsd, "offset", t)
        return [0, 0, 0]

    mbs.CreateForce(itemNumber=b, loadVector=[0, 0, 0], loadVectorUserFunction=uf)
    mbs.Assemble()
    with pytest.raises(BridgeError, match="pre-step user function"):
        exl.SolveDynamic(mbs, settings(0.01, 1e-3), showProgress=False)


def test_unchanged_values_and_visualization_cost_nothing():
    """Setting a fixed field to its own value, or a visualization field, is no change."""
    mbs = exu.SystemContainer().AddSystem()
    g, b, j = pendulum(mbs)
    ref = None
    for touch in (False, True):
        mbs2 = exu.SystemContainer().AddSystem()
        g, b, j = pendulum(mbs2)
        s = mbs2.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position))

        def pre_step(mbs, t, j=j, touch=touch):
            if touch:
                mbs.SetObjectParameter(j, "activeConnector", True)
                mbs.SetObjectParameter(j, "Vshow", False)
            return True

        mbs2.SetPreStepUserFunction(pre_step)
        mbs2.Assemble()
        exl.SolveDynamic(mbs2, settings(0.05, 1e-3), showProgress=False)
        data = mbs2.GetSensorStoredData(s)
        if ref is None:
            ref = data
    np.testing.assert_array_equal(data, ref)


# ----------------------------------------------------------------------------- refused before mbs is touched
def _state(mbs):
    sd = mbs.systemData
    out = {"consistent": mbs.systemIsConsistent, "sys": sorted(mbs.sys.keys())}
    for kind, n in (("Object", sd.NumberOfObjects()), ("Node", sd.NumberOfNodes()), ("Marker", sd.NumberOfMarkers()),
                    ("Load", sd.NumberOfLoads()), ("Sensor", sd.NumberOfSensors())):
        out[kind] = [repr({k: v for k, v in getattr(mbs, "Get" + kind)(i).items() if not k.startswith("V")})
                     for i in range(n)]
    if mbs.systemIsConsistent:
        out["state"] = repr(sd.GetSystemState()) + repr(sd.GetSystemState(exu.ConfigurationType.Initial))
        out["time"] = sd.GetTime()
    return out


@pytest.mark.parametrize("assemble", [True, False])
@pytest.mark.parametrize("what", ["PostNewtonUserFunction", "PreNewtonResidualUserFunction",
                                  "SystemJacobianUserFunction"])
def test_unhonoured_system_features_are_refused_with_mbs_unchanged(what, assemble):
    """(GeneralContact is honoured on the Exudyn-evaluated path: tests/test_general_contact.py; the
    compiled path's refusal: tests/test_foreign_items.py.)"""
    mbs, out = torsional_offset()
    if what == "PostNewtonUserFunction":
        mbs.SetPostNewtonUserFunction(lambda mbs, t: [0, -1])
    elif what == "PreNewtonResidualUserFunction":
        mbs.SetPreNewtonResidualUserFunction(lambda mbs, t, newtonIt, discIt: None)
    else:
        mbs.SetSystemJacobianUserFunction(lambda mbs, t, factorODE2, factorODE2_t: None)
    if assemble:
        mbs.Assemble()
    before = _state(mbs)
    # all three are honoured on the Exudyn-evaluated path (tests/test_evaluated.py,
    # tests/test_pre_newton_residual.py): the compiled path refuses them
    with pytest.raises(BridgeError) as e:
        exl.SolveDynamic(mbs, settings(0.01, 1e-3), showProgress=False, evaluation="compiled")
    assert what in str(e.value) and "exudyn.SolveDynamic" in str(e.value)
    assert _state(mbs) == before


# ----------------------------------------------------------------------------- a repeated hook call
@pytest.mark.parametrize("model", ["chunks", "preStep", "python"])
def test_discontinuous_iteration_repeating_the_step_gives_the_same_result(model):
    """Exudyn's discontinuous iteration calls the Newton hook again for the same step (it
    resets the ODE2 coordinates to the start of the step) whenever its post-Newton error
    exceeds ``discontinuous.iterationTolerance``; a negative tolerance forces every step to
    be repeated ``maxIterations`` times.  The result must be the single-call one."""
    results = []
    for repeat in (False, True):
        mbs = exu.SystemContainer().AddSystem()
        g, b, j = pendulum(mbs)
        mbs.CreateTorsionalSpringDamper(itemNumbers=[g, b], position=[0, 0, 0], axis=[0, 0, 1], stiffness=200)
        if model == "preStep":
            mbs.SetPreStepUserFunction(lambda mbs, t: True)
        elif model == "python":
            mbs.CreateForce(itemNumber=b, loadVector=[0, 0, 0], loadVectorUserFunction=lambda mbs, t, v: [0, 0, t])
        s = mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position,
                                     localPosition=[0.2, 0, 0]))
        mbs.Assemble()
        ss = settings(0.05, 1e-3)
        ss.solution.sensors.writePeriod = 1e-2
        checks = exu.special.exceptions.parameterRangeChecks
        exu.special.exceptions.parameterRangeChecks = False      # a negative tolerance (also in the copy)
        try:
            if repeat:
                ss.timeIntegration.discontinuous.iterationTolerance = -1.0
                ss.timeIntegration.discontinuous.maxIterations = 3
                ss.timeIntegration.discontinuous.ignoreMaxIterations = True
            exl.SolveDynamic(mbs, ss, showProgress=False)
        finally:
            exu.special.exceptions.parameterRangeChecks = checks
        it = mbs.sys["dynamicSolver"].it
        calls = it.discontinuousIterationsCount      # Newton (hook) calls
        steps = mbs.sys["lieGroupSolver"].timing["exudynSteps"]
        assert calls == (3 if repeat else 1) * steps, (calls, steps)
        results.append(mbs.GetSensorStoredData(s))
    np.testing.assert_allclose(results[1], results[0], rtol=0, atol=1e-12)


# ----------------------------------------------------------------------------- the field audit
_KEEP = []


def _models_with_every_item():
    mbs = exu.SystemContainer().AddSystem()
    g = mbs.CreateGround()
    bodies = [mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.4, 0.1, 0.1]), referencePosition=[i, 0, 0],
                                  nodeType=nt, gravity=[0, 0, -9.81])
              for i, nt in enumerate((exu.NodeType.RotationRotationVector, exu.NodeType.RotationEulerParameters,
                                      exu.NodeType.RotationRxyz))]
    mbs.CreateSphericalJoint(itemNumbers=[g, bodies[0]], position=[0, 0, 0])
    mbs.CreateRevoluteJoint(itemNumbers=[bodies[0], bodies[1]], position=[0.5, 0, 0], axis=[0, 1, 0])
    mbs.CreatePrismaticJoint(itemNumbers=[bodies[1], bodies[2]], position=[1.5, 0, 0], axis=[1, 0, 0])
    mbs.CreateGenericJoint(itemNumbers=[g, bodies[2]], position=[2, 0, 0], constrainedAxes=[0, 0, 1, 0, 0, 0])
    mbs.CreateSpringDamper(itemNumbers=[g, bodies[1]], localPosition0=[1, 1, 0], stiffness=10)
    mbs.CreateCartesianSpringDamper(itemNumbers=[g, bodies[1]], localPosition0=[1, 1, 0], stiffness=[1, 1, 1])
    # 2D bodies: one on a revolute 2D joint, one on a prismatic 2D joint to ground
    from exudyn.utilities import (MarkerBodyRigid, NodeRigidBody2D, ObjectJointPrismatic2D, ObjectJointRevolute2D,
                                  ObjectRigidBody2D)
    gm = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g, localPosition=[5, 0, 0]))
    for k, joint in enumerate((ObjectJointRevolute2D, ObjectJointPrismatic2D)):
        n2 = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[5, 0, 0]))
        b2 = mbs.AddObject(ObjectRigidBody2D(nodeNumber=n2, mass=1, inertia=0.1))
        m2 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b2, localPosition=[0, 0, 0]))
        mbs.AddObject(joint(markerNumbers=[gm, m2]))
    mbs.CreateTorsionalSpringDamper(itemNumbers=[bodies[0], bodies[1]], position=[0.5, 0, 0], axis=[0, 1, 0],
                                    stiffness=1)
    mbs.CreateRigidBodySpringDamper(itemNumbers=[g, bodies[2]], localPosition0=[2, 0, 0],
                                    stiffness=np.eye(6), damping=np.zeros((6, 6)))
    mbs.CreateForce(itemNumber=bodies[0], loadVector=[1, 0, 0])
    mbs.CreateTorque(itemNumber=bodies[0], loadVector=[1, 0, 0])
    n = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mbs.AddMarker(MarkerNodePosition(nodeNumber=n))
    mbs.AddMarker(exu.utilities.MarkerNodeRigid(nodeNumber=0))
    mbs.AddMarker(exu.utilities.MarkerBodyPosition(bodyNumber=bodies[0]))
    # issue 16's items: point masses, coordinate items, distance, linear spring-damper
    U = exu.utilities
    p3 = mbs.AddNode(U.NodePoint(referenceCoordinates=[0, 1, 0]))
    mbs.AddObject(U.ObjectMassPoint(mass=1, nodeNumber=p3))
    p2 = mbs.AddNode(U.NodePoint2D(referenceCoordinates=[0, 2]))
    mbs.AddObject(U.ObjectMassPoint2D(mass=1, nodeNumber=p2))
    mc3 = mbs.AddMarker(U.MarkerNodeCoordinate(nodeNumber=p3, coordinate=0))
    mc2 = mbs.AddMarker(U.MarkerNodeCoordinate(nodeNumber=p2, coordinate=1))
    mcg = mbs.AddMarker(U.MarkerNodeCoordinate(nodeNumber=n, coordinate=0))
    mbs.AddObject(U.ObjectConnectorCoordinate(markerNumbers=[mcg, mc3]))
    mbs.AddObject(U.ObjectConnectorCoordinateSpringDamper(markerNumbers=[mc3, mc2], stiffness=10))
    mbs.AddLoad(U.LoadCoordinate(markerNumber=mc2, load=1))
    mp2 = mbs.AddMarker(U.MarkerNodePosition(nodeNumber=p2))
    mbs.AddObject(U.ObjectConnectorDistance(markerNumbers=[mp2, mbs.AddMarker(U.MarkerNodePosition(nodeNumber=p3))],
                                            distance=float(np.sqrt(5.0))))
    mbs.AddObject(U.ObjectConnectorLinearSpringDamper(markerNumbers=[
        mbs.AddMarker(U.MarkerBodyRigid(bodyNumber=g)), mbs.AddMarker(U.MarkerBodyRigid(bodyNumber=bodies[2]))],
        stiffness=1))
    disc = mbs.CreateRigidBody(inertia=InertiaCuboid(800, [0.05, 0.5, 0.5]), referencePosition=[0, 5, 0.25])
    mbs.AddObject(U.ObjectJointRollingDisc(markerNumbers=[mbs.AddMarker(U.MarkerBodyRigid(bodyNumber=g)),
                                                          mbs.AddMarker(U.MarkerBodyRigid(bodyNumber=disc))],
                                           discRadius=0.25))
    disc2 = mbs.CreateRigidBody(inertia=InertiaCuboid(800, [0.05, 0.5, 0.5]), referencePosition=[0, 6, 0.25])
    mbs.AddObject(U.ObjectConnectorRollingDiscPenalty(
        markerNumbers=[mbs.AddMarker(U.MarkerBodyRigid(bodyNumber=g)), mbs.AddMarker(U.MarkerBodyRigid(bodyNumber=disc2))],
        nodeNumber=mbs.AddNode(U.NodeGenericData(initialCoordinates=[0, 0, 0], numberOfDataCoordinates=3)),
        discRadius=0.25, contactStiffness=1e4))
    n1 = mbs.AddNode(U.Node1D(referenceCoordinates=[0]))
    mbs.AddObject(U.ObjectMass1D(nodeNumber=n1, mass=1, referenceRotation=U.RotationMatrixZ(0.2)))
    n1r = mbs.AddNode(U.Node1D(referenceCoordinates=[0]))
    mbs.AddObject(U.ObjectRotationalMass1D(nodeNumber=n1r, inertia=1))
    mbs.AddObject(U.ObjectConnectorCoordinateSpringDamper(markerNumbers=[
        mbs.AddMarker(U.MarkerNodeCoordinate(nodeNumber=n1, coordinate=0)),
        mbs.AddMarker(U.MarkerNodeCoordinate(nodeNumber=n1r, coordinate=0))], stiffness=10))
    spun = mbs.CreateRigidBody(inertia=InertiaCuboid(800, [0.1, 0.2, 0.3]), referencePosition=[0, 7, 0])
    mbs.AddObject(U.ObjectConnectorCoordinate(markerNumbers=[mcg, mbs.AddMarker(U.MarkerNodeRotationCoordinate(
        nodeNumber=mbs.GetObject(spun)["nodeNumber"], rotationCoordinate=2))], velocityLevel=True))
    return mbs


def test_coordinate_load_set_in_a_pre_step_function_is_honoured():
    """LoadCoordinate's ``load`` is live: a pre-step function sets it, sampled every TS and held
    (10 steps of h = 1e-4 per period, as the controllers above).  A free point mass under that
    piecewise-constant force has the exact solution of the recurrence below; exl reproduces it
    to round-off (RK4 is exact for a constant force within a step); Exudyn's generalized-alpha
    differs from it by its own error after each jump (measured 1.06e-5 of 0.0163)."""
    h, T = 1e-4, 0.2

    def build():
        SC = exu.SystemContainer()
        _KEEP.append(SC)
        mbs = SC.AddSystem()
        U = exu.utilities
        n0 = mbs.AddNode(U.NodePoint(referenceCoordinates=[0, 0, 0]))
        mbs.AddObject(U.ObjectMassPoint(mass=2, nodeNumber=n0))
        mc = mbs.AddMarker(U.MarkerNodeCoordinate(nodeNumber=n0, coordinate=1))
        ld = mbs.AddLoad(U.LoadCoordinate(markerNumber=mc, load=0))

        def pre(mbs, t):
            mbs.SetLoadParameter(ld, "load", 3.0 * np.sin(10 * sampled(t)))
            return True
        mbs.SetPreStepUserFunction(pre)
        mbs.Assemble()
        return mbs

    y = v = 0.0
    for n in range(int(round(T / h))):          # the step ending at (n+1) h has the load set for it
        a = 3.0 * np.sin(10 * sampled((n + 1) * h)) / 2.0
        y, v = y + v * h + 0.5 * a * h * h, v + a * h
    out = {}
    for lie in (False, True):
        mbs = build()
        ss = settings(T, h, sensors=False)
        (exl.SolveDynamic(mbs, ss) if lie else exu.SolveDynamic(mbs, ss))
        out[lie] = (np.array(mbs.systemData.GetODE2Coordinates()), np.array(mbs.systemData.GetODE2Coordinates_t()))
    np.testing.assert_allclose(out[True][0], [0, y, 0], rtol=0, atol=1e-13)
    np.testing.assert_allclose(out[True][1], [0, v, 0], rtol=0, atol=1e-12)
    assert abs(out[False][0][1] - y) < 1e-3 * y         # the native run, for scale (its error after jumps)


def test_every_field_of_every_supported_item_has_a_status():
    """A new Exudyn field must be classified (honoured, fixed, refused, initial, ignored)
    before the bridge can read a model that has it: the dictionaries of real items and
    Exudyn's defaults of every supported type are checked."""
    mbs = _models_with_every_item()
    mbs.Assemble()
    exl.LieGroupSolver(mbs)                  # the model is supported
    seen = set()
    for kind, count, getter, tkey in (("object", mbs.systemData.NumberOfObjects(), mbs.GetObject, "objectType"),
                                      ("node", mbs.systemData.NumberOfNodes(), mbs.GetNode, "nodeType"),
                                      ("marker", mbs.systemData.NumberOfMarkers(), mbs.GetMarker, "markerType"),
                                      ("load", mbs.systemData.NumberOfLoads(), mbs.GetLoad, "loadType")):
        for i in range(count):
            d = getter(i)
            seen.add((kind, d[tkey]))
            for key in d:
                assert field_status(kind, d[tkey], key) is not None, (kind, d[tkey], key)
    assert seen == set(FIELDS), set(FIELDS) ^ seen
    defaults = {"object": mbs.GetObjectDefaults, "node": mbs.GetNodeDefaults, "marker": mbs.GetMarkerDefaults,
                "load": mbs.GetLoadDefaults}
    for (kind, t), table in FIELDS.items():
        keys = set(defaults[kind](t))
        for key in keys:
            assert field_status(kind, t, key) is not None, (kind, t, key)
        assert set(table) <= keys, (kind, t, set(table) - keys)        # no stale entries
        assert all(field_status(kind, t, k)[0] == IGNORED for k in keys if k.startswith("V"))


def test_bench_section_reports_the_parameter_update_cost():
    """``bench --sections params`` runs and reports (no timing asserted)."""
    from exudyn_lie.apps.bench_params import parameter_updates, report_lines
    p = parameter_updates(T=0.01, repeats=1)
    for key in ("none", "empty", "compute", "control", "native", "exudynSet", "watched", "bridgeOwn"):
        assert np.isfinite(p[key])
    text = "\n".join(report_lines(p))
    assert "## 8. Parameters changed during a solve" in text and "12 load vectors" in text


def _settings_fields(obj, prefix=""):
    out = []
    for a in dir(obj):
        if a.startswith("_") or a in ("GetDictionary", "SetDictionary", "ToString", "Print"):
            continue
        v = getattr(obj, a)
        if hasattr(v, "GetDictionary"):
            out += _settings_fields(v, prefix + a + ".")
        elif not callable(v):
            out.append(prefix + a)
    return out


def test_every_simulation_setting_has_a_status():
    import warnings
    from exudyn_lie.bridge.settings import setting_status
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)      # the deprecated aliases are fields too
        fields = _settings_fields(exu.SimulationSettings())
    assert len(fields) > 150
    missing = [f for f in fields if setting_status(f) is None]
    assert not missing, missing
    assert setting_status("timeIntegration.newton.relativeTolerance")[0] == IGNORED
    assert setting_status("solution.sensors.writePeriod")[0] == "live"


def test_continue_from_restart_file_is_refused_with_mbs_unchanged():
    mbs, out = torsional_offset()
    mbs.Assemble()
    ss = settings(0.01, 1e-3)
    ss.solution.restart.continueIfAvailable = True
    before = _state(mbs)
    with pytest.raises(BridgeError, match="continueIfAvailable"):
        exl.SolveDynamic(mbs, ss, showProgress=False)
    assert _state(mbs) == before


def reused_buffer():
    """A controller that reuses one array for the vectors of three loads (it holds the last
    one's vector when the step starts)."""
    mbs = exu.SystemContainer().AddSystem()
    g, b, j = pendulum(mbs)
    mB = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b, localPosition=[0.4, 0, 0]))
    loads = [mbs.AddLoad(LoadForceVector(markerNumber=mB, loadVector=[0, 0, 0])) for _ in range(3)]
    buf = np.zeros(3)

    def pre_step(mbs, t):
        for k, l in enumerate(loads):
            buf[:] = [0, 20 * (k + 1) * np.cos(10 * sampled(t)), 0]
            mbs.SetLoadParameter(l, "loadVector", buf)
        return True

    mbs.SetPreStepUserFunction(pre_step)
    return mbs, {"pos": mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position,
                                                 localPosition=[0.4, 0, 0]))}


def test_a_reused_load_vector_buffer_is_read_as_set():
    """Every load gets the value it was set to (the bridge copies it at the call), as in Exudyn."""
    mbs, ref, got = _compare(reused_buffer, 0.1, 1e-4, 1e-5, 1e-6)
    assert np.max(np.abs(got["pos"][:, 2])) > 1e-2


def test_re_reading_unchanged_items_reproduces_the_compiled_rows():
    """The rows the watch writes have compile_scene's layout: re-reading every load and
    connector of a model with every compiled kind (body-fixed loads on rotated markers,
    velocity offsets, turned torsional springs) changes no compiled number."""
    from exudyn_lie.bridge.params import ParameterWatch
    mbs = exu.SystemContainer().AddSystem()
    g = mbs.CreateGround()
    b = [mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.4, 0.1, 0.1]), referencePosition=[i, 0.1 * i, 0],
                             referenceRotationMatrix=exu.utilities.RotationMatrixZ(0.3 * i), gravity=[0, 0, -9.81])
         for i in range(1, 3)]
    mbs.CreateSpringDamper(itemNumbers=[g, b[0]], localPosition0=[1, 1, 0], localPosition1=[0.1, 0, 0],
                           stiffness=10, damping=0.5, force=0.3, velocityOffset=0.2)
    mbs.CreateCartesianSpringDamper(itemNumbers=[b[0], b[1]], localPosition0=[0.2, 0, 0], stiffness=[1, 2, 3],
                                    damping=[0.1, 0.2, 0.3], offset=[0.1, 0, 0])
    tsd = mbs.CreateTorsionalSpringDamper(itemNumbers=[b[0], b[1]], position=[1.5, 0, 0], axis=[0, 0, 1],
                                          stiffness=5, damping=0.1, offset=0.4, torque=0.2, velocityOffset=1.0)
    mbs.CreateForce(itemNumber=b[0], loadVector=[1, 2, 3], localPosition=[0.1, 0.2, 0], bodyFixed=True)
    mbs.CreateTorque(itemNumber=b[1], loadVector=[0.1, 0.2, 0.3], bodyFixed=True)
    mRot = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b[1], localPosition=[0.1, 0, 0]))
    mbs.SetMarkerParameter(mRot, "localHT", exu.rigidBodyUtilities.HomogeneousTransformation(
        exu.utilities.RotationMatrixX(0.7), [0.1, 0, 0]))
    mbs.AddLoad(LoadForceVector(markerNumber=mRot, loadVector=[0, 1, 0], bodyFixed=True))
    for intrinsic in (False, True):
        mbs.CreateRigidBodySpringDamper(itemNumbers=[b[0], b[1]], localPosition0=[0.3, 0, 0.1],
                                        localPosition1=[-0.2, 0.1, 0], stiffness=np.diag([1, 2, 3, 4, 5, 6.0]),
                                        damping=0.1 * np.ones((6, 6)), offset=[0.1, 0, 0, 0, 0.2, 0],
                                        rotationMatrixJoint=exu.utilities.RotationMatrixY(0.4),
                                        useIntrinsicFormulation=intrinsic)
    mbs.Assemble()
    n = mbs.GetObject(tsd)["nodeNumber"]
    mbs.SetNodeParameter(n, "initialCoordinates", [0.4 + 4 * np.pi])          # turned twice
    mbs.Assemble()
    solver = exl.LieGroupSolver(mbs)
    sd = solver.sim.sd
    names = ("loadIndex", "loadVectors", "springBodies", "springPoints", "springLaw", "cartesianBodies",
             "cartesianPoints", "cartesianLaw", "torsionBodies", "torsionFrames", "torsionLaw", "rigidSpringBodies",
             "rigidSpringPoints", "rigidSpringFrames", "rigidSpringLaw")
    before = {k: getattr(sd, k).copy() for k in names}
    assert solver.scene.torsionData[0].turns0 == 2
    watch = ParameterWatch(solver)
    items = [("load", l) for l in range(mbs.systemData.NumberOfLoads())
             if mbs.GetLoad(l)["loadType"] != "MassProportional"] + \
        [("object", o) for o in range(mbs.systemData.NumberOfObjects())]
    watch._rebuild(items, 0.0)
    for k in names:
        np.testing.assert_array_equal(getattr(sd, k), before[k], err_msg=k)
    assert all(len(before[k]) for k in ("loadVectors", "springLaw", "cartesianLaw", "torsionLaw", "rigidSpringLaw"))
