"""Same dynamics as Exudyn: at random states, the package's mass matrix, forces and
constraint Jacobian equal Exudyn's ``ComputeMassMatrix / ComputeODE2RHS /
ComputeJacobianAE`` (and residuals ``ComputeAlgebraicEquations``) for every supported
node, joint, connector and load type, in both c-space groups.

Exudyn's quantities are transformed into the package's velocity coordinates with the
node maps ``q_t = P V`` (see ``test_bridge_common``): ``P^T M P``, ``P^T (f - M Pdot V)``,
``C P``.  The joint rows coincide one by one (same equations, Exudyn's AE order)."""
import numpy as np
import pytest

from exudyn.utilities import (LoadForceVector, LoadMassProportional, LoadTorqueVector, MarkerBodyMass,
                              MarkerBodyPosition, MarkerNodePosition, NodePointGround, ObjectJointGeneric,
                              ObjectJointPrismaticX, ObjectJointRevoluteZ, ObjectJointSpherical, RotationMatrixX,
                              RotationMatrixY, RotationMatrixZ)

from test_bridge_common import (NODE_TYPES, add_body, compare, new_mbs, position_marker, random_state,
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


def _generic(mbs, g, b0, b1, axes, node=False, ground=False):
    p = np.array([1.2, 0.1, 0.05]) if not node else body_origin(mbs, b1)
    A = g if ground else b0
    mA, rmA = rigid_marker(mbs, A, p, RJ, markerRot=RM)
    mB, rmB = rigid_marker(mbs, b1, p, RJ, markerRot=RotationMatrixY(0.3), node=node)
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


def _revolute_rm(mbs, g, b0, b1):
    p = [1.25, 0.15, 0.0]
    mA, rmA = rigid_marker(mbs, b0, p, RJ, markerRot=RM)
    mB, rmB = rigid_marker(mbs, b1, p, RJ @ RotationMatrixZ(0.4), markerRot=RotationMatrixX(0.2))
    mbs.AddObject(ObjectJointRevoluteZ(markerNumbers=[mA, mB], rotationMarker0=rmA, rotationMarker1=rmB))


def _prismatic_rm(mbs, g, b0, b1):
    p = [1.25, 0.15, 0.0]
    mA, rmA = rigid_marker(mbs, g, p, RJ, markerRot=RM)
    mB, rmB = rigid_marker(mbs, b1, [1.35, 0.15, 0.0], RJ, markerRot=RotationMatrixX(0.2))
    # B's frame origin must lie on A's x axis: move it along the A x axis
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
    "spherical_pointground_nodemarker": _point_ground,
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


def _torsional_compiled_model(node):
    mbs, g, b0, b1 = two_bodies((node, "RotVecLG"))
    p = [1.2, 0.1, 0.0]
    mbs.CreateRevoluteJoint(itemNumbers=[b0, b1], position=p, axis=[0, 1, 1])
    mbs.CreateTorsionalSpringDamper(itemNumbers=[b0, b1], position=p, axis=[0, 1, 1], stiffness=7, damping=0.3,
                                    offset=0.1, velocityOffset=0.2, torque=0.05)
    mbs.Assemble()
    return mbs


def _revolute_state(mbs, rng, phi):
    """Random state with body 1 rotated relative to body 0 about the revolute axis by
    phi (the torsional spring's angle), other velocities random."""
    q, qt = random_state(mbs, rng)
    sd = mbs.systemData
    d = mbs.GetObject(3)          # the torsional spring (object 3)
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


@pytest.mark.parametrize("phi", [0.3, -2.0, 3.0])
@pytest.mark.parametrize("node", sorted(NODE_TYPES))
def test_compiled_torsional_spring_about_its_axis(node, phi, rng):
    """The compiled torsional spring equals Exudyn's when the relative rotation is about
    the spring axis (its use with a revolute joint)."""
    from test_bridge_common import compare
    mbs = _torsional_compiled_model(node)
    for trial in range(2):
        q, qt = _revolute_state(mbs, rng, phi)
        c = compare(mbs, "SE3", q, qt, 0.2)
        for key in ("M", "f", "g", "J"):
            assert c[key] < TOL, f"{key}: {c[key]:.3g}"


def test_compiled_torsional_spring_general_rotation(rng):
    """Also for relative rotations not about the spring axis (phi = z Tait-Bryan angle)."""
    mbs = _torsional_compiled_model("RotVecLG")
    for trial in range(3):
        q, qt = random_state(mbs, rng, scale=0.6)
        c = compare(mbs, "SE3", q, qt, 0.2)
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
