"""The paper's vector-space formulations of the motion equations, for comparison with MK: a test
oracle (the library integrates on the groups only).

Two formulations are provided, each integrated by a *plain* explicit Runge-Kutta method
(the same Butcher tableaus as the MK stepper) on a vector space, and each exposing the
same step / integrate interface as :mod:`.mk` (results converted back to poses (R, r)):

(a) **Local canonical coordinates**, eq. (ODEvec1)::

        Vdot = F(t, g, V)                       (ODEvec1a)
        qdot = dexp^{-1}_{-q} V                 (ODEvec1b)

    ``q`` (n, 6) are exponential coordinates of every body relative to a chart origin
    ``g0``: ``g = g0 exp(q)`` -- screw coordinates ``(xi, eta)`` for SE3, ``(xi, r)`` for
    SO3xR3.  Exponential coordinates are only unique for ``|xi| < pi`` and ``dexp^{-1}``
    blows up at ``|xi| = 2 pi``; therefore the chart is **re-centred** (reparameterised)
    before ``|xi|`` reaches ``pi`` (:data:`CHART_ANGLE_MAX`).  Re-centring body ``i`` means
    ``g0_i := g0_i exp(q_i)``, ``q_i := 0`` (exact: the pose is unchanged).  Rules:

    1. after every step, each body with ``|xi_i| >= recenter_angle`` (default ``pi/2``) is
       re-centred (the usual case: keeps the charts small);
    2. guarantee: ``|xi_i| < pi`` at every stage value the RK step evaluates and at the
       step end.  If a step would carry a body's coordinate to ``|xi_i| >= pi`` (e.g. a
       step that rotates more than ``pi/2`` starting from ``|xi_i|`` just below
       ``recenter_angle``), that body is re-centred at the start of the step and the step
       is redone; if the body's chart is already centred there (``q_i = 0``: the step
       itself rotates by about ``pi`` or more) or re-centring is disabled
       (``recenter_angle = inf``), a ``ValueError`` naming the step is raised.

    ``recenter_angle = inf`` keeps one global chart (the paper's remark at the end of
    appendix B: RK on (BH2) == MK with global coordinates ``g_i = g0 exp(q^(i))``), valid
    until ``|xi|`` reaches ``pi``; ``recenter_angle = 0`` re-centres after every step,
    which makes the scheme identical to the MK method (eq. MK1).  ``ChartState.max_angle``
    (``info['max_stage_angle']`` of a trajectory) is the largest ``|xi|`` used.

(b) **Dependent (redundant) coordinates**, eq. (ODEvec2)::

        Vdot = F(t, g, V),     qdot = H^{-1}(q) V

    SO3xR3 bodies use Euler parameters and the position, ``x = (Q, r)`` (7 numbers,
    eq. Hh): ``Qdot`` from the body-fixed angular velocity, ``rdot = v`` (mixed velocity);
    SE3 bodies use unit dual quaternions ``Qh = (Q, Q_eps)`` (8 numbers, eqs. DE, Qpos,
    Hdual) driven by the body-fixed twist.  With ``normalize=True`` (default) every step
    ends with a projection onto the constraint manifold: ``Q := Q / |Q|`` (and
    ``Q_eps := Q_eps / |Q|`` for dual quaternions) followed by restoring the Pluecker
    condition ``Q . Q_eps = 0`` via ``Q_eps := Q_eps - (Q . Q_eps) Q``.  This projection
    leaves the represented position ``r = 2 vec(Q_eps Q*)`` unchanged.  At the stages
    (not projected) the poses handed to ``F`` are computed from ``Q / |Q|``.

Note: the paper's matrix (Hh) carries a factor 2 on the ``I_3`` block as well; the
position rate of the mixed velocity is ``rdot = v`` (eq. hybridvel), which is used here.
"""
from dataclasses import dataclass, field

import numpy as np

from reference_mk import _as_velocity, _run, _translate, as_poses, resolve_groups
from exudyn_lie.integrators.tableau import get_method

