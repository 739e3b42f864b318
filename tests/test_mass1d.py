"""``Node1D`` with ``ObjectMass1D`` and ``ObjectRotationalMass1D`` (nodes.Node1DNode):

* a Mass1D is a point mass on the line ``referencePosition + referenceRotation e_x x`` (R^3 with
  that one free direction), with body markers (position, rigid, mass) in Exudyn's frame;
* a RotationalMass1D is a rotor ``R = referenceRotation Rz(x)`` turning about its axis only, with
  body markers on the axis (as Exudyn allows) and its angle as a rotation coordinate (turns kept);
* coordinate items (ConnectorCoordinate, CoordinateSpringDamper, LoadCoordinate) on Node1D
  coordinates, mixed with rigid-node coordinates.

Checked against Exudyn's own M, f, g and C_q at random states, a native generalized-alpha run
at a fine step (a small drive train), and refusals before ``mbs`` is touched.
"""
import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import (LoadCoordinate, LoadForceVector, LoadMassProportional, LoadTorqueVector, MarkerBodyMass,
                              MarkerBodyRigid, ObjectConnectorTorsionalSpringDamper, RotationMatrixX,
                              MarkerNodeCoordinate, Node1D, ObjectConnectorCoordinate,
                              ObjectConnectorCoordinateSpringDamper, ObjectConnectorDistance,
                              ObjectConnectorSpringDamper, ObjectGround, ObjectMass1D, ObjectRotationalMass1D,
                              RotationMatrixY, RotationMatrixZ)

import exudyn_lie as exl
from test_bridge_common import add_body, compare, new_mbs, quiet_settings, random_state

TOL = 1e-11


def one_d_model(node="RotVecLG"):
    """A rigid body, a Mass1D on a rotated line and a RotationalMass1D, tied by coordinate
    springs, a coordinate constraint (with factor) and a distance constraint to a rigid marker on
    the Mass1D; coordinate loads, a force on the Mass1D's marker, gravity on it (MarkerBodyMass)."""
    mbs = new_mbs()
    g = mbs.AddObject(ObjectGround())
    b0 = add_body(mbs, node, [1, 0, 0], RotationMatrixZ(0.3), gravity=[0, 0, -9.81])
    n0 = mbs.GetObject(b0)["nodeNumber"]
    n = mbs.AddNode(Node1D(referenceCoordinates=[0.5], initialCoordinates=[0.1], initialVelocities=[0.2]))
    o = mbs.AddObject(ObjectMass1D(nodeNumber=n, mass=2, referencePosition=[1, 2, 3],
                                   referenceRotation=RotationMatrixZ(0.3) @ RotationMatrixY(0.2)))
    n2 = mbs.AddNode(Node1D(referenceCoordinates=[0.3], initialCoordinates=[4 * np.pi + 0.2], initialVelocities=[1.5]))
    o2 = mbs.AddObject(ObjectRotationalMass1D(nodeNumber=n2, inertia=3, referencePosition=[0.5, -0.2, 0.1],
                                              referenceRotation=RotationMatrixX(0.4) @ RotationMatrixY(-0.3)))
    # body markers on the rotor (on its axis, as Exudyn requires): a torque load, a torsional spring
    mt = mbs.AddMarker(MarkerBodyRigid(bodyNumber=o2, localPosition=[0, 0, 0.2]))
    mbs.AddLoad(LoadTorqueVector(markerNumber=mt, loadVector=[0.3, -0.2, 0.5]))
    mbs.AddObject(ObjectConnectorTorsionalSpringDamper(markerNumbers=[
        mbs.AddMarker(MarkerBodyRigid(bodyNumber=g)), mt], stiffness=2.0, damping=0.1))

    def mc(nn, k=0):
        return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nn, coordinate=k))

    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mc(n), mc(n2)], stiffness=30, damping=0.4,
                                                        offset=0.1))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mc(n0, 1), mc(n)], stiffness=20, damping=0.2))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mc(n0, 2), mc(n2)], factor1=0.7,
                                            offset=0.7 * (4 * np.pi + 0.2)))     # the rotor two turns on
    mbs.AddLoad(LoadCoordinate(markerNumber=mc(n2), load=0.8))
    mbs.AddLoad(LoadCoordinate(markerNumber=mc(n), load=-0.5))
    mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=o)),
                                     loadVector=[0, 0, -9.81]))
    mr = mbs.AddMarker(MarkerBodyRigid(bodyNumber=o, localPosition=[0.1, 0.2, 0.3]))
    mg = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g, localPosition=[0.5, 0.5, 0]))
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mg, mr], stiffness=50, damping=0.3, referenceLength=0.2))
    mbs.AddLoad(LoadForceVector(markerNumber=mr, loadVector=[1, 2, 3]))
    mb = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b0, localPosition=[0.1, 0, 0]))
    od = mbs.AddObject(ObjectConnectorDistance(markerNumbers=[mb, mr], distance=2.0))
    mbs.Assemble()
    P = exu.OutputVariableType.Position
    L = np.linalg.norm(np.array(mbs.GetMarkerOutput(mb, P)) - np.array(mbs.GetMarkerOutput(mr, P)))
    mbs.SetObjectParameter(od, "distance", float(L))
    mbs.Assemble()
    return mbs


