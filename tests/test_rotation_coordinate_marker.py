"""``MarkerNodeRotationCoordinate`` in velocity-level ``ObjectConnectorCoordinate`` rows, compiled
(bridge/reader.py, ``rotation_coordinate_marker``), as Exudyn defines it
(CMarkerNodeRotationCoordinate::ComputeMarkerData): the marker's rate is component k of the node's
world angular velocity, its Jacobian that rate's; the row ``f omega_B[k] - omega_A[k] = offset``.

* the rows against Exudyn's own velocity-level residual and its Jacobian on the velocities at random
  states, for every rigid node type and axis k, on both groups;
* position-level uses (Exudyn's value is a Tait-Bryan angle in (-pi, pi]) take the Exudyn-evaluated
  path under evaluation='auto' and are refused by evaluation='compiled', naming the marker;
* TestModels style: a box on a spherical joint whose world angular velocity about axis k is held, per
  node type, against native generalized-alpha at a fine step, on the compiled and the evaluated path.
"""
import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import (MarkerNodeCoordinate, MarkerNodeRotationCoordinate, NodePointGround,
                              ObjectConnectorCoordinate, ObjectConnectorCoordinateSpringDamper)

import exudyn_lie as exl
from exudyn_lie.bridge.reader_common import BridgeError, NotCompiled
from exudyn_lie.groups import so3
from test_bridge_common import CUR, add_body, box_on_spherical_joint, new_mbs, package, quiet_settings, random_state

NODES = ("RotVecLG", "EP", "Rxyz")


def _rate_model(node, kA, kB, factor):
    """Two bodies of ``node`` type, a row between rotation coordinate kA of body 0 and kB of body 1,
    and a row from a ground node's rotation coordinate to body 1's axis 2 (Exudyn refuses the marker
    on a NodeRigidBody2D)."""
    mbs = new_mbs()
    R0 = [so3.exp(np.array([0.3, -0.2, 0.4])), so3.exp(np.array([-0.5, 0.1, 0.2]))]
    bodies = [add_body(mbs, node, [0.3 * i, 0, 0], R0[i]) for i in range(2)]
    nodes = [mbs.GetObject(b)["nodeNumber"] for b in bodies]
    ng = mbs.AddNode(NodePointGround())

    def mr(n, k):
        return mbs.AddMarker(MarkerNodeRotationCoordinate(nodeNumber=n, rotationCoordinate=k))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mr(nodes[0], kA), mr(nodes[1], kB)], factor1=factor,
                                            offset=0.3, velocityLevel=True))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mr(ng, 0), mr(nodes[1], 2)], offset=-0.2,
                                            velocityLevel=True))
    mbs.Assemble()
    return mbs


def _exudyn_velocity_rows(mbs, q, qt):
    """Exudyn's velocity-level residual of the AE rows and their Jacobian on the ODE2 velocities."""
    sd = mbs.systemData
    s = exu.MainSolverImplicitSecondOrder()
    ss = quiet_settings()
    s.InitializeSolver(mbs, ss)
    n, m = s.GetODE2size(), s.GetAEsize()
    sd.SetODE2Coordinates(q, configuration=CUR)
    sd.SetODE2Coordinates_t(qt, configuration=CUR)
    sd.SetAECoordinates(np.zeros(m), configuration=CUR)
    s.ComputeAlgebraicEquations(mbs, True)
    gv = np.array(s.GetSystemResidual())[n:n + m].copy()
    s.ComputeJacobianODE2RHS(mbs, scalarFactor_ODE2=0., scalarFactor_ODE2_t=0., scalarFactor_ODE1=0.)
    s.ComputeJacobianAE(mbs, scalarFactor_ODE2=0., scalarFactor_ODE2_t=1., scalarFactor_ODE1=0.)
    Cv = np.array(s.GetSystemJacobian())[n:n + m, :n].copy()
    s.FinalizeSolver(mbs, ss)
    return gv, Cv


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("node", NODES)
def test_rows_equal_exudyns_velocity_level_at_random_states(node, group, rng):
    """Per row: the kernel's J equals Exudyn's C_qdot P (q_t = P V), and J V - offset equals Exudyn's
    velocity-level residual, for three pairs of axes."""
    for kA, kB in [(0, 1), (1, 2), (2, 0)]:
        mbs = _rate_model(node, kA, kB, -0.7)
        for trial in range(2):
            q, qt = random_state(mbs, rng, scale=0.5)
            gv, Cv = _exudyn_velocity_rows(mbs, q, qt)
            pk = package(mbs, group, q, qt)
            sim, sc = pk["sim"], pk["scene"]
            assert len(sc.joints_info) == 2
            V = sim.V.reshape(-1)
            for ji, offset in zip(sc.joints_info, (0.3, -0.2)):
                r0 = int(sim.sd.jointIndex[ji.sceneJoint, 2])
                J = pk["J"][r0]
                ae = ji.aeRows[0]
                scale = max(1.0, np.abs(Cv[ae]).max())
                assert np.abs(J - Cv[ae] @ pk["P"]).max() < 1e-12 * scale, (kA, kB, trial)
                assert abs(J @ V - offset - gv[ae]) < 1e-12 * max(1.0, abs(gv[ae])), (kA, kB, trial)


