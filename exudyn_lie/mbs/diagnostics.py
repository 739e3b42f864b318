"""Diagnostics at a state: energies and the constraint rows of every joint."""
import numpy as np
from numba import njit

from .bodies import body_twist
from .codes import BODY_TWIST, ROW_BODY_A, ROW_BODY_B
from .constraints import joints_rows
from .force_elements import spring_energy
from .state import twist_to_world_velocity


# --------------------------------------------------------------------------- diagnostics
@njit(cache=True, _nrt=False)
def kinetic_and_gravity(gid, M, mass, com, gravity, R, r, V, Vb):
    """(kinetic energy, gravity potential) of all bodies."""
    ekin = 0.0
    egrav = 0.0
    for i in range(gid.shape[0]):
        body_twist(gid[i], R[i], V[i], Vb)
        for a in range(6):
            for c in range(6):
                ekin += 0.5 * Vb[a] * M[i, a, c] * Vb[c]
        for k in range(3):
            xc = r[i, k] + R[i, k, 0] * com[i, 0] + R[i, k, 1] * com[i, 1] + R[i, k, 2] * com[i, 2]
            egrav -= mass[i] * gravity[k] * xc
    return ekin, egrav


@njit(cache=True, _nrt=False)
def all_rows(sd, wk, R, r, V, h, Jr, eta, e):
    """Diagnostics at the states ``(R[k], r[k], V[k])``, k = 0 .. n-1 (the rows' moving offsets in
    ``wk.rdrive`` shared): residuals ``h[k]`` of every joint and ``e[k]`` = (kinetic, gravity
    potential, spring potential); ``Jr``, ``eta`` the Jacobian rows and eta of the last state.
    Output rows come a chunk at a time: one call per chunk, where a call per row cost more than the
    rows themselves (its Python frames and the unboxing of the scene's tuples)."""
    for k in range(R.shape[0]):
        joints_rows(sd.gid, sd.jointIndex, sd.jointPoints, sd.jointFrames, sd.jointParams, sd.rowIndex,
                    sd.rowsAll, wk.path.bodyParameters, wk.path.jointAngles, R[k], r[k], V[k], h[k], Jr, eta,
                    wk.rdrive, wk.v3, wk.ident, wk.zero3, wk.zero6)
        ekin, egrav = kinetic_and_gravity(sd.gid, sd.M, sd.mass, sd.com, sd.gravity, R[k], r[k], V[k], wk.tmp6)
        e[k, 0] = ekin
        e[k, 1] = egrav
        e[k, 2] = spring_energy(sd, wk, R[k], r[k], V[k])   # the registered force elements' (mbs/force_elements.py)


@njit(cache=True, inline="always", _nrt=False)
def secant_rate(a, c, e):
    """The positive root ``rho`` of ``rho^2 a + rho c = e`` (0 without a change ``e`` or a motion):
    for ``Vdot = -K q - D V``, a change ``e = |dVdot|`` over a motion ``a = |dq|``, ``c = |dV|`` bounds
    ``omega^2 a + gamma c`` of a mode ``lambda^2 + gamma lambda + omega^2 = 0``, ``|lambda| <= gamma +
    omega``: omega for a stiffness-dominated mode (``c = 0``), gamma for a damping-dominated one."""
    if e > 0.0 and (a > 0.0 or c > 0.0):
        return 2.0 * e / (c + np.sqrt(c * c + 4.0 * a * e))
    return 0.0


@njit(cache=True, _nrt=False)
def stage_rate(wq, w, upto, h, K, Vd, V0, Vj, nb):
    """Shampine's estimate between a state of rate ``V0`` and the state reached from it with the
    weights ``w_l`` (``l < upto``), whose rate is ``Vj``: the configuration of bodies ``0 .. nb-1``
    moved by ``dq = h sum_l wq_l k_l`` (in the algebra; ``wq_upto``, a partitioned method's diagonal,
    on the stage's own velocity), the velocity by ``dV = h sum_l w_l Vdot_l``; ``Vj - V0`` is the
    change of the acceleration (:func:`secant_rate`).  From the first stage to stage ``m``: ``w =
    A[m]``, ``wq = Aq[m]`` (``A[m]`` but for a partitioned method), ``upto = m``."""
    a = 0.0
    c = 0.0
    e = 0.0
    for i in range(nb):
        for k in range(6):
            dq = 0.0
            dv = 0.0
            for l in range(upto):
                dq += wq[l] * K[l, i, k]
                dv += w[l] * Vd[l, i, k]
            if wq[upto] != 0.0:          # a partitioned method's configuration on its own stage velocity
                dq += wq[upto] * K[upto, i, k]
            a += (h * dq) ** 2
            c += (h * dv) ** 2
            e += (Vj[i, k] - V0[i, k]) ** 2
    return secant_rate(np.sqrt(a), np.sqrt(c), np.sqrt(e))


