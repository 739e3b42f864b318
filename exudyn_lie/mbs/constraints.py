"""Constraint rows of the joints: residual ``h``, Jacobian rows ``J`` and ``eta = -Jdot V``
(eq. index1) for the row kinds of the generic joint (:mod:`.codes` ROW_*).

For a row ``h(g) = 0``, ``J V`` is its time derivative and ``eta`` is minus the bias part
of ``hddot``: for ``h = a . d`` (a an axis, d a point difference)
``hddot = addot . d + 2 adot . ddot + a . dddot`` and the bias collects every term that
is quadratic in the velocities."""
from numba import njit

from .bodies import _cross, _matTvec, _side, body_axis, body_point, translation_dual
from .codes import (J_BODY_A, J_BODY_B, J_NROW, J_ROW0, ROW_AX, ROW_BX, ROW_COORD, ROW_COORD_VEL, ROW_DIST, ROW_KIND,
                    ROW_ROLL, ROW_ROT, ROW_TRANS_LOCAL, ROW_TRANS_WORLD, uses_body_twist)
from .coordinate_rows import coordinate_row
from .distance_rows import distance_row
from .node_coordinates import PARAM_BASE, node_parameter_terms
from .presence import guarded
from .rolling_disc_rows import rolling_disc_row


# --------------------------------------------------------------------------- constraints
@njit(cache=True, inline="always", _nrt=False)
def extra_row(kind, q, j, a, b, gA, gB, RA, RB, rA, rB, VA, VB, rowIndex, rotA, rotB, jointParams, bodyParameters,
              jointAngles, v3, h, Jr, eta, rdrive):
    """Row ``q`` of joint ``j`` of a coordinate or rolling-disc kind (:func:`joint_rows`; its
    points and scratch in ``v3``; fewer than 30 arguments: a longer call is a star-argument
    call in Python's bytecode, which numba's inliner refuses)."""
    rax = rowIndex[q, ROW_AX]
    pA, pB, vB, bA, bB = v3[0], v3[1], v3[3], v3[4], v3[5]
    ax, axd, axb, bx, bxd, bxb = v3[11], v3[12], v3[13], v3[14], v3[15], v3[16]
    u, RtA = v3[17], v3[19]
    if kind == ROW_COORD or kind == ROW_COORD_VEL:
        coordinate_row(q, a, b, gA, gB, RA, RB, rax, rowIndex[q, ROW_BX], rotA, rotB, jointParams[j], jointAngles[j],
                       pA, pB, bA, bB, u, RtA, h, Jr, eta)
        if rax >= PARAM_BASE or rowIndex[q, ROW_BX] >= PARAM_BASE:     # rotation parameters of 3D bodies
            node_parameter_terms(q, a, b, rax, rowIndex[q, ROW_BX], RA, RB, VA, VB, bodyParameters,
                                 jointParams[j, 0], h, Jr, eta, ax, axd, axb)
        if kind == ROW_COORD_VEL:
            # velocity level: J V = w(t) constrains no position (as ROW_ROLL); the same J, and
            # eta = -Jdot V, since d/dt (J V - w) = J Vdot + Jdot V - wdot (wdot: row_drives)
            h[q] = 0.0
        else:
            h[q] -= rdrive[0, q]          # h(g) - c(t)
        eta[q] += rdrive[2, q]            # + cddot(t) (velocity level: + wdot(t))
    elif kind == ROW_ROLL:
        rolling_disc_row(q, rax, a, b, gA, gB, RA, RB, rA, rB, VA, VB, rotA, rotB, jointParams[j], pB, vB, ax, axd,
                         axb, bx, bxd, bxb, u, h, Jr, eta)


extra_row_if = guarded(extra_row)


@njit(cache=True, inline="always", _nrt=False)
def _rotation_row(q, rowIndex, rax, a, b, RA, VA, RB, VB, rotA, rotB, u, w, ax, axd, axb, bx, bxd, bxb, RtA, h, Jr,
                  eta):
    """A rotation row: ``h = a . b`` of an axis of frame A and one of frame B (a locked
    relative rotation of the generic joint), its Jacobian on both sides' angular velocities
    and ``eta``."""
    rbx = rowIndex[q, ROW_BX]
    for k in range(3):
        u[k] = rotA[k, rax]
        w[k] = rotB[k, rbx]
    body_axis(RA, VA, u, ax, axd, axb)
    body_axis(RB, VB, w, bx, bxd, bxb)
    hv = 0.0
    et = 0.0
    for k in range(3):
        hv += ax[k] * bx[k]
        et += axb[k] * bx[k] + 2.0 * axd[k] * bxd[k] + ax[k] * bxb[k]
    h[q] = hv
    eta[q] = -et
    if a >= 0:
        _matTvec(RA, bx, RtA)          # u x (RA^T b)
        c0, c1, c2 = _cross(u[0], u[1], u[2], RtA[0], RtA[1], RtA[2])
        Jr[q, 0] = c0
        Jr[q, 1] = c1
        Jr[q, 2] = c2
    if b >= 0:
        _matTvec(RB, ax, RtA)          # w x (RB^T a)
        c0, c1, c2 = _cross(w[0], w[1], w[2], RtA[0], RtA[1], RtA[2])
        Jr[q, 6] = c0
        Jr[q, 7] = c1
        Jr[q, 8] = c2


