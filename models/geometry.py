"""Constraint violation and error measures computed from body states alone.

These formulas are an independent re-implementation of the joint equations (Exudyn's
``ObjectJointGeneric`` rows, which the kernel also follows), evaluated on stored
states ``R (nt, nb, 3, 3)``, ``r (nt, nb, 3)``.  They serve two purposes: measuring
Exudyn's native solutions, which have no kernel diagnostics, and checking the
kernel's own ``jointPositionViolation`` / ``jointRotationViolation``.

Rows of a joint with frames ``F_A = R_A rotA`` (at ``p_A``) and ``F_B = R_B rotB``:

* translations, ``d = p_B - p_A``: all three locked -> the world vector ``d``;
  otherwise ``F_A[:, i] . d`` for each locked axis ``i``;
* rotations: 3 locked -> ``z_A.y_B, z_A.x_B, x_A.y_B``; 2 locked (free axis f) ->
  ``f_A . l_B`` for both locked axes l; 1 locked (free f1 < f2) -> ``f1_A . f2_B``.

The position violation of a joint is the norm of its translation rows, the rotation
violation the norm of its rotation rows (as in :class:`exudyn_lie.mbs.Result`).
"""
import numpy as np

GROUND = -1


def _side(R, r, b, pos, rot):
    """World position and frame of a joint side over time."""
    nt = R.shape[0]
    if b == GROUND:
        return np.broadcast_to(pos, (nt, 3)), np.broadcast_to(rot, (nt, 3, 3))
    p = r[:, b] + np.einsum("nij,j->ni", R[:, b], pos)
    F = np.einsum("nij,jk->nik", R[:, b], rot)
    return p, F


def rotation_row_pairs(locked):
    """(axis on A, axis on B) of the rotation rows for the locked flags (tx..rz)."""
    lr = locked[3:]
    n = sum(lr)
    if n == 3:
        return [(2, 1), (2, 0), (0, 1)]
    if n == 2:
        f = [i for i in range(3) if not lr[i]][0]
        return [(f, l) for l in range(3) if lr[l]]
    if n == 1:
        f1, f2 = [i for i in range(3) if not lr[i]]
        return [(f1, f2)]
    return []


def joint_rows(joint, R, r):
    """(translation rows (nt, k), rotation rows (nt, l)) of one joint."""
    R = np.asarray(R, float)
    r = np.asarray(r, float)
    pA, FA = _side(R, r, joint.bodyA, joint.posA, joint.rotA)
    pB, FB = _side(R, r, joint.bodyB, joint.posB, joint.rotB)
    d = pB - pA
    lt = joint.lockedAxes[:3]
    if getattr(joint, "worldTranslation", False):
        trans = d[:, [i for i in range(3) if lt[i]]]
    elif all(lt):
        trans = d
    else:
        cols = [i for i in range(3) if lt[i]]
        trans = np.stack([np.einsum("ni,ni->n", FA[:, :, i], d) for i in cols], axis=1) if cols \
            else np.zeros((R.shape[0], 0))
    pairs = rotation_row_pairs(joint.lockedAxes)
    rot = np.stack([np.einsum("ni,ni->n", FA[:, :, a], FB[:, :, b]) for a, b in pairs], axis=1) if pairs \
        else np.zeros((R.shape[0], 0))
    return trans, rot


def joint_violations(joint, R, r):
    """(position violation (nt,), rotation violation (nt,)) of one joint."""
    trans, rot = joint_rows(joint, R, r)
    return np.linalg.norm(trans, axis=1), np.linalg.norm(rot, axis=1)


def joint_velocity_violations(joint, R, r, omega, vel):
    """Norm of the time derivative of all rows of a joint (velocity constraint residual);
    ``omega`` body-fixed, ``vel`` world velocity of the frame origins."""
    R = np.asarray(R, float)
    nt = R.shape[0]

    def side(b, pos, rot):
        p, F = _side(R, r, b, pos, rot)
        if b == GROUND:
            return p, F, np.zeros((nt, 3)), np.zeros((nt, 3))
        w = np.einsum("nij,nj->ni", R[:, b], omega[:, b])         # world angular velocity
        v = vel[:, b] + np.cross(w, np.einsum("nij,j->ni", R[:, b], pos))
        return p, F, v, w

    pA, FA, vA, wA = side(joint.bodyA, joint.posA, joint.rotA)
    pB, FB, vB, wB = side(joint.bodyB, joint.posB, joint.rotB)
    d, dd = pB - pA, vB - vA
    rows = []
    lt = joint.lockedAxes[:3]
    if all(lt) or getattr(joint, "worldTranslation", False):
        rows += [dd[:, i] for i in range(3) if lt[i]]
    else:
        for i in range(3):
            if lt[i]:
                a = FA[:, :, i]
                rows.append(np.einsum("ni,ni->n", np.cross(wA, a), d) + np.einsum("ni,ni->n", a, dd))
    for a, b in rotation_row_pairs(joint.lockedAxes):
        ea, eb = FA[:, :, a], FB[:, :, b]
        rows.append(np.einsum("ni,ni->n", np.cross(wA, ea), eb) + np.einsum("ni,ni->n", ea, np.cross(wB, eb)))
    return np.linalg.norm(np.stack(rows, axis=1), axis=1) if rows else np.zeros(nt)


def all_joint_violations(info, R, r):
    """{joint name: (position, rotation)} for every joint of a model."""
    return {j.name: joint_violations(j, R, r) for j in info.joints}


def so3_log_angle(Q):
    """Rotation angle ``||log Q||`` of rotation matrices (..., 3, 3), accurate near 0
    (uses the skew part, not the trace, for small angles)."""
    Q = np.asarray(Q, float)
    s = 0.5 * np.stack([Q[..., 2, 1] - Q[..., 1, 2], Q[..., 0, 2] - Q[..., 2, 0],
                        Q[..., 1, 0] - Q[..., 0, 1]], axis=-1)
    sn = np.linalg.norm(s, axis=-1)
    c = 0.5 * (np.trace(Q, axis1=-2, axis2=-1) - 1.0)
    return np.arctan2(sn, c)


def orientation_error(R_exact, R_num):
    """eps_r = ||log(R^T R_num)|| (paper, section "Unconstrained Rigid Body -- Reference Frame at COM")."""
    return so3_log_angle(np.einsum("...ji,...jk->...ik", R_exact, R_num))


def com_positions(info, R, r):
    """World COM positions (nt, nb, 3)."""
    c = np.array([b.com for b in info.bodies])
    return r + np.einsum("nbij,bj->nbi", R, c)
