"""SolveDynamic / LieGroupSolver on ordinary Exudyn scripts: same trajectories as the
native solvers, every node type, Exudyn's output machinery (sensors, solution file,
pre/post-step functions, final state), repeated runs."""
import os

import numpy as np
import pytest

import exudyn as exu
from exudyn.utilities import (RigidBodyInertia, RotationMatrixX, RotationMatrixZ, SensorBody, SensorObject,
                              SensorUserFunction)

import exudyn_lie as exl
from exudyn_lie.models import heavy_top as HT
from exudyn_lie.bridge import LieGroupSolver

from test_bridge_common import NODE_TYPES, add_body, new_mbs, quiet_settings

O = exu.OutputVariableType


def settings(T, h, sensors=True, period=0.01):
    ss = quiet_settings(T, int(round(T / h)))
    ss.solution.sensors.active = sensors
    ss.solution.sensors.writePeriod = period
    return ss


def ga_settings(T, h):
    """Generalized-alpha as an accurate native baseline (see /tmp/facts: full Newton,
    tight tolerances, simplified Lie group kinematics for RotVecLG + joints)."""
    ss = settings(T, h)
    ss.timeIntegration.newton.useModifiedNewton = False
    ss.timeIntegration.newton.relativeTolerance = 1e-10
    ss.timeIntegration.newton.absoluteTolerance = 1e-10
    ss.timeIntegration.newton.maxIterations = 50
    ss.timeIntegration.generalizedAlpha.spectralRadius = 0.9
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    ss.timeIntegration.generalizedAlpha.lieGroupSimplifiedKinematicRelations = True
    ss.timeIntegration.adaptiveStep = False
    return ss


def rk44_settings(T, h):
    ss = settings(T, h)
    ss.timeIntegration.solverType = exu.DynamicSolverType.RK44
    ss.timeIntegration.automaticStepSize = False
    return ss


# ---------------------------------------------------------------------------- models
def heavy_top(node="RotVecLG"):
    """The paper's heavy top (the models' one builder) with a position and a joint-force sensor."""
    mbs, info = HT.build(mbs=new_mbs(), nodeType=NODE_TYPES[node])
    b, j = info.bodies[0].objectIndex, info.joints[0].objectIndex
    s = mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position))
    sj = mbs.AddSensor(SensorObject(objectNumber=j, storeInternal=True, outputVariableType=O.Force))
    mbs.Assemble()
    return mbs, b, s, sj


def pendulum_chain(node, torsional=True):
    """Revolute (ground-body0) + spherical (body0-body1) + spring + torsional spring + loads."""
    mbs = new_mbs()
    g = mbs.CreateGround()
    w0 = np.array([0.0, 0.0, 2.0])
    w1 = np.array([1.0, -0.5, 3.0])
    b0 = add_body(mbs, node, [0.2, 0, 0], np.eye(3), omega=w0, vel=np.cross(w0, [0.2, 0, 0]), com=(0.05, 0, 0),
                  gravity=[0, -9.81, 0])
    v1 = np.cross(w0, [0.4, 0, 0]) + np.cross(w1, [0.2, 0, 0])
    b1 = add_body(mbs, node, [0.6, 0, 0], RotationMatrixX(0.2), omega=w1, vel=v1,
                  com=(0.0, 0.02, 0), sides=(0.3, 0.05, 0.05), gravity=[0, -9.81, 0])
    mbs.CreateRevoluteJoint(itemNumbers=[g, b0], position=[0, 0, 0], axis=[0, 0, 1])
    mbs.CreateSphericalJoint(itemNumbers=[b0, b1], position=[0.4, 0, 0])
    mbs.CreateSpringDamper(itemNumbers=[g, b1], localPosition0=[0.8, 0.3, 0.1], localPosition1=[0.15, 0, 0],
                           stiffness=50, damping=0.2)
    if torsional:
        mbs.CreateTorsionalSpringDamper(itemNumbers=[g, b0], position=[0, 0, 0], axis=[0, 0, 1], stiffness=2,
                                        damping=0.05)
    mbs.CreateForce(itemNumber=b1, loadVector=[0, 0, 1.0], localPosition=[0.1, 0, 0])
    s0 = mbs.AddSensor(SensorBody(bodyNumber=b0, storeInternal=True, outputVariableType=O.Position,
                                  localPosition=[0.4, 0, 0]))
    s1 = mbs.AddSensor(SensorBody(bodyNumber=b1, storeInternal=True, outputVariableType=O.Position,
                                  localPosition=[0.15, 0.02, 0.01]))
    s2 = mbs.AddSensor(SensorBody(bodyNumber=b1, storeInternal=True, outputVariableType=O.AngularVelocity))
    mbs.Assemble()
    return mbs, [s0, s1, s2]


def free_body(node="RotVecLG"):
    mbs = new_mbs()
    g = mbs.CreateGround()
    b = add_body(mbs, node, [0.5, 0.1, 0], RotationMatrixZ(0.4), omega=(10 * np.pi, 2 * np.pi, 1.0), vel=(1, 0, 0.5),
                 com=(0.2, 0.05, 0), gravity=[0, 0, -9.81])
    mbs.CreateCartesianSpringDamper(itemNumbers=[g, b], localPosition0=[0.6, 0, 0.1], localPosition1=[0.1, 0, 0],
                                    stiffness=[300, 200, 100], damping=[0.5, 0.5, 0.5])
    mbs.CreateTorque(itemNumber=b, loadVector=[0.1, 0, 0.2], bodyFixed=True)
    s = mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position,
                                 localPosition=[0.1, 0.1, 0]))
    mbs.Assemble()
    return mbs, b, s


