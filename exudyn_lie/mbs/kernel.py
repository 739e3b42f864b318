"""The compiled multibody kernel: stage right-hand side and the Munthe-Kaas time loop.

Everything here is numba-compiled and allocation-free; it works on the flat arrays of
:class:`exudyn_lie.mbs.compiled.SceneData` and :class:`Work`.

State per body ``i``: ``R[i]`` (3x3, body->world), ``r[i]`` (frame origin, world) and the
velocity ``V[i] = (omega, v)``.  ``gid[i]`` selects the c-space group of the body:

* ``SE3`` (0): ``v`` body-fixed, ``rdot = R v``; Newton-Euler eq. (NE1),
  ``M Vdot - ad_V^T M V = W`` with the constant ``M = J_P``;
* ``SO3xR3`` (1): ``v = rdot`` spatial (mixed velocity, eq. hybridvel); the mixed
  Newton-Euler equations (section "Arbitrary Body-Fixed Reference Frame") with
  ``M^m = D M D^T``, ``D = diag(I, R)``.

The translation map ``T`` (``rdot = T v``) is ``R`` for SE3 and ``I`` for SO3xR3; with it
one formula serves both representations:  a body point ``s`` moves with
``pdot = T v + R (omega x s)`` and ``pddot = T vdot - R s^ omegadot + beta`` where the
velocity-product ("bias") term is ``beta = R (omega x (omega x s)) (+ R (omega x v) for SE3)``.

Constraints follow Exudyn's ``ObjectJointGeneric`` (scene.py).  For a row ``h(g) = 0``,
``J V`` is its time derivative and ``eta = -Jdot V`` (eq. index1) is minus the bias part of
``hddot``: for ``h = a . d`` (a an axis, d a point difference)
``hddot = addot . d + 2 adot . ddot + a . dddot`` and the bias collects every term that
is quadratic in the velocities.
"""
import numpy as np
from numba import njit

from ..groups import se3, so3
from .linalg import band_cholesky_inplace, band_cholesky_solve_inplace, pivoted_cholesky_solve

GID_SE3 = 0
GID_SO3xR3 = 1

ROW_TRANS_LOCAL = 0   # a = (R_A rotA)[:, ax] ; h = a . (pB - pA)
ROW_TRANS_WORLD = 1   # a = e_ax (world)       ; h = a . (pB - pA)
ROW_ROT = 2           # h = (R_A rotA)[:, ax] . (R_B rotB)[:, bx]

STATUS_OK = 0
STATUS_SINGULAR = 1
STATUS_NONFINITE = 2
STATUS_BLOWUP = 3


# --------------------------------------------------------------------------- small vector helpers
@njit(cache=True, inline="always", _nrt=False)
def _cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=True, _nrt=False)
def _matvec(M, x, out):
    for i in range(3):
        out[i] = M[i, 0] * x[0] + M[i, 1] * x[1] + M[i, 2] * x[2]


@njit(cache=True, _nrt=False)
def _matTvec(M, x, out):
    for i in range(3):
        out[i] = M[0, i] * x[0] + M[1, i] * x[1] + M[2, i] * x[2]


# --------------------------------------------------------------------------- body kinematics
@njit(cache=True, _nrt=False)
def body_point(gid, R, r, V, s, p, pd, beta):
    """World position ``p``, velocity ``pd`` and velocity-product acceleration ``beta``
    of the body point ``s`` (body coordinates)."""
    w0, w1, w2 = V[0], V[1], V[2]
    ws0, ws1, ws2 = _cross(w0, w1, w2, s[0], s[1], s[2])            # omega x s
    wws0, wws1, wws2 = _cross(w0, w1, w2, ws0, ws1, ws2)            # omega x (omega x s)
    if gid == GID_SE3:
        # rdot = R v : pd = R (v + omega x s); beta = R (omega x (omega x s) + omega x v)
        wv0, wv1, wv2 = _cross(w0, w1, w2, V[3], V[4], V[5])
        l0 = V[3] + ws0
        l1 = V[4] + ws1
        l2 = V[5] + ws2
        b0 = wws0 + wv0
        b1 = wws1 + wv1
        b2 = wws2 + wv2
        for i in range(3):
            p[i] = r[i] + R[i, 0] * s[0] + R[i, 1] * s[1] + R[i, 2] * s[2]
            pd[i] = R[i, 0] * l0 + R[i, 1] * l1 + R[i, 2] * l2
            beta[i] = R[i, 0] * b0 + R[i, 1] * b1 + R[i, 2] * b2
    else:
        for i in range(3):
            p[i] = r[i] + R[i, 0] * s[0] + R[i, 1] * s[1] + R[i, 2] * s[2]
            pd[i] = V[3 + i] + R[i, 0] * ws0 + R[i, 1] * ws1 + R[i, 2] * ws2
            beta[i] = R[i, 0] * wws0 + R[i, 1] * wws1 + R[i, 2] * wws2


