"""Projections onto Exudyn's own constraints on the Exudyn-evaluated path, the compiled path's
(mbs/projection.py) with Exudyn's residuals and C_q: at the initial state
(:mod:`.evaluated_initial`) and, with ``stabilization='position'`` (the drop-in's default) or
``'velocity'``, at the end of every Exudyn step (:class:`StepProjection`).

* positions: Gauss-Newton steps ``Delta = -M^-1 C_q^T (C_q M^-1 C_q^T)^-1 g`` in Exudyn's
  velocity coordinates, applied on the group for Lie group nodes (``R exp(Delta omega)``,
  ``r + Delta r``) and added to vector coordinates, until ``max |g| <= PROJ_TOL max(1, max |q|)``
  (the compiled path's tolerance, with Exudyn's coordinates for the scale; after a step only once
  the residual exceeds :data:`PROJECT_ABOVE` of that scale);
* velocities: the mass-orthogonal projection ``v <- v - M^-1 C_q^T (C_q M^-1 C_q^T)^-1 g_v``
  onto Exudyn's velocity-level equations (a velocity-level row's offset included), which does
  not depend on the velocity coordinates (the compiled path's projection in its group velocities
  gives the same velocities).

Both solves are the model's index-1 solve (:meth:`~.evaluated.EvaluatedModel.solve`) with ``f = 0``.

Index-1 integration lets the position level drift (the paper's subject); on this path the drift
is also what the stage equations of an implicit method cannot always absorb: Exudyn's
``ANCFmovingRigidbody.py`` (a rigid body on an ALE cable, ESDIRK3 at the script's step) drifted
off its sliding joint until no step, however small, had a Newton solution (t = 0.238 s); projected
after each step (an earlier form of this module, which projected at every step, by hand), it
passed that point and stopped later, at t = 0.384 s, for a cause not found.  The projection is
made once per Exudyn step (after its MK steps, ``substeps`` or the adaptive ones): the state
Exudyn's outputs and PostNewton see.
"""
from __future__ import annotations

import numpy as np

from ..groups import so3
from ..errors import ConstraintError
from ..mbs.codes import BODY_TWIST, PROJ_FAIL, PROJ_MAX_ITER, PROJ_TOL
from ..mbs.linalg import max_abs

#: a step's state is projected when Exudyn's residual exceeds this fraction of the scale (positions:
#: ``max(1, max |q|)``, velocities: ``max(1, max |q_t|)``), and then to PROJ_TOL of it.  On the compiled
#: path a projection costs a few percent of a step and is made at every step; here it costs two
#: evaluations by Exudyn and two KKT solves, as much as two stages (``bench --quick --sections
#: stabilization``, evaluated lines: +41 to +75 % on the paper's models when made at every step,
#: measured before this trigger).  Below it the drift is far below Exudyn's own Newton tolerance
#: (its generalized-alpha holds the constraints to it) and invisible in any output; a model whose
#: drift per step stays below it (the heavy top: 3e-11 in 0.5 s) pays two residual evaluations per
#: step (the same bench: +12 and +13 % for the heavy top and the cardan shaft, +55 and +69 % for the
#: planar four-bar and the spherical double pendulum, which drift more per step).
PROJECT_ABOVE = 1e-10


def metric(model, t):
    """``(M, C_q)`` at the state in mbs, for :func:`correction`.  One evaluation serves a step's
    Gauss-Newton iterations and its velocity projection: the corrections are of the size of one
    step's drift, so C_q at the step's end before them changes the velocity projection's result by
    their product, and the positions' iteration (a chord method) by a correction of their square."""
    M, _, Cq = model.mass_force_jacobian(t, forces=False)
    return M, Cq


def correction(model, MC, rhs):
    """``Delta`` with ``C_q Delta = rhs`` of least M-norm (the KKT solve with f = 0), ``MC = (M, C_q)``."""
    M, Cq = MC
    model.solve(M, np.zeros(model.n), Cq, np.asarray(rhs, float))
    return model.a.copy()


def position_scale(model, problem):
    """The positions' scale of the tolerance: ``max(1, max |r|, max |q|)`` with the vector
    coordinates' values (Exudyn's reference plus current coordinates: a node far from the origin
    carries the round-off of its position)."""
    p = problem
    if not hasattr(model, "_vecReference"):
        import exudyn as exu
        ref = model.sd.GetODE2Coordinates(configuration=exu.ConfigurationType.Reference)
        model._vecReference = np.asarray(ref, float)[model.L.vecIdx]
    return max(1.0, max_abs(p.r.reshape(-1)) if p.r.size else 1.0,
               max_abs(p.qv + model._vecReference) if p.qv.size else 1.0)


def project_positions(model, problem, t, tol, MC=None, chord=True):
    """Gauss-Newton onto Exudyn's position level, at most PROJ_MAX_ITER steps, from the state of
    ``problem`` (written into mbs); returns the residual left (``max |g| <= tol`` when it
    converged) and the last metric used.  ``MC`` (:func:`metric`, None: at the first step) is kept while each step reduces
    the residual tenfold (a step's drift: one evaluation) and evaluated again at the iterate
    otherwise (Gauss-Newton's own iteration for a large correction: an initial inconsistency, a
    connector switched on).  It stops early where a step with a fresh one does not halve the
    residual: the round-off of Exudyn's residual.  Without ``chord``, Gauss-Newton's own iteration
    throughout, to the end (the initial projection)."""
    L = model.L
    g = model.position_residual(t)
    gprev = np.inf
    fresh = False
    for _ in range(PROJ_MAX_ITER):
        gmax = max_abs(g)
        if not gmax > tol or (chord and fresh and gmax > 0.5 * gprev):
            break
        fresh = MC is None or not chord or gmax > 0.1 * gprev
        if fresh:
            MC = metric(model, t)
        gprev = gmax
        d = correction(model, MC, -g)
        for i in range(len(L.lgNodes)):
            idx = L.lgIdx[i]
            problem.R[i] = problem.R[i] @ so3.exp(np.ascontiguousarray(d[idx[3:]]))
            problem.r[i] += d[idx[:3]]
        problem.qv += d[L.vecIdx]
        problem.write()
        g = model.position_residual(t)
    return g, MC


