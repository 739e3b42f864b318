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

Code layout (compile time): the entry points take the ``SceneData`` / ``Work``
namedtuples (``mk_steps`` - the time loop, also the accelerations at a state with
``nsteps = 0`` - and ``all_rows`` - constraint rows and energies for diagnostics); they
unpack them and call working functions that receive only the arrays they use.  Numba's
compile time grows steeply with the size of the tuples a function receives: the big
working functions (joint rows, spring forces, ...) are compiled and cached once with
short signatures; the light per-stage ones are inlined (``inline="always"``), which
keeps the stage free of call overhead.  Scratch vectors are rows of ``wk.v3`` (20, 3)
and ``wk.m3`` (2, 3, 3).
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

# columns of the integer tables of SceneData
ROW_KIND, ROW_AX, ROW_BX, ROW_BODY_A, ROW_BODY_B = 0, 1, 2, 3, 4      # rint (m, 5)
J_BODY_A, J_BODY_B, J_ROW0, J_NROW = 0, 1, 2, 3                        # jint (nj, 4)
L_BODY, L_KIND, L_FIXED = 0, 1, 2                                      # lint (nl, 3)

STATUS_OK = 0
STATUS_SINGULAR = 1
STATUS_NONFINITE = 2
STATUS_BLOWUP = 3
STATUS_PROJECTION = 4      # the position projection did not converge
STATUS_STAGE_ARG = 5       # a stage argument Psi_j left the domain of dexpinv (wk.info[2] = body)

# Domain of the MK stage equation k_j = dexpinv_{-Psi_j} V_j (eq. MK1): dexpinv of SO(3)
# (and of SE(3), whose blocks share the coefficient) is singular at |rotation part| = 2 pi,
# where D(t) = (1 - (t/2) cot(t/2)) / t^2 has a pole.  Near it, with t = 2 pi - delta, the
# condition number of dexpinv (ratio of its singular values, 1 along the axis and
# (t/2) / |sin(t/2)| across it) is about 2 pi / delta, and so is the relative condition
# number of D(t) itself.  The time loop stops a step whose stage argument exceeds
# STAGE_ARG_MAX = so3.DEXP_ANGLE_MAX = 2 pi (1 - sqrt(eps)) (condition number <= 1/sqrt(eps):
# at most half the digits of the stage velocity lost), before evaluating that stage - the
# same rule as the Python reference stepper (integrators/mk.py), so SE3's exactness for
# motions in a subgroup holds on the same domain in both.  The test is one squared-norm
# compare per body and stage.
STAGE_ARG_MAX = so3.DEXP_ANGLE_MAX
STAGE_ARG_MAX2 = STAGE_ARG_MAX * STAGE_ARG_MAX

# stabilisation after each step (SceneData.stabilization)
STAB_NONE = 0
STAB_VELOCITY = 1          # V <- V - M^-1 J^T (J M^-1 J^T)^-1 J V
STAB_POSITION = 2          # Gauss-Newton on the group for h(g) = 0, then the velocity projection
PROJ_MAX_ITER = 20
PROJ_TOL = 1e-13           # converged: max |h| <= PROJ_TOL max(1, max |r|)
PROJ_FAIL = 1e3            # failure: max |h| > PROJ_FAIL * tolerance after PROJ_MAX_ITER iterations


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


@njit(cache=True, inline="always", _nrt=False)
def _side(gid, b, R, r, V, ident, zero3, zero6):
    """(gid, R, r, V) of a joint/connector side; ground has identity, zero velocity."""
    if b < 0:
        return GID_SE3, ident, zero3, zero6
    return gid[b], R[b], r[b], V[b]


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


# --------------------------------------------------------------------------- forces
@njit(cache=True, inline="always", _nrt=False)
def gravity_forces(gid, mass, com, gravity, R, Q, F):
    """Gravity acts at the centre of mass."""
    for i in range(gid.shape[0]):
        for k in range(3):
            F[k] = mass[i] * gravity[k]
        add_point_force(gid[i], R[i], com[i], F, Q[i])


@njit(cache=True, inline="always", _nrt=False)
def load_forces(gid, lint, lvec, R, Q, F):
    """Constant forces (at a body point) and torques, world or body-fixed."""
    for l in range(lint.shape[0]):
        i = lint[l, L_BODY]
        if lint[l, L_KIND] == 0:
            if lint[l, L_FIXED]:
                _matvec(R[i], lvec[l, 0], F)
            else:
                for k in range(3):
                    F[k] = lvec[l, 0, k]
            add_point_force(gid[i], R[i], lvec[l, 1], F, Q[i])
        else:
            if lint[l, L_FIXED]:
                for k in range(3):
                    Q[i, k] += lvec[l, 0, k]
            else:
                add_world_torque(R[i], lvec[l, 0], Q[i])


