"""The Exudyn-evaluated model as a problem of the one compiled stepper.

:class:`EvaluatedProblem` gives, for a state of bodies on their groups, the rates ``Vdot`` of
every body from Exudyn's evaluation of the whole model (:class:`~.evaluated.EvaluatedModel`:
M, f, C_q, eta and the index-1 solve).  It is the scene's right-hand side
(``Scene.SetRightHandSide``), so :class:`~exudyn_lie.mbs.Simulator` integrates it with the
same ``mk_steps`` as a compiled scene: fixed and adaptive steps, the stage-argument and
blow-up checks, the step suggestions.  One stage is one call from the compiled stepper into
:meth:`EvaluatedProblem.bind`'s function: a compiled unpacking of the stage state into
Exudyn's coordinates, Exudyn's evaluation, a compiled packing of the accelerations.

The bodies of the problem:

* one per ``NodeRigidBodyRotVecLG`` node, on SE3 or SO3xR3 (the kernel's velocity: SE3 the
  body twist ``(omega, R^T rdot)``, SO3xR3 ``(omega, rdot)``);
* the vector-space ODE2 coordinates (every other node: ``qdot = v``), three per body on R3
  (position ``r``, velocity ``V[3:6]``; ``R3`` is a vector space, so the Munthe-Kaas method
  is the underlying Runge-Kutta method there);
* the ODE1 coordinates ``y``, three per body on R3 as its velocity ``V[3:6]`` with the rate
  ``ydot`` (the body's position integrates ``y`` and is not used).
"""
from __future__ import annotations

import numpy as np

from ..groups import so3
from ..mbs.codes import BODY_TWIST, GROUP_NAMES
from ..mbs.rotation_parameters import rotvec_quat
from ..mbs.scene import Scene
from ..mbs.simulator import Simulator
from ..mbs.stiffness import StageStiffnessWatch, watch_stages
from .evaluated_jacobian import ExudynNewtonJacobian, applies as jacobian_applies
from .evaluated_kernels import pack_rates, pack_state, unpack_state
from .evaluated_stiffness import ode1_rate

ODE1_CHECK_EVALUATIONS = 16      # evaluations of the ODE1 right-hand side per step for its watch, at most



class EvaluatedScene(Scene):
    """The problem's bodies, named after Exudyn's nodes and coordinates in errors."""

    def __init__(self, names):
        super().__init__()
        self.names = names

    def describe_body(self, i):
        return self.names[i]