__all__ = [
    "RECENTER_ANGLE",
    "CHART_ANGLE_MAX",
    "rk_step",
    "rk_integrate",
    "ChartState",
    "chart_from_poses",
    "chart_poses",
    "canonical_step",
    "canonical_step_kinematic",
    "canonical_integrate",
    "canonical_integrate_kinematic",
    "DependentState",
    "dependent_from_poses",
    "dependent_poses",
    "dependent_step",
    "dependent_step_kinematic",
    "dependent_integrate",
    "dependent_integrate_kinematic",
]

#: Default re-centring threshold for the rotation part of the canonical coordinates.
RECENTER_ANGLE = 0.5 * np.pi
#: Bound on |xi| of the canonical coordinates at every stage and step end (exclusive):
#: exp is one-to-one on |xi| < pi, the chart is reparameterised before |xi| reaches pi.
CHART_ANGLE_MAX = np.pi


# --------------------------------------------------------------------------- plain RK
def rk_step(tableau, f, t, y, h):
    """One explicit Runge-Kutta step ``y+ = y + h sum_j b_j f(t + c_j h, Y_j)`` (any shape)."""
    tab = get_method(tableau)
    A, b, c = tab.A, tab.b, tab.c
    y = np.asarray(y, dtype=np.float64)
    s = tab.stages
    F = [None] * s
    inc = None
    for j in tab.active_stages:
        Yj = y
        for l in range(j):
            if A[j, l] != 0.0:
                Yj = Yj + (h * A[j, l]) * F[l]
        F[j] = np.asarray(f(t + c[j] * h, Yj), dtype=np.float64)
        if b[j] != 0.0:
            inc = b[j] * F[j] if inc is None else inc + b[j] * F[j]
    return y + h * inc


def rk_integrate(tableau, f, y0, t_span, n_steps):
    """Fixed-step RK integration; returns ``(t, Y)`` with ``Y[k]`` the state at ``t[k]``."""
    tab = get_method(tableau)
    t0, t1 = float(t_span[0]), float(t_span[1])
    h = (t1 - t0) / int(n_steps)
    y = np.array(y0, dtype=np.float64)
    Y = [y]
    for k in range(int(n_steps)):
        y = rk_step(tab, f, t0 + k * h, y, h)
        Y.append(y)
    return t0 + h * np.arange(int(n_steps) + 1), np.array(Y)


def _split(y, n):
    return y[: 6 * n].reshape(n, 6), y[6 * n:].reshape(n, 6)


# --------------------------------------------------------------------------- (a) ODEvec1
@dataclass
class ChartState:
    """State of eq. (ODEvec1): chart origins ``origin`` (poses), coordinates ``q`` (n, 6).

    The represented poses are ``origin_i exp(q_i)``; ``n_recentred`` counts re-centrings,
    ``max_angle`` is the largest ``|xi_i|`` of any stage value or step end so far.
    """

    origin: list
    q: np.ndarray
    n_recentred: int = 0
    max_angle: float = 0.0


def chart_from_poses(g):
    """A chart centred at the poses ``g`` (``q = 0``)."""
    g = as_poses(g)
    return ChartState(origin=g, q=np.zeros((len(g), 6)))


def chart_poses(groups, state):
    """Poses ``origin_i exp(q_i)`` represented by a :class:`ChartState`."""
    gms = resolve_groups(groups, len(state.origin))
    return _translate(gms, state.origin, state.q)


def _as_chart(state):
    return state if isinstance(state, ChartState) else chart_from_poses(state)


def _qdot(gms, q, V):
    """eq. (ODEvec1b): ``qdot_i = dexp^{-1}_{-q_i} V_i``."""
    out = np.empty_like(q)
    for i, gm in enumerate(gms):
        gm.dexpinv_apply_into(np.ascontiguousarray(-q[i]), np.ascontiguousarray(V[i]), out[i])
    return out


