"""Step-size control for embedded Runge-Kutta(-Munthe-Kaas) pairs, separate from the method.

Everything here is a small ``@njit`` function over scalars and float64 arrays, so that the
compiled stepper can call it inside its time loop, and the Python reference stepper
(``tests/reference_mk_adaptive.py``) calls the very same functions.  The controller state is one float64
array (indices ``S_*``), its parameters another (indices ``P_*``): no objects, no
allocation per step.

The error norm (:func:`weighted_rms`, :func:`embedded_error_norm`)
-----------------------------------------------------------------
Per body the two solutions of an embedded pair share the base point ``g`` of the step:
``g+ = g exp(Phi)``, ``g^+ = g exp(Phi^)`` with ``Phi = h sum_j b_j k_j`` and
``Phi^ = h sum_j b^_j k_j`` (eq. MK1).  Their difference is measured in the Lie algebra at
that base point, ``Phi - Phi^ = h sum_j (b_j - b^_j) k_j``, so no chart or logarithm is
involved (in contrast to Exudyn's componentwise difference of rotation vectors, which its
CSolverExplicit.cpp marks "wrong, CORRECT!"), and likewise
``V+ - V^+ = h sum_j (b_j - b^_j) Vdot_j``.  Each body contributes four 3-vectors of
physical kinds, each scaled by its own tolerance ``sc = atol_kind + rtol * size``:

==========================  ===========================  =============================
part                        atol_kind                    size (relative part)
==========================  ===========================  =============================
rotation xi of Phi - Phi^   ``atol`` [rad]               1 rad (rotations are bounded)
translation of Phi - Phi^   ``atol * L`` [m]             max(|r|, |r+|) (frame origin)
angular velocity            ``atol / T`` [rad/s]         max(|omega|, |omega+|)
translational velocity      ``atol * L / T`` [m/s]       max(|v|, |v+|)
==========================  ===========================  =============================

``L`` (a characteristic length) and ``T`` (a characteristic time) default to 1 m and 1 s:
then every absolute tolerance is Exudyn's ``absoluteTolerance`` in SI units, as Exudyn
applies it to every coordinate.  The 3-vectors enter through their Euclidean norms, so the
norm is invariant under a change of frame (body-fixed in SE3, world in SO3xR3), and
``err = sqrt(sum_i sum_kinds |e|^2 / sc^2 / (12 n))``: 12 components per body, the count
Exudyn's RMS uses for a rigid body (6 ODE2 coordinates and 6 velocities).  Lagrange
multipliers are not part of the state and do not enter.  A step is accepted if err <= 1.

The controller (:func:`control_step`)
-------------------------------------
The PI controller of Hairer's ``dopri5.f`` (Gustafsson, "Control theoretic techniques for
stepsize selection in explicit Runge-Kutta methods", ACM TOMS 17 (1991) 533-554; Hairer,
Norsett & Wanner I, sec. II.4, and Hairer & Wanner II, sec. IV.2):

    fac = err^(1/q - 0.75 beta) / err_old^beta,     q = order_hat + 1,  beta = 0.04,
    h_new = h / clip(fac / safety, 1/fac_max, 1/fac_min),   safety 0.9, fac in [0.2, 10].

A rejected step is retried with ``h / min(1/fac_min, err^(1/q - 0.75 beta) / safety)``
(the I-part alone), and the step after a rejection does not grow (h_new <= h).  ``err_old``
is the error of the last accepted step (at least 1e-4; 1e-4 before the first).  Steps are
clipped to ``[h_min, h_max]``; a rejected step whose retry would be below ``h_min`` stops
the integration (the tolerance cannot be met with steps >= h_min): the caller raises
:class:`~exudyn_lie.errors.StepSizeError` with the time and the step
(:func:`raise_step_size_error`).  With ``accept_min`` the retry is made at ``h_min`` and a
step of ``h_min`` with a finite error is accepted beyond the tolerance and counted
(``S_N_FLOOR``), as Exudyn's explicit solvers continue at their minimum step with a warning
(CSolverExplicit.cpp): a force with a jump has a local error O(h) that no step meets.

The initial step (:func:`hinit_first`, :func:`hinit_second`)
-------------------------------------------------------------
Hairer's HINIT (Hairer, Norsett & Wanner I, sec. II.4, "Starting step size"): with the
weighted norms d0 = ||y0||, d1 = ||f(t0, y0)||: h0 = 0.01 d0 / d1 (1e-6 if either is
below 1e-5); one explicit Euler step of h0, d2 = ||f(t0 + h0, y1) - f(t0, y0)|| / h0;
h1 = (0.01 / max(d1, d2))^(1/q) (max(1e-6, 1e-3 h0) if max(d1, d2) <= 1e-15);
h = min(100 h0, h1, h_max).  ``q = order_hat + 1`` as in dopri5.f (IORD = 5).
On the group ``y0 + h0 f`` is ``(g exp(h0 V), V + h0 Vdot)`` and ``f1 - f0`` is
``(V1 - V0, Vdot1 - Vdot0)``: the algebra velocity of the chart at g has derivative
``Vdot(0)`` at the base point, so the difference estimates the second derivative as in R^n.
"""
import math

