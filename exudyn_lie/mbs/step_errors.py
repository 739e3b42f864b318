"""What a simulator says when a step fails, and the step it suggests: the one
``StepSizeError`` (and the other errors) of a kernel status, the stability estimates behind
the suggested step (the spectral radius of the linearised equations, Shampine's estimate from
a step's stages).  Free functions of a :class:`~.simulator.Simulator` (``sim``), whose
``RaiseStatus``, ``suggest_step``, ``SpectralRadius`` and ``StageStiffness`` call them."""
from __future__ import annotations

import numpy as np

from ..errors import ConstraintError, SimulationError, StepSizeError
from ..integrators.stability import stability_radius
from . import external, kernel
from .bodies import body_dexpinv_stage, exp_compose
from .diagnostics import stage_stiffness
from .linalg import REL_PIVOT_TOL


def raise_status(sim, st, h):
    """Raise the error for a kernel status of ``sim`` (:meth:`Simulator.RaiseStatus`)."""
    if st == kernel.STATUS_STEP_MIN:
        sim._ad.raise_step_min()
    if st == kernel.STATUS_EXTERNAL:
        external.reraise(sim._driveToken)
        external.reraise(sim._extToken)
        if sim.wk.ext[1] and sim.rates:
            sim.wk.ext[1] = 0
            st = kernel.STATUS_NONFINITE          # the step's error below, with a suggested step
        elif sim.wk.ext[1]:
            sim.wk.ext[1] = 0
            names = ", ".join(pf.name for pf in sim.scene.pythonForces)
            raise SimulationError(f"{names} must return finite (F, T) arrays of shape ({sim.sd.nb}, 3); "
                                  f"got non-finite values at t = {sim.t:.6g} s")
        else:
            raise SimulationError(f"the Python forces failed at t = {sim.t:.6g} s")
    if st == kernel.STATUS_SINGULAR:
        # the failing stage's state (same rule as the kernel: linalg module docstring)
        rank, dep = sim._dependent_rows(sim.wk.Rs, sim.wk.rs, sim.wk.Vs, forced=True)
        names = sim._joints_of_rows(dep) if dep else sim._joints_of_rows([int(sim.wk.info[0])])
        raise ConstraintError(
            f"singular constraint Jacobian at t = {sim.t:.6g} s: the constraints of joints "
            f"{', '.join(names)} are linearly dependent (a Cholesky pivot of J M^-1 J^T fell to "
            f"{REL_PIVOT_TOL:g} x its row's diagonal or below: a singular configuration, or redundant "
            f"joints); remove the redundant constraint axes (e.g. make one joint spherical) or "
            f"check the joint frames")
    if st == kernel.STATUS_STAGE_ARG:
        i = int(sim.wk.info[2])
        psi = float(np.linalg.norm(sim.wk.Psi[i, :3]))
        # the stage arguments scale with h: aim the largest at pi, and keep the
        # stability-based suggestion if that is smaller
        sugg = min(suggest_step(sim, h), h * np.pi / psi) if psi > 0 else suggest_step(sim, h)
        raise StepSizeError(
            f"the rotation of {sim.scene.describe_body(i)} in an MK stage, |Psi| = {psi:.4g} rad, "
            f"is beyond {kernel.STAGE_ARG_MAX:.4g} = 2 pi - {2 * np.pi - kernel.STAGE_ARG_MAX:.2g} (dexp^-1 of "
            f"the stage equation is singular "
            f"at 2 pi) at t = {sim.t:.6g} s with step size {h:.3g} s (method {sim.tableau.name}); the "
            f"rotation per step is too large: try a step size of {sugg:.3g} s or smaller")
    if st == kernel.STATUS_PROJECTION:
        hres = sim.wk.h
        bad = np.nonzero(np.abs(hres) > kernel.PROJ_FAIL * kernel.PROJ_TOL)[0]
        raise ConstraintError(
            f"position projection did not converge in {kernel.PROJ_MAX_ITER} iterations at t = {sim.t:.6g} s "
            f"(max |h| = {np.max(np.abs(hres)):.3g}); the constraints of joints "
            f"{', '.join(sim._joints_of_rows(bad))} may not be satisfiable")
    sugg = suggest_step(sim, h)
    what = "non-finite (NaN/inf)" if st == kernel.STATUS_NONFINITE else "unbounded (blow-up)"
    raise StepSizeError(
        f"the state became {what} at t = {sim.t:.6g} s with step size {h:.3g} s "
        f"(method {sim.tableau.name}); the step is beyond the stability limit: "
        f"try a step size of {sugg:.3g} s or smaller")


