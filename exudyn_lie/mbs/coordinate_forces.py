"""The coordinate spring-damper: Exudyn's ``ObjectConnectorCoordinateSpringDamper`` on node
position coordinates (``MarkerNodeCoordinate``: current coordinate = total - reference, 0 on
a ground node).  Exudyn's law (CObjectConnectorCoordinateSpringDamper, Exudyn 1.13.6 has no
friction parameters in it):

    f = k (q_B - q_A - offset) + d (qdot_B - qdot_A),

``-f`` acts on coordinate ``q_B`` and ``+f`` on ``q_A`` (Exudyn's LHS ``J_B^T f - J_A^T f``).
With ``q_X = d_X . p_X - ref_X`` (the node point ``s = 0``, ``d_X`` the coordinate's fixed world
direction: ``e_k``, or a Mass1D's axis) it is a world force ``+f d_A`` at node A and ``-f d_B``
at node B, and ``q_B - q_A - offset = d_B . p_B - d_A . p_A - c`` with
``c = offset + ref_B - ref_A`` folded by the bridge.  ``SceneData.kint`` = [A, B],
``kpar`` = [k, d, c, d_A (3), d_B (3)].
"""
from numba import njit

from .bodies import _side, add_point_force, body_point


@njit(cache=True, inline="always", _nrt=False)
def _coordinate_difference(kp, pA, pB):
    """``d_B . pB - d_A . pA`` with the directions in ``kp[3:9]``."""
    out = 0.0
    for k in range(3):
        out += kp[6 + k] * pB[k] - kp[3 + k] * pA[k]
    return out


@njit(cache=True, _nrt=False)
def coordinate_spring_forces(gid, kint, kpar, R, r, V, Q, v3, ident, zero3, zero6):
    pA, pB, vA, vB, bA, bB, F = v3[0], v3[1], v3[2], v3[3], v3[4], v3[5], v3[6]
    for s in range(kint.shape[0]):
        a = kint[s, 0]
        b = kint[s, 1]
        kp = kpar[s]
        gA, RA, rA, VA = _side(gid, a, R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, b, R, r, V, ident, zero3, zero6)
        body_point(gA, RA, rA, VA, zero3, pA, vA, bA)
        body_point(gB, RB, rB, VB, zero3, pB, vB, bB)
        f = kp[0] * (_coordinate_difference(kp, pA, pB) - kp[2]) + kp[1] * _coordinate_difference(kp, vA, vB)
        if a >= 0:
            for k in range(3):
                F[k] = f * kp[3 + k]
            add_point_force(gA, RA, zero3, F, Q[a])
        if b >= 0:
            for k in range(3):
                F[k] = -f * kp[6 + k]
            add_point_force(gB, RB, zero3, F, Q[b])


@njit(cache=True, _nrt=False)
def coordinate_spring_energy(gid, kint, kpar, R, r, V, v3, ident, zero3, zero6):
    """Potential ``k/2 (q_B - q_A - offset)^2`` of every coordinate spring."""
    pA, pB, vA, vB, bA, bB = v3[0], v3[1], v3[2], v3[3], v3[4], v3[5]
    e = 0.0
    for s in range(kint.shape[0]):
        gA, RA, rA, VA = _side(gid, kint[s, 0], R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, kint[s, 1], R, r, V, ident, zero3, zero6)
        body_point(gA, RA, rA, VA, zero3, pA, vA, bA)
        body_point(gB, RB, rB, VB, zero3, pB, vB, bB)
        u = _coordinate_difference(kpar[s], pA, pB) - kpar[s, 2]
        e += 0.5 * kpar[s, 0] * u * u
    return e
