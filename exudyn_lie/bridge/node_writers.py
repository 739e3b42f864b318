"""The compiled write-back of node coordinates (a part of :mod:`.nodes`): one row writer per
node type (``*_row``: from ``(R, omega, omegadot)`` to the total rotation parameters, their
rates and second derivatives, continuous from one call to the next), selected by the node
kind's ``code`` in :func:`write_row`; :func:`write_nodes` / :func:`write_all` /
:func:`write_rows` write all nodes (and the joint multipliers) of one or many output rows in
one call.  The node codes and their writers are listed here; the node kinds in
:mod:`.nodes`."""
import math

import numpy as np
from numba import njit

from ..mbs.codes import uses_body_twist
from ..mbs.presence import guarded
from ..mbs.rotation_parameters import nearest_quat, nearest_tait_bryan, quat_of, quat_rotvec

CODE_ROTVEC = 0
CODE_EP = 1
CODE_RXYZ = 2
CODE_POINT = 3          # NodePoint: 3 position coordinates, no rotation
CODE_POINT2D = 4        # NodePoint2D: x, y
CODE_2D = 5             # NodeRigidBody2D: [x, y, phi]
CODE_1D = 6             # Node1D of an ObjectMass1D: one coordinate x = axis . (r - origin)
CODE_1D_ROT = 7         # Node1D of an ObjectRotationalMass1D: the angle of R = F Rz(x)
NCOORD_MAX = 7          # position (3) + at most 4 rotation parameters
TWO_PI = 2.0 * math.pi
ROTVEC_TURNOVER = 1e-8  # RotVecLG: within this of |theta| = 2 pi the short vector is written (rotvec_row)
RXYZ_WARN_COS = math.cos(math.radians(85.0))


# ---------------------------------------------------------------------------- compiled row writers
# One function per node type: from (R, omega_local, omegadot_local) to the total rotation
# parameters p, their rate p_t and p_tt; ``prev`` (4) holds the last written parameters
# (continuity) and is updated.  Returns 1 if an Rxyz node is near its singularity.

@njit(cache=True)
def rotvec_row(R, omega, omegad, prev, first, p, p_t, p_tt, qv):
    """NodeRigidBodyRotVecLG: Exudyn's total rotation vector ``2 acos(q0) qv / |qv|`` of the
    sign-continuous quaternion q of R (kept in ``prev``; mbs.rotation_parameters: Exudyn's Lie
    group update composes quaternions, so |theta| <= 2 pi and turns over at 2 pi); ``qv``:
    scratch (4).  The row writers allocate nothing (see :func:`write_nodes`)."""
    if first:
        quat_of(R, qv)
    else:
        nearest_quat(R, prev, qv)
    quat_rotvec(qv, p)
    t = math.sqrt(p[0] ** 2 + p[1] ** 2 + p[2] ** 2)
    if t > TWO_PI - ROTVEC_TURNOVER:
        # at the turnover (R ~ I): Exudyn 1.13.6 evaluates |theta| > 2 pi wrongly (even by one
        # rounding error of the norm), so write the same rotation's short vector (theta - 2 pi) n
        g = (t - TWO_PI) / t
        for k in range(3):
            p[k] *= g
    for k in range(4):
        prev[k] = qv[k]
    for k in range(3):
        p_t[k] = omega[k]
        p_tt[k] = omegad[k]
    return 0


@njit(cache=True)
def _ep_glocal_T_apply(e, w, out):
    """out = GL(e)^T w,  GL(e) = 2 [-e_v, e0 I - hat(e_v)]."""
    e0, e1, e2, e3 = e[0], e[1], e[2], e[3]
    out[0] = 2.0 * (-e1 * w[0] - e2 * w[1] - e3 * w[2])
    out[1] = 2.0 * (e0 * w[0] - e3 * w[1] + e2 * w[2])
    out[2] = 2.0 * (e3 * w[0] + e0 * w[1] - e1 * w[2])
    out[3] = 2.0 * (-e2 * w[0] + e1 * w[1] + e0 * w[2])


@njit(cache=True)
def ep_row(R, omega, omegad, prev, first, p, p_t, p_tt, tmp):
    """NodeRigidBodyEP: sign-continuous Euler parameters, ep_t = GL^T omega / 4,
    ep_tt = (GL(ep_t)^T omega + GL(ep)^T omegadot) / 4; ``tmp``: scratch (4)."""
    if first:
        quat_of(R, p)
    else:
        nearest_quat(R, prev, p)
    _ep_glocal_T_apply(p, omega, tmp)
    for k in range(4):
        p_t[k] = 0.25 * tmp[k]
        prev[k] = p[k]
    _ep_glocal_T_apply(p_t, omega, tmp)
    for k in range(4):
        p_tt[k] = 0.25 * tmp[k]
    _ep_glocal_T_apply(p, omegad, tmp)
    for k in range(4):
        p_tt[k] += 0.25 * tmp[k]
    return 0


