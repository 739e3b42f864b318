"""Applied and inertial generalised forces of the compiled kernel, one function per
force element (gravity, loads, point-to-point, Cartesian, torsional and rigid-body
spring-dampers) and the elements' entries on the scene tuples; ``compute_forces``, which adds
those a scene has, is generated from their registrations in :mod:`.force_elements`."""
import numpy as np
from numba import njit

from ..groups import so3
from .bodies import (_matvec, _side, add_pair_force, add_point_force, add_world_torque, body_inertial_forces,
                     body_point, connector_ends)
from .codes import L_BODY, L_FIXED, L_KIND


# --------------------------------------------------------------------------- forces
@njit(cache=True, inline="always", _nrt=False)
def gravity_forces(gid, mass, com, gravity, R, Q, F):
    """Gravity acts at the centre of mass."""
    for i in range(gid.shape[0]):
        for k in range(3):
            F[k] = mass[i] * gravity[k]
        add_point_force(gid[i], R[i], com[i], F, Q[i])


@njit(cache=True, inline="always", _nrt=False)
def load_forces(gid, loadIndex, loadVectors, R, Q, F):
    """Constant forces (at a body point) and torques, world or body-fixed."""
    for l in range(loadIndex.shape[0]):
        i = loadIndex[l, L_BODY]
        if loadIndex[l, L_KIND] == 0:
            if loadIndex[l, L_FIXED]:
                _matvec(R[i], loadVectors[l, 0], F)
            else:
                for k in range(3):
                    F[k] = loadVectors[l, 0, k]
            add_point_force(gid[i], R[i], loadVectors[l, 1], F, Q[i])
        else:
            if loadIndex[l, L_FIXED]:
                for k in range(3):
                    Q[i, k] += loadVectors[l, 0, k]
            else:
                add_world_torque(R[i], loadVectors[l, 0], Q[i])


@njit(cache=True, inline="always", _nrt=False)
def spring_length_rate(pA, pB, vA, vB):
    """The length ``L = |p_B - p_A|`` of a point-to-point spring and its rate ``Ldot = (p_B -
    p_A) . (v_B - v_A) / L``; ``Ldot = 0`` where ``L = 0`` (the direction is undefined there)."""
    L = 0.0
    for k in range(3):
        L += (pB[k] - pA[k]) ** 2
    L = np.sqrt(L)
    if L < 1e-300:
        return L, 0.0
    Ld = 0.0
    for k in range(3):
        Ld += (pB[k] - pA[k]) * (vB[k] - vA[k])
    return L, Ld / L


@njit(cache=True, forceinline=True, _nrt=False)
def spring_forces(gid, springBodies, springPoints, springLaw, R, r, V, Q, v3, ident, zero3, zero6):
    """Point-to-point spring-dampers: tension ``f = k (L - L0) + d Ldot + f0``
    (``springLaw`` = k, d, L0, f0)."""
    pA, pB, vA, vB, F = v3[0], v3[1], v3[2], v3[3], v3[6]
    for s in range(springBodies.shape[0]):
        a = springBodies[s, 0]
        b = springBodies[s, 1]
        gA, RA, gB, RB = connector_ends(gid, a, b, springPoints[s, 0], springPoints[s, 1], R, r, V, v3, ident, zero3,
                                        zero6)
        L, Ld = spring_length_rate(pA, pB, vA, vB)
        if L < 1e-300:
            continue  # direction undefined: zero-length spring exerts no force
        f = springLaw[s, 0] * (L - springLaw[s, 2]) + springLaw[s, 1] * Ld + springLaw[s, 3]
        for k in range(3):
            F[k] = f * (pB[k] - pA[k]) / L
        add_pair_force(gA, RA, springPoints[s, 0], a, gB, RB, springPoints[s, 1], b, F, Q)


@njit(cache=True, _nrt=False)
def cartesian_forces(gid, cartesianBodies, cartesianPoints, cartesianLaw, R, r, V, Q, v3, ident, zero3, zero6):
    """Cartesian spring-dampers, world components ``f_i = k_i (d_i - o_i) + c_i ddot_i``
    (``cartesianLaw[s]`` = rows k, c, o)."""
    pA, pB, vA, vB, F = v3[0], v3[1], v3[2], v3[3], v3[6]
    for s in range(cartesianBodies.shape[0]):
        a = cartesianBodies[s, 0]
        b = cartesianBodies[s, 1]
        gA, RA, gB, RB = connector_ends(gid, a, b, cartesianPoints[s, 0], cartesianPoints[s, 1], R, r, V, v3, ident,
                                        zero3, zero6)
        for k in range(3):
            F[k] = cartesianLaw[s, 0, k] * (pB[k] - pA[k] - cartesianLaw[s, 2, k]) + cartesianLaw[s, 1, k] * (vB[k] - vA[k])
        add_pair_force(gA, RA, cartesianPoints[s, 0], a, gB, RB, cartesianPoints[s, 1], b, F, Q)


