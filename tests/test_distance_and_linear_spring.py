"""``ObjectConnectorDistance`` (the kernel row ``ROW_DIST``) and
``ObjectConnectorLinearSpringDamper`` (a compiled force element): J and eta against finite
differences, Exudyn's own M, f, C_q at random states, and agreement with Exudyn's
generalized-alpha at a fine step."""
import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import (MarkerBodyPosition, MarkerBodyRigid, MarkerNodePosition, NodePoint,
                              ObjectConnectorDistance, ObjectConnectorLinearSpringDamper, ObjectMassPoint,
                              RotationMatrixX, RotationMatrixY, RotationMatrixZ)

import exudyn_lie as exl
from exudyn_lie.mbs import GROUND, Scene
from test_bridge_common import add_body, compare, new_mbs, quiet_settings, random_state
from test_kernel_joints import finite_differences, random_rotation

TOL = 1e-11


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("ground_side", ["none", "A", "B"])
def test_distance_row_against_finite_differences(group, ground_side, rng):
    for _ in range(3):
        sc = Scene()
        for _ in range(2):
            sc.AddBody(rng.uniform(0.5, 2), np.diag(rng.uniform(0.1, 0.3, 3)), com=rng.normal(size=3) * 0.1,
                       R0=random_rotation(rng), r0=rng.normal(size=3))
        A, B = (GROUND, 1) if ground_side == "A" else ((0, GROUND) if ground_side == "B" else (0, 1))
        sc.AddDistanceConstraint(A, rng.normal(size=3) * 0.3, B, rng.normal(size=3) * 0.3, rng.uniform(0.5, 2))
        J, eta, Jfd, Jdot_V = finite_differences(sc, group, rng)
        assert J.shape == (1, 12) and np.max(np.abs(J)) > 0.1
        np.testing.assert_allclose(J, Jfd, atol=1e-8, rtol=1e-6)
        np.testing.assert_allclose(-eta, Jdot_V, atol=1e-7, rtol=1e-6)


def items_model(nodes=("RotVecLG", "EP")):
    """Two rigid bodies and a point mass: distance constraints body-body, ground-body,
    point-body; linear spring-dampers on rigid markers (body, node, ground) to bodies and the point."""
    mbs = new_mbs()
    g = mbs.CreateGround(referencePosition=[0.1, 0.2, 0.3], referenceRotationMatrix=RotationMatrixY(0.2))
    b0 = add_body(mbs, nodes[0], [1, 0, 0], RotationMatrixZ(0.3), gravity=[0, 0, -9.81])
    b1 = add_body(mbs, nodes[1], [1.5, 0.3, 0.1], RotationMatrixX(0.7), omega=(-0.4, 0.6, 0.2), vel=(0.3, -0.1, 0.2))
    npt = mbs.AddNode(NodePoint(referenceCoordinates=[0.2, 0.4, -0.3], initialVelocities=[0.1, 0.2, 0.3]))
    mbs.AddObject(ObjectMassPoint(mass=1.3, nodeNumber=npt))
    mp = mbs.AddMarker(MarkerNodePosition(nodeNumber=npt))
    m0 = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b0, localPosition=[0.1, -0.05, 0.2]))
    m1 = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b1, localPosition=[-0.1, 0.1, 0.05]))
    mg = mbs.AddMarker(MarkerBodyPosition(bodyNumber=g, localPosition=[0.3, 0.0, -0.2]))
    for a, b, L in [(m0, m1, 0.7), (mg, m0, 1.1), (mp, m1, 1.4)]:
        mbs.AddObject(ObjectConnectorDistance(markerNumbers=[a, b], distance=L))
    r0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b0, localHT=exu.HT(rotation=RotationMatrixX(0.4),
                                                                       translation=[0.05, 0.1, 0])))
    rn1 = mbs.AddMarker(exu.utilities.MarkerNodeRigid(nodeNumber=mbs.GetObject(b1)["nodeNumber"]))
    rg = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g, localHT=exu.HT(rotation=RotationMatrixZ(0.5),
                                                                     translation=[0, 0.2, 0])))
    r1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b1, localHT=exu.HT(rotation=RotationMatrixY(0.3),
                                                                       translation=[-0.1, 0.1, 0.05])))
    for a, b, axis, k, d, off, vo, f in [(r0, r1, [1, 0, 0], 50, 0.5, 0.1, 0.2, 0.3),
                                          (rn1, r0, [0.6, 0, 0.8], 30, 0.2, -0.1, 0.0, 0.0),
                                          (rg, r1, [0, 1, 0], 20, 0.1, 0.0, 0.1, 1.0)]:
        mbs.AddObject(ObjectConnectorLinearSpringDamper(markerNumbers=[a, b], axisMarker0=axis, stiffness=k,
                                                        damping=d, offset=off, velocityOffset=vo, force=f))
    mbs.Assemble()
    return mbs


