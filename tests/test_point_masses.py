"""Point masses (``NodePoint`` + ``ObjectMassPoint``, ``NodePoint2D`` + ``ObjectMassPoint2D``) on
the group R^3 (``groups/rn.py``): Exudyn's own M, f and C_q at random states, and agreement
with Exudyn's generalized-alpha at a fine step."""
import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import (LoadForceVector, LoadMassProportional, MarkerBodyMass, MarkerBodyPosition,
                              MarkerNodePosition, NodePoint, NodePoint2D, ObjectConnectorCartesianSpringDamper,
                              ObjectConnectorSpringDamper, ObjectJointSpherical, ObjectMassPoint, ObjectMassPoint2D,
                              RotationMatrixZ)

import exudyn_lie as exl
from test_bridge_common import add_body, compare, new_mbs, quiet_settings, random_state

TOL = 1e-11


def point_model(rigid=True):
    """A 3D point mass, a 2D point mass and (optionally) a rigid body: springs, a Cartesian
    spring, a spherical joint point-rigid body, loads on node and body markers, gravity."""
    mbs = new_mbs()
    g = mbs.CreateGround(referencePosition=[0.1, 0.2, 0.3])
    mg = mbs.AddMarker(MarkerBodyPosition(bodyNumber=g, localPosition=[0.2, -0.1, 0.4]))
    n0 = mbs.AddNode(NodePoint(referenceCoordinates=[1.0, 0.2, -0.1], initialCoordinates=[0.05, 0, 0],
                               initialVelocities=[0.3, -0.2, 0.4]))
    o0 = mbs.AddObject(ObjectMassPoint(mass=1.7, nodeNumber=n0))
    n1 = mbs.AddNode(NodePoint2D(referenceCoordinates=[0.4, -0.6], initialVelocities=[-0.5, 0.25]))
    o1 = mbs.AddObject(ObjectMassPoint2D(mass=0.8, nodeNumber=n1))
    m0 = mbs.AddMarker(MarkerNodePosition(nodeNumber=n0))
    m0b = mbs.AddMarker(MarkerBodyPosition(bodyNumber=o0, localPosition=[0.1, 0.05, -0.2]))
    m1 = mbs.AddMarker(MarkerBodyPosition(bodyNumber=o1, localPosition=[0.0, 0.1, 0.0]))
    m1n = mbs.AddMarker(MarkerNodePosition(nodeNumber=n1))
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mg, m0], stiffness=40, damping=0.7, referenceLength=0.6))
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[m0b, m1], stiffness=25, damping=0.3,
                                              referenceLength=0.9, force=0.4))
    mbs.AddObject(ObjectConnectorCartesianSpringDamper(markerNumbers=[mg, m1n], stiffness=[11, 13, 17],
                                                       damping=[0.1, 0.2, 0.3], offset=[0.1, -0.2, 0.05]))
    mbs.AddLoad(LoadForceVector(markerNumber=m0, loadVector=[0.3, -0.4, 0.5]))
    mbs.AddLoad(LoadForceVector(markerNumber=m1, loadVector=[0.2, 0.1, 0.7]))
    for o in (o0, o1):
        mm = mbs.AddMarker(MarkerBodyMass(bodyNumber=o))
        mbs.AddLoad(LoadMassProportional(markerNumber=mm, loadVector=[0, -9.81, 0]))
    if rigid:
        b = add_body(mbs, "RotVecLG", [1.05, -0.3, -0.1], RotationMatrixZ(0.3), com=(0, 0, 0), gravity=[0, -9.81, 0],
                     vel=(0.3, -0.2, 0.4), omega=(0, 0, 0))
        # the rigid body's origin hangs on the 3D point mass by a spherical joint (point at distance 0.5)
        mb = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b, localPosition=RotationMatrixZ(0.3).T @ [0, 0.5, 0.0]))
        mbs.AddObject(ObjectJointSpherical(markerNumbers=[m0, mb]))
    mbs.Assemble()
    return mbs