@njit(cache=True, _nrt=False)
def body_axis(R, V, u, a, ad, beta):
    """World direction ``a = R u`` of the body-fixed unit vector ``u``, its rate
    ``ad = R (omega x u)`` and bias acceleration ``beta = R (omega x (omega x u))``."""
    wu0, wu1, wu2 = _cross(V[0], V[1], V[2], u[0], u[1], u[2])
    wwu0, wwu1, wwu2 = _cross(V[0], V[1], V[2], wu0, wu1, wu2)
    for i in range(3):
        a[i] = R[i, 0] * u[0] + R[i, 1] * u[1] + R[i, 2] * u[2]
        ad[i] = R[i, 0] * wu0 + R[i, 1] * wu1 + R[i, 2] * wu2
        beta[i] = R[i, 0] * wwu0 + R[i, 1] * wwu1 + R[i, 2] * wwu2


@njit(cache=True, _nrt=False)
def add_point_force(gid, R, s, F, Q):
    """Generalised force of a world force ``F`` at body point ``s``:
    ``Q = (s x R^T F, T^T F)`` so that ``Q . V`` is the power."""
    f0 = R[0, 0] * F[0] + R[1, 0] * F[1] + R[2, 0] * F[2]
    f1 = R[0, 1] * F[0] + R[1, 1] * F[1] + R[2, 1] * F[2]
    f2 = R[0, 2] * F[0] + R[1, 2] * F[1] + R[2, 2] * F[2]
    m0, m1, m2 = _cross(s[0], s[1], s[2], f0, f1, f2)
    Q[0] += m0
    Q[1] += m1
    Q[2] += m2
    if gid == GID_SE3:
        Q[3] += f0
        Q[4] += f1
        Q[5] += f2
    else:
        Q[3] += F[0]
        Q[4] += F[1]
        Q[5] += F[2]


@njit(cache=True, _nrt=False)
def add_world_torque(R, T, Q):
    """Body-fixed generalised torque of a world torque ``T``."""
    for i in range(3):
        Q[i] += R[0, i] * T[0] + R[1, i] * T[1] + R[2, i] * T[2]


@njit(cache=True, _nrt=False)
def apply_minv(gid, Minv, R, x, out, tmp):
    """``out = M_rep^-1 x`` for the body's velocity representation.

    SE3: ``M`` is the constant J_P, ``Minv`` its inverse.  SO3xR3: ``V^m = D V`` with
    ``D = diag(I, R)``, hence ``(M^m)^-1 = D M^-1 D^T``."""
    if gid == GID_SE3:
        for i in range(6):
            s = 0.0
            for k in range(6):
                s += Minv[i, k] * x[k]
            out[i] = s
    else:
        tmp[0] = x[0]
        tmp[1] = x[1]
        tmp[2] = x[2]
        for i in range(3):
            tmp[3 + i] = R[0, i] * x[3] + R[1, i] * x[4] + R[2, i] * x[5]
        for i in range(6):
            s = 0.0
            for k in range(6):
                s += Minv[i, k] * tmp[k]
            tmp[6 + i] = s
        out[0] = tmp[6]
        out[1] = tmp[7]
        out[2] = tmp[8]
        for i in range(3):
            out[3 + i] = R[i, 0] * tmp[9] + R[i, 1] * tmp[10] + R[i, 2] * tmp[11]


