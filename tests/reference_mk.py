"""TEST ORACLE ONLY: the reference (Python-level) explicit Munthe-Kaas integrator on products
of c-space groups.  No solver path runs it; every path (Simulator, SolveDynamic, Python
forces) runs the one compiled stepper, :mod:`exudyn_lie.mbs.stepper`.  The tests compare
that stepper and the vector-space formulations with this one.

The state of an ``n``-body system is ``(g, V)``:

* ``g`` -- a list of ``n`` poses ``(R, r)`` (``R`` 3x3 body->world, ``r`` a 3-vector),
  each living on its own c-space group, chosen per body: ``SE3`` (semidirect product,
  eq. MultSE3) or ``SO3xR3`` (direct product, eq. MultDirectProduct);
* ``V`` -- an ``(n, 6)`` array of velocities, rotation first: for SE3 the body-fixed twist
  ``(omega, v)`` with ``v = R^T rdot`` (eq. Vhat), for SO3xR3 the mixed velocity
  ``(omega, rdot)`` (eq. hybridvel).

The motion equations are eq. (ODE2): ``Vdot = F(t, g, V)`` (a), ``gdot = g V^`` (b).
Convention (as in the paper): right-trivialised ``dexp``, left reconstruction
``V = dexp_{-X} Xdot`` (eqs. VdexpSE3, Vhdexp), hence ``Xdot = dexp^{-1}_{-X} V``
(eq. ODE2left).  One explicit ``s``-stage MK step (eq. MK1), per body::

    Psi_j = h sum_{l<j} a_jl k_l,                 Psi_1 = 0
    g_j   = g exp(Psi_j)
    V_j   = V + h sum_{l<j} a_jl Vdot_l            (same tableau for eq. ODE2a)
    Vdot_j = F(t + c_j h, g_j, V_j)
    k_j   = dexp^{-1}_{-Psi_j} V_j
    g+    = g exp(h sum_j b_j k_j),   V+ = V + h sum_j b_j Vdot_j

The kinematic variant integrates ``gdot = g V(t, g)^`` for a prescribed velocity field.

Domain: any step size whose stage arguments satisfy |Psi_j| < 2 pi
------------------------------------------------------------------
``dexp_{-Psi}`` is singular where the rotation part xi of ``Psi`` has |xi| = 2 pi (and
4 pi, ...): its smallest singular value is |sin(|xi|/2)| / (|xi|/2) (eq. dexpSO3; the SE3
and SO3xR3 blocks share it), so the stage equation ``k_j = dexp^{-1}_{-Psi_j} V_j`` is
undefined there, and the Bernoulli series of ``dexp^{-1}`` (eq. dexpInvSeries) converges
only for |xi| < 2 pi.  The stepper therefore accepts a step only if every stage argument
has |xi(Psi_j)| < :data:`STAGE_ANGLE_MAX` ``= 2 pi (1 - sqrt(eps))`` and raises a
``ValueError`` naming the stage, body, group and step size otherwise.  The margin
2 pi sqrt(eps) = 9.4e-8 rad is where the condition number of dexp,
kappa(t) = (t/2)/|sin(t/2)| ~ 2 pi/(2 pi - t), reaches 1/sqrt(eps) (half of the digits
lost).  The increment ``Phi`` itself is not restricted (exp is defined everywhere).
For a motion along a one-parameter subgroup (the fixed-axis rotation of
tests/test_fixed_axis.py, constant body twist V) ``Psi_j = c_j h V``: an SE3 step is then
exact to round-off for any h with max_j c_j h |omega| < 2 pi (measured over 12 steps with
RK4, DOPRI5, RK6: errors <= 1.2e-13 for 2 pi - c h |omega| down to 9.4e-8; without the
guard up to 3e-13 at 1e-8, 4e-11 at 1e-9, 4e-9 at 1e-10, 1e-4..2e-3 at 1e-12..1e-13,
O(1) at 1e-14; RK4 at h |omega| = 2 pi (the double nearest to it): 4e-2, at 4 pi: 1e7).

This module favours clarity over speed: it is the reference the compiled multibody
kernel and the vector-space formulations (``tests/vector_space_oracle.py``) are compared with.
Group maps come from :mod:`exudyn_lie.groups` (numba-compiled), called per body.
"""
from dataclasses import dataclass
from types import ModuleType
from typing import Optional

import numpy as np

from exudyn_lie.groups import so3
from exudyn_lie.integrators.tableau import get_method