@njit(cache=True)
def _wrap_near(x, ref):
    # np.rint, not np.round: the same value (round half to even), but np.round's numba
    # implementation lives in numba.np.arraymath, which imports scipy.linalg when a
    # cached kernel is loaded (0.12 s of a warm start)
    return x + TWO_PI * np.rint((ref - x) / TWO_PI)


@njit(cache=True)
def rxyz_row(R, omega, omegad, prev, first, p, p_t, p_tt):
    """NodeRigidBodyRxyz: the Tait-Bryan solution (of two, modulo 2 pi) nearest to the
    previous angles; rates a_t = GR^-1 omega, a_tt = GR^-1 (omegadot - GRdot a_t)."""
    if first:
        c1 = math.sqrt(R[1, 2] ** 2 + R[2, 2] ** 2)
        p[1] = math.atan2(R[0, 2], c1)
        if c1 > 1e-14:
            p[0] = math.atan2(-R[1, 2], R[2, 2])
            p[2] = math.atan2(-R[0, 1], R[0, 0])
        else:
            p[0] = 0.0
            p[2] = math.atan2(R[1, 0], R[1, 1])
    else:
        nearest_tait_bryan(R, prev, p)
    for k in range(3):
        prev[k] = p[k]
    cb, sb = math.cos(p[1]), math.sin(p[1])
    cc, sc = math.cos(p[2]), math.sin(p[2])
    # inverse of GR = [[cb cc, sc, 0], [-cb sc, cc, 0], [sb, 0, 1]]
    p_t[0] = (cc * omega[0] - sc * omega[1]) / cb
    p_t[1] = sc * omega[0] + cc * omega[1]
    p_t[2] = omega[2] - sb * p_t[0]
    d1, d2 = p_t[1], p_t[2]
    # GRdot a_t
    g0 = (-sb * cc * d1 - cb * sc * d2) * p_t[0] + cc * d2 * p_t[1]
    g1 = (sb * sc * d1 - cb * cc * d2) * p_t[0] - sc * d2 * p_t[1]
    g2 = cb * d1 * p_t[0]
    w0, w1, w2 = omegad[0] - g0, omegad[1] - g1, omegad[2] - g2
    p_tt[0] = (cc * w0 - sc * w1) / cb
    p_tt[1] = sc * w0 + cc * w1
    p_tt[2] = w2 - sb * p_tt[0]
    return 1 if abs(cb) < RXYZ_WARN_COS else 0


@njit(cache=True)
def planar_row(R, omega, omegad, prev, first, p, p_t, p_tt, t, tracked):
    """NodeRigidBody2D: the angle phi of R = Rz(phi) at time ``t``, continued over turns: the
    2 pi shift nearest to ``tracked`` if that is finite (the kernel's angle tracked step by step,
    Work.bodyAngles: exact, given for the simulator's current state), else nearest to the
    last written angle ``prev[0]`` advanced by the trapezoidal integral of omega_z since its
    time ``prev[2]`` (``prev[1]`` its omega_z), for outputs inside a chunk;
    phi_t = omega_z, phi_tt = omegadot_z."""
    p[0] = continued_angle(math.atan2(R[1, 0], R[0, 0]), omega[2], prev, first, t, tracked)
    p_t[0] = omega[2]
    p_tt[0] = omegad[2]
    return 0


@njit(cache=True)
def continued_angle(a, omz, prev, first, t, tracked):
    """The angle ``a`` (principal) shifted by 2 pi turns: nearest to ``tracked`` if finite (the
    kernel's angle tracked step by step, exact), else to the last written angle ``prev[0]``
    advanced by the trapezoidal integral of its rate since ``prev[2]`` (``prev[1]`` the rate
    then); updates ``prev`` = (angle, rate ``omz``, time ``t``)."""
    if first:
        out = a
    elif math.isfinite(tracked):
        out = _wrap_near(a, tracked)
    else:
        out = _wrap_near(a, prev[0] + 0.5 * (prev[1] + omz) * (t - prev[2]))
    prev[0] = out
    prev[1] = omz
    prev[2] = t
    return out


