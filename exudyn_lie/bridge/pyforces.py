"""Exudyn items evaluated in Python (``Scene.AddPythonForce``): connectors with Python
user functions (the RigidBodySpringDamper with a ``springForceTorqueUserFunction``; without
one it is compiled, ``mbs/forces.rigid_spring_forces``) and loads with a
``loadVectorUserFunction``.

Every item implements ``add(t, st, F, T)``: it adds world forces ``F[b]`` (acting at the
frame origin of body ``b``) and world torques ``T[b]`` for the body states ``st``
(:class:`exudyn_lie.mbs.state.BodyStates`).  A force ``f`` at a body point ``p`` adds
``f`` to ``F[b]`` and ``(p - r_b) x f`` to ``T[b]``.  User functions are called with
Exudyn's signatures and the real ``mbs``.

The force laws are Exudyn's (checked against ``ComputeODE2RHS`` in
``tests/test_bridge_oracle.py``):

* SpringDamper: ``f = uf(mbs, t, i, L - L0, Ldot - velocityOffset, k, d, force)``, tension
  along ``e = (p1 - p0)/L``: ``-f e`` on marker 1, ``+f e`` on marker 0;
* CartesianSpringDamper: ``f = uf(mbs, t, i, u, udot, k, d, offset)`` with
  ``u = p1 - p0 - offset``: ``-f`` on marker 1, ``+f`` on marker 0;
* TorsionalSpringDamper: ``tau = uf(mbs, t, i, phi, phidot, k, d, offset)``, ``phi`` the z
  Tait-Bryan angle of ``J0^T J1`` (tracked over turns from the angle stored in the data
  node), ``phidot = z0 . (w1 - w0)``;
  torque ``-tau z0`` on marker 1, ``+tau z0`` on marker 0;
* RigidBodySpringDamper, Tait-Bryan form: ``u = (J0^T (p1 - p0), xyz angles of J0^T J1) - offset``,
  ``udot = (J0^T (v1 - v0), J0^T (w1 - w0))``; intrinsic form: ``u = log_SE3(J0, J1) - offset``
  (``(V(theta)^-1 J0^T (p1 - p0), theta)``), ``udot`` in the mid frame ``Jm = J0 exp(theta/2)``,
  the force acting at the mid point (extra torque ``1/2 (Jm u_t) x F`` on both sides);
  ``(f, m) = K u + D udot`` in that frame, or ``uf(mbs, t, i, u_disp + off_disp, u_rot + off_rot,
  udot_v, udot_w, K, D, rotationMarker0, rotationMarker1, offset)`` (Exudyn passes the
  displacement and rotation without the offset).
"""
import math

import numpy as np

from ..mbs.external_probes import (ARM_HAS, ARM_WORLD, N_PROBE, SPRING_ARM_A, SPRING_ARM_B, SPRING_E, SPRING_L, SPRING_LD, TORSION_PHI,
                                   TORSION_PHID, TORSION_Z, arm_probe_row, spring_probe, spring_probe_row,
                                   torsion_probe_row)
from ..mbs.scene import GROUND
from . import rotations as rot


def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def marker_state(mf, st):
    """(p, v, A, w, rb) of a marker: world position, velocity, world rotation of the
    marker frame (body rotation for position markers), world angular velocity, body
    frame origin (None for ground)."""
    if mf.body == GROUND:
        z = np.zeros(3)
        return mf.pos, z, mf.rotation(), z, None
    b = mf.body
    R = st.R[b]
    s = mf.pos
    om = st.omega[b]
    p = st.r[b] + R @ s
    v = st.vel[b] + R @ _cross(om, s)
    return p, v, R @ mf.rotation(), R @ om, st.r[b]


def apply(mf, p, rb, f, tq, F, T):
    """Add the world force f at world point p and world torque tq to the marker's body."""
    if mf.body == GROUND:
        return
    F[mf.body] += f
    T[mf.body] += tq + _cross(p - rb, f)