@pytest.mark.parametrize("nodes", [("RotVecLG", "EP"), ("EP", "Rxyz"), ("Rxyz", "RotVecLG")],
                         ids=lambda p: "-".join(p))
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_distance_and_linear_spring_same_as_exudyn(nodes, group, rng):
    mbs = items_model(nodes)
    for trial in range(2):
        q, qt = random_state(mbs, rng)
        c = compare(mbs, group, q, qt, 0.2 + trial)
        for key in ("M", "f", "g", "J"):
            assert c[key] < TOL, f"{key}: relative deviation {c[key]:.3g} from Exudyn (trial {trial})"
        assert c["nrows"] == 3


def pendulum_model(node="RotVecLG"):
    """A point mass on a distance constraint to the ground (a spherical pendulum) and a rigid
    body on a distance constraint to the point mass, a linear spring-damper from the body to
    the ground; consistent initial state."""
    mbs = new_mbs()
    g = mbs.CreateGround(referencePosition=[0, 0, 0])
    mg = mbs.AddMarker(MarkerBodyPosition(bodyNumber=g, localPosition=[0, 0, 0]))
    npt = mbs.AddNode(NodePoint(referenceCoordinates=[1.0, 0, 0], initialVelocities=[0, 0.8, 0.5]))
    mbs.AddObject(ObjectMassPoint(mass=1.3, nodeNumber=npt))
    mp = mbs.AddMarker(MarkerNodePosition(nodeNumber=npt))
    mbs.AddObject(ObjectConnectorDistance(markerNumbers=[mg, mp], distance=1.0))
    b = add_body(mbs, node, [1.0, -0.8, 0], np.eye(3), omega=(0.3, 0.2, 1.0), vel=(0.0, 0.8, 0.5),
                 gravity=[0, -9.81, 0])
    mb = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b, localPosition=[0, 0.2, 0]))
    mbs.AddObject(ObjectConnectorDistance(markerNumbers=[mp, mb], distance=0.6))
    mb = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b, localHT=exu.HT(rotation=np.eye(3), translation=[0, 0.2, 0])))
    rg = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g, localHT=exu.HT(rotation=np.eye(3), translation=[0, -1, 0])))
    mbs.AddObject(ObjectConnectorLinearSpringDamper(markerNumbers=[rg, mb], axisMarker0=[1, 0, 0], stiffness=30,
                                                    damping=0.2, offset=0.5))
    mm = mbs.AddMarker(exu.utilities.MarkerBodyMass(bodyNumber=1))
    mbs.AddLoad(exu.utilities.LoadMassProportional(markerNumber=mm, loadVector=[0, -9.81, 0]))
    mbs.Assemble()
    return mbs


def _final(mbs, h, T, lie):
    ss = quiet_settings(endTime=T, nsteps=int(round(T / h)))
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    if lie:
        exl.SolveDynamic(mbs, ss, method="RK4")
    else:
        exu.SolveDynamic(mbs, ss)
    return np.array(mbs.systemData.GetODE2Coordinates()), np.array(mbs.systemData.GetODE2Coordinates_t())


@pytest.mark.parametrize("node", ["RotVecLG", "EP"])
def test_distance_pendulum_agrees_with_generalized_alpha_at_a_fine_step(node):
    """Native generalized-alpha at h = 2e-5 (the reference) vs exl RK4 at h = 1e-3 over 0.5 s."""
    T = 0.5
    qn, vn = _final(pendulum_model(node), 2e-5, T, False)
    ql, vl = _final(pendulum_model(node), 1e-3, T, True)
    assert np.max(np.abs(ql - qn)) < 1e-6 * max(1, np.abs(qn).max())
    assert np.max(np.abs(vl - vn)) < 1e-5 * max(1, np.abs(vn).max())
