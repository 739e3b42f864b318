"""Reading Exudyn's connectors and loads into the scene's force elements and Python
items (a part of :class:`~.reader._Reader`): spring-dampers of every kind, the penalty
rolling disc, loads; and the bookkeeping of ``sc.itemRows`` that :mod:`.params` uses to
re-read single items during a solve."""
from __future__ import annotations

import numpy as np

from ..mbs.force_elements import ELEMENTS
from ..mbs.scene import GROUND, SceneError
from . import pyforces, pyforces_coordinates
from .reader_common import (BridgeError, CONNECTOR_READERS, NotCompiled, SUPPORTED_LOADS, TorsionData,
                           _orthonormal, _userfunction)


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


class ForceReaders:
    """The connector and load readers of :class:`~.reader._Reader`."""

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
        from .reader import ExudynScene
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
        """CObjectConnectorCoordinateSpringDamper: f = k (q_B - q_A - offset) + d (rates), Exudyn's
        LHS ``J_B^T f - J_A^T f`` (Exudyn 1.13.6 has no friction parameters in it) ->
        Scene.AddCoordinateSpringDamper (mbs/coordinate_forces.py)."""
        uf = _userfunction(d, "springForceUserFunction", what)
        if uf is None:
            sc.AddCoordinateSpringDamper(A.body, A.spec, B.body, B.spec, d["stiffness"], d["damping"],
                                         float(d["offset"]) + B.ref - A.ref, name=name)
        else:
            self._py(sc, pyforces_coordinates.CoordinateSpringDamperUF(self.mbs, o, d, A, B, uf))

    def read_linear_spring_damper(self, sc, o, d, A, B, what, name):
        """CObjectConnectorLinearSpringDamper: along ``A_0 axisMarker0`` (marker 0's orientation) ->
        Scene.AddLinearSpringDamper (mbs/linear_spring_forces.py): Exudyn adds ``f a`` to the LHS
        through the markers' position Jacobians only (+ on marker 1, - on marker 0)."""
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
        if uf is None:             # compiled (mbs/forces.rigid_spring_forces: Exudyn's law, angles as
            #                        RotationMatrix2RotXYZ, checked by tests/test_bridge_oracle.py)
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
        gap of the last step) start as stored in mbs.  -> Scene.AddRollingDiscPenalty (its parameters
        by Exudyn's names).  The kernel's law is Exudyn's (its documentation's "Geometric
        relations" and "Computation of normal and tangential forces", ComputeSlipForce for the
        friction, the rolling friction added after the torques): contact only where the stored gap
        is negative.  Exudyn's PostNewtonStep, which writes the data after a step and skips an
        inactive connector (whose data node keeps the values of its last active step, measured),
        is the kernel's contact-data step observer (mbs/step_observers.py)."""
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
    def read_loads(self, sc):
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
        world force ``load e_axis`` at the node; on a rotation parameter of a RotVecLG, EP or Rxyz
        node Scene.AddCoordinateLoad (mbs/coordinate_forces.py, Exudyn's Jacobian direction C)."""
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
            sc.pyItems.append(pyforces_coordinates.CoordinateLoadUF(self.mbs, l, load, cm, uf))
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
