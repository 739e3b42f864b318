"""Node registry: one small class per Exudyn rigid-body node type.

Each class handles all nodes of its type at once (arrays with one row per node) and
converts in both directions between Exudyn's node coordinates and the package's body
state ``(R, r, omega_local, vel_world)`` (rotation body->world, node position, body-fixed
angular velocity, world velocity of the node):

* :meth:`NodeKind.read`  ``(q_current, q_t) -> (R, r, omega, vel)``;
* the compiled row writers below ``(R, r, omega, vel[, omegaDot, acc]) -> (q_current, q_t[,
  q_tt])``, keeping the rotation parameters continuous from one call to the next;
* :meth:`NodeKind.velocity_map` ``T`` with ``q_t = T (omega, vel)`` and
  :meth:`NodeKind.velocity_map_dot` ``Tdot (omega, vel)``, to compare Exudyn's mass matrix,
  right-hand side and constraint Jacobian with the package's (tests).

Exudyn stores ``total = reference + current`` for every coordinate; ``q`` here is always
the *current* part, ``qref`` the reference part.

The per-output write-back is compiled (:mod:`.node_writers`): one row writer per node type
(``*_row``), selected by the class's ``code`` in ``write_row``.  Adding a node type = one
subclass here, its row writer + a branch in ``node_writers.write_row``, and its registration
in ``bridge/items.py``
(``register('node', typeName, 'body', ..., reader='<class name>')``).
"""
import math

import numpy as np

from ..mbs.rotation_parameters import TRACK_QUAT, TRACK_TAIT_BRYAN
from ..userwarn import warn_user
from . import items
from . import rotations as rot
from .node_writers import (CODE_1D, CODE_1D_ROT, CODE_2D, CODE_EP, CODE_POINT, CODE_POINT2D, CODE_ROTVEC, CODE_RXYZ,
                           RXYZ_WARN_COS)