@njit(cache=True, _nrt=False)
def torsion_angle(rotA, rotB, prev, RA, VA, RB, VB, FA, FB):
    """Relative rotation angle about z of frame A (tracked continuously through turns
    from the angle ``prev`` at the last accepted step) and its rate."""
    # relative rotation Rrel = (RA rotA)^T (RB rotB); phi is its third Tait-Bryan (x-y-z)
    # angle, atan2(-Rrel[0,1], Rrel[0,0])
    for i in range(3):
        for j in range(3):
            FA[i, j] = RA[i, 0] * rotA[0, j] + RA[i, 1] * rotA[1, j] + RA[i, 2] * rotA[2, j]
            FB[i, j] = RB[i, 0] * rotB[0, j] + RB[i, 1] * rotB[1, j] + RB[i, 2] * rotB[2, j]
    r01 = FA[0, 0] * FB[0, 1] + FA[1, 0] * FB[1, 1] + FA[2, 0] * FB[2, 1]
    r00 = FA[0, 0] * FB[0, 0] + FA[1, 0] * FB[1, 0] + FA[2, 0] * FB[2, 0]
    phi0 = np.arctan2(-r01, r00)
    # np.rint, not np.round: the same value (round half to even), but np.round's numba
    # implementation lives in numba.np.arraymath, which imports scipy.linalg when a
    # cached kernel is loaded (0.12 s of a warm start)
    turns = np.rint((prev - phi0) / (2.0 * np.pi))
    phi = phi0 + 2.0 * np.pi * turns
    # phidot = z_A . (omega_B,world - omega_A,world)
    wBw0 = RB[0, 0] * VB[0] + RB[0, 1] * VB[1] + RB[0, 2] * VB[2]
    wBw1 = RB[1, 0] * VB[0] + RB[1, 1] * VB[1] + RB[1, 2] * VB[2]
    wBw2 = RB[2, 0] * VB[0] + RB[2, 1] * VB[1] + RB[2, 2] * VB[2]
    wAw0 = RA[0, 0] * VA[0] + RA[0, 1] * VA[1] + RA[0, 2] * VA[2]
    wAw1 = RA[1, 0] * VA[0] + RA[1, 1] * VA[1] + RA[1, 2] * VA[2]
    wAw2 = RA[2, 0] * VA[0] + RA[2, 1] * VA[1] + RA[2, 2] * VA[2]
    phid = FA[0, 2] * (wBw0 - wAw0) + FA[1, 2] * (wBw1 - wAw1) + FA[2, 2] * (wBw2 - wAw2)
    return phi, phid


@njit(cache=True, _nrt=False)
def torsional_forces(gid, torsionBodies, torsionFrames, torsionLaw, torsionAngles, R, r, V, Q, F, m3, ident, zero3,
                     zero6):
    """Torsional spring-dampers about the z axis of the frame on A (``torsionLaw`` = k, d,
    offset, torque): ``tau = k (phi - phi0) + d phidot + torque``;
    ``-tau z_A`` acts on B, ``+tau z_A`` on A."""
    for s in range(torsionBodies.shape[0]):
        a = torsionBodies[s, 0]
        b = torsionBodies[s, 1]
        gA, RA, rA, VA = _side(gid, a, R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, b, R, r, V, ident, zero3, zero6)
        phi, phid = torsion_angle(torsionFrames[s, 0], torsionFrames[s, 1], torsionAngles[s], RA, VA, RB, VB, m3[0],
                                  m3[1])
        tau = -(torsionLaw[s, 0] * (phi - torsionLaw[s, 2]) + torsionLaw[s, 1] * phid + torsionLaw[s, 3])
        for k in range(3):
            F[k] = tau * (RA[k, 0] * torsionFrames[s, 0, 0, 2] + RA[k, 1] * torsionFrames[s, 0, 1, 2] + RA[k, 2] * torsionFrames[s, 0, 2, 2])
        if b >= 0:
            add_world_torque(RB, F, Q[b])
        if a >= 0:
            for k in range(3):
                F[k] = -F[k]
            add_world_torque(RA, F, Q[a])