class EvaluatedProblem:
    """An :class:`~.evaluated.EvaluatedModel` integrated by a :class:`Simulator` with ``tableau``."""

    def __init__(self, model, tableau):
        self.model = model
        L = model.L
        self.gid = L.gid
        nl, nv, n1 = len(L.lgNodes), len(L.vecIdx), L.nODE1
        self.nl, self.nv, self.n1 = nl, nv, n1
        self.nvb, self.n1b = -(-nv // 3), -(-n1 // 3)
        names = [f"node {n} (NodeRigidBodyRotVecLG)" for n in L.lgNodes]
        names += [f"ODE2 coordinates {list(L.vecIdx[3 * b:3 * b + 3])}" for b in range(self.nvb)]
        names += [f"ODE1 coordinates {list(range(3 * b, min(3 * b + 3, n1)))}" for b in range(self.n1b)]
        sc = EvaluatedScene(names)
        for name in names[:nl]:
            sc.AddBody(1.0, np.eye(3), name=name)
        for name in names[nl:]:
            sc.AddPointMass(1.0, name=name)
        sc.SetRightHandSide(self)
        # the quaternions of the rotation vectors last written (their continuity, evaluated_kernels)
        self.prev = np.zeros((nl, 4))
        self.prev[:, 0] = 1.0
        self._qv, self._vv, self._y = np.zeros(nv), np.zeros(nv), np.zeros(n1)
        self.sim = Simulator(sc, tableau, [GROUP_NAMES[g] for g in L.gid] + ["R3"] * (self.nvb + self.n1b))
        self.tableau = self.sim.tableau
        self.stages = self.sim.method.stages
        self._stiffness = StageStiffnessWatch(self.tableau)
        self._strict = False
        self._ode1Steps, self._ode1Last, self._ode1H = 0, 0.0, None
        self._jacobian_for_method()

    def watch_stiffness(self, strict):
        """A fixed step beyond the explicit method's stability radius (by its stages) fails at once
        (``strict``, for a caller that repeats it with the implicit method: mbs/stiffness.watch_stages),
        or after a few such steps (StageStiffnessWatch)."""
        self._strict = bool(strict)
        watch_stages(self.sim, self._strict, self.nl + self.nvb)

    def set_method(self, tableau):
        """Integrate with ``tableau`` from now on (bridge/method_choice.py)."""
        self.sim.SetMethod(tableau)
        self.tableau = self.sim.tableau
        self.stages = self.sim.method.stages
        self._stiffness = StageStiffnessWatch(self.tableau)
        watch_stages(self.sim, self._strict, self.nl + self.nvb)
        self._jacobian_for_method()

    def _jacobian_for_method(self):
        """An implicit method's Newton Jacobian from Exudyn's Jacobians where that applies
        (bridge/evaluated_jacobian.py), else the kernel's differences."""
        self.jacobian = (ExudynNewtonJacobian(self.model, self)
                         if self.tableau.implicit and jacobian_applies(self.model) else None)

    def _ode1_rate(self):
        """The ODE1 coordinates' fastest rate for the stability radius, at the state last evaluated
        in mbs (the last stage's, or the step's end after the stepper's end-state check;
        evaluated_stiffness.ode1_rate: n1 + 1 evaluations of Exudyn's ODE1 right-hand side and the
        eigenvalues of an n1 x n1 matrix), after every Exudyn step, or every
        ``ceil((n1 + 1) / ODE1_CHECK_EVALUATIONS)``-th one for many ODE1 coordinates (the evaluations
        per step bounded; a stiff mode is then seen up to that many steps late; in between, the last
        rate; measured again after a step size change or a step done again).  The stages' estimate
        reads the ODE2 bodies only: a first-order estimate over the ODE1 bodies (|d ydot| / |d y|
        between stages) was tried and saw the coupling as stiffness where ODE1 rates follow the
        mechanical state (a hydraulic actuator's pressure, tests/test_foreign_items.py); d(ydot)/dy
        at a fixed mechanical state does not."""
        fresh = self._ode1Steps % -(-(self.n1 + 1) // ODE1_CHECK_EVALUATIONS) == 0 or self._ode1H != self._h
        self._ode1Steps += 1
        if fresh:
            self._ode1Last = ode1_rate(self.model, self.tableau, self._h, self._stiffness.radius)
            self._ode1H = self._h
        return self._ode1Last

    # ------------------------------------------------------------------ the right-hand side
    def bind(self, Rs, rs, Vs, Vdot):
        """The stage function ``f(t)`` on the stepper's stage state ``Rs, rs, Vs``, writing
        ``Vdot`` (Scene.SetRightHandSide)."""
        model, L = self.model, self.model.L
        gid, lgIdx, lgRef, vecIdx = L.gid, L.lgIdx, L.lgRef, L.vecIdx
        nl, nvb, n1 = self.nl, self.nvb, self.n1
        q, qt, prev, rv, rq = model.q, model.qt, self.prev, model._rv, model._rq
        qs, vs, ys = np.zeros(self.nv), np.zeros(self.nv), np.zeros(n1)
        RsL, rsL = Rs[:nl], rs[:nl]
        accelerations, write_ode1, ydot = model.accelerations, model.write_ode1, model.ydot

        def stage(t):
            model._vmax = unpack_state(gid, Rs, rs, Vs, nvb, lgIdx, lgRef, prev, q, qt, vecIdx, qs, vs, ys, rv, rq)
            if n1:
                write_ode1(ys)
            acc = accelerations(t, RsL, rsL, prev, qs)
            pack_rates(gid, Rs, Vs, acc, lgIdx, vecIdx, ydot, nvb, Vdot)
        return stage

    # ------------------------------------------------------------------ state
    @property
    def t(self):
        return self.sim.t

    @property
    def R(self):
        """The Lie group nodes' rotations (a view of the simulator's state)."""
        return self.sim.R[:self.nl]

    @property
    def r(self):
        return self.sim.r[:self.nl]

    @property
    def V(self):
        return self.sim.V[:self.nl]

    @property
    def qv(self):
        """The vector-space ODE2 coordinates (a writable view of the simulator's state)."""
        return self.sim.r[self.nl:self.nl + self.nvb].reshape(-1)[:self.nv]

    @qv.setter
    def qv(self, value):
        self.sim.r[self.nl:self.nl + self.nvb].reshape(-1)[:self.nv] = value

    def set_vector_velocities(self, vv):
        flat = np.zeros(3 * self.nvb)
        flat[:self.nv] = vv
        self.sim.V[self.nl:self.nl + self.nvb, 3:] = flat.reshape(-1, 3)

    def read_state(self, q, qt, y=None, t=None):
        """The state from Exudyn's coordinates (Current): ``R = exp(ref + rotation vector)``."""
        L = self.model.L
        nl = self.nl
        Rl, rl, Vl = np.zeros((nl, 3, 3)), np.zeros((nl, 3)), np.zeros((nl, 6))
        for i in range(nl):
            idx, ref = L.lgIdx[i], L.lgRef[i]
            rv = ref[3:] + q[idx[3:]]
            U, _, Wt = np.linalg.svd(so3.exp(np.ascontiguousarray(rv)))
            Rl[i] = U @ Wt
            rl[i] = ref[:3] + q[idx[:3]]
            rotvec_quat(rv, self.prev[i])
            Vl[i, :3] = qt[idx[3:]]
            v = qt[idx[:3]]
            Vl[i, 3:] = Rl[i].T @ v if BODY_TWIST[self.gid[i]] else v
        if y is not None and self.n1:
            self._y[:] = y
        sim = self.sim
        pack_state(self.gid, Rl, rl, Vl, np.ascontiguousarray(q[L.vecIdx]), np.ascontiguousarray(qt[L.vecIdx]),
                   self._y, self.nvb, sim.R, sim.r, sim.V)
        if t is not None:
            sim.t = float(t)
        sim.RestartAdaptive()              # a new state: a new first step

    def snapshot(self):
        sim = self.sim
        return sim.R.copy(), sim.r.copy(), sim.V.copy(), self.prev.copy(), sim.t

    def restore(self, snap):
        sim = self.sim
        R, r, V, prev, t = snap
        sim.R[:], sim.r[:], sim.V[:], self.prev[:] = R, r, V, prev
        sim.t = t
        sim.RestartAdaptive()
        self._ode1Steps = 0                  # (the step done again: its ODE1 rate measured again)

    def write(self):
        """Write the state into mbs (Current) and remember the quaternions of the rotation vectors written."""
        m, sim = self.model, self.sim
        L = m.L
        m._vmax = unpack_state(self.gid, sim.R, sim.r, sim.V, self.nvb, L.lgIdx, L.lgRef, self.prev, m.q, m.qt,
                               L.vecIdx, self._qv, self._vv, self._y, m._rv, m._rq)
        self.prev[:] = m._rq
        if self.n1:
            m.write_ode1(self._y)

    # ------------------------------------------------------------------ steps
    def advance(self, t0, t1, nsteps, h, adaptive):
        """From ``t0`` to ``t1``: ``nsteps`` fixed steps of ``h``, or adaptive steps (the
        simulator's SetAdaptive) whose last one ends at ``t1``.  Raises StepSizeError as the
        compiled path (the stepper's checks), and for fixed steps when the stages of the
        last steps show a mode beyond the method's stability radius (:class:`~exudyn_lie.mbs.stiffness.StageStiffnessWatch`)."""
        sim = self.sim
        sim.t = t0
        if self.jacobian is not None:
            self.jacobian.before_steps(sim, t0)
        if adaptive:
            sim.AdvanceTo(t1)
        else:
            sim.Advance(nsteps, h)
            self._h = h
            # (the last of the nsteps steps; the ODE2 bodies, and the ODE1 coordinates' own modes)
            self._stiffness.check(sim, h, self.nl + self.nvb, self._ode1_rate if self.n1 else None, self._strict)
        sim.t = t1
