"""The coordinate spring-damper: a spring-damper between two body coordinates ``q_A``, ``q_B``
(each the current coordinate = total - reference, 0 on ground), with the law (no friction term)

    f = k (q_B - q_A - offset) + d (qdot_B - qdot_A),

``-f`` acts on coordinate ``q_B`` and ``+f`` on ``q_A`` (the generalised force ``J_A^T f - J_B^T f``).
A coordinate is a position coordinate ``q_X = d_X . p_X - ref_X`` (the body point ``s = 0``,
``d_X`` the coordinate's fixed world direction: ``e_k``, or the axis of a mass moving along one
axis), on which ``f`` is the world force ``f d_X`` at that point, or a rotation coordinate
(``coordSpringEnds[s, 2 / 3] = 1``): the angle about ``d_X = F_X e_z`` (:mod:`.coordinate_angles`),
on which ``f`` is the world torque ``f d_X``.  The references fold into
``c = offset + ref_B - ref_A`` (the bridge).
A third kind of coordinate is a rotation parameter of a 3D rigid body (``coordSpringEnds[s, 2 / 3] >= 10``,
:mod:`.node_coordinates`): value ``q_k`` (branch tracked in ``bodyParameters``), rate ``C . omega``
(the parametrisation's velocity coordinate for ``q_k``), and ``f`` acts as the local torque ``f C``.
``coordSpringLaw[s, COORD_SPRING_FORCE]`` is a constant ``f0`` added to ``f`` (k = d = 0 and ``f0 = -load`` is a
generalised force ``load`` on such a coordinate, :meth:`Scene.AddCoordinateLoad`, whose direction
``C`` depends on the state for 'eulerParameters' and 'taitBryanXYZ').
``SceneData.coordSpringEnds`` = [A, B, code A, code B] (0 position, 1 angle, >= 10 node parameter),
``coordSpringLaw`` = [k, d, c, d_A (3), d_B (3), f0], ``coordSpringFrames`` = [F_A, F_B]; the tracked angles of
rotation ends are path state (``PathState.springAngles[s]``).
"""
from numba import njit

from .bodies import _side, add_point_force, add_world_torque, body_point
from .coordinate_angles import frame_angle
from .node_coordinates import PARAM_BASE, node_parameter


COORD_SPRING_FORCE = 9          # the column of f0 in coordSpringLaw


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
    """Body origin, and its velocity (position coordinate) or the world omega (rotation)."""
    body_point(g, R, r, V, zero3, p, v, b)
    if rot == 1:
        for i in range(3):
            v[i] = R[i, 0] * V[0] + R[i, 1] * V[1] + R[i, 2] * V[2]


@njit(cache=True, inline="always", _nrt=False)
def _parameter_side(code, body, R, V, bodyParameters, Cout, G, tmp):
    """(value, rate) of a node-parameter end (rate = the velocity coordinate C . omega);
    its direction C into ``Cout``."""
    if body < 0 or code < PARAM_BASE:
        return 0.0, 0.0
    v, _ = node_parameter(code, R[body], bodyParameters[body], V[body], G, Cout, tmp)
    return v, Cout[0] * V[body, 0] + Cout[1] * V[body, 1] + Cout[2] * V[body, 2]


@njit(cache=True, _nrt=False)
def coordinate_spring_value(gid, coordSpringEnds, coordSpringLaw, coordSpringFrames, bodyParameters, springAngles, s,
                            R, r, V, v3, ident, zero3, zero6):
    """(q_B - q_A - offset, qdot_B - qdot_A) of coordinate spring ``s``; the directions C of
    node-parameter ends in ``v3[7]`` (A) and ``v3[8]`` (B)."""
    pA, pB, vA, vB, bA, bB = v3[0], v3[1], v3[2], v3[3], v3[4], v3[5]
    kp = coordSpringLaw[s]
    gA, RA, rA, VA = _side(gid, coordSpringEnds[s, 0], R, r, V, ident, zero3, zero6)
    gB, RB, rB, VB = _side(gid, coordSpringEnds[s, 1], R, r, V, ident, zero3, zero6)
    _side_state(coordSpringEnds[s, 2], gA, RA, rA, VA, zero3, pA, vA, bA)
    _side_state(coordSpringEnds[s, 3], gB, RB, rB, VB, zero3, pB, vB, bB)
    qA, dqA = _coordinate(coordSpringEnds[s, 2], kp, 3, coordSpringFrames[s, 0], RA, pA, vA, springAngles[s, 0])
    qB, dqB = _coordinate(coordSpringEnds[s, 3], kp, 6, coordSpringFrames[s, 1], RB, pB, vB, springAngles[s, 1])
    # node-parameter ends: their direction d is 0, so _coordinate gave 0 for them
    xA, dxA = _parameter_side(coordSpringEnds[s, 2], coordSpringEnds[s, 0], R, V, bodyParameters, v3[7], v3[9],
                              v3[10])
    xB, dxB = _parameter_side(coordSpringEnds[s, 3], coordSpringEnds[s, 1], R, V, bodyParameters, v3[8], v3[9],
                              v3[10])
    return qB + xB - qA - xA - kp[2], dqB + dxB - dqA - dxA


