"""The one registration of every Exudyn item type the bridge reads.

Each supported item type is registered once, with :func:`register`: its kind (node, object,
marker, load), its type name as in the item dictionary (``GetObject(i)['objectType']``), its
role, what reads it, what it compiles to, and the status of each of its fields during a solve.
Everything else derives from :data:`ITEMS`:

* the reader's lists (``reader.SUPPORTED_NODES / SUPPORTED_OBJECTS / SUPPORTED_MARKERS /
  SUPPORTED_LOADS``, ``BODY_OBJECTS``, ``JOINT_TYPES``, ``JOINT_READERS``,
  ``CONNECTOR_READERS``) and the node write-back registry ``nodes.NODE_KINDS``;
* the field statuses of :mod:`.params` (:data:`FIELDS`) and which changed objects it reads
  again during a solve (the connectors; a moved marker of a joint stops the solve);
* the items that keep a model on the compiled path (:mod:`.evaluated_dispatch`: any other
  type makes Exudyn evaluate the model);
* the list of supported items in docs/USING.md (``python -m exudyn_lie items --readme docs/USING.md``;
  ``tests/test_readme_items.py`` checks it against this registry).

Roles and what they need:

* node ``body``: ``reader`` is the name of its :class:`~.nodes.NodeKind` class in
  :mod:`.nodes`; ``ground`` and ``data`` nodes carry no body;
* object ``ground``; ``body`` with ``nodes`` (the node types it accepts); ``joint`` (``reader``:
  a method of the reader's ``_Reader``, None for the generic ``read_joint``); ``connector``
  (``reader`` method, ``markers``: True if both markers need an orientation, False for
  position markers, ``"coordinate"`` for MarkerNodeCoordinate, ``userFunction``: its user
  function field);
* marker ``position`` (a point, with an orientation or not) or ``coordinate``;
* load ``vector`` (``read_loads``) or ``coordinate``.

This module imports nothing of the package: it is data.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

LIVE, FIXED, REFUSED, INITIAL, IGNORED = "live", "fixed", "refused", "initial", "ignored"

#: the prefix of each kind's full Exudyn name (``Object`` + ``RigidBody``)
PREFIX = {"node": "Node", "object": "Object", "marker": "Marker", "load": "Load"}
ROLES = {"node": ("body", "ground", "data"), "object": ("ground", "body", "joint", "connector"),
         "marker": ("position", "coordinate"), "load": ("vector", "coordinate")}


@dataclass(frozen=True)
class ItemType:
    """One supported Exudyn item type (see the module docstring for the roles)."""
    kind: str
    typeName: str
    role: str
    compiles: str                       # what it becomes (the list in docs/USING.md)
    fields: dict = field(default_factory=dict)      # field -> (status, reason)
    reader: Optional[str] = None
    nodes: tuple = ()
    markers: object = False
    userFunction: Optional[str] = None

    @property
    def name(self):
        """Exudyn's full name: ``ObjectConnectorSpringDamper``."""
        return PREFIX[self.kind] + self.typeName


#: every supported item type, in registration order: (kind, typeName) -> ItemType
ITEMS = {}


def register(kind, typeName, role, compiles, fields, **kw):
    """Register one Exudyn item type (one line per type; see the module docstring)."""
    if role not in ROLES[kind]:
        raise ValueError(f"{kind} {typeName}: role {role!r} is not one of {ROLES[kind]}")
    if (kind, typeName) in ITEMS:
        raise ValueError(f"{kind} {typeName} is registered twice")
    ITEMS[(kind, typeName)] = ItemType(kind, typeName, role, compiles, dict(fields), **kw)
    return ITEMS[(kind, typeName)]


def of(kind, role=None):
    """The registered item types of a kind (and role), in registration order."""
    return [it for it in ITEMS.values() if it.kind == kind and (role is None or it.role == role)]