@njit(cache=True, _nrt=False)
def spring_forces(gid, sint, spos, spar, R, r, V, Q, v3, ident, zero3, zero6):
    """Point-to-point spring-dampers: tension ``f = k (L - L0) + d Ldot + f0``
    (``spar`` = k, d, L0, f0)."""
    pA, pB, vA, vB, bA, bB, F = v3[0], v3[1], v3[2], v3[3], v3[4], v3[5], v3[6]
    for s in range(sint.shape[0]):
        a = sint[s, 0]
        b = sint[s, 1]
        gA, RA, rA, VA = _side(gid, a, R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, b, R, r, V, ident, zero3, zero6)
        body_point(gA, RA, rA, VA, spos[s, 0], pA, vA, bA)
        body_point(gB, RB, rB, VB, spos[s, 1], pB, vB, bB)
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
        f = spar[s, 0] * (L - spar[s, 2]) + spar[s, 1] * Ld + spar[s, 3]
        if a >= 0:
            for k in range(3):
                F[k] = f * (pB[k] - pA[k]) / L
            add_point_force(gA, RA, spos[s, 0], F, Q[a])
        if b >= 0:
            for k in range(3):
                F[k] = -f * (pB[k] - pA[k]) / L
            add_point_force(gB, RB, spos[s, 1], F, Q[b])


@njit(cache=True, _nrt=False)
def cartesian_forces(gid, cint, cpos, cpar, R, r, V, Q, v3, ident, zero3, zero6):
    """Cartesian spring-dampers, world components ``f_i = k_i (d_i - o_i) + c_i ddot_i``
    (``cpar[s]`` = rows k, c, o)."""
    pA, pB, vA, vB, bA, bB, F = v3[0], v3[1], v3[2], v3[3], v3[4], v3[5], v3[6]
    for s in range(cint.shape[0]):
        a = cint[s, 0]
        b = cint[s, 1]
        gA, RA, rA, VA = _side(gid, a, R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, b, R, r, V, ident, zero3, zero6)
        body_point(gA, RA, rA, VA, cpos[s, 0], pA, vA, bA)
        body_point(gB, RB, rB, VB, cpos[s, 1], pB, vB, bB)
        for k in range(3):
            F[k] = cpar[s, 0, k] * (pB[k] - pA[k] - cpar[s, 2, k]) + cpar[s, 1, k] * (vB[k] - vA[k])
        if a >= 0:
            add_point_force(gA, RA, cpos[s, 0], F, Q[a])
        if b >= 0:
            for k in range(3):
                F[k] = -F[k]
            add_point_force(gB, RB, cpos[s, 1], F, Q[b])


@njit(cache=True, _nrt=False)
def torsion_angle(rotA, rotB, prev, RA, VA, RB, VB, FA, FB):
    """Relative rotation angle about z of frame A (tracked continuously through turns
    from the angle ``prev`` at the last accepted step) and its rate."""
    # relative rotation Rrel = (RA rotA)^T (RB rotB); phi is its third Tait-Bryan (x-y-z)
    # angle, atan2(-Rrel[0,1], Rrel[0,0]), as in Exudyn's TorsionalSpringDamper
    for i in range(3):
        for j in range(3):
            FA[i, j] = RA[i, 0] * rotA[0, j] + RA[i, 1] * rotA[1, j] + RA[i, 2] * rotA[2, j]
            FB[i, j] = RB[i, 0] * rotB[0, j] + RB[i, 1] * rotB[1, j] + RB[i, 2] * rotB[2, j]
    r01 = FA[0, 0] * FB[0, 1] + FA[1, 0] * FB[1, 1] + FA[2, 0] * FB[2, 1]
    r00 = FA[0, 0] * FB[0, 0] + FA[1, 0] * FB[1, 0] + FA[2, 0] * FB[2, 0]
    phi0 = np.arctan2(-r01, r00)
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


@njit(cache=True, _nrt=False)
def torsional_forces(gid, tint, trot, tpar, tphi, R, r, V, Q, F, m3, ident, zero3, zero6):
    """Torsional spring-dampers about the z axis of the frame on A (``tpar`` = k, d,
    offset, torque).  Exudyn's law: ``tau = k (phi - phi0) + d phidot + torque``;
    ``-tau z_A`` acts on B, ``+tau z_A`` on A."""
    for s in range(tint.shape[0]):
        a = tint[s, 0]
        b = tint[s, 1]
        gA, RA, rA, VA = _side(gid, a, R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, b, R, r, V, ident, zero3, zero6)
        phi, phid = torsion_angle(trot[s, 0], trot[s, 1], tphi[s], RA, VA, RB, VB, m3[0], m3[1])
        tau = -(tpar[s, 0] * (phi - tpar[s, 2]) + tpar[s, 1] * phid + tpar[s, 3])
        for k in range(3):
            F[k] = tau * (RA[k, 0] * trot[s, 0, 0, 2] + RA[k, 1] * trot[s, 0, 1, 2] + RA[k, 2] * trot[s, 0, 2, 2])
        if b >= 0:
            add_world_torque(RB, F, Q[b])
        if a >= 0:
            for k in range(3):
                F[k] = -F[k]
            add_world_torque(RA, F, Q[a])


