"""The items of a :class:`~.scene.Scene`: bodies, joints, the compiled force elements (each
with ``validate()``, which re-checks its mutable fields, and ``switch_off()``, which leaves it
without force), coordinates of the coordinate items, loads and Python forces, with the checks
of their data."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np


GROUND = -1

# the six relative axes of a generic joint: translations x, y, z, rotations x, y, z
JOINT_TYPES = {
    "spherical": (1, 1, 1, 0, 0, 0),
    "revolute": (1, 1, 1, 1, 1, 0),      # rotation about the joint frame's z axis
    "prismatic": (0, 1, 1, 1, 1, 1),     # translation along the joint frame's x axis
    "cylindrical": (1, 1, 0, 1, 1, 0),   # rotation about and translation along z
    "universal": (1, 1, 1, 0, 0, 1),     # Cardan: free rotations about x (frame 0) and y (frame 1)
    "fixed": (1, 1, 1, 1, 1, 1),
    "planar": (0, 0, 1, 1, 1, 0),        # motion in the joint frame's x-y plane
}


class SceneError(ValueError):
    """Raised for an inconsistent or unsupported scene description."""


def _vec3(x, what):
    a = np.asarray(x, dtype=float).reshape(-1)
    if a.shape != (3,):
        raise SceneError(f"{what} must be a 3-vector, got shape {np.shape(x)}")
    if not np.isfinite(a).all():
        raise SceneError(f"{what} is not finite: {a}")
    return a.copy()


def _rot(x, what):
    if x is None:
        return np.eye(3)
    a = np.asarray(x, dtype=float)
    if a.shape != (3, 3):
        raise SceneError(f"{what} must be a 3x3 rotation matrix, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise SceneError(f"{what} is not finite")
    E = a.T @ a - _I3
    # |R^T R - I|_F > 1e-8, and the determinant's sign by the triple product (a bridge re-reads
    # an item during a solve with these checks: np.linalg.norm and det cost 13 us of a re-read)
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = a.tolist()
    det = a00 * (a11 * a22 - a12 * a21) - a01 * (a10 * a22 - a12 * a20) + a02 * (a10 * a21 - a11 * a20)
    if float((E * E).sum()) > 1e-16 or det < 0:
        raise SceneError(f"{what} is not a proper rotation matrix (R^T R != I or det < 0)")
    return a.copy()


_I3 = np.eye(3)


@dataclass
class Body:
    mass: float
    inertia: np.ndarray          # 3x3, about the body frame origin, body coordinates
    com: np.ndarray              # centre of mass in body coordinates
    R0: np.ndarray               # initial rotation (body -> world)
    r0: np.ndarray               # initial position of the body frame origin (world)
    omega0: np.ndarray           # initial angular velocity, body-fixed
    vel0: np.ndarray             # initial velocity of the body frame origin, world frame
    name: str = ""
    # a point mass (group R3, groups/rn.py): the projector (3x3, world) onto the directions it
    # moves in (I in space, diag(1, 1, 0) in the x-y plane, e e^T along an axis e); None: rigid
    freeDirections: np.ndarray = None
    planar: bool = False         # a 2D body: 3 DOF in the x-y plane (AddBody2D)
    angle0: float = 0.0          # a 2D body / rotor: its initial angle, turns included (SceneData.bodyAngles tracks it)
    # a rotor (AddRotor): turns about the z axis of the world frame ``angleFrame`` through r0 only
    # (velocity axes ``freeAxes`` of (omega body, v)); None: all axes
    freeAxes: tuple = None
    angleFrame: np.ndarray = None
    # rotation parameters of the body tracked step by step for the write-back
    # (rotation_parameters: TRACK_QUAT / TRACK_TAIT_BRYAN, initial parameters (4)); None: not tracked
    track: tuple = None

    @property
    def isPoint(self):
        return self.freeDirections is not None


@dataclass
class Joint:
    bodyA: int
    bodyB: int
    posA: np.ndarray             # joint frame origin on A (body coordinates; world if A is ground)
    rotA: np.ndarray             # joint frame orientation on A
    posB: np.ndarray
    rotB: np.ndarray
    constrainedAxes: tuple       # (tx, ty, tz, rx, ry, rz) in {0, 1}
    kind: str = "generic"
    name: str = ""
    worldTranslation: bool = False   # translation rows along world axes (a spherical joint's)
    # kind 'coordinate' (a coordinate constraint): (d_A, d_B, f, c, rotation A, rotation B,
    # angle0 A, angle0 B), h = f q_B - q_A - c with q_X = d_X . p_X (position coordinate along the
    # world direction d_X) or the angle of X about the z axis of the frame rotX (rotation coordinate,
    # d_X = rotX e_z, tracked over turns from angle0 X; mbs/coordinate_angles.py)
    coordinate: tuple = None
    distance: float = None           # kind 'distance' (a distance constraint): h = |p_B - p_A| - distance
    # kind 'rollingDisc' (a rolling-disc constraint, velocity-level rows, mbs/rolling_disc_rows.py):
    # (discRadius, planeNormal in A's joint frame rotA, discAxis in B's joint frame rotB)
    rollingDisc: tuple = None
    # a coordinate constraint's time dependence (mbs/row_drives.py): velocity level (``velocityLevel``:
    # f qdot_B - qdot_A = c + offset(t), no position-level row) and the moving part ``offset(t)`` of
    # the right-hand side (a Python callable of t; None: constant)
    velocityLevel: bool = False
    offset: object = None


@dataclass
class SpringDamper:
    """Point-to-point spring-damper: tension ``k (L - L0) + d Ldot + f0`` along the line."""
    bodyA: int
    posA: np.ndarray
    bodyB: int
    posB: np.ndarray
    stiffness: float
    damping: float
    referenceLength: float
    force: float = 0.0
    name: str = ""

    def validate(self):
        _finite_fields(self, ("stiffness", "damping", "referenceLength", "force"))

    def switch_off(self):
        self.stiffness, self.damping, self.force = self.stiffness * 0.0, self.damping * 0.0, 0.0


@dataclass
class TorsionalSpringDamper:
    """Torsional spring-damper: ``tau = k (phi - offset) + d phidot + torque`` about the z
    axis of the frame on A; ``-tau z_A`` acts on B, ``+tau z_A`` on A.  ``phi`` is the
    third Tait-Bryan angle of the relative rotation, tracked over turns."""
    bodyA: int
    rotA: np.ndarray
    bodyB: int
    rotB: np.ndarray
    stiffness: float
    damping: float
    offset: float = 0.0
    torque: float = 0.0
    name: str = ""

    def validate(self):
        _finite_fields(self, ("stiffness", "damping", "offset", "torque"))

    def switch_off(self):
        self.stiffness, self.damping, self.torque = self.stiffness * 0.0, self.damping * 0.0, 0.0


@dataclass
class CartesianSpringDamper:
    """Componentwise spring in world coordinates: ``f_i = k_i (d_i - o_i) + c_i ddot_i``."""
    bodyA: int
    posA: np.ndarray
    bodyB: int
    posB: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    offset: np.ndarray
    name: str = ""

    def validate(self):
        for what in ("stiffness", "damping", "offset"):
            _vec3(getattr(self, what), f"{self.name}: {what}")

    def switch_off(self):
        self.stiffness, self.damping = self.stiffness * 0.0, self.damping * 0.0


@dataclass
class CoordinateSpringDamper:
    """A coordinate spring-damper on position coordinates of the body frame origins along
    world directions: ``f = k (d_B . p_B - d_A . p_A - offset) + d (rates)``,
    ``+f`` on A's coordinate, ``-f`` on B's (mbs/coordinate_forces.py)."""
    bodyA: int
    axisA: np.ndarray            # world direction d_A of A's coordinate (e_k: world axis k)
    bodyB: int
    axisB: np.ndarray
    stiffness: float
    damping: float
    offset: float = 0.0
    name: str = ""
    # rotation coordinates: per side (end code, frame F, angle0): code 1 an AngleCoordinate
    # (d = F e_z), >= 10 a RotationParameterCoordinate (node_coordinates.param_code; d = 0)
    angleA: tuple = (False, np.eye(3), 0.0)
    angleB: tuple = (False, np.eye(3), 0.0)
    force: float = 0.0           # a constant f0 added to f (AddCoordinateLoad)

    def validate(self):
        _finite_fields(self, ("stiffness", "damping", "offset"))

    def switch_off(self):
        self.stiffness, self.damping = self.stiffness * 0.0, self.damping * 0.0


@dataclass(frozen=True)
class AngleCoordinate:
    """A rotation coordinate for the coordinate items (``axis`` argument of
    :meth:`Scene.AddCoordinateConstraint` / :meth:`Scene.AddCoordinateSpringDamper`): the angle
    ``phi`` of the body about the z axis of the world frame ``frame`` (``R = frame Rz(phi)`` for a
    body turning about that axis, e.g. a 2D body with ``frame = I``), continued over turns from
    ``angle0``, the angle at the initial state.  Its rate is ``(frame e_z) . omega_world``."""
    frame: object = None
    angle0: float = 0.0


@dataclass(frozen=True)
class RotationParameterCoordinate:
    """A rotation coordinate of a 3D rigid body for the coordinate items (``axis`` argument
    of :meth:`Scene.AddCoordinateConstraint` / :meth:`Scene.AddCoordinateSpringDamper`):
    rotation parameter ``index`` (0-based) of the body's orientation in the parametrisation
    ``kind``: ``'rotationVector'`` (velocity coordinates: the local omega), ``'eulerParameters'``
    or ``'taitBryanXYZ'`` (velocity coordinates: the parameters' rates; mbs/node_coordinates.py).
    The value is taken on the branch tracked from the body's ``track`` (set from ``R0`` if
    the body has none)."""
    kind: str
    index: int


@dataclass
class LinearSpringDamper:
    """A linear spring-damper along the world axis ``a = R_A axisA``,
    ``f = k (a . (p_B - p_A) - offset) + d a . (pdot_B - pdot_A) + force``; ``+f a`` at the
    point on A, ``-f a`` at the point on B (mbs/linear_spring_forces.py)."""
    bodyA: int
    posA: np.ndarray
    axisA: np.ndarray            # unit axis in A's body frame (world if A is GROUND)
    bodyB: int
    posB: np.ndarray
    stiffness: float
    damping: float
    offset: float = 0.0
    force: float = 0.0
    name: str = ""

    def validate(self):
        _vec3(self.axisA, f"{self.name}: axisA")
        _finite_fields(self, ("stiffness", "damping", "offset", "force"))

    def switch_off(self):
        self.stiffness, self.damping, self.force = self.stiffness * 0.0, self.damping * 0.0, 0.0


@dataclass
class RigidBodySpringDamper:
    """6-dof spring-damper between two frames: ``(f, m) = K u + D udot`` in the frame on A
    (Tait-Bryan form) or in the mid frame (``intrinsic``); the exact law is
    :func:`exudyn_lie.mbs.forces.rigid_spring_forces`."""
    bodyA: int
    posA: np.ndarray
    rotA: np.ndarray
    bodyB: int
    posB: np.ndarray
    rotB: np.ndarray
    stiffness: np.ndarray        # 6x6
    damping: np.ndarray          # 6x6
    offset: np.ndarray           # 6
    name: str = ""
    intrinsic: bool = False      # the law in the mid frame (intrinsic formulation)

    def validate(self):
        if not all(np.all(np.isfinite(np.asarray(getattr(self, what), float))) and np.size(getattr(self, what)) == n
                   for what, n in (("stiffness", 36), ("damping", 36), ("offset", 6))):
            raise SceneError(f"{self.name}: stiffness (6x6), damping (6x6) and offset (6) must be finite")

    def switch_off(self):
        self.stiffness, self.damping = self.stiffness * 0.0, self.damping * 0.0


@dataclass
class RollingDiscPenalty:
    """A penalty rolling disc: a disc (body B, centre ``posB``, axis
    ``axisB`` in B's coordinates) on the plane of body A or GROUND (through ``posA``, normal
    ``normalA`` in A's coordinates, world for GROUND), penalty contact and regularised friction;
    ``data0`` the initial data coordinates (slip velocity, gap), updated after each accepted
    step (mbs/rolling_disc_penalty_forces.py has the law)."""
    bodyA: int
    posA: np.ndarray
    normalA: np.ndarray
    bodyB: int
    posB: np.ndarray
    axisB: np.ndarray
    discRadius: float
    contactStiffness: float
    contactDamping: float
    dryFriction: np.ndarray                 # (mu_x, mu_y)
    dryFrictionProportionalZone: float
    viscousFriction: np.ndarray             # (d_x, d_y)
    dryFrictionAngle: float = 0.0
    rollingViscousFriction: float = 0.0
    useLinearProportionalZone: bool = False
    active: bool = True
    data0: np.ndarray = None                # (x0, x1, x2); None: zeros
    name: str = ""

    def validate(self):
        _check_rolling_disc_penalty(self)

    def switch_off(self):
        self.active = False             # no force; an inactive disc keeps its data


@dataclass
class Load:
    """Constant force (``kind='force'``, applied at ``pos``) or torque on one body;
    ``bodyFixed`` means the vector is given in body coordinates."""
    body: int
    kind: str
    vector: np.ndarray
    pos: np.ndarray
    bodyFixed: bool = False
    name: str = ""


@dataclass
class PythonForce:
    """A Python callback adding forces: ``fn(t, state) -> (F, T)`` with ``F`` and ``T``
    arrays (nBodies, 3) of world-frame forces at the body frame origins and world-frame
    torques.  ``state`` is a :class:`exudyn_lie.mbs.state.BodyStates`.  Callbacks run
    outside the compiled kernel, so a scene that has one integrates more slowly."""
    fn: Callable
    name: str = ""


def _finite_fields(item, names):
    """Check that the fields ``names`` of a force element's item are finite numbers."""
    for what in names:
        _finite(getattr(item, what), f"{item.name}: {what}")


def _check_rolling_disc_penalty(e):
    """Validate (in place, as floats / arrays) the parameters of a RollingDiscPenalty."""
    label = e.name
    for what in ("discRadius", "contactStiffness", "contactDamping", "dryFrictionProportionalZone",
                 "dryFrictionAngle", "rollingViscousFriction"):
        setattr(e, what, _finite(getattr(e, what), f"{label}: {what}"))
    for what in ("dryFriction", "viscousFriction"):
        v = np.asarray(getattr(e, what), float).reshape(-1)
        if v.shape != (2,) or not np.all(np.isfinite(v)):
            raise SceneError(f"{label}: {what} must be 2 finite numbers, got {getattr(e, what)!r}")
        setattr(e, what, v.copy())
    d = np.zeros(3) if e.data0 is None else np.asarray(e.data0, float).reshape(-1)
    if d.shape != (3,) or not np.all(np.isfinite(d)):
        raise SceneError(f"{label}: data0 (the data coordinates: slip velocity (2), gap) must be 3 finite numbers, "
                         f"got {e.data0!r}")
    e.data0 = d.copy()


def _checked_mass_properties(label, mass, inertia, com):
    """Validated (mass, 3x3 inertia about the frame origin, com)."""
    try:
        m = float(mass)
    except (TypeError, ValueError):
        raise SceneError(f"{label}: mass must be a number, got {mass!r}") from None
    if not np.isfinite(m) or m <= 0:
        raise SceneError(f"{label}: mass must be positive and finite, got {mass}")
    J = np.asarray(inertia, dtype=float)
    if J.shape == (3,):
        J = np.diag(J)
    if J.shape != (3, 3) or not np.all(np.isfinite(J)):
        raise SceneError(f"{label}: inertia must be a finite 3x3 matrix (or its diagonal)")
    if np.linalg.norm(J - J.T) > 1e-12 * max(1.0, np.abs(J).max()):
        raise SceneError(f"{label}: inertia tensor is not symmetric")
    c = _vec3(com, f"{label}: com")
    # about the COM the tensor must be positive definite (Steiner back-shift)
    Jc = J - m * (np.dot(c, c) * np.eye(3) - np.outer(c, c))
    ev = np.linalg.eigvalsh(Jc)
    if ev.min() <= 1e-14 * max(1.0, ev.max()):
        raise SceneError(f"{label}: inertia about the centre of mass is not positive "
                         f"definite (eigenvalues {ev}); give the inertia about the body "
                         f"frame origin, consistent with mass and com")
    return m, J, c


def _checked_point_mass(label, mass):
    try:
        m = float(mass)
    except (TypeError, ValueError):
        raise SceneError(f"{label}: mass must be a number, got {mass!r}") from None
    if not np.isfinite(m) or m <= 0:
        raise SceneError(f"{label}: mass must be positive and finite, got {mass}")
    return m


def _coordinate_direction(axis, label):
    """World direction of a position coordinate: ``e_axis`` for an index 0, 1, 2, else the
    given nonzero 3-vector (used as it is)."""
    if isinstance(axis, (int, np.integer)):
        if axis not in (0, 1, 2):
            raise SceneError(f"{label}: position coordinate index must be 0, 1 or 2, got {axis}")
        return np.eye(3)[int(axis)]
    d = _vec3(axis, f"{label}: coordinate direction")
    if not np.any(d):
        raise SceneError(f"{label}: coordinate direction is zero")
    return d


def _projector(P, what):
    P = np.asarray(P, float)
    if P.shape != (3, 3) or not np.all(np.isfinite(P)) or np.abs(P @ P - P).max() > 1e-12 \
            or np.abs(P - P.T).max() > 1e-14 or np.trace(P) < 0.5:
        raise SceneError(f"{what} must be a nonzero orthogonal projector (3x3, P = P^T = P P)")
    return P.copy()


def _finite(x, what):
    try:
        v = float(x)
    except (TypeError, ValueError):
        raise SceneError(f"{what} must be a number, got {x!r}") from None
    if not np.isfinite(v):
        raise SceneError(f"{what} is not finite: {x}")
    return v


def frame_with_axis(axis, which):
    """A rotation matrix whose column ``which`` is the unit ``axis`` (others completed)."""
    a = np.asarray(axis, dtype=float).reshape(3)
    n = np.linalg.norm(a)
    if not np.isfinite(n) or n < 1e-14:
        raise SceneError(f"axis {axis} must be a nonzero finite 3-vector")
    a = a / n
    if abs(a[which] - 1.0) < 1e-15:      # already the world axis: keep the identity frame
        return np.eye(3)
    # pick the world axis least aligned with a to complete a right-handed frame
    helper = np.eye(3)[int(np.argmin(np.abs(a)))]
    b = np.cross(a, helper)
    b /= np.linalg.norm(b)
    c = np.cross(a, b)
    cols = [None, None, None]
    cols[which] = a
    cols[(which + 1) % 3] = b
    cols[(which + 2) % 3] = c
    return np.column_stack(cols)