def data(mbs, s):
    return np.asarray(mbs.GetSensorStoredData(s))


# ---------------------------------------------------------------------------- same trajectories
@pytest.mark.parametrize("node", ["RotVecLG", "EP"])
def test_heavy_top_matches_native_generalized_alpha(node):
    """Generalized-alpha (2nd order) converges to the package's RK4 solution: the
    deviation drops by ~16 when its step drops by 4, over the whole sensor record."""
    T = 0.5
    mbs, b, s, sj = heavy_top(node)
    assert exl.SolveDynamic(mbs, settings(T, 1e-3), method="RK4", liegroup="SE3") is True
    ours, lam = data(mbs, s), data(mbs, sj)
    dev = []
    for h in (1e-3, 2.5e-4):
        mbs2, b2, s2, sj2 = heavy_top(node)
        mbs2.SolveDynamic(ga_settings(T, h))
        ref = data(mbs2, s2)
        np.testing.assert_allclose(ref[:, 0], ours[:, 0], atol=1e-12)
        dev.append(np.max(np.abs(ref[:, 1:] - ours[:, 1:])))
        lamdev = np.max(np.abs(data(mbs2, sj2)[1:, 1:] - lam[1:, 1:])) / np.max(np.abs(lam[:, 1:]))
    assert dev[1] < 5e-5
    assert 10 < dev[0] / dev[1] < 22, dev
    # the joint force sensor (the multipliers written back) agrees as well
    assert lamdev < 1e-3


def test_double_pendulum_matches_native_generalized_alpha():
    """Position sensors and the angular velocity sensor of body 1.  Body 1 spins at up
    to ~57 rad/s, and generalized-alpha's (2nd-order) error in the angular velocity is
    about 1.5e-3 rad/s at h = 2.5e-4 (2.5e-5 of max |omega|): the bound is relative to
    max |omega|, and the drop by ~16 from h = 1e-3 shows the deviation is that error."""
    T = 0.5
    mbs, sens = pendulum_chain("EP")
    exl.SolveDynamic(mbs, settings(T, 1e-3), liegroup="auto")
    ours = [data(mbs, s) for s in sens]
    wmax = np.max(np.abs(ours[2][:, 1:]))
    assert wmax > 10
    dev, devw = [], []
    for h in (1e-3, 2.5e-4):
        mbs2, sens2 = pendulum_chain("EP")
        mbs2.SolveDynamic(ga_settings(T, h))
        ref = [data(mbs2, s2) for s2 in sens2]
        for r, o in zip(ref, ours):
            np.testing.assert_allclose(r[:, 0], o[:, 0], atol=1e-12)
        dev.append(max(np.max(np.abs(r[:, 1:] - o[:, 1:])) for r, o in zip(ref[:2], ours[:2])))
        devw.append(np.max(np.abs(ref[2][:, 1:] - ours[2][:, 1:])) / wmax)
    assert dev[1] < 5e-5
    assert 10 < dev[0] / dev[1] < 22, dev
    assert devw[1] < 5e-5, devw
    assert 10 < devw[0] / devw[1] < 22, devw


def test_free_body_so3xr3_equals_native_rk44():
    """Unconstrained RotVecLG body: exudyn_lie's RK4 on SO3xR3 is Exudyn's explicit Lie
    group RK44 (identical up to round-off); SE3 agrees within the method's error."""
    T, h = 0.5, 1e-3
    mbs, b, s = free_body()
    mbs.SolveDynamic(rk44_settings(T, h))
    native = data(mbs, s)
    mbs, b, s = free_body()
    exl.SolveDynamic(mbs, settings(T, h), liegroup="SO3xR3")
    assert np.max(np.abs(data(mbs, s) - native)) < 1e-12
    mbs, b, s = free_body()
    exl.SolveDynamic(mbs, settings(T, h), liegroup="SE3")
    assert np.max(np.abs(data(mbs, s) - native)) < 1e-6


@pytest.mark.parametrize("node", ["EP", "Rxyz"])
def test_every_node_type_gives_the_same_trajectory(node):
    """The integration does not depend on the node type (only reading / writing does)."""
    T, h = 0.5, 1e-3
    mbs, sens = pendulum_chain("RotVecLG")
    exl.SolveDynamic(mbs, settings(T, h), liegroup="SE3")
    ref = [data(mbs, s) for s in sens]
    mbs, sens = pendulum_chain(node)
    exl.SolveDynamic(mbs, settings(T, h), liegroup="SE3")
    for s, r in zip(sens, ref):
        np.testing.assert_allclose(data(mbs, s), r, atol=1e-11, rtol=0)