@njit(cache=True, _nrt=False)
def torsion_angles(gid, tint, trot, tphi, R, r, V, m3, ident, zero3, zero6):
    """Store the current torsion angles as the branch reference for the next step."""
    for s in range(tint.shape[0]):
        gA, RA, rA, VA = _side(gid, tint[s, 0], R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, tint[s, 1], R, r, V, ident, zero3, zero6)
        phi, phid = torsion_angle(trot[s, 0], trot[s, 1], tphi[s], RA, VA, RB, VB, m3[0], m3[1])
        tphi[s] = phi


@njit(cache=True, inline="always", _nrt=False)
def inertial_forces(gid, M, mass, com, R, V, Q):
    """Velocity-dependent (gyroscopic / centrifugal) terms of every body.

    SE3, eq. (NE1): ``M Vdot = W + ad_V^T (M V)``, ``ad_V^T (L, p) = (-(w x L) - v x p, -(w x p))``.
    SO3xR3: ``M^m Vdot = W - (w x Theta_P w, m R (w x (w x c)))``."""
    for i in range(gid.shape[0]):
        Mi = M[i]
        Vi = V[i]
        Qi = Q[i]
        w0, w1, w2 = Vi[0], Vi[1], Vi[2]
        if gid[i] == GID_SE3:
            Lx = Mi[0, 0] * w0 + Mi[0, 1] * w1 + Mi[0, 2] * w2 + Mi[0, 3] * Vi[3] + Mi[0, 4] * Vi[4] + Mi[0, 5] * Vi[5]
            Ly = Mi[1, 0] * w0 + Mi[1, 1] * w1 + Mi[1, 2] * w2 + Mi[1, 3] * Vi[3] + Mi[1, 4] * Vi[4] + Mi[1, 5] * Vi[5]
            Lz = Mi[2, 0] * w0 + Mi[2, 1] * w1 + Mi[2, 2] * w2 + Mi[2, 3] * Vi[3] + Mi[2, 4] * Vi[4] + Mi[2, 5] * Vi[5]
            px = Mi[3, 0] * w0 + Mi[3, 1] * w1 + Mi[3, 2] * w2 + Mi[3, 3] * Vi[3] + Mi[3, 4] * Vi[4] + Mi[3, 5] * Vi[5]
            py = Mi[4, 0] * w0 + Mi[4, 1] * w1 + Mi[4, 2] * w2 + Mi[4, 3] * Vi[3] + Mi[4, 4] * Vi[4] + Mi[4, 5] * Vi[5]
            pz = Mi[5, 0] * w0 + Mi[5, 1] * w1 + Mi[5, 2] * w2 + Mi[5, 3] * Vi[3] + Mi[5, 4] * Vi[4] + Mi[5, 5] * Vi[5]
            a0, a1, a2 = _cross(w0, w1, w2, Lx, Ly, Lz)
            b0, b1, b2 = _cross(Vi[3], Vi[4], Vi[5], px, py, pz)
            c0, c1, c2 = _cross(w0, w1, w2, px, py, pz)
            Qi[0] -= a0 + b0
            Qi[1] -= a1 + b1
            Qi[2] -= a2 + b2
            Qi[3] -= c0
            Qi[4] -= c1
            Qi[5] -= c2
        else:
            Lx = Mi[0, 0] * w0 + Mi[0, 1] * w1 + Mi[0, 2] * w2
            Ly = Mi[1, 0] * w0 + Mi[1, 1] * w1 + Mi[1, 2] * w2
            Lz = Mi[2, 0] * w0 + Mi[2, 1] * w1 + Mi[2, 2] * w2
            a0, a1, a2 = _cross(w0, w1, w2, Lx, Ly, Lz)
            Qi[0] -= a0
            Qi[1] -= a1
            Qi[2] -= a2
            c = com[i]
            if mass[i] * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) > 0.0:
                wc0, wc1, wc2 = _cross(w0, w1, w2, c[0], c[1], c[2])
                e0, e1, e2 = _cross(w0, w1, w2, wc0, wc1, wc2)
                Ri = R[i]
                for k in range(3):
                    Qi[3 + k] -= mass[i] * (Ri[k, 0] * e0 + Ri[k, 1] * e1 + Ri[k, 2] * e2)


@njit(cache=True, inline="always", _nrt=False)
def compute_forces(sd, wk, t, R, r, V, Q):
    """Applied and inertial generalised forces ``Q`` (nb, 6) at the state (R, r, V);
    every force type a scene lacks is skipped."""
    for i in range(sd.nb):
        for k in range(6):
            Q[i, k] = 0.0
    F = wk.v3[6]
    if sd.hasGravity:
        gravity_forces(sd.gid, sd.mass, sd.com, sd.gravity, R, Q, F)
    if sd.lint.shape[0] > 0:
        load_forces(sd.gid, sd.lint, sd.lvec, R, Q, F)
    if sd.sint.shape[0] > 0:
        spring_forces(sd.gid, sd.sint, sd.spos, sd.spar, R, r, V, Q, wk.v3, wk.ident, wk.zero3, wk.zero6)
    if sd.cint.shape[0] > 0:
        cartesian_forces(sd.gid, sd.cint, sd.cpos, sd.cpar, R, r, V, Q, wk.v3, wk.ident, wk.zero3, wk.zero6)
    if sd.tint.shape[0] > 0:
        torsional_forces(sd.gid, sd.tint, sd.trot, sd.tpar, wk.tphi, R, r, V, Q, F, wk.m3, wk.ident, wk.zero3,
                         wk.zero6)
    inertial_forces(sd.gid, sd.M, sd.mass, sd.com, R, V, Q)


