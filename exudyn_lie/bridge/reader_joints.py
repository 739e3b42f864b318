"""Reading Exudyn's joints and constraints into scene joints and rows (a part of
:class:`~.reader._Reader`): the generic, revolute, prismatic, spherical and 2D joints, distance
and coordinate constraints, rolling discs; each as Exudyn defines it (main/src/Objects)."""
from __future__ import annotations

import numpy as np

from ..mbs.scene import GROUND, SceneError, frame_with_axis
from .pyforces_coordinates import OffsetUserFunction
from .moving_offsets import MovableOffset
from .reader_common import BridgeError, JointInfo, NotCompiled, _orthonormal, _userfunction, joint_ae_map


class JointReaders:
    """The joint and constraint readers of :class:`~.reader._Reader`."""

    def read_joint(self, sc, o, d):
        t = d["objectType"]
        what = self._what("object", o, d)
        aeAll = self._constraint_ae(o, d, what, sc, "multipliers")
        if aeAll is None:
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

    def _constraint_ae(self, o, d, what, sc, multipliers="multiplier"):
        """The AE indices of a constraint object; None (skipped, its AE coordinates 0) if it is
        inactive."""
        try:
            aeAll = np.zeros(0, np.int64) if self.items else np.array(self.sd.GetObjectLTGAE(o), dtype=np.int64)
        except Exception:
            aeAll = np.zeros(0, np.int64)
        if not d.get("activeConnector", True):
            sc.skipped.append((what, f"inactive (activeConnector=False): Exudyn sets its {multipliers} to 0"))
            sc.aeZero.extend(aeAll.tolist())
            return None
        return aeAll

    def read_distance_constraint(self, sc, o, d):
        """ObjectConnectorDistance: ``|p_1 - p_0| - distance = 0`` (CObjectConnectorDistance, which
        stops with an error at ``p_1 = p_0``) -> Scene.AddDistanceConstraint (mbs/distance_rows.py)."""
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
        1 the disc centre on a 3D rigid body; free axes keep their multiplier 0 (as Exudyn) ->
        Scene.AddRollingDisc (mbs/rolling_disc_rows.py: Exudyn's row order, its plane normal used
        unnormalised, the rows its jacobian_ODE2_t ``vJacPos + vJacRot x (p_C - p_X)`` on ``e_k``)."""
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

    def read_coordinate_constraint(self, sc, o, d):
        """ObjectConnectorCoordinate (CObjectConnectorCoordinate::ComputeAlgebraicEquations):
        ``f q_B - q_A - offset = 0``, with ``offsetUserFunction`` in place of ``offset``; with
        ``velocityLevel=True`` ``f qdot_B - qdot_A - offset = 0`` on the coordinates' rates, with
        ``offsetUserFunction_t`` in place of ``offset`` (Exudyn ignores ``offsetUserFunction``
        then, and the position-level equation ignores ``offsetUserFunction_t``: its index-3
        solve never reads it).  Moving offsets: mbs/row_drives.py."""
        what = self._what("object", o, d)
        aeAll = self._constraint_ae(o, d, what, sc)
        if aeAll is None:
            return
        velocityLevel = bool(d.get("velocityLevel", False))
        key = "offsetUserFunction_t" if velocityLevel else "offsetUserFunction"
        uf = _userfunction(d, key, what)
        m0, m1 = (int(m) for m in d["markerNumbers"])
        cA = self.coordinate_marker(m0, what, velocityLevel)
        cB = self.coordinate_marker(m1, what, velocityLevel)
        A, ka, refA, B, kb, refB = cA.body, cA.spec, cA.ref, cB.body, cB.spec, cB.ref
        f = float(d.get("factor1", d.get("factorValue1", 1.0)))      # factorValue1: before 1.12.258
        if A == GROUND and (B == GROUND or f == 0.0):
            sc.skipped.append((what, "constrains no body coordinate"))
            sc.aeZero.extend(aeAll.tolist())
            return
        offset = float(d.get("offset", 0.0))
        moving = None if uf is None else OffsetUserFunction(self.mbs, o, d, uf, key)
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
