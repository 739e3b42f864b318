"""What the Exudyn-evaluated path accepts (:func:`check_model`) and what its algebraic
equations are: the rows of coordinate constraints at velocity level, of offsets moved by
parameters, the rows whose velocity level and eta come from the position level, the nodes'
own rows (a part of :mod:`.evaluated`)."""
from __future__ import annotations

import numpy as np

from .moving_offsets import offset_objects
from .reader import BridgeError, _userfunction

#: node types whose coordinates are Lie group elements (velocities are not the coordinates' rates)
LIE_GROUP_NODES = ("RigidBodyRotVecLG",)
#: node types this path cannot integrate, with what to do
REFUSED_NODES = {
    "GenericAE": "its algebraic coordinates are not Lagrange multipliers of an index-1 solve",
}
#: object types whose constraints are at velocity level (nonholonomic): Exudyn's Jacobian of their
#: rows is w.r.t. the velocities (C_qdot), and they have no position-level residual
VELOCITY_LEVEL_OBJECTS = ("JointRollingDisc", "JointRollingDisc2D")


def _describe_object(mbs, o, d=None):
    d = mbs.GetObject(o) if d is None else d
    return f"object {o} ('{d.get('name', '')}') Object{d['objectType']}"


def check_model(mbs):
    """Refuse what this path cannot integrate, naming the item (reads only)."""
    sd = mbs.systemData
    for n in range(sd.NumberOfNodes()):
        d = mbs.GetNode(n)
        t = d["nodeType"]
        if t in REFUSED_NODES:
            raise BridgeError(f"node {n} ('{d.get('name', '')}') Node{t}: {REFUSED_NODES[t]}; exudyn_lie cannot "
                              f"integrate it; solve this model with exudyn.SolveDynamic")
        if "LG" in t and t not in LIE_GROUP_NODES:
            raise BridgeError(f"node {n} ('{d.get('name', '')}') Node{t}: a Lie group node whose velocities are not "
                              f"the rates of its coordinates; exudyn_lie updates only NodeRigidBodyRotVecLG on a group; "
                              f"use NodeRigidBodyRotVecLG or solve with exudyn.SolveDynamic")
    for n in range(sd.NumberOfNodes()):
        d = mbs.GetNode(n)
        for key in ("referenceCoordinates", "initialCoordinates", "initialVelocities", "initialCoordinates_t"):
            if key in d and not np.all(np.isfinite(np.asarray(d[key], float))):
                raise BridgeError(f"node {n} ('{d.get('name', '')}') Node{d['nodeType']}: {key} are not finite: "
                                  f"{d[key]}")
    for k in range(sd.NumberOfLoads()):
        d = mbs.GetLoad(k)
        for key in ("loadVector", "load"):
            if key in d and not callable(d[key]) and not np.all(np.isfinite(np.asarray(d[key], float))):
                raise BridgeError(f"load {k} ('{d.get('name', '')}') Load{d['loadType']}: {key} is not finite: "
                                  f"{d[key]}")
    for o in range(sd.NumberOfObjects()):
        d = mbs.GetObject(o)
        t = d["objectType"]
        if t == "ConnectorCoordinate" and d.get("activeConnector", True) and _rotvec_coordinate_marker(mbs, d):
            # Exudyn's C_q on a RotVecLG rotation coordinate is e_k on the local omega, not the
            # gradient of theta_k: this path's symmetric solve with Exudyn's C_q would hold the
            # velocity-level omega_k, not theta_k (the compiled kernel integrates Exudyn's model,
            # mbs/oblique_solve.py)
            raise BridgeError(f"{_describe_object(mbs, o, d)}: a constraint on a rotation coordinate of a "
                              f"NodeRigidBodyRotVecLG is not supported when Exudyn evaluates the model (the model has "
                              f"items the compiled kernel does not have, or evaluation='exudyn'); solve with "
                              f"exudyn.SolveDynamic, or use a NodeRigidBodyEP / Rxyz node")
        if t == "JointSliding2D" and d.get("activeConnector", True) and d.get("useClassicalFormulation", True):
            # Exudyn's ComputeAlgebraicEquations raises 'velocityLevel not possible for
            # useClassicalFormulation': this path takes eta from the velocity level
            raise BridgeError(f"{_describe_object(mbs, o, d)}: useClassicalFormulation=True (Exudyn's default) has no "
                              f"velocity-level equation in Exudyn, which exudyn_lie's index-1 solve needs for the "
                              f"acceleration term; solve this model with exudyn.SolveDynamic")
        if d.get("velocityLevel", False) is True and d.get("activeConnector", True) and t != "ConnectorCoordinate":
            raise BridgeError(f"{_describe_object(mbs, o, d)}: velocityLevel=True is not supported by exudyn_lie (its "
                              f"index-1 solve needs position-level constraints); use velocityLevel=False or solve "
                              f"with exudyn.SolveDynamic")