@njit(cache=True, inline="always", _nrt=False)
def update_torsion_tracking(sd, wk, R, r, V):
    if sd.tint.shape[0] > 0:
        torsion_angles(sd.gid, sd.tint, sd.trot, wk.tphi, R, r, V, wk.m3, wk.ident, wk.zero3, wk.zero6)


# --------------------------------------------------------------------------- constraints
@njit(cache=True, _nrt=False)
def joint_rows(j, gid, jint, jpos, jrot, rint, R, r, V, h, Jr, eta, v3, ident, zero3, zero6):
    """Residual ``h``, Jacobian rows ``Jr`` (row, 12: 6 for side A, 6 for side B) and
    ``eta = -Jdot V`` of all rows of joint ``j``, written at the joint's row slots."""
    a = jint[j, J_BODY_A]
    b = jint[j, J_BODY_B]
    gA, RA, rA, VA = _side(gid, a, R, r, V, ident, zero3, zero6)
    gB, RB, rB, VB = _side(gid, b, R, r, V, ident, zero3, zero6)
    sA = jpos[j, 0]
    sB = jpos[j, 1]
    rotA = jrot[j, 0]
    rotB = jrot[j, 1]
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
    row0 = jint[j, J_ROW0]
    for q in range(row0, row0 + jint[j, J_NROW]):
        for k in range(12):
            Jr[q, k] = 0.0
        kind = rint[q, ROW_KIND]
        rax = rint[q, ROW_AX]
        if kind == ROW_ROT:
            rbx = rint[q, ROW_BX]
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
        else:
            if kind == ROW_TRANS_LOCAL:
                for k in range(3):
                    u[k] = rotA[k, rax]
                body_axis(RA, VA, u, ax, axd, axb)
            else:
                for k in range(3):
                    ax[k] = 0.0
                    axd[k] = 0.0
                    axb[k] = 0.0
                ax[rax] = 1.0
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
                if gA == GID_SE3:              # v_A: -T_A^T a
                    Jr[q, 3] = -RtA[0]
                    Jr[q, 4] = -RtA[1]
                    Jr[q, 5] = -RtA[2]
                else:
                    Jr[q, 3] = -ax[0]
                    Jr[q, 4] = -ax[1]
                    Jr[q, 5] = -ax[2]
            if b >= 0:
                _matTvec(RB, ax, RtA)          # RB^T a
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


@njit(cache=True, inline="always", _nrt=False)
def joints_rows(gid, jint, jpos, jrot, rint, R, r, V, h, Jr, eta, v3, ident, zero3, zero6):
    """:func:`joint_rows` of every joint."""
    for j in range(jint.shape[0]):
        joint_rows(j, gid, jint, jpos, jrot, rint, R, r, V, h, Jr, eta, v3, ident, zero3, zero6)


@njit(cache=True, inline="always", _nrt=False)
def _row_dot(rint, q, l, Jr, W):
    """(J M^-1 J^T)[q, l] = sum over the bodies shared by rows q and l."""
    s = 0.0
    aq = rint[q, ROW_BODY_A]
    bq = rint[q, ROW_BODY_B]
    al = rint[l, ROW_BODY_A]
    bl = rint[l, ROW_BODY_B]
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
def rows_times(rint, Jr, X, c, y, out):
    """``out = c y + J X`` for a per-body array X (nb, 6), from the row blocks of J."""
    for q in range(rint.shape[0]):
        s = c * y[q]
        a = rint[q, ROW_BODY_A]
        b = rint[q, ROW_BODY_B]
        if a >= 0:
            for k in range(6):
                s += Jr[q, k] * X[a, k]
        if b >= 0:
            for k in range(6):
                s += Jr[q, 6 + k] * X[b, k]
        out[q] = s


@njit(cache=True, inline="always", _nrt=False)
def subtract_rows_transposed(rint, W, lam, X):
    """``X -= W^T lam`` per body, W (m, 12) holding the two body blocks of each row."""
    for q in range(rint.shape[0]):
        lq = lam[q]
        a = rint[q, ROW_BODY_A]
        b = rint[q, ROW_BODY_B]
        if a >= 0:
            for k in range(6):
                X[a, k] -= W[q, k] * lq
        if b >= 0:
            for k in range(6):
                X[b, k] -= W[q, 6 + k] * lq