import numpy as np
from numba import njit

from ..errors import minimum_step_error

__all__ = [
    "P_SAFETY", "P_FAC_MIN", "P_FAC_MAX", "P_BETA", "P_EXPO", "P_H_MIN", "P_H_MAX", "P_Q",
    "S_ERR_OLD", "S_REJECTED", "S_N_ACCEPT", "S_N_REJECT", "S_N_RHS", "S_H", "S_ERR",
    "TOL_ANGLE", "TOL_LENGTH", "TOL_OMEGA", "TOL_VEL", "TOL_RTOL",
    "STATUS_ACCEPT", "STATUS_REJECT", "STATUS_H_MIN",
    "controller_params", "controller_state", "tolerances",
    "weighted_rms", "increment_difference", "embedded_error_norm",
    "control_step", "hinit_first", "hinit_second", "count_rhs",
    "raise_step_size_error",
]

# ---------------------------------------------------------------- parameter array layout
P_SAFETY, P_FAC_MIN, P_FAC_MAX, P_BETA, P_EXPO, P_H_MIN, P_H_MAX, P_Q, P_ACCEPT_MIN = range(9)
# ---------------------------------------------------------------- state array layout
#: error of the last accepted step (PI memory), 1 if the last attempt was rejected,
#: counters (accepted, rejected steps; right-hand-side evaluations), proposed step, last err,
#: steps accepted at h_min beyond the tolerance (``accept_min``)
S_ERR_OLD, S_REJECTED, S_N_ACCEPT, S_N_REJECT, S_N_RHS, S_H, S_ERR, S_N_FLOOR = range(8)
# ---------------------------------------------------------------- tolerance array layout
TOL_ANGLE, TOL_LENGTH, TOL_OMEGA, TOL_VEL, TOL_RTOL = range(5)

STATUS_ACCEPT, STATUS_REJECT, STATUS_H_MIN = 0, 1, 2

#: PI memory before the first accepted step and its lower bound (dopri5.f: FACOLD = 1e-4)
ERR_OLD_MIN = 1e-4


def controller_params(order_hat, safety=0.9, fac_min=0.2, fac_max=10.0, beta=0.04,
                      h_min=0.0, h_max=np.inf, accept_min=False):
    """Parameter array of the PI controller for an embedded pair whose lower order is
    ``order_hat`` (q = order_hat + 1; exponent 1/q - 0.75 beta; DOPRI5(4): 0.17)."""
    q = int(order_hat) + 1
    if q < 2:
        raise ValueError("controller_params: the embedded order must be >= 1")
    if not (0.0 < safety <= 1.0 and 0.0 < fac_min < 1.0 < fac_max and 0.0 <= beta < 1.0 / q):
        raise ValueError(f"controller_params: need 0 < safety <= 1, 0 < fac_min < 1 < fac_max, "
                         f"0 <= beta < 1/q; got {safety}, {fac_min}, {fac_max}, {beta}")
    if not (0.0 <= h_min < h_max):
        raise ValueError(f"controller_params: need 0 <= h_min < h_max, got {h_min}, {h_max}")
    if accept_min and not h_min > 0.0:
        raise ValueError("controller_params: accept_min needs h_min > 0")
    P = np.empty(9)
    P[P_SAFETY], P[P_FAC_MIN], P[P_FAC_MAX], P[P_BETA] = safety, fac_min, fac_max, beta
    P[P_EXPO] = 1.0 / q - 0.75 * beta
    P[P_H_MIN], P[P_H_MAX], P[P_Q] = h_min, h_max, q
    P[P_ACCEPT_MIN] = 1.0 if accept_min else 0.0
    return P


