"""The coordinate spring-damper: Exudyn's ``ObjectConnectorCoordinateSpringDamper`` on node
coordinates (``MarkerNodeCoordinate``: current coordinate = total - reference, 0 on a ground
node).  Exudyn's law (CObjectConnectorCoordinateSpringDamper, Exudyn 1.13.6 has no friction
parameters in it):

    f = k (q_B - q_A - offset) + d (qdot_B - qdot_A),

``-f`` acts on coordinate ``q_B`` and ``+f`` on ``q_A`` (Exudyn's LHS ``J_B^T f - J_A^T f``).
A coordinate is a position coordinate ``q_X = d_X . p_X - ref_X`` (the node point ``s = 0``,
``d_X`` the coordinate's fixed world direction: ``e_k``, or a Mass1D's axis), on which ``f`` is
the world force ``f d_X`` at the node, or a rotation coordinate (``kint[s, 2 / 3] = 1``): the
angle about ``d_X = F_X e_z`` (:mod:`.coordinate_angles`), on which ``f`` is the world torque
``f d_X``.  The references fold into ``c = offset + ref_B - ref_A`` (the bridge).
``SceneData.kint`` = [A, B, rotation A, rotation B], ``kpar`` = [k, d, c, d_A (3), d_B (3),
angle A, angle B], ``krot`` = [F_A, F_B].
"""
from numba import njit

from .bodies import _side, add_point_force, add_world_torque, body_point
from .coordinate_angles import frame_angle


@njit(cache=True, inline="always", _nrt=False)
def _coordinate(rot, kp, i0, F, R, p, v, prev):
    """(value, rate) of one side's coordinate without its reference: ``d . p``, ``d . v`` for a
    position coordinate, the tracked angle and ``d . (R omega)`` for a rotation coordinate
    (``v`` = world omega then)."""
    if rot == 1:
        return frame_angle(F, R, prev), kp[i0] * v[0] + kp[i0 + 1] * v[1] + kp[i0 + 2] * v[2]
    return (kp[i0] * p[0] + kp[i0 + 1] * p[1] + kp[i0 + 2] * p[2],
            kp[i0] * v[0] + kp[i0 + 1] * v[1] + kp[i0 + 2] * v[2])


@njit(cache=True, inline="always", _nrt=False)
def _side_state(rot, g, R, r, V, zero3, p, v, b):
    """Node point, and its velocity (position coordinate) or the world omega (rotation)."""
    body_point(g, R, r, V, zero3, p, v, b)
    if rot == 1:
        for i in range(3):
            v[i] = R[i, 0] * V[0] + R[i, 1] * V[1] + R[i, 2] * V[2]


@njit(cache=True, _nrt=False)
def coordinate_spring_value(gid, kint, kpar, krot, s, R, r, V, v3, ident, zero3, zero6):
    """(q_B - q_A - offset, qdot_B - qdot_A) of coordinate spring ``s``."""
    pA, pB, vA, vB, bA, bB = v3[0], v3[1], v3[2], v3[3], v3[4], v3[5]
    kp = kpar[s]
    gA, RA, rA, VA = _side(gid, kint[s, 0], R, r, V, ident, zero3, zero6)
    gB, RB, rB, VB = _side(gid, kint[s, 1], R, r, V, ident, zero3, zero6)
    _side_state(kint[s, 2], gA, RA, rA, VA, zero3, pA, vA, bA)
    _side_state(kint[s, 3], gB, RB, rB, VB, zero3, pB, vB, bB)
    qA, dqA = _coordinate(kint[s, 2], kp, 3, krot[s, 0], RA, pA, vA, kp[9])
    qB, dqB = _coordinate(kint[s, 3], kp, 6, krot[s, 1], RB, pB, vB, kp[10])
    return qB - qA - kp[2], dqB - dqA


@njit(cache=True, _nrt=False)
def coordinate_spring_forces(gid, kint, kpar, krot, R, r, V, Q, v3, ident, zero3, zero6):
    F = v3[6]
    for s in range(kint.shape[0]):
        a = kint[s, 0]
        b = kint[s, 1]
        kp = kpar[s]
        u, ud = coordinate_spring_value(gid, kint, kpar, krot, s, R, r, V, v3, ident, zero3, zero6)
        f = kp[0] * u + kp[1] * ud
        if a >= 0:
            for k in range(3):
                F[k] = f * kp[3 + k]
            if kint[s, 2] == 1:
                add_world_torque(R[a], F, Q[a])
            else:
                add_point_force(gid[a], R[a], zero3, F, Q[a])
        if b >= 0:
            for k in range(3):
                F[k] = -f * kp[6 + k]
            if kint[s, 3] == 1:
                add_world_torque(R[b], F, Q[b])
            else:
                add_point_force(gid[b], R[b], zero3, F, Q[b])


@njit(cache=True, _nrt=False)
def coordinate_spring_energy(gid, kint, kpar, krot, R, r, V, v3, ident, zero3, zero6):
    """Potential ``k/2 (q_B - q_A - offset)^2`` of every coordinate spring."""
    e = 0.0
    for s in range(kint.shape[0]):
        u, _ = coordinate_spring_value(gid, kint, kpar, krot, s, R, r, V, v3, ident, zero3, zero6)
        e += 0.5 * kpar[s, 0] * u * u
    return e


# the element's entries (registered in mbs/force_elements.py)
@njit(cache=True, inline="always", _nrt=False)
def coordinate_spring_element(sd, wk, R, r, V, Q):
    coordinate_spring_forces(sd.gid, sd.kint, sd.kpar, sd.krot, R, r, V, Q, wk.v3, wk.ident, wk.zero3, wk.zero6)


@njit(cache=True, inline="always", _nrt=False)
def coordinate_spring_element_energy(sd, wk, R, r, V, e):
    """``e`` plus the coordinate springs' potential (summed on its own, then added)."""
    if sd.kint.shape[0] > 0:
        return e + coordinate_spring_energy(sd.gid, sd.kint, sd.kpar, sd.krot, R, r, V, wk.v3, wk.ident, wk.zero3,
                                            wk.zero6)
    return e
