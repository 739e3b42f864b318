"""The implicit methods' Newton Jacobian on the Exudyn-evaluated path from Exudyn's own Jacobians.

The simplified Newton iteration of an implicit stage (``mbs/implicit.py``) needs ``D_Theta =
dVdot/dTheta`` and ``D_V = dVdot/dV`` at the step's start.  The kernel forms them by forward
differences of the stage right-hand side, two evaluations per coordinate: on this path each is an
evaluation by Exudyn (M, f, C_q, eta), 2n per Jacobian.  For a model of vector-space coordinates only (no
``NodeRigidBodyRotVecLG``, whose group coordinates would need the tangent maps, and no ODE1
coordinates), they follow from Exudyn's own Jacobians in one pass: with ``qdot = v`` and
``[M C_q^T; C_q 0][a; lam] = [f; eta]`` (eq. index1),

    da = P (K dq + D dv),   K = df/dq, D = df/dv (``ComputeJacobianODE2RHS``, loads included),
    P = M^-1 - M^-1 C_q^T (C_q M^-1 C_q^T)^-1 C_q M^-1,

so ``D_Theta = P K`` and ``D_V = P D`` on the coordinates (``Theta`` of a vector coordinate is its
increment).  The derivatives of M, of ``C_q^T lam`` and of eta are left out: the Newton matrix of a
simplified Newton iteration may be approximate, the iteration still converges to the stage's exact
solution, and a stage that does not converge with this Jacobian is solved again with the kernel's
difference Jacobian of its own step (``implicit.solve_stage``).  Not with a GeneralContact: its
Jacobian is that of the active-set law (bridge/general_contact.py), which this path does not
evaluate.
"""
from __future__ import annotations

import numpy as np

from ..mbs.implicit import NS_FRESH, NS_H, NS_JACOBIANS, NS_STALE, newton_band
from .general_contact import general_contacts


def applies(model):
    """Whether :class:`ExudynNewtonJacobian` serves this model (module docstring)."""
    return len(model.L.lgNodes) == 0 and model.n1 == 0 and model.n > 0 and not general_contacts(model.mbs)


#: a Jacobian at every step up to this many coordinates (else when the kernel asks for one): the
#: iteration then contracts faster (the Jacobian of the step's own start) and fewer stages need the
#: kernel's difference Jacobian of 2n evaluations (the ANCF cable of ``bench --sections stiff``, 39
#: coordinates, h = 1e-3, T = 0.1 s: ``pytest -s tests/test_evaluated_jacobian.py`` prints the
#: evaluations by Exudyn with this Jacobian and with differences only).  Its dense products grow
#: with n^3, the difference Jacobian with n times a stage; a size, not a timing, so that a run does
#: not depend on the machine's load
EVERY_STEP_MAX_COORDINATES = 300


class ExudynNewtonJacobian:
    """Fills the Newton arrays' ``Dth``, ``Dv`` of an :class:`~.evaluated_problem.EvaluatedProblem`
    from Exudyn's Jacobians at the simulator's state (module docstring)."""

    def __init__(self, model, problem):
        self.model, self.problem = model, problem
        vec = np.asarray(model.L.vecIdx, np.int64)
        c = np.arange(len(vec))
        # the coordinate vec[c] is axis 3 + c % 3 of the simulator's point body c // 3 (after no LG nodes)
        self.cols = (6 * (c // 3) + 3 + c % 3).astype(np.int64)
        self.vec = vec
        self.evaluations = 0
        self.everyStep = len(vec) <= EVERY_STEP_MAX_COORDINATES

    @staticmethod
    def _projector(M, Cq):
        """P, the upper left block of the inverse of [M C_q^T; C_q 0] (M may be singular where the
        rows fix its coordinates, as the index-1 solve allows); None if that matrix is singular."""
        M = np.asarray(M, float)
        n = M.shape[0]
        C = np.zeros((0, n)) if Cq is None else np.asarray(Cq, float)
        C = C[np.any(C != 0.0, axis=1)]
        m = C.shape[0]
        K = np.zeros((n + m, n + m))
        K[:n, :n] = M
        K[:n, n:] = C.T
        K[n:, :n] = C
        rhs = np.zeros((n + m, n))
        rhs[:n] = np.eye(n)
        try:
            return np.linalg.solve(K, rhs)[:n]
        except np.linalg.LinAlgError:            # redundant rows, or a coordinate that nothing holds
            return None

    def fill(self, newton, t):
        """``newton.Dth``, ``newton.Dv`` at the simulator's state and time ``t``; marks the Jacobian as
        current (the kernel refactors the Newton matrix at its next stage)."""
        m, p = self.model, self.problem
        p.write()
        M, _, Cq = m.mass_force_jacobian(t)
        P = self._projector(M, Cq)
        if P is None:
            self.everyStep = False                 # (still stale: the kernel's differences; not
            return                                 #  tried again at every step)
        K, D = m.force_jacobians(t)
        Aq = P @ K
        Av = P @ D
        v, cols = self.vec, self.cols
        ix = np.ix_(cols, cols)
        newton.Dth[:] = 0.0
        newton.Dv[:] = 0.0
        newton.Dth[ix] = Aq[np.ix_(v, v)]
        newton.Dv[ix] = Av[np.ix_(v, v)]
        newton_band(newton, newton.Dv.shape[0])
        st = newton.st
        st[NS_STALE] = 0.0
        st[NS_H] = 0.0                         # a new matrix: factored at the next stage
        st[NS_FRESH] = 0.0                     # (not the kernel's own: a failing stage gets that one)
        st[NS_JACOBIANS] += 1.0
        self.evaluations += 1

    def before_steps(self, sim, t):
        """Before the simulator's steps from ``t``: Exudyn's Jacobian if the kernel asks for a new one."""
        for method in (sim.method, getattr(getattr(sim, "_ad", None), "method", None)):
            nw = getattr(method, "newton", None)
            if nw is not None and (nw.st[NS_STALE] != 0.0 or self.everyStep):
                self.fill(nw, t)
