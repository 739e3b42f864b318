"""The Exudyn-evaluated model: Exudyn computes the whole right-hand side of the index-1
equations (M, f, C_q and the velocity-level constraints) through the
``MainSolverImplicitSecondOrder`` interface, for any item Exudyn can evaluate.

Why the *whole* model (the design question): an item the kernel does not compile
(an ANCF cable, a contact, a GenericODE2 system) couples to the rigid bodies through
markers whose kinematics, Jacobians and reaction forces Exudyn computes in its own
coordinates.  Evaluating everything in Exudyn couples every item with every other exactly
as Exudyn does, and keeps one bookkeeping of coordinates, markers and parameters (no
splitting of M, f, C_q between two evaluators, no translation of Exudyn's velocity
coordinates into the kernel's for half of the model).  The price is Exudyn's interface:
dense copies of M and of the system Jacobian per stage (measured in the README's section
"Which path a model takes and what it costs").

Coordinate layout (:class:`Layout`): Exudyn's ODE2 coordinates ``q``, velocities ``v``, ODE1
coordinates ``y``; data coordinates are frozen during a step (updated by Exudyn's
PostNewton after it).  ``NodeRigidBodyRotVecLG`` nodes are Lie group elements ``(R, r)`` on
SE3 or SO3xR3 (:mod:`.evaluated_kernels`); every other ODE2 coordinate lives in vector
space (``qdot = v``).

One evaluation at a stage state (:meth:`EvaluatedModel.accelerations`):

1. the state is written into mbs' Current coordinates (zero-copy views) and the time into
   ``mbs.systemData`` (``SetTime``: what Exudyn's own explicit solvers set per stage, so
   user functions and time-dependent items see the stage time);
2. ``ComputeMassMatrix``, ``ComputeODE2RHS`` (f with ``M a = f``), ``ComputeJacobianAE`` into a
   zeroed system Jacobian (it *adds*), ``ComputeODE1RHS``;
3. ``eta = -d/dt g_v(q(t), v, t)`` at fixed velocities (:meth:`EvaluatedModel.eta`): Exudyn has
   no access to ``Cdot_q v``, so it is the central difference of the velocity-level
   constraints ``ComputeAlgebraicEquations(velocityLevel=True)`` (= ``C_q v + C_t``) along the
   motion, ``(g_v(q exp(+eps V), t + eps) - g_v(q exp(-eps V), t - eps)) / (2 eps)``;
4. ``[M C_q^T; C_q 0][a; lam] = [f; eta]`` with M block diagonal (blocks found once from
   the pattern of M and the nodes' coordinates) and the Schur complement
   (:class:`~exudyn_lie.mbs.block_kkt.BlockKKT`, the kernel's factorisations); a singular
   block of M falls back to the whole KKT matrix.

The step of the central difference (the rule): ``eps = cbrt(eps_mach) * tau`` with the time
scale ``tau = 1 / max(1 1/s, max|v|)`` (v: Exudyn's velocity coordinates in SI units per
second), so that the configuration moves by at most ``cbrt(eps_mach) ~ 6e-6`` (m or rad) and
the truncation error ``eps^2 |g_v'''| / 6`` balances the rounding error
``eps_mach |g_v| / eps``: about ``eps_mach^(2/3) ~ 4e-11`` relative.  :meth:`eta_error`
estimates it: Richardson's comparison of ``eps`` and ``2 eps`` for the truncation (error of
the eps-result ~ |eta(2 eps) - eta(eps)| / 3) plus the rounding bound.  Measured against the
compiled kernel's exact eta at random states of random mechanisms (tests/test_evaluated.py):
below 2e-10 relative; the trajectories of the paper's models differ by at most 1.4e-10.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConstraintError, SimulationError
from ..mbs.block_kkt import BlockKKT
from ..mbs.row_drives import offset_and_derivatives
from .evaluated_items import (LIE_GROUP_NODES, coordinate_constraint_rows, ep_node_rows, multiplier_rows, node_rows,
                              position_derived_rows, refuse_oblique_coordinate_row)
from .evaluated_kernels import euler_parameter_eta, write_exudyn_state, write_moved_positions
from .evaluated_sliding import SlidingCoordinates, sliding_joints
from .reader import BridgeError, mbs_user_function

EPS_CBRT = float(np.finfo(float).eps) ** (1.0 / 3.0)
EPS_SIXTH = float(np.finfo(float).eps) ** (1.0 / 6.0)
class Layout:
    """Where every coordinate goes: Lie group nodes (index arrays into Exudyn's ODE2
    vector, reference coordinates, group), vector-space ODE2 coordinates, ODE1 and AE
    sizes; the block structure of M."""

    def __init__(self, mbs, nodeGroups):
        from ..mbs.codes import GROUP_NAMES
        sd = mbs.systemData
        self.nODE2 = int(sd.ODE2Size())
        self.nODE1 = int(sd.ODE1Size())
        self.nAE = int(sd.AEsize())
        self.nData = int(sd.DataSize())
        lgNodes, lgIdx, lgRef, gid = [], [], [], []
        inLG = np.zeros(self.nODE2, bool)
        for n in range(sd.NumberOfNodes()):
            d = mbs.GetNode(n)
            if d["nodeType"] in LIE_GROUP_NODES:
                idx = np.asarray(sd.GetNodeLTGODE2(n), np.int64)
                lgNodes.append(n)
                lgIdx.append(idx)
                lgRef.append(np.asarray(d["referenceCoordinates"], float).reshape(6))
                gid.append(GROUP_NAMES.index(nodeGroups.get(n, "SE3")))
                inLG[idx] = True
        self.lgNodes = lgNodes
        self.lgIdx = np.array(lgIdx, np.int64).reshape(-1, 6)
        self.lgRef = np.array(lgRef, float).reshape(-1, 6)
        self.gid = np.array(gid, np.int64)
        self.vecIdx = np.nonzero(~inLG)[0].astype(np.int64)
        self.nodeIdx = [np.asarray(sd.GetNodeLTGODE2(n), np.int64) for n in range(sd.NumberOfNodes())
                        if len(sd.GetNodeLTGODE2(n))]
        # Euler parameters of NodeRigidBodyEP nodes (coordinates 3..6 of the node) and their
        # reference values: the total parameters ref + q lie on the unit sphere
        ep = [n for n in range(sd.NumberOfNodes()) if mbs.GetNode(n)["nodeType"] == "RigidBodyEP"]
        self.epIdx = np.array([np.asarray(sd.GetNodeLTGODE2(n), np.int64)[3:7] for n in ep], np.int64).reshape(-1, 4)
        self.epRef = np.array([np.asarray(mbs.GetNode(n)["referenceCoordinates"], float)[3:7] for n in ep],
                              float).reshape(-1, 4)

    def blocks(self, M):
        """Connected components of the pattern of M joined with each node's coordinates:
        (blk, blkPtr) for :class:`~exudyn_lie.mbs.block_kkt.BlockKKT`."""
        n = self.nODE2
        parent = np.arange(n)

        def find(i):
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        def union(i, k):
            a, b = find(i), find(k)
            if a != b:
                parent[max(a, b)] = min(a, b)

        for idx in self.nodeIdx:
            for k in idx[1:]:
                union(idx[0], k)
        rows, cols = np.nonzero(M)
        for i, k in zip(rows, cols):
            if i != k:
                union(int(i), int(k))
        roots = np.array([find(i) for i in range(n)])
        order = np.argsort(roots, kind="stable")
        _, starts = np.unique(roots[order], return_index=True)
        ptr = np.append(starts, n).astype(np.int64)
        return order.astype(np.int64), ptr


def callable_user_function(mbs, name):
    """The Python function of the mbs' ``name`` (reader.mbs_user_function), or None without one; one
    this path cannot call raises BridgeError."""
    uf = mbs_user_function(mbs, name)
    if uf is None:
        return None
    f = uf.get("function") if isinstance(uf, dict) else uf
    if not callable(f):
        raise BridgeError(f"mbs' {name} is not a Python callable ({uf!r}); exudyn_lie calls it from Python; solve "
                          f"with exudyn.SolveDynamic")
    return f


def check_dense_size(n, nJacobian):
    """Exudyn's interface gives M (n x n) and the system Jacobian (nJacobian x nJacobian; 0: not
    needed, no constraints) as dense copies; refuse a model whose copies exceed half of the memory
    (a particle system of 150,000 coordinates: 168 GiB each) with a clear error instead of a
    MemoryError."""
    import os
    need = 8.0 * (n * n + 2 * nJacobian * nJacobian)
    try:
        have = float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return
    if need > 0.5 * have:
        what = "the mass matrix and the system Jacobian" if nJacobian else "the mass matrix"
        raise BridgeError(f"this model has {n} ODE2 coordinates: Exudyn evaluates it (items the compiled kernel does "
                          f"not have), and its interface copies {what} densely, {need / 2 ** 30:.3g} GiB, more than "
                          f"half of this machine's memory ({have / 2 ** 30:.3g} GiB); solve this model with "
                          f"exudyn.SolveDynamic")


class EvaluatedModel:
    """Exudyn's M, f, C_q and eta at a state of the Lie group / vector-space layout.

    ``solver`` is the initialised ``exudyn.MainSolverImplicitSecondOrder`` of the run;
    ``q``, ``qt`` are writable views of mbs' Current ODE2 coordinates and velocities."""

    def __init__(self, mbs, solver, layout: Layout, q, qt, verbose=False):
        self.mbs, self.solver, self.L = mbs, solver, layout
        self.q, self.qt = q, qt
        self.sd = mbs.systemData
        self.verbose = verbose
        n, m, n1 = layout.nODE2, layout.nAE, layout.nODE1
        self.n, self.m, self.n1 = n, m, n1
        self.nsys = n + n1 + m
        check_dense_size(n, self.nsys if m else 0)
        self._Z = np.zeros((self.nsys, self.nsys) if m else (0, 0))
        self.kkt = BlockKKT(n, m, layout.blocks, self._check_rows, verbose)
        self.a, self.lam = self.kkt.a, self.kkt.lam
        self.ydot = np.zeros(n1)
        self._ER = np.zeros((3, 3))
        self._rv = np.zeros((len(layout.lgNodes), 3))
        self._rq = np.zeros((len(layout.lgNodes), 4))
        self._qsave = np.zeros(n)
        self._eta0 = np.zeros(0)
        self._etaBuf = np.zeros(m)
        self._vmax = 0.0
        self.read_rows()
        self.evaluations = 0
        self.constantMass = False        # set by the solver (mass_force_jacobian)
        # bound methods, looked up once (the stage loop is Python)
        s = solver
        self._massMatrix, self._getM = s.ComputeMassMatrix, s.GetSystemMassMatrix
        self._ode2rhs, self._residual = s.ComputeODE2RHS, s.GetSystemResidual
        self._ode1rhs = s.ComputeODE1RHS
        self._setJ, self._jacAE, self._getJ = s.SetSystemJacobian, s.ComputeJacobianAE, s.GetSystemJacobian
        self._zeroJ = self._fastest_zeroing() if layout.nAE else None
        self._ae = s.ComputeAlgebraicEquations
        self._setTime = self.sd.SetTime
        self._preNewton = callable_user_function(mbs, "PreNewtonResidualUserFunction")
        self._jacobianUser = callable_user_function(mbs, "SystemJacobianUserFunction")
        import exudyn as exu
        self._cur = exu.ConfigurationType.Current
        self.aeCur = self.sd.GetAECoordinates(configuration=self._cur, copy=False) if m else np.zeros(0)

    def read_rows(self, changed=()):
        """What the rows need beyond Exudyn's evaluation, from the items as they are now (again
        when a user function changed the objects ``changed``: an offset function, a connector
        switched on or to velocity level; one switched on or to position level is checked again as
        evaluated_items.check_model checked every object at the start)."""
        mbs = self.mbs
        for o in changed:
            refuse_oblique_coordinate_row(mbs, int(o))
        self.velocityRows, functionRows = coordinate_constraint_rows(mbs)
        self.multiplierRows = multiplier_rows(mbs)
        # rows whose g_v and eta come from the position level (position_derived_rows)
        self.positionRows, self._allPosition = position_derived_rows(mbs)
        # an offset function's rate and acceleration are added to Exudyn's velocity level; the
        # position level's differences along the motion (t moves with it) hold them already
        P = set(self.positionRows.tolist())
        self._functionRows = [x for x in functionRows if x[0] not in P]
        self._paramRows = getattr(self, "_paramRows", [])
        self._movingRows = self._functionRows + self._paramRows
        self._velocityLevel = not self._allPosition
        # of those, the nodes' own rows: differentiated along the straight line in their
        # coordinates (_onto_unit_sphere says why the others are not)
        nr = np.isin(self.positionRows, node_rows(mbs))
        self._posObjectRows, self._posNodeRows = self.positionRows[~nr], self.positionRows[nr]
        # C_qdot of velocity-level rows: the ODE2_t factor (position-level rows have no ODE2_t part)
        self._factorODE2_t = 1.0 if len(self.velocityRows) else 0.0
        # AE unknowns that are coordinates (ObjectJointSliding2D's s: bridge/evaluated_sliding.py)
        joints = sliding_joints(mbs)
        if not hasattr(self, "sliding"):
            self.sliding = SlidingCoordinates(self, joints) if joints else None
        elif [j[0] for j in joints] != ([] if self.sliding is None else self.sliding.objects):
            raise BridgeError("an ObjectJointSliding2D was switched on or off during the run (activeConnector); "
                              "exudyn_lie takes its sliding coordinate from the positions only for the joints "
                              "active at the start; solve with exudyn.SolveDynamic")
        # rows of Euler parameters only: eta = -2 p_t . p_t (the derivative of 2 p . p_t along the motion)
        # without the two velocity-level evaluations by Exudyn of the differences
        self._epRows, self._epCoords = ep_node_rows(mbs)
        self._etaClosed = len(self._epRows) == self.m and not len(self.positionRows) and self.sliding is None

    # ------------------------------------------------------------------ state
    def write_state(self, R, r, V, prev, qv, vv):
        """Exudyn's Current q, v of the state (Lie group nodes and vector coordinates)."""
        L = self.L
        self._vmax = write_exudyn_state(L.gid, R, r, V, L.lgIdx, L.lgRef, prev, self.q, self.qt, L.vecIdx, qv, vv,
                                        self._rv, self._rq)

    def _fastest_zeroing(self):
        """How the system Jacobian is zeroed before ``ComputeJacobianAE`` (which adds into it):
        ``SetSystemJacobian(zeros)`` copies (n+m)^2 doubles in; ``ComputeJacobianODE2RHS`` with
        all factors 0 zeroes it in C++ (and adds zero times the bodies' own Jacobians to the
        ODE2 rows, which are not read: only the AE rows are).  The faster of the two, timed
        here once (for 50 rigid bodies: 112 us against 19 us)."""
        import time
        s, mbs, Z = self.solver, self.mbs, self._Z

        def by_copy():
            s.SetSystemJacobian(Z)

        def by_rhs_jacobian():
            s.ComputeJacobianODE2RHS(mbs, scalarFactor_ODE2=0.0, scalarFactor_ODE2_t=0.0, scalarFactor_ODE1=0.0)

        best = {}
        for f in (by_copy, by_rhs_jacobian):
            ts = []
            for _ in range(3):
                t0 = time.perf_counter()
                f()
                ts.append(time.perf_counter() - t0)
            best[f] = min(ts)
        return min(best, key=best.get)

    def write_ode1(self, y):
        """Exudyn's Current ODE1 coordinates."""
        self.sd.SetODE1Coordinates(y, configuration=self._cur)

    # ------------------------------------------------------------------ evaluations
    def mass_force_jacobian(self, t, forces=True):
        """(M, f, C_q) at the state in mbs (C_q rows of the AE equations; None without; f = 0 without
        ``forces``: the projections, bridge/evaluated_projection.py).  M is
        evaluated once when ``constantMass`` (Exudyn's ``reuseConstantMassMatrix`` on a system whose
        bodies all declare a constant one, evaluated_items.constant_mass_matrix): the dense copy of
        an n x n matrix per stage cost more than the rest of a stage for many bodies (particles);
        the returned M must not be changed."""
        self._setTime(t)
        mbs = self.mbs
        if self.sliding is not None:
            self.sliding.project(t, self.aeCur)
        M = self.kkt.constantM           # (the solve keeps the constant M and its blocks' inverses)
        if M is None:
            self._massMatrix(mbs)
            M = self._getM()
            if self.constantMass:
                self.kkt.constantM = M
        if forces:
            if self._preNewton is not None:
                # Exudyn calls it before each residual of its Newton iteration (a load that follows the
                # state, say); a stage evaluation is this path's residual.  newtonIt 0: no Newton here
                self._preNewton(mbs, t, 0, 0)
            self._ode2rhs(mbs)
            f = self._residual()[:self.n]
            if self.n1:
                self._ode1rhs(mbs)
                self.ydot[:] = self._residual()[self.n:self.n + self.n1]
        else:
            f = np.zeros(self.n)
        Cq = None
        if self.m:
            self._zeroJ()
            self._jacAE(mbs, scalarFactor_ODE2_t=self._factorODE2_t)
            J = self._getJ()
            Cq = J[self.n + self.n1:, :self.n]
            if self.n1 and np.any(J[self.n + self.n1:, self.n:self.n + self.n1]):
                raise BridgeError("a constraint acts on ODE1 coordinates; exudyn_lie's index-1 solve handles "
                                  "constraints on ODE2 coordinates only; solve with exudyn.SolveDynamic")
            self._lamlam = J[self.n + self.n1:, self.n + self.n1:]
            if self.sliding is not None:
                self._lamlam = self._lamlam.copy()
                self.sliding.velocities(J, self.qt)
                f = self.sliding.transform(Cq, f, self._lamlam)
        return M, f, Cq

    def force_jacobians(self, t):
        """``(K, D) = (df/dq, df/dv)`` on the ODE2 coordinates at the state in mbs (Exudyn's
        ``ComputeJacobianODE2RHS``, loads included), with the part of the mbs'
        SystemJacobianUserFunction, which Exudyn adds to its Newton Jacobian."""
        s, mbs, n = self.solver, self.mbs, self.n
        out = []
        for fq, fv, loads in ((1.0, 0.0, 1), (0.0, 1.0, 2)):
            s.ComputeJacobianODE2RHS(mbs, scalarFactor_ODE2=fq, scalarFactor_ODE2_t=fv, scalarFactor_ODE1=0.0,
                                     computeLoadsJacobian=loads)
            A = np.array(s.GetSystemJacobian()[:n, :n])
            if self._jacobianUser is not None:
                A += self._user_jacobian(t, fq, fv)
            out.append(A)
        return out[0], out[1]

    def _user_jacobian(self, t, factorODE2, factorODE2_t):
        """The mbs' SystemJacobianUserFunction's part of df/dq (factorODE2 = 1) or df/dv
        (factorODE2_t = 1) on the ODE2 coordinates (n x n, dense)."""
        mc = self._jacobianUser(self.mbs, t, factorODE2, factorODE2_t, 0.0)
        # its triplets, in system indices (Exudyn adds them to its sparse Newton Jacobian whatever the
        # container's declared size, which scripts leave smaller than the indices they use)
        T = np.asarray(mc.GetPythonObject()["triplets"], float).reshape(-1, 3)
        out = np.zeros((self.n, self.n))
        i, j = T[:, 0].astype(np.int64), T[:, 1].astype(np.int64)
        keep = (i < self.n) & (j < self.n)          # (the ODE2 block; ODE1 and AE rows are not this Jacobian's)
        np.add.at(out, (i[keep], j[keep]), T[keep, 2])
        return out

    def position_residual(self, t):
        """Exudyn's position-level residual at the state in mbs; a velocity-level row and a
        connector switched off have none (Exudyn returns its velocity equation, the multiplier,
        there): 0; the rows of sliding joints in the basis of bridge/evaluated_sliding.py."""
        self._setTime(t)
        if self.sliding is not None:
            self.sliding.project(t, self.aeCur)
        self._ae(self.mbs, False)
        g = self._residual()[self.n + self.n1:].copy()
        g[self.velocityRows] = 0.0
        g[self.multiplierRows] = 0.0
        return g if self.sliding is None else self.sliding.transform_rows(g)

    def ae_solution(self):
        """Exudyn's AE coordinates of the last solve: the multipliers (and the sliding joints'
        forces and coordinates)."""
        return self.lam if self.sliding is None else self.sliding.forces(self.lam, self.aeCur)

    def start_step(self):
        """A step starts: Exudyn's PostNewton after the last one (none before the first) added the
        sliding coordinates' increments to the joints' data nodes, so they start again from 0."""
        if self.sliding is not None:
            self.aeCur[self.sliding.slots] = 0.0

    def raw_residuals(self):
        """Exudyn's own position- and velocity-level AE residuals at the state and time in
        mbs (no corrections of moving offsets)."""
        o = self.n + self.n1
        self._ae(self.mbs, False)
        g = self._residual()[o:].copy()
        if not self._velocityLevel:
            raise BridgeError("an ObjectConnectorCoordinate offset moved by a user function and a GenericJoint with "
                              "offsetUserFunction_t in one model: Exudyn cannot evaluate the velocity level of this "
                              "model; remove offsetUserFunction_t or solve with exudyn.SolveDynamic")
        self._ae(self.mbs, True)
        return g, self._residual()[o:].copy()

    def set_parameter_offsets(self, moving):
        """The moving rows of offsets changed by user functions (bridge/moving_offsets.py)."""
        self._paramRows = moving
        self._movingRows = self._functionRows + moving

    def velocity_constraints(self, t, R=None, r=None, prev=None, qv=None):
        """``g_v(q, v, t)`` at the state in mbs: Exudyn's velocity-level AE residual, with the
        moving offsets' rates (coordinate_constraint_rows) and, for the position-derived rows
        (``R, r, prev, qv``: the state's Lie group and vector parts, needed for them), the
        central difference of the position level along the motion."""
        m = self.m
        if self.sliding is not None:
            self.sliding.refresh(t, self.aeCur, self.qt)
        if self._velocityLevel:
            self._setTime(t)
            self._ae(self.mbs, True)
            gv = self._residual()[self.n + self.n1:].copy()
        else:
            gv = np.zeros(m)
        if len(self.positionRows):
            if R is None:
                raise SimulationError("internal: velocity_constraints needs the state for position-derived rows")
            eps = EPS_CBRT / max(1.0, self._vmax)
            gp, _, gm = self._position_along_motion(t, R, r, prev, qv, eps, False, False)
            P = self.positionRows
            gv[P] = (gp[P] - gm[P]) * (0.5 / eps)
        for row, fn, label in self._movingRows:          # - cdot(t): coordinate_constraint_rows
            gv[row] -= offset_and_derivatives(fn, t, label)[1]
        return gv if self.sliding is None else self.sliding.transform_rows(gv)

    def _onto_unit_sphere(self, q):
        """Normalise the Euler parameters of EP nodes in ``q`` (Current = total - reference).

        The path along which the position-derived rows are differentiated must keep every
        node's own algebraic equation: Exudyn's C_q of an EP node acts through ``G(p)``, with
        ``G p = 0``, so it sees only the tangential part of an acceleration, and the normal
        part ``-|pdot|^2 p`` is fixed by the node's row ``|p|^2 = 1``.  On the straight line
        ``p + s pdot`` the second difference would add ``g_p (|pdot|^2 p)``, an acceleration
        the solve cannot see; on ``(p + s pdot) / |p + s pdot|`` it is the node's own."""
        L = self.L
        for k in range(L.epIdx.shape[0]):
            idx = L.epIdx[k]
            p = L.epRef[k] + q[idx]
            q[idx] = p / np.sqrt(p @ p) - L.epRef[k]

    def _position_along_motion(self, t, R, r, prev, qv, eps, centre, sphere=True):
        """Exudyn's position-level residuals at the state moved by ``+eps`` and ``-eps`` along
        the motion (and at the state itself if ``centre``); mbs is restored.  ``sphere``: the
        EP nodes' parameters are kept on the unit sphere (:meth:`_onto_unit_sphere`)."""
        L, q, mbs, ae, res, setTime = self.L, self.q, self.mbs, self._ae, self._residual, self._setTime
        o = self.n + self.n1
        self._qsave[:] = q
        sl = self.sliding
        if sl is not None:
            s0 = self.aeCur[sl.slots].copy()
        g0 = None
        if centre:
            setTime(t)
            ae(mbs, False)
            g0 = res()[o:].copy()
        write_moved_positions(R, r, L.lgIdx, L.lgRef, prev, q, self.qt, L.vecIdx, qv, eps, self._ER, self._rv)
        if sphere:
            self._onto_unit_sphere(q)
        if sl is not None:
            sl.move(self.aeCur, s0, eps)
        setTime(t + eps)
        ae(mbs, False)
        gp = res()[o:].copy()
        write_moved_positions(R, r, L.lgIdx, L.lgRef, prev, q, self.qt, L.vecIdx, qv, -eps, self._ER, self._rv)
        if sphere:
            self._onto_unit_sphere(q)
        if sl is not None:
            sl.move(self.aeCur, s0, -eps)
        setTime(t - eps)
        ae(mbs, False)
        gm = res()[o:].copy()
        q[:] = self._qsave
        if sl is not None:
            self.aeCur[sl.slots] = s0
        setTime(t)
        return gp, g0, gm

    def eta_step(self):
        """The central-difference step (module docstring): ``cbrt(eps) / max(1, max|v|)``."""
        return EPS_CBRT / max(1.0, self._vmax)

    def eta(self, t, R, r, prev, qv, eps=None, restore=True):
        """``eta = -d/dt g_v`` along the motion at fixed velocities (module docstring),
        at the state last written (``R, r``: its Lie group part, ``qv`` its vector part).
        ``restore=False`` (the stage loop) leaves mbs at the last moved configuration and
        time: nothing reads them before the next stage writes its state."""
        if self._etaClosed and not self._movingRows:
            euler_parameter_eta(self.qt, self._epCoords, self._epRows, self._etaBuf)
            return self._etaBuf.copy() if restore else self._etaBuf
        P = self.positionRows
        if len(P):
            # the position-derived rows (position_derived_rows): eta = -d2/ds2 g(q(s), t + s)
            # along the motion at fixed velocities, by second central differences at steps e
            # and 2 e extrapolated (Richardson: the e^2 term cancels); the step balances the
            # truncation (~ e^4 |g^(6)|) and the rounding (~ 4 eps_mach |g| / e^2), whose terms
            # are positions (the rows are differences of positions, not of small numbers):
            # e = eps_mach^(1/6) tau, about eps_mach^(2/3) ~ 4e-11 relative
            e = EPS_SIXTH / max(1.0, self._vmax)
            etaP = np.zeros(self.m)
            g0 = None                           # the residual at the state: the same for both paths
            for rows, sphere in ((self._posObjectRows, True), (self._posNodeRows, False)):
                if len(rows):
                    gp, c, gm = self._position_along_motion(t, R, r, prev, qv, e, g0 is None, sphere)
                    g0 = c if g0 is None else g0
                    gp2, _, gm2 = self._position_along_motion(t, R, r, prev, qv, 2.0 * e, False, sphere)
                    d1 = (gp[rows] + gm[rows] - 2.0 * g0[rows]) / (e * e)
                    d2 = (gp2[rows] + gm2[rows] - 2.0 * g0[rows]) / (4.0 * e * e)
                    etaP[rows] = -(4.0 * d1 - d2) / 3.0
            etaP = etaP[P]
        if eps is None:
            eps = EPS_CBRT / max(1.0, self._vmax)
        L, q, mbs, ae, res, setTime = self.L, self.q, self.mbs, self._ae, self._residual, self._setTime
        out = self._etaBuf
        if self._velocityLevel:
            if restore:
                self._qsave[:] = q
            write_moved_positions(R, r, L.lgIdx, L.lgRef, prev, q, self.qt, L.vecIdx, qv, eps, self._ER, self._rv)
            setTime(t + eps)
            ae(mbs, True)
            gp = res()
            write_moved_positions(R, r, L.lgIdx, L.lgRef, prev, q, self.qt, L.vecIdx, qv, -eps, self._ER, self._rv)
            setTime(t - eps)
            ae(mbs, True)
            gm = res()
            o = self.n + self.n1
            np.subtract(gm[o:], gp[o:], out=out)
            out *= 0.5 / eps
        else:
            out[:] = 0.0
        if len(P):
            out[P] = etaP
        for row, fn, label in self._movingRows:        # + cddot(t): coordinate_constraint_rows
            out[row] += offset_and_derivatives(fn, t, label)[2]
        if self.sliding is not None:
            self.sliding.transform_rows(out)
        if restore:
            q[:] = self._qsave
            setTime(t)
            return out.copy()
        return out

    def eta_error(self, t, R, r, prev, qv):
        """Error estimate of :meth:`eta` (a diagnostic): ``(eta(eps), estimate)`` with the
        truncation part by Richardson's comparison of eps and 2 eps (``|eta(2 eps) - eta(eps)|
        / 3``) plus the rounding part ``4 eps_mach (|C_q| |v| + |g_v|) / eps`` (the rounding
        error of the two evaluations of g_v, whose terms are of size |C_q| |v|, divided by
        the step)."""
        self._vmax = float(np.max(np.abs(self.qt))) if self.n else 0.0
        eps = self.eta_step()
        e1 = self.eta(t, R, r, prev, qv)
        e2 = self.eta(t, R, r, prev, qv, 2.0 * eps)
        gv = self.velocity_constraints(t, R, r, prev, qv)
        _, _, Cq = self.mass_force_jacobian(t)
        terms = np.abs(np.asarray(Cq)) @ np.abs(self.qt) + np.abs(gv)
        return e1, np.abs(e2 - e1) / 3.0 + 4.0 * np.finfo(float).eps * terms / eps

    def accelerations(self, t, R, r, prev, qv, restore=False):
        """Exudyn's accelerations ``a`` (nODE2), multipliers ``lam`` and ODE1 rates ``ydot`` at
        the state last written (:meth:`write_state`) and time t (eq. index1).  Without
        ``restore`` (the stage loop) mbs is left at a configuration moved by eta's
        differentiation step; with it, at the state and time t."""
        self.evaluations += 1
        M, f, Cq = self.mass_force_jacobian(t)
        eta = self.eta(t, R, r, prev, qv, None, restore) if self.m else self._eta0
        self.solve(M, f, Cq, eta)
        return self.a

    def _check_rows(self, Cq, empty=None):
        """Refuse AE rows the index-1 solve cannot take: a row without ODE2 coordinates must
        be an equation in its multiplier alone (an inactive connector: lam = 0); a row with
        both (a compliant constraint) is refused."""
        LL = self._lamlam
        if empty is None:
            empty = ~np.any(np.asarray(Cq) != 0.0, axis=1)
        for i in np.nonzero(empty)[0]:
            if not np.any(LL[i] != 0.0):
                raise ConstraintError(f"AE row {i} constrains neither ODE2 coordinates nor its multiplier at this "
                                      f"state; exudyn_lie cannot solve it (a constraint on data or ODE1 "
                                      f"coordinates?); solve with exudyn.SolveDynamic")
        rows = np.nonzero(~empty)[0]
        mixed = rows[np.any(LL[rows] != 0.0, axis=1)]
        if len(mixed):
            raise ConstraintError(f"AE rows {mixed.tolist()} depend on both coordinates and multipliers (e.g. a "
                                  f"constraint with a compliance); exudyn_lie's index-1 solve needs rigid "
                                  f"constraints; solve with exudyn.SolveDynamic")

    # ------------------------------------------------------------------ linear algebra
    def solve(self, M, f, Cq, eta):
        """``a``, ``lam`` of ``[M Cq^T; Cq 0][a; lam] = [f; eta]`` (Exudyn's matrices;
        :class:`~exudyn_lie.mbs.block_kkt.BlockKKT`, blocks from the nodes and M's pattern)."""
        self.kkt.solve(M, f, np.zeros((0, self.n)) if Cq is None else np.asarray(Cq), eta)

    @property
    def pivoted(self):
        return self.kkt.pivoted

    @property
    def dense(self):
        return self.kkt.dense

    @property
    def blkPtr(self):
        return None if self.kkt.blk is None else self.kkt.blkPtr