class PyItem:
    """Base: an Exudyn item evaluated in Python (``active`` False: an inactive connector,
    no force; :meth:`idle` keeps its tracking going)."""
    label = ""
    active = True

    def idle(self, st):
        pass

    def bodies(self):
        return []

    def add(self, t, st, F, T):
        raise NotImplementedError


class _Connector(PyItem):
    def __init__(self, mbs, o, d, A, B):
        self.mbs = mbs
        self.o = int(o)
        self.d = d
        self.A = A
        self.B = B
        self.label = f"object {o} Object{d['objectType']}"

    def bodies(self):
        return [self.A.body, self.B.body]


def _call(label, fn, *args):
    try:
        return fn(*args)
    except Exception as e:
        raise type(e)(f"{label}: user function raised: {e}") from e


class SpringDamperUF(_Connector):
    def __init__(self, mbs, o, d, A, B, uf):
        super().__init__(mbs, o, d, A, B)
        self.uf = uf

    def add(self, t, st, F, T):
        # the spring's kinematics are its probe's (mbs/external_probes.spring_probe), also where
        # no Work holds the probe: one computation of length, rate, direction and arms
        p = self._kinematics
        if p is None:                    # its input row (bodies, points) is fixed: a changed item is replaced
            p = self._kinematics = np.array(self.probe_row(), float)
        spring_probe(st.R, st.r, np.ascontiguousarray(np.hstack((st.omega, st.vel))), p)
        f = self.force(t, float(p[SPRING_L]), float(p[SPRING_LD]))
        e0, e1, e2 = p[SPRING_E:SPRING_E + 3].tolist()
        force_at(self.A, p[SPRING_ARM_A:SPRING_ARM_A + 3].tolist(), f * e0, f * e1, f * e2, F, T)
        force_at(self.B, p[SPRING_ARM_B:SPRING_ARM_B + 3].tolist(), -f * e0, -f * e1, -f * e2, F, T)

    def force(self, t, L, Ld):
        """The user function's tension at length ``L`` and rate ``Ld``."""
        d = self.d
        return float(_call(self.label, self.uf, self.mbs, t, self.o, L - d["referenceLength"],
                           Ld - d.get("velocityOffset", 0.0), d["stiffness"], d["damping"], d["force"]))

    # ---- the stepper's seam: length, rate, direction and arms computed by the compiled stage
    probeIndex = None        # the row of Work.probe (Combined.probe_rows)
    _kinematics = None       # its probe row outside a stage (add)

    def probe_row(self):
        """The input row of its probe (mbs/external_probes.py): bodies and marker points."""
        return spring_probe_row(self.A.body, self.B.body, self.A.pos, self.B.pos)

    def add_stage(self, t, st, F, T, P, Q):
        """:meth:`add` in the stepper's seam from its probe's outputs (``P``, ``Q``: flat
        memoryviews of ``Work.probe`` and ``Work.Qext``, see
        :meth:`TorsionalSpringDamperUF.add_stage`)."""
        j = self.probeIndex * N_PROBE
        f = self.force(t, P[j + SPRING_L], P[j + SPRING_LD])
        e0, e1, e2 = P[j + SPRING_E], P[j + SPRING_E + 1], P[j + SPRING_E + 2]
        a, b = self.A.body, self.B.body
        if a != GROUND:
            _force_flat(Q, 6 * a, P, j + SPRING_ARM_A, f * e0, f * e1, f * e2)
        if b != GROUND:
            _force_flat(Q, 6 * b, P, j + SPRING_ARM_B, -f * e0, -f * e1, -f * e2)


def force_at(mf, arm, f0, f1, f2, F, T):
    """``apply`` for a force only, in scalar arithmetic: ``F[b] += f``, ``T[b] += arm x f``."""
    if mf.body == GROUND:
        return
    b = mf.body
    a0, a1, a2 = arm
    F[b, 0] += f0
    F[b, 1] += f1
    F[b, 2] += f2
    T[b, 0] += a1 * f2 - a2 * f1
    T[b, 1] += a2 * f0 - a0 * f2
    T[b, 2] += a0 * f1 - a1 * f0


