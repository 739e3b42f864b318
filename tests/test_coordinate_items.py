"""Coordinate items on node position coordinates: ``ObjectConnectorCoordinate`` (the kernel row
``ROW_COORD``), ``ObjectConnectorCoordinateSpringDamper`` and ``LoadCoordinate``.

* J and eta of the row against finite differences (both rigid-body groups);
* Exudyn's own M, f, C_q and residuals at random states, on rigid nodes of each type, point
  masses and a ground node;
* agreement with Exudyn's generalized-alpha at a fine step.
"""
import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import (MarkerNodeCoordinate, NodePoint, NodePoint2D, NodePointGround, ObjectConnectorCoordinate,
                              ObjectMassPoint, ObjectMassPoint2D, RotationMatrixX, RotationMatrixZ)

import exudyn_lie as exl
from exudyn_lie.mbs import GROUND, Scene
from test_bridge_common import NODE_TYPES, add_body, compare, new_mbs, quiet_settings, random_state
from test_kernel_joints import finite_differences, random_rotation

TOL = 1e-11


# ---------------------------------------------------------------------------- kernel row
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("ground_side", ["none", "A", "B"])
def test_coordinate_row_against_finite_differences(group, ground_side, rng):
    for ax, bx in [(0, 0), (1, 2), (2, 0)]:
        sc = Scene()
        for _ in range(2):
            sc.AddBody(rng.uniform(0.5, 2), np.diag(rng.uniform(0.1, 0.3, 3)), com=rng.normal(size=3) * 0.1,
                       R0=random_rotation(rng), r0=rng.normal(size=3))
        A, B = (GROUND, 1) if ground_side == "A" else ((0, GROUND) if ground_side == "B" else (0, 1))
        sc.AddCoordinateConstraint(A, ax, B, bx, factor=rng.choice([-1, 1]) * rng.uniform(0.5, 2), constant=rng.normal())
        J, eta, Jfd, Jdot_V = finite_differences(sc, group, rng)
        assert J.shape == (1, 12) and np.max(np.abs(J)) > 0.1
        np.testing.assert_allclose(J, Jfd, atol=1e-8, rtol=1e-6)
        np.testing.assert_allclose(-eta, Jdot_V, atol=1e-7, rtol=1e-6)


# ---------------------------------------------------------------------------- Exudyn as the oracle
def coordinate_model(nodes=("RotVecLG", "EP"), factor=1.7, offset=0.05):
    """Two rigid bodies, a 3D and a 2D point mass, a ground node: coordinate constraints
    between position coordinates of all of them."""
    mbs = new_mbs()
    b0 = add_body(mbs, nodes[0], [1, 0, 0], RotationMatrixZ(0.3), gravity=[0, 0, -9.81])
    b1 = add_body(mbs, nodes[1], [1.5, 0.3, 0.1], RotationMatrixX(0.7), omega=(-0.4, 0.6, 0.2), vel=(0.3, -0.1, 0.2))
    n0, n1 = mbs.GetObject(b0)["nodeNumber"], mbs.GetObject(b1)["nodeNumber"]
    np3 = mbs.AddNode(NodePoint(referenceCoordinates=[0.2, 0.4, -0.3], initialVelocities=[0.1, 0.2, 0.3]))
    mbs.AddObject(ObjectMassPoint(mass=1.3, nodeNumber=np3))
    np2 = mbs.AddNode(NodePoint2D(referenceCoordinates=[-0.2, 0.5], initialVelocities=[0.4, -0.3]))
    mbs.AddObject(ObjectMassPoint2D(mass=0.6, nodeNumber=np2))
    ng = mbs.AddNode(NodePointGround(referenceCoordinates=[0.3, 0.1, 0.2]))

    def mc(n, k):
        return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=k))

    for (na, ka), (nb, kb), f, off in [((n0, 0), (n1, 1), factor, offset), ((ng, 0), (n0, 2), 1.0, 0.0),
                                       ((np3, 1), (n1, 0), -0.5, 0.2), ((np2, 1), (np3, 2), 1.0, -0.1),
                                       ((n1, 2), (ng, 0), 1.0, 0.3), ((np2, 0), (n0, 1), 2.0, 0.0)]:
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mc(na, ka), mc(nb, kb)], factor1=f, offset=off))
    mbs.Assemble()
    return mbs