# ---------------------------------------------------------------- shared field tables
_MARKER_MOVES = "moves the marker: connectors and loads follow it; a joint using the marker stops the solve"
_RIGID_NODE = {
    "referenceCoordinates": (FIXED, "the node's reference frame; change the state with "
                                    "mbs.systemData.SetODE2Coordinates(..., configuration=Current) instead"),
    "initialCoordinates": (INITIAL, "set by Assemble (the initial state)"),
    "initialVelocities": (INITIAL, "set by Assemble (the initial state)"),
}
_JOINT = {
    "markerNumbers": (FIXED, "the joint's bodies"),
    "activeConnector": (FIXED, "the joint's constraint rows are compiled (an inactive joint has none)"),
    "constrainedAxes": (FIXED, "the joint's constraint rows"),
    "rotationMarker0": (FIXED, "the joint frame on marker 0 (a moving joint frame needs its velocity and "
                               "acceleration in the index-1 formulation)"),
    "rotationMarker1": (FIXED, "the joint frame on marker 1"),
}
_COMPILED_ROW = (FIXED, "compiled into a constraint row; a change during a run is not re-read")
_UF_LIVE = (LIVE, "another Python function: live; switching between no function and a function stops the solve "
                  "(compiled item vs Python item)")
_MASS = (FIXED, "compiled mass matrix")
_NODE = (FIXED, "the body's node")

# ---------------------------------------------------------------- nodes
register("node", "RigidBodyRotVecLG", "body", "a rigid body on SE3 or SO3xR3", _RIGID_NODE, reader="RotVecLGNode")
register("node", "RigidBodyEP", "body", "a rigid body on SE3 or SO3xR3 (sign-continuous Euler parameters)",
         dict(_RIGID_NODE, addConstraintEquation=(
             REFUSED, "False is refused: exudyn_lie keeps the Euler parameters on the unit sphere, Exudyn would "
                      "need a user constraint")), reader="EPNode")
register("node", "RigidBodyRxyz", "body", "a rigid body on SE3 or SO3xR3 (continuous Tait-Bryan angles)",
         _RIGID_NODE, reader="RxyzNode")
register("node", "RigidBody2D", "body", "a planar body on SE2 or SO2xR2 (angle tracked over turns)", _RIGID_NODE,
         reader="Rigid2DNode")
register("node", "Point", "body", "a point mass on R3", _RIGID_NODE, reader="PointNode")
register("node", "Point2D", "body", "a point mass on R3 moving in x, y", _RIGID_NODE, reader="Point2DNode")
register("node", "1D", "body", "a point mass on a line (Mass1D) or a rotor (RotationalMass1D)", _RIGID_NODE,
         reader="Node1DNode")
register("node", "PointGround", "ground", "ground (markers on it)",
         {"referenceCoordinates": (LIVE, "moves the markers on the ground node")})
register("node", "GenericData", "data", "data only (a torsional spring's continuous angle, a penalty rolling "
         "disc's slip velocity and gap)", {
    "initialCoordinates": (INITIAL, "a torsional spring's continuous angle, a penalty rolling disc's slip "
                                    "velocity and gap at the start"),
    "numberOfDataCoordinates": (FIXED, "set by Assemble")})

# ---------------------------------------------------------------- bodies
register("object", "Ground", "ground", "ground (reference position and rotation)",
         {k: (LIVE, "moves the markers on the ground: " + _MARKER_MOVES)
          for k in ("referencePosition", "referenceRotation", "referenceHT")})
register("object", "RigidBody", "body", "a body (Scene.AddBody)",
         {"mass": _MASS, "inertia": _MASS, "centerOfMass": _MASS, "nodeNumber": _NODE},
         nodes=("RigidBodyRotVecLG", "RigidBodyEP", "RigidBodyRxyz"))
register("object", "RigidBody2D", "body", "a planar body (Scene.AddBody2D)",
         {"mass": _MASS, "inertia": _MASS, "centerOfMass": _MASS, "nodeNumber": _NODE}, nodes=("RigidBody2D",))
register("object", "MassPoint", "body", "a point mass (Scene.AddPointMass)", {"mass": _MASS, "nodeNumber": _NODE},
         nodes=("Point",))
register("object", "MassPoint2D", "body", "a point mass in x, y (Scene.AddPointMass)",
         {"mass": _MASS, "nodeNumber": _NODE}, nodes=("Point2D",))