@pytest.mark.parametrize("node", ["RotVecLG", "EP", "Rxyz"])
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_one_d_items_same_as_exudyn(node, group, rng):
    mbs = one_d_model(node)
    for trial in range(2):
        q, qt = random_state(mbs, rng)
        c = compare(mbs, group, q, qt, 0.2 + trial)
        for key in ("M", "f", "g", "J"):
            assert c[key] < TOL, f"{key}: relative deviation {c[key]:.3g} from Exudyn (trial {trial})"
        assert c["nrows"] == 2
        assert np.abs(c["fvals"][1]).max() > 1.0              # the forces are not trivially zero


# ---------------------------------------------------------------------------- a drive train, natively at a fine step
def drive_train():
    """Exudyn's driveTrainTest in small: a rotor driven by a coordinate load, a gear
    (ConnectorCoordinate, factor1) to a second rotor held by a torsional coordinate spring to a
    ground coordinate, a piston (Mass1D on a rotated line, gravity) on a coordinate spring to the
    first rotor (a rack), and a rigid pendulum's coordinate coupled to the piston by a spring."""
    from exudyn.utilities import NodePointGround
    mbs = new_mbs()
    ng = mbs.AddNode(NodePointGround())
    nr = [mbs.AddNode(Node1D(referenceCoordinates=[0.2 * k], initialVelocities=[v])) for k, v in enumerate((2.0, -5.0))]
    for k, n in enumerate(nr):
        mbs.AddObject(ObjectRotationalMass1D(nodeNumber=n, inertia=0.5 + k))
    npis = mbs.AddNode(Node1D(referenceCoordinates=[0.1], initialVelocities=[0.3]))
    op = mbs.AddObject(ObjectMass1D(nodeNumber=npis, mass=1.5, referencePosition=[0, 0, 0.2],
                                    referenceRotation=RotationMatrixY(-0.4)))
    b = add_body(mbs, "RotVecLG", [0.3, 0, 0], np.eye(3), omega=(0, 0, 1.0), vel=(0, 0.1, 0), gravity=[0, 0, -9.81])
    nb = mbs.GetObject(b)["nodeNumber"]

    def mc(n, k=0):
        return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=k))

    mbs.AddLoad(LoadCoordinate(markerNumber=mc(nr[0]), load=1.5))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mc(nr[1]), mc(nr[0])], factor1=-2.5))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mc(ng), mc(nr[1])], stiffness=40, damping=0.5))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mc(nr[0]), mc(npis)], stiffness=60,
                                                        damping=0.2, offset=0.05))
    mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=op)),
                                     loadVector=[0, 0, -9.81]))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mc(npis), mc(nb, 0)], stiffness=80,
                                                        damping=0.1))
    g = mbs.AddObject(ObjectGround())
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mbs.AddMarker(MarkerBodyRigid(bodyNumber=g)),
                                                             mbs.AddMarker(MarkerBodyRigid(bodyNumber=b))],
                                              stiffness=100, damping=0.5, referenceLength=0.2))
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mbs.AddMarker(MarkerBodyRigid(bodyNumber=g)),
                                                             mbs.AddMarker(MarkerBodyRigid(bodyNumber=op,
                                                                                           localPosition=[0, 0.1, 0]))],
                                              stiffness=30, referenceLength=0.3))
    mbs.Assemble()
    return mbs