def _force_flat(Q, i, P, k, f0, f1, f2):
    """:func:`force_at` on the flat ``Qext`` row at ``i`` (force, then torque), the arm at
    ``P[k:k+3]``: the same sums."""
    a0, a1, a2 = P[k], P[k + 1], P[k + 2]
    Q[i] += f0
    Q[i + 1] += f1
    Q[i + 2] += f2
    Q[i + 3] += a1 * f2 - a2 * f1
    Q[i + 4] += a2 * f0 - a0 * f2
    Q[i + 5] += a0 * f1 - a1 * f0


class CartesianSpringDamperUF(_Connector):
    def __init__(self, mbs, o, d, A, B, uf):
        super().__init__(mbs, o, d, A, B)
        self.uf = uf

    def add(self, t, st, F, T):
        d = self.d
        pA, vA, _, _, rA = marker_state(self.A, st)
        pB, vB, _, _, rB = marker_state(self.B, st)
        u = pB - pA - np.asarray(d["offset"], float)
        f = np.asarray(_call(self.label, self.uf, self.mbs, t, self.o, u, vB - vA, d["stiffness"],
                             d["damping"], d["offset"]), float).reshape(3)
        z = np.zeros(3)
        apply(self.A, pA, rA, f, z, F, T)
        apply(self.B, pB, rB, -f, z, F, T)


