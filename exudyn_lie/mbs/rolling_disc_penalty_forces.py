"""The penalty rolling disc: a disc that rolls on a plane with a penalty contact and
regularised friction (the bridge maps its item onto it, bridge/reader_forces.py).

A disc (end 1: the disc centre on body B, axis ``w1 = A1 discAxis``) on the plane of
end 0 (a rigid body A or the ground, normal ``n0 = A0 planeNormal``, through the end's
point ``p0``).  Geometry:

    w2 = (w1 x n0) / |w1 x n0|   (longitudinal),   w3 = w1 x w2   (centre -> contact point),
    wLat = n0 x w2,
    pC = p1 + r w3 - p0,         vC = v1 + omega1 x (r w3) - (v0 + omega0 x pC),
    vt = (vC . wLat, vC . w2)    (slip velocity in the joint frame J1).

Forces, with the data coordinates ``x = (x0, x1, x2)``: ``(x0, x1)`` the slip velocity and
``x2`` the gap at the last accepted step (they change only after a step):

* contact only if the *stored* gap ``x2 < 0``; then ``fn = -(k pC . n0 + d vC . n0)``
  (with the current ``pC``, ``vC``), else ``fn = 0`` and no friction;
* friction (:func:`slip_force`): none if ``|vt| = 0`` or ``|x01| = 0``; else the
  direction is the stored one ``x01 / |x01|`` with ``phi = 1``, except in the proportional zone
  ``|x01| <= v_mu`` (``v_mu != 0``): there the current direction ``vt / |vt|`` and
  ``phi = f (2 - f)`` (or ``phi = f`` with useLinearProportionalZone), ``f = |vt| / v_mu``;
  ``ft = -phi |fn| mu e`` with ``mu = diag(mu_x + d_x |vt|, mu_y + d_y |vt|)``, rotated by
  the dryFrictionAngle ``alpha``: ``ft = Rot^T mu Rot (-phi |fn| e)``, ``Rot = [[c, -s], [s, c]]``;
* the force on the disc ``f = ft_x wLat + ft_y w2 + fn n0`` acts at the contact point: at the
  disc centre ``f`` and the torque ``(r w3) x f``; on A ``-f`` at ``p0`` and ``pC x (-f)``;
* rolling friction (rollingViscousFriction ``mu_r``): ``-mu_r |fn| vg`` on the disc centre,
  ``+mu_r |fn| vg`` at ``p0`` (no torque), ``vg = v1 - (v0 + omega0 x pC)`` without its normal part.

After each accepted step, :func:`update_rolling_disc_penalty_data` stores ``(vt, pC . n0)`` of the
new state in the data coordinates (a step observer, mbs/step_observers.py); the explicit steps
use the data of the last accepted step throughout the step.  A switched-off disc gives no
force and keeps its data as they are.

Layout: ``PathState.rollingDiscs`` (``wk.path``), one row per disc, columns ``D_*`` below: A (plane, -1 ground), B (disc),
active, useLinearProportionalZone (integers stored as floats), the parameters, and the data
coordinates (x0, x1, x2) at ``D_DATA``.  One array in Work, not SceneData, and not three: with
three arrays (integers, parameters, data) passed to these functions in the stepper's loop the heavy
top, which has no disc, took 3.0 -> 3.6 us per step; the same fields without the calls, or one
array with the calls, left it at 2.9-3.2 us (bench --sections perstep, interleaved with main).
"""
import numpy as np
from numba import njit

from .bodies import _side, add_point_force, add_world_torque, body_point

D_A, D_B, D_ACTIVE, D_LINEAR = 0, 1, 2, 3             # bodies (plane, disc) and flags
D_POSA, D_POSB, D_NORMAL, D_AXIS = 4, 7, 10, 13      # marker points (body coordinates), normal on A, axis on B
D_RADIUS, D_K, D_D, D_MU, D_VMU, D_VISC, D_ALPHA, D_ROLL = 16, 17, 18, 19, 21, 22, 24, 25
D_DATA = 26                                          # data coordinates: slip (2), gap
N_DISC = 29