def project_velocities(model, problem, t, gv=None, MC=None):
    """The mass-orthogonal projection onto Exudyn's velocity level, written as the problem's
    velocities (and into mbs), with ``MC`` (:func:`metric`; by default at that state); returns the
    largest change of a velocity coordinate."""
    L = model.L
    if gv is None:
        gv = model.velocity_constraints(t, problem.R, problem.r, problem.prev, problem.qv)
    dv = correction(model, metric(model, t) if MC is None else MC, -gv)
    qt = model.qt.copy() + dv
    for i in range(len(L.lgNodes)):
        idx = L.lgIdx[i]
        problem.V[i, :3] = qt[idx[3:]]
        v = qt[idx[:3]]
        problem.V[i, 3:] = problem.R[i].T @ v if BODY_TWIST[problem.gid[i]] else v
    problem.set_vector_velocities(qt[L.vecIdx])
    problem.write()
    return max_abs(dv)


class StepProjection:
    """The projection at the end of an Exudyn step (module docstring): ``'position'`` projects
    the positions and then the velocities, ``'velocity'`` the velocities only.  A residual
    below :data:`PROJECT_ABOVE` is left as it is (no solve); a position projection that does not
    converge stops the run with the compiled path's :class:`~exudyn_lie.errors.ConstraintError`.

    The run-time check (bridge/constraint_check.py) stays an oracle: projected onto Exudyn's own
    constraints, the state always satisfies them, so a velocity level that leaves something out
    (a moving offset, a marker moved by a user function) would be pulled back silently at every
    step.  ``account`` (the check's :class:`~.constraint_check.ConsistencyAccount`) therefore
    accounts each step from the projected state of the step before to the state integrated,
    *before* this projection, and starts the next step from the projected one: the corrections
    that the velocity level does not explain add up in its ``unexplained`` sums, which the check
    judges as it judges a residual (``ConstraintCheck.check(..., projected=...)``)."""

    def __init__(self, model, problem, level, describe_rows):
        self.model, self.problem = model, problem
        self.positions = level == "position"
        self.describe_rows = describe_rows
        self.account = None
        self.projections = 0                 # steps whose state was changed

    def _account(self, t, gv=None):
        if self.account is not None:
            p = self.problem
            if gv is None:
                gv = self.model.velocity_constraints(t, p.R, p.r, p.prev, p.qv)
            self.account.step(t, gv, self.model._vmax)

    def __call__(self, t):
        """Project the state integrated to ``t`` (written into mbs here); returns whether it changed
        (written again then)."""
        model, problem = self.model, self.problem
        problem.write()
        if len(model.multiplierRows):
            model.aeCur[model.multiplierRows] = 0.0   # lam = 0, as Exudyn's Newton makes them (its residual)
        R, r, prev = problem.R, problem.r, problem.prev
        gv = model.velocity_constraints(t, R, r, prev, problem.qv)
        self._account(t, gv)
        changed = False
        MC = None
        if self.positions:
            g = model.position_residual(t)
            gmax = max_abs(g)
            # (the scale is at least 1: below PROJECT_ABOVE no scale is needed to tell)
            scale = position_scale(model, problem) if gmax > PROJECT_ABOVE else 1.0
            if gmax > PROJECT_ABOVE * scale:
                tol = PROJ_TOL * scale
                g, MC = project_positions(model, problem, t, tol, metric(model, t))
                changed = True
                if max_abs(g) > PROJ_FAIL * tol:
                    bad = np.nonzero(np.abs(g) > PROJ_FAIL * tol)[0]
                    raise ConstraintError(
                        f"position projection did not converge in {PROJ_MAX_ITER} iterations at t = {t:.6g} s (max "
                        f"|h| = {max_abs(g):.3g}); the constraints of {self.describe_rows(bad)} may not be "
                        f"satisfiable")
                gv = model.velocity_constraints(t, R, r, prev, problem.qv)
        # the velocities with the metric of the positions' last step (C_q there differs from the state's by
        # that step's correction); a second pass with the state's own where that leaves them above the trigger
        for _ in range(2):
            gv = gv.copy()                   # (the account holds the one it was given)
            gv[model.multiplierRows] = 0.0
            gvmax = max_abs(gv)
            if not (gvmax > PROJECT_ABOVE and gvmax > PROJECT_ABOVE * max(1.0, max_abs(model.qt))):
                break
            project_velocities(model, problem, t, gv, MC)
            changed = True
            MC = None
            gv = model.velocity_constraints(t, R, r, prev, problem.qv)
        if changed:
            self.projections += 1
            if problem.sim.adaptiveRun is not None:
                problem.sim.adaptiveRun.drop_fsal()      # (the last stage is not this state's)
            self._account(t, gv)             # (the same t: the next step starts from the projected state)
        return changed
