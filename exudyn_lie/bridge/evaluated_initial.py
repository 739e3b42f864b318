"""Initial consistency on the Exudyn-evaluated path: Exudyn's own constraint equations as the
levels of the one rule (:func:`~exudyn_lie.mbs.initial_state.check_initial_state`, which the
compiled path's ``Simulator._check_initial_consistency`` uses too); the projections are those
of every step (:mod:`.evaluated_projection`).
"""
from __future__ import annotations

import numpy as np

from ..errors import ConstraintError
from ..mbs.codes import PROJ_MAX_ITER, PROJ_TOL
from ..mbs.initial_state import check_initial_state
from .evaluated_projection import position_scale, project_positions, project_velocities


def _rows_to_objects(mbs):
    sd = mbs.systemData
    out = {}
    for o in range(sd.NumberOfObjects()):
        for r in sd.GetObjectLTGAE(o):
            d = mbs.GetObject(o)
            out[int(r)] = f"{o} ('{d.get('name', '')}', Object{d['objectType']})"
    for n in range(sd.NumberOfNodes()):
        for r in sd.GetNodeLTGAE(n):
            out[int(r)] = f"node {n} (Node{mbs.GetNode(n)['nodeType']}, its own constraint)"
    return out


def _names(mbs, rows):
    m = _rows_to_objects(mbs)
    return ", ".join(dict.fromkeys(m.get(int(r), f"AE row {r}") for r in rows))


class _ExudynLevels:
    """Exudyn's own constraint equations at the problem's state as the levels of
    :func:`~exudyn_lie.mbs.initial_state.check_initial_state`."""

    def __init__(self, model, problem, t):
        self.model, self.problem, self.t = model, problem, t
        self.velocityChange = 0.0

    def position_residual(self):
        self.scale = position_scale(self.model, self.problem)
        return self.model.position_residual(self.t), self.scale

    def velocity_residual(self):
        m, p = self.model, self.problem
        gv = m.velocity_constraints(self.t, p.R, p.r, p.prev, p.qv)
        return gv, max(1.0, float(np.max(np.abs(m.qt))) if m.n else 1.0)

    def project_positions(self):
        """Gauss-Newton steps on the group for Lie group nodes, added to vector coordinates."""
        tol = PROJ_TOL * self.scale
        g, _ = project_positions(self.model, self.problem, self.t, tol, chord=False)
        if not np.max(np.abs(g)) > tol:
            return
        bad = np.nonzero(np.abs(g) > tol)[0]
        raise ConstraintError(f"the initial configuration could not be projected onto the constraints of "
                              f"{self.describe_rows(bad)} in {PROJ_MAX_ITER} Gauss-Newton steps (max |h| = "
                              f"{np.max(np.abs(g)):.3g}); they may not be satisfiable")

    def project_velocities(self):
        """The mass-orthogonal projection, written as the problem's velocities."""
        self.velocityChange = project_velocities(self.model, self.problem, self.t)

    def describe_rows(self, rows):
        return describe_rows(self.model.mbs, rows)


def describe_rows(mbs, rows):
    """The Exudyn items of AE rows ``rows``, for errors."""
    return "objects " + _names(mbs, rows)


def project_initial(model, problem, t, projectInitial):
    """Check / project the problem's (:mod:`.evaluated_problem`) initial state
    (:func:`~exudyn_lie.mbs.initial_state.check_initial_state`); writes it into mbs.  Returns a
    description of the correction, or None."""
    if model.m == 0:
        return None
    problem.write()
    levels = _ExudynLevels(model, problem, t)
    fixed = check_initial_state(levels, projectInitial)
    out = []
    for level, rows, residual in fixed:
        if level == "positions":
            out.append(f"positions of {levels.describe_rows(rows)} (max |h| = {residual:.3g})")
        else:
            out.append(f"velocities of {levels.describe_rows(rows)} (max |g_v| = {residual:.3g}): changed by up "
                       f"to {levels.velocityChange:.3g}")
    return "; ".join(out) or None
