"""What the readers of an Exudyn ``mbs`` share (:mod:`.reader`, :mod:`.reader_joints`,
:mod:`.reader_forces`): the lists of supported items (derived from the one registration per
item type, bridge/items.py), the errors, the resolved markers and joints, and small
conversions of Exudyn's item data."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from ..mbs.compiled import joint_row_descriptors
from ..mbs.kernel import ROW_ROT
from ..mbs.scene import AngleCoordinate, RotationParameterCoordinate, SceneError
from . import items

# the lists below derive from the one registration per item type (bridge/items.py)
SUPPORTED_NODES = tuple(it.name + (" (data only)" if it.role == "data" else "") for it in items.of("node"))
# objects that are bodies of the scene: Exudyn object type -> the node types it accepts
BODY_OBJECTS = {it.typeName: it.nodes for it in items.of("object", "body")}
RIGID_NODE_TYPES = BODY_OBJECTS["RigidBody"]
# bodies whose body markers must sit on their axis (CObjectRotationalMass1D: Exudyn throws
# for a marker or load at localPosition x, y != 0, and has no mass integral for MarkerBodyMass)
ROTOR_BODIES = ("RotationalMass1D",)
SUPPORTED_MARKERS = items.supported_names("marker")
POSITION_MARKERS = tuple(it.name for it in items.of("marker", "position"))   # markers with a position
SUPPORTED_LOADS = items.supported_names("load")

JOINT_TYPES = tuple(it.typeName for it in items.of("object", "joint"))
# joints with a reader of their own (the others: read_joint): Exudyn object type -> reader method
JOINT_READERS = {it.typeName: it.reader for it in items.of("object", "joint") if it.reader}
# connectors: Exudyn object type -> (reader method of _Reader, markers need an orientation)
CONNECTOR_READERS = {it.typeName: (it.reader, it.markers) for it in items.of("object", "connector")}
CONNECTOR_TYPES = tuple(CONNECTOR_READERS)
SUPPORTED_OBJECTS = items.supported_names("object")


@dataclass
class CoordinateMarker:
    """A MarkerNodeCoordinate on a position coordinate: the value is ``direction . p - ref``
    of the body frame origin (the node), 0 on ground; ``direction`` is the world axis of the
    coordinate (``e_k`` for coordinate k of a point or rigid node, the Mass1D's axis
    ``referenceRotation e_x`` for a Node1D)."""
    index: int
    body: int
    direction: np.ndarray
    ref: float
    markerType: str = "NodeCoordinate"
    # a rotation coordinate (the angle of a NodeRigidBody2D): value = tracked angle - ref
    angle: Optional[AngleCoordinate] = None
    # a rotation parameter of a 3D rigid node (RotVecLG, EP, Rxyz; mbs/node_coordinates.py):
    # value = tracked parameter - ref, direction 0
    param: Optional[RotationParameterCoordinate] = None
    paramPrev: Optional[np.ndarray] = None  # its node's parameters (4) last seen (Python items, pyforces)

    def __post_init__(self):
        # ``direction`` as three floats, read by the Python items at every stage (pyforces_coordinates)
        self.axis = tuple(float(c) for c in self.direction)

    @property
    def spec(self):
        """The coordinate for Scene.AddCoordinate*: a direction, the AngleCoordinate or the
        RotationParameterCoordinate."""
        if self.param is not None:
            return self.param
        return self.direction if self.angle is None else self.angle


class BridgeError(SceneError):
    """The Exudyn model contains something exudyn_lie cannot integrate (or bad data)."""


class NotCompiled(BridgeError):
    """An item, an option of an item or an mbs-level function that the compiled kernel does not
    have, but Exudyn evaluates: ``SolveDynamic``'s 'auto' takes the Exudyn-evaluated path for it
    (bridge/evaluated_dispatch.py), ``evaluation='compiled'`` raises it."""


@dataclass
class MarkerFrame:
    """A marker resolved to a scene body: ``pos``/``rot`` in body coordinates (world
    coordinates for ``GROUND``); ``rot`` is None for position-only markers."""
    index: int
    markerType: str
    body: int
    pos: np.ndarray
    rot: Optional[np.ndarray]

    def rotation(self):
        return np.eye(3) if self.rot is None else self.rot


@dataclass
class JointInfo:
    """An Exudyn joint and where its kernel rows go: ``aeRows[k]`` is the Exudyn AE index
    (global) of the scene joint's k-th row (kernel row order); ``aeAll`` all AE indices
    of the object."""
    objectIndex: int
    objectType: str
    sceneJoint: Optional[int]
    aeRows: np.ndarray
    aeAll: np.ndarray


@dataclass
class TorsionData:
    """A torsional spring with Exudyn's data node (continuous angle): ``dataNode`` the
    NodeGenericData, ``angle0`` its value read; compiled springs (``spring`` = scene index)
    have ``turns0`` turns folded into the offset (the kernel tracks the angle from the
    principal one, so kernel angle + 2 pi turns0 = Exudyn's angle); Python items
    (``item``) track from ``angle0`` themselves."""
    objectIndex: int
    dataNode: int
    angle0: float
    spring: Optional[int] = None
    turns0: int = 0
    item: object = None


def _userfunction(d, key, what, evaluated=False):
    """The Python callable of an Exudyn user-function parameter, None if unset.  Any other kind
    (Exudyn's symbolic user functions, ``exudyn.symbolic``) is evaluated by Exudyn itself: the
    compiled reader raises NotCompiled (the Exudyn-evaluated path takes the model), the evaluated
    path's own readers (``evaluated``: they call the function themselves) a BridgeError."""
    uf = d.get(key, 0)
    if isinstance(uf, (int, float)) and uf == 0:
        return None
    if uf is None:
        return None
    fn = uf.get("function") if isinstance(uf, dict) else uf
    if not callable(fn):
        kind = uf.get("type") if isinstance(uf, dict) else type(uf).__name__
        if evaluated:
            raise BridgeError(f"{what}: {key} of type {kind} is not a Python callable; exudyn_lie calls this "
                              f"function itself (its rate by differences) and supports Python functions only")
        raise NotCompiled(f"{what}: {key} of type {kind} (Exudyn evaluates it; the compiled kernel calls Python "
                          f"functions only)")
    return fn


def _ht(d):
    """(translation, rotation) of a marker's localHT (or localPosition)."""
    if "localHT" in d:
        H = np.asarray(d["localHT"], float)
        return H[:3, 3].copy(), H[:3, :3].copy()
    return np.asarray(d.get("localPosition", [0, 0, 0]), float).copy(), None


def _inertia_matrix(v):
    v = np.asarray(v, float).reshape(-1)
    if v.shape == (3, 3):
        return v
    Jxx, Jyy, Jzz, Jyz, Jxz, Jxy = v
    return np.array([[Jxx, Jxy, Jxz], [Jxy, Jyy, Jyz], [Jxz, Jyz, Jzz]])


def joint_ae_map(objectType, constrainedAxes):
    """Local Exudyn AE index of each kernel row of the joint (kernel row order)."""
    rows = joint_row_descriptors(constrainedAxes)
    nrot = sum(constrainedAxes[3:])
    out = []
    for kind, ax, bx in rows:
        if kind != ROW_ROT:
            out.append(ax - 1 if objectType == "JointPrismaticX" else ax)
            continue
        if objectType == "JointRevoluteZ":
            out.append(3 + bx)                              # z0.x1, z0.y1
        elif objectType == "JointPrismaticX":
            out.append({(2, 1): 2, (2, 0): 3, (0, 1): 4}[(ax, bx)])
        elif nrot == 3:
            out.append({(2, 1): 3, (2, 0): 4, (0, 1): 5}[(ax, bx)])
        elif nrot == 2:
            out.append(3 + bx)
        else:
            out.append(3 + [i for i in range(3) if constrainedAxes[3 + i]][0])
    return out


def _tracked_start(parametrisation, p):
    """The parameters a node's tracking starts from (rotation_parameters: the quaternion of a
    RotVecLG's rotation vector or an EP node's own, of the sign given; Rxyz angles)."""
    out = np.zeros(4)
    if parametrisation == "rotationVector":
        t = float(np.linalg.norm(p))
        out[0] = np.cos(0.5 * t)
        out[1:] = p * (np.sin(0.5 * t) / t if t > 0 else 0.5)
    else:
        out[:len(p)] = p
    return out


def _orthonormal(R):
    """Remove rounding noise (Exudyn stores 1e-16-accurate matrices; Scene wants 1e-8)."""
    R = np.asarray(R, float)
    U, s, Vt = np.linalg.svd(R)
    if np.max(np.abs(s - 1.0)) > 1e-6:
        raise BridgeError(f"rotation matrix is not orthonormal (singular values {s})")
    return U @ Vt
