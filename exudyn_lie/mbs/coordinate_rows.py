"""The coordinate-constraint row (``ROW_COORD``): a coordinate constraint,

    h = f q_B - q_A - offset,

on two body coordinates ``q_A``, ``q_B`` (each the *current* coordinate, total minus
reference; a coordinate of ground is 0).  A coordinate is either

* a position coordinate along a fixed world direction ``d`` (``e_k`` for coordinate k of a point
  mass or rigid body, the fixed axis of a mass moving along one axis):
  ``q = d . p - ref`` with ``p`` the body origin (the body point ``s = 0``), rate
  ``d . pdot = (T^T d) . v`` (``pdot = T v``), bias ``d . beta`` (``beta`` the velocity-product
  acceleration of that point, ``R (omega x v)`` for SE3, 0 else; :func:`~.bodies.body_point`); or
* a rotation coordinate (``rowIndex[q, ROW_AX / ROW_BX] = 1``): the angle ``phi`` about
  ``d = F e_z`` tracked over turns (:mod:`.coordinate_angles`, frame ``F`` in ``jointFrames``), rate
  ``(R^T d) . omega``, bias 0.

The references fold into ``c = offset + f ref_B - ref_A`` (the bridge);
``jointParams[j] = (f, c, d_A, d_B)``, the tracked angles of rotation ends in the path state
(``PathState.jointAngles[j]``).  Rows (eq. index1): ``J V = f qdot_B - qdot_A``
and ``eta = -(f bias_B - bias_A)``.
"""
from numba import njit

from .bodies import translation_dual
from .coordinate_angles import angle_rate_row, frame_angle


@njit(cache=True, inline="always", _nrt=False)
def coordinate_row(q, a, b, gA, gB, RA, RB, rotEndA, rotEndB, FA, FB, par, angles, pA, pB, bA, bB, e, RTe, h, Jr,
                   eta):
    """Row ``q`` of a coordinate constraint from the body origins ``pA, pB`` and their bias
    accelerations ``bA, bB`` (body_point at s = 0); ``par = jointParams[j]``, ``angles = jointAngles[j]``; ``rotEndX`` 1 for a
    rotation coordinate (frame ``FX``)."""
    f = par[0]
    hv = -par[1]
    et = 0.0
    if a >= 0:
        if rotEndA == 1:
            hv -= frame_angle(FA, RA, angles[0])
            _rotation_column(RA, par, 2, -1.0, e, RTe, Jr, q, 0)
        else:
            for k in range(3):
                hv -= par[2 + k] * pA[k]
                et -= par[2 + k] * bA[k]
            _translation_column(gA, RA, par, 2, -1.0, e, RTe, Jr, q, 3)
    if b >= 0:
        if rotEndB == 1:
            hv += f * frame_angle(FB, RB, angles[1])
            _rotation_column(RB, par, 5, f, e, RTe, Jr, q, 6)
        else:
            for k in range(3):
                hv += f * par[5 + k] * pB[k]
                et += f * par[5 + k] * bB[k]
            _translation_column(gB, RB, par, 5, f, e, RTe, Jr, q, 9)
    h[q] = hv
    eta[q] = -et


@njit(cache=True, inline="always", _nrt=False)
def _translation_column(g, R, par, i0, s, e, RTe, Jr, q, col):
    """``Jr[q, col:col+3] = s T^T d`` with ``d = par[i0:i0+3]`` (``rdot = T v``; bodies.translation_dual)."""
    for i in range(3):
        e[i] = par[i0 + i]
    for i in range(3):
        RTe[i] = R[0, i] * e[0] + R[1, i] * e[1] + R[2, i] * e[2]
    Te = translation_dual(g, e, RTe)
    for i in range(3):
        Jr[q, col + i] = s * Te[i]


@njit(cache=True, inline="always", _nrt=False)
def _rotation_column(R, par, i0, s, e, RTe, Jr, q, col):
    """``Jr[q, col:col+3] = s R^T d`` with ``d = par[i0:i0+3]`` (the rate of a rotation coordinate)."""
    for i in range(3):
        e[i] = par[i0 + i]
    angle_rate_row(e, R, RTe)
    for i in range(3):
        Jr[q, col + i] = s * RTe[i]