class TorsionalSpringDamperUF(_Connector):
    """Torsional spring with a user function (``uf``), or without a data node
    (``track=False``: Exudyn's angle is then the principal one, in (-pi, pi]).

    With a data node (``track=True``) the angle is Exudyn's: the branch of the principal
    angle nearest to the previous angle, starting from ``angle0``, the continuous angle
    stored in the spring's NodeGenericData (0 for a new spring; after turns, e.g. in a
    continued simulation, the turned angle)."""

    def __init__(self, mbs, o, d, A, B, rotA, rotB, uf, track=True, angle0=0.0):
        super().__init__(mbs, o, d, A, B)
        self.rotA = rotA
        self.rotB = rotB
        # the columns of the marker rotations that :meth:`angle` uses (x, z of A; x, y of B), as floats
        self._colsA = _columns(rotA, 0, 2)
        self._colsB = _columns(rotB, 0, 1)
        self.uf = uf
        self.track = track
        self.prev = float(angle0) if track else None

    def idle(self, st):
        if self.track:          # Exudyn updates the data node's angle also while inactive
            self.angle(st)

    def angle(self, st):
        """(phi tracked, phidot, world z axis of the A frame).  Only the rotations enter (the
        torque acts as a pure couple), in scalar arithmetic on floats: this runs once per
        stage, and numpy's per-call cost on 3x3 products, 3-vectors and element reads was
        most of it.  One ``tolist`` of each body's rotation and angular velocity, and only
        the four frame columns used (bench_userfunctions' PD torque, overhead per call:
        15.3 us with numpy, 5.2 us with lists; with this and the cheaper seam 4.9 -> 2.4 us
        CPU time, measured interleaved on a loaded machine)."""
        a, b = self.A.body, self.B.body
        if a == GROUND:
            (x0, x1, x2, z0, z1, z2), wa0, wa1, wa2 = self._colsA, 0.0, 0.0, 0.0
        else:
            x0, x1, x2, z0, z1, z2, wa0, wa1, wa2 = _frame_and_omega(st, a, self._colsA)
        if b == GROUND:
            (c0, c1, c2, s0, s1, s2), wb0, wb1, wb2 = self._colsB, 0.0, 0.0, 0.0
        else:
            c0, c1, c2, s0, s1, s2, wb0, wb1, wb2 = _frame_and_omega(st, b, self._colsB)
        c = x0 * c0 + x1 * c1 + x2 * c2          # (RA^T RB)[0, 0]
        s = x0 * s0 + x1 * s1 + x2 * s2          # (RA^T RB)[0, 1]
        phi = math.atan2(-s, c)
        if self.track:
            phi += 2 * math.pi * round((self.prev - phi) / (2 * math.pi))
            self.prev = phi
        phid = z0 * (wb0 - wa0) + z1 * (wb1 - wa1) + z2 * (wb2 - wa2)
        return phi, phid, (z0, z1, z2)

    def torque(self, t, phi, phid):
        """tau: the user function, or Exudyn's law without one."""
        d = self.d
        if self.uf is None:
            return d["stiffness"] * (phi - d["offset"]) + d["damping"] * (phid - d.get("velocityOffset", 0.0)) \
                + d["torque"]
        try:
            tau = self.uf(self.mbs, t, self.o, phi, phid, d["stiffness"], d["damping"], d["offset"])
        except Exception as e:
            raise type(e)(f"{self.label}: user function raised: {e}") from e
        return float(tau)

    def add(self, t, st, F, T):
        phi, phid, (z0, z1, z2) = self.angle(st)
        tau = self.torque(t, phi, phid)
        # torque +tau z0 on marker 0's body, -tau z0 on marker 1's (a couple: no force)
        a, b = self.A.body, self.B.body
        if a != GROUND:
            T[a, 0] += tau * z0
            T[a, 1] += tau * z1
            T[a, 2] += tau * z2
        if b != GROUND:
            T[b, 0] -= tau * z0
            T[b, 1] -= tau * z1
            T[b, 2] -= tau * z2

    # ---- the stepper's seam: the angle, its rate and z0 computed by the compiled stage
    probeIndex = None        # the row of Work.probe (Combined.probe_rows)

    def probe_row(self):
        """The input row of its probe (mbs/external_probes.py): bodies and the frame columns
        :meth:`angle` uses."""
        return torsion_probe_row(self.A.body, self.B.body, self._colsA, self._colsB)

    def add_stage(self, t, st, F, T, P, Q):
        """:meth:`add` in the stepper's seam (:meth:`Combined.stage_adder`) from its probe's
        outputs: ``P`` the flat ``Work.probe`` (the principal angle, rate and world z0 of
        this stage, computed as :meth:`angle` does), ``Q`` the flat ``Work.Qext`` (torques in
        columns 3-5 of a body's six), both memoryviews: their items are Python floats, and
        reading and adding them costs a fraction of numpy's item access (the PD torque of
        ``bench --sections userfunctions``, one call, timeit: 1.65 us in :meth:`add`, 0.65 us
        here with 2D memoryviews, 0.54 us with flat ones; the user function's own 0.17 us
        included)."""
        j = self.probeIndex * N_PROBE
        phi = P[j + TORSION_PHI]
        if self.track:                    # as in angle(): the branch nearest the last angle
            phi += 2 * math.pi * round((self.prev - phi) / (2 * math.pi))
            self.prev = phi
        tau = self.torque(t, phi, P[j + TORSION_PHID])
        z0, z1, z2 = P[j + TORSION_Z], P[j + TORSION_Z + 1], P[j + TORSION_Z + 2]
        a, b = self.A.body, self.B.body
        if a != GROUND:
            i = 6 * a + 3
            Q[i] += tau * z0
            Q[i + 1] += tau * z1
            Q[i + 2] += tau * z2
        if b != GROUND:
            i = 6 * b + 3
            Q[i] -= tau * z0
            Q[i + 1] -= tau * z1
            Q[i + 2] -= tau * z2


def _columns(rot, j, k):
    """Columns ``j`` and ``k`` of the 3x3 rotation ``rot`` as six floats."""
    R = np.asarray(rot, float).reshape(3, 3).tolist()
    return R[0][j], R[1][j], R[2][j], R[0][k], R[1][k], R[2][k]