def controller_state(h0=0.0):
    """Fresh controller state (no step taken yet; proposed step ``h0``)."""
    S = np.zeros(8)
    S[S_ERR_OLD] = ERR_OLD_MIN
    S[S_H] = h0
    return S


def tolerances(atol, rtol, length_scale=1.0, time_scale=1.0):
    """The tolerance array of :func:`weighted_rms` from one ``atol`` and ``rtol`` (module
    docstring): angles atol [rad], lengths atol L [m], angular velocities atol/T [rad/s],
    velocities atol L/T [m/s]."""
    atol, rtol, L, T = float(atol), float(rtol), float(length_scale), float(time_scale)
    if not (atol > 0.0 and rtol >= 0.0 and L > 0.0 and T > 0.0):
        raise ValueError(f"tolerances: need atol > 0, rtol >= 0 and positive scales; got "
                         f"atol={atol}, rtol={rtol}, length_scale={L}, time_scale={T}")
    tol = np.empty(5)
    tol[TOL_ANGLE], tol[TOL_LENGTH] = atol, atol * L
    tol[TOL_OMEGA], tol[TOL_VEL] = atol / T, atol * L / T
    tol[TOL_RTOL] = rtol
    return tol


@njit(cache=True, inline="always", _nrt=False)
def _norm3(x, o):
    return math.sqrt(x[o] * x[o] + x[o + 1] * x[o + 1] + x[o + 2] * x[o + 2])


@njit(cache=True, inline="always", _nrt=False)
def _sq3_over(x, o, sc):
    a, b, c = x[o] / sc, x[o + 1] / sc, x[o + 2] / sc
    return a * a + b * b + c * c


@njit(cache=True, _nrt=False)
def weighted_rms(dPhi, dV, r0, r1, V0, V1, tol):
    """Weighted RMS (module docstring) of configuration differences ``dPhi`` (n, 6) in the
    Lie algebra (rotation first) and velocity differences ``dV`` (n, 6); the relative
    parts use the frame origins ``r0``, ``r1`` (n, 3) and velocities ``V0``, ``V1`` (n, 6)
    at the start and end of the step."""
    n = dPhi.shape[0]
    rtol = tol[TOL_RTOL]
    sc_ang = tol[TOL_ANGLE] + rtol          # size of a rotation: 1 rad
    acc = 0.0
    for i in range(n):
        sc_len = tol[TOL_LENGTH] + rtol * max(_norm3(r0[i], 0), _norm3(r1[i], 0))
        sc_om = tol[TOL_OMEGA] + rtol * max(_norm3(V0[i], 0), _norm3(V1[i], 0))
        sc_vel = tol[TOL_VEL] + rtol * max(_norm3(V0[i], 3), _norm3(V1[i], 3))
        acc += (_sq3_over(dPhi[i], 0, sc_ang) + _sq3_over(dPhi[i], 3, sc_len)
                + _sq3_over(dV[i], 0, sc_om) + _sq3_over(dV[i], 3, sc_vel))
    return math.sqrt(acc / (12.0 * n)) if n > 0 else 0.0


@njit(cache=True, _nrt=False)
def increment_difference(e, h, K, Vd, dPhi, dV):
    """``dPhi = h sum_j e_j K[j]``, ``dV = h sum_j e_j Vd[j]`` for the stage arrays of the
    MK loop (K, Vd of shape (s, n, 6), as in ``mbs.kernel.finish``) and ``e = b - b_hat``:
    the difference of the two increments of an embedded pair (same base point)."""
    s, n = K.shape[0], K.shape[1]
    for i in range(n):
        for k in range(6):
            p = 0.0
            v = 0.0
            for j in range(s):
                if e[j] != 0.0:
                    p += e[j] * K[j, i, k]
                    v += e[j] * Vd[j, i, k]
            dPhi[i, k] = h * p
            dV[i, k] = h * v