@njit(cache=True, _nrt=False)
def stage_rates(A, Aq, h, stages, K, Vd, nb):
    """``(largest, last, before)``: the fastest rate |lambda| the last step met, from its stages
    (Shampine's idea, for second-order equations, :func:`stage_rate` between the first and each
    evaluated stage), that of the last stage alone, and the largest of the stages before it.
    ``h rho`` beyond the method's stability radius means the step amplifies that mode.  The largest over the stages: a contact that only some stages reach (an
    impact inside one step) shows at those stages alone (RK4 across a floor at h omega = 10: 10 at the
    second stage, 0.15 at the last).  (``sqrt(|dVdot| / |dq|)`` alone saw the damping force of a step
    that starts at a turning point, ``dq ~ h V ~ 0``, as a mode of any rate.)"""
    before = 0.0
    last = 0.0
    for jj in range(1, stages.shape[0]):
        j = stages[jj]
        before = max(before, last)
        last = stage_rate(Aq[j], A[j], j, h, K, Vd, Vd[0], Vd[j], nb)
    return max(before, last), last, before


def joint_rows_at(sd, wk, R, r, V, h, Jr, eta):
    """Residuals ``h``, Jacobian rows ``Jr`` and ``eta`` of every joint at the state (R, r, V):
    ``all_rows`` without the energies, and without an entry taking the SceneData /
    Work tuples (a first run compiles none for the initial checks)."""
    joints_rows(sd.gid, sd.jointIndex, sd.jointPoints, sd.jointFrames, sd.jointParams, sd.rowIndex, sd.rowsAll,
                wk.path.bodyParameters, wk.path.jointAngles, R, r, V, h, Jr, eta,
                wk.rdrive, wk.v3, wk.ident, wk.zero3, wk.zero6)


def constraint_jacobian(sd, wk, R, r, V):
    """Residuals h(g), the dense constraint Jacobian J (m, 6 nb) in the bodies' group
    velocity coordinates, and eta = -Jdot V, at the state (R, r, V)."""
    m = sd.nrows
    joint_rows_at(sd, wk, np.ascontiguousarray(R, dtype=float), np.ascontiguousarray(r, dtype=float),
                  np.ascontiguousarray(V, dtype=float), wk.h, wk.Jr, wk.eta)
    J = np.zeros((m, 6 * sd.nb))
    for q in range(m):
        a, b = sd.rowIndex[q, ROW_BODY_A], sd.rowIndex[q, ROW_BODY_B]
        if a >= 0:
            J[q, 6 * a:6 * a + 6] += wk.Jr[q, :6]
        if b >= 0:
            J[q, 6 * b:6 * b + 6] += wk.Jr[q, 6:]
    return wk.h.copy(), J, wk.eta.copy()


def schur_complement(sd, wk, R, r, V):
    """Residuals h(g) and the dense ``S = J M^-1 J^T`` (m, m) at the state (R, r, V), in
    the bodies' group velocity coordinates (``M^-1`` is ``D M^-1 D^T``, ``D = diag(I, R)``,
    for SO3xR3 bodies, as in the kernel).  Assembled body by body from the row blocks:
    O(m^2) memory, no (m, 6 nb) Jacobian.  Used only on the rare singular paths."""
    m = sd.nrows
    joint_rows_at(sd, wk, np.ascontiguousarray(R, dtype=float), np.ascontiguousarray(r, dtype=float),
                  np.ascontiguousarray(V, dtype=float), wk.h, wk.Jr, wk.eta)
    S = np.zeros((m, m))
    blocks = {}
    for q in range(m):
        for side, col in ((ROW_BODY_A, 0), (ROW_BODY_B, 6)):
            b = int(sd.rowIndex[q, side])
            if b >= 0:
                blocks.setdefault(b, []).append((q, col))
    for b, lst in blocks.items():
        Mi = sd.Minv[b]
        if not BODY_TWIST[sd.gid[b]]:
            D = np.eye(6)
            D[3:, 3:] = R[b]
            Mi = D @ Mi @ D.T
        rows = np.array([q for q, _ in lst])          # distinct: a row's two sides are different bodies
        Jb = np.array([wk.Jr[q, c:c + 6] for q, c in lst])
        S[np.ix_(rows, rows)] += Jb @ Mi @ Jb.T
    return wk.h.copy(), S


def momentum(bodies, gid, R, r, V):
    """(linear momentum, angular momentum about the world origin) of ``bodies``, world frame."""
    p = np.zeros(3)
    L = np.zeros(3)
    omega, vel = twist_to_world_velocity(gid, R, V)
    for i, b in enumerate(bodies):
        c = b.com
        wW = R[i] @ omega[i]
        vc = vel[i] + np.cross(wW, R[i] @ c)
        Jc = b.inertia - b.mass * (np.dot(c, c) * np.eye(3) - np.outer(c, c))
        p += b.mass * vc
        L += np.cross(r[i] + R[i] @ c, b.mass * vc) + R[i] @ (Jc @ omega[i])
    return p, L


def joint_violations(h, rowJoint, rowIsRot, nj):
    """(position, rotation) violation of each of ``nj`` joints, ``(..., nj)``: the 2-norms of its
    translational and of its rotational rows' residuals ``h`` (..., m), summed row by row in the
    rows' order (as ``np.bincount``, to the bit) for every leading index at once."""
    h2 = np.asarray(h) * np.asarray(h)
    pv = np.zeros(h2.shape[:-1] + (nj,))
    rv = np.zeros_like(pv)
    for q in range(len(rowJoint)):
        (rv if rowIsRot[q] else pv)[..., rowJoint[q]] += h2[..., q]
    return np.sqrt(pv), np.sqrt(rv)