__all__ = [
    "STAGE_ANGLE_MAX",
    "resolve_groups",
    "mk_increment",
    "mk_increment_kinematic",
    "mk_step",
    "mk_step_kinematic",
    "integrate",
    "integrate_kinematic",
    "Trajectory",
    "as_poses",
]

_GROUP_API = ("exp", "compose", "dexpinv_apply_into")

#: Largest rotation angle |xi| of an MK stage argument Psi_j accepted (see the module
#: docstring): 2 pi - 2 pi sqrt(eps), where kappa(dexp) = (t/2)/|sin(t/2)| = 1/sqrt(eps).
STAGE_ANGLE_MAX = so3.DEXP_ANGLE_MAX


# --------------------------------------------------------------------------- helpers
def _groups_table():
    from exudyn_lie.groups import GROUPS, interface
    # the reference stepper integrates 3D poses: the groups whose algebra spans all six axes
    # (not the planar subgroups SE2 / SO2xR2 of the 2D bodies)
    return {k: m for k, m in GROUPS.items() if interface.algebra_axes(m) == tuple(range(6))}


def _resolve_one(gm):
    if isinstance(gm, str):
        table = _groups_table()
        for key, mod in table.items():
            if key.lower() == gm.strip().lower():
                return mod
        raise ValueError(f"unknown c-space group '{gm}'; available: " + ", ".join(table))
    if isinstance(gm, ModuleType) or all(hasattr(gm, a) for a in _GROUP_API):
        missing = [a for a in _GROUP_API if not hasattr(gm, a)]
        if missing:
            raise TypeError(f"group {gm!r} lacks {', '.join(missing)}")
        return gm
    raise TypeError(f"a group must be a group module or one of the names 'SE3'/'SO3xR3', "
                    f"got {gm!r}")


def resolve_groups(groups, n):
    """Per-body group modules from a module / name, or a sequence of them (length ``n``)."""
    if isinstance(groups, (str, ModuleType)):
        groups = [groups] * n
    gms = tuple(_resolve_one(gm) for gm in groups)
    if len(gms) != n:
        raise ValueError(f"{len(gms)} groups given for {n} bodies")
    return gms


def as_poses(g):
    """A list of poses ``(R, r)`` as C-contiguous float64 arrays (copies)."""
    out = []
    for pose in g:
        R, r = pose
        out.append((np.array(R, dtype=np.float64, order="C"),
                    np.array(r, dtype=np.float64, order="C").reshape(3)))
    return out


def _as_velocity(V, n, what="V"):
    V = np.asarray(V, dtype=np.float64)
    if V.size != 6 * n:
        raise ValueError(f"{what} must have shape ({n}, 6), got {V.shape}")
    return np.ascontiguousarray(V.reshape(n, 6))


def _lincomb(coeffs, arrays, upto):
    """sum_{l < upto} coeffs[l] * arrays[l], skipping zero coefficients; None if all zero."""
    acc = None
    for l in range(upto):
        a = coeffs[l]
        if a != 0.0:
            acc = a * arrays[l] if acc is None else acc + a * arrays[l]
    return acc


def _translate(gms, g, X):
    """Poses ``g_i exp(X_i)`` (bodies with ``X_i = 0`` are passed through unchanged)."""
    out = []
    for i, gm in enumerate(gms):
        Xi = X[i]
        if not Xi.any():
            out.append(g[i])
            continue
        Re, re = gm.exp(np.ascontiguousarray(Xi))
        out.append(gm.compose(g[i][0], g[i][1], Re, re))
    return out


def _dexpinv_rows(gms, X, Y, out):
    """``out_i = dexp^{-1}_{X_i} Y_i`` row by row (bodies on their own groups)."""
    for i, gm in enumerate(gms):
        gm.dexpinv_apply_into(np.ascontiguousarray(X[i]), np.ascontiguousarray(Y[i]), out[i])
    return out


def _group_name(gm):
    for key, mod in _groups_table().items():
        if mod is gm:
            return key
    return getattr(gm, "__name__", repr(gm))


