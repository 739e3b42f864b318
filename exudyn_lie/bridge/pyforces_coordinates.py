"""The coordinate items evaluated in Python (a part of :mod:`.pyforces`): a
``CoordinateSpringDamper`` with a ``springForceUserFunction`` and a ``LoadCoordinate`` with a
``loadVectorUserFunction``, on position coordinates, rotation coordinates (angles tracked over
turns) and rotation parameters of 3D nodes, as Exudyn defines them (CMarkerNodeCoordinate);
and the moving offset of an ``ObjectConnectorCoordinate`` (``offsetUserFunction``)."""
import math

import numpy as np

from ..mbs.external_probes import COORD_OUT_A, COORD_OUT_B, N_PROBE, coord_probe_row
from ..mbs.node_coordinates import PARAM_KINDS, PARAM_TAIT_BRYAN, node_parameter, param_code
from ..mbs.rotation_parameters import TRACK_QUAT, TRACK_TAIT_BRYAN, nearest_parameters
from ..mbs.scene import GROUND
from .pyforces import PyItem, _Connector, _call


def coordinate_state(cm, st):
    """(current coordinate, its rate) of a node coordinate (reader.CoordinateMarker):
    ``direction . p - ref`` of the body frame origin, 0 on the ground; a rotation coordinate:
    the angle about ``direction`` (mbs.coordinate_angles), continued from the last value this
    marker returned, minus ``ref``, and ``direction . omega_world``.  In scalar arithmetic, in
    the order of the compiled probe (mbs/external_probes.coordinate_probe), which the stage
    reads instead (:func:`probed_state`): the two agree to the bit."""
    if cm.body == GROUND:
        return 0.0, 0.0
    if cm.param is not None:
        v, rate, _ = parameter_state(cm, st)
        return v - cm.ref, rate
    d0, d1, d2 = cm.axis
    if cm.angle is not None:
        (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = st.R[cm.body].tolist()
        f0, f1, f2 = _frame_column(cm)
        w0, w1, w2 = st.omega[cm.body].tolist()
        wx, wy, wz = r00 * w0 + r01 * w1 + r02 * w2, r10 * w0 + r11 * w1 + r12 * w2, r20 * w0 + r21 * w1 + r22 * w2
        return _tracked_angle(cm, f0 * r00 + f1 * r10 + f2 * r20, f0 * r01 + f1 * r11 + f2 * r21), \
            d0 * wx + d1 * wy + d2 * wz
    x0, x1, x2 = st.r[cm.body].tolist()
    v0, v1, v2 = st.vel[cm.body].tolist()
    return (d0 * x0 + d1 * x1 + d2 * x2) - cm.ref, d0 * v0 + d1 * v1 + d2 * v2


def _frame_column(cm):
    """The first column of a rotation coordinate's reference frame, three floats."""
    F = np.asarray(cm.angle.frame, float)
    return float(F[0, 0]), float(F[1, 0]), float(F[2, 0])


def _tracked_angle(cm, c, s):
    """The angle ``atan2(-s, c)`` on the branch nearest the last one this marker returned
    (from the coordinate's total initial angle), minus ``ref``."""
    a = math.atan2(-s, c)
    a += 2.0 * math.pi * round((getattr(cm, "prev", cm.angle.angle0) - a) / (2.0 * math.pi))
    cm.prev = a
    return a - cm.ref


_GROUND_SIDE = (GROUND, (0.0, 0.0, 0.0), None)


def probe_side(cm):
    """(body, world axis, frame column or None) of a marker for its coordinate probe
    (mbs/external_probes.coord_probe_row); None for a rotation parameter (no probe)."""
    if cm.param is not None:
        return None
    if cm.body == GROUND:
        return _GROUND_SIDE
    return cm.body, cm.axis, (None if cm.angle is None else _frame_column(cm))


def probe_row(A, B):
    """The coordinate probe of markers ``A`` and ``B`` (``B`` None: a load), None where either
    is a rotation parameter (the item then runs :meth:`add`)."""
    a = probe_side(A)
    b = _GROUND_SIDE if B is None else probe_side(B)
    if a is None or b is None:
        return None
    return coord_probe_row(a[0], a[1], a[2], b[0], b[1], b[2])


def probed_state(cm, P, j):
    """:func:`coordinate_state` from the probe's outputs of one side at ``P[j:j+3]``."""
    if cm.body == GROUND:
        return 0.0, 0.0
    if cm.angle is not None:
        return _tracked_angle(cm, P[j], P[j + 1]), P[j + 2]
    return P[j] - cm.ref, P[j + 2]


def apply_probed(cm, f, Q):
    """:func:`apply_coordinate` on the flat ``Qext`` (rows of force and torque, six per body)
    for a position or rotation coordinate: the same products."""
    if cm.body == GROUND:
        return
    i = 6 * cm.body + (0 if cm.angle is None else 3)
    d0, d1, d2 = cm.axis
    Q[i] += f * d0
    Q[i + 1] += f * d1
    Q[i + 2] += f * d2


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
    X = F if cm.angle is None else T
    d0, d1, d2 = cm.axis
    b = cm.body
    X[b, 0] += f * d0
    X[b, 1] += f * d1
    X[b, 2] += f * d2


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

    # ---- the stepper's seam: both coordinates and their rates computed by the compiled stage
    probeIndex = None        # the row of Work.probe (Combined.probe_rows)

    def probe_row(self):
        return probe_row(self.A, self.B)

    def add_stage(self, t, st, F, T, P, Q):
        """:meth:`add` from the probe's outputs (``P``, ``Q``: flat memoryviews of ``Work.probe``
        and ``Work.Qext``, pyforces.TorsionalSpringDamperUF.add_stage); without a probe (a
        rotation parameter), :meth:`add`."""
        if self.probeIndex is None:
            return self.add(t, st, F, T)
        j = self.probeIndex * N_PROBE
        d = self.d
        qA, vA = probed_state(self.A, P, j + COORD_OUT_A)
        qB, vB = probed_state(self.B, P, j + COORD_OUT_B)
        f = float(_call(self.label, self.uf, self.mbs, t, self.o, qB - qA, vB - vA, d["stiffness"], d["damping"],
                        d["offset"]))
        apply_probed(self.A, f, Q)
        apply_probed(self.B, -f, Q)


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

    # ---- the stepper's seam: the load reads no state (its direction is constant), so it has
    # no probe; it writes into the flat Qext
    def add_stage(self, t, st, F, T, P, Q):
        """:meth:`add` writing into the flat ``Qext`` (a rotation parameter: :meth:`add`)."""
        if self.cm.param is not None:
            return self.add(t, st, F, T)
        apply_probed(self.cm, float(_call(self.label, self.uf, self.mbs, t, self.load)), Q)


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
