"""Rotation coordinates of the coordinate items (Scene.AngleCoordinate): the angle ``phi`` of a
body about the z axis of a world frame ``F``,

    phi = atan2(-(F^T R)[0, 1], (F^T R)[0, 0]) + 2 pi n,

the third Tait-Bryan angle of ``F^T R`` as for the torsional spring (``= phi`` exactly for
``R = F Rz(phi)``, a body turning about ``F e_z``: a 2D body with ``F = I``), with the turn count
``n`` that puts it nearest to the angle tracked at the last accepted step.  Its rate is
``(F e_z) . omega_world``, whose derivative at frozen V is ``(F e_z) . R (omega x omega) = 0``:
a rotation coordinate adds nothing to ``eta`` (coordinate_rows).

The tracked angles are path state (``PathState.jointAngles[j]`` of a coordinate constraint,
``PathState.springAngles[s]`` of a coordinate spring; frames in ``jointFrames`` /
``coordSpringFrames``), start at
the angle of the initial state (``AngleCoordinate.angle0``, the total angle over all turns) and are
moved on after every accepted step by :func:`update_coordinate_angles`.
"""
import numpy as np
from numba import njit

from .codes import J_BODY_A, J_BODY_B, J_ROW0, ROW_AX, ROW_BX, ROW_COORD, ROW_KIND

TWO_PI = 2.0 * np.pi


@njit(cache=True, inline="always", _nrt=False)
def frame_angle(F, R, prev):
    """Angle of ``R`` about ``F e_z`` (see the module text), on the branch nearest ``prev``."""
    c = F[0, 0] * R[0, 0] + F[1, 0] * R[1, 0] + F[2, 0] * R[2, 0]
    s = -(F[0, 0] * R[0, 1] + F[1, 0] * R[1, 1] + F[2, 0] * R[2, 1])
    a = np.arctan2(s, c)
    # np.rint, not np.round: the same value (round half to even), but np.round's numba
    # implementation lives in numba.np.arraymath, which imports scipy.linalg when a
    # cached kernel is loaded (0.12 s of a warm start)
    return a + TWO_PI * np.rint((prev - a) / TWO_PI)


@njit(cache=True, inline="always", _nrt=False)
def angle_rate_row(d, R, out):
    """``out = R^T d``: the rate ``d . (R omega)`` of a rotation coordinate about ``d = F e_z``
    as a row on the body-fixed omega."""
    for i in range(3):
        out[i] = R[0, i] * d[0] + R[1, i] * d[1] + R[2, i] * d[2]


@njit(cache=True, _nrt=False)
def update_coordinate_angles(jointIndex, jointFrames, jointAngles, rowIndex, coordSpringEnds, coordSpringFrames,
                             springAngles, R):
    """Move every tracked angle to the current state (after an accepted step)."""
    for j in range(jointIndex.shape[0]):
        q = jointIndex[j, J_ROW0]
        if rowIndex[q, ROW_KIND] != ROW_COORD:
            continue
        if rowIndex[q, ROW_AX] == 1:
            jointAngles[j, 0] = frame_angle(jointFrames[j, 0], R[jointIndex[j, J_BODY_A]], jointAngles[j, 0])
        if rowIndex[q, ROW_BX] == 1:
            jointAngles[j, 1] = frame_angle(jointFrames[j, 1], R[jointIndex[j, J_BODY_B]], jointAngles[j, 1])
    for s in range(coordSpringEnds.shape[0]):
        if coordSpringEnds[s, 2] == 1:
            springAngles[s, 0] = frame_angle(coordSpringFrames[s, 0], R[coordSpringEnds[s, 0]], springAngles[s, 0])
        if coordSpringEnds[s, 3] == 1:
            springAngles[s, 1] = frame_angle(coordSpringFrames[s, 1], R[coordSpringEnds[s, 1]], springAngles[s, 1])