def coordinate_constraint_rows(mbs):
    """The rows that need more than Exudyn's evaluation (active ones): ``(velocity-level AE rows,
    [(AE row, offset function, label)])``: the rows of nonholonomic joints
    (:data:`VELOCITY_LEVEL_OBJECTS`) and of velocity-level ObjectConnectorCoordinates, and the
    moving offsets of position-level ones.  A velocity-level row's
    Jacobian is Exudyn's ``C_qdot`` (``ComputeJacobianAE`` with the ODE2_t factor), its
    position-level residual does not exist (the initial position check skips it).  A
    position-level row with an ``offsetUserFunction`` and no ``offsetUserFunction_t``: Exudyn's
    velocity-level equation (CObjectConnectorCoordinate::ComputeAlgebraicEquations) leaves the
    offset's rate out, so its rate and acceleration are added here (mbs/row_drives.py's central
    differences; with an ``offsetUserFunction_t`` Exudyn's equation holds it, as its doc asks)."""
    from .pyforces_coordinates import OffsetUserFunction
    sd = mbs.systemData
    vel, moving = [], []
    for o in range(sd.NumberOfObjects()):
        d = mbs.GetObject(o)
        if d["objectType"] in VELOCITY_LEVEL_OBJECTS and d.get("activeConnector", True):
            vel += [int(r) for r in sd.GetObjectLTGAE(o)]
            continue
        if d["objectType"] != "ConnectorCoordinate" or not d.get("activeConnector", True):
            continue
        rows = [int(r) for r in sd.GetObjectLTGAE(o)]
        if d.get("velocityLevel", False):
            vel += rows
            continue
        what = _describe_object(mbs, o, d)
        uf = _userfunction(d, "offsetUserFunction", what, evaluated=True)
        if uf is not None and _userfunction(d, "offsetUserFunction_t", what, evaluated=True) is None:
            fn = OffsetUserFunction(mbs, o, d, uf, "offsetUserFunction")
            moving += [(r, fn, fn.label) for r in rows]
    return np.array(vel, np.int64), moving


def parameter_offset_rows(mbs):
    """``[(object, AE rows, label)]`` of the ObjectConnectorCoordinates whose ``offset`` a
    user function may move during the run (bridge/moving_offsets.py)."""
    sd = mbs.systemData
    return [(o, [int(r) for r in sd.GetObjectLTGAE(o)], label)
            for o, label in offset_objects(mbs, lambda o, d: _describe_object(mbs, o, d))]


def position_derived_rows(mbs):
    """The AE rows whose velocity-level equation in Exudyn is not the time derivative of the
    position-level one, so that ``g_v`` and ``eta`` must come from the position level:
    ``(rows, every)``.

    * ``ObjectJointGeneric`` with an ``offsetUserFunction``: its velocity-level equation
      (CObjectJointGeneric::ComputeAlgebraicEquations, ``velocityLevel``) leaves the offset
      out altogether, its translation and its rotation (``A0all`` without the offset's
      RotXYZ), so it holds the joint at the offset's value at t = 0 at velocity level while
      Exudyn's index-3 solve holds the moving offset;
    * ``every``: the model has a GenericJoint with ``offsetUserFunction_t``, for which
      Exudyn's velocity-level call raises ``offsetUserFunction_t not implemented for
      velocity level constraints`` for the whole system: every row's ``g_v`` and ``eta``
      then come from the position level (velocity-level rows are refused: they have none).
    """
    sd = mbs.systemData
    rows, every = [], False
    for o in range(sd.NumberOfObjects()):
        d = mbs.GetObject(o)
        if d["objectType"] != "JointGeneric" or not d.get("activeConnector", True):
            continue
        what = _describe_object(mbs, o, d)
        if _userfunction(d, "offsetUserFunction_t", what, evaluated=True) is not None:
            every = True
        if _userfunction(d, "offsetUserFunction", what, evaluated=True) is not None:
            rows += [int(r) for r in sd.GetObjectLTGAE(o)]
    if every:
        vel = [o for o in range(sd.NumberOfObjects()) if mbs.GetObject(o).get("velocityLevel", False) is True
               and mbs.GetObject(o).get("activeConnector", True)]
        if vel:
            raise BridgeError(f"{_describe_object(mbs, vel[0])} is a velocity-level constraint, and the model has an "
                              f"ObjectJointGeneric with offsetUserFunction_t, for which Exudyn cannot evaluate the "
                              f"velocity-level equations; exudyn_lie cannot integrate the two together: remove "
                              f"offsetUserFunction_t (the position-level offsetUserFunction is enough) or solve with "
                              f"exudyn.SolveDynamic")
        rows = list(range(int(sd.AEsize())))
    return np.array(sorted(set(rows)), np.int64), every


def node_rows(mbs):
    """The AE rows of the nodes' own equations (a NodeRigidBodyEP's ``|p|^2 = 1``)."""
    sd = mbs.systemData
    out = []
    for n in range(sd.NumberOfNodes()):
        out += [int(r) for r in sd.GetNodeLTGAE(n)]
    return np.array(out, np.int64)


def _rotvec_coordinate_marker(mbs, d):
    """True if a marker of the item is a MarkerNodeCoordinate on a rotation coordinate (3..5)
    of a NodeRigidBodyRotVecLG."""
    for m in d.get("markerNumbers", []):
        md = mbs.GetMarker(int(m))
        if md["markerType"] == "NodeCoordinate" and int(md["coordinate"]) >= 3:
            if mbs.GetNode(int(md["nodeNumber"]))["nodeType"] == "RigidBodyRotVecLG":
                return True
    return False
