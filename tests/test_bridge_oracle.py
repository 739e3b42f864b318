"""Same dynamics as Exudyn: at random states, the package's mass matrix, forces and
constraint Jacobian equal Exudyn's ``ComputeMassMatrix / ComputeODE2RHS /
ComputeJacobianAE`` (and residuals ``ComputeAlgebraicEquations``) for every supported
node, joint, connector and load type, in both c-space groups.

Exudyn's quantities are transformed into the package's velocity coordinates with the
node maps ``q_t = P V`` (see ``test_bridge_common``): ``P^T M P``, ``P^T (f - M Pdot V)``,
``C P``.  The joint rows coincide one by one (same equations, Exudyn's AE order)."""
import contextlib
import warnings

import numpy as np
import pytest

from exudyn.utilities import (LoadForceVector, LoadMassProportional, LoadTorqueVector, MarkerBodyMass,
                              MarkerBodyPosition, MarkerNodePosition, NodePointGround,
                              ObjectConnectorCartesianSpringDamper, ObjectConnectorSpringDamper, ObjectJointGeneric,
                              ObjectJointPrismaticX, ObjectJointRevoluteZ, ObjectJointSpherical, RotationMatrixX,
                              RotationMatrixY, RotationMatrixZ)

from test_bridge_common import (NODE_TYPES, add_body, compare, new_mbs, oracle, package, position_marker, random_state,
                                rigid_marker)

TOL = 1e-11

RA = RotationMatrixZ(0.3) @ RotationMatrixX(0.4)
RB = RotationMatrixX(0.7) @ RotationMatrixY(-0.2)
RJ = RotationMatrixY(0.5) @ RotationMatrixZ(-0.9)      # a joint frame
RM = RotationMatrixX(-0.6) @ RotationMatrixZ(0.25)     # a marker localHT rotation


def two_bodies(nodeTypes, gravity=True):
    mbs = new_mbs()
    g = mbs.CreateGround(referencePosition=[0.1, 0.2, 0.3], referenceRotationMatrix=RotationMatrixY(0.2))
    b0 = add_body(mbs, nodeTypes[0], [1, 0, 0], RA, gravity=[0, 0, -9.81] if gravity else None)
    b1 = add_body(mbs, nodeTypes[1], [1.5, 0.3, 0.1], RB, omega=(-0.4, 0.6, 0.2), vel=(0.3, -0.1, 0.2),
                  com=(-0.05, 0.03, 0.04), sides=(0.3, 0.2, 0.1))
    return mbs, g, b0, b1


# ---------------------------------------------------------------------------- items
def uf_spring(mbs, t, i, dL, dLt, k, d, f):
    return k * dL + 0.5 * dL ** 3 + d * dLt * (1 + dLt ** 2) + f + t


def uf_cart(mbs, t, i, u, v, k, d, off):
    return [k[j] * u[j] ** 3 + d[j] * v[j] + u[j] + t for j in range(3)]


def uf_torsion(mbs, t, i, rot, omega, k, d, off):
    return k * (rot - off) + 0.3 * rot ** 3 + d * omega + t


def uf_rbsd(mbs, t, i, disp, rot, vel, omega, K, D, J0, J1, off):
    u = np.r_[disp, rot]
    v = np.r_[vel, omega]
    return list(np.asarray(K) @ u + np.asarray(D) @ v + 0.1 * u ** 3 + t)


def uf_load(mbs, t, lv):
    return [lv[0] * (1 + t), lv[1] - t, 2 * lv[2]]


K6 = np.diag([10, 20, 30, 4, 5, 6.]) + 0.5 * np.ones((6, 6))
D6 = np.diag([1, 2, 3, .4, .5, .6]) + 0.1 * np.ones((6, 6))
OFF6 = [0.01, 0.02, 0.03, 0.1, 0.2, 0.3]


