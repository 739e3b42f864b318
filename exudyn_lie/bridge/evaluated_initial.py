"""Initial consistency on the Exudyn-evaluated path, with the compiled path's rules
(``Simulator._check_initial_consistency``): a residual above ``INITIAL_TOL`` (relative) of the
position-level constraints, then of the velocity-level ones, either raises
:class:`~exudyn_lie.errors.ConstraintError` (``projectInitial=False``) or is projected away:

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
from ..mbs.simulator import INITIAL_TOL

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


def _position_residual(model, t):
    """The position-level residual; a velocity-level row has none (Exudyn returns its velocity
    equation there): 0."""
    model._setTime(t)
    model._ae(model.mbs, False)
    g = model._residual()[model.n + model.n1:].copy()
    g[model.velocityRows] = 0.0
    return g


def _correction(model, t, rhs):
    """``Delta`` with ``C_q Delta = rhs`` of least M-norm (the KKT solve with f = 0)."""
    M, f, Cq = model.mass_force_jacobian(t)
    model.solve(M, np.zeros(model.n), Cq, np.asarray(rhs, float))
    return model.a.copy()


def project_initial(model, problem, t, projectInitial):
    """Check / project the problem's (:mod:`.evaluated_problem`) initial state; writes it into mbs.  Returns a
    description of the correction, or None."""
    if model.m == 0:
        return None
    mbs = model.mbs
    problem.write()
    fixed = []
    g = _position_residual(model, t)
    scale = max(1.0, float(np.max(np.abs(problem.r))) if problem.r.size else 1.0,
                float(np.max(np.abs(problem.qv))) if problem.qv.size else 1.0)
    bad = np.nonzero(np.abs(g) > INITIAL_TOL * scale)[0]
    if len(bad):
        if not projectInitial:
            raise ConstraintError(f"initial configuration violates the constraints of objects {_names(mbs, bad)} "
                                  f"(max |g| = {np.max(np.abs(g)):.3g}); fix the initial poses or pass "
                                  f"projectInitial=True to project them onto the constraints first")
        g0 = float(np.max(np.abs(g)))
        L = model.L
        for _ in range(MAX_ITER):
            d = _correction(model, t, -g)
            for i in range(len(L.lgNodes)):
                idx = L.lgIdx[i]
                problem.R[i] = problem.R[i] @ so3.exp(np.ascontiguousarray(d[idx[3:]]))
                problem.r[i] += d[idx[:3]]
            problem.qv += d[L.vecIdx]
            problem.write()
            g = _position_residual(model, t)
            if np.max(np.abs(g)) <= TOL * scale:
                break
        else:
            raise ConstraintError(f"the initial configuration could not be projected onto the constraints of "
                                  f"objects {_names(mbs, bad)} in {MAX_ITER} Gauss-Newton steps (max |g| = "
                                  f"{np.max(np.abs(g)):.3g}); they may not be satisfiable")
        fixed.append(f"positions of objects {_names(mbs, bad)} (max |g| = {g0:.3g})")
    # velocities: C_q v (+ C_t) = g_v
    gv = model.velocity_constraints(t, problem.R, problem.r, problem.prev, problem.qv)
    vscale = max(1.0, float(np.max(np.abs(model.qt))) if model.n else 1.0)
    bad = np.nonzero(np.abs(gv) > INITIAL_TOL * vscale)[0]
    if len(bad):
        if not projectInitial:
            raise ConstraintError(f"initial velocities violate the velocity constraints of objects "
                                  f"{_names(mbs, bad)} (max |g_v| = {np.max(np.abs(gv)):.3g}); pass "
                                  f"projectInitial=True to project them onto the constraints first")
        dv = _correction(model, t, -gv)
        qt = model.qt.copy() + dv
        L = model.L
        for i in range(len(L.lgNodes)):
            idx = L.lgIdx[i]
            problem.V[i, :3] = qt[idx[3:]]
            v = qt[idx[:3]]
            problem.V[i, 3:] = problem.R[i].T @ v if BODY_TWIST[problem.gid[i]] else v
        problem.set_vector_velocities(qt[L.vecIdx])
        problem.write()
        fixed.append(f"velocities of objects {_names(mbs, bad)} (max |g_v| = {np.max(np.abs(gv)):.3g}): changed "
                     f"by up to {np.max(np.abs(dv)):.3g}")
    return "; ".join(fixed) or None