@njit(cache=True, _nrt=False)
def schur_solve(gid, Minv, rint, bw, redundant, pivotTol, R, Jr, W, lam, Sb, Sd, perm, ytmp, info, tmp12):
    """``W = M^-1 J^T`` (row blocks) and ``lam <- (J M^-1 J^T)^-1 lam``: the Schur
    complement shared by the index-1 solve and the projections.  ``S`` is banded (band
    Cholesky); with redundant rows the pivoted Cholesky drops the dependent ones.
    Returns a status code (info[0] = failing row, info[1] = rank if redundant)."""
    m = rint.shape[0]
    for q in range(m):
        a = rint[q, ROW_BODY_A]
        b = rint[q, ROW_BODY_B]
        if a >= 0:
            apply_minv(gid[a], Minv[a], R[a], Jr[q, 0:6], W[q, 0:6], tmp12)
        else:
            for k in range(6):
                W[q, k] = 0.0
        if b >= 0:
            apply_minv(gid[b], Minv[b], R[b], Jr[q, 6:12], W[q, 6:12], tmp12)
        else:
            for k in range(6):
                W[q, 6 + k] = 0.0
    if redundant:
        for q in range(m):
            for l in range(q + 1):
                v = _row_dot(rint, q, l, Jr, W)
                Sd[q, l] = v
                Sd[l, q] = v
        info[1] = pivoted_cholesky_solve(Sd, m, lam, perm, ytmp, pivotTol)
        return STATUS_OK
    dmax = 0.0
    for q in range(m):
        l0 = q - bw
        if l0 < 0:
            l0 = 0
        for l in range(l0, q + 1):
            Sb[q, q - l] = _row_dot(rint, q, l, Jr, W)
        if Sb[q, 0] > dmax:
            dmax = Sb[q, 0]
    fail = band_cholesky_inplace(Sb, m, bw, pivotTol * dmax)
    if fail >= 0:
        info[0] = fail
        return STATUS_SINGULAR
    band_cholesky_solve_inplace(Sb, m, bw, lam)
    return STATUS_OK


@njit(cache=True, inline="always", _nrt=False)
def schur_correct(gid, Minv, rint, bw, redundant, pivotTol, R, X, c, y, Jr, W, lam, Sb, Sd, perm, ytmp, info, tmp12):
    """``X -= M^-1 J^T lambda`` with ``(J M^-1 J^T) lambda = c y + J X``: the correction that
    makes ``J X = -c y``.  The index-1 solve (eq. index1) is ``X = Vdot = M^-1 Q``,
    ``c y = -eta``; the velocity projection ``X = V``, ``c = 0``.  Returns a status code."""
    rows_times(rint, Jr, X, c, y, lam)
    st = schur_solve(gid, Minv, rint, bw, redundant, pivotTol, R, Jr, W, lam, Sb, Sd, perm, ytmp, info, tmp12)
    if st != STATUS_OK:
        return st
    subtract_rows_transposed(rint, W, lam, X)
    return STATUS_OK


@njit(cache=True, inline="always", _nrt=False)
def free_accelerations(gid, Minv, R, Q, Vdot, tmp12):
    """``Vdot = M^-1 Q`` body by body."""
    for i in range(gid.shape[0]):
        apply_minv(gid[i], Minv[i], R[i], Q[i], Vdot[i], tmp12)


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
    free_accelerations(sd.gid, sd.Minv, R, Q, Vdot, wk.tmp12)
    if sd.nrows == 0:
        return STATUS_OK
    joints_rows(sd.gid, sd.jint, sd.jpos, sd.jrot, sd.rint, R, r, V, wk.h, wk.Jr, wk.eta, wk.v3, wk.ident,
                wk.zero3, wk.zero6)
    return schur_correct(sd.gid, sd.Minv, sd.rint, sd.bandwidth, sd.redundant, sd.pivotTol, R, Vdot, -1.0, wk.eta,
                         wk.Jr, wk.W, wk.lam, wk.Sb, wk.Sd, wk.perm, wk.ytmp, wk.info, wk.tmp12)


# --------------------------------------------------------------------------- Munthe-Kaas steps
@njit(cache=True, _nrt=False)
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
def stage_state(gid, A, j, h, R, r, V, K, Vd, Psi, Rs, rs, Vs, ER, Er):
    """Stage configuration ``g exp(Psi_j)`` and velocity ``V + h sum a_jl Vdot_l`` (eq. MK1).

    Returns -1, or the first body whose stage argument has ``|rotation part of Psi_j|``
    beyond STAGE_ARG_MAX (dexpinv_{-Psi_j} of the stage is singular at 2 pi); then the
    stage is not evaluated."""
    for i in range(gid.shape[0]):
        Pi = Psi[i]
        for k in range(6):
            ps = 0.0
            vs = V[i, k]
            for l in range(j):
                ps += A[j, l] * K[l, i, k]
                vs += h * A[j, l] * Vd[l, i, k]
            Pi[k] = h * ps
            Vs[i, k] = vs
        if j == 0:
            for a in range(3):
                rs[i, a] = r[i, a]
                for b in range(3):
                    Rs[i, a, b] = R[i, a, b]
        else:
            if Pi[0] * Pi[0] + Pi[1] * Pi[1] + Pi[2] * Pi[2] > STAGE_ARG_MAX2:   # (NaN: state_is_finite)
                return i
            _exp_compose(gid[i], R[i], r[i], Pi, Rs[i], rs[i], ER, Er)
    return -1