def test_free_body_every_node_type_same_as_native(rng):
    T, h = 0.3, 1e-3
    mbs, b, s = free_body()
    mbs.SolveDynamic(rk44_settings(T, h))
    native = data(mbs, s)
    for node in NODE_TYPES:
        mbs, b, s = free_body(node)
        exl.SolveDynamic(mbs, settings(T, h), liegroup="SO3xR3")
        assert np.max(np.abs(data(mbs, s) - native)) < 1e-11, node


# ---------------------------------------------------------------------------- Exudyn machinery
def test_sensors_solution_file_and_final_state_like_native(tmp_path):
    T, h = 0.2, 1e-3
    files = {}
    for label in ("native", "lie"):
        mbs, b, s, sj = heavy_top()
        sf = str(tmp_path / f"{label}_sensor.txt")
        mbs.AddSensor(SensorBody(bodyNumber=b, fileName=sf, outputVariableType=O.Velocity))
        mbs.Assemble()
        ss = ga_settings(T, h) if label == "native" else settings(T, h)
        ss.solution.file.write = True
        ss.solution.file.name = str(tmp_path / f"{label}_solution.txt")
        ss.solution.file.writePeriod = 0.02
        ss.solution.sensors.writePeriod = 0.01
        if label == "native":
            mbs.SolveDynamic(ss)
        else:
            exl.SolveDynamic(mbs, ss)
        sol = np.loadtxt(ss.solution.file.name, comments="#", delimiter=",")
        sens = np.loadtxt(sf, comments="#", delimiter=",")
        files[label] = (sol, sens, data(mbs, s), mbs)
    (solN, sensN, dN, _), (solL, sensL, dL, mL) = files["native"], files["lie"]
    assert solL.shape == solN.shape and sensL.shape == sensN.shape and dL.shape == dN.shape
    np.testing.assert_allclose(solL[:, 0], solN[:, 0], atol=1e-12)          # same output times
    np.testing.assert_allclose(sensL[:, 0], sensN[:, 0], atol=1e-12)
    np.testing.assert_allclose(solL[:, 1:7], solN[:, 1:7], atol=1e-3)        # same motion (GA error)
    # the velocity sensor file: generalized-alpha's error at h = 1e-3 is 4.3e-3 m/s (it drops
    # to 2.7e-4 at h = 2.5e-4, second order) of a velocity up to 6.3 m/s
    assert np.max(np.abs(sensL[:, 1:])) > 5
    np.testing.assert_allclose(sensL[:, 1:], sensN[:, 1:], rtol=0, atol=1e-2)
    # its last row is the final velocity left in mbs (file precision: 10 digits)
    np.testing.assert_allclose(sensL[-1, 1:], mL.GetObjectOutputBody(1, O.Velocity, localPosition=[0, 0, 0]),
                               rtol=1e-9, atol=1e-12)
    # final state left in mbs = last sensor row; the stored solver is there
    np.testing.assert_allclose(mL.GetObjectOutputBody(1, O.Position, localPosition=[0, 0, 0]), dL[-1, 1:],
                               atol=1e-14)
    assert mL.systemData.GetTime() == pytest.approx(T)
    assert isinstance(mL.sys["dynamicSolver"], exu.MainSolverImplicitSecondOrder)
    assert isinstance(mL.sys["lieGroupSolver"], LieGroupSolver)
    # accelerations in the last row: Exudyn's q_tt of the final state (from the Lie group state)
    sim = mL.sys["lieGroupSolver"].sim
    Vdot, lam = sim.Accelerations()
    np.testing.assert_allclose(mL.systemData.GetODE2Coordinates_tt()[3:6], Vdot[0, :3], atol=1e-10)
    # ... and Exudyn's own equations hold there: M q_tt + C_q^T lambda = f
    assert exudyn_equations_residual(mL) < 1e-12


def exudyn_equations_residual(mbs, state=None):
    """Relative residual of Exudyn's equations of motion ``M q_tt + C_q^T lambda = f`` at
    the state left in mbs (or ``state = (t, q, q_t, q_tt, lambda)``), with Exudyn's
    ComputeMassMatrix / ComputeODE2RHS / ComputeJacobianAE (test_bridge_common.oracle)."""
    from test_bridge_common import oracle
    sd = mbs.systemData
    if state is None:
        state = (sd.GetTime(), sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t(), sd.GetODE2Coordinates_tt(),
                 sd.GetAECoordinates())
    t, q, qt, qtt, lam = (np.array(x, float) for x in state)
    M, f, g, C = oracle(mbs, q, qt, float(t))
    r = M @ qtt - f
    if lam.size:
        r += C.T @ lam
    assert np.max(np.abs(f)) > 1.0
    return float(np.max(np.abs(r)) / np.max(np.abs(f)))