def _position_level_model(spring):
    mbs = new_mbs()
    b = add_body(mbs, "EP", [0, 0, 0], np.eye(3))
    n = mbs.GetObject(b)["nodeNumber"]
    ng = mbs.AddNode(NodePointGround())
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ng, coordinate=0))
    mr = mbs.AddMarker(MarkerNodeRotationCoordinate(nodeNumber=n, rotationCoordinate=2))
    if spring:
        mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mg, mr], stiffness=10.0, damping=0.1))
    else:
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mg, mr]))
    mbs.Assemble()
    return mbs


def test_position_level_constraint_is_refused_before_mbs_is_touched():
    """Exudyn's position-level value is a Tait-Bryan angle in (-pi, pi] whose gradient is not the
    marker's Jacobian: evaluation='compiled' refuses it naming the marker; the Exudyn-evaluated path
    too (its index-1 solve with Exudyn's C_q would hold the angular velocity: the run-time check
    stopped it at t = 0.085 s before this refusal), with the reason, before mbs is touched."""
    mbs = _position_level_model(False)
    with pytest.raises(NotCompiled, match="MarkerNodeRotationCoordinate"):
        exl.SolveDynamic(mbs, quiet_settings(0.1, 20), evaluation="compiled")
    q0 = np.array(mbs.systemData.GetODE2Coordinates())
    with pytest.raises(BridgeError, match="Tait-Bryan angle of the node, whose gradient is not"):
        exl.SolveDynamic(mbs, quiet_settings(0.1, 20))
    assert np.array_equal(q0, mbs.systemData.GetODE2Coordinates()) and mbs.systemData.GetTime() == 0.0


def test_spring_on_the_angle_runs_on_the_evaluated_path_as_native():
    """A spring on the Tait-Bryan angle: Exudyn's own force on the Exudyn-evaluated path ('auto', with
    its warning), RK4 at 200 steps over 0.1 s within 1e-6 of native generalized-alpha at 20,000."""
    mbs = _position_level_model(True)
    with pytest.raises(NotCompiled, match="MarkerNodeRotationCoordinate"):
        exl.SolveDynamic(mbs, quiet_settings(0.1, 20), evaluation="compiled")
    with pytest.warns(RuntimeWarning, match="evaluates the whole model"):
        exl.SolveDynamic(mbs, quiet_settings(0.1, 200), method="RK4")
    x = np.array(mbs.systemData.GetODE2Coordinates())
    ref = _position_level_model(True)
    exu.SolveDynamic(ref, quiet_settings(0.1, 20000))
    assert np.abs(x - ref.systemData.GetODE2Coordinates()).max() < 1e-6


