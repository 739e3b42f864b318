"""Kinematics of Python-evaluated items, computed by the compiled stage before the external call.

A Python force item (the bridge's connectors with a user function, ``bridge/pyforces.py``)
needs a few scalars of the stage state: a torsional spring its angle and angular rate.  In
Python these cost far more than the user function itself (scalar arithmetic on
the rotation matrices: about 0.9 us of a PD controller's 1.7 us per call, measured on the
heavy top, ``python -m exudyn_lie bench --sections userfunctions``).  So the compiled stage
computes them (:func:`probe_kinematics`, called by ``external_calls.external_forces`` right before
the one call of the Python side per stage) into ``Work.probe``, one row per *probe*, and the Python
side only reads floats, calls the user function and adds the result.

A row holds the probe's inputs (kind, bodies, constant frame columns; written when the
simulator is made and when the item's parameters change during a solve) and its outputs
(written at every stage).  The Python force callable declares its probes through
``fn.probe_rows()`` (:func:`probe_table`; it numbers its items in that order) and reads
them through ``fn.stage_adder(probe, Qext)`` (``Simulator._external_views``).

Kinds (the arithmetic is the Python item's, in its order, so the results are the same to
the bit):

* :data:`PROBE_TORSION`: a torsional spring about the z axis of frame ``A``, inputs the x, z
  columns of frame ``A`` in body ``A`` coordinates and the x, y columns of frame ``B`` in body
  ``B`` coordinates (for the ground: in world coordinates); outputs the principal angle
  ``phi = atan2(-(x_A . y_B), x_A . x_B)`` of the relative rotation ``J_A^T J_B`` (world
  columns), ``phidot = z_A . (w_B - w_A)`` (world angular velocities) and the world ``z_A``
  (the bridge's ``TorsionalSpringDamperUF.angle``);
* :data:`PROBE_SPRING`: a point-to-point spring-damper, inputs the points in body coordinates;
  outputs the length ``L``, its rate ``(v_B - v_A) . e``, the unit vector ``e`` from A to B and
  the world arms ``R s`` of both points (the only kinematics of the bridge's Python
  spring-damper, in a stage or not);
* :data:`PROBE_ARM`: a point of a body (a load's point of application), output its world
  arm ``R s`` (the bridge's ``pyforces._add_force``);
* :data:`PROBE_COORD`: the node coordinates of a coordinate item's two markers (a single one
  for a load: side B on the ground), each a position coordinate (input its world axis ``d``;
  outputs ``d . r``, 0, ``d . v``) or a rotation coordinate (inputs the axis ``d`` and the
  first column ``f`` of its reference frame; outputs ``f . R e_x``, ``f . R e_y`` and
  ``d . R omega``, from which the item takes the angle and tracks it over turns; the bridge's
  ``pyforces_coordinates.coordinate_state``).
"""
import math

import numpy as np
from numba import njit

GROUND = -1

PROBE_TORSION = 1
PROBE_SPRING = 2
PROBE_ARM = 3
PROBE_COORD = 4

# the columns of a row: kind and bodies, then per kind its inputs and outputs
P_KIND, P_BODY_A, P_BODY_B = 0, 1, 2
TORSION_COLS_A = 3    # inputs: x_A (3), z_A (3) in body A coordinates
TORSION_COLS_B = 9    # x_B (3), y_B (3) in body B coordinates
TORSION_PHI = 15      # outputs: principal angle, rate, world z_A (3)
TORSION_PHID = 16
TORSION_Z = 17
SPRING_POS_A = 3      # inputs: the spring's end points in body coordinates
SPRING_POS_B = 6
SPRING_L = 9          # outputs: length, its rate, world unit vector A -> B (3), world arms R s (3, 3)
SPRING_LD = 10
SPRING_E = 11
SPRING_ARM_A = 14
SPRING_ARM_B = 17
ARM_POS = 3           # inputs: the point in body coordinates, 1.0 if it is not the frame origin
ARM_HAS = 6
ARM_WORLD = 7         # output: the world arm R s (3)
COORD_DIR_A = 3       # inputs per side: world axis d (3), frame column f (3), 1.0 for a rotation coordinate
COORD_F_A = 6
COORD_DIR_B = 9
COORD_F_B = 12
COORD_ANGLE_A = 15
COORD_ANGLE_B = 16
COORD_OUT_A = 17      # outputs per side: (d . r, 0, d . v) or (f . R e_x, f . R e_y, d . R omega)
COORD_OUT_B = 20
N_PROBE = 24


def _row(kind, bodyA, bodyB, *groups):
    row = [float(kind), float(bodyA), float(bodyB)]
    for g in groups:
        row += [float(c) for c in g]
    return row + [0.0] * (N_PROBE - len(row))


