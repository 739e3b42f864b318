"""Stability of an explicit step on the Exudyn-evaluated path (stiff items such as ANCF
cables at the script's step).

The linearised, undamped equations on the constraint manifold have the eigenvalues
``+-i omega`` with ``omega^2`` the generalised eigenvalues of ``(N^T K N, N^T M N)``:
``K = -df/dq`` (Exudyn's ``ComputeJacobianODE2RHS``, loads included), ``N`` a basis of the
null space of ``C_q`` (motions the constraints allow).  A step ``h`` is linearly stable for
all of them if ``h omega_max <= y_max``, the method's stability limit on the imaginary axis
(:func:`~exudyn_lie.integrators.stability.imaginary_axis_limit`, from the tableau's
coefficients).  :func:`check_step` raises :class:`~exudyn_lie.errors.StepSizeError` with the
stable step ``0.9 y_max / omega_max`` before a run whose step is beyond that limit;
:func:`suggest_step` gives the same step for the error of a blow-up during the run.
"""
from __future__ import annotations

import numpy as np

from ..errors import StepSizeError
from ..integrators.stability import imaginary_axis_limit, stability_radius

SAFETY = 0.9


def omega_max(model):
    """Largest angular frequency of the linearised, undamped, constrained equations at the
    state in mbs (rad/s); 0 if there is no stiffness."""
    s, mbs, n, n1 = model.solver, model.mbs, model.n, model.n1
    M, f, Cq = model.mass_force_jacobian(model.sd.GetTime())
    M = np.array(M)
    Cq = None if Cq is None else np.array(Cq)
    s.ComputeJacobianODE2RHS(mbs, scalarFactor_ODE2=-1.0, scalarFactor_ODE2_t=0.0, scalarFactor_ODE1=0.0,
                             computeLoadsJacobian=1)
    K = np.array(s.GetSystemJacobian()[:n, :n])
    if not np.any(K):
        return 0.0
    K = 0.5 * (K + K.T)
    if Cq is not None and Cq.shape[0]:
        rows = np.any(Cq != 0.0, axis=1)
        Cq = Cq[rows]
    if Cq is not None and Cq.shape[0]:
        u, sv, vt = np.linalg.svd(Cq)
        rank = int(np.sum(sv > 1e-10 * max(sv.max(), 1e-300)))
        N = vt[rank:].T
    else:
        N = np.eye(n)
    if N.shape[1] == 0:
        return 0.0
    Mr = N.T @ M @ N
    Kr = N.T @ K @ N
    try:
        ev = np.linalg.eigvals(np.linalg.solve(Mr, Kr))
    except np.linalg.LinAlgError:
        return 0.0
    ev = ev[np.isfinite(ev)]
    if ev.size == 0:
        return 0.0
    return float(np.sqrt(max(0.0, float(np.max(np.abs(ev))))))


def stable_step(tableau, omega):
    """``SAFETY y_max / omega`` (inf without stiffness); methods stable on no part of the
    imaginary axis use the radius of their stability half-disk."""
    lim = imaginary_axis_limit(tableau)
    if not lim > 0:
        lim = stability_radius(tableau)
    return float("inf") if omega <= 0 else SAFETY * lim / omega, lim


def check_step(model, tableau, h):
    """Raise StepSizeError if ``h`` is beyond the linear stability limit at the state in mbs."""
    om = omega_max(model)
    step, lim = stable_step(tableau, om)
    if h * om > lim:
        raise StepSizeError(f"the step size {h:.3g} s is beyond the stability limit of {tableau.name} for this "
                            f"model: its stiffest mode has omega = {om:.4g} rad/s (Exudyn's stiffness and mass "
                            f"matrices on the constraint manifold), so h omega = {h * om:.3g} > {lim:.3g} (the "
                            f"method's limit on the imaginary axis); use timeIntegration.numberOfSteps for a step "
                            f"size of {step:.3g} s or smaller", )
    return om, step


def suggest_step(stepper, h):
    """A stable step for the error of a blow-up: from the stiffness at the state the run
    last started a step from (``stepper.start``), else ``h / 10``."""
    start = getattr(stepper, "start", None)
    if start is None:
        return h / 10
    try:
        stepper.restore(start)
        stepper.write()
        om = omega_max(stepper.model)
        step, _ = stable_step(stepper.tableau, om)
        return min(step, h / 2)
    except Exception:           # noqa: BLE001 - the suggestion must not hide the error
        return h / 10
