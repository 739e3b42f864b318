"""Adaptive explicit Munthe-Kaas integration with error control on the group: the Python
reference (test oracle) for the compiled adaptive stepper.

One step from ``(t, g, V)`` with an embedded pair ``(A, b, b_hat)`` (eq. MK1, per body)::

    Psi_j  = h sum_{l<j} a_jl k_l,         V_j = V + h sum_{l<j} a_jl Vdot_l
    Vdot_j = F(t + c_j h, g exp(Psi_j), V_j),   k_j = dexp^{-1}_{-Psi_j} V_j
    Phi    = h sum_j b_j k_j,   Phi^ = h sum_j b^_j k_j      (same base point g)
    dV     = h sum_j b_j Vdot_j, dV^ = h sum_j b^_j Vdot_j

The error is ``(Phi - Phi^, dV - dV^)`` in the Lie algebra at ``g`` (no chart), scaled by
:func:`.control.weighted_rms`; the PI controller :func:`.control.control_step` accepts or
rejects; the first step comes from Hairer's HINIT (:func:`.control.hinit_first` /
:func:`.control.hinit_second`).  The solution advances with the higher order
(``g+ = g exp(Phi)``, ``V+ = V + dV``: local extrapolation, as dopri5).

FSAL: when the last row of A equals b (:attr:`ButcherTableau.fsal`), the last stage is
evaluated at ``(t + h, g exp(Phi), V+)`` -- the next step's first right-hand side, which is
reused (one evaluation saved per accepted step).  Its stage value ``k_s = dexp^{-1}_{-Phi}
V+`` enters b_hat; the next step's ``k_1 = V+`` needs no evaluation.

Dense output on the group: the continuous extension ``b_j(theta)`` of the tableau
(:class:`ContinuousExtension`) applied to the algebra increment and mapped by exp,

    g(t + theta h) = g exp(h sum_j b_j(theta) k_j),   V(t + theta h) = V + h sum_j b_j(theta) Vdot_j,

which is the continuous extension of the RK method applied to the local ODE
``sigma' = dexp^{-1}_{-sigma} V(g exp(sigma))`` in the algebra, so it has the order of
the extension (extra stages, as Verner's, are evaluated only in steps with output).
Output times are met exactly without shortening any step; only the last step is clipped
to the end time.  For a motion in a one-parameter subgroup (a body on a fixed screw axis
in SE3) every ``k_j`` is a multiple of the same twist, so every ``g(t + theta h)`` stays
in the subgroup: the constraint holds to round-off between steps too.

This module favours clarity: it is the reference the compiled stepper is compared with.
Its stage sweep is the one of :mod:`.mk` (tests check that its result is bit-identical
to :func:`.mk.mk_step` for the same step), extended by the embedded weights, FSAL reuse
and the extra dense-output stages.
"""
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from exudyn_lie.integrators import control as C
from exudyn_lie.integrators.tableau import resolve_pair
from reference_mk import STAGE_ANGLE_MAX, as_poses, resolve_groups

__all__ = ["AdaptiveStats", "AdaptiveTrajectory", "integrate_adaptive", "initial_step",
           "resolve_pair"]


@dataclass
class AdaptiveStats:
    """Counters of an adaptive run: accepted and rejected steps, right-hand-side
    evaluations (including HINIT's and the extra dense-output stages), and the accepted
    steps as (t_start, h, err)."""
    accepted: int = 0
    rejected: int = 0
    rhs_evaluations: int = 0
    steps: list = field(default_factory=list)
    h_initial: float = 0.0


@dataclass
class AdaptiveTrajectory:
    """States at the output times ``t``: ``R`` (m, n, 3, 3), ``r`` (m, n, 3), ``V`` (m, n, 6)."""
    t: np.ndarray
    R: np.ndarray
    r: np.ndarray
    V: np.ndarray
    stats: AdaptiveStats

    def pose(self, k=-1):
        return [(self.R[k, i].copy(), self.r[k, i].copy()) for i in range(self.R.shape[1])]


# ------------------------------------------------------------------------- group helpers
def _translate(gms, g, X):
    """Poses ``g_i exp(X_i)`` (X_i = 0: g_i itself)."""
    out = []
    for i, gm in enumerate(gms):
        Xi = X[i]
        if not Xi.any():
            out.append(g[i])
            continue
        Re, re = gm.exp(np.ascontiguousarray(Xi))
        out.append(gm.compose(g[i][0], g[i][1], Re, re))
    return out


def _lincomb(coeffs, arrays, upto):
    """sum_{l < upto} coeffs[l] arrays[l] accumulated in order, zero coefficients skipped
    (the summation of :mod:`.mk`, so that equal steps give equal bits); None if all zero."""
    acc = None
    for l in range(upto):
        a = coeffs[l]
        if a != 0.0:
            acc = a * arrays[l] if acc is None else acc + a * arrays[l]
    return acc


def _origins(g):
    return np.array([r for _, r in g])