@njit(cache=True, inline="always", _nrt=False)
def _world_translation_row(q, rax, a, b, gA, gB, RA, RB, sA, sB, d, bd, h, Jr, eta):
    """A translation row along world axis ``rax``: ``h = d[rax]`` of the points' distance."""
    # a = e_ax: the general branch below with its zeros left out (adot = 0, abias = 0,
    # R^T a = row ax of R); the same values to the bit, in about half the time.  A branch of
    # its own on purpose: folded into the general branch (R^T a read as a row of R there,
    # the sums shortened), states bit-identical, the step got slower: heavy top 1.00-1.06 ->
    # 1.25-1.36 us, double pendulum 2.15-2.18 -> 2.26-2.39 us (bench --sections perstep
    # --quick --models heavytop,doublependulum, twice interleaved)
    h[q] = d[rax]
    eta[q] = -bd[rax]
    if a >= 0:
        c0, c1, c2 = _cross(RA[rax, 0], RA[rax, 1], RA[rax, 2], sA[0], sA[1], sA[2])
        Jr[q, 0] = c0
        Jr[q, 1] = c1
        Jr[q, 2] = c2
        if uses_body_twist(gA):     # v_A: -T_A^T a (translation_dual)
            Jr[q, 3] = -RA[rax, 0]
            Jr[q, 4] = -RA[rax, 1]
            Jr[q, 5] = -RA[rax, 2]
        else:
            Jr[q, 3 + rax] = -1.0
    if b >= 0:
        c0, c1, c2 = _cross(sB[0], sB[1], sB[2], RB[rax, 0], RB[rax, 1], RB[rax, 2])
        Jr[q, 6] = c0
        Jr[q, 7] = c1
        Jr[q, 8] = c2
        if uses_body_twist(gB):
            Jr[q, 9] = RB[rax, 0]
            Jr[q, 10] = RB[rax, 1]
            Jr[q, 11] = RB[rax, 2]
        else:
            Jr[q, 9 + rax] = 1.0


@njit(cache=True, inline="always", _nrt=False)
def _axis_translation_row(q, kind, rax, a, b, j, gA, gB, RA, VA, RB, sA, sB, rotA, jointParams, u, ax, axd, axb, d,
                          dd, bd, dAl, RtA, h, Jr, eta):
    """A translation row along an axis of frame A (local), a world axis through the general
    branch, or a distance row: ``h = a . d``, its Jacobian and ``eta``."""
    if kind == ROW_TRANS_LOCAL:
        for k in range(3):
            u[k] = rotA[k, rax]
        body_axis(RA, VA, u, ax, axd, axb)
    elif kind == ROW_DIST:
        distance_row(q, jointParams[j, 0], d, dd, bd, ax, h, eta)    # ax <- e, the row's world direction
    else:
        for k in range(3):
            ax[k] = 0.0
            axd[k] = 0.0
            axb[k] = 0.0
        ax[rax] = 1.0
    if kind != ROW_DIST:
        hv = 0.0
        et = 0.0
        for k in range(3):
            hv += ax[k] * d[k]
            et += axb[k] * d[k] + 2.0 * axd[k] * dd[k] + ax[k] * bd[k]
        h[q] = hv
        eta[q] = -et
    if a >= 0:
        _matTvec(RA, ax, RtA)          # RA^T a
        if kind == ROW_TRANS_LOCAL:
            # -(a . pdot_A) + adot . d -> omega_A . (u x RA^T (pB - rA)) since RA^T a = u
            c0, c1, c2 = _cross(u[0], u[1], u[2], dAl[0], dAl[1], dAl[2])
        else:
            # -(a . pdot_A) -> omega_A . (RA^T a x sA)
            c0, c1, c2 = _cross(RtA[0], RtA[1], RtA[2], sA[0], sA[1], sA[2])
        Jr[q, 0] = c0
        Jr[q, 1] = c1
        Jr[q, 2] = c2
        Ta = translation_dual(gA, ax, RtA)     # v_A: -T_A^T a
        Jr[q, 3] = -Ta[0]
        Jr[q, 4] = -Ta[1]
        Jr[q, 5] = -Ta[2]
    if b >= 0:
        _matTvec(RB, ax, RtA)          # RB^T a
        c0, c1, c2 = _cross(sB[0], sB[1], sB[2], RtA[0], RtA[1], RtA[2])
        Jr[q, 6] = c0
        Jr[q, 7] = c1
        Jr[q, 8] = c2
        Ta = translation_dual(gB, ax, RtA)     # v_B: T_B^T a
        Jr[q, 9] = Ta[0]
        Jr[q, 10] = Ta[1]
        Jr[q, 11] = Ta[2]