def _frame_and_omega(st, b, cols):
    """Nine floats: the two columns ``cols`` (six floats, from :func:`_columns`) of a marker
    frame ``rot`` turned to the world, ``R_b rot``, and the world angular velocity
    ``R_b omega_b`` of body ``b``."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = st.R[b].tolist()
    w0, w1, w2 = st.omega[b].tolist()
    a0, a1, a2, b0, b1, b2 = cols
    return (r00 * a0 + r01 * a1 + r02 * a2, r10 * a0 + r11 * a1 + r12 * a2, r20 * a0 + r21 * a1 + r22 * a2,
            r00 * b0 + r01 * b1 + r02 * b2, r10 * b0 + r11 * b1 + r12 * b2, r20 * b0 + r21 * b1 + r22 * b2,
            r00 * w0 + r01 * w1 + r02 * w2, r10 * w0 + r11 * w1 + r12 * w2, r20 * w0 + r21 * w1 + r22 * w2)


def _left_jacobian(th):
    """V(theta) = I + (1 - cos t)/t^2 W + (t - sin t)/t^3 W^2 (SE(3) translation part)."""
    t = np.linalg.norm(th)
    W = rot.skew(th)
    if t < 1e-4:
        b, c = 0.5 - t * t / 24.0, 1.0 / 6.0 - t * t / 120.0
    else:
        b, c = (1 - np.cos(t)) / t ** 2, (t - np.sin(t)) / t ** 3
    return np.eye(3) + b * W + c * (W @ W)


class RigidBodySpringDamper(_Connector):
    """Exudyn's ``ObjectConnectorRigidBodySpringDamper`` (both formulations)."""

    def __init__(self, mbs, o, d, A, B, rotA, rotB, uf):
        super().__init__(mbs, o, d, A, B)
        self.rotA = rotA
        self.rotB = rotB
        self.K = np.asarray(d["stiffness"], float).reshape(6, 6)
        self.D = np.asarray(d["damping"], float).reshape(6, 6)
        self.off = np.asarray(d["offset"], float).reshape(6)
        self.intrinsic = bool(d.get("useIntrinsicFormulation", False))
        self.uf = uf

    def add(self, t, st, F, T):
        pA, vA, _, wA, rA = marker_state(self.A, st)
        pB, vB, _, wB, rB = marker_state(self.B, st)
        J0 = (st.R[self.A.body] @ self.rotA) if self.A.body != GROUND else self.rotA
        J1 = (st.R[self.B.body] @ self.rotB) if self.B.body != GROUND else self.rotB
        Rrel = J0.T @ J1
        if self.intrinsic:
            th = rot.matrix_to_rotvec(Rrel)[0]
            Jm = J0 @ rot.rotvec_to_matrix(0.5 * th)[0]
            ul = np.linalg.solve(_left_jacobian(th), J0.T @ (pB - pA))
            u = np.r_[ul, th] - self.off
            ut = np.r_[Jm.T @ (vB - vA), Jm.T @ (wB - wA)]
            Jf = Jm
            lever = 0.5 * (Jm @ ul)          # the force acts at the mid point
        else:
            ang = rot.matrix_to_rxyz_candidates(Rrel)[0, 0]
            u = np.r_[J0.T @ (pB - pA), ang] - self.off
            ut = np.r_[J0.T @ (vB - vA), J0.T @ (wB - wA)]
            Jf = J0
            lever = None
        if self.uf is None:
            fl = self.K @ u + self.D @ ut
        else:
            raw = u + self.off                # Exudyn passes the displacement without the offset
            fl = np.asarray(_call(self.label, self.uf, self.mbs, t, self.o, raw[:3], raw[3:], ut[:3], ut[3:],
                                  self.K, self.D, self.d.get("rotationMarker0", np.eye(3)),
                                  self.d.get("rotationMarker1", np.eye(3)), self.off), float).reshape(6)
        f = Jf @ fl[:3]
        m = Jf @ fl[3:]
        c = _cross(lever, f) if lever is not None else np.zeros(3)
        apply(self.A, pA, rA, f, m + c, F, T)
        apply(self.B, pB, rB, -f, -m + c, F, T)