# ------------------------------------------------------------------------- the stage sweep
class _Step:
    """Stage storage of one step: K, Vd for the s stages plus the dense extra stages."""

    def __init__(self, tab, n):
        self.tab = tab
        s = tab.stages
        m = tab.dense.extra_stages if tab.dense is not None else 0
        self.s, self.m = s, m
        A = np.zeros((s + m, s + m))
        A[:s, :s] = tab.A
        c = np.zeros(s + m)
        c[:s] = tab.c
        if m:
            A[s:, :] = tab.dense.A_extra
            c[s:] = tab.dense.c_extra
        self.A, self.c = A, c
        self.K = np.zeros((s + m, n, 6))
        self.Vd = np.zeros((s + m, n, 6))

    def sweep(self, gms, g, V, t, h, rhs, j0, j1, Vd_first=None):
        """Stages j0 <= j < j1 (eq. MK1).  ``Vd_first``: the FSAL value of stage 1.
        Returns ``(n, ok)``: the number of rhs evaluations made, and False if a stage
        argument reached STAGE_ANGLE_MAX (dexp^-1 singular: the step must be reduced).  The last stage's
        pose and velocity are kept (``self.last``): for an FSAL pair they are the step's
        result, bit for bit (same sums as :meth:`increments` with b)."""
        A, c, K, Vd = self.A, self.c, self.K, self.Vd
        nrhs = 0
        for j in range(j0, j1):
            psi = _lincomb(A[j], K, j)
            dv = _lincomb(A[j], Vd, j)
            Vj = V if dv is None else V + h * dv
            if psi is None:                                  # Psi_j = 0: g_j = g, k_j = V_j
                Psi, gj = None, g
            else:
                Psi = h * psi
                if not np.all(np.linalg.norm(Psi[:, :3], axis=1) < STAGE_ANGLE_MAX):
                    return nrhs, False
                gj = _translate(gms, g, Psi)
            if j == 0 and Vd_first is not None:
                Vd[0] = Vd_first
            else:
                Vd[j] = np.asarray(rhs(t + c[j] * h, gj, Vj), dtype=np.float64).reshape(V.shape)
                nrhs += 1
            if Psi is None:
                K[j] = Vj
            else:
                for i, gm in enumerate(gms):
                    gm.dexpinv_apply_into(np.ascontiguousarray(-Psi[i]),
                                          np.ascontiguousarray(Vj[i]), K[j, i])
            self.last = (gj, Vj)
        return nrhs, True

    def increments(self, h, w):
        """``(h sum_j w_j K_j, h sum_j w_j Vd_j)`` over the stages of ``w``."""
        k = len(w)
        return h * _lincomb(w, self.K, k), h * _lincomb(w, self.Vd, k)


# ------------------------------------------------------------------------- HINIT
def initial_step(tab, gms, g, V, t, rhs, tol, h_max, Vd0=None):
    """Hairer's HINIT on the group (:mod:`.control`).  Returns ``(h, Vd0, nrhs)``."""
    nrhs = 0
    if Vd0 is None:
        Vd0 = np.asarray(rhs(t, g, V), dtype=np.float64).reshape(V.shape)
        nrhs += 1
    r0 = _origins(g)
    unit_rot = np.zeros_like(V)
    unit_rot[:, 0] = 1.0                                     # a rotation's size: 1 rad
    size = unit_rot.copy()
    size[:, 3:] = r0
    d0 = C.weighted_rms(size, V, r0, r0, V, V, tol)          # ||y0||
    d1 = C.weighted_rms(V, Vd0, r0, r0, V, V, tol)           # ||f(t0, y0)||
    h0 = min(C.hinit_first(d0, d1), h_max)
    g1 = _translate(gms, g, h0 * V)                          # explicit Euler probe
    V1 = V + h0 * Vd0
    Vd1 = np.asarray(rhs(t + h0, g1, V1), dtype=np.float64).reshape(V.shape)
    nrhs += 1
    d2 = C.weighted_rms(V1 - V, Vd1 - Vd0, r0, r0, V, V, tol) / h0
    h = C.hinit_second(h0, d1, d2, tab.order_hat + 1, h_max)
    return h, Vd0, nrhs


# ------------------------------------------------------------------------- the driver
def _checked_problem(tableau, groups, g0, V0, t_span, t_eval):
    """(pair, poses, group maps, velocities, t0, t1, output times) of :func:`integrate_adaptive`'s
    arguments, checked."""
    tab = resolve_pair(tableau)
    if tab.b_hat is None:
        raise ValueError(f"method '{tab.name}' has no embedded weights (b_hat): adaptive "
                         f"steps need an embedded pair, e.g. DOPRI5, BS3 or Vern6")
    g = as_poses(g0)
    n = len(g)
    gms = resolve_groups(groups, n)
    V = np.array(V0, dtype=np.float64).reshape(n, 6)
    t0, t1 = float(t_span[0]), float(t_span[1])
    if not t1 > t0:
        raise ValueError("t_span must be increasing")
    t_out = np.array([t1] if t_eval is None else t_eval, dtype=np.float64)
    if t_out.size and (np.any(np.diff(t_out) < 0) or t_out[0] < t0 or t_out[-1] > t1):
        raise ValueError("t_eval must be sorted and inside t_span")
    needs_dense = np.any((t_out > t0) & (t_out < t1))
    if needs_dense and tab.dense is None:
        raise ValueError(f"method '{tab.name}' has no continuous extension: output times "
                         f"inside the interval need dense output")
    return tab, g, gms, V, t0, t1, t_out