def rolling_disc_penalty_row(e):
    """``PathState.rollingDiscs`` row of a Scene.RollingDiscPenalty without its data coordinates (columns
    ``D_A`` ... ``D_DATA - 1``)."""
    return [float(e.bodyA), float(e.bodyB), float(e.active), float(e.useLinearProportionalZone), *e.posA, *e.posB,
            *e.normalA, *e.axisB, e.discRadius, e.contactStiffness, e.contactDamping, *e.dryFriction,
            e.dryFrictionProportionalZone, *e.viscousFriction, e.dryFrictionAngle, e.rollingViscousFriction]


def write_rolling_disc_penalty_row(sd, wk, k, e):
    """The registration's ``writeRow`` (mbs/force_elements.py): disc ``k``'s bodies, flags and
    parameters from the scene item ``e`` (changed during a run); its data coordinates (slip
    velocity and gap of the last step, columns ``D_DATA:``) go on as they are."""
    wk.path.rollingDiscs[k, :D_DATA] = rolling_disc_penalty_row(e)


@njit(cache=True, inline="always", _nrt=False)
def _rot_apply(R, x, i0, out):
    for k in range(3):
        out[k] = R[k, 0] * x[i0] + R[k, 1] * x[i0 + 1] + R[k, 2] * x[i0 + 2]


@njit(cache=True, inline="always", _nrt=False)
def _cross_into(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@njit(cache=True, inline="always", _nrt=False)
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, _nrt=False)
def disc_contact(gA, RA, rA, VA, gB, RB, rB, VB, par, v3):
    """The contact kinematics of one disc into ``v3``: 0 p0, 1 p1, 2 v0, 3 v1, 4 (bias, unused),
    4 r w3, 5 n0, 6 w1, 7 w2, 8 w3, 9 wLat, 10 pC, 11 vC, 12 omega0 (world), 13 omega1 (world),
    14 scratch.  Returns ``(gap pC . n0, normal rate vC . n0, slip lateral, slip longitudinal)``."""
    p0, p1, v0, v1, bias = v3[0], v3[1], v3[2], v3[3], v3[4]
    n0, w1, w2, w3, wl, pC, vC, om0, om1, tmp = (v3[5], v3[6], v3[7], v3[8], v3[9], v3[10], v3[11], v3[12],
                                                 v3[13], v3[14])
    body_point(gA, RA, rA, VA, par[D_POSA:D_POSA + 3], p0, v0, bias)
    body_point(gB, RB, rB, VB, par[D_POSB:D_POSB + 3], p1, v1, bias)
    _rot_apply(RA, VA, 0, om0)                  # world angular velocities (V[:3] is body-fixed)
    _rot_apply(RB, VB, 0, om1)
    _rot_apply(RA, par, D_NORMAL, n0)           # n0 = A0 planeNormal
    _rot_apply(RB, par, D_AXIS, w1)             # w1 = A1 discAxis
    _cross_into(w1, n0, w2)
    nw = np.sqrt(_dot(w2, w2))
    for k in range(3):
        w2[k] /= nw
    _cross_into(w1, w2, w3)
    _cross_into(n0, w2, wl)
    rad = par[D_RADIUS]
    for k in range(3):
        bias[k] = rad * w3[k]                   # r w3 (bias is free after body_point)
        pC[k] = p1[k] + bias[k] - p0[k]
    _cross_into(om1, bias, vC)
    _cross_into(om0, pC, tmp)
    for k in range(3):
        vC[k] += v1[k] - v0[k] - tmp[k]
    return _dot(pC, n0), _dot(vC, n0), _dot(vC, wl), _dot(vC, w2)


@njit(cache=True, _nrt=False)
def slip_force(par, linear, s0, s1, d0, d1, fn):
    """The tangential force (J1 coordinates) at slip velocity
    ``(s0, s1)``, stored slip velocity ``(d0, d1)`` and normal force ``fn``."""
    v = np.sqrt(s0 * s0 + s1 * s1)
    dv = np.sqrt(d0 * d0 + d1 * d1)
    if dv == 0.0 or v == 0.0:
        return 0.0, 0.0
    e0, e1 = d0 / dv, d1 / dv
    phi = 1.0
    vmu = par[D_VMU]
    if dv <= vmu and vmu != 0.0:
        f = v / vmu                             # in the proportional zone: current slip
        phi = f if linear else f * (2.0 - f)
        e0, e1 = s0 / v, s1 / v
    a = -phi * abs(fn)
    f0, f1 = a * e0, a * e1
    m0 = par[D_MU] + par[D_VISC] * v
    m1 = par[D_MU + 1] + par[D_VISC + 1] * v
    alpha = par[D_ALPHA]
    if alpha == 0.0:
        return m0 * f0, m1 * f1
    c, s = np.cos(alpha), np.sin(alpha)
    g0 = m0 * (c * f0 - s * f1)                 # mu Rot f
    g1 = m1 * (s * f0 + c * f1)
    return c * g0 + s * g1, -s * g0 + c * g1    # Rot^T (mu Rot f)