def _check_stage_arguments(tab, gms, j, Psi, t, h):
    """Refuse a stage argument whose rotation part reaches STAGE_ANGLE_MAX (dexp singular)."""
    ang = np.sqrt(np.einsum("ij,ij->i", Psi[:, :3], Psi[:, :3]))
    bad = np.flatnonzero(~(ang < STAGE_ANGLE_MAX))          # also catches NaN
    if bad.size == 0:
        return
    i = int(bad[0])
    a = float(ang[i])
    hint = (f"; |Psi| scales with h: h < {h * STAGE_ANGLE_MAX / a:.12g} keeps it below the "
            f"limit, h <= {h * np.pi / a:.12g} keeps it within pi" if np.isfinite(a) and a > 0 else "")
    raise ValueError(
        f"Munthe-Kaas step t = {t:.17g}, h = {h:.17g} ({tab.name}, stage {j + 1}, "
        f"c = {tab.c[j]:g}): the stage argument Psi of body {i} (group {_group_name(gms[i])}) "
        f"has a rotation part |xi| = {a:.17g} rad >= 2 pi - {2 * np.pi - STAGE_ANGLE_MAX:.2g} "
        f"(STAGE_ANGLE_MAX); dexp_(-Psi) is singular at |xi| = 2 pi, so the stage equation "
        f"k = dexp^-1_(-Psi) V (eq. MK1) is undefined. The MK update is defined for stage "
        f"arguments |Psi| < 2 pi: reduce the step size{hint}.")


# --------------------------------------------------------------------------- the MK core
def _mk_core(tab, gms, g, t, h, stage_velocity):
    """Generic explicit MK sweep, eq. (MK1).  Returns the increment ``Phi = h sum b_j k_j``.

    ``stage_velocity(j, t_j, g_j)`` returns the stage velocity ``V_j`` (n, 6).
    """
    n = len(g)
    s = tab.stages
    A, b, c = tab.A, tab.b, tab.c
    K = np.zeros((s, n, 6))
    for j in tab.active_stages:
        psi = _lincomb(A[j], K, j)                      # Psi_j / h
        if psi is None:                                 # Psi_j = 0: g_j = g, k_j = V_j
            Vj = stage_velocity(j, t + c[j] * h, g)
            K[j] = Vj
            continue
        Psi = h * psi                                   # eq. (MK1): Psi_j = h sum a_jl k_l
        _check_stage_arguments(tab, gms, j, Psi, t, h)  # |Psi_j| < 2 pi (module docstring)
        gj = _translate(gms, g, Psi)                    # g_j = g exp(Psi_j)
        Vj = stage_velocity(j, t + c[j] * h, gj)
        _dexpinv_rows(gms, -Psi, Vj, K[j])              # k_j = dexp^{-1}_{-Psi_j} V_j
    return h * _lincomb(b, K, s)                        # Phi = h sum b_j k_j


def _prepare(tableau, groups, g):
    tab = get_method(tableau)
    g = as_poses(g)
    gms = resolve_groups(groups, len(g))
    return tab, gms, g


def _increment_kinematic(tab, gms, g, t, h, vel):
    n = len(g)

    def stage_velocity(j, tj, gj):
        return _as_velocity(vel(tj, gj), n, "vel(t, g)")

    return _mk_core(tab, gms, g, t, h, stage_velocity)


def _increment(tab, gms, g, V, t, h, rhs):
    n = len(g)
    s = tab.stages
    A = tab.A
    Vd = np.zeros((s, n, 6))

    def stage_velocity(j, tj, gj):
        dv = _lincomb(A[j], Vd, j)
        Vj = V if dv is None else V + h * dv                      # V_j = V + h sum a_jl Vdot_l
        Vd[j] = _as_velocity(rhs(tj, gj, Vj), n, "rhs(t, g, V)")  # Vdot_j = F(t_j, g_j, V_j)
        return Vj

    Phi = _mk_core(tab, gms, g, t, h, stage_velocity)
    return Phi, h * _lincomb(tab.b, Vd, s)


def mk_increment_kinematic(tableau, groups, g, t, h, vel):
    """Increment ``Phi`` (n, 6) of one MK step for ``gdot = g V(t, g)^``: ``g+ = g exp(Phi)``."""
    tab, gms, g = _prepare(tableau, groups, g)
    return _increment_kinematic(tab, gms, g, t, h, vel)


def mk_step_kinematic(tableau, groups, g, t, h, vel):
    """One MK step (eq. MK1) for a prescribed velocity field ``vel(t, g) -> V`` (n, 6).

    Returns the new poses ``g exp(Phi)`` as a list of ``(R, r)``.
    """
    tab, gms, g = _prepare(tableau, groups, g)
    return _translate(gms, g, _increment_kinematic(tab, gms, g, t, h, vel))


