"""Sliding coordinates on the Exudyn-evaluated path: algebraic unknowns that are coordinates,
not multipliers (Exudyn's ``ObjectJointSliding2D``).

Exudyn's ``ObjectJointSliding2D`` (CObjectJointSliding2D.cpp, ``useClassicalFormulation=True``,
its default) holds the position ``p0`` of marker 0 on the curve ``r(s)`` of a chain of ANCF
cable elements.  Its algebraic unknowns are the force ``lam = (fx, fy)`` and the sliding
coordinate ``s`` (an increment on the data node's value of the step's start; Exudyn's
PostNewton adds it to the data node and moves to the next cable element when ``s`` leaves the
current one).  Its equations are

    g = r(s) - p0 = 0                              rows P (position level),
    c . lam - |c| F_ax = 0                         row of s,   c = dg/ds = r'(s),

the second one the equation of motion of a massless coordinate: no force along the curve but
``axialForce`` F_ax.  Exudyn has no velocity-level form of them (its velocity-level call raises),
and the index-1 solve cannot take ``s`` as a multiplier.  This module eliminates ``s``:

* ``s`` from the positions: Gauss-Newton on ``g``, ``Delta s = -c . g / |c|^2`` (the closest
  point of the curve; on the constraint, the point itself); ``c`` is Exudyn's Jacobian column
  of the slot ``s`` (``ComputeJacobianAE``);
* ``sdot = -c . (C_q v) / |c|^2`` (the velocity level ``C_q v + c sdot = 0`` in least squares);
* the acceleration level ``C_q a + c sddot = eta`` (``eta``: second differences of ``g`` along
  the motion with ``s`` moving at ``sdot``, :meth:`~.evaluated.EvaluatedModel.eta`) in the
  orthonormal basis ``[c^, n^]`` of the rows P: the row along ``c^`` only gives ``sddot`` and is
  dropped, ``n^ . (C_q a - eta) = 0`` remains, with the multiplier ``mu``;
* the force ``lam = c^ mu0 + n^ mu`` with ``mu0 = c . lam / |c| = F_ax`` from the row of ``s``:
  ``-C_q^T c^ mu0`` is a known force moved to the right-hand side.

So the solve is that of a point on a curve without friction (and with F_ax along it), which is
what Exudyn's generalized-alpha converges to as its step falls.

``useClassicalFormulation=False`` writes the same joint with the normal ``n = (-c_y, c_x)``:

    lam_0 = 0                                      row 0 (a dummy: lam_0 is no force),
    (r(s) - p0) . n = 0                            row 1 (the constraint, multiplier lam_1),
    (r(s) - p0) . c = 0                            row of s (the closest point),

without ``axialForce``.  Row 1 already is the normal row of the elimination above (its ``s``
column ``(r - p0) . n'`` vanishes on the constraint), so only ``s`` is eliminated: Newton on
the row of s with Exudyn's ``J(s, s)``, ``sdot = -(C_q v)_s / J(s, s)``; rows 0 and s become
equations of their multipliers alone, and Exudyn's AE coordinates get ``(0, lam_1, s)``.  (Exudyn's implicit solvers add
the Jacobian transposed times *all* AE unknowns to the forces, ``s`` included: a force of order
``|lam| Delta s / L`` per step that vanishes with the step; it is not reproduced.)
"""
from __future__ import annotations

import numpy as np

from ..errors import ConstraintError

#: Gauss-Newton iterations for s before the positions count as off the curve
MAX_ITER = 30


def sliding_joints(mbs):
    """The active ObjectJointSliding2D of mbs (evaluated_items refuses constrainRotation):
    ``[(object, AE rows P (2), AE slot of s, classical formulation)]``."""
    sd = mbs.systemData
    out = []
    for o in range(sd.NumberOfObjects()):
        d = mbs.GetObject(o)
        if d["objectType"] == "JointSliding2D" and d.get("activeConnector", True):
            rows = [int(r) for r in sd.GetObjectLTGAE(o)]
            out.append((o, rows[:2], rows[2], bool(d.get("useClassicalFormulation", True))))
    return out


