"""Scenes and Exudyn models of the stress suite (``python -m exudyn_lie stress``).

Kernel scenes (:class:`exudyn_lie.mbs.Scene`):

* :func:`spring_mass` - a point-like body on a zero-length spring: an exactly linear
  isotropic oscillator (the stability test equation ``y' = i omega y``);
* :func:`fast_top` - a heavy top spinning at >= 100 rad/s about its pivot-COM axis;
* :func:`fast_free_body` - the paper's free box (frame off the COM) spinning fast;
* :func:`heavy_top` - the paper's heavy top (spherical joint, spring, gravity);
* :func:`planar_fourbar` - a planar four-bar closed by FOUR revolute joints (redundant);
* :func:`random_mechanism` - seeded random chains / trees with every joint type.

Exudyn models (built with Exudyn's own API, for the bridge): :func:`exudyn_from_spec`
turns a :class:`MechanismSpec` (the data of :func:`random_mechanism`) into an ``mbs``
with ``CreateRigidBody`` + ``MarkerBodyRigid`` + ``ObjectJointGeneric``;
:func:`exudyn_tumbling_body` is a free body on a chosen node type.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import List

import numpy as np

from ..groups import so3
from ..mbs.scene import GROUND, JOINT_TYPES, Scene
from ..models import heavy_top as HT

# the paper's free body (section "Unconstrained Rigid Body"): box 0.8 x 0.4 x 0.1 m
BOX_MASS = 86.4
BOX_THETA = np.diag([1.224, 4.68, 5.76])
BOX_COM = np.array([0.4, 0.0, 0.0])


def _shift_inertia(Jc, m, c):
    """Inertia about a point at -c from the COM (COM at c in the body frame)."""
    c = np.asarray(c, float)
    return Jc + m * (np.dot(c, c) * np.eye(3) - np.outer(c, c))


def spring_mass(stiffness=1e6, mass=1.0, x0=1e-2):
    """Body (frame at the COM) on a zero-length spring to the origin: f = -k x exactly
    linear; released from rest at (x0, 0, 0); omega = sqrt(k/m)."""
    sc = Scene()
    b = sc.AddBody(mass, np.eye(3) * 1e-3 * mass, r0=[x0, 0, 0])
    sc.AddSpringDamper(GROUND, [0, 0, 0], b, [0, 0, 0], stiffness=stiffness, referenceLength=0.0)
    return sc


def fast_top(spin=150.0, tilt=0.3):
    """The paper's heavy top (:func:`exudyn_lie.models.heavy_top.build`) without its
    spring, tilted by ``tilt`` and spinning at ``spin`` rad/s about its pivot-COM axis,
    plus a small transverse rate (body-fixed (spin, 0.4, -0.3)): fast precession and
    nutation under gravity."""
    return HT.scene(spring=False, tilt=tilt, omega0=[spin, 0.4, -0.3])


def fast_free_body(omega0=(120.0, 15.0, 10.0), vcom=(2.0, 0.0, 1.0)):
    """The paper's free box with the frame at one end (COM at (0.4, 0, 0) body), spinning
    fast about (mostly) its minor axis."""
    sc = Scene()
    om = np.array(omega0, float)
    JP = _shift_inertia(BOX_THETA, BOX_MASS, BOX_COM)
    sc.AddBody(BOX_MASS, JP, com=BOX_COM, r0=[0, 0, 0], omega0=om,
               vel0=np.array(vcom, float) - np.cross(om, BOX_COM), name="box")
    return sc


def spinning_box(spin=150.0, speed=2.0):
    """The paper's box with the frame at its COM spinning about its x axis (a principal
    axis) and translating perpendicular to it: omega constant, COM velocity constant; the
    SE3 body-fixed velocity rotates at ``spin`` (v' = -omega x v)."""
    sc = Scene()
    sc.AddBody(BOX_MASS, BOX_THETA, omega0=[spin, 0, 0], vel0=[0, speed, 0], name="box")
    return sc


def heavy_top(spring=True):
    """The paper's heavy top (:func:`exudyn_lie.models.heavy_top.build`): COM at (0.5, 0, 0),
    pivot at the origin, omega0 = (0, 0, 0.5), spring c = 1e4 to (1, 0, 0.5), gravity."""
    return HT.scene(spring=spring)


FOURBAR_POINTS = (np.array([0, 0, 0.]), np.array([0, 0.2, 0]), np.array([0.5, 0.4, 0]),
                  np.array([0.5, 0, 0]))


def planar_fourbar(crank_speed=2 * np.pi, consistent=True, joint4="revolute", gravity=True):
    """Planar four-bar closed by four revolute joints (20 rows, rank 17: 3 redundant);
    ``joint4='spherical'``: 3 revolute + spherical (18 rows, still 1 redundant: the paper's
    choice); ``'universal-spherical'``: revolute, revolute, universal, spherical (17 rows,
    full rank).  Links are slender bars (m = 1 kg) with the frame at their middle.  ``consistent``: initial link velocities
    from the velocity constraints (crank speed given), else only the crank moves."""
    sc = Scene(gravity=[0, -9.81, 0] if gravity else [0, 0, 0])
    P = FOURBAR_POINTS
    # velocities: crank rotates about P0 at w1; coupler, rocker from the loop closure
    w = _fourbar_rates(P, crank_speed) if consistent else (crank_speed, 0.0, 0.0)
    bodies = []
    for k in range(3):
        mid = 0.5 * (P[k] + P[k + 1])
        L = np.linalg.norm(P[k + 1] - P[k])
        om = np.array([0, 0, w[k]])
        if k == 0:
            vel = np.cross(om, mid - P[0])
        elif k == 1:
            vB = np.cross([0, 0, w[0]], P[1] - P[0])
            vel = vB + np.cross(om, mid - P[1])
        else:
            vel = np.cross(om, mid - P[3])
        ang = np.arctan2(*(P[k + 1] - P[k])[[1, 0]])
        R0 = so3.exp(np.array([0, 0, ang]))
        J = np.diag([1e-4, L ** 2 / 12, L ** 2 / 12 + 1e-4])
        bodies.append(sc.AddBody(1.0, J, R0=R0, r0=mid, omega0=R0.T @ om, vel0=vel, name=f"link{k + 1}"))
    sc.AddRevoluteJoint(GROUND, bodies[0], P[0], name="rev1")
    sc.AddRevoluteJoint(bodies[0], bodies[1], P[1], name="rev2")
    if joint4 == "universal-spherical":
        # 5 + 5 + 4 + 3 = 17 rows = 18 - 1 dof: not redundant.  The universal joint keeps the
        # coupler's z axis perpendicular to the rocker's x axis (free relative rotation about z)
        sc.AddUniversalJoint(bodies[1], bodies[2], P[2], axisA=(0, 0, 1), axisB=(1, 0, 0), name="univ3")
    else:
        sc.AddRevoluteJoint(bodies[1], bodies[2], P[2], name="rev3")
    if joint4 == "revolute":
        sc.AddRevoluteJoint(bodies[2], GROUND, P[3], name="rev4")
    else:
        sc.AddSphericalJoint(bodies[2], GROUND, P[3], name="sph4")
    return sc


def _fourbar_rates(P, w1):
    """Planar angular rates (crank, coupler, rocker) from the loop closure."""
    a = P[1] - P[0]
    b = P[2] - P[1]
    c = P[2] - P[3]
    # w1 k x a + w2 k x b = w3 k x c  ->  2 equations for w2, w3
    perp = lambda v: np.array([-v[1], v[0]])
    M = np.column_stack([perp(b)[:2], -perp(c)[:2]])
    rhs = -w1 * perp(a)[:2]
    w2, w3 = np.linalg.solve(M, rhs)
    return w1, w2, w3


# --------------------------------------------------------------------------- random mechanisms
@dataclass
class BodySpec:
    mass: float
    inertia: np.ndarray          # about the body frame origin
    com: np.ndarray
    R0: np.ndarray
    r0: np.ndarray
    omega0: np.ndarray           # body-fixed
    vel0: np.ndarray             # world velocity of the frame origin


@dataclass
class JointSpec:
    kind: str
    bodyA: int
    bodyB: int
    posA: np.ndarray             # joint frame on A (body coords; world for ground)
    rotA: np.ndarray
    posB: np.ndarray
    rotB: np.ndarray


@dataclass
class SpringSpec:
    bodyA: int
    posA: np.ndarray
    bodyB: int
    posB: np.ndarray
    stiffness: float
    referenceLength: float


@dataclass
class MechanismSpec:
    seed: int
    topology: str
    gravity: np.ndarray
    bodies: List[BodySpec] = field(default_factory=list)
    joints: List[JointSpec] = field(default_factory=list)
    springs: List[SpringSpec] = field(default_factory=list)

    def describe(self):
        kinds = ",".join(j.kind for j in self.joints)
        return f"seed {self.seed}: {self.topology}, {len(self.bodies)} bodies, joints [{kinds}]"


def random_rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def random_mechanism(seed, max_bodies=4, kinds=None, spring=True):
    """A seeded random chain or tree: bodies with random mass, box-like inertia (random
    principal axes), COM offset, pose and initial twist; one joint per body to its parent
    (ground or an earlier body) of a random type from ``JOINT_TYPES`` (``kinds``: the
    sequence of types to cycle through in order; default all types in a seed-dependent order); gravity in a
    random direction; optionally an undamped spring.  Joint frames coincide on both sides
    initially (positions consistent); the initial twists are random, hence inconsistent
    with the velocity constraints (project them with ``projectInitial=True``)."""
    rng = np.random.default_rng(10_000 + int(seed))
    nb = int(rng.integers(1, max_bodies + 1))
    topology = "chain" if rng.random() < 0.5 else "tree"
    all_kinds = list(JOINT_TYPES)
    order = [all_kinds[i] for i in rng.permutation(len(all_kinds))] if kinds is None else list(kinds)
    g = rng.normal(size=3)
    spec = MechanismSpec(seed=int(seed), topology=topology, gravity=9.81 * g / np.linalg.norm(g))
    for i in range(nb):
        parent = (i - 1) if topology == "chain" else int(rng.integers(-1, i))
        m = float(rng.uniform(0.5, 5.0))
        sides = rng.uniform(0.05, 0.4, 3)
        Jp = m / 12 * np.array([sides[1] ** 2 + sides[2] ** 2, sides[0] ** 2 + sides[2] ** 2,
                                sides[0] ** 2 + sides[1] ** 2])
        Q = random_rotation(rng)
        Jc = Q @ np.diag(Jp) @ Q.T
        c = rng.uniform(-0.1, 0.1, 3)
        J = _shift_inertia(Jc, m, c)
        J = 0.5 * (J + J.T)
        R0 = random_rotation(rng)
        base = np.zeros(3) if parent == GROUND else spec.bodies[parent].r0
        d = rng.normal(size=3)
        d *= rng.uniform(0.2, 0.5) / np.linalg.norm(d)
        r0 = base + d
        om = rng.normal(size=3) * 2.0
        vel = rng.normal(size=3) * 0.5
        spec.bodies.append(BodySpec(m, J, c, R0, r0, om, vel))
        # joint: world frame at a point between parent and child, random orientation
        pj = base + rng.uniform(0.3, 0.7) * d + rng.normal(size=3) * 0.02
        Rj = random_rotation(rng)
        kind = order[i % len(order)]
        posA, rotA = (pj, Rj) if parent == GROUND else (spec.bodies[parent].R0.T @ (pj - base),
                                                       spec.bodies[parent].R0.T @ Rj)
        posB, rotB = R0.T @ (pj - r0), R0.T @ Rj
        spec.joints.append(JointSpec(kind, parent, i, posA, rotA, posB, rotB))
    if spring:
        i = int(rng.integers(0, nb))
        a = int(rng.integers(-1, nb))
        if a == i:
            a = GROUND
        pa = rng.uniform(-0.3, 0.3, 3) if a == GROUND else rng.uniform(-0.1, 0.1, 3)
        pb = rng.uniform(-0.1, 0.1, 3)
        k = float(rng.uniform(20.0, 200.0)) * spec.bodies[i].mass
        # reference length a bit off the initial length: the spring starts loaded
        pA = pa if a == GROUND else spec.bodies[a].r0 + spec.bodies[a].R0 @ pa
        pB = spec.bodies[i].r0 + spec.bodies[i].R0 @ pb
        L = float(np.linalg.norm(pB - pA))
        spec.springs.append(SpringSpec(a, pa, i, pb, k, L * float(rng.uniform(0.7, 1.3))))
    return spec


def scene_from_spec(spec: MechanismSpec):
    sc = Scene(gravity=spec.gravity)
    for i, b in enumerate(spec.bodies):
        sc.AddBody(b.mass, b.inertia, com=b.com, R0=b.R0, r0=b.r0, omega0=b.omega0, vel0=b.vel0,
                   name=f"body{i}")
    for k, j in enumerate(spec.joints):
        sc.AddJoint(j.bodyA, j.bodyB, JOINT_TYPES[j.kind], posA=j.posA, rotA=j.rotA, posB=j.posB,
                    rotB=j.rotB, kind=j.kind, name=f"joint{k}({j.kind})")
    for s in spec.springs:
        sc.AddSpringDamper(s.bodyA, s.posA, s.bodyB, s.posB, s.stiffness, 0.0, s.referenceLength)
    return sc


def spec_with_state(spec: MechanismSpec, R, r, omega, vel):
    """A copy of ``spec`` whose bodies start at the given state (e.g. after projection)."""
    import copy
    out = copy.deepcopy(spec)
    for i, b in enumerate(out.bodies):
        b.R0, b.r0, b.omega0, b.vel0 = (np.array(x[i], float) for x in (R, r, omega, vel))
    return out


# --------------------------------------------------------------------------- Exudyn models
_KEEP = []


def _new_mbs():
    import exudyn as exu
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    _KEEP.append(SC)              # the container must outlive mbs
    del _KEEP[:-8]
    return mbs


def exudyn_from_spec(spec: MechanismSpec, nodeType=None):
    """The mechanism as an ordinary Exudyn model (assembled): ``CreateRigidBody`` per body
    (gravity as its mass-proportional load), ``ObjectJointGeneric`` with ``MarkerBodyRigid``
    markers carrying the joint frame in ``localHT``, ``ObjectConnectorSpringDamper``.
    Returns ``(mbs, bodyObjects, nodes)``."""
    import exudyn as exu
    from exudyn.itemInterface import (MarkerBodyPosition, MarkerBodyRigid, ObjectConnectorSpringDamper,
                                      ObjectGround, ObjectJointGeneric)
    from exudyn.rigidBodyUtilities import RigidBodyInertia
    nodeType = exu.NodeType.RotationRotationVector if nodeType is None else nodeType
    mbs = _new_mbs()
    ground = mbs.AddObject(ObjectGround(referencePosition=[0, 0, 0]))
    objs, nodes = [], []
    for b in spec.bodies:
        d = mbs.CreateRigidBody(inertia=RigidBodyInertia(b.mass, b.inertia, b.com),
                                referencePosition=list(map(float, b.r0)), referenceRotationMatrix=b.R0,
                                initialVelocity=list(map(float, b.vel0)),
                                initialAngularVelocity=list(map(float, b.R0 @ b.omega0)),
                                gravity=list(map(float, spec.gravity)), nodeType=nodeType, returnDict=True)
        objs.append(d["bodyNumber"])
        nodes.append(d["nodeNumber"])

    def obj(i):
        return ground if i == GROUND else objs[i]

    for j in spec.joints:
        # the joint frame goes into the markers' localHT (Exudyn 1.13: rotationMarker0/1 are deprecated)
        mA = mbs.AddMarker(MarkerBodyRigid(bodyNumber=obj(j.bodyA), localHT=exu.HT(rotation=np.asarray(j.rotA, float),
                                                                                   translation=list(map(float, j.posA)))))
        mB = mbs.AddMarker(MarkerBodyRigid(bodyNumber=obj(j.bodyB), localHT=exu.HT(rotation=np.asarray(j.rotB, float),
                                                                                   translation=list(map(float, j.posB)))))
        mbs.AddObject(ObjectJointGeneric(markerNumbers=[mA, mB], constrainedAxes=list(JOINT_TYPES[j.kind])))
    for s in spec.springs:
        mA = mbs.AddMarker(MarkerBodyPosition(bodyNumber=obj(s.bodyA), localPosition=list(map(float, s.posA))))
        mB = mbs.AddMarker(MarkerBodyPosition(bodyNumber=obj(s.bodyB), localPosition=list(map(float, s.posB))))
        mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mA, mB], stiffness=s.stiffness, damping=0.0,
                                                  referenceLength=s.referenceLength))
    mbs.Assemble()
    return mbs, objs, nodes