def mk_increment(tableau, groups, g, V, t, h, rhs):
    """Increments ``(Phi, dV)`` of one MK step of eq. (ODE2): ``g+ = g exp(Phi)``, ``V+ = V + dV``."""
    tab, gms, g = _prepare(tableau, groups, g)
    return _increment(tab, gms, g, _as_velocity(V, len(g)), t, h, rhs)


def mk_step(tableau, groups, g, V, t, h, rhs):
    """One explicit MK step (eq. MK1) of the motion equations (ODE2).

    Parameters
    ----------
    tableau : ButcherTableau or str
    groups : sequence of group modules or names ('SE3', 'SO3xR3'), one per body
        (a single module / name applies to all bodies)
    g : list of (R, r) poses;  V : (n, 6) velocities (see module docstring)
    t, h : time and step size
    rhs : callable ``rhs(t, g, V) -> Vdot`` (n, 6)

    Returns ``(g_new, V_new)``.  Raises ``ValueError`` if a stage argument leaves the
    domain |xi(Psi_j)| < STAGE_ANGLE_MAX (module docstring).
    """
    tab, gms, g = _prepare(tableau, groups, g)
    V = _as_velocity(V, len(g))
    Phi, dV = _increment(tab, gms, g, V, t, h, rhs)
    return _translate(gms, g, Phi), V + dV


# --------------------------------------------------------------------------- trajectories
@dataclass
class Trajectory:
    """Stored states: ``t`` (m,), ``R`` (m, n, 3, 3), ``r`` (m, n, 3), ``V`` (m, n, 6) or None.

    ``info`` carries formulation-specific extras (e.g. the number of chart re-centrings).
    """

    t: np.ndarray
    R: np.ndarray
    r: np.ndarray
    V: Optional[np.ndarray] = None
    info: Optional[dict] = None

    def pose(self, k=-1):
        """Poses at stored index ``k`` as a list of ``(R, r)``."""
        return [(self.R[k, i].copy(), self.r[k, i].copy()) for i in range(self.R.shape[1])]

    @property
    def final_pose(self):
        return self.pose(-1)


def _run(step, state, V, poses_of, t_span, n_steps, every):
    """Fixed-step driver shared by all formulations.

    ``step(state, V, t, h) -> (state, V)`` (``V`` is None for kinematic runs);
    ``poses_of(state)`` -> list of (R, r).
    """
    t0, t1 = float(t_span[0]), float(t_span[1])
    n_steps = int(n_steps)
    if n_steps < 1:
        raise ValueError("n_steps must be >= 1")
    every = max(1, int(every))
    h = (t1 - t0) / n_steps
    ts, Rs, rs, Vs = [], [], [], []

    def store(k, state, V):
        ts.append(t0 + k * h)
        p = poses_of(state)
        Rs.append(np.array([R for R, _ in p]))
        rs.append(np.array([r for _, r in p]))
        if V is not None:
            Vs.append(np.array(V, dtype=np.float64))

    store(0, state, V)
    for k in range(n_steps):
        state, V = step(state, V, t0 + k * h, h)
        if (k + 1) % every == 0 or k + 1 == n_steps:
            store(k + 1, state, V)
    traj = Trajectory(np.array(ts), np.array(Rs), np.array(rs),
                      np.array(Vs) if Vs else None)
    return traj, state


def integrate(tableau, groups, g0, V0, rhs, t_span, n_steps, every=1):
    """Integrate eq. (ODE2) with ``n_steps`` fixed MK steps over ``t_span = (t0, t1)``.

    Returns a :class:`Trajectory` (every ``every``-th state plus the final one).
    """
    tab, gms, g0 = _prepare(tableau, groups, g0)
    V0 = _as_velocity(V0, len(g0))

    def step(g, V, t, h):
        Phi, dV = _increment(tab, gms, g, V, t, h, rhs)
        return _translate(gms, g, Phi), V + dV

    traj, _ = _run(step, g0, V0, lambda g: g, t_span, n_steps, every)
    return traj


def integrate_kinematic(tableau, groups, g0, vel, t_span, n_steps, every=1):
    """Integrate ``gdot = g V(t, g)^`` with fixed MK steps; returns a :class:`Trajectory`."""
    tab, gms, g0 = _prepare(tableau, groups, g0)

    def step(g, V, t, h):
        return _translate(gms, g, _increment_kinematic(tab, gms, g, t, h, vel)), None

    traj, _ = _run(step, g0, None, lambda g: g, t_span, n_steps, every)
    return traj