def _recentre(gms, state, q, recenter_angle, bodies=None):
    """Exact chart change ``g0_i := g0_i exp(q_i), q_i := 0`` where ``|xi_i| >= angle``
    (or for the listed ``bodies``)."""
    origin = list(state.origin)
    q = np.array(q)
    count = state.n_recentred
    for i, gm in enumerate(gms):
        if not q[i].any():
            continue
        if (i in bodies) if bodies is not None else np.linalg.norm(q[i, :3]) >= recenter_angle:
            Re, re = gm.exp(np.ascontiguousarray(q[i]))
            origin[i] = gm.compose(origin[i][0], origin[i][1], Re, re)
            q[i] = 0.0
            count += 1
    return ChartState(origin=origin, q=q, n_recentred=count, max_angle=state.max_angle)


class _ChartLimit(Exception):
    """A chart coordinate reached |xi| >= CHART_ANGLE_MAX (caught by _chart_rk_step)."""

    def __init__(self, body, angle, where):
        super().__init__(body, angle, where)
        self.body, self.angle, self.where = body, angle, where


def _chart_angles(q, where, record):
    """|xi_i| of every body; raises _ChartLimit at the first body with |xi_i| >= pi."""
    ang = np.sqrt(np.einsum("ij,ij->i", q[:, :3], q[:, :3]))
    bad = np.flatnonzero(~(ang < CHART_ANGLE_MAX))
    if bad.size:
        raise _ChartLimit(int(bad[0]), float(ang[bad[0]]), where)
    record[0] = max(record[0], float(ang.max(initial=0.0)))


def _chart_rk_step(tab, gms, state, t, h, make_f, tail, recenter_angle):
    """One plain RK step of ``y = (q, tail)`` with the chart guard (module docstring, rule 2).

    ``make_f(origin)`` -> ``f(t, y)`` for the chart origins ``origin``.  Returns
    ``(ChartState, y_new)`` (not yet re-centred by rule 1).
    """
    n = len(gms)
    while True:
        record = [0.0]
        f = make_f(state.origin)

        def guarded(tj, y, f=f, record=record):
            _chart_angles(y[:6 * n].reshape(n, 6), "at a stage", record)
            return f(tj, y)

        try:
            y = rk_step(tab, guarded, t, np.concatenate([state.q.ravel(), tail]), h)
            _chart_angles(y[:6 * n].reshape(n, 6), "at the step end", record)
        except _ChartLimit as e:
            if np.isfinite(recenter_angle) and state.q[e.body].any():
                state = _recentre(gms, state, state.q, recenter_angle, bodies=(e.body,))
                continue                     # redo the step in the re-centred chart
            why = ("re-centring is disabled (recenter_angle = inf: one global chart)"
                   if not np.isfinite(recenter_angle) else
                   "even in a chart centred at the start of the step: the step rotates the "
                   "body by about pi or more")
            raise ValueError(
                f"ODEvec1 (local canonical coordinates) step t = {t:.17g}, h = {h:.17g} "
                f"({tab.name}): the chart coordinate of body {e.body} would reach "
                f"|xi| = {e.angle:.6g} rad >= pi {e.where}, {why}. Exponential coordinates "
                f"are unique only for |xi| < pi and the chart must be reparameterised "
                f"before |xi| reaches pi: reduce the step size") from None
        state = ChartState(origin=state.origin, q=state.q, n_recentred=state.n_recentred,
                           max_angle=max(state.max_angle, record[0]))
        return state, y