@njit(cache=True, _nrt=False)
def add_inertial_forces(gid, M, mass, com, R, V, Q):
    """Add the velocity-dependent (gyroscopic / centrifugal) terms to ``Q``.

    SE3, eq. (NE1): ``M Vdot = W + ad_V^T (M V)``, ``ad_V^T (L, p) = (-(w x L) - v x p, -(w x p))``.
    SO3xR3: ``M^m Vdot = W - (w x Theta_P w, m R (w x (w x c)))``."""
    w0, w1, w2 = V[0], V[1], V[2]
    if gid == GID_SE3:
        Lx = M[0, 0] * V[0] + M[0, 1] * V[1] + M[0, 2] * V[2] + M[0, 3] * V[3] + M[0, 4] * V[4] + M[0, 5] * V[5]
        Ly = M[1, 0] * V[0] + M[1, 1] * V[1] + M[1, 2] * V[2] + M[1, 3] * V[3] + M[1, 4] * V[4] + M[1, 5] * V[5]
        Lz = M[2, 0] * V[0] + M[2, 1] * V[1] + M[2, 2] * V[2] + M[2, 3] * V[3] + M[2, 4] * V[4] + M[2, 5] * V[5]
        px = M[3, 0] * V[0] + M[3, 1] * V[1] + M[3, 2] * V[2] + M[3, 3] * V[3] + M[3, 4] * V[4] + M[3, 5] * V[5]
        py = M[4, 0] * V[0] + M[4, 1] * V[1] + M[4, 2] * V[2] + M[4, 3] * V[3] + M[4, 4] * V[4] + M[4, 5] * V[5]
        pz = M[5, 0] * V[0] + M[5, 1] * V[1] + M[5, 2] * V[2] + M[5, 3] * V[3] + M[5, 4] * V[4] + M[5, 5] * V[5]
        a0, a1, a2 = _cross(w0, w1, w2, Lx, Ly, Lz)
        b0, b1, b2 = _cross(V[3], V[4], V[5], px, py, pz)
        c0, c1, c2 = _cross(w0, w1, w2, px, py, pz)
        Q[0] -= a0 + b0
        Q[1] -= a1 + b1
        Q[2] -= a2 + b2
        Q[3] -= c0
        Q[4] -= c1
        Q[5] -= c2
    else:
        Lx = M[0, 0] * w0 + M[0, 1] * w1 + M[0, 2] * w2
        Ly = M[1, 0] * w0 + M[1, 1] * w1 + M[1, 2] * w2
        Lz = M[2, 0] * w0 + M[2, 1] * w1 + M[2, 2] * w2
        a0, a1, a2 = _cross(w0, w1, w2, Lx, Ly, Lz)
        Q[0] -= a0
        Q[1] -= a1
        Q[2] -= a2
        if mass * (com[0] * com[0] + com[1] * com[1] + com[2] * com[2]) > 0.0:
            wc0, wc1, wc2 = _cross(w0, w1, w2, com[0], com[1], com[2])
            e0, e1, e2 = _cross(w0, w1, w2, wc0, wc1, wc2)
            for i in range(3):
                Q[3 + i] -= mass * (R[i, 0] * e0 + R[i, 1] * e1 + R[i, 2] * e2)


# --------------------------------------------------------------------------- forces
@njit(cache=True, inline="always", _nrt=False)
def _side(sd, b, R, r, V, ident, zero3, zero6):
    """(gid, R, r, V) of a joint/connector side; ground has identity, zero velocity."""
    if b < 0:
        return GID_SE3, ident, zero3, zero6
    return sd.gid[b], R[b], r[b], V[b]