@njit(cache=True, inline="always", _nrt=False)
def _mat_mat(A, B, out):
    for i in range(3):
        for j in range(3):
            out[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]


@njit(cache=True, inline="always", _nrt=False)
def _matT_vec(A, x, out):
    for i in range(3):
        out[i] = A[0, i] * x[0] + A[1, i] * x[1] + A[2, i] * x[2]


@njit(cache=True, _nrt=False)
def tait_bryan_xyz(Rr, out):
    """The principal Tait-Bryan angles ``Rr = Rx(a0) Ry(a1) Rz(a2)`` (at cos a1 = 0 only
    a0 + a2 is defined: a0 = 0)."""
    c1 = np.sqrt(Rr[1, 2] * Rr[1, 2] + Rr[2, 2] * Rr[2, 2])
    out[1] = np.arctan2(Rr[0, 2], c1)
    if c1 < 1e-14:
        out[0] = 0.0
        out[2] = np.arctan2(Rr[1, 0], Rr[1, 1])
    else:
        out[0] = np.arctan2(-Rr[1, 2], Rr[2, 2])
        out[2] = np.arctan2(-Rr[0, 1], Rr[0, 0])


@njit(cache=True, _nrt=False)
def rigid_spring_forces(gid, rigidSpringBodies, rigidSpringPoints, rigidSpringFrames, rigidSpringLaw, R, r, V, Q, v3,
                        m3, ident, zero3, zero6):
    """6-dof spring-dampers between the frames ``J0 = R_A rotA``
    at ``pA`` and ``J1 = R_B rotB`` at ``pB`` (``rigidSpringLaw`` rows: K (6x6), D (6x6), offset):

    * Tait-Bryan form: ``u = (J0^T (pB - pA), xyz angles of J0^T J1) - offset``,
      ``udot = (J0^T (vB - vA), J0^T (wB - wA))``, the frame of the law ``Jf = J0``;
    * intrinsic form (``rigidSpringBodies[s, 2]``): ``theta = log(J0^T J1)``, ``u = (V(theta)^-1 J0^T (pB - pA),
      theta) - offset`` (``V`` the left Jacobian of SO(3), i.e. ``dexp_theta``),
      ``udot`` in the mid frame ``Jf = Jm = J0 exp(theta / 2)``, the force acting at the mid
      point: an extra torque ``1/2 (Jm u_t) x f`` on both sides (``u_t`` before the offset);

    ``(f, m) = K u + D udot`` in the frame ``Jf``; ``Jf f`` at ``pA`` and ``-Jf f`` at ``pB``,
    torques ``Jf m + c`` on A and ``-Jf m + c`` on B (the bridge's oracle tests compare
    them with the modelling system's own right-hand side, ``tests/test_bridge_oracle.py``)."""
    pA, pB, vA, vB, bA, bB = v3[0], v3[1], v3[2], v3[3], v3[4], v3[5]
    F, Tq, wA, wB, dp, uT, uR, utT, utR, lever, tmp = (v3[6], v3[7], v3[8], v3[9], v3[10], v3[11], v3[12],
                                                       v3[13], v3[14], v3[15], v3[16])
    J0, J1, Jf, E = m3[0], m3[1], m3[2], m3[3]
    for s in range(rigidSpringBodies.shape[0]):
        a = rigidSpringBodies[s, 0]
        b = rigidSpringBodies[s, 1]
        gA, RA, rA, VA = _side(gid, a, R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, b, R, r, V, ident, zero3, zero6)
        body_point(gA, RA, rA, VA, rigidSpringPoints[s, 0], pA, vA, bA)
        body_point(gB, RB, rB, VB, rigidSpringPoints[s, 1], pB, vB, bB)
        _matvec(RA, VA[:3], wA)                      # world angular velocities
        _matvec(RB, VB[:3], wB)
        _mat_mat(RA, rigidSpringFrames[s, 0], J0)
        _mat_mat(RB, rigidSpringFrames[s, 1], J1)
        for i in range(3):                           # E = J0^T J1, the relative rotation
            for j in range(3):
                E[i, j] = J0[0, i] * J1[0, j] + J0[1, i] * J1[1, j] + J0[2, i] * J1[2, j]
            dp[i] = pB[i] - pA[i]
        if rigidSpringBodies[s, 2]:
            so3.log_into(E, uR)                      # theta, principal
            for i in range(3):
                tmp[i] = 0.5 * uR[i]
            so3.exp_into(tmp, E)
            _mat_mat(J0, E, Jf)                      # mid frame Jm
            _matT_vec(J0, dp, tmp)
            so3.dexpinv_apply_into(uR, tmp, uT)      # V(theta)^-1 J0^T (pB - pA)
            _matvec(Jf, uT, lever)
            for i in range(3):
                lever[i] *= 0.5
        else:
            for i in range(3):
                for j in range(3):
                    Jf[i, j] = J0[i, j]
                lever[i] = 0.0
            _matT_vec(J0, dp, uT)
            tait_bryan_xyz(E, uR)
        for i in range(3):
            dp[i] = vB[i] - vA[i]
            tmp[i] = wB[i] - wA[i]
        _matT_vec(Jf, dp, utT)
        _matT_vec(Jf, tmp, utR)
        for i in range(3):
            uT[i] -= rigidSpringLaw[s, 12, i]
            uR[i] -= rigidSpringLaw[s, 12, 3 + i]
        # (f, m) = K u + D udot in the frame Jf
        for i in range(6):
            x = 0.0
            for j in range(3):
                x += rigidSpringLaw[s, i, j] * uT[j] + rigidSpringLaw[s, i, 3 + j] * uR[j] \
                    + rigidSpringLaw[s, 6 + i, j] * utT[j] + rigidSpringLaw[s, 6 + i, 3 + j] * utR[j]
            if i < 3:
                dp[i] = x
            else:
                tmp[i - 3] = x
        _matvec(Jf, dp, F)                           # world force f
        _matvec(Jf, tmp, Tq)                         # world torque m
        c0 = lever[1] * F[2] - lever[2] * F[1]
        c1 = lever[2] * F[0] - lever[0] * F[2]
        c2 = lever[0] * F[1] - lever[1] * F[0]
        if a >= 0:
            add_point_force(gA, RA, rigidSpringPoints[s, 0], F, Q[a])
            dp[0], dp[1], dp[2] = Tq[0] + c0, Tq[1] + c1, Tq[2] + c2
            add_world_torque(RA, dp, Q[a])
        if b >= 0:
            for k in range(3):
                F[k] = -F[k]
            add_point_force(gB, RB, rigidSpringPoints[s, 1], F, Q[b])
            dp[0], dp[1], dp[2] = -Tq[0] + c0, -Tq[1] + c1, -Tq[2] + c2
            add_world_torque(RB, dp, Q[b])


