"""Read an assembled Exudyn ``mbs`` into an exudyn_lie :class:`~exudyn_lie.mbs.Scene`.

:func:`SceneFromExudyn` only *reads* ``mbs`` (items and the initial configuration); it
never changes it.  Every item is either translated exactly (same equations as Exudyn,
checked against Exudyn's own ``ComputeMassMatrix / ComputeODE2RHS / ComputeJacobianAE``
in ``tests/test_bridge_oracle.py``), skipped for a stated reason (inactive joints,
ground-to-ground items, sensors), or rejected with a :class:`BridgeError` naming the
item type, its index and what is supported.

Mapping (Exudyn -> scene):

* ``ObjectRigidBody`` on ``NodeRigidBodyRotVecLG / EP / Rxyz`` -> a body; its frame is
  the node frame, inertia about the node (``physicsInertia``), COM ``physicsCenterOfMass``;
* ``ObjectGround`` (reference position / rotation), ``NodePointGround`` -> ground;
* markers ``MarkerBodyRigid / MarkerNodeRigid`` (localHT), ``MarkerBodyPosition /
  MarkerNodePosition`` (localPosition), ``MarkerBodyMass`` (mass-proportional loads);
* ``ObjectJointSpherical / RevoluteZ / PrismaticX / Generic`` -> ``Scene.AddJoint`` with the
  joint frame ``marker localHT rotation @ rotationMarker`` (Exudyn's equations = the
  kernel's ``ObjectJointGeneric`` rows, row by row, see :func:`joint_ae_map`);
* ``ObjectConnectorSpringDamper / CartesianSpringDamper / TorsionalSpringDamper /
  RigidBodySpringDamper`` -> compiled springs (``velocityOffset`` folded into the constant
  force / torque; an inactive one with zero coefficients, so that a user function can
  switch it on); with a Python user function, and a torsional spring without its
  NodeGenericData (Exudyn then uses the principal angle) -> :mod:`.pyforces`
  (``Scene.AddPythonForce``, evaluated in Python at every stage);
* ``LoadForceVector / LoadTorqueVector / LoadMassProportional`` -> constant loads (a
  uniform mass-proportional load on every body becomes the scene's gravity), with a
  ``loadVectorUserFunction`` -> :mod:`.pyforces`.  As in Exudyn (which refuses them at
  ``Assemble``), a torque, or a force with ``bodyFixed=True``, needs a marker with an
  orientation.

A torsional spring's ``NodeGenericData`` holds Exudyn's continuous angle of the last step
(Exudyn takes the branch of the principal angle nearest to it); the reader starts from the
stored value, so a spring that has already turned (e.g. a continued simulation) keeps its
turn count (:class:`TorsionData`).

``sc.itemRows`` maps each connector and load to its compiled row (or Python item), and
``sc.reader`` keeps the marker frames: :mod:`.params` re-reads single items during a solve.
:func:`check_system_level` refuses GeneralContact and the mbs-level user functions the
bridge does not call.

``configuration='items'`` reads an mbs that is not assembled yet from its item
dictionaries (the initial values ``mbs.Assemble()`` will set): ``SolveDynamic`` validates
the model that way before it assembles anything.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import List, Optional

import numpy as np

from ..mbs.compiled import joint_row_descriptors
from ..mbs.force_elements import ELEMENTS
from ..mbs.kernel import ROW_ROT
from ..mbs.scene import GROUND, AngleCoordinate, NodeParameterCoordinate, Scene, SceneError, frame_with_axis
from . import items, pyforces
from .moving_offsets import MovableOffset
from ..mbs.node_coordinates import PARAM_KINDS
from .nodes import NODE_KINDS

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
    param: Optional[NodeParameterCoordinate] = None
    paramPrev: Optional[np.ndarray] = None  # its node's parameters (4) last seen (Python items, pyforces)

    @property
    def spec(self):
        """The coordinate for Scene.AddCoordinate*: a direction, the AngleCoordinate or the
        NodeParameterCoordinate."""
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


class ExudynScene(Scene):
    """A :class:`Scene` read from an Exudyn ``mbs``, with the maps back to Exudyn items."""

    def __init__(self, mbs, gravity=(0.0, 0.0, 0.0)):
        super().__init__(gravity)
        self.mbs = mbs
        self.bodyObject: List[int] = []       # Exudyn object index of each scene body
        self.bodyNode: List[int] = []         # Exudyn node index of each scene body
        self.nodeKinds = []                   # NodeKind instances (one per node type present)
        self.kindBodies = []                  # scene body indices of each NodeKind's rows
        self.joints_info: List[JointInfo] = []
        self.pyItems = []                     # Python force items (pyforces.PyItem)
        self.pyConnectedBodies = set()        # bodies tied by Python-force connectors
        self.skipped = []                     # (item, index, reason)
        self.aeZero: List[int] = []           # AE coordinates that stay 0 (EP norm rows, inactive joints)
        self.nodeTypes = {}                   # node index -> Exudyn node type string
        self.torsionData: List[TorsionData] = []   # torsional springs with a data node (turns)
        self.rollingDiscData = []             # (object, NodeGenericData) of each penalty rolling disc, scene order
        self.configuration = "initial"        # what was read ('items': mbs not assembled yet)
        # where each Exudyn item went: ("object", o) / ("load", l) -> (table, row), table one of
        # the name of a registered force element (its compiled row, mbs/force_elements.py: "spring",
        # "cartesian", ...), "py" (index in pyItems), "load"
        # (compiled load row), "massProportional", "ground" (no effect); joints: joints_info
        self.itemRows = {}
        self.reader = None                    # the _Reader (marker frames), for bridge.params
        # a re-read during a solve (_Reader.reread_connector): the turns folded into each compiled
        # torsional spring's offset when it was first read (object -> turns0), kept by the re-read
        self.keptTurns = {}
        # object -> MovableOffset: the ConnectorCoordinate rows whose offset a pre- or post-step
        # function may move (bridge/moving_offsets.py)
        self.movableOffsets = {}

    def body_of_object(self, obj):
        try:
            return self.bodyObject.index(int(obj))
        except ValueError:
            return None

    def describe_body(self, i):
        if i == GROUND:
            return "the ground"
        o, n = self.bodyObject[i], self.bodyNode[i]
        name = self.bodies[i].name
        return f"object {o} ('{name}', node {n} {self.nodeTypes[n]})"


# mbs-level user functions of Exudyn 1.13.6 (MainSystem.Get*/Set*UserFunction): pre- and
# post-step functions run as in a native solve (Exudyn's own time loop calls them); the
# others act inside Exudyn's Newton / discontinuous iteration, which exudyn_lie replaces
UNHONOURED_MBS_FUNCTIONS = {
    "PostNewtonUserFunction": "it runs after each Newton solve of Exudyn's discontinuous iteration (contact, "
                              "switching), which exudyn_lie's explicit step replaces",
    "PreNewtonResidualUserFunction": "it runs before each Newton residual, which exudyn_lie's explicit step "
                                     "does not compute",
    "SystemJacobianUserFunction": "it modifies Exudyn's Newton Jacobian, which exudyn_lie's explicit step does "
                                  "not use",
}


def check_system_level(mbs, unhonoured=None, contactReason=""):
    """Refuse what is not an item but changes the model: GeneralContact and mbs-level user
    functions that exudyn_lie does not honour (``unhonoured``: name -> why; default
    ``UNHONOURED_MBS_FUNCTIONS``) (reads only; raises BridgeError)."""
    n = int(mbs.NumberOfGeneralContacts())
    if n > 0:
        raise BridgeError(f"mbs has {n} GeneralContact(s) (mbs.AddGeneralContact): exudyn_lie does not "
                          f"integrate GeneralContact{contactReason}; solve this model with exudyn.SolveDynamic, "
                          f"or remove the contact (mbs.DeleteGeneralContact)")
    for name, why in (UNHONOURED_MBS_FUNCTIONS if unhonoured is None else unhonoured).items():
        fn = getattr(mbs, "Get" + name, None)
        if fn is None:
            continue
        uf = fn()
        if not (isinstance(uf, (int, float)) and uf == 0) and uf is not None:
            # Exudyn's PostNewton calls it on the Exudyn-evaluated path
            error = NotCompiled if name == "PostNewtonUserFunction" else BridgeError
            raise error(f"mbs has a {name} (mbs.Set{name}): exudyn_lie does not call it ({why}); "
                              f"solve with exudyn.SolveDynamic, or remove it with mbs.Set{name}(0)")


def _userfunction(d, key, what):
    """The Python callable of an Exudyn user-function parameter, None if unset."""
    uf = d.get(key, 0)
    if isinstance(uf, (int, float)) and uf == 0:
        return None
    if uf is None:
        return None
    fn = uf.get("function") if isinstance(uf, dict) else uf
    if not callable(fn):
        raise BridgeError(f"{what}: {key} of type {uf.get('type') if isinstance(uf, dict) else type(uf)} "
                          f"is not a Python callable; exudyn_lie supports Python user functions only")
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


class _Reader:
    def __init__(self, mbs, configuration):
        import exudyn as exu
        self.exu = exu
        self.mbs = mbs
        self.sd = mbs.systemData
        cfg = {"initial": exu.ConfigurationType.Initial, "current": exu.ConfigurationType.Current, "items": None}
        if not isinstance(configuration, str) or configuration.lower() not in cfg:
            raise BridgeError(f"configuration must be 'initial', 'current' or 'items', got {configuration!r}")
        self.items = configuration.lower() == "items"
        if not self.items and not mbs.systemIsConsistent:
            raise BridgeError("mbs is not assembled (mbs.systemIsConsistent is False); call mbs.Assemble() "
                              "first (SolveDynamic does that with autoAssemble=True)")
        self.config = cfg[configuration.lower()]
        if self.items:
            self._items_coordinates()
        else:
            self.q = np.asarray(self.sd.GetODE2Coordinates(configuration=self.config), float)
            self.q_t = np.asarray(self.sd.GetODE2Coordinates_t(configuration=self.config), float)
        self.nObjects = self.sd.NumberOfObjects()
        self.objects = [mbs.GetObject(i) for i in range(self.nObjects)]
        self.markers = {}
        self.ground = {}          # object index -> (pos, rot) of ObjectGround
        self.rigidNodeBody = {}   # node index -> scene body
        self.nodeAxisFrame = {}   # Node1D of a Mass1D -> (world axis, origin) of its one coordinate
        self.nodeRotor = {}       # Node1D of a RotationalMass1D -> (frame F, origin): R = F Rz(x)
        self.badNodes = []

    def _items_coordinates(self):
        """mbs not assembled: the initial coordinates / velocities Assemble() will set (the
        nodes' ``initialCoordinates`` / ``initialVelocities``) in a layout of our own."""
        self.ltg = {}
        q, qt = [], []
        for n in range(self.sd.NumberOfNodes()):
            d = self.mbs.GetNode(n)
            if d["nodeType"] not in NODE_KINDS:
                continue
            nq = len(np.asarray(d["referenceCoordinates"]).reshape(-1))
            start = sum(len(x) for x in q)
            self.ltg[n] = list(range(start, start + nq))
            for key, out in (("initialCoordinates", q), ("initialVelocities", qt)):
                v = np.asarray(d.get(key, np.zeros(nq)), float).reshape(-1)
                out.append(v if len(v) == nq else np.zeros(nq))
        self.q = np.concatenate(q) if q else np.zeros(0)
        self.q_t = np.concatenate(qt) if qt else np.zeros(0)

    def node_ltg(self, n):
        """ODE2 indices of node n (in the reader's own layout for 'items')."""
        return self.ltg[n] if self.items else self.sd.GetNodeLTGODE2(n)

    def data_coordinate(self, n):
        """First data coordinate of NodeGenericData n in the configuration read."""
        if self.items:
            v = np.asarray(self.mbs.GetNode(n).get("initialCoordinates", [0.0]), float).reshape(-1)
        else:
            v = np.asarray(self.sd.GetDataCoordinates(configuration=self.config), float)[
                np.asarray(self.sd.GetNodeLTGData(n), np.int64)]
        return float(v[0]) if len(v) else 0.0

    def data_coordinates(self, n):
        """All data coordinates of NodeGenericData n in the configuration read."""
        if self.items:
            return np.asarray(self.mbs.GetNode(n).get("initialCoordinates", []), float).reshape(-1)
        return np.asarray(self.sd.GetDataCoordinates(configuration=self.config), float)[
            np.asarray(self.sd.GetNodeLTGData(n), np.int64)]

    # ------------------------------------------------------------------ nodes
    def read_nodes(self, sc: ExudynScene):
        mbs = self.mbs
        byKind = {}
        for n in range(self.sd.NumberOfNodes()):
            d = mbs.GetNode(n)
            t = d["nodeType"]
            sc.nodeTypes[n] = t
            if t in NODE_KINDS:
                if t == "RigidBodyEP" and not d.get("addConstraintEquation", True):
                    raise NotCompiled(f"node {n} ('{d.get('name', '')}') NodeRigidBodyEP: addConstraintEquation=False "
                                      f"is not supported by exudyn_lie (it keeps the Euler parameters on the unit "
                                      f"sphere itself); use the default addConstraintEquation=True")
                byKind.setdefault(t, []).append(n)
            elif ("node", t) in items.ITEMS:        # ground and data nodes: no body
                continue
            else:
                self.badNodes.append((n, d.get("name", ""), t))
        self.byKind = byKind

    def check_nodes(self):
        """Unsupported nodes not already reported through their object."""
        for n, name, t in self.badNodes:
            raise NotCompiled(f"node {n} ('{name}') of type Node{t} is not supported by exudyn_lie; supported "
                              f"nodes: {', '.join(SUPPORTED_NODES)}")

    # ------------------------------------------------------------------ bodies
    def read_bodies(self, sc: ExudynScene):
        mbs = self.mbs
        bodyOfNode = {}
        for o, d in enumerate(self.objects):
            t = d["objectType"]
            if t == "Ground":
                R = np.asarray(d.get("referenceRotation", np.eye(3)), float)
                self.ground[o] = (np.asarray(d.get("referencePosition", [0, 0, 0]), float), R)
            elif t in BODY_OBJECTS:
                n = int(d["nodeNumber"])
                nt = sc.nodeTypes.get(n)
                if nt not in BODY_OBJECTS[t]:
                    raise BridgeError(f"object {o} ('{d.get('name', '')}') Object{t} uses node {n} of "
                                      f"type Node{nt}; supported nodes for it: "
                                      f"{', '.join('Node' + k for k in BODY_OBJECTS[t])}")
                if n in bodyOfNode:
                    raise BridgeError(f"object {o} ('{d.get('name', '')}') Object{t} shares node {n} with "
                                      f"object {bodyOfNode[n]}; one body per node is supported")
                bodyOfNode[n] = o
            elif t not in JOINT_TYPES + CONNECTOR_TYPES:
                raise NotCompiled(f"object {o} ('{d.get('name', '')}') of type Object{t} is not supported by "
                                  f"exudyn_lie; supported objects: {', '.join(SUPPORTED_OBJECTS)}")
        self.check_nodes()
        # node kinds, in node order; states of all nodes of a kind at once
        states = {}
        angles = {}         # NodeRigidBody2D: total angle
        tracks = {}         # nodes' rotation parameters tracked step by step (NodeKind.tracked)
        for t, nodes in self.byKind.items():
            nodes = [n for n in nodes if n in bodyOfNode]
            if not nodes:
                continue
            idx = np.array([self.node_ltg(n) for n in nodes], dtype=np.int64)
            qref = np.array([np.asarray(mbs.GetNode(n)["referenceCoordinates"], float) for n in nodes])
            for k, n in enumerate(nodes):
                for name, arr in (("coordinates", self.q), ("velocities", self.q_t)):
                    if not np.all(np.isfinite(arr[idx[k]])) or not np.all(np.isfinite(qref[k])):
                        raise BridgeError(f"node {n} ({t}, body object {bodyOfNode[n]}): initial {name} are not "
                                          f"finite: {arr[idx[k]] if np.all(np.isfinite(qref[k])) else qref[k]}")
            kind = NODE_KINDS[t](nodes, idx, qref)
            kind.bind_objects([self.objects[bodyOfNode[n]] for n in nodes])
            if hasattr(kind, "coordinate_frame"):
                for k, n in enumerate(nodes):
                    if kind.coordinate_frame(k) is not None:
                        self.nodeAxisFrame[n] = kind.coordinate_frame(k)
                    else:
                        self.nodeRotor[n] = (kind.frame[k].copy(), kind.origin[k].copy())
            R, r, om, vel = kind.read(self.q, self.q_t)
            for k, n in enumerate(nodes):
                states[n] = (R[k], r[k], om[k], vel[k])
                if getattr(kind, "planar", False):
                    angles[n] = float(kind.prev[k, 0])          # the total angle, turns included
                elif hasattr(kind, "total_angle") and kind.total_angle(k) is not None:
                    angles[n] = kind.total_angle(k)
                tracks[n] = kind.tracked(k)
            sc.nodeKinds.append(kind)
        # bodies in object order
        for o, d in enumerate(self.objects):
            if d["objectType"] not in BODY_OBJECTS:
                continue
            n = int(d["nodeNumber"])
            R, r, om, vel = states[n]
            label = d.get("name", "") or f"object{o}"
            try:
                if d["objectType"] == "RigidBody2D":
                    b = sc.AddBody2D(mass=float(d["mass"]), inertia=float(d["inertia"]), position=r[:2],
                                     angle=angles[n], omega=float(om[2]),
                                     velocity=vel[:2], com=np.asarray(d.get("centerOfMass", [0, 0]), float),
                                     name=label)
                elif d["objectType"] == "Mass1D":
                    # nodes.Node1DNode: a point mass on the line origin + axis x
                    axis = self.nodeAxisFrame[n][0]
                    b = sc.AddPointMass(float(d.get("mass", d.get("physicsMass"))), r0=r, vel0=vel, name=label,
                                        freeDirections=np.outer(axis, axis))
                elif d["objectType"] == "RotationalMass1D":
                    # nodes.Node1DNode: a rotor R = F Rz(x) turning about F e_z at its reference position
                    F, origin = self.nodeRotor[n]
                    b = sc.AddRotor(float(d.get("inertia", d.get("physicsInertia"))), frame=_orthonormal(F),
                                    position=origin, angle=angles[n], omega=float(om[2]), name=label)
                elif d["objectType"] != "RigidBody":
                    b = sc.AddPointMass(float(d.get("mass", d.get("physicsMass"))), r0=r, vel0=vel, name=label,
                                        freeDirections=np.diag([1.0, 1.0, float(d["objectType"] == "MassPoint")]))
                else:
                    b = sc.AddBody(mass=float(d["mass"]), inertia=_inertia_matrix(d["inertia"]),
                                   com=np.asarray(d.get("centerOfMass", [0, 0, 0]), float), R0=_orthonormal(R),
                                   r0=r, omega0=om, vel0=vel, name=label)
            except SceneError as e:
                raise BridgeError(f"object {o} Object{d['objectType']}: {e}") from None
            sc.bodies[b].track = tracks.get(n)      # node rotation parameters tracked per step
            sc.bodyObject.append(o)
            sc.bodyNode.append(n)
            self.rigidNodeBody[n] = b
        for kind in sc.nodeKinds:
            sc.kindBodies.append(np.array([self.rigidNodeBody[n] for n in kind.ids], dtype=np.int64))
        if sc.nBodies == 0:
            raise NotCompiled("the Exudyn model has no ObjectRigidBody or mass point; nothing to integrate")
        # EP normalisation rows stay 0
        for n, t in sc.nodeTypes.items():
            if t == "RigidBodyEP" and not self.items:
                try:
                    sc.aeZero.extend(int(i) for i in self.sd.GetNodeLTGAE(n))
                except Exception:
                    pass

    # ------------------------------------------------------------------ markers
    def marker(self, m, what, need_rotation=False, allow_mass=False) -> MarkerFrame:
        m = int(m)
        if m in self.markers:
            mf = self.markers[m]
        else:
            if not 0 <= m < self.sd.NumberOfMarkers():
                raise BridgeError(f"{what}: marker {m} does not exist")
            d = self.mbs.GetMarker(m)
            t = d["markerType"]
            pos, Rm = _ht(d)
            if t in ("BodyRigid", "BodyPosition", "BodyMass"):
                o = int(d["bodyNumber"])
                if o in self.ground:
                    gp, gR = self.ground[o]
                    body, pos, Rm = GROUND, gp + gR @ pos, (None if Rm is None else gR @ Rm)
                elif self.objects[o]["objectType"] in ROTOR_BODIES and (t == "BodyMass" or pos[0] != 0 or pos[1] != 0):
                    raise BridgeError(f"{what}: marker {m} (Marker{t}) on object {o} (Object"
                                      f"{self.objects[o]['objectType']}) "
                                      + ("has no mass integral (Exudyn cannot apply it either)" if t == "BodyMass" else
                                         f"is at localPosition {pos.tolist()}; Exudyn applies markers and loads on a "
                                         f"RotationalMass1D only on its axis (localPosition x = y = 0) and raises "
                                         f"otherwise; use an ObjectRigidBody2D or ObjectRigidBody there"))
                elif self.objects[o]["objectType"] in BODY_OBJECTS:
                    body = self._body_of_object(o)
                    if self.objects[o]["objectType"] == "Mass1D":
                        # CObjectMass1D: p = referencePosition + referenceRotation (node + local);
                        # the point mass has R = I, so body coordinates are world directions
                        Rref = np.asarray(self.objects[o].get("referenceRotation", np.eye(3)), float)
                        pos = Rref @ pos
                        Rm = Rref if (Rm is None and t == "BodyRigid") else (None if Rm is None else Rref @ Rm)
                else:
                    raise BridgeError(f"{what}: marker {m} (Marker{t}) is attached to object {o} of type "
                                      f"Object{self.objects[o]['objectType']}, not to a rigid body or ground")
                if t == "BodyMass":
                    pos, Rm = np.zeros(3), None
            elif t in ("NodeRigid", "NodePosition"):
                n = int(d["nodeNumber"])
                nt = self.mbs.GetNode(n)["nodeType"]
                if nt == "PointGround":
                    body = GROUND
                    pos = np.asarray(self.mbs.GetNode(n)["referenceCoordinates"], float)[:3] + (
                        np.zeros(3) if t == "NodePosition" else pos)
                elif nt == "1D":
                    raise BridgeError(f"{what}: marker {m} (Marker{t}) is on Node1D {n}, which has no position or "
                                      f"orientation (Exudyn refuses it too); use a MarkerNodeCoordinate, or a body "
                                      f"marker on its ObjectMass1D")
                elif n in self.rigidNodeBody:
                    body = self.rigidNodeBody[n]
                    if t == "NodePosition":
                        pos = np.zeros(3)
                else:
                    raise BridgeError(f"{what}: marker {m} (Marker{t}) is attached to node {n} of type Node{nt}, "
                                      f"which belongs to no ObjectRigidBody / ObjectRigidBody2D")
            else:
                raise NotCompiled(f"{what}: marker {m} of type Marker{t} is not supported for this item; it "
                                  f"needs one of: {', '.join(POSITION_MARKERS)}")
            mf = MarkerFrame(m, t, body, np.asarray(pos, float), Rm)
            self.markers[m] = mf
        if mf.markerType == "BodyMass" and not allow_mass:
            raise BridgeError(f"{what}: marker {m} is a MarkerBodyMass, which only mass-proportional loads use")
        if need_rotation and mf.rot is None:
            raise BridgeError(f"{what}: marker {m} (Marker{mf.markerType}) has no orientation; this item needs "
                              f"a MarkerBodyRigid or MarkerNodeRigid")
        return mf

    def _body_of_object(self, o):
        n = int(self.objects[o]["nodeNumber"])
        return self.rigidNodeBody[n]

    # ------------------------------------------------------------------ joints / connectors
    def read_items(self, sc: ExudynScene):
        for o, d in enumerate(self.objects):
            t = d["objectType"]
            if t in JOINT_READERS:
                getattr(self, JOINT_READERS[t])(sc, o, d)
            elif t in JOINT_TYPES:
                self.read_joint(sc, o, d)
            elif t in CONNECTOR_TYPES:
                self.read_connector(sc, o, d)

    def _what(self, kind, o, d):
        return f"object {o} ('{d.get('name', '')}') Object{d['objectType']}"

    def read_joint(self, sc, o, d):
        t = d["objectType"]
        what = self._what("object", o, d)
        try:
            aeAll = np.zeros(0, np.int64) if self.items else np.array(self.sd.GetObjectLTGAE(o), dtype=np.int64)
        except Exception:
            aeAll = np.zeros(0, np.int64)
        if not d.get("activeConnector", True):
            sc.skipped.append((what, "inactive (activeConnector=False): Exudyn sets its multipliers to 0"))
            sc.aeZero.extend(aeAll.tolist())
            return
        for key in ("offsetUserFunction", "offsetUserFunction_t"):
            if _userfunction(d, key, what) is not None:
                raise NotCompiled(f"{what}: {key} (moving joint offsets) is not supported by exudyn_lie")
        if d.get("alternativeConstraints", False):
            raise NotCompiled(f"{what}: alternativeConstraints=True is not supported by exudyn_lie; use the "
                              f"default rotation constraints")
        m0, m1 = (int(m) for m in d["markerNumbers"])
        if t in ("JointRevolute2D", "JointPrismatic2D"):
            return self.read_joint_2d(sc, o, d, what, aeAll, m0, m1)
        spherical = t == "JointSpherical"
        A = self.marker(m0, what, need_rotation=not spherical)
        B = self.marker(m1, what, need_rotation=not spherical)
        if A.body == GROUND and B.body == GROUND:
            sc.skipped.append((what, "connects ground to ground"))
            sc.aeZero.extend(aeAll.tolist())
            return
        if spherical:
            ca = tuple(int(c) for c in d.get("constrainedAxes", [1, 1, 1])) + (0, 0, 0)
        elif t == "JointRevoluteZ":
            ca = (1, 1, 1, 1, 1, 0)
        elif t == "JointPrismaticX":
            ca = (0, 1, 1, 1, 1, 1)
        else:
            ca = tuple(int(c) for c in d["constrainedAxes"])
        if sum(ca) == 0:
            sc.skipped.append((what, "constrains no axis"))
            sc.aeZero.extend(aeAll.tolist())
            return
        if spherical:
            # Exudyn (CObjectJointSpherical): rows (p1 - p0)_i in world components for the
            # locked axes i, whatever the lock - the scene's world translation rows
            rotA = rotB = np.eye(3)
        else:
            rotA = A.rot @ np.asarray(d.get("rotationMarker0", np.eye(3)), float)
            rotB = B.rot @ np.asarray(d.get("rotationMarker1", np.eye(3)), float)
        kind = {"JointSpherical": "spherical", "JointRevoluteZ": "revolute", "JointPrismaticX": "prismatic",
                "JointGeneric": "generic"}[t]
        try:
            j = sc.AddJoint(A.body, B.body, ca, posA=A.pos, rotA=_orthonormal(rotA), posB=B.pos,
                            rotB=_orthonormal(rotB), kind=kind, name=d.get("name", "") or f"object{o}",
                            worldTranslation=spherical)
        except SceneError as e:
            raise BridgeError(f"{what}: {e}") from None
        local = joint_ae_map(t, ca)
        if spherical:
            local = [ax for ax in range(3) if ca[ax]]
        aeRows = aeAll[local] if len(aeAll) else np.zeros(0, np.int64)
        sc.joints_info.append(JointInfo(o, t, j, aeRows, aeAll))
        # AE rows of unlocked axes (g = lambda) stay 0
        sc.aeZero.extend(sorted(set(aeAll.tolist()) - set(aeRows.tolist())))

    def _constraint_ae(self, o, d, what, sc):
        """The AE indices of a one-row constraint object; None (skipped) if it is inactive."""
        try:
            aeAll = np.zeros(0, np.int64) if self.items else np.array(self.sd.GetObjectLTGAE(o), dtype=np.int64)
        except Exception:
            aeAll = np.zeros(0, np.int64)
        if not d.get("activeConnector", True):
            sc.skipped.append((what, "inactive (activeConnector=False): Exudyn sets its multiplier to 0"))
            sc.aeZero.extend(aeAll.tolist())
            return None
        return aeAll

    def read_distance_constraint(self, sc, o, d):
        """ObjectConnectorDistance: ``|p_1 - p_0| - distance = 0`` (CObjectConnectorDistance)."""
        what = self._what("object", o, d)
        aeAll = self._constraint_ae(o, d, what, sc)
        if aeAll is None:
            return
        m0, m1 = (int(m) for m in d["markerNumbers"])
        A = self.marker(m0, what)
        B = self.marker(m1, what)
        if A.body == GROUND and B.body == GROUND:
            sc.skipped.append((what, "connects ground to ground"))
            sc.aeZero.extend(aeAll.tolist())
            return
        try:
            j = sc.AddDistanceConstraint(A.body, A.pos, B.body, B.pos, float(d["distance"]),
                                         name=d.get("name", "") or f"object{o}")
        except SceneError as e:
            raise BridgeError(f"{what}: {e}") from None
        sc.joints_info.append(JointInfo(o, d["objectType"], j, aeAll[:1], aeAll))

    def read_rolling_disc(self, sc, o, d):
        """ObjectJointRollingDisc (CObjectJointRollingDisc): velocity-level rows, the velocity of
        the disc's contact point relative to the plane in (lateral, forward, normal) directions
        for the locked ``constrainedAxes``; marker 0 the plane (a 3D rigid body or ground), marker
        1 the disc centre on a 3D rigid body; free axes keep their multiplier 0 (as Exudyn)."""
        what = self._what("object", o, d)
        aeAll = self._constraint_ae(o, d, what, sc)
        if aeAll is None:
            return
        m0, m1 = (int(m) for m in d["markerNumbers"])
        A = self.marker(m0, what, need_rotation=True)
        B = self.marker(m1, what, need_rotation=True)
        if B.body == GROUND:
            raise BridgeError(f"{what}: marker 1 (the disc) is on the ground; Exudyn's rolling disc has the disc "
                              f"on marker 1 and the plane (ground or body) on marker 0")
        ca = [int(c) for c in np.asarray(d.get("constrainedAxes", [1, 1, 1])).reshape(-1)]
        if not any(ca):
            sc.skipped.append((what, "constrains no axis"))
            sc.aeZero.extend(aeAll.tolist())
            return
        try:
            j = sc.AddRollingDisc(A.body, B.body, float(d["discRadius"]), posA=A.pos, rotA=_orthonormal(A.rotation()),
                                  posB=B.pos, rotB=_orthonormal(B.rotation()),
                                  planeNormal=np.asarray(d.get("planeNormal", [0, 0, 1]), float),
                                  discAxis=np.asarray(d.get("discAxis", [1, 0, 0]), float), constrainedAxes=ca,
                                  name=d.get("name", "") or f"object{o}")
        except SceneError as e:
            raise BridgeError(f"{what}: {e}") from None
        locked = [i for i in range(3) if ca[i]]
        aeRows = aeAll[locked] if len(aeAll) else np.zeros(0, np.int64)
        sc.joints_info.append(JointInfo(o, d["objectType"], j, aeRows, aeAll))
        sc.aeZero.extend(sorted(set(aeAll.tolist()) - set(aeRows.tolist())))

    def coordinate_marker(self, m, what):
        """(body, position axis, reference value) of a MarkerNodeCoordinate: the marker value
        is the node's current coordinate ``p[axis] - reference`` (0 on a ground node)."""
        m = int(m)
        if not 0 <= m < self.sd.NumberOfMarkers():
            raise BridgeError(f"{what}: marker {m} does not exist")
        d = self.mbs.GetMarker(m)
        if d["markerType"] != "NodeCoordinate":
            raise BridgeError(f"{what}: marker {m} is a Marker{d['markerType']}; this item needs "
                              f"MarkerNodeCoordinate markers")
        n, k = int(d["nodeNumber"]), int(d["coordinate"])
        nt = self.mbs.GetNode(n)["nodeType"]
        if nt == "PointGround":
            return CoordinateMarker(m, GROUND, np.eye(3)[0], 0.0)
        if n not in self.rigidNodeBody:
            raise BridgeError(f"{what}: marker {m} (MarkerNodeCoordinate) is on node {n} of type Node{nt}, which "
                              f"belongs to no body exudyn_lie integrates")
        npos = getattr(NODE_KINDS.get(nt), "positionCoordinates", None) or 0
        if nt == "RigidBody2D" and k == 2:
            # the angle phi of R = Rz(phi): a rotation coordinate about the world z axis, tracked
            # over turns from its total value (reference + current) in the configuration read
            ref = float(np.asarray(self.mbs.GetNode(n)["referenceCoordinates"], float).reshape(-1)[2])
            total = ref + float(self.q[self.node_ltg(n)[2]])
            return CoordinateMarker(m, self.rigidNodeBody[n], np.eye(3)[2], ref,
                                    angle=AngleCoordinate(np.eye(3), total))
        nrot = getattr(NODE_KINDS.get(nt), "nrot", 0)
        if nt in PARAM_KINDS and npos <= k < npos + nrot:
            # a rotation parameter of a 3D rigid node: Exudyn's coordinate (value, rate and
            # Jacobian as CMarkerNodeCoordinate defines them, mbs/node_coordinates.py)
            qref = np.asarray(self.mbs.GetNode(n)["referenceCoordinates"], float).reshape(-1)
            total = qref[npos:npos + nrot] + self.q[self.node_ltg(n)[npos:npos + nrot]]
            return CoordinateMarker(m, self.rigidNodeBody[n], np.zeros(3), float(qref[k]),
                                    param=NodeParameterCoordinate(nt, k - npos),
                                    paramPrev=_tracked_start(nt, total))
        if not 0 <= k < npos:
            raise BridgeError(f"{what}: marker {m} (MarkerNodeCoordinate) is on coordinate {k} of node {n} "
                              f"(Node{nt}), not a position coordinate; exudyn_lie supports coordinate items on node "
                              f"position coordinates, the rotation parameters of RotVecLG, EP and Rxyz rigid nodes, "
                              f"the angle of a NodeRigidBody2D and Node1D coordinates; solve with exudyn.SolveDynamic"
                              + (f" (0..{npos - 1} of this node)" if npos else ""))
        ref = float(np.asarray(self.mbs.GetNode(n)["referenceCoordinates"], float).reshape(-1)[k])
        if n in self.nodeRotor:            # a rotor's angle: a rotation coordinate about F e_z
            F = self.nodeRotor[n][0]
            total = ref + float(self.q[self.node_ltg(n)[0]])
            return CoordinateMarker(m, self.rigidNodeBody[n], F[:, 2].copy(), ref,
                                    angle=AngleCoordinate(_orthonormal(F), total))
        frame = self.nodeAxisFrame.get(n)
        if frame is None:
            return CoordinateMarker(m, self.rigidNodeBody[n], np.eye(3)[k], ref)
        axis, origin = frame         # a Node1D: value = axis . (p - origin) - ref
        return CoordinateMarker(m, self.rigidNodeBody[n], axis, ref + float(axis @ origin))

    def read_coordinate_constraint(self, sc, o, d):
        """ObjectConnectorCoordinate (CObjectConnectorCoordinate::ComputeAlgebraicEquations):
        ``f q_B - q_A - offset = 0``, with ``offsetUserFunction`` in place of ``offset``; with
        ``velocityLevel=True`` ``f qdot_B - qdot_A - offset = 0`` on the coordinates' rates, with
        ``offsetUserFunction_t`` in place of ``offset`` (Exudyn ignores ``offsetUserFunction``
        then, and the position-level equation ignores ``offsetUserFunction_t``: its index-3
        solve never reads it).  Moving offsets: mbs/row_drives.py."""
        what = self._what("object", o, d)
        try:
            aeAll = np.zeros(0, np.int64) if self.items else np.array(self.sd.GetObjectLTGAE(o), dtype=np.int64)
        except Exception:
            aeAll = np.zeros(0, np.int64)
        if not d.get("activeConnector", True):
            sc.skipped.append((what, "inactive (activeConnector=False): Exudyn sets its multiplier to 0"))
            sc.aeZero.extend(aeAll.tolist())
            return
        velocityLevel = bool(d.get("velocityLevel", False))
        key = "offsetUserFunction_t" if velocityLevel else "offsetUserFunction"
        uf = _userfunction(d, key, what)
        m0, m1 = (int(m) for m in d["markerNumbers"])
        cA = self.coordinate_marker(m0, what)
        cB = self.coordinate_marker(m1, what)
        A, ka, refA, B, kb, refB = cA.body, cA.spec, cA.ref, cB.body, cB.spec, cB.ref
        f = float(d.get("factor1", d.get("factorValue1", 1.0)))      # factorValue1: before 1.12.258
        if A == GROUND and (B == GROUND or f == 0.0):
            sc.skipped.append((what, "constrains no body coordinate"))
            sc.aeZero.extend(aeAll.tolist())
            return
        offset = float(d.get("offset", 0.0))
        moving = None if uf is None else pyforces.OffsetUserFunction(self.mbs, o, d, uf, key)
        if moving is None and not velocityLevel and (self.mbs.GetPreStepUserFunction()
                                                     or self.mbs.GetPostStepUserFunction()):
            # a step function may move the offset (Exudyn's reeving crane): a moving row
            moving = sc.movableOffsets[o] = MovableOffset(offset, f"the offset of {what}")
        # the references fold into the constant of a position-level row (rates have none); a
        # moving offset replaces the offset
        constant = (0.0 if velocityLevel else f * refB - refA) + (0.0 if moving is not None else offset)
        try:
            j = sc.AddCoordinateConstraint(A, ka, B, kb, factor=f, name=d.get("name", "") or f"object{o}",
                                           constant=constant, velocityLevel=velocityLevel, offset=moving)
        except SceneError as e:
            raise BridgeError(f"{what}: {e}") from None
        sc.joints_info.append(JointInfo(o, d["objectType"], j, aeAll[:1], aeAll))

    def read_joint_2d(self, sc, o, d, what, aeAll, m0, m1):
        """ObjectJointRevolute2D: ``(p1 - p0)_x = (p1 - p0)_y = 0`` (world rows, as the
        spherical joint's).  ObjectJointPrismatic2D (CObjectJointPrismatic2D): ``(p1 - p0) . n1 = 0``
        and ``t0 . n1 = 0`` with ``n1 = A1 normalMarker1``, ``t0 = A0 axisMarker0``: the normal
        lives on marker 1, so the scene joint runs from marker 1 (side A, whose local axis the
        translation row takes) to marker 0, with the axes negated so that both rows equal
        Exudyn's: ``(-n1) . (p0 - p1)`` and ``(-n1) . (-t0)``."""
        t = d["objectType"]
        name = d.get("name", "") or f"object{o}"
        prismatic = t == "JointPrismatic2D"
        A = self.marker(m0, what, need_rotation=prismatic)
        B = self.marker(m1, what, need_rotation=prismatic)
        if A.body == GROUND and B.body == GROUND:
            sc.skipped.append((what, "connects ground to ground"))
            sc.aeZero.extend(aeAll.tolist())
            return
        try:
            if not prismatic:
                j = sc.AddJoint(A.body, B.body, (1, 1, 0, 0, 0, 0), posA=A.pos, posB=B.pos, kind="revolute2D",
                                name=name, worldTranslation=True)
            else:
                if not d.get("constrainRotation", True):
                    raise NotCompiled(f"{what}: constrainRotation=False is not supported by exudyn_lie; use the "
                                      f"default constrainRotation=True (or a 2D body with a coordinate constraint)")
                axes = {}
                for key in ("axisMarker0", "normalMarker1"):
                    v = np.asarray(d.get(key), float).reshape(-1)
                    if v.shape != (3,) or not np.all(np.isfinite(v)) or abs(np.linalg.norm(v) - 1.0) > 1e-12:
                        raise BridgeError(f"{what}: {key} = {v} must be a finite unit 3-vector for exudyn_lie "
                                          f"(Exudyn uses it unnormalised, so its length scales the constraint)")
                    axes[key] = v
                rotA = B.rotation() @ frame_with_axis(-axes["normalMarker1"], 0)      # column 0: -n1
                rotB = A.rotation() @ frame_with_axis(-axes["axisMarker0"], 1)        # column 1: -t0
                j = sc.AddJoint(B.body, A.body, (1, 0, 0, 0, 0, 1), posA=B.pos, rotA=_orthonormal(rotA),
                                posB=A.pos, rotB=_orthonormal(rotB), kind="prismatic2D", name=name)
        except SceneError as e:
            raise BridgeError(f"{what}: {e}") from None
        aeRows = aeAll[[0, 1]] if len(aeAll) else np.zeros(0, np.int64)
        sc.joints_info.append(JointInfo(o, t, j, aeRows, aeAll))

    def read_connector(self, sc, o, d):
        t = d["objectType"]
        what = self._what("object", o, d)
        m0, m1 = (int(m) for m in d["markerNumbers"])
        reader, rigid = CONNECTOR_READERS[t]
        if rigid == "coordinate":
            A, B = self.coordinate_marker(m0, what), self.coordinate_marker(m1, what)
        else:
            A = self.marker(m0, what, need_rotation=rigid)
            B = self.marker(m1, what, need_rotation=rigid)
        if A.body == GROUND and B.body == GROUND:
            sc.skipped.append((what, "connects ground to ground (no force on any body)"))
            return
        active = bool(d.get("activeConnector", True))
        if not active:
            # compiled with zero coefficients (no force, as Exudyn's inactive connector), so
            # that a user function can switch it on during the solve (bridge.params)
            sc.skipped.append((what, "inactive (activeConnector=False): no force until it is switched on"))
        name = d.get("name", "") or f"object{o}"
        nPy = len(sc.pyItems)
        counts = _element_counts(sc)
        getattr(self, reader)(sc, o, d, A, B, what, name)
        sc.itemRows[("object", o)] = _new_row(sc, nPy, counts)
        if not active:
            deactivate(sc, sc.itemRows[("object", o)])

    def reread_connector(self, sc, o, d):
        """A connector read again during a solve (bridge.params: a live field or one of its
        markers changed), by the same code that read it before the solve, into a scratch scene
        sharing ``sc``'s bodies.  Returns ``(scratch, row)``: ``row`` its ``itemRows`` entry in
        the scratch scene (``("py", 0)`` or (the force element's name, 0)), None if it connects
        ground to ground.  What the kernel tracks from the first read stays: a torsional
        spring's turns (``keptTurns``)."""
        scratch = ExudynScene(self.mbs)
        scratch.bodies = sc.bodies
        scratch.nodeTypes = sc.nodeTypes
        scratch.keptTurns = {td.objectIndex: td.turns0 for td in sc.torsionData if td.spring is not None}
        self.read_connector(scratch, o, d)
        return scratch, scratch.itemRows.get(("object", o))

    def read_spring_damper(self, sc, o, d, A, B, what, name):
        uf = _userfunction(d, "springForceUserFunction", what)
        if uf is None:
            sc.AddSpringDamper(A.body, A.pos, B.body, B.pos, d["stiffness"], d["damping"],
                               d["referenceLength"], float(d["force"]) - float(d["damping"]) * float(
                                   d.get("velocityOffset", 0.0)), name=name)
        else:
            self._py(sc, pyforces.SpringDamperUF(self.mbs, o, d, A, B, uf))

    def read_cartesian_spring_damper(self, sc, o, d, A, B, what, name):
        uf = _userfunction(d, "springForceUserFunction", what)
        if uf is None:
            sc.AddCartesianSpringDamper(A.body, A.pos, B.body, B.pos, d["stiffness"], d["damping"],
                                        d["offset"], name=name)
        else:
            self._py(sc, pyforces.CartesianSpringDamperUF(self.mbs, o, d, A, B, uf))

    def read_coordinate_spring_damper(self, sc, o, d, A, B, what, name):
        """CObjectConnectorCoordinateSpringDamper: f = k (q_B - q_A - offset) + d (rates)."""
        uf = _userfunction(d, "springForceUserFunction", what)
        if uf is None:
            sc.AddCoordinateSpringDamper(A.body, A.spec, B.body, B.spec, d["stiffness"], d["damping"],
                                         float(d["offset"]) + B.ref - A.ref, name=name)
        else:
            self._py(sc, pyforces.CoordinateSpringDamperUF(self.mbs, o, d, A, B, uf))

    def read_linear_spring_damper(self, sc, o, d, A, B, what, name):
        """CObjectConnectorLinearSpringDamper: along ``A_0 axisMarker0`` (marker 0's orientation)."""
        if _userfunction(d, "springForceUserFunction", what) is not None:
            raise NotCompiled(f"{what}: springForceUserFunction is not supported by exudyn_lie yet; solve with "
                              f"exudyn.SolveDynamic")
        sc.AddLinearSpringDamper(A.body, A.pos, A.rot @ np.asarray(d["axisMarker0"], float), B.body, B.pos,
                                 d["stiffness"], d["damping"], d["offset"],
                                 float(d["force"]) - float(d["damping"]) * float(d.get("velocityOffset", 0.0)),
                                 name=name)

    def read_torsional_spring_damper(self, sc, o, d, A, B, what, name):
        uf = _userfunction(d, "springTorqueUserFunction", what)
        rotA = A.rot @ np.asarray(d.get("rotationMarker0", np.eye(3)), float)
        rotB = B.rot @ np.asarray(d.get("rotationMarker1", np.eye(3)), float)
        dataNode = int(d.get("nodeNumber", -1))
        track = dataNode >= 0      # NodeGenericData: Exudyn's continuous angle of the last step
        angle0 = self.data_coordinate(dataNode) if track else 0.0
        if track and not np.isfinite(angle0):
            raise BridgeError(f"{what}: the angle stored in its NodeGenericData {dataNode} is not finite: "
                              f"{angle0}")
        if uf is None and track:
            # Scene (= Exudyn's law): tau = k (phi - off) + d phidot + torque, -tau z_A on B;
            # Exudyn's velocityOffset vo enters as d (phidot - vo): torque - d vo.  The kernel
            # tracks phi from the principal angle; Exudyn's angle is the branch nearest to the
            # stored one, turns0 turns away: folded into the offset
            phi = _principal_torsion_angle(sc, A, B, rotA, rotB)
            turns0 = int(np.round((angle0 - phi) / (2 * np.pi)))
            # re-read during a solve: the kernel's tracked angle goes on from the first read, so
            # its turns stay (Exudyn's angle = kernel angle + 2 pi turns0 throughout the solve)
            turns0 = sc.keptTurns.get(o, turns0)
            s_ = sc.AddTorsionalSpringDamper(A.body, B.body, rotA=_orthonormal(rotA), rotB=_orthonormal(rotB),
                                             stiffness=d["stiffness"], damping=d["damping"],
                                             offset=float(d["offset"]) - 2 * np.pi * turns0,
                                             torque=float(d["torque"]) - float(d["damping"]) * float(
                                                 d.get("velocityOffset", 0.0)), name=name)
            sc.torsionData.append(TorsionData(o, dataNode, angle0, spring=s_, turns0=turns0))
        else:
            # a user function, or no data node: Exudyn then uses the principal angle in
            # (-pi, pi] (the torque jumps at +-pi), which the compiled spring does not do
            item = pyforces.TorsionalSpringDamperUF(self.mbs, o, d, A, B, rotA, rotB, uf, track, angle0)
            self._py(sc, item)
            if track:
                sc.torsionData.append(TorsionData(o, dataNode, angle0, item=item))

    def read_rigid_body_spring_damper(self, sc, o, d, A, B, what, name):
        uf = _userfunction(d, "springForceTorqueUserFunction", what)
        if _userfunction(d, "postNewtonStepUserFunction", what) is not None:
            raise BridgeError(f"{what}: postNewtonStepUserFunction (switching / data coordinates) is not "
                              f"supported by exudyn_lie")
        rotA = A.rot @ np.asarray(d.get("rotationMarker0", np.eye(3)), float)
        rotB = B.rot @ np.asarray(d.get("rotationMarker1", np.eye(3)), float)
        if uf is None:             # compiled (mbs/forces.rigid_spring_forces: the same law)
            sc.AddRigidBodySpringDamper(A.body, B.body, posA=A.pos, rotA=_orthonormal(rotA), posB=B.pos,
                                        rotB=_orthonormal(rotB), stiffness=np.asarray(d["stiffness"], float),
                                        damping=np.asarray(d["damping"], float),
                                        offset=np.asarray(d["offset"], float), name=name,
                                        intrinsic=bool(d.get("useIntrinsicFormulation", False)))
            return
        self._py(sc, pyforces.RigidBodySpringDamper(self.mbs, o, d, A, B, rotA, rotB, uf))

    def read_rolling_disc_penalty(self, sc, o, d, A, B, what, name):
        """CObjectConnectorRollingDiscPenalty (mbs/rolling_disc_penalty_forces.py): marker 0 the
        plane (ground or a 3D rigid body, normal ``A0 planeNormal``), marker 1 the disc centre
        (axis ``A1 discAxis``); the three data coordinates of its NodeGenericData (slip velocity,
        gap of the last step) start as stored in mbs."""
        if B.body == GROUND:
            raise BridgeError(f"{what}: marker 1 (the disc) is on the ground; Exudyn's rolling disc has the disc "
                              f"on marker 1 and the plane (ground or body) on marker 0")
        n = int(d.get("nodeNumber", -1))
        if not (0 <= n < self.sd.NumberOfNodes()) or self.mbs.GetNode(n)["nodeType"] != "GenericData":
            raise BridgeError(f"{what}: nodeNumber {n} is not a NodeGenericData; Exudyn needs one with 3 data "
                              f"coordinates (slip velocity, gap)")
        data = self.data_coordinates(n)
        if data.shape != (3,) or not np.all(np.isfinite(data)):
            raise BridgeError(f"{what}: its NodeGenericData {n} must hold 3 finite data coordinates (Exudyn's slip "
                              f"velocity and gap), got {data.tolist()}")
        roll = d.get("rollingViscousFriction", d.get("rollingFrictionViscous", 0.0))
        try:
            sc.AddRollingDiscPenalty(
                A.body, B.body, float(d["discRadius"]), float(d["contactStiffness"]), float(d["contactDamping"]),
                dryFriction=np.asarray(d["dryFriction"], float),
                dryFrictionProportionalZone=float(d["dryFrictionProportionalZone"]),
                viscousFriction=np.asarray(d["viscousFriction"], float),
                dryFrictionAngle=float(d["dryFrictionAngle"]), rollingViscousFriction=float(roll),
                useLinearProportionalZone=bool(d["useLinearProportionalZone"]), posA=A.pos,
                planeNormal=A.rotation() @ np.asarray(d["planeNormal"], float), posB=B.pos,
                discAxis=B.rotation() @ np.asarray(d["discAxis"], float), data0=data, name=name)
        except SceneError as e:
            raise BridgeError(f"{what}: {e}") from None
        sc.rollingDiscData.append((o, n))

    def _py(self, sc, item):
        sc.pyItems.append(item)
        for b in item.bodies():
            if b != GROUND:
                sc.pyConnectedBodies.add(b)

    # ------------------------------------------------------------------ loads
    def read_loads(self, sc: ExudynScene):
        mass_prop = {}      # body -> summed constant mass-proportional vector
        mass_prop_loads = []
        for l in range(self.sd.NumberOfLoads()):
            d = self.mbs.GetLoad(l)
            t = d["loadType"]
            what = f"load {l} ('{d.get('name', '')}') Load{t}"
            if t == "Coordinate":
                self.read_coordinate_load(sc, l, d, what)
                continue
            if t not in ("ForceVector", "TorqueVector", "MassProportional"):
                raise NotCompiled(f"{what} is not supported by exudyn_lie; supported loads: "
                                  f"{', '.join(SUPPORTED_LOADS)}")
            lv = np.asarray(d["loadVector"], float)
            if not np.all(np.isfinite(lv)):
                raise BridgeError(f"{what}: loadVector is not finite: {lv}")
            uf = _userfunction(d, "loadVectorUserFunction", what)
            mf = self.marker(d["markerNumber"], what, allow_mass=(t == "MassProportional"))
            if t == "MassProportional" and mf.markerType != "BodyMass":
                raise BridgeError(f"{what}: needs a MarkerBodyMass, got Marker{mf.markerType}")
            bodyFixed = bool(d.get("bodyFixed", False))
            if mf.rot is None and t != "MassProportional" and (t == "TorqueVector" or bodyFixed):
                # Exudyn's Assemble refuses both (a torque needs an orientation marker; a force
                # with bodyFixed "must provide orientation"); set after Assemble, its solvers fail
                raise BridgeError(f"{what}: {'a torque' if t == 'TorqueVector' else 'bodyFixed=True'} needs a "
                                  f"marker with an orientation (MarkerBodyRigid or MarkerNodeRigid), got marker "
                                  f"{mf.index} (Marker{mf.markerType}); Exudyn refuses this combination too")
            if mf.body == GROUND:
                sc.skipped.append((what, "acts on ground"))
                sc.itemRows[("load", l)] = ("ground", -1)
                continue
            name = d.get("name", "") or f"load{l}"
            if uf is not None:
                sc.itemRows[("load", l)] = ("py", len(sc.pyItems))
                sc.pyItems.append(pyforces.LoadUF(self.mbs, l, t, lv, mf, bodyFixed, uf,
                                                  sc.bodies[mf.body].mass, sc.bodies[mf.body].com))
                continue
            Rm = mf.rotation()
            if t == "ForceVector":
                sc.itemRows[("load", l)] = ("load", len(sc.loads))
                sc.AddForce(mf.body, Rm @ lv if bodyFixed else lv, position=mf.pos, bodyFixed=bodyFixed, name=name)
            elif t == "TorqueVector":
                sc.itemRows[("load", l)] = ("load", len(sc.loads))
                sc.AddTorque(mf.body, Rm @ lv if bodyFixed else lv, bodyFixed=bodyFixed, name=name)
            else:
                sc.itemRows[("load", l)] = ("massProportional", -1)
                mass_prop[mf.body] = mass_prop.get(mf.body, np.zeros(3)) + lv
                mass_prop_loads.append(name)
        # a mass-proportional load equal on every body is gravity (energy diagnostics include it)
        vecs = [mass_prop.get(b) for b in range(sc.nBodies)]
        if all(v is not None for v in vecs) and all(np.array_equal(v, vecs[0]) for v in vecs):
            sc.gravity = np.array(vecs[0], float)
        else:
            for b, v in mass_prop.items():
                B = sc.bodies[b]
                sc.AddForce(b, B.mass * v, position=B.com, name=f"massProportional{b}")

    def read_coordinate_load(self, sc, l, d, what):
        """LoadCoordinate: a generalised force ``load`` on a node position coordinate, i.e. the
        world force ``load e_axis`` at the node."""
        load = float(d["load"])
        if not np.isfinite(load):
            raise BridgeError(f"{what}: load is not finite: {load}")
        cm = self.coordinate_marker(d["markerNumber"], what)
        if cm.body == GROUND:
            sc.skipped.append((what, "acts on ground"))
            sc.itemRows[("load", l)] = ("ground", -1)
            return
        uf = _userfunction(d, "loadUserFunction", what)
        if uf is not None:
            sc.itemRows[("load", l)] = ("py", len(sc.pyItems))
            sc.pyItems.append(pyforces.CoordinateLoadUF(self.mbs, l, load, cm, uf))
            return
        if cm.param is not None:        # a node rotation parameter: the generalised force load C (state-dependent)
            sc.itemRows[("load", l)] = ("coordinateLoad", len(sc.coordinateSprings))
            sc.AddCoordinateLoad(cm.body, cm.param, load, name=d.get("name", "") or f"load{l}")
            return
        sc.itemRows[("load", l)] = ("load", len(sc.loads))
        if cm.angle is not None:        # a rotation coordinate: the world torque load d
            sc.AddTorque(cm.body, load * cm.direction, name=d.get("name", "") or f"load{l}")
        else:
            sc.AddForce(cm.body, load * cm.direction, name=d.get("name", "") or f"load{l}")


def _tracked_start(nodeType, p):
    """The parameters a node's tracking starts from (rotation_parameters: the quaternion of a
    RotVecLG's rotation vector or an EP node's own, of the sign given; Rxyz angles)."""
    out = np.zeros(4)
    if nodeType == "RigidBodyRotVecLG":
        t = float(np.linalg.norm(p))
        out[0] = np.cos(0.5 * t)
        out[1:] = p * (np.sin(0.5 * t) / t if t > 0 else 0.5)
    else:
        out[:len(p)] = p
    return out


#: the scene list of every registered compiled force element, by its registered name (the tables of itemRows)
ELEMENT_LISTS = {e.name: e.sceneList for e in ELEMENTS}


def _element_counts(sc):
    """The number of items of every registered compiled force element (mbs/force_elements.py)."""
    return tuple(len(getattr(sc, e.sceneList)) for e in ELEMENTS)


def _new_row(sc, nPy, counts):
    """(table, row) of the item a connector read just added to ``sc``: ``("py", k)`` or (the
    registered force element's name, its row)."""
    if len(sc.pyItems) > nPy:
        return ("py", nPy)
    for e, before, now in zip(ELEMENTS, counts, _element_counts(sc)):
        if now > before:
            return (e.name, before)
    raise AssertionError("connector read without a scene item")


def deactivate(sc, row):
    """An inactive connector: zero force (the scene item's coefficients, or the Python
    item's ``active`` flag)."""
    table, k = row
    if table == "py":
        sc.pyItems[k].active = False
        return
    getattr(sc, ELEMENT_LISTS[table])[k].switch_off()        # the element's own (mbs/scene.py)


def _principal_torsion_angle(sc, A, B, rotA, rotB):
    """Exudyn's principal torsion angle in (-pi, pi] (z Tait-Bryan angle of the relative
    rotation of the two spring frames) in the configuration read."""
    RA = rotA if A.body == GROUND else sc.bodies[A.body].R0 @ rotA
    RB = rotB if B.body == GROUND else sc.bodies[B.body].R0 @ rotB
    Rrel = RA.T @ RB
    return float(np.arctan2(-Rrel[0, 1], Rrel[0, 0]))


def _orthonormal(R):
    """Remove rounding noise (Exudyn stores 1e-16-accurate matrices; Scene wants 1e-8)."""
    R = np.asarray(R, float)
    U, s, Vt = np.linalg.svd(R)
    if np.max(np.abs(s - 1.0)) > 1e-6:
        raise BridgeError(f"rotation matrix is not orthonormal (singular values {s})")
    return U @ Vt


def SceneFromExudyn(mbs, configuration="initial") -> ExudynScene:
    """Read an assembled Exudyn ``mbs`` into an :class:`ExudynScene` (a :class:`Scene`).

    ``configuration``: ``'initial'`` (what a solve starts from), ``'current'``, or
    ``'items'`` (an mbs not assembled yet: the initial values ``mbs.Assemble()`` will set,
    from the item dictionaries; the scene then has no Exudyn AE indices, it is for
    validation).  ``mbs`` is not modified.  Raises :class:`BridgeError` for unsupported
    items."""
    check_system_level(mbs)
    rd = _Reader(mbs, configuration)
    sc = ExudynScene(mbs)
    sc.reader = rd
    sc.configuration = configuration.lower()
    rd.read_nodes(sc)
    rd.read_bodies(sc)
    rd.read_items(sc)
    rd.read_loads(sc)
    sc.aeZero = sorted(set(sc.aeZero))
    if sc.pyItems:
        sc.AddPythonForce(pyforces.combined(sc.pyItems, sc.nBodies), name="exudyn user functions")
    return sc