@njit(cache=True, inline="always", _nrt=False)
def compute_forces(sd, wk, t, R, r, V, Q):
    """Applied and inertial generalised forces ``Q`` (nb, 6) at the state (R, r, V)."""
    nb = sd.nb
    pA = wk.v3a
    pB = wk.v3b
    vA = wk.v3c
    vB = wk.v3d
    bA = wk.v3e
    bB = wk.v3f
    F = wk.v3g
    ident = wk.ident
    zero3 = wk.zero3
    zero6 = wk.zero6
    for i in range(nb):
        for k in range(6):
            Q[i, k] = 0.0
    # gravity acts at the centre of mass
    if sd.hasGravity:
        for i in range(nb):
            for k in range(3):
                F[k] = sd.mass[i] * sd.gravity[k]
            add_point_force(sd.gid[i], R[i], sd.com[i], F, Q[i])
    # constant loads
    for l in range(sd.lbody.shape[0]):
        i = sd.lbody[l]
        if sd.lkind[l] == 0:
            if sd.lfixed[l]:
                _matvec(R[i], sd.lvec[l], F)
            else:
                for k in range(3):
                    F[k] = sd.lvec[l, k]
            add_point_force(sd.gid[i], R[i], sd.lpos[l], F, Q[i])
        else:
            if sd.lfixed[l]:
                for k in range(3):
                    Q[i, k] += sd.lvec[l, k]
            else:
                add_world_torque(R[i], sd.lvec[l], Q[i])
    # point-to-point spring-dampers: tension f = k (L - L0) + d Ldot + f0
    for s in range(sd.sA.shape[0]):
        a = sd.sA[s]
        b = sd.sB[s]
        gA, RA, rA, VA = _side(sd, a, R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(sd, b, R, r, V, ident, zero3, zero6)
        body_point(gA, RA, rA, VA, sd.sposA[s], pA, vA, bA)
        body_point(gB, RB, rB, VB, sd.sposB[s], pB, vB, bB)
        L = 0.0
        for k in range(3):
            L += (pB[k] - pA[k]) ** 2
        L = np.sqrt(L)
        if L < 1e-300:
            continue  # direction undefined: zero-length spring exerts no force
        Ld = 0.0
        for k in range(3):
            Ld += (pB[k] - pA[k]) * (vB[k] - vA[k])
        Ld /= L
        f = sd.sK[s] * (L - sd.sL0[s]) + sd.sD[s] * Ld + sd.sf0[s]
        if a >= 0:
            for k in range(3):
                F[k] = f * (pB[k] - pA[k]) / L
            add_point_force(gA, RA, sd.sposA[s], F, Q[a])
        if b >= 0:
            for k in range(3):
                F[k] = -f * (pB[k] - pA[k]) / L
            add_point_force(gB, RB, sd.sposB[s], F, Q[b])
    # Cartesian spring-dampers, world components
    for s in range(sd.cA.shape[0]):
        a = sd.cA[s]
        b = sd.cB[s]
        gA, RA, rA, VA = _side(sd, a, R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(sd, b, R, r, V, ident, zero3, zero6)
        body_point(gA, RA, rA, VA, sd.cposA[s], pA, vA, bA)
        body_point(gB, RB, rB, VB, sd.cposB[s], pB, vB, bB)
        for k in range(3):
            F[k] = sd.cK[s, k] * (pB[k] - pA[k] - sd.coff[s, k]) + sd.cD[s, k] * (vB[k] - vA[k])
        if a >= 0:
            add_point_force(gA, RA, sd.cposA[s], F, Q[a])
        if b >= 0:
            for k in range(3):
                F[k] = -F[k]
            add_point_force(gB, RB, sd.cposB[s], F, Q[b])
    # torsional spring-dampers about the z axis of the frame on A
    for s in range(sd.tA.shape[0]):
        a = sd.tA[s]
        b = sd.tB[s]
        gA, RA, rA, VA = _side(sd, a, R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(sd, b, R, r, V, ident, zero3, zero6)
        phi, phid = torsion_angle(sd, wk, s, RA, VA, RB, VB)
        # Exudyn's law: tau = k (phi - phi0) + d phidot + torque; -tau z_A acts on B, +tau z_A on A
        tau = -(sd.tK[s] * (phi - sd.toff[s]) + sd.tD[s] * phid + sd.ttq[s])
        _matvec(RA, sd.trotA[s, :, 2], F)
        for k in range(3):
            F[k] *= tau
        if b >= 0:
            add_world_torque(RB, F, Q[b])
        if a >= 0:
            for k in range(3):
                F[k] = -F[k]
            add_world_torque(RA, F, Q[a])
    # inertial (velocity product) terms
    for i in range(nb):
        add_inertial_forces(sd.gid[i], sd.M[i], sd.mass[i], sd.com[i], R[i], V[i], Q[i])


@njit(cache=True, inline="always", _nrt=False)
def torsion_angle(sd, wk, s, RA, VA, RB, VB):
    """Relative rotation angle about z of frame A (tracked continuously through turns
    using the angle at the last accepted step, ``wk.tphi[s]``) and its rate."""
    # relative rotation Rrel = (RA rotA)^T (RB rotB); phi is its third Tait-Bryan (x-y-z)
    # angle, atan2(-Rrel[0,1], Rrel[0,0]), as in Exudyn's TorsionalSpringDamper
    FA = wk.m3a
    FB = wk.m3b
    for i in range(3):
        for j in range(3):
            FA[i, j] = RA[i, 0] * sd.trotA[s, 0, j] + RA[i, 1] * sd.trotA[s, 1, j] + RA[i, 2] * sd.trotA[s, 2, j]
            FB[i, j] = RB[i, 0] * sd.trotB[s, 0, j] + RB[i, 1] * sd.trotB[s, 1, j] + RB[i, 2] * sd.trotB[s, 2, j]
    r01 = FA[0, 0] * FB[0, 1] + FA[1, 0] * FB[1, 1] + FA[2, 0] * FB[2, 1]
    r00 = FA[0, 0] * FB[0, 0] + FA[1, 0] * FB[1, 0] + FA[2, 0] * FB[2, 0]
    phi0 = np.arctan2(-r01, r00)
    prev = wk.tphi[s]
    turns = np.round((prev - phi0) / (2.0 * np.pi))
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


@njit(cache=True, inline="always", _nrt=False)
def update_torsion_tracking(sd, wk, R, r, V):
    """Store the current torsion angles as the branch reference for the next step."""
    for s in range(sd.tA.shape[0]):
        gA, RA, rA, VA = _side(sd, sd.tA[s], R, r, V, wk.ident, wk.zero3, wk.zero6)
        gB, RB, rB, VB = _side(sd, sd.tB[s], R, r, V, wk.ident, wk.zero3, wk.zero6)
        phi, phid = torsion_angle(sd, wk, s, RA, VA, RB, VB)
        wk.tphi[s] = phi


# --------------------------------------------------------------------------- constraints
@njit(cache=True, inline="always", _nrt=False)
def joint_rows(sd, wk, j, R, r, V, h, Jr, eta, want_eta):
    """Residual ``h``, Jacobian rows ``Jr`` (row, 12: 6 for side A, 6 for side B) and
    ``eta = -Jdot V`` of all rows of joint ``j``, written at the joint's row slots."""
    a = sd.jA[j]
    b = sd.jB[j]
    gA, RA, rA, VA = _side(sd, a, R, r, V, wk.ident, wk.zero3, wk.zero6)
    gB, RB, rB, VB = _side(sd, b, R, r, V, wk.ident, wk.zero3, wk.zero6)
    pA = wk.v3a
    pB = wk.v3b
    vA = wk.v3c
    vB = wk.v3d
    bA = wk.v3e
    bB = wk.v3f
    body_point(gA, RA, rA, VA, sd.jposA[j], pA, vA, bA)
    body_point(gB, RB, rB, VB, sd.jposB[j], pB, vB, bB)
    d = wk.v3g
    dd = wk.v3h
    bd = wk.v3i
    for k in range(3):
        d[k] = pB[k] - pA[k]
        dd[k] = vB[k] - vA[k]
        bd[k] = bB[k] - bA[k]
    # body-frame quantities used by all rows
    dAl = wk.v3j    # RA^T (pB - rA): lever of the A-axis rotation
    tmp = wk.v3k
    for k in range(3):
        tmp[k] = pB[k] - rA[k]
    _matTvec(RA, tmp, dAl)
    ax = wk.v3l
    axd = wk.v3m
    axb = wk.v3n
    bx = wk.v3o
    bxd = wk.v3p
    bxb = wk.v3q
    u = wk.v3r
    w = wk.v3s
    RtA = wk.v3t
    for q in range(sd.jrow0[j], sd.jrow0[j] + sd.jnrow[j]):
        for k in range(12):
            Jr[q, k] = 0.0
        kind = sd.rkind[q]
        if kind == ROW_ROT:
            for k in range(3):
                u[k] = sd.jrotA[j, k, sd.rax[q]]
                w[k] = sd.jrotB[j, k, sd.rbx[q]]
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
        else:
            if kind == ROW_TRANS_LOCAL:
                for k in range(3):
                    u[k] = sd.jrotA[j, k, sd.rax[q]]
                body_axis(RA, VA, u, ax, axd, axb)
            else:
                for k in range(3):
                    ax[k] = 0.0
                    axd[k] = 0.0
                    axb[k] = 0.0
                ax[sd.rax[q]] = 1.0
            hv = 0.0
            et = 0.0
            for k in range(3):
                hv += ax[k] * d[k]
                et += axb[k] * d[k] + 2.0 * axd[k] * dd[k] + ax[k] * bd[k]
            h[q] = hv
            eta[q] = -et
            if a >= 0:
                _matTvec(RA, ax, RtA)          # RA^T a
                sA = sd.jposA[j]
                # -(a . pdot_A) -> omega_A . (RA^T a x sA), v_A: -T_A^T a
                c0, c1, c2 = _cross(RtA[0], RtA[1], RtA[2], sA[0], sA[1], sA[2])
                if kind == ROW_TRANS_LOCAL:
                    # + adot . d -> omega_A . (u x RA^T d); combined with the point term
                    # this is omega_A . (u x RA^T (pB - rA)) since RA^T a = u
                    e0, e1, e2 = _cross(u[0], u[1], u[2], dAl[0], dAl[1], dAl[2])
                    Jr[q, 0] = e0
                    Jr[q, 1] = e1
                    Jr[q, 2] = e2
                else:
                    Jr[q, 0] = c0
                    Jr[q, 1] = c1
                    Jr[q, 2] = c2
                if gA == GID_SE3:
                    Jr[q, 3] = -RtA[0]
                    Jr[q, 4] = -RtA[1]
                    Jr[q, 5] = -RtA[2]
                else:
                    Jr[q, 3] = -ax[0]
                    Jr[q, 4] = -ax[1]
                    Jr[q, 5] = -ax[2]
            if b >= 0:
                _matTvec(RB, ax, RtA)          # RB^T a
                sB = sd.jposB[j]
                c0, c1, c2 = _cross(sB[0], sB[1], sB[2], RtA[0], RtA[1], RtA[2])
                Jr[q, 6] = c0
                Jr[q, 7] = c1
                Jr[q, 8] = c2
                if gB == GID_SE3:
                    Jr[q, 9] = RtA[0]
                    Jr[q, 10] = RtA[1]
                    Jr[q, 11] = RtA[2]
                else:
                    Jr[q, 9] = ax[0]
                    Jr[q, 10] = ax[1]
                    Jr[q, 11] = ax[2]


@njit(cache=True, _nrt=False)
def all_rows(sd, wk, R, r, V, h, Jr, eta):
    for j in range(sd.jA.shape[0]):
        joint_rows(sd, wk, j, R, r, V, h, Jr, eta, True)


@njit(cache=True, inline="always", _nrt=False)
def _row_dot(sd, q, l, Jr, W):
    """(J M^-1 J^T)[q, l] = sum over the bodies shared by rows q and l."""
    s = 0.0
    aq = sd.rbodyA[q]
    bq = sd.rbodyB[q]
    al = sd.rbodyA[l]
    bl = sd.rbodyB[l]
    if aq >= 0:
        if aq == al:
            for k in range(6):
                s += Jr[q, k] * W[l, k]
        if aq == bl:
            for k in range(6):
                s += Jr[q, k] * W[l, 6 + k]
    if bq >= 0:
        if bq == al:
            for k in range(6):
                s += Jr[q, 6 + k] * W[l, k]
        if bq == bl:
            for k in range(6):
                s += Jr[q, 6 + k] * W[l, 6 + k]
    return s


@njit(cache=True, inline="always", _nrt=False)
def solve_accelerations(sd, wk, R, V, Q, Vdot):
    """Index-1 solve (eq. index1) by the Schur complement:
    ``Vfree = M^-1 Q``, ``S = J M^-1 J^T``, ``S lambda = J Vfree - eta``,
    ``Vdot = Vfree - M^-1 J^T lambda``.  Returns a status code (wk.info[0] = row)."""
    nb = sd.nb
    for i in range(nb):
        apply_minv(sd.gid[i], sd.Minv[i], R[i], Q[i], Vdot[i], wk.tmp12)
    m = sd.nrows
    if m == 0:
        return STATUS_OK
    Jr = wk.Jr
    W = wk.W
    # W = M^-1 J^T, per row and side
    for q in range(m):
        a = sd.rbodyA[q]
        b = sd.rbodyB[q]
        if a >= 0:
            apply_minv(sd.gid[a], sd.Minv[a], R[a], Jr[q, 0:6], W[q, 0:6], wk.tmp12)
        else:
            for k in range(6):
                W[q, k] = 0.0
        if b >= 0:
            apply_minv(sd.gid[b], sd.Minv[b], R[b], Jr[q, 6:12], W[q, 6:12], wk.tmp12)
        else:
            for k in range(6):
                W[q, 6 + k] = 0.0
    # right-hand side J Vfree - eta
    lam = wk.lam
    for q in range(m):
        s = -wk.eta[q]
        a = sd.rbodyA[q]
        b = sd.rbodyB[q]
        if a >= 0:
            for k in range(6):
                s += Jr[q, k] * Vdot[a, k]
        if b >= 0:
            for k in range(6):
                s += Jr[q, 6 + k] * Vdot[b, k]
        lam[q] = s
    bw = sd.bandwidth
    if sd.redundant:
        S = wk.Sd
        for q in range(m):
            for l in range(q + 1):
                v = _row_dot(sd, q, l, Jr, W)
                S[q, l] = v
                S[l, q] = v
        rank = pivoted_cholesky_solve(S, m, lam, wk.perm, wk.ytmp, sd.pivotTol)
        wk.info[1] = rank
    else:
        B = wk.Sb
        dmax = 0.0
        for q in range(m):
            l0 = q - bw
            if l0 < 0:
                l0 = 0
            for l in range(l0, q + 1):
                B[q, q - l] = _row_dot(sd, q, l, Jr, W)
            if B[q, 0] > dmax:
                dmax = B[q, 0]
        fail = band_cholesky_inplace(B, m, bw, sd.pivotTol * dmax)
        if fail >= 0:
            wk.info[0] = fail
            return STATUS_SINGULAR
        band_cholesky_solve_inplace(B, m, bw, lam)
    # Vdot -= W lambda
    for q in range(m):
        lq = lam[q]
        a = sd.rbodyA[q]
        b = sd.rbodyB[q]
        if a >= 0:
            for k in range(6):
                Vdot[a, k] -= W[q, k] * lq
        if b >= 0:
            for k in range(6):
                Vdot[b, k] -= W[q, 6 + k] * lq
    return STATUS_OK


@njit(cache=True, inline="always", _nrt=False)
def rhs(sd, wk, t, R, r, V, Qext, Vdot):
    """Stage right-hand side ``Vdot = F(g, V)`` (eq. ODE2a).  ``Qext`` holds extra
    generalised forces (from Python callbacks), zeros otherwise."""
    Q = wk.Q
    compute_forces(sd, wk, t, R, r, V, Q)
    if sd.hasQext:
        for i in range(sd.nb):
            for k in range(6):
                Q[i, k] += Qext[i, k]
    if sd.nrows > 0:
        for j in range(sd.jA.shape[0]):
            joint_rows(sd, wk, j, R, r, V, wk.h, wk.Jr, wk.eta, True)
    return solve_accelerations(sd, wk, R, V, Q, Vdot)


# --------------------------------------------------------------------------- Munthe-Kaas steps
@njit(cache=True, inline="always", _nrt=False)
def _exp_compose(gid, R, r, X, Rout, rout, ER, Er):
    """``(Rout, rout) = (R, r) exp(X)`` in the body's group (eqs. expX / expSO3xR3)."""
    if gid == GID_SE3:
        se3.exp_into(X, ER, Er)
        for i in range(3):
            rout[i] = r[i] + R[i, 0] * Er[0] + R[i, 1] * Er[1] + R[i, 2] * Er[2]
    else:
        so3.exp_into(X[0:3], ER)
        for i in range(3):
            rout[i] = r[i] + X[3 + i]
    for i in range(3):
        for j in range(3):
            Rout[i, j] = R[i, 0] * ER[0, j] + R[i, 1] * ER[1, j] + R[i, 2] * ER[2, j]


@njit(cache=True, inline="always", _nrt=False)
def mk_stage_state(sd, wk, A, j, h, R, r, V):
    """Stage configuration ``g exp(Psi_j)`` and velocity ``V + h sum a_jl Vdot_l`` (eq. MK1)."""
    for i in range(sd.nb):
        Psi = wk.Psi[i]
        for k in range(6):
            ps = 0.0
            vs = V[i, k]
            for l in range(j):
                ps += A[j, l] * wk.K[l, i, k]
                vs += h * A[j, l] * wk.Vd[l, i, k]
            Psi[k] = h * ps
            wk.Vs[i, k] = vs
        if j == 0:
            for a in range(3):
                wk.rs[i, a] = r[i, a]
                for b in range(3):
                    wk.Rs[i, a, b] = R[i, a, b]
        else:
            _exp_compose(sd.gid[i], R[i], r[i], Psi, wk.Rs[i], wk.rs[i], wk.m3a, wk.v3a)


@njit(cache=True, inline="always", _nrt=False)
def mk_stage_k(sd, wk, j):
    """``k_j = dexp^-1_{-Psi_j} V_j`` (eq. MK1), per body in its own group."""
    for i in range(sd.nb):
        Kj = wk.K[j, i]
        if j == 0:
            for k in range(6):
                Kj[k] = wk.Vs[i, k]
        else:
            mPsi = wk.tmp6
            for k in range(6):
                mPsi[k] = -wk.Psi[i, k]
            if sd.gid[i] == GID_SE3:
                se3.dexpinv_apply_into(mPsi, wk.Vs[i], Kj)
            else:
                so3.dexpinv_apply_into(mPsi[0:3], wk.Vs[i, 0:3], Kj[0:3])
                for k in range(3):
                    Kj[3 + k] = wk.Vs[i, 3 + k]


@njit(cache=True, inline="always", _nrt=False)
def mk_finish(sd, wk, b, h, R, r, V):
    """``g <- g exp(h sum b_j k_j)``, ``V <- V + h sum b_j Vdot_j``; re-orthonormalise R
    with one Newton step ``R <- R (3 I - R^T R) / 2`` (changes R by O(eps) only)."""
    s = b.shape[0]
    for i in range(sd.nb):
        Phi = wk.Psi[i]
        for k in range(6):
            ph = 0.0
            vv = 0.0
            for j in range(s):
                ph += b[j] * wk.K[j, i, k]
                vv += b[j] * wk.Vd[j, i, k]
            Phi[k] = h * ph
            V[i, k] += h * vv
        _exp_compose(sd.gid[i], R[i], r[i], Phi, wk.m3b, wk.v3b, wk.m3a, wk.v3a)
        Rn = wk.m3b
        # Newton orthonormalisation
        for a in range(3):
            for c in range(3):
                g = 0.0
                for k in range(3):
                    g += Rn[k, a] * Rn[k, c]
                wk.m3a[a, c] = -0.5 * g
            wk.m3a[a, a] += 1.5
        for a in range(3):
            r[i, a] = wk.v3b[a]
            for c in range(3):
                R[i, a, c] = Rn[a, 0] * wk.m3a[0, c] + Rn[a, 1] * wk.m3a[1, c] + Rn[a, 2] * wk.m3a[2, c]


@njit(cache=True, inline="always", _nrt=False)
def state_is_finite(sd, R, r, V, vmax):
    """0 if finite and bounded, STATUS_NONFINITE / STATUS_BLOWUP otherwise."""
    for i in range(sd.nb):
        for k in range(6):
            x = V[i, k]
            if not np.isfinite(x):
                return STATUS_NONFINITE
            if abs(x) > vmax:
                return STATUS_BLOWUP
        for k in range(3):
            if not np.isfinite(r[i, k]):
                return STATUS_NONFINITE
    return STATUS_OK


@njit(cache=True, inline="always", _nrt=False)
def copy_state(sd, R, r, V, Rto, rto, Vto):
    for i in range(sd.nb):
        for a in range(3):
            rto[i, a] = r[i, a]
            for c in range(3):
                Rto[i, a, c] = R[i, a, c]
        for k in range(6):
            Vto[i, k] = V[i, k]


@njit(cache=True, _nrt=False)
def mk_steps(sd, wk, A, b, c, t0, h, nsteps, R, r, V, vmax):
    """Advance ``nsteps`` MK steps in place.  Returns (status, steps done); on a failure
    (R, r, V) hold the last accepted step (the rejected one is undone from wk.Rb...)."""
    s = b.shape[0]
    Qext = wk.Qext
    for n in range(nsteps):
        t = t0 + n * h
        for j in range(s):
            mk_stage_state(sd, wk, A, j, h, R, r, V)
            st = rhs(sd, wk, t + c[j] * h, wk.Rs, wk.rs, wk.Vs, Qext, wk.Vd[j])
            if st != STATUS_OK:
                return st, n
            mk_stage_k(sd, wk, j)
        copy_state(sd, R, r, V, wk.Rb, wk.rb, wk.Vb)
        mk_finish(sd, wk, b, h, R, r, V)
        st = state_is_finite(sd, R, r, V, vmax)
        if st != STATUS_OK:
            copy_state(sd, wk.Rb, wk.rb, wk.Vb, R, r, V)
            return st, n
        if sd.tA.shape[0] > 0:
            update_torsion_tracking(sd, wk, R, r, V)
        watch_rotation_entries(wk, R)
    return STATUS_OK, nsteps


@njit(cache=True, inline="always", _nrt=False)
def watch_rotation_entries(wk, R):
    """Largest |R[body][i, j]| of the watched entries over the accepted steps (cheap
    monitoring between outputs, e.g. of a coordinate singularity; none by default)."""
    for w in range(wk.watchBody.shape[0]):
        a = abs(R[wk.watchBody[w], wk.watchEntry[w, 0], wk.watchEntry[w, 1]])
        if a > wk.watchMax[w]:
            wk.watchMax[w] = a


# --------------------------------------------------------------------------- diagnostics
@njit(cache=True, _nrt=False)
def constraint_residuals(sd, wk, R, r, V, h):
    """All constraint residuals h(g) (row order of the scene)."""
    for j in range(sd.jA.shape[0]):
        joint_rows(sd, wk, j, R, r, V, h, wk.Jr, wk.eta, False)


@njit(cache=True, _nrt=False)
def energies(sd, wk, R, r, V, out):
    """out = (kinetic, gravity potential, spring potential)."""
    ekin = 0.0
    egrav = 0.0
    for i in range(sd.nb):
        # body-fixed twist: v_b = R^T v for mixed bodies
        Vb = wk.tmp6
        for k in range(3):
            Vb[k] = V[i, k]
        if sd.gid[i] == GID_SE3:
            for k in range(3):
                Vb[3 + k] = V[i, 3 + k]
        else:
            for k in range(3):
                Vb[3 + k] = R[i, 0, k] * V[i, 3] + R[i, 1, k] * V[i, 4] + R[i, 2, k] * V[i, 5]
        for a in range(6):
            for c in range(6):
                ekin += 0.5 * Vb[a] * sd.M[i, a, c] * Vb[c]
        for k in range(3):
            xc = r[i, k] + R[i, k, 0] * sd.com[i, 0] + R[i, k, 1] * sd.com[i, 1] + R[i, k, 2] * sd.com[i, 2]
            egrav -= sd.mass[i] * sd.gravity[k] * xc
    espr = 0.0
    pA = wk.v3a
    pB = wk.v3b
    vA = wk.v3c
    vB = wk.v3d
    bA = wk.v3e
    bB = wk.v3f
    for s in range(sd.sA.shape[0]):
        gA, RA, rA, VA = _side(sd, sd.sA[s], R, r, V, wk.ident, wk.zero3, wk.zero6)
        gB, RB, rB, VB = _side(sd, sd.sB[s], R, r, V, wk.ident, wk.zero3, wk.zero6)
        body_point(gA, RA, rA, VA, sd.sposA[s], pA, vA, bA)
        body_point(gB, RB, rB, VB, sd.sposB[s], pB, vB, bB)
        L = np.sqrt((pB[0] - pA[0]) ** 2 + (pB[1] - pA[1]) ** 2 + (pB[2] - pA[2]) ** 2)
        espr += 0.5 * sd.sK[s] * (L - sd.sL0[s]) ** 2 + sd.sf0[s] * L
    for s in range(sd.cA.shape[0]):
        gA, RA, rA, VA = _side(sd, sd.cA[s], R, r, V, wk.ident, wk.zero3, wk.zero6)
        gB, RB, rB, VB = _side(sd, sd.cB[s], R, r, V, wk.ident, wk.zero3, wk.zero6)
        body_point(gA, RA, rA, VA, sd.cposA[s], pA, vA, bA)
        body_point(gB, RB, rB, VB, sd.cposB[s], pB, vB, bB)
        for k in range(3):
            espr += 0.5 * sd.cK[s, k] * (pB[k] - pA[k] - sd.coff[s, k]) ** 2
    for s in range(sd.tA.shape[0]):
        gA, RA, rA, VA = _side(sd, sd.tA[s], R, r, V, wk.ident, wk.zero3, wk.zero6)
        gB, RB, rB, VB = _side(sd, sd.tB[s], R, r, V, wk.ident, wk.zero3, wk.zero6)
        phi, phid = torsion_angle(sd, wk, s, RA, VA, RB, VB)
        espr += 0.5 * sd.tK[s] * (phi - sd.toff[s]) ** 2 + sd.ttq[s] * phi
    out[0] = ekin
    out[1] = egrav
    out[2] = espr