@njit(cache=True, _nrt=False)
def embedded_error_norm(e, h, K, Vd, r0, r1, V0, V1, tol, dPhi, dV):
    """:func:`increment_difference` into the work arrays ``dPhi``, ``dV``, then
    :func:`weighted_rms`: the scaled error of one MK step of an embedded pair."""
    increment_difference(e, h, K, Vd, dPhi, dV)
    return weighted_rms(dPhi, dV, r0, r1, V0, V1, tol)


@njit(cache=True, _nrt=False)
def control_step(P, S, h, err):
    """Decide on a step of size ``h`` with scaled error ``err`` (PI controller, module
    docstring).  Updates the state ``S`` (counters, PI memory, ``S[S_H]`` = the next step
    to try) and returns a status: STATUS_ACCEPT, STATUS_REJECT (retry with ``S[S_H]``) or
    STATUS_H_MIN (rejected and the retry would be below ``P[P_H_MIN]``: stop; with
    ``P[P_ACCEPT_MIN]`` the retry is at ``h_min`` and a step there is accepted, module docstring).
    A NaN or infinite error is a rejection with the largest decrease."""
    safety, expo, beta = P[P_SAFETY], P[P_EXPO], P[P_BETA]
    dec_max = 1.0 / P[P_FAC_MIN]            # largest decrease h / h_new (dopri5.f FACC1)
    inc_max = 1.0 / P[P_FAC_MAX]            # largest increase, as h / h_new (FACC2)
    S[S_ERR] = err
    finite = err == err and err < np.inf
    floor = P[P_ACCEPT_MIN] != 0.0 and finite
    if not (err <= 1.0) and floor and h <= P[P_H_MIN] * (1.0 + 1e-12):
        S[S_N_FLOOR] += 1.0                 # no smaller step: accepted beyond the tolerance
    elif not (err <= 1.0):                  # reject (also NaN / inf)
        if finite:
            fac11 = err ** expo
            h_new = h / min(dec_max, fac11 / safety)
        else:
            h_new = h / dec_max
        S[S_REJECTED] = 1.0
        S[S_N_REJECT] += 1.0
        S[S_H] = h_new
        if h_new < P[P_H_MIN]:
            if not floor:
                return STATUS_H_MIN
            S[S_H] = P[P_H_MIN]
        return STATUS_REJECT
    fac11 = err ** expo if err > 0.0 else 0.0
    fac = fac11 / S[S_ERR_OLD] ** beta
    fac = max(inc_max, min(dec_max, fac / safety))
    h_new = h / fac
    S[S_ERR_OLD] = max(err, ERR_OLD_MIN)
    if h_new > P[P_H_MAX]:
        h_new = P[P_H_MAX]
    if h_new < P[P_H_MIN]:                  # try the minimum; if it fails, stop (above)
        h_new = P[P_H_MIN]
    if S[S_REJECTED] != 0.0:                # no growth right after a rejection
        h_new = min(h_new, h)
    S[S_REJECTED] = 0.0
    S[S_N_ACCEPT] += 1.0
    S[S_H] = h_new
    return STATUS_ACCEPT


@njit(cache=True, _nrt=False)
def count_rhs(S, n):
    """Add ``n`` right-hand-side evaluations to the counter."""
    S[S_N_RHS] += n


@njit(cache=True, _nrt=False)
def hinit_first(d0, d1):
    """HINIT, first guess: ``h0 = 0.01 d0 / d1`` (1e-6 if d0 or d1 < 1e-5)."""
    if d0 < 1e-5 or d1 < 1e-5:
        return 1e-6
    return 0.01 * d0 / d1


@njit(cache=True, _nrt=False)
def hinit_second(h0, d1, d2, q, h_max):
    """HINIT, final step from the Euler probe: ``min(100 h0, h1, h_max)`` with
    ``h1 = (0.01 / max(d1, d2))^(1/q)`` (``max(1e-6, 1e-3 h0)`` if max(d1, d2) <= 1e-15)."""
    der12 = max(d1, d2)
    if der12 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / der12) ** (1.0 / q)
    return min(100.0 * h0, h1, h_max)


def raise_step_size_error(t, h, h_min, err, method=""):
    """Raise :class:`~exudyn_lie.errors.StepSizeError` for a step below the minimum,
    with ``.time`` and ``.step`` attributes (Python side of STATUS_H_MIN)."""
    raise minimum_step_error(method or "?", t, h, h_min, err)
