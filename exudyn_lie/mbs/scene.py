"""The multibody scene: bodies, joints and forces, described in plain Python.

A :class:`Scene` is what the user (or the bridge) builds.  It knows nothing of
time integration; :func:`exudyn_lie.mbs.compiled.compile_scene` turns it into the flat
arrays the numba kernel works on.

Conventions (see ``exudyn_lie/groups``):
* every body has a body-fixed reference frame ``C = (R, r)``; ``R`` maps body to world;
* inertia is given about the body frame origin (eq. NE1 with ``J_P``), the centre of
  mass may sit at ``com`` (body coordinates) away from that origin;
* twists are ``(omega, v)``, rotation first.  ``omega`` is always body-fixed; ``v`` is
  body-fixed for SE3 bodies and spatial (``rdot``) for SO3xR3 bodies (mixed velocity);
* a joint locks any subset of the six relative axes of its joint frame, one row per locked
  axis (:mod:`.constraints`), so that its constraint Jacobian can be compared row by row with
  that of the modelling system the bridge reads.

The dataclass of every compiled force element (the lists of the registrations in
``mbs/force_elements.py``) has ``validate()``, which re-checks its mutable fields
(:meth:`Scene.validate` calls it for every item of every registered element), and
``switch_off()``, which leaves it without force (an inactive connector, e.g. one the bridge
reads as switched off).
"""
from __future__ import annotations

from typing import List, Sequence

import numpy as np

from .force_elements import ELEMENTS
from .scene_items import (AngleCoordinate, Body, CartesianSpringDamper, CoordinateSpringDamper, GROUND,
                          JOINT_TYPES, Joint, LinearSpringDamper, Load, RotationParameterCoordinate, PythonForce,
                          RigidBodySpringDamper, RollingDiscPenalty, SceneError, SpringDamper,
                          TorsionalSpringDamper, _check_rolling_disc_penalty, _checked_mass_properties,
                          _checked_point_mass, _coordinate_direction, _finite, _projector, _rot, _vec3,
                          frame_with_axis)  # noqa: F401 (items re-exported)