@pytest.mark.parametrize("liegroup", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("model", ["free body", "heavy top", "double pendulum"])
@pytest.mark.parametrize("node", sorted(NODE_TYPES))
def test_written_back_accelerations_satisfy_exudyns_equations(node, model, liegroup):
    """q_tt (and the joint multipliers in the AE coordinates) left in mbs satisfy Exudyn's
    own equations at the final state: for the unconstrained body q_tt = M^-1 f, for the
    constrained models M q_tt + C_q^T lambda = f (the EP nodes' normalisation multiplier
    is 0 for exactly normalised parameters)."""
    if model == "free body":
        mbs = free_body(node)[0]
    elif model == "heavy top":
        mbs = heavy_top(node)[0]
    else:
        mbs = pendulum_chain(node)[0]
    exl.SolveDynamic(mbs, settings(0.05, 1e-3, sensors=False), liegroup=liegroup)
    assert (len(mbs.sys["lieGroupSolver"].scene.joints) > 0) == (model != "free body")
    assert exudyn_equations_residual(mbs) < 1e-12


def test_pre_and_post_step_functions_every_step_and_state_changes_are_used():
    T, h = 0.1, 1e-3
    calls = {"pre": [], "post": []}

    def pre(mbs, t):
        calls["pre"].append(t)
        if abs(t - 0.05) < 1e-9:        # a user intervention: stop the body
            q_t = mbs.systemData.GetODE2Coordinates_t()
            mbs.systemData.SetODE2Coordinates_t(0 * q_t)
        return True

    def post(mbs, t):
        calls["post"].append(t)
        return True

    mbs, b, s = free_body()
    mbs.SetPreStepUserFunction(pre)
    mbs.SetPostStepUserFunction(post)
    vs = mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.AngularVelocity))
    mbs.Assemble()
    exl.SolveDynamic(mbs, settings(T, h))
    # as natively (checked with exudyn 1.13.6): pre-step before each of the 100 steps,
    # post-step once after the initialisation (t = 0) and after each step
    assert len(calls["pre"]) == 100 and calls["pre"][0] == pytest.approx(h)
    assert len(calls["post"]) == 101 and calls["post"][0] == 0.0 and calls["post"][-1] == pytest.approx(T)
    w = data(mbs, vs)
    # the velocities set in the pre-step function at t = 0.05 were integrated from:
    # one step later the angular velocity is O(h) (only the torque and spring act)
    i = int(np.argmin(np.abs(w[:, 0] - 0.05)))
    assert np.linalg.norm(w[i - 1, 1:]) > 10 and np.linalg.norm(w[i, 1:]) < 0.1


def test_start_time_and_substeps_give_the_same_outputs():
    mbs, b, s = free_body()
    ss = settings(0.3, 1e-3)
    ss.timeIntegration.startTime = 0.1
    ss.timeIntegration.numberOfSteps = 200
    exl.SolveDynamic(mbs, ss)
    d_auto = data(mbs, s)
    assert mbs.sys["lieGroupSolver"].timing["substeps"] == 10
    assert d_auto[0, 0] == pytest.approx(0.1) and d_auto[-1, 0] == pytest.approx(0.3) and len(d_auto) == 21
    mbs2, b2, s2 = free_body()
    exl.SolveDynamic(mbs2, ss, substeps=1)
    np.testing.assert_allclose(data(mbs2, s2), d_auto, atol=1e-13)


def test_update_initial_values_continues_the_motion():
    mbs, b, s = free_body()
    exl.SolveDynamic(mbs, settings(0.2, 1e-3))
    exl.SolveDynamic(mbs, settings(0.1, 1e-3), updateInitialValues=True)
    q_after = np.array(mbs.systemData.GetODE2Coordinates())
    np.testing.assert_allclose(mbs.systemData.GetODE2Coordinates(configuration=exu.ConfigurationType.Initial),
                               q_after, atol=1e-15)
    mbs2, b2, s2 = free_body()
    exl.SolveDynamic(mbs2, settings(0.1, 1e-3))
    exl.SolveDynamic(mbs2, settings(0.1, 1e-3), updateInitialValues=True)
    exl.SolveDynamic(mbs2, settings(0.1, 1e-3))
    mbs3, b3, s3 = free_body()
    exl.SolveDynamic(mbs3, settings(0.2, 1e-3))
    np.testing.assert_allclose(mbs2.systemData.GetODE2Coordinates()[:3], mbs3.systemData.GetODE2Coordinates()[:3],
                               atol=1e-10)


def test_lie_group_solver_repeated_runs_and_parameter_changes():
    mbs, b, s = free_body()
    solver = LieGroupSolver(mbs, method="RK4", liegroup="SE3")
    solver.Solve(settings(0.2, 1e-3))
    d1 = data(mbs, s)
    solver.Solve(settings(0.2, 1e-3))
    np.testing.assert_allclose(data(mbs, s), d1, atol=0)
    # a changed parameter is picked up (the model is re-read)
    mbs.SetObjectParameter(1 + 1, "stiffness", [600, 400, 200])       # the Cartesian spring (object 2)
    solver.Solve(settings(0.2, 1e-3))
    assert np.max(np.abs(data(mbs, s) - d1)) > 1e-4
    # the fast path without Exudyn outputs gives the same final state as Solve
    res = solver.Run(endTime=0.2, stepSize=1e-3, outputEvery=50)
    assert res.times[-1] == pytest.approx(0.2)
    np.testing.assert_allclose(mbs.GetSensorValues(s), data(mbs, s)[-1, 1:], atol=1e-12)