def canonical_step(tableau, groups, state, V, t, h, rhs, recenter_angle=RECENTER_ANGLE):
    """One plain RK step of eq. (ODEvec1) on ``(q, V)``, then chart re-centring.

    ``state``: a :class:`ChartState` (or a list of poses: a fresh chart is centred there).
    Returns ``(ChartState, V_new)``; poses via :func:`chart_poses`.  Raises ``ValueError``
    if the step would carry ``|xi|`` to ``pi`` (module docstring, rule 2).
    """
    tab = get_method(tableau)
    state = _as_chart(state)
    n = len(state.origin)
    gms = resolve_groups(groups, n)
    V = _as_velocity(V, n)

    def make_f(origin):
        def f(tj, y):
            q, Vj = _split(y, n)
            gj = _translate(gms, origin, q)                              # g = g0 exp(q)
            Vdot = _as_velocity(rhs(tj, gj, Vj), n, "rhs(t, g, V)")     # eq. (ODEvec1a)
            return np.concatenate([_qdot(gms, q, Vj).ravel(), Vdot.ravel()])
        return f

    state, y = _chart_rk_step(tab, gms, state, t, h, make_f, V.ravel(), recenter_angle)
    q, V_new = _split(y, n)
    return _recentre(gms, state, q, recenter_angle), V_new.copy()


def canonical_step_kinematic(tableau, groups, state, t, h, vel, recenter_angle=RECENTER_ANGLE):
    """One plain RK step of ``qdot = dexp^{-1}_{-q} V(t, g0 exp(q))`` (eq. ODEvec1b)."""
    tab = get_method(tableau)
    state = _as_chart(state)
    n = len(state.origin)
    gms = resolve_groups(groups, n)

    def make_f(origin):
        def f(tj, y):
            q = y.reshape(n, 6)
            Vj = _as_velocity(vel(tj, _translate(gms, origin, q)), n, "vel(t, g)")
            return _qdot(gms, q, Vj).ravel()
        return f

    state, y = _chart_rk_step(tab, gms, state, t, h, make_f, np.empty(0), recenter_angle)
    return _recentre(gms, state, y.reshape(n, 6), recenter_angle)


def canonical_integrate(tableau, groups, g0, V0, rhs, t_span, n_steps, every=1,
                        recenter_angle=RECENTER_ANGLE):
    """Integrate eq. (ODEvec1) with fixed RK steps; returns a :class:`~reference_mk.Trajectory`.

    ``info['n_recentred']`` is the total number of chart re-centrings,
    ``info['max_stage_angle']`` the largest ``|xi|`` of any stage value or step end.
    """
    tab = get_method(tableau)
    g0 = as_poses(g0)
    gms = resolve_groups(groups, len(g0))

    def step(st, V, t, h):
        return canonical_step(tab, gms, st, V, t, h, rhs, recenter_angle)

    traj, st = _run(step, chart_from_poses(g0), _as_velocity(V0, len(g0)),
                    lambda s_: chart_poses(gms, s_), t_span, n_steps, every)
    traj.info = {"n_recentred": st.n_recentred, "max_stage_angle": st.max_angle}
    return traj


def canonical_integrate_kinematic(tableau, groups, g0, vel, t_span, n_steps, every=1,
                                  recenter_angle=RECENTER_ANGLE):
    """Kinematic counterpart of :func:`canonical_integrate`."""
    tab = get_method(tableau)
    g0 = as_poses(g0)
    gms = resolve_groups(groups, len(g0))

    def step(st, V, t, h):
        return canonical_step_kinematic(tab, gms, st, t, h, vel, recenter_angle), None

    traj, st = _run(step, chart_from_poses(g0), None, lambda s_: chart_poses(gms, s_),
                    t_span, n_steps, every)
    traj.info = {"n_recentred": st.n_recentred, "max_stage_angle": st.max_angle}
    return traj


# --------------------------------------------------------------------------- (b) ODEvec2
def _kinds(gms):
    """'dq' (dual quaternion, SE3) or 'ep' (Euler parameters + position, SO3xR3) per body."""
    from exudyn_lie.groups import GROUPS
    kinds = []
    for gm in gms:
        if gm is GROUPS.get("SE3"):
            kinds.append("dq")
        elif gm is GROUPS.get("SO3xR3"):
            kinds.append("ep")
        else:
            raise ValueError(f"no dependent-coordinate representation for group {gm!r}")
    return tuple(kinds)


def _layout(kinds):
    offs, o = [], 0
    for k in kinds:
        offs.append(o)
        o += 8 if k == "dq" else 7
    return tuple(offs), o