class NodeKind:
    """Base class: nodes ``ids`` (Exudyn node numbers) of one type with coordinates
    ``[position(3), rotation parameters(nrot)]`` at ODE2 indices ``idx`` (n, 3+nrot).

    Per type: ``typeName`` (Exudyn's nodeType), ``code`` (selects the compiled row writer
    :func:`write_row`), ``nrot`` and the numpy maps ``rotation``, ``omega_from_rate``,
    ``rate_from_omega``, ``rate2_from_omega`` (independent of the compiled writer; the
    tests check one against the other)."""
    typeName = ""
    parametrisation = None      # the rotation parameters' name in the kernel, if it has them
    code = -1
    nrot = 3
    npos = 3                # position coordinates before the rotation parameters
    # ((i, j), limit): the coordinates are singular where |R[i, j]| reaches 1; the bridge
    # watches the entry at every internal step and warns above ``limit`` (None: regular)
    singularity = None
    # number of leading coordinates that are the node position's world components (the
    # coordinates that coordinate items may use, bridge.reader.coordinate_marker); None: none
    positionCoordinates = None

    def __init__(self, ids, idx, qref):
        self.ids = np.asarray(ids, dtype=np.int64)
        n = len(self.ids)
        self.idx = np.asarray(idx, dtype=np.int64).reshape(n, self.npos + self.nrot)
        self.qref = np.asarray(qref, float).reshape(n, self.npos + self.nrot)
        self.prev = np.zeros((n, 4))        # last total rotation parameters (continuity)
        self.first = True
        self.warned = np.zeros(n, bool)

    def bind_objects(self, objects):
        """The item dictionaries of the nodes' objects (in node order); a node kind whose
        coordinates depend on its object (Node1D) reads what it needs here."""

    def table_reference(self):
        """Per-node reference data of the compiled writer (bridge.fast.NodeTable.qref,
        at most NCOORD_MAX columns): the reference coordinates."""
        return self.qref

    def row_codes(self):
        """The compiled writer's code of each node (:func:`write_row`)."""
        return np.full(len(self), self.code, np.int64)

    def __len__(self):
        return len(self.ids)

    # ---- per type (numpy)
    def rotation(self, p):
        """R (n,3,3) from total rotation parameters p (n, nrot)."""
        raise NotImplementedError

    def omega_from_rate(self, p, p_t):
        raise NotImplementedError

    def rate_from_omega(self, p, omega):
        raise NotImplementedError

    def rate2_from_omega(self, p, p_t, omega, omegad):
        raise NotImplementedError

    def check_params(self, p, quiet=False):
        """Validate / normalise total rotation parameters read from Exudyn."""
        return np.array(p, float, copy=True)

    # ---- common
    def read(self, q, q_t):
        """(R, r, omega_local, vel_world) from the current coordinates q and velocities q_t
        (full ODE2 system vectors); also the start of the continuity tracking."""
        tot = self.qref + q[self.idx]
        vel = q_t[self.idx]
        p = self.check_params(tot[:, 3:])
        self.prev[:, :self.nrot] = p
        self.first = False
        return self.rotation(p), tot[:, :3].copy(), self.omega_from_rate(p, vel[:, 3:]), vel[:, :3].copy()

    def singular_warning(self, i):
        pass

    #: what the kernel tracks of the node's body step by step (mbs.rotation_parameters), None: nothing
    trackCode = None

    def tracked(self, k):
        """``(track code, parameters (4))`` of node k in the configuration read (Body.track:
        the kernel continues them after every accepted step), or None."""
        return None if self.trackCode is None else (self.trackCode, self.prev[k].copy())

    def velocity_map(self, q):
        """T (n, 3+nrot, 6): node velocity coordinates = T (omega_local, vel_world)."""
        p = self.check_params(self.qref[:, 3:] + q[self.idx[:, 3:]], quiet=True)
        n = len(self)
        T = np.zeros((n, 3 + self.nrot, 6))
        T[:, :3, 3:] = np.eye(3)
        for k in range(3):
            e = np.zeros((n, 3))
            e[:, k] = 1.0
            T[:, 3:, k] = self.rate_from_omega(p, e)
        return T

    def velocity_map_dot(self, q, q_t):
        """Tdot (omega, vel) = d/dt(T) applied to (omega, vel): the velocity-product
        part of the node accelerations, q_tt = T (omegadot, acc) + Tdot (omega, vel)."""
        p = self.qref[:, 3:] + q[self.idx[:, 3:]]
        p_t = q_t[self.idx[:, 3:]]
        omega = self.omega_from_rate(p, p_t)
        n = len(self)
        out = np.zeros((n, 3 + self.nrot))
        out[:, 3:] = self.rate2_from_omega(p, p_t, omega, np.zeros((n, 3)))
        return out


class RotVecLGNode(NodeKind):
    """``NodeRigidBodyRotVecLG``: rotation vector, velocities ``[v world, omega local]``.

    Written as Exudyn's own solvers write it: Exudyn's Lie group update
    (``CompositionRotationVector``) composes the quaternions of the total vector and of the
    increment and returns ``2 acos(q0) qv / |qv|``, so the vector passes |theta| = pi
    continuously and turns over at |theta| = 2 pi (|theta| <= 2 pi); the write-back takes the
    quaternion the kernel tracked step by step (mbs.rotation_parameters, TRACK_QUAT).  Within
    ROTVEC_TURNOVER of 2 pi the short vector is written instead (Exudyn 1.13.6 evaluates
    |theta| > 2 pi wrongly, even by a rounding error of the norm)."""
    typeName = "RigidBodyRotVecLG"
    parametrisation = "rotationVector"      # the kernel's name (mbs/node_coordinates.PARAM_KINDS)
    code = CODE_ROTVEC
    nrot = 3
    positionCoordinates = 3
    trackCode = TRACK_QUAT

    def read(self, q, q_t):
        out = super().read(q, q_t)
        # continuity is kept on the quaternion of the total vector v (rotvec_row):
        # (cos(|v|/2), sin(|v|/2) v/|v|), of either sign as Exudyn's composition keeps it
        v = self.prev[:, :3].copy()
        t = np.linalg.norm(v, axis=1)
        half = np.where(t > 0, np.sin(0.5 * t) / np.where(t > 0, t, 1.0), 0.5)
        self.prev[:, 0] = np.cos(0.5 * t)
        self.prev[:, 1:] = v * half[:, None]
        return out

    def check_params(self, p, quiet=False):
        big = np.linalg.norm(p, axis=1) > rot.TWO_PI
        if np.any(big) and not quiet:
            warn_user(f"exudyn_lie: RotVecLG node(s) {self.ids[big].tolist()} have a rotation vector "
                      f"with |theta| > 2 pi; Exudyn 1.13.6 evaluates such vectors incorrectly, "
                      f"exudyn_lie uses the exact rotation exp(theta)")
        return np.array(p, float, copy=True)

    def rotation(self, p):
        return rot.rotvec_to_matrix(p)

    def omega_from_rate(self, p, p_t):
        return np.array(p_t, float, copy=True)

    def rate_from_omega(self, p, omega):
        return np.array(omega, float, copy=True)

    def rate2_from_omega(self, p, p_t, omega, omegad):
        return np.array(omegad, float, copy=True)