def test_python_force_path_and_stabilization_work_inside_exudyn():
    """User-function items run the Python stage loop; stabilization too."""
    def uf(mbs, t, i, dL, dLt, k, d, f):
        return k * dL + d * dLt

    mbs, b, s, sj = heavy_top()
    spring = [i for i in range(mbs.systemData.NumberOfObjects())
              if mbs.GetObject(i)["objectType"] == "ConnectorSpringDamper"][0]
    mbs.SetObjectParameter(spring, "springForceUserFunction", uf)
    exl.SolveDynamic(mbs, settings(0.05, 1e-3), liegroup="SE3")
    ref = data(mbs, s)
    mbs2, b2, s2, sj2 = heavy_top()
    exl.SolveDynamic(mbs2, settings(0.05, 1e-3), liegroup="SE3")
    np.testing.assert_allclose(ref, data(mbs2, s2), atol=1e-13)
    mbs3, b3, s3, sj3 = heavy_top()
    exl.SolveDynamic(mbs3, settings(0.05, 1e-3), liegroup="SO3xR3", stabilization="position")
    np.testing.assert_allclose(data(mbs3, s3), ref, atol=1e-6)


def test_inactive_items_are_skipped_not_mis_modelled():
    T, h = 0.1, 1e-3
    mbs, b, s = free_body()
    exl.SolveDynamic(mbs, settings(T, h))
    ref = data(mbs, s)
    mbs2 = new_mbs()
    g = mbs2.CreateGround()
    b2 = add_body(mbs2, "RotVecLG", [0.5, 0.1, 0], RotationMatrixZ(0.4), omega=(10 * np.pi, 2 * np.pi, 1.0),
                  vel=(1, 0, 0.5), com=(0.2, 0.05, 0), gravity=[0, 0, -9.81])
    mbs2.CreateCartesianSpringDamper(itemNumbers=[g, b2], localPosition0=[0.6, 0, 0.1], localPosition1=[0.1, 0, 0],
                                     stiffness=[300, 200, 100], damping=[0.5, 0.5, 0.5])
    mbs2.CreateTorque(itemNumber=b2, loadVector=[0.1, 0, 0.2], bodyFixed=True)
    j = mbs2.CreateSphericalJoint(itemNumbers=[g, b2], position=[0.3, 0.3, 0.3])
    sp = mbs2.CreateSpringDamper(itemNumbers=[g, b2], localPosition0=[1, 1, 1], stiffness=1e3)
    mbs2.SetObjectParameter(j, "activeConnector", False)
    mbs2.SetObjectParameter(sp, "activeConnector", False)
    s2 = mbs2.AddSensor(SensorBody(bodyNumber=b2, storeInternal=True, outputVariableType=O.Position,
                                   localPosition=[0.1, 0.1, 0]))
    mbs2.Assemble()
    solver = LieGroupSolver(mbs2)
    assert len(solver.scene.skipped) == 2 and solver.groups == ["SE3"]      # COM off the frame: SE3
    solver.Solve(settings(T, h))
    np.testing.assert_allclose(data(mbs2, s2), ref, atol=1e-13)


def test_verbose_prints_the_group_choice(capsys):
    mbs, sens = pendulum_chain("RotVecLG", torsional=False)
    free = add_body(mbs, "EP", [3, 0, 0], np.eye(3), com=(0, 0, 0))
    mbs.Assemble()
    solver = LieGroupSolver(mbs, liegroup="auto", verbose=True)
    out = capsys.readouterr().out
    assert solver.groups == ["SE3", "SE3", "SO3xR3"]
    assert "SO3xR3 (auto: unconstrained, frame at COM)" in out and out.count("SE3 (auto") == 2
    solver = LieGroupSolver(mbs, liegroup={free: "SE3", 1: "SO3xR3"})
    assert solver.groups == ["SO3xR3", "SE3", "SE3"]


def rp_mechanism(node):
    """Revolute (ground-body0, axis z) + prismatic (body0-body1, axis parallel to z),
    both COMs off the axes; gravity along -z and a spring to ground."""
    mbs = new_mbs()
    g = mbs.CreateGround()
    w = np.array([0.0, 0.0, 3.0])
    b0 = add_body(mbs, node, [0.1, 0, 0], np.eye(3), omega=w, vel=np.cross(w, [0.1, 0, 0]), com=(0.05, 0.01, 0),
                  gravity=[0, 0, -9.81])
    b1 = add_body(mbs, node, [0.3, 0, 0.05], RotationMatrixZ(0.3), omega=w, vel=np.cross(w, [0.3, 0, 0.05]) + [0, 0, 0.2],
                  com=(0.02, 0, 0.01), sides=(0.2, 0.04, 0.04), gravity=[0, 0, -9.81])
    mbs.CreateRevoluteJoint(itemNumbers=[g, b0], position=[0, 0, 0], axis=[0, 0, 1])
    mbs.CreatePrismaticJoint(itemNumbers=[b0, b1], position=[0.3, 0, 0.05], axis=[0, 0, 1])
    mbs.CreateSpringDamper(itemNumbers=[g, b1], localPosition0=[0, 0, 0.5], localPosition1=[0.05, 0, 0],
                           stiffness=80, referenceLength=0.3)
    s = mbs.AddSensor(SensorBody(bodyNumber=b1, storeInternal=True, outputVariableType=O.Position,
                                 localPosition=[0.1, 0.02, 0]))
    mbs.Assemble()
    return mbs, s