@dataclass
class DependentState:
    """State of eq. (ODEvec2): the flat coordinate vector ``x`` of all bodies.

    Body ``i`` occupies ``x[offsets[i]:...]``: 8 dual-quaternion entries ``(Q, Q_eps)`` for
    SE3 bodies, 7 entries ``(Q, r)`` for SO3xR3 bodies (Q scalar first).
    """

    x: np.ndarray
    kinds: tuple
    offsets: tuple = field(default=())

    def __post_init__(self):
        self.kinds = tuple(self.kinds)
        offs, size = _layout(self.kinds)
        if not self.offsets:
            self.offsets = offs
        self.x = np.asarray(self.x, dtype=np.float64)
        if self.x.shape != (size,) or tuple(self.offsets) != offs:
            raise ValueError(f"DependentState: x must have shape ({size},) for kinds "
                             f"{self.kinds}, got {self.x.shape}")

    def body(self, i):
        o = self.offsets[i]
        return self.x[o:o + (8 if self.kinds[i] == "dq" else 7)]


def _quat():
    from exudyn_lie.groups import quaternion
    return quaternion


def _dualquat():
    import dualquat_oracle as dualquat
    return dualquat


def dependent_from_poses(groups, g):
    """Dependent coordinates of the poses ``g`` (Euler parameters / dual quaternions)."""
    g = as_poses(g)
    gms = resolve_groups(groups, len(g))
    kinds = _kinds(gms)
    offs, size = _layout(kinds)
    x = np.empty(size)
    for i, (R, r) in enumerate(g):
        o = offs[i]
        if kinds[i] == "dq":
            x[o:o + 8] = _dualquat().from_pose(R, r)
        else:
            x[o:o + 4] = _quat().from_matrix(R)
            x[o + 4:o + 7] = r
    return DependentState(x=x, kinds=kinds, offsets=offs)


def _poses_of_x(kinds, offs, x):
    """Poses represented by the (possibly not normalised) coordinates ``x``."""
    out = []
    for i, k in enumerate(kinds):
        o = offs[i]
        if k == "dq":
            Qh = x[o:o + 8]
            nQ = np.linalg.norm(Qh[:4])
            R, r = _dualquat().to_pose(np.ascontiguousarray(Qh / nQ))
            out.append((np.asarray(R), np.asarray(r)))
        else:
            Q = x[o:o + 4]
            R = _quat().to_matrix(np.ascontiguousarray(Q / np.linalg.norm(Q)))
            out.append((np.asarray(R), np.array(x[o + 4:o + 7])))
    return out


def dependent_poses(groups, state):
    """Poses ``(R, r)`` represented by a :class:`DependentState` (``groups`` is accepted for
    symmetry with :func:`chart_poses`; the state carries its own layout)."""
    return _poses_of_x(state.kinds, state.offsets, state.x)


def _xdot(kinds, offs, x, V):
    """eq. (ODEvec2b): ``xdot = H^{-1}(x) V`` body by body (eqs. Hdual, Hh)."""
    quat = _quat()
    dq_rate = _dualquat().qhdot_from_twist        # Qhdot = 1/2 Qh (0, omega; 0, v)
    out = np.empty_like(x)
    for i, k in enumerate(kinds):
        o = offs[i]
        Vi = np.ascontiguousarray(V[i])
        if k == "dq":
            out[o:o + 8] = dq_rate(np.ascontiguousarray(x[o:o + 8]), Vi)
        else:
            out[o:o + 4] = quat.qdot_from_omega(np.ascontiguousarray(x[o:o + 4]),
                                                np.ascontiguousarray(Vi[:3]))
            out[o + 4:o + 7] = Vi[3:]                    # rdot = v (mixed velocity)
    return out


def _normalise(kinds, offs, x):
    """Projection onto |Q| = 1 and (dual quaternions) the Pluecker condition Q . Q_eps = 0."""
    x = np.array(x)
    for i, k in enumerate(kinds):
        o = offs[i]
        nQ = np.linalg.norm(x[o:o + 4])
        if k == "dq":
            x[o:o + 8] /= nQ
            Q, Qe = x[o:o + 4], x[o + 4:o + 8]
            Qe -= np.dot(Q, Qe) * Q
        else:
            x[o:o + 4] /= nQ
    return x