@pytest.mark.parametrize("nodes", [("RotVecLG", "EP"), ("EP", "Rxyz"), ("Rxyz", "RotVecLG")],
                         ids=lambda p: "-".join(p))
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_coordinate_constraints_same_as_exudyn(nodes, group, rng):
    mbs = coordinate_model(nodes)
    for trial in range(2):
        q, qt = random_state(mbs, rng)
        c = compare(mbs, group, q, qt, 0.2 + trial)
        for key in ("M", "f", "g", "J"):
            assert c[key] < TOL, f"{key}: relative deviation {c[key]:.3g} from Exudyn (trial {trial})"
        assert c["nrows"] == 6


def coordinate_forces_model(nodes=("RotVecLG", "EP"), userFunctions=False):
    """Coordinate spring-dampers and coordinate loads (compiled, or with user functions) between
    position coordinates of rigid nodes, point masses and a ground node."""
    from exudyn.utilities import LoadCoordinate, ObjectConnectorCoordinateSpringDamper
    mbs = new_mbs()
    b0 = add_body(mbs, nodes[0], [1, 0, 0], RotationMatrixZ(0.3), gravity=[0, 0, -9.81])
    b1 = add_body(mbs, nodes[1], [1.5, 0.3, 0.1], RotationMatrixX(0.7), omega=(-0.4, 0.6, 0.2), vel=(0.3, -0.1, 0.2))
    n0, n1 = mbs.GetObject(b0)["nodeNumber"], mbs.GetObject(b1)["nodeNumber"]
    np3 = mbs.AddNode(NodePoint(referenceCoordinates=[0.2, 0.4, -0.3], initialVelocities=[0.1, 0.2, 0.3]))
    mbs.AddObject(ObjectMassPoint(mass=1.3, nodeNumber=np3))
    np2 = mbs.AddNode(NodePoint2D(referenceCoordinates=[-0.2, 0.5], initialVelocities=[0.4, -0.3]))
    mbs.AddObject(ObjectMassPoint2D(mass=0.6, nodeNumber=np2))
    ng = mbs.AddNode(NodePointGround(referenceCoordinates=[0.3, 0.1, 0.2]))

    def mc(n, k):
        return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=k))

    def uf_spring(mbs, t, i, u, v, k, d, off):
        return k * (u - off) + 0.3 * u ** 3 + d * v + t

    def uf_load(mbs, t, load):
        return load * (1 + t)

    kw = dict(springForceUserFunction=uf_spring) if userFunctions else {}
    for (na, ka), (nb, kb), k, d, off in [((n0, 0), (n1, 1), 40.0, 0.5, 0.05), ((ng, 0), (n0, 2), 30.0, 0.0, 0.1),
                                          ((np3, 1), (n1, 0), 20.0, 0.3, -0.2), ((np2, 1), (np3, 2), 15.0, 0.2, 0.0),
                                          ((n1, 2), (ng, 0), 25.0, 0.1, 0.3)]:
        mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mc(na, ka), mc(nb, kb)], stiffness=k,
                                                            damping=d, offset=off, **kw))
    kw = dict(loadUserFunction=uf_load) if userFunctions else {}
    for n, kk, load in [(n0, 1, 2.5), (np3, 0, -1.5), (np2, 1, 0.7), (n1, 2, 0.4)]:
        mbs.AddLoad(LoadCoordinate(markerNumber=mc(n, kk), load=load, **kw))
    mbs.Assemble()
    return mbs


@pytest.mark.parametrize("userFunctions", [False, True])
@pytest.mark.parametrize("nodes", [("RotVecLG", "EP"), ("Rxyz", "RotVecLG")], ids=lambda p: "-".join(p))
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_coordinate_springs_and_loads_same_as_exudyn(nodes, group, userFunctions, rng):
    mbs = coordinate_forces_model(nodes, userFunctions)
    for trial in range(2):
        q, qt = random_state(mbs, rng)
        c = compare(mbs, group, q, qt, 0.2 + trial)
        for key in ("M", "f"):
            assert c[key] < TOL, f"{key}: relative deviation {c[key]:.3g} from Exudyn (trial {trial})"