class EPNode(NodeKind):
    """``NodeRigidBodyEP``: Euler parameters (+ Exudyn's algebraic |ep| = 1 equation, whose
    multiplier is 0), velocities ``[v world, ep_t]``.  The sign of ep is kept continuous."""
    typeName = "RigidBodyEP"
    parametrisation = "eulerParameters"
    code = CODE_EP
    nrot = 4
    positionCoordinates = 3
    trackCode = TRACK_QUAT
    TOL = 1e-6

    def check_params(self, p, quiet=False):
        nrm = np.linalg.norm(p, axis=1)
        bad = np.abs(nrm - 1.0) > self.TOL
        if np.any(bad) and not quiet:
            from .reader import BridgeError
            i = int(np.argmax(bad))
            raise BridgeError(f"NodeRigidBodyEP {int(self.ids[i])}: Euler parameters (reference + initial) "
                              f"have norm {nrm[i]:.9g}, not 1; give unit Euler parameters (e.g. from "
                              f"RotationMatrix2EulerParameters)")
        return p / nrm[:, None]

    def rotation(self, p):
        return rot.ep_to_matrix(p)

    def omega_from_rate(self, p, p_t):
        return np.einsum("nij,nj->ni", rot.ep_glocal(p), p_t)

    def rate_from_omega(self, p, omega):
        return 0.25 * np.einsum("nji,nj->ni", rot.ep_glocal(p), omega)

    def rate2_from_omega(self, p, p_t, omega, omegad):
        return 0.25 * (np.einsum("nji,nj->ni", rot.ep_glocal(p_t), omega)
                       + np.einsum("nji,nj->ni", rot.ep_glocal(p), omegad))


class RxyzNode(NodeKind):
    """``NodeRigidBodyRxyz``: Tait-Bryan angles R = Rx Ry Rz, velocities ``[v, angle rates]``.

    Writing keeps the angles continuous (both solutions of R, nearest 2 pi shift) and
    warns once per node when the middle angle comes within 5 deg of +-90 deg, where the
    angle rates ``GR^-1 omega`` grow without bound (the integration itself, done on R, is
    not affected)."""
    typeName = "RigidBodyRxyz"
    parametrisation = "taitBryanXYZ"
    code = CODE_RXYZ
    nrot = 3
    positionCoordinates = 3
    trackCode = TRACK_TAIT_BRYAN
    singularity = ((0, 2), math.sqrt(1.0 - RXYZ_WARN_COS ** 2))     # R[0, 2] = sin(beta)

    def singular_warning(self, i):
        if self.warned[i]:
            return
        self.warned[i] = True
        warn_user(f"exudyn_lie: NodeRigidBodyRxyz {int(self.ids[i])}: the middle Tait-Bryan angle is "
                      f"within 5 deg of +-90 deg (singularity of Rxyz); the angle rates written to Exudyn, "
                      f"GR^-1 omega, become large and are infinite at 90 deg. The Lie group integration is "
                      f"not affected; use NodeRigidBodyRotVecLG or EP nodes to avoid this")

    def rotation(self, p):
        return rot.rxyz_to_matrix(p)

    def omega_from_rate(self, p, p_t):
        return np.einsum("nij,nj->ni", rot.rxyz_glocal(p), p_t)

    def rate_from_omega(self, p, omega):
        return np.linalg.solve(rot.rxyz_glocal(p), np.asarray(omega, float)[..., None])[..., 0]

    def rate2_from_omega(self, p, p_t, omega, omegad):
        rhs = np.asarray(omegad, float) - np.einsum("nij,nj->ni", rot.rxyz_glocal_dot(p, p_t), p_t)
        return np.linalg.solve(rot.rxyz_glocal(p), rhs[..., None])[..., 0]