@pytest.mark.parametrize("node", ["RotVecLG", "Rxyz"])
def test_revolute_prismatic_matches_native_generalized_alpha(node):
    T = 0.5
    mbs, s = rp_mechanism(node)
    exl.SolveDynamic(mbs, settings(T, 1e-3), liegroup="SE3")
    ours = data(mbs, s)
    dev = []
    for h in (1e-3, 2.5e-4):
        mbs2, s2 = rp_mechanism(node)
        mbs2.SolveDynamic(ga_settings(T, h))
        dev.append(np.max(np.abs(data(mbs2, s2)[:, 1:] - ours[:, 1:])))
    assert dev[1] < 5e-5
    assert 10 < dev[0] / dev[1] < 22, dev


def test_rxyz_node_through_its_singularity_warns_and_stays_exact():
    """A free body turning about its y axis passes the Rxyz singularity: a warning, the
    Exudyn outputs stay exact (the Lie group state is not affected)."""
    def model(node):
        mbs = new_mbs()
        b = add_body(mbs, node, [0, 0, 0], np.eye(3), omega=(0.0, 4.0, 0.3), vel=(0, 0, 0), com=(0, 0, 0))
        s = mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position,
                                     localPosition=[0.3, 0.1, 0.2]))
        mbs.Assemble()
        return mbs, s
    mbs, s = model("RotVecLG")
    exl.SolveDynamic(mbs, settings(1.0, 1e-3))
    ref = data(mbs, s)
    mbs, s = model("Rxyz")
    with pytest.warns(RuntimeWarning, match="singularity of Rxyz"):
        exl.SolveDynamic(mbs, settings(1.0, 1e-3))
    np.testing.assert_allclose(data(mbs, s), ref, atol=1e-12)


@pytest.mark.parametrize("method", exl.method_names())
def test_every_method_runs_through_the_bridge(method):
    mbs, b, s = free_body()
    assert exl.SolveDynamic(mbs, settings(0.02, 1e-3), method=method)
    assert mbs.sys["lieGroupSolver"].tableau.name == method


@pytest.mark.parametrize("evaluation", ["compiled", "exudyn"])
def test_progress_lines_on_long_runs(capsys, monkeypatch, evaluation):
    import exudyn_lie.bridge.time_loop as tl
    monkeypatch.setattr(tl, "PROGRESS_FIRST", 0.0)
    monkeypatch.setattr(tl, "PROGRESS_EVERY", 0.0)
    mbs, b, s = free_body()
    exl.SolveDynamic(mbs, settings(0.05, 1e-3), evaluation=evaluation)
    out = capsys.readouterr().out
    assert "exudyn_lie: t = 0.05 / 0.05 s (100 %)" in out
    mbs, b, s = free_body()
    exl.SolveDynamic(mbs, settings(0.05, 1e-3), showProgress=False, evaluation=evaluation)
    assert "exudyn_lie: t =" not in capsys.readouterr().out


def test_fast_path_is_used_for_compiled_scenes():
    """Chunks of outputs per kernel call (resolved entry points) and zero-copy coordinate
    views are active."""
    import warnings
    from exudyn_lie.bridge.node_writers import write_rows
    from exudyn_lie.mbs import kernel
    mbs, b, s, sj = heavy_top()
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        exl.SolveDynamic(mbs, settings(0.5, 1e-3))
    solver = mbs.sys["lieGroupSolver"]
    ch = solver._chunks
    assert ch is not None and ch.size > 1 and ch.maxRows > 1
    assert ch.out._ep["mk"] is not kernel.mk_steps and ch._ep["write"] is not write_rows
    assert solver._live
    # the resolved entry point is the compiled overload of the chunk call's argument types
    sig = [sg for sg in kernel.mk_steps.overloads if kernel.mk_steps.overloads[sg].entry_point is ch.out._ep["mk"]]
    assert len(sig) == 1 and callable(ch.out._ep["mk"])


def test_entry_point_resolves_only_compiled_signatures():
    """entry_point: the compiled function of exactly the argument types it was called with
    (same result as the dispatcher), None for types never compiled or no overload."""
    from numba import njit

    from exudyn_lie.mbs.entry import call, entry_point

    @njit
    def f(x, a):
        return x * a.sum()

    a = np.arange(3.0)
    assert entry_point(f, (2.0, a)) is None                  # not compiled yet
    assert f(2.0, a) == 6.0
    ep = entry_point(f, (2.0, a))
    assert ep is not None and ep is not f and ep(3.0, a) == 9.0
    assert entry_point(f, (2.0, a)) is ep                    # cached
    assert entry_point(f, (2, a)) is None                    # int64 x: a signature never compiled
    assert entry_point(f, (2.0, a.astype(np.float32))) is None
    assert entry_point(f, ()) is None
    cache = {}                                               # call: resolved once, then reused
    assert call(cache, "f", f, (2.0, a)) == 6.0 and cache["f"] is ep
    assert call(cache, "f", f, (1.0, a)) == 3.0