@pytest.mark.parametrize("group", ["SE3", "SO3xR3", "auto"])
def test_point_masses_same_M_f_jacobian_as_exudyn(group, rng):
    mbs = point_model()
    for trial in range(2):
        q, qt = random_state(mbs, rng)
        c = compare(mbs, group, q, qt, 0.3 + trial)
        for key in ("M", "f", "g", "J"):
            assert c[key] < TOL, f"{key}: relative deviation {c[key]:.3g} from Exudyn (trial {trial})"
        assert c["nrows"] == 3


def test_point_masses_are_on_R3_whatever_group_is_asked():
    from exudyn_lie.bridge import SceneFromExudyn
    from exudyn_lie.mbs import Simulator
    sc = SceneFromExudyn(point_model(), "initial")
    sim = Simulator(sc, "RK4", "SE3")
    assert sim.groups == ["R3", "R3", "SE3"]
    np.testing.assert_array_equal(sim.sd.Minv[1][3:, 3:], np.diag([1 / 0.8, 1 / 0.8, 0.0]))


def _solve(mbs, h, T, lie):
    ss = quiet_settings(endTime=T, nsteps=int(round(T / h)))
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    if lie:
        exl.SolveDynamic(mbs, ss, method="RK4")
    else:
        exu.SolveDynamic(mbs, ss)
    return np.array(mbs.systemData.GetODE2Coordinates()), np.array(mbs.systemData.GetODE2Coordinates_t())


def test_point_masses_agree_with_generalized_alpha_at_a_fine_step():
    """Native generalized-alpha (2nd order) at h = 2e-5 vs exl RK4 at h = 1e-3, T = 0.5 s:
    the difference is the native run's error, O(h^2) ~ 1e-7 relative."""
    T = 0.5
    qn, vn = _solve(point_model(), 2e-5, T, False)
    ql, vl = _solve(point_model(), 1e-3, T, True)
    assert np.max(np.abs(ql - qn)) < 2e-6 * max(1, np.abs(qn).max())
    assert np.max(np.abs(vl - vn)) < 2e-5 * max(1, np.abs(vn).max())


def test_R3_is_refused_for_a_rigid_body():
    from exudyn_lie.bridge import SceneFromExudyn
    from exudyn_lie.mbs import SceneError, Simulator
    sc = SceneFromExudyn(point_model(), "initial")
    with pytest.raises(SceneError, match="R3 is the group of point masses"):
        Simulator(sc, "RK4", ["R3", "R3", "R3"])
    assert Simulator(sc, "RK4", ["R3", "R3", "SO3xR3"]).groups == ["R3", "R3", "SO3xR3"]


def test_a_mass_point_on_a_ground_node_is_ground_and_a_marker_on_it_is_refused():
    """Exudyn accepts an ObjectMassPoint on a NodePointGround (fourBarMechanismTest): no
    coordinates, it stays at the node; markers on the node are ground points.  A body marker on
    that object makes Exudyn's own solver fail, so it is refused, before mbs is touched."""
    import importlib
    import exudyn_lie as exl
    mod = importlib.import_module("item_corpus.massPointOnGroundNode")
    mbs, ss = mod.Build()
    sc = exl.SceneFromExudyn(mbs)
    assert sc.nBodies == 2 and sc.bodyObject == [1, 2]
    o0 = 0
    mbs.AddMarker(exu.itemInterface.MarkerBodyPosition(bodyNumber=o0, localPosition=[0, 0, 0]))
    m = mbs.systemData.NumberOfMarkers() - 1
    n1m = [k for k in range(m) if mbs.GetMarker(k)["markerType"] == "NodePosition"][1]
    mbs.AddObject(exu.itemInterface.ObjectConnectorSpringDamper(markerNumbers=[m, n1m], stiffness=1.0))
    mbs.Assemble()
    with pytest.raises(exl.BridgeError, match=r"marker \d+ \(MarkerBodyPosition\) is on object 0 \(ObjectMassPoint "
                                              r"on a NodePointGround\)"):
        exl.SceneFromExudyn(mbs)