def _final(h, T, lie):
    mbs = drive_train()
    ss = quiet_settings(endTime=T, nsteps=int(round(T / h)))
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    ss.timeIntegration.newton.relativeTolerance = 1e-12
    ss.timeIntegration.newton.absoluteTolerance = 1e-14
    (exl.SolveDynamic(mbs, ss, method="RK4") if lie else exu.SolveDynamic(mbs, ss))
    return np.array(mbs.systemData.GetODE2Coordinates()), np.array(mbs.systemData.GetODE2Coordinates_t())


@pytest.mark.slow
def test_drive_train_agrees_with_fine_generalized_alpha():
    """Native generalized-alpha at h = 2e-4, 1e-4, 5e-5 over 1 s: second order (differences
    1.76e-6, 4.40e-7, measured), so the Richardson extrapolation of the two finest is the reference
    (it agrees with that of the two coarser ones to 4.4e-11, measured).  exl RK4 at h = 4e-3,
    2e-3, 1e-3: errors 3.5e-7, 2.2e-8, 1.4e-9 (measured), order 4."""
    T = 1.0
    nat = {h: _final(h, T, False)[0] for h in (2e-4, 1e-4, 5e-5)}
    d1, d2 = np.abs(nat[2e-4] - nat[1e-4]).max(), np.abs(nat[1e-4] - nat[5e-5]).max()
    assert 3.5 < d1 / d2 < 4.5, (d1, d2)
    ref = nat[5e-5] + (nat[5e-5] - nat[1e-4]) / 3
    assert np.abs(ref - (nat[1e-4] + (nat[1e-4] - nat[2e-4]) / 3)).max() < 1e-9
    err = {h: np.abs(_final(h, T, True)[0] - ref).max() for h in (4e-3, 2e-3, 1e-3)}
    assert err[1e-3] < 1e-8, err
    assert np.log2(err[4e-3] / err[2e-3]) > 3.6 and np.log2(err[2e-3] / err[1e-3]) > 3.5, err


# ---------------------------------------------------------------------------- refused before mbs is touched
def _refused(mbs, match):
    q0 = np.array(mbs.systemData.GetODE2Coordinates())
    with pytest.raises(exl.BridgeError, match=match):
        exl.SolveDynamic(mbs, quiet_settings())
    assert np.array_equal(q0, mbs.systemData.GetODE2Coordinates())


def test_one_d_bad_input_is_refused_before_mbs_is_touched():
    # a body marker off the axis of a RotationalMass1D (Exudyn raises for it during the solve)
    mbs = new_mbs()
    g = mbs.AddObject(ObjectGround())
    n = mbs.AddNode(Node1D(referenceCoordinates=[0], initialVelocities=[1.0]))
    o = mbs.AddObject(ObjectRotationalMass1D(nodeNumber=n, inertia=1))
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mbs.AddMarker(MarkerBodyRigid(bodyNumber=g)),
                                                             mbs.AddMarker(MarkerBodyRigid(bodyNumber=o,
                                                                                           localPosition=[0.1, 0, 0]))],
                                              stiffness=1))
    mbs.Assemble()
    _refused(mbs, r"ObjectConnectorSpringDamper.*ObjectRotationalMass1D.*localPosition")
    # a Mass1D without mass (Exudyn allows it; M would be singular here)
    mbs = new_mbs()
    n = mbs.AddNode(Node1D(referenceCoordinates=[0]))
    mbs.AddObject(ObjectMass1D(nodeNumber=n, mass=0.0))
    mbs.Assemble()
    _refused(mbs, r"ObjectMass1D.*mass")
