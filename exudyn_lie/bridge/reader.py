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
  joint frame ``marker localHT rotation @ rotationMarker`` (Exudyn's equations, those of
  ``ObjectJointGeneric``, = the kernel's joint rows, row by row, see :func:`joint_ae_map`);
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

The readers of joints and constraints are in :mod:`.reader_joints`, of connectors and loads in
:mod:`.reader_forces` (parts of one reader class), what they share in :mod:`.reader_common`.

``configuration='items'`` reads an mbs that is not assembled yet from its item
dictionaries (the initial values ``mbs.Assemble()`` will set): ``SolveDynamic`` validates
the model that way before it assembles anything.
"""
from __future__ import annotations

from typing import List

import numpy as np

from ..mbs.scene import GROUND, AngleCoordinate, RotationParameterCoordinate, Scene, SceneError, frame_with_axis
from . import items, pyforces
from .nodes import NODE_KINDS
from .reader_common import (BODY_OBJECTS, BridgeError, CONNECTOR_TYPES, CoordinateMarker, JOINT_READERS,
                           JOINT_TYPES, JointInfo, MarkerFrame, NotCompiled, POSITION_MARKERS, ROTOR_BODIES,
                           SUPPORTED_NODES, SUPPORTED_OBJECTS, TorsionData, _ht, _inertia_matrix,
                           _orthonormal, _tracked_start)
from .reader_common import (CONNECTOR_READERS, SUPPORTED_LOADS, SUPPORTED_MARKERS,  # noqa: F401 (re-exported)
                           _userfunction)
from .reader_joints import JointReaders
from .reader_forces import ForceReaders, deactivate  # noqa: F401 (re-exported)


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

#: the mbs-level user functions that the Exudyn-evaluated path honours (bridge/evaluated.py): why
EVALUATED_MBS_FUNCTIONS = {
    "PostNewtonUserFunction": "which Exudyn's PostNewton calls after each step of its discontinuous iteration",
    "PreNewtonResidualUserFunction": "which Exudyn calls before each evaluation of the model",
    "SystemJacobianUserFunction": "which Exudyn adds to the Jacobian of an implicit method",
}


def mbs_user_function(mbs, name):
    """``mbs.Get<name>()`` if a function is set (Exudyn gives ``{'function': f, 'type': ...}``, and 0
    when none is), else None."""
    fn = getattr(mbs, "Get" + name, None)
    uf = fn() if fn is not None else 0
    return None if uf is None or (isinstance(uf, (int, float)) and uf == 0) else uf


def check_system_level(mbs, unhonoured=None, generalContact=False):
    """Refuse what is not an item but changes the model: GeneralContact (unless ``generalContact``:
    the Exudyn-evaluated path, bridge/general_contact.py) and mbs-level user functions that
    exudyn_lie does not honour (``unhonoured``: name -> why; default ``UNHONOURED_MBS_FUNCTIONS``)
    (reads only; raises BridgeError)."""
    n = int(mbs.NumberOfGeneralContacts())
    if n > 0 and not generalContact:
        raise BridgeError(f"mbs has {n} GeneralContact(s) (mbs.AddGeneralContact): the compiled kernel does not "
                          f"have GeneralContact; evaluation='auto' (the default) or 'exudyn' lets Exudyn evaluate "
                          f"the model")
    for name, why in (UNHONOURED_MBS_FUNCTIONS if unhonoured is None else unhonoured).items():
        if mbs_user_function(mbs, name) is not None:
            if name in EVALUATED_MBS_FUNCTIONS:
                # the Exudyn-evaluated path honours it (the reason it is taken)
                raise NotCompiled(f"mbs has a {name} (mbs.Set{name}), {EVALUATED_MBS_FUNCTIONS[name]} (on the "
                                  f"Exudyn-evaluated path: evaluation='auto' or 'exudyn'; or exudyn.SolveDynamic)")
            raise BridgeError(f"mbs has a {name} (mbs.Set{name}): exudyn_lie does not call it ({why}); "
                              f"solve with exudyn.SolveDynamic, or remove it with mbs.Set{name}(0)")


class _Reader(JointReaders, ForceReaders):
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
        self.ground = {}          # object index -> (pos, rot) of ObjectGround (and mass points on ground nodes)
        self.groundMassPoints = set()     # ObjectMassPoint(2D) on a NodePointGround: no coordinates
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
                if nt == "PointGround" and t in ("MassPoint", "MassPoint2D"):
                    # Exudyn accepts a mass point on a ground node: it has no coordinates, so it
                    # stays at the node's reference position; its markers are ground points
                    gp = np.asarray(self.mbs.GetNode(n)["referenceCoordinates"], float).reshape(-1)[:3]
                    self.ground[o] = (np.pad(gp, (0, 3 - len(gp))), np.eye(3))
                    self.groundMassPoints.add(o)
                    continue
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
            if d["objectType"] not in BODY_OBJECTS or o in self.ground:
                continue
            n = int(d["nodeNumber"])
            b = self._add_body(sc, o, d, n, states[n], angles.get(n))
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

    def _add_body(self, sc, o, d, n, state, angle):
        """The scene body of object ``o`` (item dictionary ``d``) on node ``n`` with its state
        ``(R, r, omega, vel)`` read from the node (``angle``: a 2D body's or rotor's total angle)."""
        R, r, om, vel = state
        label = d.get("name", "") or f"object{o}"
        if d["objectType"] == "RigidBody2D" and float(d["inertia"]) == 0.0:
            # a massless rotation (finite segments joined by rotational springs): the kernel
            # inverts each body's mass; Exudyn's whole KKT matrix can be regular
            raise NotCompiled(f"object {o} ('{d.get('name', '')}') ObjectRigidBody2D: inertia = 0 is not supported "
                              f"by the compiled kernel (it inverts each body's mass matrix)")
        try:
            if d["objectType"] == "RigidBody2D":
                # inertia about the node (Exudyn's reference point); Exudyn's 2D bodies take no
                # force or reaction off the plane, as the kernel's planar body
                b = sc.AddBody2D(mass=float(d["mass"]), inertia=float(d["inertia"]), position=r[:2],
                                 angle=angle, omega=float(om[2]),
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
                                position=origin, angle=angle, omega=float(om[2]), name=label)
            elif d["objectType"] != "RigidBody":
                b = sc.AddPointMass(float(d.get("mass", d.get("physicsMass"))), r0=r, vel0=vel, name=label,
                                    freeDirections=np.diag([1.0, 1.0, float(d["objectType"] == "MassPoint")]))
            else:
                b = sc.AddBody(mass=float(d["mass"]), inertia=_inertia_matrix(d["inertia"]),
                               com=np.asarray(d.get("centerOfMass", [0, 0, 0]), float), R0=_orthonormal(R),
                               r0=r, omega0=om, vel0=vel, name=label)
        except SceneError as e:
            raise BridgeError(f"object {o} Object{d['objectType']}: {e}") from None
        return b

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
                if o in self.groundMassPoints:
                    raise BridgeError(f"{what}: marker {m} (Marker{t}) is on object {o} (Object"
                                      f"{self.objects[o]['objectType']} on a NodePointGround), which has no "
                                      f"coordinates; Exudyn's solver fails on it too; put the marker on the node "
                                      f"(MarkerNodePosition)")
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

    def coordinate_marker(self, m, what, velocityLevel=False):
        """(body, position axis, reference value) of a MarkerNodeCoordinate: the marker value
        is the node's current coordinate ``p[axis] - reference`` (0 on a ground node); in a
        velocity-level row (``velocityLevel``) also a MarkerNodeRotationCoordinate."""
        m = int(m)
        if not 0 <= m < self.sd.NumberOfMarkers():
            raise BridgeError(f"{what}: marker {m} does not exist")
        d = self.mbs.GetMarker(m)
        if d["markerType"] == "NodeRotationCoordinate":
            return self.rotation_coordinate_marker(m, d, what, velocityLevel)
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
        param = getattr(NODE_KINDS.get(nt), "parametrisation", None)
        if param is not None and npos <= k < npos + nrot:
            # a rotation parameter of a 3D rigid node: Exudyn's coordinate (value, rate and
            # Jacobian as CMarkerNodeCoordinate defines them, mbs/node_coordinates.py: the value on
            # the branch Exudyn's continuous integration reaches, the Jacobian e_k on the node's
            # velocity coordinates, the local omega for RotVecLG, mbs/oblique_solve.py)
            qref = np.asarray(self.mbs.GetNode(n)["referenceCoordinates"], float).reshape(-1)
            total = qref[npos:npos + nrot] + self.q[self.node_ltg(n)[npos:npos + nrot]]
            return CoordinateMarker(m, self.rigidNodeBody[n], np.zeros(3), float(qref[k]),
                                    param=RotationParameterCoordinate(param, k - npos),
                                    paramPrev=_tracked_start(param, total))
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

    def rotation_coordinate_marker(self, m, d, what, velocityLevel):
        """A MarkerNodeRotationCoordinate (CMarkerNodeRotationCoordinate::ComputeMarkerData): its
        rate is component k (``rotationCoordinate``) of the node's world angular velocity, and its
        Jacobian that rate's, at both levels.  In a velocity-level row that is the rate of the
        kernel's rotation coordinate about ``d = e_k``, ``(R^T e_k) . omega`` (mbs/coordinate_angles.py,
        a frame whose third column is e_k), exactly.  Its position-level value is the Tait-Bryan (xyz)
        angle k of the node's rotation in (-pi, pi], not tracked over turns, whose gradient is not that
        Jacobian (for k = 0, 1 not an angle about a fixed axis at all): not compiled."""
        n, k = int(d["nodeNumber"]), int(d["rotationCoordinate"])
        nt = self.mbs.GetNode(n)["nodeType"]
        if nt == "PointGround":              # value and rate 0 at both levels, no Jacobian: ground
            return CoordinateMarker(m, GROUND, np.eye(3)[min(max(k, 0), 2)], 0.0, markerType="NodeRotationCoordinate")
        if not velocityLevel:
            raise NotCompiled(f"{what}: marker {m} (MarkerNodeRotationCoordinate) at position level: Exudyn's value is "
                              f"the Tait-Bryan angle {k} of node {n}'s rotation in (-pi, pi], which exudyn_lie compiles "
                              f"only as a rate, in velocity-level ObjectConnectorCoordinate rows")
        if not 0 <= k < 3:
            raise BridgeError(f"{what}: marker {m} (MarkerNodeRotationCoordinate) has rotationCoordinate {k}; it "
                              f"must be 0, 1 or 2 (the world axis)")
        axis = np.eye(3)[k]
        if n not in self.rigidNodeBody or nt not in ("RigidBodyRotVecLG", "RigidBodyEP", "RigidBodyRxyz"):
            # (Exudyn's Assemble refuses it on nodes without an orientation, NodeRigidBody2D among them)
            raise BridgeError(f"{what}: marker {m} (MarkerNodeRotationCoordinate) is on node {n} of type Node{nt}; "
                              f"exudyn_lie takes it on the rigid-body nodes of ObjectRigidBody")
        return CoordinateMarker(m, self.rigidNodeBody[n], axis, 0.0, markerType="NodeRotationCoordinate",
                                angle=AngleCoordinate(frame_with_axis(axis, 2), 0.0))


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