register("object", "Mass1D", "body", "a point mass on its line (Scene.AddPointMass)", {
    "mass": _MASS, "nodeNumber": _NODE,
    "referencePosition": (FIXED, "the line the mass moves on (compiled point mass)"),
    "referenceRotation": (FIXED, "the line the mass moves on (compiled point mass)")}, nodes=("1D",))
register("object", "RotationalMass1D", "body", "a rotor about its axis (Scene.AddRotor)", {
    "inertia": _MASS, "nodeNumber": _NODE,
    "referencePosition": (FIXED, "the rotor's axis (compiled rotor)"),
    "referenceRotation": (FIXED, "the rotor's axis (compiled rotor)")}, nodes=("1D",))

# ---------------------------------------------------------------- joints
register("object", "JointSpherical", "joint", "joint rows (any constrainedAxes)",
         {k: v for k, v in _JOINT.items() if not k.startswith("rotationMarker")})
register("object", "JointRevoluteZ", "joint", "joint rows", {k: v for k, v in _JOINT.items() if k != "constrainedAxes"})
register("object", "JointPrismaticX", "joint", "joint rows",
         {k: v for k, v in _JOINT.items() if k != "constrainedAxes"})
register("object", "JointGeneric", "joint", "joint rows (any constrainedAxes, marker frames)", dict(_JOINT, **{
    "alternativeConstraints": (REFUSED, "True is refused (default rotation constraints only)"),
    "offsetUserFunction": (REFUSED, "a moving joint offset is refused"),
    "offsetUserFunction_t": (REFUSED, "a moving joint offset is refused"),
    "offsetUserFunctionParameters": (IGNORED, "read only by offsetUserFunction, which is refused")}))
register("object", "JointRevolute2D", "joint", "joint rows (planar)",
         {k: _JOINT[k] for k in ("markerNumbers", "activeConnector")})
register("object", "JointPrismatic2D", "joint", "joint rows (planar)", {
    **{k: _JOINT[k] for k in ("markerNumbers", "activeConnector")},
    "axisMarker0": (FIXED, "the joint's constraint rows (its axis on marker 0)"),
    "normalMarker1": (FIXED, "the joint's constraint rows (its normal on marker 1)"),
    "constrainRotation": (REFUSED, "False is refused (the rotation row is compiled)")})
register("object", "ConnectorCoordinate", "joint", "a coordinate row (mbs/coordinate_rows.py)", {
    "markerNumbers": (FIXED, "the constrained coordinates"), "factor1": _COMPILED_ROW,
    "offset": (LIVE, "moved by a pre- or post-step function, the row follows it over the step "
                     "(bridge/moving_offsets.py); a velocity-level row's offset is fixed"),
    "activeConnector": (FIXED, "the constraint row is compiled (an inactive one has none)"),
    "velocityLevel": (FIXED, "the kind of the compiled constraint row (position or velocity level)"),
    # a moving offset enters the row's right-hand side with its time derivatives (mbs/row_drives.py);
    # Exudyn's index-3 solve jumps to a new offset function, the index-1 rows cannot (it would need a
    # projection of the state), so a change stops the solve
    "offsetUserFunction": (FIXED, "the moving offset of a position-level row, evaluated in Python at every "
                                  "stage; ignored with velocityLevel=True, as in Exudyn"),
    "offsetUserFunction_t": (FIXED, "the moving offset of a velocity-level row, evaluated in Python at every "
                                    "stage; ignored with velocityLevel=False, as by Exudyn's index-3 solve")},
         reader="read_coordinate_constraint")
register("object", "ConnectorDistance", "joint", "a distance row (mbs/distance_rows.py)", {
    "markerNumbers": (FIXED, "the constrained points"), "distance": _COMPILED_ROW,
    "activeConnector": (FIXED, "the constraint row is compiled (an inactive one has none)")},
         reader="read_distance_constraint")
register("object", "JointRollingDisc", "joint", "velocity-level rolling rows (mbs/rolling_disc_rows.py)", {
    **{k: _JOINT[k] for k in ("markerNumbers", "activeConnector", "constrainedAxes")},
    **{k: _COMPILED_ROW for k in ("discRadius", "discAxis", "planeNormal")}}, reader="read_rolling_disc")