class PointNode(NodeKind):
    """``NodePoint``: position coordinates only (a point mass on R^3, group ``R3``); the
    state is ``(I, r, 0, rdot)``."""
    typeName = "Point"
    code = CODE_POINT
    nrot = 0
    npos = 3
    positionCoordinates = 3

    def __init__(self, ids, idx, qref):
        self.ids = np.asarray(ids, dtype=np.int64)
        n = len(self.ids)
        self.idx = np.asarray(idx, dtype=np.int64).reshape(n, self.npos)
        self.qref = np.asarray(qref, float).reshape(n, self.npos)
        self.prev = np.zeros((n, 4))
        self.first = True
        self.warned = np.zeros(n, bool)

    def _pad(self, x):
        out = np.zeros((len(self), 3))
        out[:, :self.npos] = x
        return out

    def read(self, q, q_t):
        n = len(self)
        self.first = False
        return (np.repeat(np.eye(3)[None], n, axis=0), self._pad(self.qref + q[self.idx]), np.zeros((n, 3)),
                self._pad(q_t[self.idx]))

    def velocity_map(self, q):
        T = np.zeros((len(self), self.npos, 6))
        T[:, :, 3:3 + self.npos] = np.eye(self.npos)
        return T

    def velocity_map_dot(self, q, q_t):
        return np.zeros((len(self), self.npos))


class Point2DNode(PointNode):
    """``NodePoint2D``: coordinates x, y (z = 0, Exudyn's CNodePoint2D)."""
    typeName = "Point2D"
    code = CODE_POINT2D
    npos = 2
    positionCoordinates = 2



class Rigid2DNode(NodeKind):
    """``NodeRigidBody2D``: coordinates ``[x, y, phi]``, ``R = Rz(phi)``, velocities
    ``[vx, vy, omega_z]`` (CNodeRigidBody2D).  The body moves in the world x-y plane
    (z = 0); written angles stay continuous (no wrap to (-pi, pi])."""
    typeName = "RigidBody2D"
    code = CODE_2D
    nrot = 1
    npos = 2
    positionCoordinates = 2
    planar = True

    @staticmethod
    def _rz(phi):
        c, s = np.cos(phi), np.sin(phi)
        R = np.zeros((len(phi), 3, 3))
        R[:, 0, 0], R[:, 0, 1], R[:, 1, 0], R[:, 1, 1], R[:, 2, 2] = c, -s, s, c, 1.0
        return R

    def read(self, q, q_t):
        tot = self.qref + q[self.idx]
        vel = q_t[self.idx]
        n = len(self)
        self.prev[:, 0] = tot[:, 2]
        self.prev[:, 1] = vel[:, 2]           # omega_z; prev[:, 2] the time (bridge.fast.NodeTable)
        self.first = False
        r = np.zeros((n, 3))
        r[:, :2] = tot[:, :2]
        om = np.zeros((n, 3))
        om[:, 2] = vel[:, 2]
        v = np.zeros((n, 3))
        v[:, :2] = vel[:, :2]
        return self._rz(tot[:, 2]), r, om, v

    def velocity_map(self, q):
        T = np.zeros((len(self), 3, 6))
        T[:, 0, 3] = T[:, 1, 4] = T[:, 2, 2] = 1.0
        return T

    def velocity_map_dot(self, q, q_t):
        return np.zeros((len(self), 3))