@njit(cache=True, forceinline=True, _nrt=False)
def joint_rows(j, gid, jointIndex, jointPoints, jointFrames, jointParams, rowIndex, rowsAll, bodyParameters,
               jointAngles, R, r, V, h, Jr, eta, rdrive, v3, ident, zero3, zero6):
    """Residual ``h``, Jacobian rows ``Jr`` (row, 12: 6 for side A, 6 for side B) and
    ``eta = -Jdot V`` of all rows of joint ``j``, written at the joint's row slots
    (``rowsAll``: SceneData.rowsAll, None compiles no coordinate and rolling-disc rows, mbs/presence.py;
    ``bodyParameters``: the node rotation parameters tracked per body, Work.bodyParameters; ``rdrive``: the
    time-dependent part of a coordinate row, :mod:`.row_drives`)."""
    a = jointIndex[j, J_BODY_A]
    b = jointIndex[j, J_BODY_B]
    gA, RA, rA, VA = _side(gid, a, R, r, V, ident, zero3, zero6)
    gB, RB, rB, VB = _side(gid, b, R, r, V, ident, zero3, zero6)
    sA = jointPoints[j, 0]
    sB = jointPoints[j, 1]
    rotA = jointFrames[j, 0]
    rotB = jointFrames[j, 1]
    pA, pB, vA, vB, bA, bB = v3[0], v3[1], v3[2], v3[3], v3[4], v3[5]
    d, dd, bd, dAl, tmp = v3[6], v3[7], v3[8], v3[9], v3[10]
    ax, axd, axb, bx, bxd, bxb = v3[11], v3[12], v3[13], v3[14], v3[15], v3[16]
    u, w, RtA = v3[17], v3[18], v3[19]
    body_point(gA, RA, rA, VA, sA, pA, vA, bA)
    body_point(gB, RB, rB, VB, sB, pB, vB, bB)
    for k in range(3):
        d[k] = pB[k] - pA[k]
        dd[k] = vB[k] - vA[k]
        bd[k] = bB[k] - bA[k]
    # RA^T (pB - rA): lever of the A-axis rotation, used by the local translation rows
    for k in range(3):
        tmp[k] = pB[k] - rA[k]
    _matTvec(RA, tmp, dAl)
    row0 = jointIndex[j, J_ROW0]
    for q in range(row0, row0 + jointIndex[j, J_NROW]):
        for k in range(12):
            Jr[q, k] = 0.0
        kind = rowIndex[q, ROW_KIND]
        rax = rowIndex[q, ROW_AX]
        if kind == ROW_COORD or kind == ROW_COORD_VEL or kind == ROW_ROLL:
            # not in a lean scene: compiled only for full ones (mbs/presence.py)
            extra_row_if(rowsAll, kind, q, j, a, b, gA, gB, RA, RB, rA, rB, VA, VB, rowIndex, rotA, rotB,
                         jointParams, bodyParameters, jointAngles, v3,
                         h, Jr, eta, rdrive)
        elif kind == ROW_ROT:
            _rotation_row(q, rowIndex, rax, a, b, RA, VA, RB, VB, rotA, rotB, u, w, ax, axd, axb, bx, bxd, bxb, RtA,
                          h, Jr, eta)
        elif kind == ROW_TRANS_WORLD:
            _world_translation_row(q, rax, a, b, gA, gB, RA, RB, sA, sB, d, bd, h, Jr, eta)
        else:
            _axis_translation_row(q, kind, rax, a, b, j, gA, gB, RA, VA, RB, sA, sB, rotA, jointParams, u, ax, axd,
                                  axb, d, dd, bd, dAl, RtA, h, Jr, eta)


@njit(cache=True, inline="always", _nrt=False)
def joints_rows(gid, jointIndex, jointPoints, jointFrames, jointParams, rowIndex, rowsAll, bodyParameters,
                jointAngles, R, r, V, h, Jr, eta, rdrive, v3, ident, zero3, zero6):
    """:func:`joint_rows` of every joint.  ``rdrive`` (3, m): the time-dependent part of the
    coordinate rows at the evaluation time (:mod:`.row_drives`): ``h - c(t)``, ``eta + cddot(t)``
    (the rate ``cdot(t)`` is the velocity target ``J V = cdot`` of the projections).  (Applied
    in the coordinate rows' branch: a loop over all rows here cost the heavy top 0.4 us of its
    2.9 us per step, measured.)"""
    for j in range(jointIndex.shape[0]):
        joint_rows(j, gid, jointIndex, jointPoints, jointFrames, jointParams, rowIndex, rowsAll, bodyParameters,
                   jointAngles, R, r, V, h, Jr, eta, rdrive, v3, ident, zero3, zero6)