# ---------------------------------------------------------------- connectors
register("object", "ConnectorSpringDamper", "connector",
         "a compiled spring (mbs/forces.py); with its user function, a Python force", {
             **{k: (LIVE, "force law") for k in ("stiffness", "damping", "referenceLength", "force",
                                                 "velocityOffset")},
             "activeConnector": (LIVE, "switches the force off and on"),
             "springForceUserFunction": _UF_LIVE, "markerNumbers": (FIXED, "the connected bodies")},
         reader="read_spring_damper", markers=False, userFunction="springForceUserFunction")
register("object", "ConnectorCartesianSpringDamper", "connector",
         "a compiled spring (mbs/forces.py); with its user function, a Python force", {
             **{k: (LIVE, "force law") for k in ("stiffness", "damping", "offset")},
             "activeConnector": (LIVE, "switches the force off and on"),
             "springForceUserFunction": _UF_LIVE, "markerNumbers": (FIXED, "the connected bodies")},
         reader="read_cartesian_spring_damper", markers=False, userFunction="springForceUserFunction")
register("object", "ConnectorRigidBodySpringDamper", "connector",
         "a compiled spring (mbs/forces.py); with its user function, a Python force", {
             **{k: (LIVE, "force law") for k in ("stiffness", "damping", "offset", "rotationMarker0",
                                                 "rotationMarker1", "useIntrinsicFormulation",
                                                 "springForceTorqueUserFunction")},
             "activeConnector": (LIVE, "switches the force off and on"),
             "markerNumbers": (FIXED, "the connected bodies"),
             "postNewtonStepUserFunction": (REFUSED, "acts in Exudyn's discontinuous iteration, which exudyn_lie "
                                                     "replaces"),
             "nodeNumber": (IGNORED, "data coordinates read only by postNewtonStepUserFunction, which is refused")},
         reader="read_rigid_body_spring_damper", markers=True, userFunction="springForceTorqueUserFunction")
register("object", "ConnectorTorsionalSpringDamper", "connector",
         "a compiled spring (mbs/forces.py), continuing from its data node's angle; with its user function or "
         "without a data node, a Python force", {
             **{k: (LIVE, "torque law") for k in ("stiffness", "damping", "offset", "torque", "velocityOffset",
                                                  "rotationMarker0", "rotationMarker1")},
             "activeConnector": (LIVE, "switches the torque off and on"),
             "springTorqueUserFunction": _UF_LIVE, "markerNumbers": (FIXED, "the connected bodies"),
             "nodeNumber": (FIXED, "the data node of the continuous angle")},
         reader="read_torsional_spring_damper", markers=True, userFunction="springTorqueUserFunction")
register("object", "ConnectorCoordinateSpringDamper", "connector",
         "a compiled spring (mbs/coordinate_forces.py); with its user function, a Python force", {
             **{k: (LIVE, "force law") for k in ("stiffness", "damping", "offset")},
             "activeConnector": (LIVE, "switches the force off and on"),
             "springForceUserFunction": (FIXED, "compiled item or Python item, chosen at the start"),
             "markerNumbers": (FIXED, "the connected coordinates")},
         reader="read_coordinate_spring_damper", markers="coordinate", userFunction="springForceUserFunction")
register("object", "ConnectorLinearSpringDamper", "connector", "a compiled spring (mbs/linear_spring_forces.py)", {
    **{k: (LIVE, "force law") for k in ("stiffness", "damping", "axisMarker0", "offset", "velocityOffset", "force")},
    "activeConnector": (LIVE, "switches the force off and on"),
    "springForceUserFunction": (REFUSED, "a user function is refused"),
    "markerNumbers": (FIXED, "the connected bodies")},
         reader="read_linear_spring_damper", markers=True, userFunction="springForceUserFunction")