class LoadUF(PyItem):
    """LoadForceVector / LoadTorqueVector / LoadMassProportional with a
    ``loadVectorUserFunction(mbs, t, loadVector)``."""

    def __init__(self, mbs, l, loadType, lv, mf, bodyFixed, uf, mass, com):
        self.mbs = mbs
        self.l = int(l)
        self.loadType = loadType
        self.lv = lv
        self.mf = mf
        self.bodyFixed = bodyFixed
        self.uf = uf
        self.mass = mass
        self.com = com
        self.label = f"load {l} Load{loadType}"

    def vector(self, t):
        """The user function's vector as three floats."""
        try:
            v = self.uf(self.mbs, t, self.lv)
        except Exception as e:
            raise type(e)(f"{self.label}: user function raised: {e}") from e
        try:
            v0, v1, v2 = v
        except (TypeError, ValueError):
            v0, v1, v2 = np.asarray(v, float).reshape(3)
        if type(v0) is not float or type(v1) is not float or type(v2) is not float:   # (cheaper than float())
            v0, v1, v2 = float(v0), float(v1), float(v2)
        return v0, v1, v2

    # ---- the stepper's seam: the world arm of the point of a force computed by the compiled stage
    probeIndex = None        # the row of Work.probe (Combined.probe_rows)

    def probe_row(self):
        """The input row of its probe (mbs/external_probes.py): the point of a force (the
        marker's, or the centre of mass for a mass-proportional load); None for a torque."""
        if self.loadType == "TorqueVector":
            return None
        return arm_probe_row(self.mf.body, self.com if self.loadType == "MassProportional" else self.mf.pos)

    def add_stage(self, t, st, F, T, P, Q):
        """:meth:`add` in the stepper's seam (:meth:`Combined.stage_adder`): adds through the
        flat memoryview ``Q`` of ``Work.Qext``, the arm of a force read from its probe in ``P``
        (numpy's item access cost more than the rest; zero user load of ``bench --sections
        userfunctions``, one call, timeit: 0.50 us in :meth:`add`, 0.30 here); a body-fixed
        force or torque as :meth:`add`."""
        lt = self.loadType
        if self.bodyFixed and lt != "MassProportional":
            self.add(t, st, F, T)
            return
        v0, v1, v2 = self.vector(t)
        i = 6 * self.mf.body
        if lt == "TorqueVector":
            Q[i + 3] += v0
            Q[i + 4] += v1
            Q[i + 5] += v2
            return
        if lt == "MassProportional":
            m = self.mass
            v0, v1, v2 = m * v0, m * v1, m * v2
        # as _add_force: the force, then the torque of its arm unless the point is the origin
        Q[i] += v0
        Q[i + 1] += v1
        Q[i + 2] += v2
        j = self.probeIndex * N_PROBE
        if P[j + ARM_HAS]:
            a0, a1, a2 = P[j + ARM_WORLD], P[j + ARM_WORLD + 1], P[j + ARM_WORLD + 2]
            Q[i + 3] += a1 * v2 - a2 * v1
            Q[i + 4] += a2 * v0 - a0 * v2
            Q[i + 5] += a0 * v1 - a1 * v0

    def add(self, t, st, F, T):
        # scalar arithmetic: this runs once per stage, numpy's per-call cost on 3-vectors
        # would be most of it
        v0, v1, v2 = self.vector(t)
        b = self.mf.body
        if self.loadType == "MassProportional":
            m = self.mass
            f0, f1, f2 = m * v0, m * v1, m * v2
            _add_force(st.R[b], self.com, b, f0, f1, f2, F, T)
            return
        if self.bodyFixed:
            v0, v1, v2 = self.mf.rotation() @ np.array((v0, v1, v2))     # R (A v), Exudyn's order
            R = st.R[b]
            v0, v1, v2 = (R[0, 0] * v0 + R[0, 1] * v1 + R[0, 2] * v2, R[1, 0] * v0 + R[1, 1] * v1 + R[1, 2] * v2,
                          R[2, 0] * v0 + R[2, 1] * v1 + R[2, 2] * v2)
        if self.loadType == "ForceVector":
            _add_force(st.R[b], self.mf.pos, b, v0, v1, v2, F, T)
        else:
            T[b, 0] += v0
            T[b, 1] += v1
            T[b, 2] += v2