def test_ground_rotation_marker_is_a_ground_coordinate_at_position_level():
    """On a NodePointGround the marker's value and rate are 0 and it has no Jacobian (Exudyn assembles
    it): a position-level ConnectorCoordinate from it to a point mass's coordinate is compiled and
    holds that coordinate at the offset, as Exudyn's run does."""
    from exudyn.utilities import NodePoint, ObjectMassPoint, LoadForceVector, MarkerNodePosition
    out = []
    for lie in (False, True):
        mbs = new_mbs()
        p = mbs.AddNode(NodePoint(referenceCoordinates=[0, 0, 0], initialVelocities=[0.0, 0.5, 0.0]))
        mbs.AddObject(ObjectMassPoint(nodeNumber=p, physicsMass=2.0))
        mbs.AddLoad(LoadForceVector(markerNumber=mbs.AddMarker(MarkerNodePosition(nodeNumber=p)), loadVector=[1, 0, 0]))
        ng = mbs.AddNode(NodePointGround())
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[
            mbs.AddMarker(MarkerNodeRotationCoordinate(nodeNumber=ng, rotationCoordinate=1)),
            mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=p, coordinate=0))], offset=0.0))
        mbs.Assemble()
        ss = quiet_settings(0.5, 100)
        (exl.SolveDynamic(mbs, ss, evaluation="compiled") if lie else exu.SolveDynamic(mbs, ss))
        out.append(np.array(mbs.systemData.GetODE2Coordinates()))
    assert abs(out[1][0]) < 1e-12 and abs(out[1][1] - 0.25) < 1e-12, out[1]
    assert np.abs(out[1] - out[0]).max() < 1e-10, out


def test_a_row_switched_to_position_level_during_the_run_stops_it():
    """A pre-step function sets velocityLevel=False on the Exudyn-evaluated path (evaluation='exudyn'):
    the rows are read again and refused with the reason, instead of holding the angular velocity."""
    mbs = _held_rate_model("EP", 2)
    o = mbs.systemData.NumberOfObjects() - 1

    def pre(mbs, t):
        if t > 0.05:
            mbs.SetObjectParameter(o, "velocityLevel", False)
        return True
    mbs.SetPreStepUserFunction(pre)
    with pytest.raises(BridgeError, match="Tait-Bryan angle of the node, whose gradient is not"):
        exl.SolveDynamic(mbs, quiet_settings(0.2, 200), evaluation="exudyn", method="RK4")


def _held_rate_model(node, k):
    """A box (offset COM, gravity) on a spherical joint at its node, its world angular velocity about
    axis k held at 2.5 rad/s by a velocity-level ObjectConnectorCoordinate (consistent initially)."""
    mbs = new_mbs()
    om = [1.0, -2.0, 3.0]
    om[k] = 2.5
    n, ng = box_on_spherical_joint(mbs, node, so3.exp(np.array([0.3, -0.2, 0.4])), om, com=(0.02, 0.01, 0.0),
                                   sides=(0.3, 0.1, 0.2))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ng, coordinate=0)),
        mbs.AddMarker(MarkerNodeRotationCoordinate(nodeNumber=n, rotationCoordinate=k))], offset=2.5,
        velocityLevel=True))
    mbs.Assemble()
    return mbs


def _final_state(node, k, nsteps, **lie):
    mbs = _held_rate_model(node, k)
    ss = quiet_settings(1.0, nsteps)
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    ss.timeIntegration.newton.relativeTolerance = 1e-12
    ss.timeIntegration.newton.absoluteTolerance = 1e-14
    (exl.SolveDynamic(mbs, ss, **lie) if lie else exu.SolveDynamic(mbs, ss))
    sd = mbs.systemData
    return np.r_[sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t()]


@pytest.mark.parametrize("node,k", [("RotVecLG", 0), ("EP", 2), ("Rxyz", 1)])
def test_held_rate_agrees_with_fine_generalized_alpha(node, k):
    """Over 1 s (|theta| passes pi: RotVecLG's coordinates on Exudyn's branch): native at 20,000 and
    40,000 steps differ by 8e-8 .. 2e-7 (measured); RK4 at 500 steps on the compiled path and on the
    Exudyn-evaluated path is within 2e-7 of the native run at 40,000 steps (measured 2.6e-8 .. 6.9e-8),
    coordinates and velocities."""
    ref = _final_state(node, k, 40000)
    for evaluation in ("compiled", "exudyn"):
        x = _final_state(node, k, 500, method="RK4", evaluation=evaluation)
        assert np.abs(x - ref).max() < 2e-7, (evaluation, np.abs(x - ref).max())