class SlidingCoordinates:
    """The sliding coordinates of a model (module docstring): ``project`` them from the positions
    written into mbs, ``transform`` Exudyn's rows and forces, ``forces`` back."""

    def __init__(self, model, joints):
        self.model = model
        self.objects = [j[0] for j in joints]
        self.P = np.array([j[1] for j in joints], np.int64).reshape(-1, 2)
        self.slots = np.array([j[2] for j in joints], np.int64)
        self.classical = np.array([j[3] for j in joints], bool)
        self._nc = ~self.classical                    # the joints of useClassicalFormulation=False
        k = len(joints)
        self.c = np.zeros((k, 2))
        self.jss = np.ones(k)              # J(s, s) of the row of s (the other formulation's Newton)
        self.sdot = np.zeros(k)
        self.fs = np.zeros(k)              # c . lam, the force along the curve (|c| F_ax)
        self._haveC = False
        # the length scale of the positions (the round-off of r(s) - p0): the reference values
        import exudyn as exu
        ref = np.asarray(model.sd.GetODE2Coordinates(configuration=exu.ConfigurationType.Reference), float)
        self.scale = max(1.0, float(np.max(np.abs(ref))) if ref.size else 1.0)

    # ------------------------------------------------------------------ s from the positions
    def _jacobian_columns(self, J):
        o = self.model.n + self.model.n1
        self.c[:, 0] = J[o + self.P[:, 0], o + self.slots]
        self.c[:, 1] = J[o + self.P[:, 1], o + self.slots]
        self.jss[:] = J[o + self.slots, o + self.slots]
        self._haveC = True

    def _fresh_jacobian(self):
        m = self.model
        m._zeroJ()
        m._jacAE(m.mbs, scalarFactor_ODE2_t=m._factorODE2_t)
        J = m._getJ()
        self._jacobian_columns(J)
        return J

    def project(self, t, ae):
        """``s`` of every joint for the positions and time in mbs, written into ``ae`` (mbs'
        Current AE coordinates; the joints' forces there are 0 during the iteration, so that
        the row of s gives ``-|c| F_ax``, and then as before: sensors read them)."""
        if not self._haveC:
            self._fresh_jacobian()
        P = self.P
        forces = ae[P].copy()
        ae[P] = 0.0
        try:
            self._iterate(t, ae)
        finally:
            ae[P] = forces

    def _iterate(self, t, ae):
        m, P, slots = self.model, self.P, self.slots
        o = m.n + m.n1
        m._setTime(t)
        last = np.inf
        for it in range(MAX_ITER):
            m._ae(m.mbs, False)
            g = m._residual()[o:]
            ds = -np.sum(self.c * g[P], axis=1) / np.sum(self.c * self.c, axis=1)
            ds[self._nc] = -g[slots[self._nc]] / self.jss[self._nc]      # Newton on the row of s
            self.fs[:] = np.where(self.classical, -g[slots], 0.0)
            step = float(np.max(np.abs(ds)))
            # converged, or at the rounding floor (the step no longer halves)
            if step <= 1e-15 * self.scale or (it >= 3 and step > 0.5 * last and step <= 1e-9 * self.scale):
                return
            ae[slots] += ds
            last = step
            if it == 2:
                self._fresh_jacobian()        # slow contraction: c of the new s
        k = int(np.argmax(np.abs(ds)))       # (not converged: the positions left the cable)
        raise ConstraintError(f"object {self.objects[k]} (ObjectJointSliding2D): its marker's position is not on the "
                              f"cable (the closest point was not found in {MAX_ITER} Gauss-Newton steps; last "
                              f"change of the sliding coordinate {ds[k]:.3g} m); the joint's constraint is lost")

    def refresh(self, t, ae, qt):
        """``s``, ``c`` and ``sdot`` at the state in mbs (outside a stage's evaluation)."""
        self.project(t, ae)
        self.velocities(self._fresh_jacobian(), qt)

    def velocities(self, J, qt):
        """``sdot`` from Exudyn's Jacobian ``J`` at the state (its columns ``c`` too) and the
        velocities ``qt``."""
        self._jacobian_columns(J)
        n, o = self.model.n, self.model.n + self.model.n1
        for k in range(len(self.slots)):
            if not self.classical[k]:
                self.sdot[k] = -float(J[o + self.slots[k], :n] @ qt) / self.jss[k]
                continue
            cq = J[o + self.P[k], :n] @ qt
            c = self.c[k]
            self.sdot[k] = -float(c @ cq) / float(c @ c)

    def move(self, ae, s0, eps):
        """The sliding coordinates moved along the motion: ``s0 + eps sdot``."""
        ae[self.slots] = s0 + eps * self.sdot

    # ------------------------------------------------------------------ the rows in the basis [c^, n^]
    def _bases(self):
        """``c^``, ``n^``, ``|c|``; for the other formulation ``c^ = (1, 0)``, ``n^ = (0, 1)``, whose
        rows are already in its basis (row 0 the dummy, row 1 the normal one)."""
        c = self.c
        nc = np.sqrt(np.sum(c * c, axis=1))
        nc[self._nc] = 1.0             # (its c is Exudyn's J(rows 0, 1; s): no slope; its fs is 0)
        ch = c / nc[:, None]
        ch[self._nc] = (1.0, 0.0)
        nh = np.stack([-ch[:, 1], ch[:, 0]], axis=1)
        return ch, nh, nc

    def transform(self, Cq, f, LL):
        """Exudyn's rows (``Cq``, multiplier block ``LL``: changed in place) and forces ``f`` (a new
        array if changed) in the basis of the module docstring: the row along ``c^`` and the row of
        ``s`` become equations of their multipliers alone (lam = 0)."""
        ch, nh, nc = self._bases()
        P0, P1, S = self.P[:, 0], self.P[:, 1], self.slots
        mu0 = self.fs / nc
        if np.any(mu0 != 0.0):
            f = f - (Cq[P0].T * (ch[:, 0] * mu0) + Cq[P1].T * (ch[:, 1] * mu0)).sum(axis=1)
        Cq[P1] = Cq[P0] * nh[:, :1] + Cq[P1] * nh[:, 1:]
        Cq[P0] = 0.0
        Cq[S] = 0.0
        for rows in (P0, P1, S):
            LL[rows] = 0.0
        LL[P0, P0] = 1.0
        LL[S, S] = 1.0
        return f

    def transform_rows(self, g):
        """A position- or velocity-level residual (or eta) of Exudyn's rows in the same basis."""
        ch, nh, _ = self._bases()
        P0, P1 = self.P[:, 0], self.P[:, 1]
        g[P1] = nh[:, 0] * g[P0] + nh[:, 1] * g[P1]
        g[P0] = 0.0
        g[self.slots] = 0.0
        return g

    def forces(self, lam, ae):
        """Exudyn's AE coordinates from the solve's multipliers: the joints' forces
        ``c^ mu0 + n^ mu`` (the other formulation: ``(0, mu)``, _bases) and their sliding
        coordinates (as in ``ae``)."""
        out = np.array(lam, float)
        ch, nh, nc = self._bases()
        mu0, mu = self.fs / nc, out[self.P[:, 1]]
        out[self.P[:, 0]] = ch[:, 0] * mu0 + nh[:, 0] * mu
        out[self.P[:, 1]] = ch[:, 1] * mu0 + nh[:, 1] * mu
        out[self.slots] = ae[self.slots]
        return out