#: the row writers in the order of :func:`present_writers`' tuple (CODE_ROTVEC, CODE_EP, CODE_RXYZ, CODE_2D)
WRITER_CODES = (CODE_ROTVEC, CODE_EP, CODE_RXYZ, CODE_2D)
_rotvec_row_if = guarded(rotvec_row, default=0)
_ep_row_if = guarded(ep_row, default=0)
_rxyz_row_if = guarded(rxyz_row, default=0)
_planar_row_if = guarded(planar_row, default=0)


def present_writers(codes):
    """The ``present`` argument of :func:`write_row` for nodes of the compiled writer codes
    ``codes``: per row writer of :data:`WRITER_CODES` an empty array if some node needs it,
    else None, so that the write-back compiles only the writers the scene uses (its type
    differs per combination; mbs/presence.py)."""
    used = set(int(c) for c in codes)
    return tuple(np.zeros(0) if c in used else None for c in WRITER_CODES)


@njit(cache=True)
def write_row(code, R, omega, omegad, prev, first, p, p_t, p_tt, t, tracked, tmp, present):
    """Rotation parameters of one node by its ``code``; ``present``: :func:`present_writers`."""
    if code == CODE_POINT or code == CODE_POINT2D or code == CODE_1D or code == CODE_1D_ROT:
        return 0                         # no rotation parameters
    if code == CODE_2D:
        return _planar_row_if(present[3], R, omega, omegad, prev, first, p, p_t, p_tt, t, tracked)
    if code == CODE_ROTVEC:
        return _rotvec_row_if(present[0], R, omega, omegad, prev, first, p, p_t, p_tt, tmp)
    elif code == CODE_EP:
        return _ep_row_if(present[1], R, omega, omegad, prev, first, p, p_t, p_tt, tmp)
    return _rxyz_row_if(present[2], R, omega, omegad, prev, first, p, p_t, p_tt)


# ---------------------------------------------------------------------------- all nodes at once
# (kept in this file: numba's cache is invalidated only by changes of the defining file)
@njit(cache=True)
def write_nodes(gid, R, r, V, Vdot, doacc, code, body, idx, nq, qref, prev, first, q, qt, qtt, flags, t, tracked, exact,
                scratch, present):
    """Node coordinates from the body states (R, r, V) and accelerations Vdot (in each
    body's group velocity coordinates: SE3 v body-fixed, SO3xR3 v = rdot).  With ``exact``,
    ``tracked`` (nb, 4) holds what the kernel tracked at this state step by step
    (mbs.rotation_parameters.record_tracked: angle of a 2D body / rotor, quaternion of EP and
    RotVecLG nodes, Tait-Bryan angles of Rxyz nodes): the rotation parameters written are
    those, i.e. Exudyn's continuous branch however far apart the outputs are.  ``scratch``
    (8, 4): the working vectors, zeroed here; nothing is allocated, so the compiled
    write-back needs no numba array allocator (its implementation module is not imported
    when the cached code is loaded: 14 ms CPU of a warm first solve)."""
    for i in range(scratch.shape[0]):
        for k in range(4):
            scratch[i, k] = 0.0
    om = scratch[0, :3]
    vel = scratch[1, :3]
    omd = scratch[2, :3]
    acc = scratch[3, :3]
    p = scratch[4]
    pt = scratch[5]
    ptt = scratch[6]
    nflag = 0
    for i in range(code.shape[0]):
        b = body[i]
        Rb = R[b]
        for k in range(3):
            om[k] = V[b, k]
        if uses_body_twist(gid[b]):
            for k in range(3):
                vel[k] = Rb[k, 0] * V[b, 3] + Rb[k, 1] * V[b, 4] + Rb[k, 2] * V[b, 5]
        else:
            for k in range(3):
                vel[k] = V[b, 3 + k]
        if doacc:
            for k in range(3):
                omd[k] = Vdot[b, k]
            if uses_body_twist(gid[b]):
                # a = R (vdot + omega x v)
                w0, w1, w2 = V[b, 0], V[b, 1], V[b, 2]
                v0, v1, v2 = V[b, 3], V[b, 4], V[b, 5]
                a0 = Vdot[b, 3] + w1 * v2 - w2 * v1
                a1 = Vdot[b, 4] + w2 * v0 - w0 * v2
                a2 = Vdot[b, 5] + w0 * v1 - w1 * v0
                for k in range(3):
                    acc[k] = Rb[k, 0] * a0 + Rb[k, 1] * a1 + Rb[k, 2] * a2
            else:
                for k in range(3):
                    acc[k] = Vdot[b, 3 + k]
        if exact and (code[i] == CODE_EP or code[i] == CODE_ROTVEC or code[i] == CODE_RXYZ):
            for k in range(4):
                prev[i, k] = tracked[b, k]     # the row writer's nearest branch is then this one
        f = write_row(code[i], Rb, om, omd, prev[i], first, p, pt, ptt, t, tracked[b, 0] if exact else math.nan,
                      scratch[7], present)
        if f:
            flags[i] = 1                 # kept until the warning is given (warn_flags)
            nflag += 1
        if code[i] == CODE_1D:
            # qref row = (axis . origin + reference coordinate, axis): x = axis . r - qref[0]
            j = idx[i, 0]
            x = -qref[i, 0]
            xt = 0.0
            xtt = 0.0
            for k in range(3):
                x += qref[i, 1 + k] * r[b, k]
                xt += qref[i, 1 + k] * vel[k]
                xtt += qref[i, 1 + k] * acc[k]
            q[j] = x
            qt[j] = xt
            if doacc:
                qtt[j] = xtt
            continue
        if code[i] == CODE_1D_ROT:
            # qref row = (reference angle, F e_x): the angle of R = F Rz(x), atan2(-(F e_x) . R e_y,
            # (F e_x) . R e_x) as coordinate_angles.frame_angle, continued over turns
            c = qref[i, 1] * Rb[0, 0] + qref[i, 2] * Rb[1, 0] + qref[i, 3] * Rb[2, 0]
            s = -(qref[i, 1] * Rb[0, 1] + qref[i, 2] * Rb[1, 1] + qref[i, 3] * Rb[2, 1])
            j = idx[i, 0]
            q[j] = continued_angle(math.atan2(s, c), om[2], prev[i], first, t,
                                   tracked[b, 0] if exact else math.nan) - qref[i, 0]
            qt[j] = om[2]
            if doacc:
                qtt[j] = omd[2]
            continue
        npos = 2 if (code[i] == CODE_POINT2D or code[i] == CODE_2D) else 3
        for k in range(npos):
            q[idx[i, k]] = r[b, k] - qref[i, k]
            qt[idx[i, k]] = vel[k]
            if doacc:
                qtt[idx[i, k]] = acc[k]
        for k in range(nq[i] - npos):
            j = idx[i, npos + k]
            q[j] = p[k] - qref[i, npos + k]
            qt[j] = pt[k]
            if doacc:
                qtt[j] = ptt[k]
    return nflag