@njit(cache=True, inline="always", _nrt=False)
def stage_k(gid, j, Psi, Vs, K, tmp6):
    """``k_j = dexp^-1_{-Psi_j} V_j`` (eq. MK1), per body in its own group."""
    for i in range(gid.shape[0]):
        Kj = K[j, i]
        if j == 0:
            for k in range(6):
                Kj[k] = Vs[i, k]
        else:
            for k in range(6):
                tmp6[k] = -Psi[i, k]
            if gid[i] == GID_SE3:
                se3.dexpinv_apply_into(tmp6, Vs[i], Kj)
            else:
                so3.dexpinv_apply_into(tmp6[0:3], Vs[i, 0:3], Kj[0:3])
                for k in range(3):
                    Kj[3 + k] = Vs[i, 3 + k]


@njit(cache=True, inline="always", _nrt=False)
def finish(gid, b, h, R, r, V, K, Vd, Psi, Rn, C, rn, Er):
    """``g <- g exp(h sum b_j k_j)``, ``V <- V + h sum b_j Vdot_j``; re-orthonormalise R
    with one Newton step ``R <- R (3 I - R^T R) / 2`` (changes R by O(eps) only)."""
    s = b.shape[0]
    for i in range(gid.shape[0]):
        Phi = Psi[i]
        for k in range(6):
            ph = 0.0
            vv = 0.0
            for j in range(s):
                ph += b[j] * K[j, i, k]
                vv += b[j] * Vd[j, i, k]
            Phi[k] = h * ph
            V[i, k] += h * vv
        _exp_compose(gid[i], R[i], r[i], Phi, Rn, rn, C, Er)
        # Newton orthonormalisation: C = (3 I - Rn^T Rn) / 2
        for a in range(3):
            for c in range(3):
                g = 0.0
                for k in range(3):
                    g += Rn[k, a] * Rn[k, c]
                C[a, c] = -0.5 * g
            C[a, a] += 1.5
        for a in range(3):
            r[i, a] = rn[a]
            for c in range(3):
                R[i, a, c] = Rn[a, 0] * C[0, c] + Rn[a, 1] * C[1, c] + Rn[a, 2] * C[2, c]


# the MK stages on the scene tuples: inlined into mk_steps, callable from Python too
# (Simulator._python_step for scenes with Python forces or stabilisation)
@njit(cache=True, _nrt=False)
def project(level, gid, Minv, jint, jpos, jrot, rint, bw, redundant, pivotTol, R, r, V, h, Jr, eta, W, lam, Sb,
            Sd, perm, ytmp, info, tmp12, Psi, v3, m3, ident, zero3, zero6):
    """Constraint stabilisation (Simulator(stabilization=...)), both on the group:

    * positions (``level`` 2): Gauss-Newton ``g_i <- g_i exp(delta_i)``,
      ``delta = -M^-1 J^T (J M^-1 J^T)^-1 h(g)`` (the mass-weighted least-change
      correction; J is the derivative of h along g exp(delta) in each body's group);
    * velocities (``level`` >= 1): ``V <- V - M^-1 J^T (J M^-1 J^T)^-1 J V``.

    Returns a status code (STATUS_PROJECTION if max |h| stays above the tolerance)."""
    nb = gid.shape[0]
    if level >= STAB_POSITION:
        scale = 1.0
        for i in range(nb):
            for k in range(3):
                if abs(r[i, k]) > scale:
                    scale = abs(r[i, k])
        tol = PROJ_TOL * scale
        hmax = 0.0
        for it in range(PROJ_MAX_ITER + 1):
            joints_rows(gid, jint, jpos, jrot, rint, R, r, V, h, Jr, eta, v3, ident, zero3, zero6)
            hmax = 0.0
            for q in range(rint.shape[0]):
                if abs(h[q]) > hmax:
                    hmax = abs(h[q])
            if hmax <= tol or it == PROJ_MAX_ITER:
                break
            for q in range(rint.shape[0]):
                lam[q] = h[q]
            st = schur_solve(gid, Minv, rint, bw, redundant, pivotTol, R, Jr, W, lam, Sb, Sd, perm, ytmp, info,
                             tmp12)
            if st != STATUS_OK:
                return st
            for i in range(nb):
                for k in range(6):
                    Psi[i, k] = 0.0
            subtract_rows_transposed(rint, W, lam, Psi)
            for i in range(nb):
                _exp_compose(gid[i], R[i], r[i], Psi[i], m3[1], v3[1], m3[0], v3[0])
                for a in range(3):
                    r[i, a] = v3[1, a]
                    for c in range(3):
                        R[i, a, c] = m3[1, a, c]
        if hmax > PROJ_FAIL * tol:
            return STATUS_PROJECTION
    else:
        joints_rows(gid, jint, jpos, jrot, rint, R, r, V, h, Jr, eta, v3, ident, zero3, zero6)
    return schur_correct(gid, Minv, rint, bw, redundant, pivotTol, R, V, 0.0, eta, Jr, W, lam, Sb, Sd, perm, ytmp,
                         info, tmp12)


