"""Initial consistency on the Exudyn-evaluated path: Exudyn's own constraint equations as the
levels of the one rule (:func:`~exudyn_lie.mbs.initial_state.check_initial_state`, which the
compiled path's ``Simulator._check_initial_consistency`` uses too); the projections:

* positions: Gauss-Newton steps ``Delta = -M^-1 C_q^T (C_q M^-1 C_q^T)^-1 g`` in Exudyn's
  velocity coordinates, applied on the group for Lie group nodes (``R exp(Delta omega)``,
  ``r + Delta r``) and added to vector coordinates;
* velocities: the mass-orthogonal projection ``v <- v - M^-1 C_q^T (C_q M^-1 C_q^T)^-1 C_q v``,
  which does not depend on the velocity coordinates (the compiled path's projection in its
  group velocities gives the same velocities).

Both solves are the model's index-1 solve (:meth:`~.evaluated.EvaluatedModel.solve`) with ``f = 0``.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConstraintError
from ..groups import so3
from ..mbs.codes import BODY_TWIST
from ..mbs.initial_state import check_initial_state

MAX_ITER = 20
TOL = 1e-13


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


def _correction(model, t, rhs):
    """``Delta`` with ``C_q Delta = rhs`` of least M-norm (the KKT solve with f = 0)."""
    M, f, Cq = model.mass_force_jacobian(t)
    model.solve(M, np.zeros(model.n), Cq, np.asarray(rhs, float))
    return model.a.copy()


class _ExudynLevels:
    """Exudyn's own constraint equations at the problem's state as the levels of
    :func:`~exudyn_lie.mbs.initial_state.check_initial_state`."""

    def __init__(self, model, problem, t):
        self.model, self.problem, self.t = model, problem, t
        self.velocityChange = 0.0

    def position_residual(self):
        p = self.problem
        scale = max(1.0, float(np.max(np.abs(p.r))) if p.r.size else 1.0,
                    float(np.max(np.abs(p.qv))) if p.qv.size else 1.0)
        self.scale = scale
        return self.model.position_residual(self.t), scale

    def velocity_residual(self):
        m, p = self.model, self.problem
        gv = m.velocity_constraints(self.t, p.R, p.r, p.prev, p.qv)
        return gv, max(1.0, float(np.max(np.abs(m.qt))) if m.n else 1.0)

    def project_positions(self):
        """Gauss-Newton steps on the group for Lie group nodes, added to vector coordinates."""
        model, problem, t = self.model, self.problem, self.t
        L = model.L
        g = model.position_residual(t)
        for _ in range(MAX_ITER):
            d = _correction(model, t, -g)
            for i in range(len(L.lgNodes)):
                idx = L.lgIdx[i]
                problem.R[i] = problem.R[i] @ so3.exp(np.ascontiguousarray(d[idx[3:]]))
                problem.r[i] += d[idx[:3]]
            problem.qv += d[L.vecIdx]
            problem.write()
            g = model.position_residual(t)
            if np.max(np.abs(g)) <= TOL * self.scale:
                return
        bad = np.nonzero(np.abs(g) > TOL * self.scale)[0]
        raise ConstraintError(f"the initial configuration could not be projected onto the constraints of "
                              f"{self.describe_rows(bad)} in {MAX_ITER} Gauss-Newton steps (max |h| = "
                              f"{np.max(np.abs(g)):.3g}); they may not be satisfiable")

    def project_velocities(self):
        """The mass-orthogonal projection, written as the problem's velocities."""
        model, problem, t = self.model, self.problem, self.t
        L = model.L
        gv = model.velocity_constraints(t, problem.R, problem.r, problem.prev, problem.qv)
        dv = _correction(model, t, -gv)
        qt = model.qt.copy() + dv
        for i in range(len(L.lgNodes)):
            idx = L.lgIdx[i]
            problem.V[i, :3] = qt[idx[3:]]
            v = qt[idx[:3]]
            problem.V[i, 3:] = problem.R[i].T @ v if BODY_TWIST[problem.gid[i]] else v
        problem.set_vector_velocities(qt[L.vecIdx])
        problem.write()
        self.velocityChange = float(np.max(np.abs(dv)))

    def describe_rows(self, rows):
        return "objects " + _names(self.model.mbs, rows)


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