class Node1DNode(PointNode):
    """``Node1D``: one ODE2 coordinate ``x`` (total = reference + current), whose meaning comes
    from its object (CObjectMass1D / CObjectRotationalMass1D):

    * ``ObjectMass1D``: the point ``p = referencePosition + referenceRotation (x, 0, 0)``, a point
      mass on the line ``origin + axis x`` (``axis = referenceRotation e_x``, ``origin =
      referencePosition``), integrated on R^3 with the free direction ``axis``:
      ``x = axis . (r - origin)``, ``x_t = axis . rdot``;
    * ``ObjectRotationalMass1D``: a rotor (Scene.AddRotor) ``R = F Rz(x)`` at ``origin`` with
      ``F = referenceRotation``: ``x`` its angle continued over turns, ``x_t = omega_z``."""
    typeName = "1D"
    code = CODE_1D
    npos = 1
    positionCoordinates = 1

    def bind_objects(self, objects):
        n = len(self)
        self.axis = np.zeros((n, 3))
        self.origin = np.zeros((n, 3))
        self.frame = np.repeat(np.eye(3)[None], n, axis=0)
        self.rotor = np.zeros(n, bool)
        for k, d in enumerate(objects):
            F = np.asarray(d.get("referenceRotation", np.eye(3)), float).reshape(3, 3)
            self.origin[k] = np.asarray(d.get("referencePosition", [0, 0, 0]), float)
            self.frame[k] = F
            self.rotor[k] = d["objectType"] == "RotationalMass1D"
            self.axis[k] = F[:, 2] if self.rotor[k] else F[:, 0]

    def row_codes(self):
        return np.where(self.rotor, CODE_1D_ROT, CODE_1D)

    def coordinate_frame(self, k):
        """(axis, origin) of node k's coordinate: ``x = axis . (r - origin)``; None for a rotor."""
        return None if self.rotor[k] else (self.axis[k].copy(), self.origin[k].copy())

    def total_angle(self, k):
        """A rotor's total angle (turns included) in the configuration read; None otherwise."""
        return float(self.prev[k, 0]) if self.rotor[k] else None

    def table_reference(self):
        out = np.zeros((len(self), 4))
        out[:, 0] = self.qref[:, 0] + np.where(self.rotor, 0.0, np.einsum("ni,ni->n", self.axis, self.origin))
        out[:, 1:] = np.where(self.rotor[:, None], self.frame[:, :, 0], self.axis)
        return out

    def _rz(self, x):
        c, s = np.cos(x), np.sin(x)
        R = np.zeros((len(x), 3, 3))
        R[:, 0, 0], R[:, 0, 1], R[:, 1, 0], R[:, 1, 1], R[:, 2, 2] = c, -s, s, c, 1.0
        return R

    def read(self, q, q_t):
        n = len(self)
        self.first = False
        x = self.qref[:, 0] + q[self.idx[:, 0]]
        xt = q_t[self.idx[:, 0]]
        rot = self.rotor[:, None]
        R = np.where(rot[:, :, None], self.frame @ self._rz(x), np.eye(3)[None])
        r = np.where(rot, self.origin, self.origin + self.axis * x[:, None])
        om = np.zeros((n, 3))
        om[:, 2] = np.where(self.rotor, xt, 0.0)
        vel = np.where(rot, 0.0, self.axis * xt[:, None])
        self.prev[:, 0] = np.where(self.rotor, x, self.prev[:, 0])
        self.prev[:, 1] = np.where(self.rotor, xt, self.prev[:, 1])
        return R, r, om, vel

    def velocity_map(self, q):
        T = np.zeros((len(self), 1, 6))
        T[:, 0, 3:] = np.where(self.rotor[:, None], 0.0, self.axis)
        T[:, 0, 2] = np.where(self.rotor, 1.0, 0.0)
        return T

    def velocity_map_dot(self, q, q_t):
        return np.zeros((len(self), 1))


#: the registry: Exudyn ``nodeType`` string -> class, from the body nodes' registrations in
#: bridge/items.py (each names its class here as ``reader``)
NODE_KINDS = {it.typeName: globals()[it.reader] for it in items.of("node", "body")}
assert all(cls.typeName == t for t, cls in NODE_KINDS.items()), "bridge/items.py: node registered with a wrong class"