class Scene:
    """A rigid multibody system in absolute coordinates (paper eq. BH2/index1).

    Example
    -------
    >>> sc = Scene(gravity=[0, 0, -9.81])
    >>> b = sc.AddBody(mass=1.0, inertia=np.eye(3) * 0.01, r0=[0.5, 0, 0])
    >>> j = sc.AddSphericalJoint(GROUND, b, position=[0, 0, 0])
    """

    def __init__(self, gravity: Sequence[float] = (0.0, 0.0, 0.0)):
        self.gravity = _vec3(gravity, "gravity")
        self.bodies: List[Body] = []
        self.joints: List[Joint] = []
        self.springs: List[SpringDamper] = []
        self.torsionalSprings: List[TorsionalSpringDamper] = []
        self.cartesianSprings: List[CartesianSpringDamper] = []
        self.rigidSprings: List[RigidBodySpringDamper] = []
        self.coordinateSprings: List[CoordinateSpringDamper] = []
        self.linearSprings: List[LinearSpringDamper] = []
        self.rollingDiscPenalties: List[RollingDiscPenalty] = []
        self.loads: List[Load] = []
        self.pythonForces: List[PythonForce] = []
        self.rightHandSide = None

    def SetGravity(self, gravity):
        """Change the gravity vector (world frame).  Checked before it is assigned: a
        rejected value leaves the scene unchanged.  Simulators created afterwards see it
        (a Simulator compiles the scene once, at construction)."""
        self.gravity = _vec3(gravity, "gravity")

    # ----------------------------------------------------------------- bodies
    def AddBody(self, mass, inertia, com=(0, 0, 0), R0=None, r0=(0, 0, 0),
                omega0=(0, 0, 0), vel0=(0, 0, 0), name: str = "") -> int:
        """Add a rigid body; returns its index.

        ``inertia`` is the 3x3 inertia tensor about the *body frame origin* (for a frame
        at the COM this is the COM inertia); ``com`` the centre of mass in body
        coordinates; ``omega0`` body-fixed angular velocity; ``vel0`` the world velocity
        of the body frame origin."""
        idx = len(self.bodies)
        label = name or f"body{idx}"
        m, J, c = _checked_mass_properties(label, mass, inertia, com)
        self.bodies.append(Body(m, J, c, _rot(R0, f"{label}: R0"), _vec3(r0, f"{label}: r0"),
                                _vec3(omega0, f"{label}: omega0"), _vec3(vel0, f"{label}: vel0"),
                                label))
        return idx

    def AddPointMass(self, mass, r0=(0, 0, 0), vel0=(0, 0, 0), freeDirections=None, name: str = "") -> int:
        """Add a point mass (no orientation, integrated on R^3); returns its body index.

        ``freeDirections``: the 3x3 orthogonal projector onto the world directions the
        point moves in (default: all three); forces along the others have no effect, as
        for a point mass moving in a plane (x, y) or along one axis."""
        idx = len(self.bodies)
        label = name or f"point{idx}"
        m = _checked_point_mass(label, mass)
        P = _projector(np.eye(3) if freeDirections is None else freeDirections, f"{label}: freeDirections")
        v = _vec3(vel0, f"{label}: vel0")
        self.bodies.append(Body(m, np.zeros((3, 3)), np.zeros(3), np.eye(3), _vec3(r0, f"{label}: r0"),
                                np.zeros(3), P @ v, label, P))
        return idx

    def AddBody2D(self, mass, inertia, position=(0, 0), angle=0.0, omega=0.0, velocity=(0, 0), com=(0, 0),
                  name: str = "") -> int:
        """Add a planar rigid body: 3 DOF, moving in the world x-y plane; ``inertia`` about
        the z axis through the body frame origin (its reference point), ``com`` the centre of
        mass in body x-y coordinates.  It is integrated on the planar subgroup (SE2 / SO2xR2)
        of the chosen c-space; forces and constraint reactions off the plane do not act on it."""
        idx = len(self.bodies)
        label = name or f"body{idx}"
        J = _finite(float(inertia), f"{label}: inertia")
        if J <= 0:
            raise SceneError(f"{label}: the inertia of a 2D body must be positive, got {J}")
        cxy = np.asarray(com, float).reshape(-1)
        c3 = (cxy[0], cxy[1], 0.0)
        # the off-plane inertias never act (M^-1 is zero off the plane, compiled.planar_minv);
        # chosen so that the tensor about the COM is positive definite
        Jo = J + 2.0 * float(mass) * float(cxy @ cxy)
        m, Jt, c = _checked_mass_properties(label, mass, np.diag([Jo, Jo, J]), c3)
        ca, sa = np.cos(angle), np.sin(angle)
        R0 = np.array([[ca, -sa, 0.0], [sa, ca, 0.0], [0.0, 0.0, 1.0]])
        p = np.asarray(position, float).reshape(-1)
        v = np.asarray(velocity, float).reshape(-1)
        self.bodies.append(Body(m, Jt, c, R0, _vec3((p[0], p[1], 0.0), f"{label}: position"),
                                _vec3((0.0, 0.0, omega), f"{label}: omega"),
                                _vec3((v[0], v[1], 0.0), f"{label}: velocity"), label, planar=True,
                                angle0=_finite(angle, f"{label}: angle")))
        return idx

    def AddRotor(self, inertia, frame=None, position=(0, 0, 0), angle=0.0, omega=0.0, name: str = "") -> int:
        """Add a rotor: a rigid body ``R = frame Rz(angle)`` at
        ``position`` turning about ``frame e_z`` only (its velocity is omega_z; M^-1 is zero on the
        other axes, compiled.axes_minv), ``inertia`` about that axis.  ``angle`` is the total angle,
        turns included (SceneData.bodyAngles tracks it)."""
        idx = len(self.bodies)
        label = name or f"rotor{idx}"
        J = _finite(inertia, f"{label}: inertia")
        if J <= 0:
            raise SceneError(f"{label}: the inertia of a rotor must be positive, got {J}")
        F = _rot(frame, f"{label}: frame")
        a = _finite(angle, f"{label}: angle")
        ca, sa = np.cos(a), np.sin(a)
        R0 = F @ np.array([[ca, -sa, 0.0], [sa, ca, 0.0], [0.0, 0.0, 1.0]])
        # the mass and the inertias off the axis never act (M^-1 is zero there); a sphere-like
        # tensor J I keeps the gyroscopic term omega x J omega zero, as for a rotor
        self.bodies.append(Body(J, J * np.eye(3), np.zeros(3), R0, _vec3(position, f"{label}: position"),
                                _vec3((0.0, 0.0, _finite(omega, f"{label}: omega")), f"{label}: omega"), np.zeros(3),
                                label, angle0=a, freeAxes=(2,), angleFrame=F))
        return idx

    def describe_body(self, i):
        """Body ``i`` as errors name it (a scene read by the bridge names the items it was read from)."""
        return "the ground" if i == GROUND else f"body {i} ('{self.bodies[i].name}')"

    def _check_body(self, b, what, allow_ground=True):
        if b == GROUND and allow_ground:
            return
        if not (isinstance(b, (int, np.integer)) and 0 <= b < len(self.bodies)):
            raise SceneError(f"{what}: unknown body index {b} (scene has {len(self.bodies)} bodies"
                             f"{', use GROUND=-1 for the ground' if allow_ground else ''})")

    # ----------------------------------------------------------------- joints
    def AddJoint(self, bodyA, bodyB, constrainedAxes, posA=(0, 0, 0), rotA=None,
                 posB=(0, 0, 0), rotB=None, kind="generic", name="", worldTranslation=False) -> int:
        """Generic joint: lock any subset of the six relative axes of the joint frame.

        The joint frame sits at ``posA``/``rotA`` on body A (world data if A is GROUND)
        and ``posB``/``rotB`` on B.  Equations: translations in A's joint frame (global if
        all three are locked), rotations by dot products of joint frame axes.
        ``worldTranslation=True``: the locked translations are the world components of
        ``pB - pA`` whatever the lock (a spherical joint with some translation axes free)."""
        idx = len(self.joints)
        label = name or f"joint{idx}({kind})"
        self._check_body(bodyA, label)
        self._check_body(bodyB, label)
        if bodyA == bodyB:
            raise SceneError(f"{label}: both sides of the joint are on the same body, {self.describe_body(bodyA)}; "
                             f"a joint must connect two different bodies")
        ax = tuple(int(a) for a in constrainedAxes)
        if len(ax) != 6 or any(a not in (0, 1) for a in ax):
            raise SceneError(f"{label}: constrainedAxes must be six 0/1 flags, got {constrainedAxes}")
        if sum(ax) == 0:
            raise SceneError(f"{label}: constrainedAxes locks nothing")
        self.joints.append(Joint(int(bodyA), int(bodyB), _vec3(posA, f"{label}: posA"),
                                 _rot(rotA, f"{label}: rotA"), _vec3(posB, f"{label}: posB"),
                                 _rot(rotB, f"{label}: rotB"), ax, kind, label, bool(worldTranslation)))
        return idx

    def AddCoordinateConstraint(self, bodyA, axisA, bodyB, axisB, factor=1.0, constant=0.0, name="",
                                velocityLevel=False, offset=None) -> int:
        """One row ``h = factor * d_B . p_B - d_A . p_A - constant`` on position coordinates of
        the body frame origins (0 for GROUND) along world directions ``d = axis`` (an index
        0, 1, 2: the world axis; or a 3-vector, e.g. the axis of a mass moving along one axis):
        a coordinate constraint on position coordinates (the bridge folds the reference
        coordinates into ``constant``).

        ``offset``: a Python callable ``offset(t) -> float``, the moving part of the right-hand
        side: ``h = ... - constant - offset(t)`` (a prescribed motion; its first and second
        time derivatives enter the velocity and acceleration levels, mbs/row_drives.py).
        ``velocityLevel``: the row is ``factor qdot_B - qdot_A = constant + offset(t)`` on the
        coordinates' rates (no position-level equation)."""
        idx = len(self.joints)
        label = name or f"joint{idx}(coordinate)"
        self._check_body(bodyA, label)
        self._check_body(bodyB, label)
        if bodyA == GROUND and bodyB == GROUND:
            raise SceneError(f"{label}: both sides are on the ground")
        (dA, angA), (dB, angB) = (self._coordinate_end(b, ax, label) for b, ax in ((bodyA, axisA), (bodyB, axisB)))
        f = _finite(factor, f"{label}: factor")
        c = _finite(constant, f"{label}: constant")
        if bodyB == GROUND or f == 0.0:
            if bodyA == GROUND:
                raise SceneError(f"{label}: the row acts on no body (factor 0 and side A on the ground)")
        if offset is not None and not callable(offset):
            raise SceneError(f"{label}: offset must be a callable offset(t) -> float or None, got {offset!r}")
        self.joints.append(Joint(int(bodyA), int(bodyB), np.zeros(3), angA[1], np.zeros(3), angB[1],
                                 (1, 0, 0, 0, 0, 0), "coordinate", label, False,
                                 (dA, dB, f, c, angA[0], angB[0], angA[2], angB[2]),
                                 velocityLevel=bool(velocityLevel), offset=offset))
        return idx

    def AddDistanceConstraint(self, bodyA, posA, bodyB, posB, distance, name="") -> int:
        """A distance constraint: one row ``h = |p_B - p_A| - distance`` between body points
        (world points on GROUND)."""
        idx = len(self.joints)
        label = name or f"joint{idx}(distance)"
        self._check_body(bodyA, label)
        self._check_body(bodyB, label)
        if bodyA == bodyB:
            raise SceneError(f"{label}: both sides are on the same {'ground' if bodyA == GROUND else 'body'}")
        L0 = _finite(distance, f"{label}: distance")
        if L0 <= 0.0:
            raise SceneError(f"{label}: distance must be positive (the direction is undefined at 0), got {L0}")
        self.joints.append(Joint(int(bodyA), int(bodyB), _vec3(posA, f"{label}: posA"), np.eye(3),
                                 _vec3(posB, f"{label}: posB"), np.eye(3), (1, 0, 0, 0, 0, 0), "distance", label,
                                 False, None, L0))
        return idx

    def AddRollingDisc(self, bodyA, bodyB, discRadius, posA=(0, 0, 0), rotA=None, posB=(0, 0, 0), rotB=None,
                       planeNormal=(0, 0, 1), discAxis=(1, 0, 0), constrainedAxes=(1, 1, 1), name="") -> int:
        """A rolling-disc constraint: a disc (body B, centre ``posB``, axis
        ``rotB discAxis`` in B's coordinates) rolls on the plane of body A (or GROUND) through
        ``posA`` with normal ``rotA planeNormal``.  Velocity-level rows (nonholonomic): the
        velocity of the disc's material contact point relative to A's, in the (lateral,
        forward, normal) directions locked by ``constrainedAxes`` (mbs/rolling_disc_rows.py).
        ``planeNormal`` and ``discAxis`` are used as given (not normalised)."""
        idx = len(self.joints)
        label = name or f"joint{idx}(rollingDisc)"
        self._check_body(bodyA, label)
        self._check_body(bodyB, label, allow_ground=False)
        if bodyA == bodyB:
            raise SceneError(f"{label}: the disc and the plane are the same body")
        for b, side in ((bodyA, "plane (A)"), (bodyB, "disc (B)")):
            if b != GROUND and (self.bodies[b].isPoint or self.bodies[b].planar):
                raise SceneError(f"{label}: the {side} must be a 3D rigid body or the ground, "
                                 f"not {'a point mass' if self.bodies[b].isPoint else 'a 2D body'}")
        ax = tuple(int(a) for a in constrainedAxes)
        if len(ax) != 3 or any(a not in (0, 1) for a in ax) or sum(ax) == 0:
            raise SceneError(f"{label}: constrainedAxes must be three 0/1 flags (lateral, forward, normal) "
                             f"locking at least one, got {constrainedAxes}")
        r = _finite(discRadius, f"{label}: discRadius")
        n = _vec3(planeNormal, f"{label}: planeNormal")
        a = _vec3(discAxis, f"{label}: discAxis")
        RA, RB = _rot(rotA, f"{label}: rotA"), _rot(rotB, f"{label}: rotB")
        nw = RA @ n if bodyA == GROUND else self.bodies[bodyA].R0 @ RA @ n
        aw = self.bodies[bodyB].R0 @ RB @ a
        if np.linalg.norm(np.cross(aw, nw)) <= 1e-12 * max(1e-300, np.linalg.norm(aw) * np.linalg.norm(nw)):
            raise SceneError(f"{label}: the disc axis is parallel to the plane normal (or zero); the rolling "
                             f"direction (discAxis x planeNormal) is undefined")
        self.joints.append(Joint(int(bodyA), int(bodyB), _vec3(posA, f"{label}: posA"), RA,
                                 _vec3(posB, f"{label}: posB"), RB, ax + (0, 0, 0), "rollingDisc", label, False,
                                 None, None, (r, n, a)))
        return idx

    def _joint_at(self, kind, bodyA, bodyB, position, rotation, name):
        """Joint whose frame coincides on both bodies at a world ``position``/``rotation``
        in the initial configuration."""
        p = _vec3(position, f"{kind} joint position")
        Rw = _rot(rotation, f"{kind} joint rotation")
        frames = []
        for b in (bodyA, bodyB):
            self._check_body(b, f"{kind} joint")
            if b == GROUND:
                frames.append((p, Rw))
            else:
                B = self.bodies[b]
                frames.append((B.R0.T @ (p - B.r0), B.R0.T @ Rw))
        return self.AddJoint(bodyA, bodyB, JOINT_TYPES[kind], posA=frames[0][0], rotA=frames[0][1],
                             posB=frames[1][0], rotB=frames[1][1], kind=kind, name=name)

    def AddSphericalJoint(self, bodyA, bodyB, position, name=""):
        return self._joint_at("spherical", bodyA, bodyB, position, None, name)

    def AddRevoluteJoint(self, bodyA, bodyB, position, axis=(0, 0, 1), name=""):
        """Revolute joint about world ``axis`` through ``position`` (initial configuration)."""
        return self._joint_at("revolute", bodyA, bodyB, position, frame_with_axis(axis, 2), name)

    def AddPrismaticJoint(self, bodyA, bodyB, position, axis=(1, 0, 0), name=""):
        return self._joint_at("prismatic", bodyA, bodyB, position, frame_with_axis(axis, 0), name)

    def AddCylindricalJoint(self, bodyA, bodyB, position, axis=(0, 0, 1), name=""):
        return self._joint_at("cylindrical", bodyA, bodyB, position, frame_with_axis(axis, 2), name)

    def AddUniversalJoint(self, bodyA, bodyB, position, axisA=(1, 0, 0), axisB=(0, 1, 0), name=""):
        """Cardan joint: ``axisA`` (fixed in A) and ``axisB`` (fixed in B) stay perpendicular."""
        a = _vec3(axisA, "axisA")
        b = _vec3(axisB, "axisB")
        a /= np.linalg.norm(a)
        b = b - a * np.dot(a, b)
        if np.linalg.norm(b) < 1e-12:
            raise SceneError("universal joint: axisA and axisB must not be parallel")
        b /= np.linalg.norm(b)
        Rw = np.column_stack([a, b, np.cross(a, b)])
        return self._joint_at("universal", bodyA, bodyB, position, Rw, name)

    def AddFixedJoint(self, bodyA, bodyB, position, name=""):
        return self._joint_at("fixed", bodyA, bodyB, position, None, name)

    def AddPlanarJoint(self, bodyA, bodyB, position, normal=(0, 0, 1), name=""):
        return self._joint_at("planar", bodyA, bodyB, position, frame_with_axis(normal, 2), name)

    # ----------------------------------------------------------------- forces
    def AddSpringDamper(self, bodyA, posA, bodyB, posB, stiffness, damping=0.0,
                        referenceLength=0.0, force=0.0, name="") -> int:
        label = name or f"spring{len(self.springs)}"
        self._check_body(bodyA, label)
        self._check_body(bodyB, label)
        self.springs.append(SpringDamper(int(bodyA), _vec3(posA, label), int(bodyB), _vec3(posB, label),
                                         _finite(stiffness, f"{label}: stiffness"),
                                         _finite(damping, f"{label}: damping"),
                                         _finite(referenceLength, f"{label}: referenceLength"),
                                         _finite(force, f"{label}: force"), label))
        return len(self.springs) - 1

    def AddTorsionalSpringDamper(self, bodyA, bodyB, rotA=None, rotB=None, stiffness=0.0,
                                 damping=0.0, offset=0.0, torque=0.0, name="") -> int:
        label = name or f"torsionalSpring{len(self.torsionalSprings)}"
        self._check_body(bodyA, label)
        self._check_body(bodyB, label)
        self.torsionalSprings.append(TorsionalSpringDamper(
            int(bodyA), _rot(rotA, label), int(bodyB), _rot(rotB, label),
            _finite(stiffness, f"{label}: stiffness"), _finite(damping, f"{label}: damping"),
            _finite(offset, f"{label}: offset"), _finite(torque, f"{label}: torque"), label))
        return len(self.torsionalSprings) - 1

    def AddCartesianSpringDamper(self, bodyA, posA, bodyB, posB, stiffness, damping=(0, 0, 0),
                                 offset=(0, 0, 0), name="") -> int:
        label = name or f"cartesianSpring{len(self.cartesianSprings)}"
        self._check_body(bodyA, label)
        self._check_body(bodyB, label)
        self.cartesianSprings.append(CartesianSpringDamper(
            int(bodyA), _vec3(posA, label), int(bodyB), _vec3(posB, label),
            _vec3(stiffness, label), _vec3(damping, label), _vec3(offset, label), label))
        return len(self.cartesianSprings) - 1

    def AddRigidBodySpringDamper(self, bodyA, bodyB, posA=(0, 0, 0), rotA=None, posB=(0, 0, 0),
                                 rotB=None, stiffness=None, damping=None, offset=None, name="",
                                 intrinsic=False) -> int:
        label = name or f"rigidBodySpring{len(self.rigidSprings)}"
        self._check_body(bodyA, label)
        self._check_body(bodyB, label)
        K = np.zeros((6, 6)) if stiffness is None else np.asarray(stiffness, float).reshape(6, 6)
        D = np.zeros((6, 6)) if damping is None else np.asarray(damping, float).reshape(6, 6)
        o = np.zeros(6) if offset is None else np.asarray(offset, float).reshape(6)
        if not (np.all(np.isfinite(K)) and np.all(np.isfinite(D)) and np.all(np.isfinite(o))):
            raise SceneError(f"{label}: stiffness, damping and offset must be finite")
        self.rigidSprings.append(RigidBodySpringDamper(
            int(bodyA), _vec3(posA, label), _rot(rotA, label), int(bodyB), _vec3(posB, label),
            _rot(rotB, label), K.copy(), D.copy(), o.copy(), label, bool(intrinsic)))
        return len(self.rigidSprings) - 1

    def AddCoordinateSpringDamper(self, bodyA, axisA, bodyB, axisB, stiffness, damping=0.0, offset=0.0,
                                  name="") -> int:
        """Spring-damper between two world position coordinates of body frame origins
        (GROUND: 0) along world directions ``d = axis`` (index or 3-vector, as in
        :meth:`AddCoordinateConstraint`): ``f = k (d_B . p_B - d_A . p_A - offset) + d (rates)``,
        ``+f`` along ``d_A`` on A, ``-f`` along ``d_B`` on B."""
        label = name or f"coordinateSpring{len(self.coordinateSprings)}"
        self._check_body(bodyA, label)
        self._check_body(bodyB, label)
        (dA, angA), (dB, angB) = (self._coordinate_end(b, ax, label) for b, ax in ((bodyA, axisA), (bodyB, axisB)))
        self.coordinateSprings.append(CoordinateSpringDamper(
            int(bodyA), dA, int(bodyB), dB, _finite(stiffness, f"{label}: stiffness"),
            _finite(damping, f"{label}: damping"), _finite(offset, f"{label}: offset"), label, angA, angB))
        return len(self.coordinateSprings) - 1

    def AddCoordinateLoad(self, body, axis, load, name="") -> int:
        """A generalised force ``load`` on a coordinate of ``body``: a coordinate spring from
        the ground with ``k = d = 0`` and ``f0 = -load`` (``-f`` acts on side B), so the force
        follows the coordinate's direction (state-dependent for a RotationParameterCoordinate
        of 'eulerParameters' or 'taitBryanXYZ')."""
        label = name or f"coordinateLoad{len(self.coordinateSprings)}"
        self._check_body(body, label, allow_ground=False)
        k = self.AddCoordinateSpringDamper(GROUND, 0, body, axis, 0.0, 0.0, name=label)
        self.coordinateSprings[k].force = -_finite(load, f"{label}: load")
        return k

    def _coordinate_end(self, body, axis, label):
        """(world direction d, (is rotation, frame, angle0)) of one side of a coordinate item."""
        if isinstance(axis, RotationParameterCoordinate):
            return np.zeros(3), (self._node_parameter_code(body, axis, label), np.eye(3), 0.0)
        if not isinstance(axis, AngleCoordinate):
            return _coordinate_direction(axis, label), (False, np.eye(3), 0.0)
        if body == GROUND or self.bodies[body].isPoint:
            raise SceneError(f"{label}: a rotation coordinate needs a rigid body (2D or 3D), not "
                             f"{'the ground' if body == GROUND else 'a point mass'}")
        F = _rot(axis.frame, f"{label}: rotation coordinate frame")
        return F[:, 2].copy(), (True, F, _finite(axis.angle0, f"{label}: rotation coordinate angle0"))

    def _node_parameter_code(self, body, axis, label):
        """End code (node_coordinates.param_code) of a RotationParameterCoordinate; the body's
        rotation parameters are tracked (Body.track, from R0 unless already set)."""
        from .node_coordinates import PARAM_EULER_PARAMETERS, PARAM_KINDS, PARAM_TAIT_BRYAN, param_code
        from .rotation_parameters import TRACK_QUAT, TRACK_TAIT_BRYAN, nearest_tait_bryan, quat_of
        kind = PARAM_KINDS.get(axis.kind)
        if kind is None:
            raise SceneError(f"{label}: rotation parameter coordinate of kind {axis.kind!r}; use one of "
                             f"{sorted(PARAM_KINDS)}")
        n = 4 if kind == PARAM_EULER_PARAMETERS else 3
        if not 0 <= int(axis.index) < n:
            raise SceneError(f"{label}: the parametrisation {axis.kind} has rotation parameters 0..{n - 1}, "
                             f"not {axis.index}")
        if body == GROUND or self.bodies[body].isPoint or self.bodies[body].planar:
            raise SceneError(f"{label}: a rotation parameter coordinate needs a 3D rigid body")
        b = self.bodies[body]
        code = TRACK_TAIT_BRYAN if kind == PARAM_TAIT_BRYAN else TRACK_QUAT
        if b.track is None:
            p = np.zeros(4)
            if code == TRACK_TAIT_BRYAN:
                nearest_tait_bryan(np.asarray(b.R0, float), np.zeros(4), p)
            else:
                quat_of(np.asarray(b.R0, float), p)
            b.track = (code, p)
        elif int(b.track[0]) != code:
            raise SceneError(f"{label}: {self.describe_body(body)} tracks other rotation parameters than "
                             f"{axis.kind}'s")
        return param_code(kind, axis.index)

    def AddLinearSpringDamper(self, bodyA, posA, axisA, bodyB, posB, stiffness, damping=0.0, offset=0.0, force=0.0,
                              name="") -> int:
        """Spring-damper along the axis ``axisA`` fixed in body A (mbs/linear_spring_forces.py)."""
        label = name or f"linearSpring{len(self.linearSprings)}"
        self._check_body(bodyA, label)
        self._check_body(bodyB, label)
        ax = _vec3(axisA, f"{label}: axisA")
        self.linearSprings.append(LinearSpringDamper(
            int(bodyA), _vec3(posA, f"{label}: posA"), ax, int(bodyB), _vec3(posB, f"{label}: posB"),
            _finite(stiffness, f"{label}: stiffness"), _finite(damping, f"{label}: damping"),
            _finite(offset, f"{label}: offset"), _finite(force, f"{label}: force"), label))
        return len(self.linearSprings) - 1

    def AddRollingDiscPenalty(self, bodyA, bodyB, discRadius, contactStiffness, contactDamping=0.0,
                              dryFriction=(0.0, 0.0), dryFrictionProportionalZone=0.0, viscousFriction=(0.0, 0.0),
                              dryFrictionAngle=0.0, rollingViscousFriction=0.0, useLinearProportionalZone=False,
                              posA=(0, 0, 0), planeNormal=(0, 0, 1), posB=(0, 0, 0), discAxis=(1, 0, 0),
                              active=True, data0=(0.0, 0.0, 0.0), name="") -> int:
        """A penalty rolling disc (mbs/rolling_disc_penalty_forces.py): the disc on body B
        (centre ``posB``, ``discAxis`` in B's coordinates) on the plane of body A or GROUND
        (``posA``, ``planeNormal`` in A's coordinates); ``data0``: the initial data coordinates
        (slip velocity lateral, longitudinal; gap), contact only where the stored gap is
        negative."""
        label = name or f"rollingDiscPenalty{len(self.rollingDiscPenalties)}"
        self._check_body(bodyA, label)
        self._check_body(bodyB, label, allow_ground=False)
        if bodyA == bodyB:
            raise SceneError(f"{label}: the disc and the plane are the same body")
        for b, side in ((bodyA, "plane (A)"), (bodyB, "disc (B)")):
            if b != GROUND and (self.bodies[b].isPoint or self.bodies[b].planar):
                raise SceneError(f"{label}: the {side} must be a 3D rigid body or the ground, "
                                 f"not {'a point mass' if self.bodies[b].isPoint else 'a 2D body'}")
        n = _vec3(planeNormal, f"{label}: planeNormal")
        a = _vec3(discAxis, f"{label}: discAxis")
        nw = n if bodyA == GROUND else self.bodies[bodyA].R0 @ n
        aw = self.bodies[bodyB].R0 @ a
        if np.linalg.norm(np.cross(aw, nw)) <= 1e-12 * max(1e-300, np.linalg.norm(aw) * np.linalg.norm(nw)):
            raise SceneError(f"{label}: the disc axis is parallel to the plane normal (or zero); the rolling "
                             f"direction (discAxis x planeNormal) is undefined")
        e = RollingDiscPenalty(int(bodyA), _vec3(posA, f"{label}: posA"), n, int(bodyB),
                               _vec3(posB, f"{label}: posB"),
                               a, discRadius, contactStiffness, contactDamping, dryFriction,
                               dryFrictionProportionalZone, viscousFriction, dryFrictionAngle, rollingViscousFriction,
                               bool(useLinearProportionalZone), bool(active), data0, label)
        _check_rolling_disc_penalty(e)
        self.rollingDiscPenalties.append(e)
        return len(self.rollingDiscPenalties) - 1

    def AddForce(self, body, force, position=(0, 0, 0), bodyFixed=False, name="") -> int:
        """Constant force at body point ``position`` (body coordinates); world frame unless
        ``bodyFixed``."""
        label = name or f"force{len(self.loads)}"
        self._check_body(body, label, allow_ground=False)
        self.loads.append(Load(int(body), "force", _vec3(force, label), _vec3(position, label),
                               bool(bodyFixed), label))
        return len(self.loads) - 1

    def AddTorque(self, body, torque, bodyFixed=False, name="") -> int:
        label = name or f"torque{len(self.loads)}"
        self._check_body(body, label, allow_ground=False)
        self.loads.append(Load(int(body), "torque", _vec3(torque, label), np.zeros(3),
                               bool(bodyFixed), label))
        return len(self.loads) - 1

    def AddPythonForce(self, fn, name="") -> int:
        if not callable(fn):
            raise SceneError(f"AddPythonForce: {fn!r} is not callable")
        self.pythonForces.append(PythonForce(fn, name or f"pythonForce{len(self.pythonForces)}"))
        return len(self.pythonForces) - 1

    def SetRightHandSide(self, rhs):
        """Let ``rhs`` give the bodies' whole right-hand side ``Vdot = F(t, g, V)`` (eq. ODE2)
        instead of the compiled forces and joints: a problem evaluated outside the kernel (the
        bridge's evaluated model, bridge/evaluated_problem.py).  ``rhs.bind(Rs, rs, Vs, Vdot)`` gets
        the stage state and the output (arrays the compiled stepper shares, valid while the
        simulator's work arrays live) and returns ``f(t)``, which fills ``Vdot`` (nBodies, 6) at the
        stage state.  Such a scene has bodies only (their mass properties are not used)."""
        if not callable(getattr(rhs, "bind", None)):
            raise SceneError(f"SetRightHandSide: {rhs!r} has no bind(Rs, rs, Vs, Vdot) method")
        self.rightHandSide = rhs

    def validate(self):
        """Re-check all data (the item records are mutable): raises SceneError."""
        if self.rightHandSide is not None:
            other = [name for name in ("joints", "loads",
                                       "pythonForces") + self.CONNECTOR_LISTS if getattr(self, name)]
            if other or np.any(self.gravity != 0):
                raise SceneError(f"a scene whose right-hand side is set (SetRightHandSide) has bodies only; this one "
                                 f"has {', '.join(other + (['gravity'] if np.any(self.gravity != 0) else []))}")
        for b in self.bodies:
            if b.isPoint:
                b.mass = _checked_point_mass(b.name, b.mass)
                b.freeDirections = _projector(b.freeDirections, f"{b.name}: freeDirections")
                continue
            b.mass, b.inertia, b.com = _checked_mass_properties(b.name, b.mass, b.inertia, b.com)
            b.R0 = _rot(b.R0, f"{b.name}: R0")
            for what in ("r0", "omega0", "vel0"):
                setattr(b, what, _vec3(getattr(b, what), f"{b.name}: {what}"))
        for e in ELEMENTS:              # the registered force elements' items check themselves
            for item in getattr(self, e.sceneList):
                item.validate()
        for l in self.loads:
            _vec3(l.vector, f"{l.name}: vector")
        if not np.all(np.isfinite(self.gravity)):
            raise SceneError(f"gravity is not finite: {self.gravity}")

    # ----------------------------------------------------------------- info
    @property
    def nBodies(self):
        return len(self.bodies)

    # the two-body force elements (connectors), each a list attribute: from their registrations
    CONNECTOR_LISTS = tuple(e.sceneList for e in ELEMENTS)

    def connectors(self):
        """Every connector (two-body force element) of the scene, list by list."""
        return [c for name in self.CONNECTOR_LISTS for c in getattr(self, name)]

    def constraint_rows_per_joint(self):
        return [int(sum(j.constrainedAxes)) for j in self.joints]

    def __repr__(self):
        return (f"Scene({len(self.bodies)} bodies, {len(self.joints)} joints, "
                f"{len(self.connectors())} "
                f"connectors, {len(self.loads)} loads, gravity={self.gravity.tolist()})")
