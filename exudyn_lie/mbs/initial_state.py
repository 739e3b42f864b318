"""The check of an initial state against the constraints and its projection, for any
problem (the compiled kernel's rows, or the equations the bridge evaluates in the modelling
system it reads, on the evaluated path): one rule, one order, one error text.

The rule: a position residual above ``INITIAL_TOL`` relative to the configuration's scale
(``max(1, max |position|)``), then a velocity residual above ``INITIAL_TOL`` relative to
``max(1, max |velocity|)``, is either a :class:`~exudyn_lie.errors.ConstraintError`
(``projectInitial=False``) or projected away: the positions first (Gauss-Newton steps on the
group, mass-weighted), then the velocities (mass-orthogonal), each by the problem's own
projection.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConstraintError
from ..userwarn import warn_user
from . import kernel
from .compiled import with_redundant
from .linalg import REL_PIVOT_TOL

# relative size of the constraint residual / velocity error accepted at the start
INITIAL_TOL = 1e-8


def check_initial_state(levels, projectInitial):
    """Check the initial state of ``levels``, a problem's constraint levels with

    * ``position_residual()`` -> (residual of every row, scale),
    * ``velocity_residual()`` -> (velocity residual of every row, scale),
    * ``project_positions()``, ``project_velocities()``,
    * ``describe_rows(rows)`` -> the items of those rows (e.g. "joints A, B"),

    and raise or project as the module says.  Returns what was projected: a list of
    ``(level, rows, max residual)`` with level ``"positions"`` / ``"velocities"``."""
    fixed = []
    g, scale = levels.position_residual()
    bad = np.nonzero(np.abs(g) > INITIAL_TOL * scale)[0]
    if len(bad):
        if not projectInitial:
            raise ConstraintError(f"initial configuration violates the constraints of {levels.describe_rows(bad)} "
                                  f"(max |h| = {np.max(np.abs(g)):.3g}); fix the initial poses or pass "
                                  f"projectInitial=True to project them onto the constraints first")
        fixed.append(("positions", bad, float(np.max(np.abs(g)))))
        levels.project_positions()
    gv, vscale = levels.velocity_residual()
    bad = np.nonzero(np.abs(gv) > INITIAL_TOL * vscale)[0]
    if len(bad):
        if not projectInitial:
            raise ConstraintError(f"initial velocities violate the velocity constraints of "
                                  f"{levels.describe_rows(bad)} (max |J V| = {np.max(np.abs(gv)):.3g}); pass "
                                  f"projectInitial=True to project them onto the constraints first")
        fixed.append(("velocities", bad, float(np.max(np.abs(gv)))))
        levels.project_velocities()
    return fixed


class RowLevels:
    """The kernel's constraint rows of a :class:`~.simulator.Simulator` as the levels of
    :func:`check_initial_state` (its own projections on the group)."""

    def __init__(self, sim):
        self.sim = sim
        self._rows = None           # (h, J V) at the current state: one evaluation serves both levels

    def position_residual(self):
        sim = self.sim
        self._rows = sim._residuals_and_JV()
        return self._rows[0], max(1.0, float(np.max(np.abs(sim.r))) if sim.r.size else 1.0)

    def velocity_residual(self):
        sim = self.sim
        rows = self._rows if self._rows is not None else sim._residuals_and_JV()
        return rows[1], max(1.0, float(np.max(np.abs(sim.V))))

    def project_positions(self):
        self._rows = None           # the state moved
        self.sim.ProjectPositions()

    def project_velocities(self):
        self.sim.ProjectVelocities()

    def describe_rows(self, rows):
        return "joints " + ", ".join(self.sim._joints_of_rows(rows))


def check_redundancy(sim):
    """Redundant rows at ``sim``'s initial state switch the kernel to its rank-revealing solve.

    One rule decides, the kernel's (:mod:`exudyn_lie.mbs.linalg`): the time loop's own
    band Cholesky of ``S = J M^-1 J^T`` at the initial state (O(m b^2)).  If a pivot
    falls to ``<= REL_PIVOT_TOL * S_ii`` (its row's diagonal) the time loop would stop at its first
    stage, so the simulator switches to the rank-revealing (complete-pivoted
    Cholesky) solve, which applies the same tolerance, and warns: "redundant" with
    the rank when the pivoted factorisation drops rows, "ill-conditioned" when only
    the band factorisation's ordering met the threshold.  The joints are named from
    the null space of the dense S (O(m^3), only on this path)."""
    if sim.sd.nrows == 0:
        return
    if sim._evaluate(sim.t, sim.R, sim.r, sim.V) != kernel.STATUS_SINGULAR:
        return
    m = sim.sd.nrows
    rank, dep = sim._dependent_rows(sim.R, sim.r, sim.V, forced=True)
    sim.redundantJoints = sim._joints_of_rows(dep)
    sim.sd = with_redundant(sim.sd, True)
    sim.wk = sim._make_work()
    sim._update_tracking()
    names = ", ".join(sim.redundantJoints)
    rule = (f"Cholesky pivots of J M^-1 J^T at or below {REL_PIVOT_TOL:g} x their row's diagonal at the "
            f"initial state")
    if rank < m:
        msg = (f"exudyn_lie: redundant constraints among joints {names} (numerical rank {rank} of {m} "
               f"rows: {rule}); using the rank-revealing (pivoted Cholesky) solve")
    else:
        msg = (f"exudyn_lie: ill-conditioned constraints among joints {names} (a band Cholesky pivot of "
               f"J M^-1 J^T at or below {REL_PIVOT_TOL:g} x its row's diagonal at the initial state, "
               f"full rank with pivoting); using the pivoted Cholesky solve")
    warn_user(msg)