def stage_stiffness_of(sim, h, nb=None):
    """Shampine's estimate of the fastest rate the last fixed step of size ``h`` met, from
    its stages (:func:`~.diagnostics.stage_stiffness`; the first ``nb`` bodies, default all):
    a mode that became stiff during the run (a contact that closed) shows here before it
    blows up."""
    tab = sim.method
    return float(stage_stiffness(tab.A, float(h), int(tab.stages[-1]), sim.wk.K, sim.wk.Vd,
                                 sim.sd.nb if nb is None else int(nb)))


def suggest_step(sim, h):
    """A step size that should be stable: ``0.8 r / rho``, where ``rho`` is the spectral
    radius of the linearised equations of motion at the state the failed
    :meth:`Advance` started from (:meth:`SpectralRadius`) and ``r`` the radius of the
    method's stability half-disk (:func:`~exudyn_lie.integrators.stability.stability_radius`).
    Never more than ``h / 2``; ``h / 10`` if the estimate is not available."""
    start = getattr(sim, "_segmentStart", None)
    try:
        if start is None:
            raise ValueError("no reference state")
        t0, R, r, V = start[:4]
        rho = spectral_radius(sim, R, r, V, t0)
    except Exception:           # noqa: BLE001 - a suggestion must never mask the error
        return h / 10.0
    if not np.isfinite(rho) or rho <= 0:
        return h / 10.0
    return float(min(0.5 * h, 0.8 * stability_radius(sim.tableau) / rho))


def spectral_radius(sim, R=None, r=None, V=None, t=None, iterations=40, seed=0):
    """Estimate of the spectral radius ``rho`` of the Jacobian of the first-order
    equations of motion ``(xi, V)' = (dexp^-1_{-xi} V, F(g exp(xi), V))`` in local
    coordinates ``xi`` around ``g`` (eqs. ODE2 with MK1): power iteration on
    central-difference Jacobian-vector products.  ``h rho`` is what the step size
    must keep inside the method's stability region."""
    R = sim.R if R is None else np.asarray(R, float)
    r = sim.r if r is None else np.asarray(r, float)
    V = sim.V if V is None else np.asarray(V, float)
    t = sim.t if t is None else float(t)
    nb = sim.sd.nb
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(2, nb, 6))
    d /= np.linalg.norm(d)
    scale = 1.0 + float(np.max(np.abs(V))) + float(np.max(np.abs(r)))
    logs = []
    for it in range(int(iterations)):
        eps = 1e-7 * scale
        fp = _local_field(sim, R, r, V, t, eps * d)
        fm = _local_field(sim, R, r, V, t, -eps * d)
        w = (fp - fm) / (2 * eps)
        nw = float(np.linalg.norm(w))
        if not np.isfinite(nw):
            return float("nan")
        if nw == 0.0:
            return 0.0
        logs.append(np.log(nw))
        d = w / nw
    # the dominant modes of a mechanical system come in complex pairs, for which the
    # norm ratio oscillates: average the logarithms of the second half
    return float(np.exp(np.mean(logs[len(logs) // 2:])))


def _local_field(sim, R, r, V, t, dx):
    """The vector field of :meth:`SpectralRadius` at ``(xi, V + dV) = dx``."""
    sd, wk = sim.sd, sim.wk
    nb = sd.nb
    Rp = np.empty((nb, 3, 3))
    rp = np.empty((nb, 3))
    Vp = np.ascontiguousarray(V + dx[1])
    out = np.empty((2, nb, 6))
    ER, Er = np.empty((3, 3)), np.empty(3)
    for i in range(nb):
        X = np.ascontiguousarray(dx[0, i])
        exp_compose(int(sim.gid[i]), R[i], r[i], X, Rp[i], rp[i], ER, Er)
        body_dexpinv_stage(int(sim.gid[i]), -X, Vp[i], out[0, i])
    if sim._evaluate(t, Rp, rp, Vp) != kernel.STATUS_OK:
        raise SimulationError("right-hand side failed while estimating the spectral radius")
    out[1] = wk.Vd[0]
    return out