@njit(cache=True)
def write_multipliers(lam, jrow, jae, ae):
    for i in range(jrow.shape[0]):
        ae[jae[i]] = lam[jrow[i]]


@njit(cache=True)
def write_all(gid, R, r, V, Vdot, lam, doacc, code, body, idx, nq, qref, prev, q, qt, qtt, flags, jrow, jae, ae, t,
              tracked, exact, scratch, present):
    """write_nodes + write_multipliers of one state (at time ``t``; ``exact``: ``tracked`` holds
    the kernel's tracked values at it, write_nodes)."""
    if doacc:
        write_multipliers(lam, jrow, jae, ae)
    return write_nodes(gid, R, r, V, Vdot, doacc, code, body, idx, nq, qref, prev, False, q, qt, qtt, flags, t,
                       tracked, exact, scratch, present)


@njit(cache=True)
def write_rows(nrows, gid, Rs, rs, Vs, Vdots, lams, doacc, code, body, idx, nq, qref, prev, Q, Qt, Qtt, flags, jrow,
               jae, AE, To, Po, scratch, present):
    """:func:`write_all` of the states ``Rs[o], rs[o], Vs[o]`` at times ``To[o]`` (accelerations
    ``Vdots[o]``, multipliers ``lams[o]``) into rows ``o < nrows`` of ``Q, Qt, Qtt, AE``, in order,
    with the angles and rotation parameters the kernel tracked at each state in ``Po[o]``
    (mbs.rotation_parameters; rows beyond ``Po``'s: continuous from the previous row).  The single compiled entry of
    the write-back: every path uses it, one state being one row.  Returns the number of
    flagged (node, row) pairs.  ``scratch``: (8, 4) working array (:func:`write_nodes`);
    ``present``: the row writers compiled (:func:`present_writers` of the nodes' codes)."""
    nflag = 0
    for o in range(nrows):
        nflag += write_all(gid, Rs[o], rs[o], Vs[o], Vdots[o], lams[o], doacc, code, body, idx, nq, qref, prev,
                           Q[o], Qt[o], Qtt[o], flags, jrow, jae, AE[o], To[o], Po[min(o, Po.shape[0] - 1)],
                           o < Po.shape[0], scratch, present)
    return nflag