@pytest.mark.parametrize("rows", [1, 3, None])
def test_chunked_outputs_equal_one_output_per_call(monkeypatch, rows):
    """Outputs computed a chunk at a time are the states of the one-output-per-call path:
    sensors (position, joint force = multipliers), final coordinates and q_tt."""
    import exudyn_lie.bridge.solver as bsolver
    ref = None
    for r in (1, rows):
        if r is not None:
            monkeypatch.setattr(bsolver, "CHUNK_ROWS", r)
        else:
            monkeypatch.undo()
        mbs, b, s, sj = heavy_top()
        exl.SolveDynamic(mbs, settings(0.5, 1e-3))
        solver = mbs.sys["lieGroupSolver"]
        assert solver._chunks.maxRows == (r or bsolver.CHUNK_ROWS)
        sd = mbs.systemData
        out = (np.asarray(mbs.GetSensorStoredData(s)), np.asarray(mbs.GetSensorStoredData(sj)),
               np.asarray(sd.GetODE2Coordinates()), np.asarray(sd.GetODE2Coordinates_tt()))
        if ref is None:
            ref = out
            assert len(out[0]) == 51
            continue
        for a, x in zip(ref, out):
            np.testing.assert_allclose(x, a, rtol=0, atol=1e-12)


# ---------------------------------------------------------------------------- restart file
def read_restart(name):
    """The state in an Exudyn restart file: {key: array or float}."""
    out = {}
    with open(name) as fh:
        for line in fh:
            if line.startswith("#") or "=" not in line:
                continue
            key, val = line.strip().split("=", 1)
            if key in ("ODE2", "ODE2_t", "ODE2_tt", "AE"):
                out[key] = np.array([float(x) for x in val.split(",")]) if val else np.zeros(0)
            elif key == "time":
                out[key] = float(val)
    return out