@njit(cache=True, _nrt=False)
def torsion_angles(gid, torsionBodies, torsionFrames, torsionAngles, R, r, V, m3, ident, zero3, zero6):
    """Store the current torsion angles as the branch reference for the next step."""
    for s in range(torsionBodies.shape[0]):
        gA, RA, rA, VA = _side(gid, torsionBodies[s, 0], R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, torsionBodies[s, 1], R, r, V, ident, zero3, zero6)
        phi, phid = torsion_angle(torsionFrames[s, 0], torsionFrames[s, 1], torsionAngles[s], RA, VA, RB, VB, m3[0],
                                  m3[1])
        torsionAngles[s] = phi


@njit(cache=True, forceinline=True, _nrt=False)
def inertial_forces(gid, M, mass, com, R, V, Q):
    """Velocity-dependent (gyroscopic / centrifugal) terms of every body, in its group
    (:func:`~.bodies.body_inertial_forces`, inlined here; this loop is compiled on its own:
    one call per stage, and mk_steps compiles faster than with a nested inline)."""
    for i in range(gid.shape[0]):
        body_inertial_forces(gid[i], M[i], mass[i], com[i], R[i], V[i], Q[i])


# --------------------------------------------------------------------------- the elements' entries
# Each compiled force element has two entries on the scene tuples, registered once in
# mbs/force_elements.py (which generates compute_forces and the spring energy from them):
# its forces ``(sd, wk, R, r, V, Q)`` and, if it has a potential, its energy added to ``e``.
@njit(cache=True, inline="always", _nrt=False)
def spring_element(sd, wk, R, r, V, Q):
    spring_forces(sd.gid, sd.springBodies, sd.springPoints, sd.springLaw, R, r, V, Q, wk.v3, wk.ident, wk.zero3,
                  wk.zero6)


@njit(cache=True, inline="always", _nrt=False)
def cartesian_element(sd, wk, R, r, V, Q):
    cartesian_forces(sd.gid, sd.cartesianBodies, sd.cartesianPoints, sd.cartesianLaw, R, r, V, Q, wk.v3, wk.ident,
                     wk.zero3, wk.zero6)


