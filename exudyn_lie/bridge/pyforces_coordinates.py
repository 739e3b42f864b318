"""The coordinate items evaluated in Python (a part of :mod:`.pyforces`): a
``CoordinateSpringDamper`` with a ``springForceUserFunction`` and a ``LoadCoordinate`` with a
``loadVectorUserFunction``, on position coordinates, rotation coordinates (angles tracked over
turns) and rotation parameters of 3D nodes, as Exudyn defines them (CMarkerNodeCoordinate);
and the moving offset of an ``ObjectConnectorCoordinate`` (``offsetUserFunction``)."""
import math

import numpy as np

from ..mbs.node_coordinates import PARAM_KINDS, PARAM_TAIT_BRYAN, node_parameter, param_code
from ..mbs.rotation_parameters import TRACK_QUAT, TRACK_TAIT_BRYAN, nearest_parameters
from ..mbs.scene import GROUND
from .pyforces import PyItem, _Connector, _call


def coordinate_state(cm, st):
    """(current coordinate, its rate) of a node coordinate (reader.CoordinateMarker):
    ``direction . p - ref`` of the body frame origin, 0 on the ground; a rotation coordinate:
    the angle about ``direction`` (mbs.coordinate_angles), continued from the last value this
    marker returned, minus ``ref``, and ``direction . omega_world``."""
    if cm.body == GROUND:
        return 0.0, 0.0
    if cm.param is not None:
        v, rate, _ = parameter_state(cm, st)
        return v - cm.ref, rate
    if cm.angle is not None:
        R = st.R[cm.body]
        F = np.asarray(cm.angle.frame, float)
        prev = getattr(cm, "prev", cm.angle.angle0)
        a = math.atan2(-(F[:, 0] @ R[:, 1]), F[:, 0] @ R[:, 0])
        a += 2.0 * math.pi * round((prev - a) / (2.0 * math.pi))
        cm.prev = a
        return a - cm.ref, float(cm.direction @ (R @ st.omega[cm.body]))
    return float(cm.direction @ st.r[cm.body]) - cm.ref, float(cm.direction @ st.vel[cm.body])


def parameter_state(cm, st):
    """(value, rate, world direction) of a node rotation parameter (reader.CoordinateMarker
    with ``param``; mbs/node_coordinates.py): the parameter on the branch nearest the one this
    marker saw last (``cm.paramPrev``, from the node's initial parameters), Exudyn's velocity
    coordinate ``C . omega``, and ``R C``: the generalised force ``f`` is the torque ``f R C``."""
    R = np.ascontiguousarray(st.R[cm.body], dtype=float)
    w = np.ascontiguousarray(st.omega[cm.body], dtype=float)
    code = param_code(PARAM_KINDS[cm.param.kind], cm.param.index)
    G, C, tmp = np.zeros(3), np.zeros(3), np.zeros(3)
    v, _ = node_parameter(code, R, cm.paramPrev, w, G, C, tmp)
    nearest_parameters(TRACK_TAIT_BRYAN if PARAM_KINDS[cm.param.kind] == PARAM_TAIT_BRYAN else TRACK_QUAT, R, cm.paramPrev,
                       cm.paramPrev)
    return v, float(C @ w), R @ C


def apply_coordinate(cm, f, F, T, st):
    """A generalised force ``f`` on a node coordinate: world force ``f direction`` at the node
    (the body frame origin), the world torque ``f direction`` on a rotation coordinate, or
    ``f R C`` on a node rotation parameter (Exudyn's e_k on the node's velocity coordinates)."""
    if cm.body == GROUND:
        return
    if cm.param is not None:
        T[cm.body] += f * parameter_state(cm, st)[2]
        return
    (F if cm.angle is None else T)[cm.body] += f * cm.direction


class CoordinateSpringDamperUF(_Connector):
    """ObjectConnectorCoordinateSpringDamper with ``springForceUserFunction(mbs, t, i,
    q_B - q_A, qdot_B - qdot_A, k, d, offset)``: ``-f`` on q_B, ``+f`` on q_A."""

    def __init__(self, mbs, o, d, A, B, uf):
        super().__init__(mbs, o, d, A, B)
        self.uf = uf

    def add(self, t, st, F, T):
        d = self.d
        qA, vA = coordinate_state(self.A, st)
        qB, vB = coordinate_state(self.B, st)
        f = float(_call(self.label, self.uf, self.mbs, t, self.o, qB - qA, vB - vA, d["stiffness"], d["damping"],
                        d["offset"]))
        apply_coordinate(self.A, f, F, T, st)
        apply_coordinate(self.B, -f, F, T, st)


class CoordinateLoadUF(PyItem):
    """LoadCoordinate with ``loadUserFunction(mbs, t, load)``: a generalised force on the
    node coordinate."""

    def __init__(self, mbs, l, load, cm, uf):
        self.mbs = mbs
        self.l = int(l)
        self.load = load
        self.cm = cm
        self.uf = uf
        self.label = f"load {l} LoadCoordinate"

    def bodies(self):
        return [self.cm.body]

    def add(self, t, st, F, T):
        apply_coordinate(self.cm, float(_call(self.label, self.uf, self.mbs, t, self.load)), F, T, st)


class OffsetUserFunction:
    """The moving offset of an ObjectConnectorCoordinate, ``t -> uf(mbs, t, i, offset)``
    (Exudyn's ``offsetUserFunction`` or, with ``velocityLevel=True``, ``offsetUserFunction_t``;
    its derivatives: mbs/row_drives.py); ``label`` names the item in the errors."""

    def __init__(self, mbs, o, d, uf, key):
        self.mbs = mbs
        self.o = int(o)
        self.offset = float(d.get("offset", 0.0))
        self.uf = uf
        self.label = f"object {o} ObjectConnectorCoordinate ('{d.get('name', '')}') {key}"

    def __call__(self, t):
        return self.uf(self.mbs, t, self.o, self.offset)
