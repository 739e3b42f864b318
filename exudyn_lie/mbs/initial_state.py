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