def _as_dependent(groups, state):
    if not isinstance(state, DependentState):
        return dependent_from_poses(groups, state)
    kinds = _kinds(resolve_groups(groups, len(state.kinds)))
    if kinds != state.kinds:
        raise ValueError(f"state representation {state.kinds} does not match the groups "
                         f"({kinds})")
    return state


def dependent_step(tableau, groups, state, V, t, h, rhs, normalize=True):
    """One plain RK step of eq. (ODEvec2) on ``(x, V)``; optional projection (normalize).

    ``state``: a :class:`DependentState` (or a list of poses, converted first).
    Returns ``(DependentState, V_new)``; poses via :func:`dependent_poses`.
    """
    tab = get_method(tableau)
    state = _as_dependent(groups, state)
    kinds, offs = state.kinds, state.offsets
    n = len(kinds)
    V = _as_velocity(V, n)
    m = state.x.size

    def f(tj, y):
        x, Vj = y[:m], y[m:].reshape(n, 6)
        gj = _poses_of_x(kinds, offs, x)
        Vdot = _as_velocity(rhs(tj, gj, Vj), n, "rhs(t, g, V)")    # eq. (ODEvec2a)
        return np.concatenate([_xdot(kinds, offs, x, Vj), Vdot.ravel()])

    y = rk_step(tab, f, t, np.concatenate([state.x, V.ravel()]), h)
    x = _normalise(kinds, offs, y[:m]) if normalize else y[:m].copy()
    return DependentState(x=x, kinds=kinds, offsets=offs), y[m:].reshape(n, 6).copy()


def dependent_step_kinematic(tableau, groups, state, t, h, vel, normalize=True):
    """One plain RK step of ``xdot = H^{-1}(x) V(t, g(x))`` (eq. ODEvec2b)."""
    tab = get_method(tableau)
    state = _as_dependent(groups, state)
    kinds, offs = state.kinds, state.offsets
    n = len(kinds)

    def f(tj, x):
        Vj = _as_velocity(vel(tj, _poses_of_x(kinds, offs, x)), n, "vel(t, g)")
        return _xdot(kinds, offs, x, Vj)

    x = rk_step(tab, f, t, state.x, h)
    if normalize:
        x = _normalise(kinds, offs, x)
    return DependentState(x=x, kinds=kinds, offsets=offs)


def dependent_integrate(tableau, groups, g0, V0, rhs, t_span, n_steps, every=1,
                        normalize=True):
    """Integrate eq. (ODEvec2) with fixed RK steps; returns a :class:`~reference_mk.Trajectory`.

    ``info['x']`` holds the final dependent coordinates.
    """
    tab = get_method(tableau)
    g0 = as_poses(g0)
    gms = resolve_groups(groups, len(g0))

    def step(st, V, t, h):
        return dependent_step(tab, gms, st, V, t, h, rhs, normalize)

    traj, st = _run(step, dependent_from_poses(gms, g0), _as_velocity(V0, len(g0)),
                    lambda s_: dependent_poses(gms, s_), t_span, n_steps, every)
    traj.info = {"x": st.x.copy()}
    return traj


def dependent_integrate_kinematic(tableau, groups, g0, vel, t_span, n_steps, every=1,
                                  normalize=True):
    """Kinematic counterpart of :func:`dependent_integrate`."""
    tab = get_method(tableau)
    g0 = as_poses(g0)
    gms = resolve_groups(groups, len(g0))

    def step(st, V, t, h):
        return dependent_step_kinematic(tab, gms, st, t, h, vel, normalize), None

    traj, st = _run(step, dependent_from_poses(gms, g0), None,
                    lambda s_: dependent_poses(gms, s_), t_span, n_steps, every)
    traj.info = {"x": st.x.copy()}
    return traj