def test_restart_file_holds_the_final_accelerations_and_multipliers(tmp_path):
    """A restart file written by exl.SolveDynamic stores q, q_t, q_tt and the AE coordinates
    of the final state, consistent with each other: Exudyn's equations
    M q_tt + C_q^T lambda = f hold for the stored values (nothing else reads q_tt here, so
    without the restart file they would not be written every output)."""
    T = 0.2
    mbs, b, s, sj = heavy_top()
    ss = settings(T, 1e-3, sensors=False)
    ss.solution.restart.write = True
    ss.solution.restart.name = str(tmp_path / "restart.txt")
    ss.solution.restart.writePeriod = 0.05
    exl.SolveDynamic(mbs, ss)
    assert mbs.sys["lieGroupSolver"].timing["substeps"] == 50
    rs = read_restart(ss.solution.restart.name)
    assert rs["time"] == pytest.approx(T)
    sd = mbs.systemData
    np.testing.assert_allclose(rs["ODE2"], sd.GetODE2Coordinates(), rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(rs["ODE2_tt"], sd.GetODE2Coordinates_tt(), rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(rs["AE"], sd.GetAECoordinates(), rtol=1e-15, atol=1e-15)
    assert np.max(np.abs(rs["AE"])) > 100                    # the joint force, not the initial zeros
    res = exudyn_equations_residual(mbs, (rs["time"], rs["ODE2"], rs["ODE2_t"], rs["ODE2_tt"], rs["AE"]))
    assert res < 1e-12


# ---------------------------------------------------------------------------- settings
def test_simulation_settings_are_not_changed_during_or_after_the_run():
    """The run works on a copy: user functions reading the settings (the object passed,
    also as mbs.sys['simulationSettings']) see the user's values, and afterwards they are
    unchanged."""
    seen = []
    ss = settings(0.1, 1e-3)
    ss.timeIntegration.solverType = exu.DynamicSolverType.RK44          # the user's own values
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    ss.timeIntegration.generalizedAlpha.useNewmark = True
    ss.timeIntegration.generalizedAlpha.useIndex2Constraints = True
    ss.timeIntegration.adaptiveStep = True
    ss.timeIntegration.automaticStepSize = True
    before = ss.GetDictionary()

    def look(mbs, t):
        s_ = mbs.sys["simulationSettings"]
        assert s_ is ss
        ti = s_.timeIntegration
        ga = ti.generalizedAlpha
        seen.append((ti.numberOfSteps, ti.solverType, ga.computeInitialAccelerations, ga.useNewmark,
                     ga.useIndex2Constraints, ti.adaptiveStep, ti.automaticStepSize))

    def sensor_uf(mbs, t, sensorNumbers, factors, configuration):
        look(mbs, t)
        return [t]

    mbs, b, s = free_body()
    mbs.AddSensor(SensorUserFunction(sensorNumbers=[s], storeInternal=True, sensorUserFunction=sensor_uf))
    mbs.Assemble()
    exl.SolveDynamic(mbs, ss)
    assert mbs.sys["lieGroupSolver"].timing["substeps"] == 10        # numberOfSteps 10 for Exudyn's loop
    mbs2, b2, s2 = free_body()
    mbs2.SetPreStepUserFunction(lambda mbs, t: look(mbs, t) or True)
    mbs2.Assemble()
    exl.SolveDynamic(mbs2, ss)
    assert len(seen) > 100
    assert set(seen) == {(100, exu.DynamicSolverType.RK44, True, True, True, True, True)}
    assert ss.GetDictionary() == before


# ---------------------------------------------------------------------------- torsional spring turns
def spinning_torsion(uf=False):
    """A body spinning at ~20 rad/s about z, held by a weak torsional spring to ground
    (turns several times in a second)."""
    mbs = new_mbs()
    g = mbs.CreateGround()
    b = add_body(mbs, "RotVecLG", [0, 0, 0], np.eye(3), omega=(0.0, 0.0, 20.0), vel=(0, 0, 0), com=(0, 0, 0))
    kw = dict(springTorqueUserFunction=lambda mbs, t, i, phi, om, k, d, off: k * (phi - off) + d * om) if uf else {}
    o = mbs.CreateTorsionalSpringDamper(itemNumbers=[g, b], position=[0, 0, 0], axis=[0, 0, 1], stiffness=0.05,
                                        damping=0.001, offset=0.2, **kw)
    mbs.Assemble()
    return mbs, o


@pytest.mark.parametrize("uf", [False, True], ids=["compiled", "userfunction"])
def test_torsional_spring_turns_carry_over_to_a_continued_run(uf):
    """The turned angle is left in the spring's data node (as a native solve leaves it,
    even when Exudyn's own update, once per output, would lose turns) and a run continued
    with updateInitialValues starts from it: 0.5 s + 0.5 s = 1 s in one run."""
    T = 0.5
    ss = settings(T, 1e-3, sensors=False)          # no outputs: one Exudyn step of 500 steps
    mbs, o = spinning_torsion(uf)
    exl.SolveDynamic(mbs, ss, liegroup="SO3xR3")
    assert mbs.sys["lieGroupSolver"].timing["exudynSteps"] == 1
    nat, on = spinning_torsion(uf)
    nss = settings(T, 1e-3, sensors=False)
    nss.timeIntegration.solverType = exu.DynamicSolverType.RK44
    nat.SolveDynamic(nss)
    angle = float(nat.systemData.GetDataCoordinates()[0])
    assert angle > 8                                       # turned more than once
    np.testing.assert_allclose(mbs.systemData.GetDataCoordinates(), [angle], rtol=0, atol=1e-9)
    np.testing.assert_allclose(mbs.GetObjectOutput(o, O.Rotation), angle, rtol=0, atol=1e-9)
    # continued run == one run of 1 s
    exl.SolveDynamic(mbs, settings(T, 1e-3, sensors=False), updateInitialValues=True, liegroup="SO3xR3")
    exl.SolveDynamic(mbs, settings(T, 1e-3, sensors=False), liegroup="SO3xR3")
    one, o1 = spinning_torsion(uf)
    exl.SolveDynamic(one, settings(2 * T, 1e-3, sensors=False), liegroup="SO3xR3")
    sd, sd1 = mbs.systemData, one.systemData
    np.testing.assert_allclose(sd.GetDataCoordinates(), sd1.GetDataCoordinates(), rtol=0, atol=1e-9)
    np.testing.assert_allclose(sd.GetODE2Coordinates_t(), sd1.GetODE2Coordinates_t(), rtol=0, atol=1e-9)
    np.testing.assert_allclose(sd.GetODE2Coordinates(), sd1.GetODE2Coordinates(), rtol=0, atol=1e-9)


@pytest.mark.parametrize("uf", [False, True], ids=["compiled", "userfunction"])
def test_torsional_spring_turns_survive_a_state_change_in_a_pre_step_function(uf):
    """A pre-step function changes the state after the spring has turned past pi: the
    bridge re-reads the state and continues the angle from the spring's data node, as
    Exudyn does; the run equals Exudyn's RK44 (= RK4 on SO3xR3 for this body)."""
    T = 0.6

    def pre(mbs, t):
        if abs(t - 0.3) < 1e-9:                  # slow the spin down
            mbs.systemData.SetODE2Coordinates_t(0.5 * mbs.systemData.GetODE2Coordinates_t())
        return True

    out = []
    for native in (True, False):
        mbs, o = spinning_torsion(uf)
        mbs.SetPreStepUserFunction(pre)
        mbs.Assemble()
        ss = settings(T, 1e-3, sensors=False)
        if native:
            ss.timeIntegration.solverType = exu.DynamicSolverType.RK44
            mbs.SolveDynamic(ss)
        else:
            exl.SolveDynamic(mbs, ss, liegroup="SO3xR3")
        sd = mbs.systemData
        out.append((np.array(sd.GetDataCoordinates()), np.array(sd.GetODE2Coordinates_t()),
                    np.array(mbs.GetObjectOutputBody(1, O.RotationMatrix, localPosition=[0, 0, 0]))))
    assert out[0][0][0] > 2 * np.pi                     # turned more than once
    for a, b in zip(*out):
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-9)


def test_the_model_is_read_once_per_solve(monkeypatch):
    """SolveDynamic on an assembled model reads it once: the scene the path choice read is the
    compiled path's (a second reading cost the set-up of every solve)."""
    import exudyn_lie.bridge.evaluated_dispatch as dispatch
    import exudyn_lie.bridge.solver as bsolver
    calls = []
    real = dispatch.SceneFromExudyn

    def counting(*a, **k):
        calls.append(a[1:])
        return real(*a, **k)
    monkeypatch.setattr(dispatch, "SceneFromExudyn", counting)
    monkeypatch.setattr(bsolver, "SceneFromExudyn", counting)
    mbs, b, s, sj = heavy_top()
    exl.SolveDynamic(mbs, settings(0.01, 1e-3))
    assert len(calls) == 1, calls
