"""What a simulator says when a step fails: the errors of a kernel status (:func:`raise_status`, a free
function of a :class:`~.simulator.Simulator` ``sim``, whose ``RaiseStatus`` calls it).  The
estimates behind a suggested step live in :mod:`.stiffness`."""
from __future__ import annotations

import numpy as np

from ..errors import ConstraintError, SimulationError, step_size_error
from . import external, kernel
from .codes import INFO_BODY, INFO_ROW
from .linalg import REL_PIVOT_TOL
from .stiffness import suggest_step


def raise_status(sim, st, h):
    """Raise the error for a kernel status of ``sim`` (:meth:`Simulator.RaiseStatus`)."""
    if st == kernel.STATUS_STEP_MIN:
        sim._ad.raise_step_min()
    if st == kernel.STATUS_NO_RHS:
        raise SimulationError("internal: a Work without the address of the stage right-hand side (mbs/rhs_address.py)")
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
        names = sim._joints_of_rows(dep) if dep else sim._joints_of_rows([int(sim.wk.failInfo[INFO_ROW])])
        raise ConstraintError(
            f"singular constraint Jacobian at t = {sim.t:.6g} s: the constraints of joints "
            f"{', '.join(names)} are linearly dependent (a Cholesky pivot of J M^-1 J^T fell to "
            f"{REL_PIVOT_TOL:g} x its row's diagonal or below: a singular configuration, or redundant "
            f"joints); remove the redundant constraint axes (e.g. make one joint spherical) or "
            f"check the joint frames")
    if st == kernel.STATUS_STAGE_ARG:
        i = int(sim.wk.failInfo[INFO_BODY])
        psi = float(np.linalg.norm(sim.wk.Psi[i, :3]))
        # the stage arguments scale with h: aim the largest at pi, and keep the
        # stability-based suggestion if that is smaller
        sugg = min(suggest_step(sim, h), h * np.pi / psi) if psi > 0 else suggest_step(sim, h)
        raise step_size_error(
            sim.tableau.name, h, sim.t,
            f"the rotation of {sim.scene.describe_body(i)} in an MK stage, |Psi| = {psi:.4g} rad, "
            f"is beyond {kernel.STAGE_ARG_MAX:.4g} = 2 pi - {2 * np.pi - kernel.STAGE_ARG_MAX:.2g} (dexp^-1 of "
            f"the stage equation is singular at 2 pi)", "the rotation per step is too large", sugg)
    if st == kernel.STATUS_PROJECTION:
        hres = sim.wk.h
        bad = np.nonzero(np.abs(hres) > kernel.PROJ_FAIL * kernel.PROJ_TOL)[0]
        raise ConstraintError(
            f"position projection did not converge in {kernel.PROJ_MAX_ITER} iterations at t = {sim.t:.6g} s "
            f"(max |h| = {np.max(np.abs(hres)):.3g}); the constraints of joints "
            f"{', '.join(sim._joints_of_rows(bad))} may not be satisfiable")
    if st == kernel.STATUS_NEWTON:
        parts = sim.newtonSubsteps
        exc = step_size_error(
            sim.tableau.name, h, sim.t, "the Newton iteration of an implicit stage did not converge (with a "
            "Jacobian of this step, then at each iterate" + (f", and with the step in up to {parts[-1]} parts)"
                                                              if parts else ")"),
            "the step is too large for the nonlinearity of the model", h / parts[-1] if parts else h / 2)
        exc.newton = True
        raise exc
    if st == kernel.STATUS_STIFF:
        exc = step_size_error(sim.tableau.name, h, sim.t, "the step size is beyond the stability limit of the method",
                              "a step shows a mode beyond the method's stability radius, by its stages or, where its "
                              "last stage alone entered it, at its end (e.g. a contact that closed)", suggest_step(sim, h))
        exc.stiffStages = True
        raise exc
    sugg = suggest_step(sim, h)
    what = "non-finite (NaN/inf)" if st == kernel.STATUS_NONFINITE else "unbounded (blow-up)"
    raise step_size_error(sim.tableau.name, h, sim.t, f"the state became {what}",
                          "the step is beyond the stability limit", sugg)


