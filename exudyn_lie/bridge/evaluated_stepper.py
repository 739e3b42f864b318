"""The Munthe-Kaas step of the Exudyn-evaluated path: a compact Python stage loop over the
same :class:`~exudyn_lie.integrators.tableau.ButcherTableau` (only the stages that can
change a step, ``stepper.needed_stages``) whose per-stage work is two compiled calls
(:mod:`.evaluated_kernels`: the stage state with the compiled kernel's own group maps, and
the stage rates with ``k_j = dexp^-1_{-Psi_j} V_j``) around Exudyn's evaluation
(:class:`~.evaluated.EvaluatedModel`).

Why not the compiled stepper's external seam (``mbs/external.py``): that seam lets Python add
*forces* to bodies the kernel knows; here Exudyn supplies the whole ``Vdot`` of coordinates
the kernel does not know (ANCF, ODE1, GenericODE2, ...) and the multipliers.  A mode of
``stage_rhs`` that returns a whole ``Vdot`` would need the kernel's state, work and output
arrays for vector-space coordinates as well; the stage loop here reuses the kernel's stage
functions instead and costs one Python iteration per stage, small beside Exudyn's
evaluation (a few microseconds against tens).

State: ``R, r, V`` of the Lie group nodes (group velocities as the compiled kernel: SE3 the
body twist ``(omega, R^T rdot)``, SO3xR3 ``(omega, rdot)``), ``qv, vv`` the vector-space ODE2
coordinates and velocities, ``y`` the ODE1 coordinates (same tableau, vector space).
"""
from __future__ import annotations

import numpy as np

from ..errors import StepSizeError
from ..mbs.codes import STAGE_ARG_MAX
from ..mbs.stepper import method_arrays
from .evaluated_kernels import lg_finish, lg_stage, lg_stage_rates, stiffness_estimate

BLOWUP = 1e12        # a velocity beyond BLOWUP x max(1, initial velocity scale) is a blow-up
STIFF_STEPS = 3      # h rho beyond the stability radius in this many consecutive steps: StepSizeError
STIFF_FACTOR = 10.0  # ... or beyond this multiple of it in one step (a stiff contact lasts a step or two)