def torsion_probe_row(bodyA, bodyB, colsA, colsB):
    """The input row of a :data:`PROBE_TORSION` probe: ``colsA`` = (x_A, z_A), ``colsB`` =
    (x_B, y_B) as six floats each (frame columns in body coordinates)."""
    return _row(PROBE_TORSION, bodyA, bodyB, colsA, colsB)


def spring_probe_row(bodyA, bodyB, posA, posB):
    """The input row of a :data:`PROBE_SPRING` probe: the end points ``posA``, ``posB``
    in body coordinates (world coordinates on the ground)."""
    return _row(PROBE_SPRING, bodyA, bodyB, posA, posB)


def arm_probe_row(body, pos):
    """The input row of a :data:`PROBE_ARM` probe: the point ``pos`` of ``body`` (body
    coordinates)."""
    pos = [float(c) for c in pos]
    return _row(PROBE_ARM, body, GROUND, pos, [0.0 if pos == [0.0, 0.0, 0.0] else 1.0])


def coord_probe_row(bodyA, dirA, frameA, bodyB, dirB, frameB):
    """The input row of a :data:`PROBE_COORD` probe: per side the body, the coordinate's
    world axis and, for a rotation coordinate, its frame's first column (None otherwise)."""
    row = _row(PROBE_COORD, bodyA, bodyB, dirA, [0.0] * 3 if frameA is None else frameA,
               dirB, [0.0] * 3 if frameB is None else frameB)
    row[COORD_ANGLE_A] = 0.0 if frameA is None else 1.0
    row[COORD_ANGLE_B] = 0.0 if frameB is None else 1.0
    return row


def probe_table(scene):
    """``Work.probe`` of a scene: the rows its Python forces declare (``fn.probe_rows()``,
    optional), in their order; (0, N_PROBE) without probes."""
    rows = []
    for pf in scene.pythonForces:
        declare = getattr(pf.fn, "probe_rows", None)
        if declare is not None:
            rows += declare(len(rows))
    return np.array(rows, float).reshape(-1, N_PROBE)


@njit(cache=True, inline="always", _nrt=False)
def _world_column(R, p, c):
    """``R p[c:c+3]`` in the Python item's order of operations."""
    return (R[0, 0] * p[c] + R[0, 1] * p[c + 1] + R[0, 2] * p[c + 2],
            R[1, 0] * p[c] + R[1, 1] * p[c + 1] + R[1, 2] * p[c + 2],
            R[2, 0] * p[c] + R[2, 1] * p[c + 1] + R[2, 2] * p[c + 2])


@njit(cache=True, inline="always", _nrt=False)
def _point(Rs, rs, Vw, b, p, c):
    """World position, velocity and arm ``R s`` (nine floats) of the body point ``s =
    p[c:c+3]`` of body ``b`` (the ground: ``s`` itself, at rest, no arm)."""
    s0, s1, s2 = p[c], p[c + 1], p[c + 2]
    if b == GROUND:
        return s0, s1, s2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    R = Rs[b]
    w0, w1, w2 = Vw[b, 0], Vw[b, 1], Vw[b, 2]
    a0, a1, a2 = _world_column(R, p, c)
    c0, c1, c2 = w1 * s2 - w2 * s1, w2 * s0 - w0 * s2, w0 * s1 - w1 * s0          # omega x s (body)
    return (rs[b, 0] + a0, rs[b, 1] + a1, rs[b, 2] + a2,
            Vw[b, 3] + R[0, 0] * c0 + R[0, 1] * c1 + R[0, 2] * c2,
            Vw[b, 4] + R[1, 0] * c0 + R[1, 1] * c1 + R[1, 2] * c2,
            Vw[b, 5] + R[2, 0] * c0 + R[2, 1] * c1 + R[2, 2] * c2, a0, a1, a2)


@njit(cache=True, _nrt=False)
def probe_kinematics(Rs, rs, Vw, probe):
    """The outputs of every probe at the stage state: ``Rs, rs`` the body frames,
    ``Vw = (omega body, world rdot)`` (``bodies.body_world_velocity``)."""
    for k in range(probe.shape[0]):
        p = probe[k]
        kind = p[P_KIND]
        if kind == PROBE_TORSION:
            torsion_probe(Rs, Vw, p)
        elif kind == PROBE_SPRING:
            spring_probe(Rs, rs, Vw, p)
        elif kind == PROBE_ARM:
            b = int(p[P_BODY_A])
            p[ARM_WORLD], p[ARM_WORLD + 1], p[ARM_WORLD + 2] = _world_column(Rs[b], p, ARM_POS)
        elif kind == PROBE_COORD:
            coordinate_probe(Rs, rs, Vw, p, int(p[P_BODY_A]), COORD_DIR_A, COORD_F_A, COORD_ANGLE_A, COORD_OUT_A)
            coordinate_probe(Rs, rs, Vw, p, int(p[P_BODY_B]), COORD_DIR_B, COORD_F_B, COORD_ANGLE_B, COORD_OUT_B)