def _add_force(R, s, b, f0, f1, f2, F, T):
    """Add the world force f at the body point s (body coordinates) of body b: ``F[b] += f``,
    ``T[b] += (R s) x f`` (scalar arithmetic)."""
    F[b, 0] += f0
    F[b, 1] += f1
    F[b, 2] += f2
    s0, s1, s2 = float(s[0]), float(s[1]), float(s[2])
    if s0 == 0.0 and s1 == 0.0 and s2 == 0.0:
        return
    a0 = R[0, 0] * s0 + R[0, 1] * s1 + R[0, 2] * s2
    a1 = R[1, 0] * s0 + R[1, 1] * s1 + R[1, 2] * s2
    a2 = R[2, 0] * s0 + R[2, 1] * s1 + R[2, 2] * s2
    T[b, 0] += a1 * f2 - a2 * f1
    T[b, 1] += a2 * f0 - a0 * f2
    T[b, 2] += a0 * f1 - a1 * f0


class Combined:
    """One ``Scene.AddPythonForce`` callback evaluating all items: ``fn(t, st) -> (F, T)``,
    and ``add_into(t, st, F, T)``, which the simulator's Python-force seam calls to add
    into its own arrays (no allocation per stage)."""

    #: ``before(t, st)``, called first at every stage when set (bridge/stage_state.py: the stage
    #: state into mbs for user functions that read it)
    before = None

    def __init__(self, items, nb):
        self.items = items
        self.nb = nb

    def add_into(self, t, st, F, T):
        if self.before is not None:
            self.before(t, st)
        for it in self.items:
            if it.active:
                it.add(t, st, F, T)
            else:
                it.idle(st)

    def __call__(self, t, st):
        F = np.zeros((self.nb, 3))
        T = np.zeros((self.nb, 3))
        self.add_into(t, st, F, T)
        return F, T

    def probe_rows(self, first):
        """The probes of its items (mbs/external_probes.py), numbered from ``first``."""
        rows = []
        for it in self.items:
            row = it.probe_row() if hasattr(it, "probe_row") else None
            if row is not None:
                it.probeIndex = first + len(rows)
                rows.append(row)
        return rows

    def stage_adder(self, probe, Qext):
        """``add_into`` for the stepper's seam (``Simulator._external_views``, once per work
        set): items with an ``add_stage(t, st, F, T, P, Q)`` add through flat memoryviews ``P`` of
        ``probe`` (the kinematics the compiled stage computed, mbs/external_probes.py) and
        ``Q`` of ``Qext`` (rows (F, T) of six); the others run as in :meth:`add_into`.  In the
        items' order, so the sums are :meth:`add_into`'s to the bit."""
        # probe None: no item of the scene reads one (compiled.make_work)
        P, Q = (None if probe is None else _flat(probe)), _flat(Qext)
        nprobe = 0 if probe is None else probe.shape[0]
        steps = []
        for it in self.items:
            fast = getattr(it, "add_stage", None)
            if hasattr(it, "probe_row") and it.probe_row() is not None \
                    and not (it.probeIndex is not None and it.probeIndex < nprobe):
                fast = None                 # its probe is not in this work set
            steps.append((it, fast))
        steps = tuple(steps)
        combined = self

        def add(t, st, F, T):
            if combined.before is not None:
                combined.before(t, st)
            for it, fast in steps:
                if not it.active:
                    it.idle(st)
                elif fast is not None:
                    fast(t, st, F, T, P, Q)
                else:
                    it.add(t, st, F, T)
        return add


def _flat(a):
    """A flat memoryview of the C-contiguous float array ``a`` (shares its memory: the
    reshape of a C-contiguous array is a view)."""
    if not a.flags.c_contiguous:
        raise ValueError("the seam's arrays must be C-contiguous")
    return memoryview(a.reshape(-1))


def combined(items, nb):
    """One ``Scene.AddPythonForce`` callback evaluating all items."""
    return Combined(items, nb)