@njit(cache=True, _nrt=False)
def rolling_disc_penalty_forces(gid, disc, R, r, V, Q, v3, ident, zero3, zero6):
    """Generalised forces of the penalty rolling discs (module docstring) into ``Q``."""
    n0, w2, wl, pC = v3[5], v3[7], v3[9], v3[10]
    v0, v1, om0 = v3[2], v3[3], v3[12]
    F, T, tmp = v3[15], v3[16], v3[14]
    for s in range(disc.shape[0]):
        par = disc[s]
        if par[D_ACTIVE] == 0.0:
            continue
        a = int(par[D_A])
        b = int(par[D_B])
        gA, RA, rA, VA = _side(gid, a, R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, b, R, r, V, ident, zero3, zero6)
        gap, gapRate, s0, s1 = disc_contact(gA, RA, rA, VA, gB, RB, rB, VB, par, v3)
        if not par[D_DATA + 2] < 0.0:            # contact by the stored gap only
            continue
        fn = -(par[D_K] * gap + par[D_D] * gapRate)
        ft0, ft1 = slip_force(par, par[D_LINEAR] != 0.0, s0, s1, par[D_DATA], par[D_DATA + 1], fn)
        for k in range(3):
            F[k] = ft0 * wl[k] + ft1 * w2[k] + fn * n0[k]        # on the disc, at the contact point
        _cross_into(v3[4], F, T)                                   # (r w3) x f about the disc centre
        add_world_torque(RB, T, Q[b])
        _cross_into(pC, F, T)                                    # pC x f (about p0; -T on A)
        muR = par[D_ROLL]
        if muR != 0.0:
            # rolling friction at the disc centre and at p0, no torque (added after the torques)
            _cross_into(om0, pC, tmp)
            for k in range(3):
                tmp[k] = v1[k] - v0[k] - tmp[k]
            vn = _dot(tmp, n0)
            c = muR * abs(fn)
            for k in range(3):
                F[k] -= c * (tmp[k] - vn * n0[k])
        add_point_force(gB, RB, par[D_POSB:D_POSB + 3], F, Q[b])
        if a >= 0:
            for k in range(3):
                F[k] = -F[k]
                T[k] = -T[k]
            add_point_force(gA, RA, par[D_POSA:D_POSA + 3], F, Q[a])
            add_world_torque(RA, T, Q[a])


@njit(cache=True, _nrt=False)
def update_rolling_disc_penalty_data(gid, disc, R, r, V, v3, ident, zero3, zero6):
    """After an accepted step: the data coordinates of every active disc become the slip
    velocity and the gap of the new state."""
    for s in range(disc.shape[0]):
        par = disc[s]
        if par[D_ACTIVE] == 0.0:
            continue                            # a switched-off disc keeps its data
        gA, RA, rA, VA = _side(gid, int(par[D_A]), R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, int(par[D_B]), R, r, V, ident, zero3, zero6)
        gap, gapRate, s0, s1 = disc_contact(gA, RA, rA, VA, gB, RB, rB, VB, par, v3)
        par[D_DATA] = s0
        par[D_DATA + 1] = s1
        par[D_DATA + 2] = gap


@njit(cache=True, inline="always", _nrt=False)
def rolling_disc_penalty_element(sd, wk, R, r, V, Q):
    """The element's forces entry (mbs/force_elements.py); its table lives in ``wk.path.rollingDiscs``."""
    rolling_disc_penalty_forces(sd.gid, wk.path.rollingDiscs, R, r, V, Q, wk.v3, wk.ident, wk.zero3, wk.zero6)