@njit(cache=True, _nrt=False)
def coordinate_spring_forces(gid, coordSpringEnds, coordSpringLaw, coordSpringFrames, bodyParameters, springAngles,
                             R, r, V, Q, v3, ident, zero3, zero6):
    F = v3[6]
    for s in range(coordSpringEnds.shape[0]):
        a = coordSpringEnds[s, 0]
        b = coordSpringEnds[s, 1]
        kp = coordSpringLaw[s]
        u, ud = coordinate_spring_value(gid, coordSpringEnds, coordSpringLaw, coordSpringFrames, bodyParameters,
                                        springAngles, s, R, r, V, v3, ident, zero3, zero6)
        f = kp[0] * u + kp[1] * ud + kp[COORD_SPRING_FORCE]
        if a >= 0:
            if coordSpringEnds[s, 2] >= PARAM_BASE:          # e_k on the parametrisation's velocity coordinates
                for k in range(3):
                    Q[a, k] += f * v3[7, k]
            else:
                for k in range(3):
                    F[k] = f * kp[3 + k]
                if coordSpringEnds[s, 2] == 1:
                    add_world_torque(R[a], F, Q[a])
                else:
                    add_point_force(gid[a], R[a], zero3, F, Q[a])
        if b >= 0:
            if coordSpringEnds[s, 3] >= PARAM_BASE:
                for k in range(3):
                    Q[b, k] -= f * v3[8, k]
            else:
                for k in range(3):
                    F[k] = -f * kp[6 + k]
                if coordSpringEnds[s, 3] == 1:
                    add_world_torque(R[b], F, Q[b])
                else:
                    add_point_force(gid[b], R[b], zero3, F, Q[b])


@njit(cache=True, _nrt=False)
def coordinate_spring_energy(gid, coordSpringEnds, coordSpringLaw, coordSpringFrames, bodyParameters, springAngles,
                             R, r, V, v3, ident, zero3, zero6):
    """Potential ``k/2 (q_B - q_A - offset)^2`` of every coordinate spring (a potential of
    the force only where it acts along the coordinate's gradient: not on a rotation-vector
    parameter ('rotationVector'), whose force acts along C = e_k, see node_coordinates)."""
    e = 0.0
    for s in range(coordSpringEnds.shape[0]):
        u, _ = coordinate_spring_value(gid, coordSpringEnds, coordSpringLaw, coordSpringFrames, bodyParameters,
                                       springAngles, s, R, r, V, v3, ident, zero3, zero6)
        e += 0.5 * coordSpringLaw[s, 0] * u * u
    return e


# the element's entries (registered in mbs/force_elements.py)
@njit(cache=True, inline="always", _nrt=False)
def coordinate_spring_element(sd, wk, R, r, V, Q):
    coordinate_spring_forces(sd.gid, sd.coordSpringEnds, sd.coordSpringLaw, sd.coordSpringFrames,
                             wk.path.bodyParameters, wk.path.springAngles, R, r, V, Q, wk.v3, wk.ident, wk.zero3, wk.zero6)


@njit(cache=True, inline="always", _nrt=False)
def coordinate_spring_element_energy(sd, wk, R, r, V, e):
    """``e`` plus the coordinate springs' potential (summed on its own, then added)."""
    if sd.coordSpringEnds.shape[0] > 0:
        return e + coordinate_spring_energy(sd.gid, sd.coordSpringEnds, sd.coordSpringLaw, sd.coordSpringFrames,
                                            wk.path.bodyParameters, wk.path.springAngles, R, r, V, wk.v3, wk.ident, wk.zero3,
                                            wk.zero6)
    return e
