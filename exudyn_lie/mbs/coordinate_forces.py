"""The coordinate spring-damper: Exudyn's ``ObjectConnectorCoordinateSpringDamper`` on node
position coordinates (``MarkerNodeCoordinate``: current coordinate = total - reference, 0 on
a ground node).  Exudyn's law (CObjectConnectorCoordinateSpringDamper, Exudyn 1.13.6 has no
friction parameters in it):

    f = k (q_B - q_A - offset) + d (qdot_B - qdot_A),

``-f`` acts on coordinate ``q_B`` and ``+f`` on ``q_A`` (Exudyn's LHS ``J_B^T f - J_A^T f``).
With ``q_X = p_X[k_X] - ref_X`` (the node point ``s = 0``) it is a world force ``+f e_kA`` at
node A and ``-f e_kB`` at node B, and ``q_B - q_A - offset = p_B[kB] - p_A[kA] - c`` with
``c = offset + ref_B - ref_A`` folded by the bridge.  ``SceneData.kint`` = [A, B, kA, kB],
``kpar`` = [k, d, c].
"""
from numba import njit

from .bodies import _side, add_point_force, body_point


@njit(cache=True, _nrt=False)
def coordinate_spring_forces(gid, kint, kpar, R, r, V, Q, v3, ident, zero3, zero6):
    pA, pB, vA, vB, bA, bB, F = v3[0], v3[1], v3[2], v3[3], v3[4], v3[5], v3[6]
    for s in range(kint.shape[0]):
        a = kint[s, 0]
        b = kint[s, 1]
        ka = kint[s, 2]
        kb = kint[s, 3]
        gA, RA, rA, VA = _side(gid, a, R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, b, R, r, V, ident, zero3, zero6)
        body_point(gA, RA, rA, VA, zero3, pA, vA, bA)
        body_point(gB, RB, rB, VB, zero3, pB, vB, bB)
        f = kpar[s, 0] * (pB[kb] - pA[ka] - kpar[s, 2]) + kpar[s, 1] * (vB[kb] - vA[ka])
        if a >= 0:
            for k in range(3):
                F[k] = 0.0
            F[ka] = f
            add_point_force(gA, RA, zero3, F, Q[a])
        if b >= 0:
            for k in range(3):
                F[k] = 0.0
            F[kb] = -f
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
        u = pB[kint[s, 3]] - pA[kint[s, 2]] - kpar[s, 2]
        e += 0.5 * kpar[s, 0] * u * u
    return e