@njit(cache=True, inline="always", _nrt=False)
def coordinate_probe(Rs, rs, Vw, p, b, dcol, fcol, acol, out):
    """:data:`PROBE_COORD`, one side: as ``pyforces_coordinates.coordinate_state`` without the
    reference value and the tracking (nothing on the ground)."""
    if b == GROUND:
        return
    d0, d1, d2 = p[dcol], p[dcol + 1], p[dcol + 2]
    if p[acol] != 0.0:
        R = Rs[b]
        f0, f1, f2 = p[fcol], p[fcol + 1], p[fcol + 2]
        w0, w1, w2 = _world_column(R, Vw[b], 0)
        p[out] = f0 * R[0, 0] + f1 * R[1, 0] + f2 * R[2, 0]
        p[out + 1] = f0 * R[0, 1] + f1 * R[1, 1] + f2 * R[2, 1]
        p[out + 2] = d0 * w0 + d1 * w1 + d2 * w2
    else:
        p[out] = d0 * rs[b, 0] + d1 * rs[b, 1] + d2 * rs[b, 2]
        p[out + 1] = 0.0
        p[out + 2] = d0 * Vw[b, 3] + d1 * Vw[b, 4] + d2 * Vw[b, 5]


@njit(cache=True, inline="always", _nrt=False)
def _frame_side(Rs, Vw, p, b, col):
    """World columns ``p[col:col+3]`` and ``p[col+3:col+6]`` of one side's joint frame and the
    side's angular velocity (nine floats; the ground: stored world columns, at rest)."""
    if b == GROUND:
        return p[col], p[col + 1], p[col + 2], p[col + 3], p[col + 4], p[col + 5], 0.0, 0.0, 0.0
    u0, u1, u2 = _world_column(Rs[b], p, col)
    v0, v1, v2 = _world_column(Rs[b], p, col + 3)
    w0, w1, w2 = _world_column(Rs[b], Vw[b], 0)
    return u0, u1, u2, v0, v1, v2, w0, w1, w2


@njit(cache=True, inline="always", _nrt=False)
def torsion_probe(Rs, Vw, p):
    """:data:`PROBE_TORSION`: as ``TorsionalSpringDamperUF.angle`` without the tracking."""
    a, b = int(p[P_BODY_A]), int(p[P_BODY_B])
    x0, x1, x2, z0, z1, z2, wa0, wa1, wa2 = _frame_side(Rs, Vw, p, a, TORSION_COLS_A)
    c0, c1, c2, s0, s1, s2, wb0, wb1, wb2 = _frame_side(Rs, Vw, p, b, TORSION_COLS_B)
    c = x0 * c0 + x1 * c1 + x2 * c2          # (J_A^T J_B)[0, 0]
    s = x0 * s0 + x1 * s1 + x2 * s2          # (J_A^T J_B)[0, 1]
    p[TORSION_PHI] = math.atan2(-s, c)
    p[TORSION_PHID] = z0 * (wb0 - wa0) + z1 * (wb1 - wa1) + z2 * (wb2 - wa2)
    p[TORSION_Z], p[TORSION_Z + 1], p[TORSION_Z + 2] = z0, z1, z2


@njit(cache=True, inline="always", _nrt=False)
def spring_probe(Rs, rs, Vw, p):
    """:data:`PROBE_SPRING`: ``L = |p_B - p_A|``, ``e = (p_B - p_A) / L``, ``Ldot = (v_B - v_A) . e``
    and the arms."""
    pA0, pA1, pA2, vA0, vA1, vA2, aA0, aA1, aA2 = _point(Rs, rs, Vw, int(p[P_BODY_A]), p, SPRING_POS_A)
    pB0, pB1, pB2, vB0, vB1, vB2, aB0, aB1, aB2 = _point(Rs, rs, Vw, int(p[P_BODY_B]), p, SPRING_POS_B)
    d0, d1, d2 = pB0 - pA0, pB1 - pA1, pB2 - pA2
    L = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    e0, e1, e2 = d0 / L, d1 / L, d2 / L
    p[SPRING_L] = L
    p[SPRING_LD] = (vB0 - vA0) * e0 + (vB1 - vA1) * e1 + (vB2 - vA2) * e2
    p[SPRING_E], p[SPRING_E + 1], p[SPRING_E + 2] = e0, e1, e2
    p[SPRING_ARM_A], p[SPRING_ARM_A + 1], p[SPRING_ARM_A + 2] = aA0, aA1, aA2
    p[SPRING_ARM_B], p[SPRING_ARM_B + 1], p[SPRING_ARM_B + 2] = aB0, aB1, aB2