register("object", "ConnectorRollingDiscPenalty", "connector",
         "a compiled contact and friction law with data coordinates (mbs/rolling_disc_penalty_forces.py)", {
    **{k: (LIVE, "contact and friction law (its compiled row is rewritten)")
       for k in ("discRadius", "discAxis", "planeNormal", "dryFrictionAngle", "contactStiffness", "contactDamping",
                 "dryFriction", "dryFrictionProportionalZone", "viscousFriction", "rollingViscousFriction",
                 "useLinearProportionalZone")},
    "activeConnector": (LIVE, "switches the contact forces off and on (an inactive disc keeps its data "
                              "coordinates, as in Exudyn)"),
    "markerNumbers": (FIXED, "the disc and the plane"),
    "nodeNumber": (FIXED, "the data node (slip velocity and gap of the last step)")},
         reader="read_rolling_disc_penalty", markers=True)

# ---------------------------------------------------------------- markers
register("marker", "BodyRigid", "position", "a point and frame on a body",
         {"localHT": (LIVE, _MARKER_MOVES), "localPosition": (LIVE, _MARKER_MOVES),
          "bodyNumber": (FIXED, "the marker's body")})
register("marker", "BodyPosition", "position", "a point on a body",
         {"localPosition": (LIVE, _MARKER_MOVES), "bodyNumber": (FIXED, "the marker's body")})
register("marker", "NodeRigid", "position", "a point and frame on a node",
         {"localHT": (LIVE, _MARKER_MOVES), "nodeNumber": (FIXED, "the marker's node")})
register("marker", "NodePosition", "position", "a node's position", {"nodeNumber": (FIXED, "the marker's node")})
register("marker", "BodyMass", "position", "a body's mass (mass-proportional loads)",
         {"bodyNumber": (FIXED, "the marker's body")})
register("marker", "NodeCoordinate", "coordinate", "a position or rotation coordinate",
         {"nodeNumber": (FIXED, "the marker's node"), "coordinate": (FIXED, "the marker's coordinate")})
register("marker", "NodeRotationCoordinate", "coordinate", "in velocity-level coordinate constraints: the "
                                                           "node's world angular velocity about axis k",
         {"nodeNumber": (FIXED, "the marker's node"), "rotationCoordinate": (FIXED, "the marker's axis")})

# ---------------------------------------------------------------- loads
register("load", "ForceVector", "vector", "a compiled load; with its user function, a Python force", {
    "loadVector": (LIVE, "the force"), "bodyFixed": (LIVE, "the force's frame"),
    "loadVectorUserFunction": _UF_LIVE, "markerNumber": (FIXED, "the loaded body")})
register("load", "TorqueVector", "vector", "a compiled load; with its user function, a Python force", {
    "loadVector": (LIVE, "the torque"), "bodyFixed": (LIVE, "the torque's frame"),
    "loadVectorUserFunction": _UF_LIVE, "markerNumber": (FIXED, "the loaded body")})
register("load", "MassProportional", "vector", "gravity when equal on every body, else compiled loads; with its "
                                               "user function, a Python force", {
    "loadVector": (LIVE, "with a loadVectorUserFunction (a Python item); a constant one is compiled as "
                         "gravity, and a change stops the solve"),
    "loadVectorUserFunction": _UF_LIVE, "markerNumber": (FIXED, "the loaded body")})
register("load", "Coordinate", "coordinate", "a compiled load on the coordinate; with its user function, a "
                                             "Python force", {
    "load": (LIVE, "the generalised force on the coordinate"), "loadUserFunction": _UF_LIVE,
    "markerNumber": (FIXED, "the loaded coordinate")})


#: status and reason of every field of every supported Exudyn item type, keyed by
#: ``(kind, type)`` with the type as in the item dictionary (``GetObject(i)['objectType']``)
FIELDS = {key: it.fields for key, it in ITEMS.items()}


def supported_names(kind):
    """Full Exudyn names of the supported types of a kind (``ObjectRigidBody``, ...)."""
    return tuple(it.name for it in of(kind))


def readme_lines():
    """The list of supported items (docs/USING.md), one table row per registered type."""
    title = {"node": "nodes", "object": "objects", "marker": "markers", "load": "loads"}
    out = ["| Exudyn item | kind | what exudyn_lie makes of it |", "|---|---|---|"]
    for kind in PREFIX:
        for it in of(kind):
            out.append(f"| `{it.name}` | {it.role} {title[kind][:-1]} | {it.compiles} |")
    return out