@contextlib.contextmanager
def deprecated_rotation_markers():
    """These cases use Exudyn's deprecated rotationMarker0/1 on purpose: Exudyn still reads
    them (until 2031), so the bridge must too.  Only that deprecation is silenced."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r".*rotationMarker[01] is deprecated", category=DeprecationWarning)
        yield


def _generic(mbs, g, b0, b1, axes, node=False, ground=False):
    p = np.array([1.2, 0.1, 0.05]) if not node else body_origin(mbs, b1)
    A = g if ground else b0
    mA, rmA = rigid_marker(mbs, A, p, RJ, markerRot=RM)
    mB, rmB = rigid_marker(mbs, b1, p, RJ, markerRot=RotationMatrixY(0.3), node=node)
    with deprecated_rotation_markers():
        mbs.AddObject(ObjectJointGeneric(markerNumbers=[mA, mB], constrainedAxes=list(axes), rotationMarker0=rmA,
                                         rotationMarker1=rmB))


def body_origin(mbs, b):
    from test_bridge_common import body_frame
    return body_frame(mbs, b)[0]


def _spherical_partial(mbs, g, b0, b1, axes, swap):
    mg = mbs.AddMarker(MarkerBodyPosition(bodyNumber=g, localPosition=[0.3, -0.2, 0.1]))
    # put the ground point at the body point: ground marker defines p
    from test_bridge_common import body_frame
    rg, Rg = body_frame(mbs, g)
    pw = rg + Rg @ np.array([0.3, -0.2, 0.1])
    mb = position_marker(mbs, b0, pw)
    ms = [mb, mg] if swap else [mg, mb]
    mbs.AddObject(ObjectJointSpherical(markerNumbers=ms, constrainedAxes=list(axes)))


def _point_ground(mbs, g, b0, b1):
    n = mbs.AddNode(NodePointGround(referenceCoordinates=[0.7, -0.1, 0.2]))
    mg = mbs.AddMarker(MarkerNodePosition(nodeNumber=n))
    mb = position_marker(mbs, b1, [0.7, -0.1, 0.2])
    mbs.AddObject(ObjectJointSpherical(markerNumbers=[mg, mb]))


def _node_position_markers(mbs, g, b0, b1):
    """MarkerNodePosition on the rigid-body nodes (the node = the body frame origin) in a
    spherical joint, a spring, a Cartesian spring and a force."""
    from test_bridge_common import body_frame
    m0 = position_marker(mbs, b0, None, node=True)
    m1 = position_marker(mbs, b1, None, node=True)
    p0 = body_frame(mbs, b0)[0]
    mg = mbs.AddMarker(MarkerBodyPosition(bodyNumber=g, localPosition=list(
        body_frame(mbs, g)[1].T @ (p0 - body_frame(mbs, g)[0]))))
    mbs.AddObject(ObjectJointSpherical(markerNumbers=[mg, m0]))
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[m0, m1], stiffness=80, damping=0.7,
                                              referenceLength=0.3, force=0.4))
    mbs.AddObject(ObjectConnectorCartesianSpringDamper(markerNumbers=[mg, m1], stiffness=[10, 20, 30],
                                                       damping=[1, 2, 3], offset=[0.1, 0.2, 0.3]))
    mbs.AddLoad(LoadForceVector(markerNumber=m1, loadVector=[0.5, -1, 2]))


def _revolute_rm(mbs, g, b0, b1):
    p = [1.25, 0.15, 0.0]
    mA, rmA = rigid_marker(mbs, b0, p, RJ, markerRot=RM)
    mB, rmB = rigid_marker(mbs, b1, p, RJ @ RotationMatrixZ(0.4), markerRot=RotationMatrixX(0.2))
    with deprecated_rotation_markers():
        mbs.AddObject(ObjectJointRevoluteZ(markerNumbers=[mA, mB], rotationMarker0=rmA, rotationMarker1=rmB))


def _prismatic_rm(mbs, g, b0, b1):
    p = [1.25, 0.15, 0.0]
    mA, rmA = rigid_marker(mbs, g, p, RJ, markerRot=RM)
    mB, rmB = rigid_marker(mbs, b1, [1.35, 0.15, 0.0], RJ, markerRot=RotationMatrixX(0.2))
    # B's frame origin must lie on A's x axis: move it along the A x axis
    with deprecated_rotation_markers():
        mbs.AddObject(ObjectJointPrismaticX(markerNumbers=[mA, mB], rotationMarker0=rmA, rotationMarker1=rmB))


def _torsional(mbs, g, b0, b1, uf):
    p = [1.2, 0.1, 0.0]
    kw = dict(springTorqueUserFunction=uf_torsion) if uf else {}
    mbs.CreateRevoluteJoint(itemNumbers=[b0, b1], position=p, axis=[0, 1, 1])
    mbs.CreateTorsionalSpringDamper(itemNumbers=[b0, b1], position=p, axis=[0, 1, 1], stiffness=7, damping=0.3,
                                    offset=0.1, velocityOffset=0.2, torque=0.05, **kw)


def _rbsd(mbs, g, b0, b1, intrinsic, uf, ground=False):
    kw = dict(springForceTorqueUserFunction=uf_rbsd) if uf else {}
    mbs.CreateRigidBodySpringDamper(itemNumbers=[g if ground else b0, b1], localPosition0=[0.1, 0, 0],
                                    localPosition1=[0, 0.1, 0], stiffness=K6, damping=D6, offset=OFF6,
                                    rotationMatrixJoint=RotationMatrixY(0.4), useIntrinsicFormulation=intrinsic,
                                    **kw)


def _loads(mbs, g, b0, b1, uf):
    kw = dict(loadVectorUserFunction=uf_load) if uf else {}
    m = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b1, localPosition=[0.1, -0.05, 0.02]))
    mr, _ = rigid_marker(mbs, b0, [1.1, 0.0, 0.05], np.eye(3), markerRot=RM)
    mbs.AddLoad(LoadForceVector(markerNumber=m, loadVector=[1, 2, 3], **kw))
    mbs.AddLoad(LoadForceVector(markerNumber=mr, loadVector=[-1, 0.5, 2], bodyFixed=True, **kw))
    mbs.AddLoad(LoadTorqueVector(markerNumber=mr, loadVector=[0.1, 0.2, 0.3], **kw))
    mbs.AddLoad(LoadTorqueVector(markerNumber=mr, loadVector=[0.3, -0.2, 0.1], bodyFixed=True, **kw))
    mm = mbs.AddMarker(MarkerBodyMass(bodyNumber=b1))
    mbs.AddLoad(LoadMassProportional(markerNumber=mm, loadVector=[0.1, -9.81, 0.3], **kw))


ITEMS = {
    "spherical_ground": lambda mbs, g, b0, b1: mbs.CreateSphericalJoint(itemNumbers=[g, b0], position=[0.8, 0, 0]),
    "spherical_bodies": lambda mbs, g, b0, b1: mbs.CreateSphericalJoint(itemNumbers=[b0, b1], position=[1.2, 0.2, 0]),
    "spherical_partial": lambda mbs, g, b0, b1: _spherical_partial(mbs, g, b0, b1, [1, 0, 1], False),
    "spherical_partial_swapped": lambda mbs, g, b0, b1: _spherical_partial(mbs, g, b0, b1, [0, 1, 1], True),
    "spherical_partial_bodies": lambda mbs, g, b0, b1: mbs.AddObject(ObjectJointSpherical(
        markerNumbers=[position_marker(mbs, b0, [1.2, 0.2, 0]), position_marker(mbs, b1, [1.2, 0.2, 0])],
        constrainedAxes=[1, 0, 1])),
    "spherical_pointground_nodemarker": _point_ground,
    "node_position_markers": _node_position_markers,
    "revolute_create": lambda mbs, g, b0, b1: mbs.CreateRevoluteJoint(itemNumbers=[b0, b1], position=[1.2, 0.1, 0],
                                                                      axis=[0, 1, 1]),
    "revolute_ground": lambda mbs, g, b0, b1: mbs.CreateRevoluteJoint(itemNumbers=[g, b1], position=[1.2, 0.1, 0],
                                                                      axis=[1, 0, 0.3]),
    "revolute_rotationMarker": _revolute_rm,
    "prismatic_create": lambda mbs, g, b0, b1: mbs.CreatePrismaticJoint(itemNumbers=[b0, b1], position=[1.3, 0, 0],
                                                                        axis=[1, 1, 0]),
    "prismatic_rotationMarker": _prismatic_rm,
    "generic_111111": lambda mbs, g, b0, b1: _generic(mbs, g, b0, b1, [1, 1, 1, 1, 1, 1]),
    "generic_101011": lambda mbs, g, b0, b1: _generic(mbs, g, b0, b1, [1, 0, 1, 0, 1, 1]),
    "generic_011100": lambda mbs, g, b0, b1: _generic(mbs, g, b0, b1, [0, 1, 1, 1, 0, 0]),
    "generic_111001_ground": lambda mbs, g, b0, b1: _generic(mbs, g, b0, b1, [1, 1, 1, 0, 0, 1], ground=True),
    "generic_110000": lambda mbs, g, b0, b1: _generic(mbs, g, b0, b1, [1, 1, 0, 0, 0, 0]),
    "generic_000111_nodemarker": lambda mbs, g, b0, b1: _generic(mbs, g, b0, b1, [0, 0, 0, 1, 1, 1], node=True),
    "generic_create": lambda mbs, g, b0, b1: mbs.CreateGenericJoint(itemNumbers=[b0, g], position=[1.2, 0, 0],
                                                                    constrainedAxes=[1, 1, 1, 1, 0, 1],
                                                                    rotationMatrixAxes=RotationMatrixX(0.2)),
    "spring": lambda mbs, g, b0, b1: mbs.CreateSpringDamper(itemNumbers=[g, b0], localPosition0=[1, 1, 0],
                                                            localPosition1=[0.1, 0.05, 0], stiffness=100, damping=3,
                                                            force=2, velocityOffset=0.4),
    "spring_bodies_L0": lambda mbs, g, b0, b1: mbs.CreateSpringDamper(itemNumbers=[b0, b1], localPosition0=[0.1, 0, 0],
                                                                      localPosition1=[0, 0.1, 0], stiffness=70,
                                                                      damping=0.5, referenceLength=0.0),
    "spring_userfunction": lambda mbs, g, b0, b1: mbs.CreateSpringDamper(
        itemNumbers=[b0, b1], localPosition0=[0.1, 0, 0], localPosition1=[0, 0.1, 0], stiffness=70, damping=1,
        force=0.3, velocityOffset=0.1, springForceUserFunction=uf_spring),
    "cartesian": lambda mbs, g, b0, b1: mbs.CreateCartesianSpringDamper(
        itemNumbers=[b0, b1], localPosition0=[0.1, 0.2, 0], localPosition1=[0, 0, 0.1], stiffness=[10, 20, 30],
        damping=[1, 2, 3], offset=[0.1, 0.2, 0.3]),
    "cartesian_ground": lambda mbs, g, b0, b1: mbs.CreateCartesianSpringDamper(
        itemNumbers=[g, b1], localPosition0=[0.5, 0.2, 0], localPosition1=[0, 0, 0.1], stiffness=[10, 20, 30],
        damping=[1, 2, 3], offset=[0.1, 0.2, 0.3]),
    "cartesian_userfunction": lambda mbs, g, b0, b1: mbs.CreateCartesianSpringDamper(
        itemNumbers=[b0, b1], localPosition0=[0.1, 0.2, 0], localPosition1=[0, 0, 0.1], stiffness=[10, 20, 30],
        damping=[1, 2, 3], offset=[0.1, 0.2, 0.3], springForceUserFunction=uf_cart),
    "torsional_userfunction": lambda mbs, g, b0, b1: _torsional(mbs, g, b0, b1, True),
    "torsional_no_data_node": lambda mbs, g, b0, b1: (
        mbs.CreateRevoluteJoint(itemNumbers=[b0, b1], position=[1.2, 0.1, 0], axis=[0, 1, 1]),
        mbs.CreateTorsionalSpringDamper(itemNumbers=[b0, b1], position=[1.2, 0.1, 0], axis=[0, 1, 1], stiffness=7,
                                        damping=0.3, offset=0.1, velocityOffset=0.2, torque=0.05,
                                        unlimitedRotations=False)),
    "rbsd_intrinsic": lambda mbs, g, b0, b1: _rbsd(mbs, g, b0, b1, True, False),
    "rbsd_taitbryan": lambda mbs, g, b0, b1: _rbsd(mbs, g, b0, b1, False, False),
    "rbsd_ground_intrinsic": lambda mbs, g, b0, b1: _rbsd(mbs, g, b0, b1, True, False, ground=True),
    "rbsd_userfunction_intrinsic": lambda mbs, g, b0, b1: _rbsd(mbs, g, b0, b1, True, True),
    "rbsd_userfunction_taitbryan": lambda mbs, g, b0, b1: _rbsd(mbs, g, b0, b1, False, True),
    "loads": lambda mbs, g, b0, b1: _loads(mbs, g, b0, b1, False),
    "loads_userfunction": lambda mbs, g, b0, b1: _loads(mbs, g, b0, b1, True),
}

NODE_PAIRS = [("RotVecLG", "EP"), ("EP", "Rxyz"), ("Rxyz", "RotVecLG")]


def _check(mbs, rng, group, t=0.37, tol=TOL, ntrials=2):
    for trial in range(ntrials):
        q, qt = random_state(mbs, rng)
        c = compare(mbs, group, q, qt, t + trial)
        for key in ("M", "f", "g", "J"):
            assert c[key] < tol, f"{key}: relative deviation {c[key]:.3g} from Exudyn (trial {trial})"


@pytest.mark.parametrize("item", sorted(ITEMS))
@pytest.mark.parametrize("nodes", NODE_PAIRS, ids=lambda p: "-".join(p))
def test_same_M_f_jacobian_as_exudyn(item, nodes, rng):
    mbs, g, b0, b1 = two_bodies(nodes)
    ITEMS[item](mbs, g, b0, b1)
    mbs.Assemble()
    _check(mbs, rng, "SE3" if nodes[0] != "EP" else "SO3xR3")


@pytest.mark.parametrize("group", ["SE3", "SO3xR3", "auto"])
@pytest.mark.parametrize("node", sorted(NODE_TYPES))
def test_all_items_together_each_node_type_and_group(group, node, rng):
    """One model with a joint of each kind, springs and loads, per node type and group."""
    mbs, g, b0, b1 = two_bodies((node, node))
    for item in ("spherical_ground", "revolute_create", "spring", "cartesian_userfunction", "rbsd_intrinsic",
                 "loads", "loads_userfunction"):
        ITEMS[item](mbs, g, b0, b1)
    mbs.Assemble()
    _check(mbs, rng, group)


def _torsional_compiled_model(node, turns=0, uf=False):
    """Revolute joint + torsional spring between two bodies; the spring's data
    node holds ``2 pi turns`` (the spring has turned ``turns`` times, e.g. in an earlier
    run: Exudyn's angle is the branch of the principal angle nearest to that value)."""
    mbs, g, b0, b1 = two_bodies((node, "RotVecLG"))
    p = [1.2, 0.1, 0.0]
    kw = dict(springTorqueUserFunction=uf_torsion) if uf else {}
    mbs.CreateRevoluteJoint(itemNumbers=[b0, b1], position=p, axis=[0, 1, 1])
    ts = mbs.CreateTorsionalSpringDamper(itemNumbers=[b0, b1], position=p, axis=[0, 1, 1], stiffness=7, damping=0.3,
                                         offset=0.1, velocityOffset=0.2, torque=0.05, **kw)
    if turns:
        mbs.SetNodeParameter(mbs.GetObject(ts)["nodeNumber"], "initialCoordinates", [2 * np.pi * turns])
    mbs.Assemble()
    return mbs


def _revolute_state(mbs, rng, phi):
    """Random state with body 1 rotated relative to body 0 about the revolute axis by
    phi (the torsional spring's angle), other velocities random."""
    q, qt = random_state(mbs, rng)
    sd = mbs.systemData
    d = [mbs.GetObject(o) for o in range(mbs.systemData.NumberOfObjects())
         if mbs.GetObject(o)["objectType"] == "ConnectorTorsionalSpringDamper"][0]
    m0, m1 = d["markerNumbers"]
    H0 = np.asarray(mbs.GetMarker(m0)["localHT"])[:3, :3]
    H1 = np.asarray(mbs.GetMarker(m1)["localHT"])[:3, :3]
    # body 1 (RotVecLG, node 1) rotation: R1 = R0 H0 Rz(phi) H1^T
    from exudyn_lie.bridge.nodes import NODE_KINDS
    n0 = mbs.GetObject(1)["nodeNumber"]
    n1 = mbs.GetObject(2)["nodeNumber"]
    k0 = NODE_KINDS[mbs.GetNode(n0)["nodeType"]]([n0], [sd.GetNodeLTGODE2(n0)], [mbs.GetNode(n0)["referenceCoordinates"]])
    R0 = k0.read(q, qt)[0][0]
    R1 = R0 @ H0 @ RotationMatrixZ(phi) @ H1.T
    from exudyn_lie.bridge.rotations import matrix_to_rotvec
    i1 = np.asarray(sd.GetNodeLTGODE2(n1))
    q[i1[3:]] = matrix_to_rotvec(R1)[0] - np.asarray(mbs.GetNode(n1)["referenceCoordinates"])[3:]
    return q, qt


def _assert_compiled_torsion(mbs):
    from exudyn_lie.bridge import SceneFromExudyn
    sc = SceneFromExudyn(mbs)
    assert len(sc.torsionalSprings) == 1 and not sc.pyItems      # the compiled spring is tested


@pytest.mark.parametrize("turns", [0, 2])
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("phi", [0.3, -2.0, 3.0])
@pytest.mark.parametrize("node", sorted(NODE_TYPES))
def test_compiled_torsional_spring_about_its_axis(node, phi, group, turns, rng):
    """The compiled torsional spring equals Exudyn's when the relative rotation is about
    the spring axis (its use with a revolute joint), in both groups, also when its data
    node says it has turned twice already (Exudyn's angle then is phi + 4 pi)."""
    mbs = _torsional_compiled_model(node, turns)
    _assert_compiled_torsion(mbs)
    for trial in range(2):
        q, qt = _revolute_state(mbs, rng, phi)
        c = compare(mbs, group, q, qt, 0.2)
        for key in ("M", "f", "g", "J"):
            assert c[key] < TOL, f"{key}: {c[key]:.3g}"


@pytest.mark.parametrize("turns", [0, -1])
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_compiled_torsional_spring_general_rotation(group, turns, rng):
    """Also for relative rotations not about the spring axis (phi = z Tait-Bryan angle)."""
    mbs = _torsional_compiled_model("RotVecLG", turns)
    _assert_compiled_torsion(mbs)
    for trial in range(3):
        q, qt = random_state(mbs, rng, scale=0.6)
        c = compare(mbs, group, q, qt, 0.2)
        for key in ("M", "f", "g", "J"):
            assert c[key] < TOL, f"{key}: {c[key]:.3g}"


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("turns", [3, -2])
@pytest.mark.parametrize("uf", [False, True], ids=["compiled", "userfunction"])
def test_torsional_spring_starts_from_the_turns_in_its_data_node(uf, turns, group, rng):
    """A data node holding 2 pi turns (+ a bit): Exudyn's ComputeODE2RHS uses the angle
    phi + 2 pi turns; so does the package, compiled (turns folded into the offset) and
    with a user function (the Python item tracks from the stored angle)."""
    mbs = _torsional_compiled_model("EP", turns, uf=uf)
    from exudyn_lie.bridge import SceneFromExudyn
    sc = SceneFromExudyn(mbs)
    assert len(sc.torsionData) == 1 and (len(sc.pyItems) == 1) == uf
    for phi in (0.4, -2.5):
        q, qt = _revolute_state(mbs, rng, phi)
        c = compare(mbs, group, q, qt, 0.2)
        for key in ("M", "f", "g", "J"):
            assert c[key] < TOL, f"{key}: {c[key]:.3g}"


def test_torsional_angle_tracking_follows_the_data_node():
    """With Exudyn's NodeGenericData the angle is unwrapped over turns (compiled kernel);
    without it Exudyn uses the principal angle, and so does the bridge (Python item)."""
    from exudyn_lie.bridge import SceneFromExudyn
    from exudyn_lie.mbs.state import BodyStates
    for unlimited in (True, False):
        mbs = new_mbs()
        g = mbs.CreateGround()
        b = add_body(mbs, "RotVecLG", [0, 0, 0], np.eye(3), com=(0, 0, 0))
        mbs.CreateTorsionalSpringDamper(itemNumbers=[g, b], position=[0, 0, 0], axis=[0, 0, 1], stiffness=1,
                                        unlimitedRotations=unlimited)
        mbs.Assemble()
        sc = SceneFromExudyn(mbs)
        if unlimited:
            assert len(sc.torsionalSprings) == 1 and not sc.pyItems
            continue
        item = sc.pyItems[0]
        phis = []
        for a in (2.8, 3.0, 3.3, 3.6):
            st = BodyStates(0.0, RotationMatrixZ(a)[None], np.zeros((1, 3)), np.zeros((1, 3)), np.zeros((1, 3)))
            phis.append(item.angle(st)[0])
        np.testing.assert_allclose(phis, [2.8, 3.0, 3.3 - 2 * np.pi, 3.6 - 2 * np.pi], atol=1e-12)


# ---------------------------------------------------------------------------- gravity
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("nodes", NODE_PAIRS, ids=lambda p: "-".join(p))
def test_uniform_mass_proportional_load_becomes_scene_gravity(nodes, group, rng):
    """The same LoadMassProportional on every body (CreateRigidBody(gravity=...)) is read
    as the scene's gravity (kernel gravity forces at the COMs, in the energy too), not as
    per-body forces: f equals Exudyn's."""
    from exudyn_lie.bridge import SceneFromExudyn
    gv = [0.3, -9.81, 1.2]
    mbs = new_mbs()
    g = mbs.CreateGround()
    b0 = add_body(mbs, nodes[0], [1, 0, 0], RA, gravity=gv)
    b1 = add_body(mbs, nodes[1], [1.5, 0.3, 0.1], RB, omega=(-0.4, 0.6, 0.2), vel=(0.3, -0.1, 0.2),
                  com=(-0.05, 0.03, 0.04), sides=(0.3, 0.2, 0.1), gravity=gv)
    mbs.CreateSpringDamper(itemNumbers=[g, b1], localPosition0=[1, 1, 0], stiffness=50, damping=0.5)
    mbs.Assemble()
    assert [mbs.GetLoad(l)["loadType"] for l in range(mbs.systemData.NumberOfLoads())] == ["MassProportional"] * 2
    sc = SceneFromExudyn(mbs)
    np.testing.assert_array_equal(sc.gravity, gv)
    assert not sc.loads and not sc.pyItems
    _check(mbs, rng, group)


# ---------------------------------------------------------------------------- partial spherical joints
def _spherical_bodies(nodes, axes):
    mbs, g, b0, b1 = two_bodies(nodes)
    p = [1.2, 0.2, 0.0]
    j = mbs.AddObject(ObjectJointSpherical(markerNumbers=[position_marker(mbs, b0, p), position_marker(mbs, b1, p)],
                                           constrainedAxes=list(axes)))
    mbs.Assemble()
    return mbs, j


@pytest.mark.parametrize("axes", [[1, 0, 1], [0, 1, 0], [1, 1, 0]])
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_partial_spherical_between_bodies_is_world_axis_rows(axes, group, rng):
    """Exudyn's spherical joint with partial ``constrainedAxes`` between two bodies
    (CObjectJointSpherical): rows (p1 - p0)_i in *world* components for the locked axes
    i, AE rows ``lambda_i = 0`` for the others.  The bridge reads it as a scene joint
    with ``worldTranslation=True``: one world-axis row (ROW_TRANS_WORLD) per locked
    axis, equal to Exudyn's rows and Jacobian at random states."""
    nodes = ("RotVecLG", "EP")
    mbs, j = _spherical_bodies(nodes, axes)
    ae = np.asarray(mbs.systemData.GetObjectLTGAE(j))
    locked = [i for i in range(3) if axes[i]]
    free = [i for i in range(3) if not axes[i]]
    for trial in range(2):
        q, qt = random_state(mbs, rng)
        Me, fe, ge, Ce = oracle(mbs, q, qt, 0.3)
        pk = package(mbs, group, q, qt, 0.3)
        ji = pk["scene"].joints_info[0]
        r0, n = (int(x) for x in pk["sim"].sd.jointIndex[ji.sceneJoint, 2:4])
        assert n == len(locked) and list(pk["sim"].sd.rowIndex[r0:r0 + n, 0]) == [1] * n    # kernel.ROW_TRANS_WORLD
        h, J = pk["h"][r0:r0 + n], pk["J"][r0:r0 + n]
        scale = max(1.0, np.max(np.abs(J)))
        np.testing.assert_allclose(ge[ae[locked]], h, rtol=0, atol=1e-13)
        np.testing.assert_allclose(Ce[ae[locked]] @ pk["P"], J, rtol=0, atol=1e-12 * scale)
        assert np.all(Ce[ae[free]] == 0)                  # the free axes' rows only hold lambda_i = 0


@pytest.mark.parametrize("item", ["rbsd_intrinsic", "rbsd_taitbryan", "rbsd_ground_intrinsic",
                                  "rbsd_userfunction_intrinsic"])
def test_rigid_body_spring_damper_compiled_unless_user_function(item, rng):
    """Without a user function the RigidBodySpringDamper is a compiled scene item (no Python
    force; the oracle comparisons above then check the compiled law), with one a Python item;
    both agree with Exudyn at random states, also with the tilted joint frame about y."""
    from exudyn_lie.bridge import SceneFromExudyn
    mbs, g, b0, b1 = two_bodies(("RotVecLG", "RotVecLG"))
    ITEMS[item](mbs, g, b0, b1)
    mbs.Assemble()
    sc = SceneFromExudyn(mbs)
    uf = "userfunction" in item
    assert len(sc.rigidSprings) == (0 if uf else 1)
    assert bool(sc.pythonForces) == uf
    _check(mbs, rng, "SE3", ntrials=4)