def exudyn_tumbling_body(nodeType, omega0=(0.0, 3.0, 0.0), R0=None):
    """A free box (principal axes = body axes, frame at the COM) on the given node type,
    ``omega0`` body-fixed.  With ``omega0`` along y and ``R0 = I`` the orientation is
    ``Ry(3 t)``: the middle Tait-Bryan angle passes +-pi/2 exactly."""
    from exudyn.rigidBodyUtilities import RigidBodyInertia
    mbs = _new_mbs()
    R0 = np.eye(3) if R0 is None else np.asarray(R0, float)
    om = np.asarray(omega0, float)
    d = mbs.CreateRigidBody(inertia=RigidBodyInertia(BOX_MASS, BOX_THETA, np.zeros(3)),
                            referencePosition=[0.0, 0.0, 0.0], referenceRotationMatrix=R0,
                            initialVelocity=[0.1, 0.0, 0.0], initialAngularVelocity=list(R0 @ om),
                            nodeType=nodeType, returnDict=True)
    mbs.Assemble()
    return mbs, d["bodyNumber"], d["nodeNumber"]


def exudyn_node_state(mbs, node):
    """(R, r, omega body, vel world) of a rigid-body node, current configuration."""
    import exudyn as exu
    O = exu.OutputVariableType
    R = np.asarray(mbs.GetNodeOutput(node, O.RotationMatrix), float).reshape(3, 3)
    r = np.asarray(mbs.GetNodeOutput(node, O.Position), float)
    om = np.asarray(mbs.GetNodeOutput(node, O.AngularVelocityLocal), float)
    v = np.asarray(mbs.GetNodeOutput(node, O.Velocity), float)
    return R, r, om, v