def integrate_adaptive(tableau, groups, g0, V0, rhs, t_span, rtol=1e-6, atol=1e-6, *,
                       t_eval=None, h0=None, h_min=0.0, h_max=np.inf, length_scale=1.0,
                       time_scale=1.0, max_steps=1_000_000, **controller):
    """Integrate eq. (ODE2) ``Vdot = rhs(t, g, V)``, ``gdot = g V^`` with adaptive MK steps.

    ``t_eval``: output times in ``t_span`` (dense output on the group; default: the end
    time only).  ``h0``: first step (default: HINIT).  ``h_min``, ``h_max``: step bounds; a
    rejected step whose retry would fall below ``h_min`` raises ``StepSizeError`` (with
    ``.time`` and ``.step``).  ``controller``:
    keywords of :func:`.control.controller_params` (safety, fac_min, fac_max, beta).
    Returns an :class:`AdaptiveTrajectory` whose ``stats`` count the steps and evaluations.
    """
    tab, g, gms, V, t0, t1, t_out = _checked_problem(tableau, groups, g0, V0, t_span, t_eval)
    n = len(g)
    tol = C.tolerances(atol, rtol, length_scale, time_scale)
    P = C.controller_params(tab.order_hat, h_min=h_min, h_max=min(h_max, t1 - t0), **controller)
    S = C.controller_state()
    stats = AdaptiveStats()
    e = np.asarray(tab.b) - np.asarray(tab.b_hat)
    st = _Step(tab, n)
    s = tab.stages
    out_R, out_r, out_V = [], [], []
    k_out = 0

    def store(gg, VV):
        out_R.append(np.array([R for R, _ in gg]))
        out_r.append(np.array([r for _, r in gg]))
        out_V.append(np.array(VV))

    while k_out < t_out.size and t_out[k_out] == t0:
        store(g, V)
        k_out += 1

    Vd_first = None
    if h0 is None:
        h, Vd_first, nr = initial_step(tab, gms, g, V, t0, rhs, tol, P[C.P_H_MAX])
        stats.rhs_evaluations += nr
    else:
        h = min(float(h0), P[C.P_H_MAX])
    h = max(h, h_min)                                     # HINIT is a guess: start at h_min
    stats.h_initial = h
    t = t0
    dPhi = np.zeros((n, 6))
    dV = np.zeros((n, 6))
    while t < t1:
        if stats.accepted + stats.rejected >= max_steps:
            raise RuntimeError(f"integrate_adaptive: more than {max_steps} steps")
        last = t + h >= t1 - 4.0 * np.finfo(float).eps * abs(t1)   # no sliver step at the end
        h_try = t1 - t if last else h
        nr, ok = st.sweep(gms, g, V, t, h_try, rhs, 0, s, Vd_first)
        stats.rhs_evaluations += nr
        Vd_first = st.Vd[0].copy()                       # stage 1 is reusable on rejection
        if not ok:                                       # stage argument beyond 2 pi
            err = np.inf
        else:
            if tab.fsal:                                 # the last stage is the result
                g_new, V_new = st.last
            else:
                Phi, dVb = st.increments(h_try, tab.b)
                g_new, V_new = _translate(gms, g, Phi), V + dVb
            err = C.embedded_error_norm(e, h_try, st.K[:s], st.Vd[:s], _origins(g),
                                        _origins(g_new), V, V_new, tol, dPhi, dV)
        status = C.control_step(P, S, h_try, err)
        if status == C.STATUS_H_MIN:
            C.raise_step_size_error(t, S[C.S_H], h_min, err, tab.name)
        if status == C.STATUS_REJECT:
            stats.rejected += 1
            h = S[C.S_H]
            continue
        stats.accepted += 1
        stats.steps.append((t, h_try, err))
        t_new = t1 if last else t + h_try
        # dense output at the output times of (t, t_new]
        extra_done = False
        while k_out < t_out.size and t_out[k_out] <= t_new:
            tk = t_out[k_out]
            if tk == t_new:
                store(g_new, V_new)
            else:
                if st.m and not extra_done:
                    stats.rhs_evaluations += st.sweep(gms, g, V, t, h_try, rhs, s, s + st.m)[0]
                    extra_done = True
                w = tab.dense.weights((tk - t) / h_try)
                sig, dv = st.increments(h_try, w)
                store(_translate(gms, g, sig), V + dv)
            k_out += 1
        # FSAL: the last stage's right-hand side is the next step's first
        Vd_first = st.Vd[s - 1].copy() if tab.fsal else None
        g, V, t = g_new, V_new, t_new
        h = S[C.S_H]
    return AdaptiveTrajectory(np.array(t_out[:k_out]), np.array(out_R), np.array(out_r),
                              np.array(out_V), stats)