class EvaluatedStepper:
    """Fixed Munthe-Kaas steps of an :class:`~.evaluated.EvaluatedModel`."""

    def __init__(self, model, tableau):
        self.model = model
        self.tableau = tableau
        meth = method_arrays(tableau)
        self.A, self.b, self.c, self.stages = meth.A, meth.b, meth.c, meth.stages
        L = model.L
        s = len(self.b)
        nl, nv, n1 = len(L.lgNodes), len(L.vecIdx), L.nODE1
        self.gid = L.gid
        self.R = np.zeros((nl, 3, 3))
        self.r = np.zeros((nl, 3))
        self.V = np.zeros((nl, 6))
        self.prev = np.zeros((nl, 3))          # rotation vectors last written (continuity)
        self.qv = np.zeros(nv)
        self.vv = np.zeros(nv)
        self.y = np.zeros(n1)
        self.K = np.zeros((s, nl, 6))
        self.Vd = np.zeros((s, nl, 6))
        self.Psi = np.zeros((nl, 6))
        self.Rs = np.zeros((nl, 3, 3))
        self.rs = np.zeros((nl, 3))
        self.Vs = np.zeros((nl, 6))
        self.QK = np.zeros((s, nv))
        self.VK = np.zeros((s, nv))
        self.qs = np.zeros(nv)
        self.vs = np.zeros(nv)
        self.YK = np.zeros((s, n1))
        self.ys = np.zeros(n1)
        self.m3 = np.zeros((2, 3, 3))
        self.v3 = np.zeros((2, 3))
        self.tmp6 = np.zeros(6)
        self.vscale = 1.0
        self.t = 0.0
        from ..integrators.stability import stability_radius
        self._radius = stability_radius(tableau)
        self._lastStage = int(self.stages[-1])
        self._stiffCount = 0
        # what a step uses, unpacked once (the stage loop is Python)
        self._stageList = [(int(j), float(self.c[j])) for j in self.stages]
        self._hot = (self.gid, self.A, self.R, self.r, self.V, self.K, self.Vd, self.Psi, self.Rs, self.rs, self.Vs,
                     self.m3[0], self.v3[0], self.qv, self.vv, self.QK, self.VK, self.qs, self.vs, L.lgIdx, L.vecIdx,
                     self.tmp6)

    # ------------------------------------------------------------------ state
    def read_state(self, q, qt, y=None, t=None):
        """The state from Exudyn's coordinates (Current): ``R = exp(ref + rotation vector)``."""
        from ..groups import so3
        L = self.model.L
        for i in range(len(L.lgNodes)):
            idx, ref = L.lgIdx[i], L.lgRef[i]
            rv = ref[3:] + q[idx[3:]]
            R = so3.exp(np.ascontiguousarray(rv))
            U, _, Wt = np.linalg.svd(R)
            self.R[i] = U @ Wt
            self.r[i] = ref[:3] + q[idx[:3]]
            self.prev[i] = rv
            om, v = qt[idx[3:]], qt[idx[:3]]
            self.V[i, :3] = om
            from ..mbs.codes import BODY_TWIST
            self.V[i, 3:] = self.R[i].T @ v if BODY_TWIST[self.gid[i]] else v
        self.qv[:] = q[L.vecIdx]
        self.vv[:] = qt[L.vecIdx]
        if y is not None and len(self.y):
            self.y[:] = y
        if t is not None:
            self.t = float(t)
        self.vscale = max(1.0, float(np.max(np.abs(qt))) if len(qt) else 0.0)

    def snapshot(self):
        return (self.R.copy(), self.r.copy(), self.V.copy(), self.prev.copy(), self.qv.copy(), self.vv.copy(),
                self.y.copy(), self.t)

    def restore(self, snap):
        R, r, V, prev, qv, vv, y, t = snap
        self.R[:], self.r[:], self.V[:], self.prev[:] = R, r, V, prev
        self.qv[:], self.vv[:], self.y[:] = qv, vv, y
        self.t = t

    def write(self):
        """Write the state into mbs (Current) and remember the rotation vectors written."""
        m = self.model
        m.write_state(self.R, self.r, self.V, self.prev, self.qv, self.vv)
        self.prev[:] = m._rv
        if len(self.y):
            m.write_ode1(self.y)

    # ------------------------------------------------------------------ one step
    def step(self, h):
        """One MK step of size h (eq. MK1) from ``self.t``; raises StepSizeError for a stage
        argument out of dexp^-1's domain or a non-finite / exploding state.  (Kept lean:
        per stage two compiled calls around Exudyn's evaluation.)"""
        model = self.model
        gid, A, R, r, V, K, Vd, Psi, Rs, rs, Vs, ER, Er, qv, vv, QK, VK, qs, vs, lgIdx, vecIdx, tmp6 = self._hot
        t = self.t
        n1 = len(self.y)
        write, accelerations, prev = model.write_state, model.accelerations, self.prev
        for j, cj in self._stageList:
            bad = lg_stage(gid, A, j, h, R, r, V, K, Vd, Psi, Rs, rs, Vs, ER, Er, qv, vv, QK, VK, qs, vs)
            if bad >= 0:
                self._raise_stage_arg(bad, h)
            write(Rs, rs, Vs, prev, qs, vs)
            if n1:
                model.write_ode1(self.y + h * (A[j, :j] @ self.YK[:j]))
            acc = accelerations(t + cj * h, Rs, rs, prev, qs)
            lg_stage_rates(gid, j, Rs, Vs, acc, lgIdx, Psi, K, Vd, tmp6, vecIdx, vs, QK, VK)
            if n1:
                self.YK[j] = model.ydot
        st = lg_finish(gid, self.stages, self.b, h, R, r, V, K, Vd, Psi, self.m3[1], self.m3[0], self.v3[1],
                       self.v3[0], qv, vv, QK, VK, BLOWUP * self.vscale)
        if n1:
            self.y += h * (self.b[self.stages] @ self.YK[self.stages])
            if not np.all(np.isfinite(self.y)):
                st = 1
        self.t = t + h
        if st:
            self._raise_blowup(h, "non-finite (NaN/inf)" if st == 1 else "unbounded (blow-up)")
        # a mode that became stiff during the run (a contact that closed, a friction zone):
        # Shampine's estimate from the stages, the tableau's stability radius
        rho = stiffness_estimate(A, h, self._lastStage, K, Vd, QK, VK)
        if h * rho > self._radius:
            self._stiffCount += 1
            if self._stiffCount >= STIFF_STEPS or h * rho > STIFF_FACTOR * self._radius:
                self._raise_stiff(h, rho)
        else:
            self._stiffCount = 0

    def _raise_stage_arg(self, i, h):
        psi = float(np.linalg.norm(self.Psi[i, :3]))
        node = self.model.L.lgNodes[i]
        sugg = h * np.pi / psi if psi > 0 else h / 10
        raise StepSizeError(f"the rotation of node {node} (NodeRigidBodyRotVecLG) in an MK stage, |Psi| = {psi:.4g} "
                            f"rad, is beyond {STAGE_ARG_MAX:.4g} (dexp^-1 of the stage equation is singular at 2 pi) "
                            f"at t = {self.t:.6g} s with step size {h:.3g} s (method {self.tableau.name}); try a "
                            f"step size of {sugg:.3g} s or smaller")

    def _raise_stiff(self, h, rho):
        raise StepSizeError(f"the step size {h:.3g} s is beyond the stability limit of {self.tableau.name} at t = "
                            f"{self.t:.6g} s: the stages of the last step(s) show a mode of rate "
                            f"|lambda| ~ {rho:.4g} 1/s (Shampine's estimate from the stages; e.g. a contact or a "
                            f"friction zone that became active), h |lambda| = {h * rho:.3g} > {self._radius:.3g} "
                            f"(the method's stability radius); the state is not reliable: try a step size of "
                            f"{0.9 * self._radius / rho:.3g} s or smaller")

    def _raise_blowup(self, h, what):
        from .evaluated_stiffness import suggest_step
        t = self.t
        sugg = suggest_step(self, h)           # (restores the state the Exudyn step started from)
        raise StepSizeError(f"the state became {what} at t = {t:.6g} s with step size {h:.3g} s (method "
                            f"{self.tableau.name}, Exudyn-evaluated model); the step is beyond the stability "
                            f"limit: try a step size of {sugg:.3g} s or smaller")