@njit(cache=True, inline="always", _nrt=False)
def project_state(sd, wk, level, R, r, V):
    if sd.nrows == 0:
        return STATUS_OK
    return project(level, sd.gid, sd.Minv, sd.jint, sd.jpos, sd.jrot, sd.rint, sd.bandwidth, sd.redundant,
                   sd.pivotTol, R, r, V, wk.h, wk.Jr, wk.eta, wk.W, wk.lam, wk.Sb, wk.Sd, wk.perm, wk.ytmp, wk.info,
                   wk.tmp12, wk.Psi, wk.v3, wk.m3, wk.ident, wk.zero3, wk.zero6)


@njit(cache=True, inline="always", _nrt=False)
def mk_stage_state(sd, wk, A, j, h, R, r, V):
    """:func:`stage_state` on the scene tuples; a stage argument out of the domain of
    dexpinv gives STATUS_STAGE_ARG with the body in ``wk.info[2]``."""
    bad = stage_state(sd.gid, A, j, h, R, r, V, wk.K, wk.Vd, wk.Psi, wk.Rs, wk.rs, wk.Vs, wk.m3[0], wk.v3[0])
    if bad >= 0:
        wk.info[2] = bad
        return STATUS_STAGE_ARG
    return STATUS_OK


@njit(cache=True, inline="always", _nrt=False)
def mk_stage_k(sd, wk, j):
    stage_k(sd.gid, j, wk.Psi, wk.Vs, wk.K, wk.tmp6)


@njit(cache=True, inline="always", _nrt=False)
def mk_finish(sd, wk, b, h, R, r, V):
    finish(sd.gid, b, h, R, r, V, wk.K, wk.Vd, wk.Psi, wk.m3[1], wk.m3[0], wk.v3[1], wk.v3[0])


@njit(cache=True, inline="always", _nrt=False)
def state_is_finite(gid, R, r, V, vmax):
    """0 if finite and bounded, STATUS_NONFINITE / STATUS_BLOWUP otherwise."""
    for i in range(gid.shape[0]):
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
def copy_state(R, r, V, Rto, rto, Vto):
    for i in range(R.shape[0]):
        for a in range(3):
            rto[i, a] = r[i, a]
            for c in range(3):
                Rto[i, a, c] = R[i, a, c]
        for k in range(6):
            Vto[i, k] = V[i, k]


@njit(cache=True, _nrt=False)
def watch_rotation_entries(watchBody, watchEntry, watchMax, R):
    """Largest |R[body][i, j]| of the watched entries over the accepted steps (cheap
    monitoring between outputs, e.g. of a coordinate singularity; none by default)."""
    for w in range(watchBody.shape[0]):
        a = abs(R[watchBody[w], watchEntry[w, 0], watchEntry[w, 1]])
        if a > watchMax[w]:
            watchMax[w] = a


@njit(cache=True, _nrt=False)
def mk_steps(sd, wk, A, b, c, t0, h, nsteps, R, r, V, vmax, every, Ro, ro, Vo, Vdo, lamo):
    """Advance ``nsteps`` MK steps in place.  Returns (status, steps done); on a failure
    (R, r, V) hold the last accepted step (the rejected one is undone from wk.Rb...).

    ``nsteps = 0`` evaluates the equations of motion once at the current state (the
    first stage of a step): accelerations in ``wk.Vd[0]``, multipliers in ``wk.lam``.
    (One call site of the inlined right-hand side serves both uses: a second one would
    double the compile time.)

    Outputs: with ``every > 0`` the state after every ``every``-th step goes to row
    ``o = (n + 1) / every - 1`` of ``Ro, ro, Vo``; if ``Vdo`` has rows, the accelerations
    and multipliers at that state go to ``Vdo[o], lamo[o]``.  They are the first stage of
    the following step (explicit RK: stage 1 is evaluated at the step's initial state),
    so recording them costs one extra evaluation per call, after the last step.  A failure
    in that evaluation leaves ``Vdo[o, 0, 0]`` NaN.  (A caller that needs several outputs
    then enters the compiled code once instead of once per output.)"""
    s = b.shape[0]
    Qext = wk.Qext
    acc = Vdo.shape[0] > 0
    pending = -1                         # output row whose accelerations are still due
    n = 0
    while True:
        t = t0 + n * h
        evalOnly = n >= nsteps
        if evalOnly and nsteps > 0 and pending < 0:
            return STATUS_OK, nsteps
        for j in range(s):
            st = mk_stage_state(sd, wk, A, j, h, R, r, V)
            if st != STATUS_OK:          # only for j >= 1: any pending output is written
                return st, n
            st = rhs(sd, wk, t + c[j] * h, wk.Rs, wk.rs, wk.Vs, Qext, wk.Vd[j])
            if st != STATUS_OK:
                if pending >= 0:
                    Vdo[pending, 0, 0] = np.nan
                return st, n
            if pending >= 0:
                for i in range(Vdo.shape[1]):
                    for k in range(6):
                        Vdo[pending, i, k] = wk.Vd[0, i, k]
                for k in range(lamo.shape[1]):
                    lamo[pending, k] = wk.lam[k]
                pending = -1
            if evalOnly:
                return STATUS_OK, nsteps
            mk_stage_k(sd, wk, j)
        copy_state(R, r, V, wk.Rb, wk.rb, wk.Vb)
        mk_finish(sd, wk, b, h, R, r, V)
        st = state_is_finite(sd.gid, R, r, V, vmax)
        if st != STATUS_OK:
            copy_state(wk.Rb, wk.rb, wk.Vb, R, r, V)
            return st, n
        if sd.stabilization != STAB_NONE:
            st = project_state(sd, wk, sd.stabilization, R, r, V)
            if st != STATUS_OK:
                copy_state(wk.Rb, wk.rb, wk.Vb, R, r, V)
                return st, n
        update_torsion_tracking(sd, wk, R, r, V)
        if wk.watchBody.shape[0] > 0:
            watch_rotation_entries(wk.watchBody, wk.watchEntry, wk.watchMax, R)
        n += 1
        if every > 0 and n % every == 0:
            o = n // every - 1
            copy_state(R, r, V, Ro[o], ro[o], Vo[o])
            if acc:
                pending = o