def test_rotation_coordinate_of_a_3d_node_is_constrained():
    """A ConnectorCoordinate on rotation coordinate 1 of a RotVecLG node (Exudyn's coordinate:
    the rotation-vector component, tests/test_node_rotation_coordinates.py) keeps it at its
    initial value through the solve."""
    mbs = new_mbs()
    b0 = add_body(mbs, "RotVecLG", [1, 0, 0], np.eye(3))
    n0 = mbs.GetObject(b0)["nodeNumber"]
    ng = mbs.AddNode(NodePointGround())
    m0 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ng, coordinate=0))
    m1 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n0, coordinate=4))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[m0, m1]))
    mbs.Assemble()
    with pytest.warns(RuntimeWarning, match="projected onto them"):       # omega_y = -0.2 initially
        exl.SolveDynamic(mbs, quiet_settings())
    q = np.array(mbs.systemData.GetODE2Coordinates())
    assert np.abs(q[3:6]).max() > 0.05 and abs(q[4]) < 1e-12


# ---------------------------------------------------------------------------- dynamics vs native
def _final(mbs, h, T, lie):
    ss = quiet_settings(endTime=T, nsteps=int(round(T / h)))
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    if lie:
        exl.SolveDynamic(mbs, ss, method="RK4")
    else:
        exu.SolveDynamic(mbs, ss)
    return np.array(mbs.systemData.GetODE2Coordinates()), np.array(mbs.systemData.GetODE2Coordinates_t())


def consistent_model(node="RotVecLG"):
    """Constraints satisfied initially (positions and velocities): a spinning rigid body whose
    x and z node coordinates are held (ground node), a point mass whose y coordinate is half
    the body's (factor 2), a 2D point mass whose x follows the point's z with an offset;
    springs and gravity drive them."""
    from exudyn.utilities import MarkerNodePosition, ObjectConnectorSpringDamper
    mbs = new_mbs()
    b = add_body(mbs, node, [0, 0, 0], RotationMatrixZ(0.3), omega=(0.5, 1.0, 2.0), vel=(0, 0.4, 0),
                 gravity=[0, -9.81, 0])
    nb = mbs.GetObject(b)["nodeNumber"]
    npt = mbs.AddNode(NodePoint(referenceCoordinates=[0.5, 0.2, 0.1], initialVelocities=[0.3, 0.2, -0.1]))
    mbs.AddObject(ObjectMassPoint(mass=1.3, nodeNumber=npt))
    np2 = mbs.AddNode(NodePoint2D(referenceCoordinates=[-0.4, 0.3], initialVelocities=[-0.1, 0.25]))
    mbs.AddObject(ObjectMassPoint2D(mass=0.6, nodeNumber=np2))
    ng = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))

    def mc(n, k):
        return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=k))

    for (na, ka), (nb_, kb), f, off in [((ng, 0), (nb, 0), 1.0, 0.0), ((nb, 2), (ng, 0), 1.0, 0.0),
                                        ((nb, 1), (npt, 1), 2.0, 0.0), ((npt, 2), (np2, 0), 1.0, 0.0)]:
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mc(na, ka), mc(nb_, kb)], factor1=f, offset=off))
    mp = mbs.AddMarker(MarkerNodePosition(nodeNumber=npt))
    mp2 = mbs.AddMarker(MarkerNodePosition(nodeNumber=np2))
    from exudyn.utilities import MarkerBodyPosition
    mB = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b, localPosition=[0.1, 0.05, -0.1]))
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mB, mp], stiffness=80, damping=0.5, referenceLength=0.3))
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mp, mp2], stiffness=30, damping=0.2, referenceLength=0.6))
    mbs.Assemble()
    return mbs


@pytest.mark.parametrize("node", ["RotVecLG", "EP"])
def test_coordinate_constraints_agree_with_generalized_alpha_at_a_fine_step(node):
    """Native generalized-alpha at h = 2e-5 (the reference) vs exl RK4 at h = 1e-3 over 0.5 s."""
    T = 0.5
    qn, vn = _final(consistent_model(node), 2e-5, T, False)
    ql, vl = _final(consistent_model(node), 1e-3, T, True)
    assert np.max(np.abs(ql - qn)) < 1e-6 * max(1, np.abs(qn).max())
    assert np.max(np.abs(vl - vn)) < 1e-5 * max(1, np.abs(vn).max())