@njit(cache=True, inline="always", _nrt=False)
def torsional_element(sd, wk, R, r, V, Q):
    torsional_forces(sd.gid, sd.torsionBodies, sd.torsionFrames, sd.torsionLaw, wk.path.torsionAngles, R, r, V, Q,
                     wk.v3[6], wk.m3, wk.ident, wk.zero3, wk.zero6)


@njit(cache=True, inline="always", _nrt=False)
def rigid_spring_element(sd, wk, R, r, V, Q):
    rigid_spring_forces(sd.gid, sd.rigidSpringBodies, sd.rigidSpringPoints, sd.rigidSpringFrames, sd.rigidSpringLaw,
                        R, r, V, Q, wk.v3, wk.m3, wk.ident, wk.zero3,
                        wk.zero6)


@njit(cache=True, _nrt=False)
def spring_potential(gid, springBodies, springPoints, springLaw, R, r, V, v3, ident, zero3, zero6, e):
    """``e`` plus the potential ``k (L - L0)^2 / 2 + f0 L`` of the point-to-point springs."""
    pA, pB, vA, vB = v3[0], v3[1], v3[2], v3[3]
    for s in range(springBodies.shape[0]):
        connector_ends(gid, springBodies[s, 0], springBodies[s, 1], springPoints[s, 0], springPoints[s, 1], R, r, V,
                       v3, ident, zero3, zero6)
        L, _ = spring_length_rate(pA, pB, vA, vB)
        e += 0.5 * springLaw[s, 0] * (L - springLaw[s, 2]) ** 2 + springLaw[s, 3] * L
    return e


@njit(cache=True, _nrt=False)
def cartesian_potential(gid, cartesianBodies, cartesianPoints, cartesianLaw, R, r, V, v3, ident, zero3, zero6, e):
    """``e`` plus the potential of the Cartesian springs."""
    pA, pB = v3[0], v3[1]
    for s in range(cartesianBodies.shape[0]):
        connector_ends(gid, cartesianBodies[s, 0], cartesianBodies[s, 1], cartesianPoints[s, 0],
                       cartesianPoints[s, 1], R, r, V, v3, ident, zero3, zero6)
        for k in range(3):
            e += 0.5 * cartesianLaw[s, 0, k] * (pB[k] - pA[k] - cartesianLaw[s, 2, k]) ** 2
    return e


@njit(cache=True, _nrt=False)
def torsional_potential(gid, torsionBodies, torsionFrames, torsionLaw, torsionAngles, R, r, V, m3, ident, zero3,
                        zero6, e):
    """``e`` plus the potential ``k (phi - offset)^2 / 2 + torque phi`` of the torsional springs."""
    for s in range(torsionBodies.shape[0]):
        gA, RA, rA, VA = _side(gid, torsionBodies[s, 0], R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, torsionBodies[s, 1], R, r, V, ident, zero3, zero6)
        phi, phid = torsion_angle(torsionFrames[s, 0], torsionFrames[s, 1], torsionAngles[s], RA, VA, RB, VB, m3[0],
                                  m3[1])
        e += 0.5 * torsionLaw[s, 0] * (phi - torsionLaw[s, 2]) ** 2 + torsionLaw[s, 3] * phi
    return e


# (the energy entries are inlined: a compiled function that receives the SceneData / Work
# tuples costs compile time steeply; the potentials above receive only their arrays)
@njit(cache=True, inline="always", _nrt=False)
def spring_element_energy(sd, wk, R, r, V, e):
    return spring_potential(sd.gid, sd.springBodies, sd.springPoints, sd.springLaw, R, r, V, wk.v3, wk.ident,
                            wk.zero3, wk.zero6, e)


@njit(cache=True, inline="always", _nrt=False)
def cartesian_element_energy(sd, wk, R, r, V, e):
    return cartesian_potential(sd.gid, sd.cartesianBodies, sd.cartesianPoints, sd.cartesianLaw, R, r, V, wk.v3,
                               wk.ident, wk.zero3, wk.zero6, e)


@njit(cache=True, inline="always", _nrt=False)
def torsional_element_energy(sd, wk, R, r, V, e):
    return torsional_potential(sd.gid, sd.torsionBodies, sd.torsionFrames, sd.torsionLaw, wk.path.torsionAngles, R,
                               r, V, wk.m3, wk.ident, wk.zero3, wk.zero6, e)
