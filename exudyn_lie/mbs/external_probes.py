"""Kinematics of Python-evaluated items, computed by the compiled stage before the external call.

A Python force item (the bridge's connectors with a user function, ``bridge/pyforces.py``)
needs a few scalars of the stage state: a torsional spring its angle and angular rate.  In
Python these cost far more than the user function itself (scalar arithmetic on
the rotation matrices: about 0.9 us of a PD controller's 1.7 us per call, measured on the
heavy top, ``python -m exudyn_lie bench --sections userfunctions``).  So the compiled stage
computes them (:func:`probe_kinematics`, called by ``stepper.external_forces`` right before
the one call of the Python side per stage) into ``Work.probe``, one row per *probe*, and the Python
side only reads floats, calls the user function and adds the result.

A row holds the probe's inputs (kind, bodies, constant frame columns; written when the
simulator is made and when the item's parameters change during a solve) and its outputs
(written at every stage).  The Python force callable declares its probes through
``fn.probe_rows()`` (:func:`probe_table`; it numbers its items in that order) and reads
them through ``fn.stage_adder(probe, Qext)`` (``Simulator._external_views``).

Kinds:

* :data:`PROBE_TORSION`: a torsional spring about the z axis of frame ``A`` (Exudyn's
  ``ObjectTorsionalSpringDamper``), inputs the x, z columns of ``A``'s marker frame in body
  ``A`` coordinates and the x, y columns of ``B``'s in body ``B`` coordinates (for the ground:
  in world coordinates); outputs the principal angle ``phi = atan2(-(x_A . y_B), x_A . x_B)``
  of the relative rotation ``J_A^T J_B`` (world columns), ``phidot = z_A . (w_B - w_A)``
  (world angular velocities) and the world ``z_A``.  The arithmetic is the Python item's,
  in its order (``TorsionalSpringDamperUF.angle``), so the angle is the same to the bit.
"""
import math

import numpy as np
from numba import njit

GROUND = -1

PROBE_TORSION = 1

# the columns of a row
P_KIND, P_BODY_A, P_BODY_B = 0, 1, 2
P_COLS_A = 3          # x_A (3), z_A (3): body A coordinates
P_COLS_B = 9          # x_B (3), y_B (3): body B coordinates
P_PHI = 15            # outputs: principal angle, rate, world z_A (3)
P_PHID = 16
P_Z = 17
N_PROBE = 20


def torsion_probe_row(bodyA, bodyB, colsA, colsB):
    """The input row of a :data:`PROBE_TORSION` probe: ``colsA`` = (x_A, z_A), ``colsB`` =
    (x_B, y_B) as six floats each (marker frame columns in body coordinates)."""
    row = [0.0] * N_PROBE
    row[P_KIND], row[P_BODY_A], row[P_BODY_B] = float(PROBE_TORSION), float(bodyA), float(bodyB)
    row[P_COLS_A:P_COLS_A + 6] = [float(c) for c in colsA]
    row[P_COLS_B:P_COLS_B + 6] = [float(c) for c in colsB]
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


@njit(cache=True, _nrt=False)
def probe_kinematics(Rs, Vw, probe):
    """The outputs of every probe at the stage state: ``Rs`` rotations, ``Vw[:, :3]`` the
    body-fixed angular velocities (``bodies.body_world_velocity``)."""
    for k in range(probe.shape[0]):
        p = probe[k]
        if p[P_KIND] == PROBE_TORSION:
            a, b = int(p[P_BODY_A]), int(p[P_BODY_B])
            if a == GROUND:
                x0, x1, x2 = p[P_COLS_A], p[P_COLS_A + 1], p[P_COLS_A + 2]
                z0, z1, z2 = p[P_COLS_A + 3], p[P_COLS_A + 4], p[P_COLS_A + 5]
                wa0, wa1, wa2 = 0.0, 0.0, 0.0
            else:
                x0, x1, x2 = _world_column(Rs[a], p, P_COLS_A)
                z0, z1, z2 = _world_column(Rs[a], p, P_COLS_A + 3)
                wa0, wa1, wa2 = _world_column(Rs[a], Vw[a], 0)
            if b == GROUND:
                c0, c1, c2 = p[P_COLS_B], p[P_COLS_B + 1], p[P_COLS_B + 2]
                s0, s1, s2 = p[P_COLS_B + 3], p[P_COLS_B + 4], p[P_COLS_B + 5]
                wb0, wb1, wb2 = 0.0, 0.0, 0.0
            else:
                c0, c1, c2 = _world_column(Rs[b], p, P_COLS_B)
                s0, s1, s2 = _world_column(Rs[b], p, P_COLS_B + 3)
                wb0, wb1, wb2 = _world_column(Rs[b], Vw[b], 0)
            c = x0 * c0 + x1 * c1 + x2 * c2          # (J_A^T J_B)[0, 0]
            s = x0 * s0 + x1 * s1 + x2 * s2          # (J_A^T J_B)[0, 1]
            p[P_PHI] = math.atan2(-s, c)
            p[P_PHID] = z0 * (wb0 - wa0) + z1 * (wb1 - wa1) + z2 * (wb2 - wa2)
            p[P_Z], p[P_Z + 1], p[P_Z + 2] = z0, z1, z2