# --------------------------------------------------------------------------- diagnostics
@njit(cache=True, _nrt=False)
def kinetic_and_gravity(gid, M, mass, com, gravity, R, r, V, Vb):
    """(kinetic energy, gravity potential) of all bodies."""
    ekin = 0.0
    egrav = 0.0
    for i in range(gid.shape[0]):
        # body-fixed twist: v_b = R^T v for mixed bodies
        for k in range(3):
            Vb[k] = V[i, k]
        if gid[i] == GID_SE3:
            for k in range(3):
                Vb[3 + k] = V[i, 3 + k]
        else:
            for k in range(3):
                Vb[3 + k] = R[i, 0, k] * V[i, 3] + R[i, 1, k] * V[i, 4] + R[i, 2, k] * V[i, 5]
        for a in range(6):
            for c in range(6):
                ekin += 0.5 * Vb[a] * M[i, a, c] * Vb[c]
        for k in range(3):
            xc = r[i, k] + R[i, k, 0] * com[i, 0] + R[i, k, 1] * com[i, 1] + R[i, k, 2] * com[i, 2]
            egrav -= mass[i] * gravity[k] * xc
    return ekin, egrav


@njit(cache=True, _nrt=False)
def spring_energy(gid, sint, spos, spar, cint, cpos, cpar, tint, trot, tpar, tphi, R, r, V, v3, m3, ident, zero3,
                  zero6):
    """Potential energy of the point-to-point, Cartesian and torsional springs."""
    pA, pB, vA, vB, bA, bB = v3[0], v3[1], v3[2], v3[3], v3[4], v3[5]
    espr = 0.0
    for s in range(sint.shape[0]):
        gA, RA, rA, VA = _side(gid, sint[s, 0], R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, sint[s, 1], R, r, V, ident, zero3, zero6)
        body_point(gA, RA, rA, VA, spos[s, 0], pA, vA, bA)
        body_point(gB, RB, rB, VB, spos[s, 1], pB, vB, bB)
        L = np.sqrt((pB[0] - pA[0]) ** 2 + (pB[1] - pA[1]) ** 2 + (pB[2] - pA[2]) ** 2)
        espr += 0.5 * spar[s, 0] * (L - spar[s, 2]) ** 2 + spar[s, 3] * L
    for s in range(cint.shape[0]):
        gA, RA, rA, VA = _side(gid, cint[s, 0], R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, cint[s, 1], R, r, V, ident, zero3, zero6)
        body_point(gA, RA, rA, VA, cpos[s, 0], pA, vA, bA)
        body_point(gB, RB, rB, VB, cpos[s, 1], pB, vB, bB)
        for k in range(3):
            espr += 0.5 * cpar[s, 0, k] * (pB[k] - pA[k] - cpar[s, 2, k]) ** 2
    for s in range(tint.shape[0]):
        gA, RA, rA, VA = _side(gid, tint[s, 0], R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, tint[s, 1], R, r, V, ident, zero3, zero6)
        phi, phid = torsion_angle(trot[s, 0], trot[s, 1], tphi[s], RA, VA, RB, VB, m3[0], m3[1])
        espr += 0.5 * tpar[s, 0] * (phi - tpar[s, 2]) ** 2 + tpar[s, 3] * phi
    return espr


@njit(cache=True, _nrt=False)
def all_rows(sd, wk, R, r, V, h, Jr, eta, e):
    """Diagnostics at the state (R, r, V): residuals ``h``, Jacobian rows ``Jr`` and
    ``eta`` of every joint, and ``e`` = (kinetic, gravity potential, spring potential)."""
    joints_rows(sd.gid, sd.jint, sd.jpos, sd.jrot, sd.rint, R, r, V, h, Jr, eta, wk.v3, wk.ident, wk.zero3,
                wk.zero6)
    ekin, egrav = kinetic_and_gravity(sd.gid, sd.M, sd.mass, sd.com, sd.gravity, R, r, V, wk.tmp6)
    e[0] = ekin
    e[1] = egrav
    e[2] = spring_energy(sd.gid, sd.sint, sd.spos, sd.spar, sd.cint, sd.cpos, sd.cpar, sd.tint, sd.trot, sd.tpar,
                         wk.tphi, R, r, V, wk.v3, wk.m3, wk.ident, wk.zero3, wk.zero6)
