"""Vector-space formulations (eqs. ODEvec1, ODEvec2) versus the MK method (eq. MK1).

Problems (exact solutions, independent of the package's group maps):
* the torque-free symmetric top with COM offset under gravity (as in
  test_mk_convergence.py), one SE3 body and one SO3xR3 body;
* the paper's fixed-axis rotation (eq. TrapSol).
"""
import numpy as np
import pytest

import dualquat_oracle as dualquat
from exudyn_lie.groups import quaternion
from exudyn_lie.integrators import METHODS
import reference_mk as mk
import vector_space_oracle as vs
from test_mk_convergence import memo, step_counts

GROUPS = ["SE3", "SO3xR3"]


# --------------------------------------------------------------------------- oracles
def cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def hat3(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def rodrigues(w):
    t = np.linalg.norm(w)
    if t == 0.0:
        return np.eye(3)
    K = hat3(w / t)
    return np.eye(3) + np.sin(t) * K + (1.0 - np.cos(t)) * K @ K


def pose_errors(g, g_exact):
    return np.array([max(np.abs(R - Re).max(), np.abs(r - re).max())
                     for (R, r), (Re, re) in zip(g, g_exact)])


# symmetric top (I1 = I2) about its COM, frame origin offset by -d from the COM, gravity
THETA = np.diag([0.4, 0.4, 0.7])
THETA_INV = np.linalg.inv(THETA)
D_COM = np.array([0.2, -0.1, 0.3])
GRAV = np.array([0.0, 0.0, -9.81])
W0 = np.array([1.2, -0.7, 2.0])
VC0 = np.array([0.5, 0.3, 1.0])
RC0 = np.array([0.1, 0.2, 0.3])
LAM = (THETA[2, 2] - THETA[0, 0]) * W0[2] / THETA[0, 0]
E3 = np.array([0.0, 0.0, 1.0])


def top_exact(t):
    R = rodrigues(t * (W0 + LAM * E3)) @ rodrigues(-LAM * t * E3)
    w = rodrigues(LAM * t * E3) @ W0
    r = RC0 + VC0 * t + 0.5 * t * t * GRAV - R @ D_COM
    rdot = VC0 + GRAV * t - R @ cross(w, D_COM)
    return ([(R, r), (R.copy(), r.copy())],
            np.array([np.concatenate([w, R.T @ rdot]), np.concatenate([w, rdot])]))


def top_rhs(t, g, V):
    out = np.empty((2, 6))
    for i in range(2):
        R, _ = g[i]
        w, v = V[i, :3], V[i, 3:]
        wd = -THETA_INV @ cross(w, THETA @ w)
        out[i, :3] = wd
        if i == 0:      # SE3, body-fixed twist
            out[i, 3:] = -cross(w, v + cross(w, D_COM)) + R.T @ GRAV - cross(wd, D_COM)
        else:           # SO3xR3, mixed velocity
            out[i, 3:] = GRAV - R @ cross(w, cross(w, D_COM)) - R @ cross(wd, D_COM)
    return out


def top_errors(traj):
    """Max over the stored grid of pose and velocity errors, per body."""
    errs = []
    for k, t in enumerate(traj.t):
        g_ex, V_ex = top_exact(t)
        errs.append(np.maximum(pose_errors(traj.pose(k), g_ex),
                               np.abs(traj.V[k] - V_ex).max(axis=1)))
    return np.max(errs, axis=0)


# fixed axis (eq. TrapSol)
XI = np.array([1.0, 2.0, 2.0]) / 3.0
P = np.array([0.4, -0.3, 1.1])
OMEGA0 = 1.3
V_BODY = np.concatenate([OMEGA0 * XI, OMEGA0 * np.cross(P, XI)])
G_ID = [(np.eye(3), np.zeros(3))]


def axis_exact(t):
    R = rodrigues(OMEGA0 * t * XI)
    return R, P - R @ P


def vel_se3(t, g):
    return V_BODY[None, :]


def vel_mixed(t, g):
    return np.concatenate([OMEGA0 * XI, g[0][0] @ np.cross(P, OMEGA0 * XI)])[None, :]


def joint_violation(R, r):
    return max(np.abs(r + R @ P - P).max(), np.abs(R @ XI - XI).max())


# step counts: the order-derived rule of test_mk_convergence.py (pilot run + C h^p model)
N_CAP = 128


def slope(Ns, errs, T=1.0):
    return np.polyfit(np.log(T / np.asarray(Ns, float)), np.log(errs), 1)[0]


def assert_slope(Ns, errs, order, what):
    errs = np.asarray(errs)
    assert np.all(errs > 1e-15), f"{what}: round-off reached {errs}"
    s = slope(Ns, errs)
    assert order - 0.3 <= s <= order + 0.5, f"{what}: slope {s:.3f}, expected {order} ({errs})"


# --------------------------------------------------------------------------- ODEvec1
@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_canonical_recentred_every_step_is_mk(method):
    """recenter_angle = 0: q restarts at 0 every step, so RK on eq. (ODEvec1) is eq. (MK1)."""
    g0, V0 = top_exact(0.0)
    a = mk.integrate(method, GROUPS, g0, V0, top_rhs, (0.0, 1.0), 10)
    b = vs.canonical_integrate(method, GROUPS, g0, V0, top_rhs, (0.0, 1.0), 10,
                               recenter_angle=0.0)
    for k in range(len(a.t)):
        assert pose_errors(a.pose(k), b.pose(k)).max() < 1e-13
    np.testing.assert_allclose(a.V, b.V, rtol=0, atol=1e-13)
    assert b.info["n_recentred"] == 2 * 10


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_canonical_order_and_agreement_with_mk(method):
    g0, V0 = top_exact(0.0)

    @memo
    def run(N):
        return vs.canonical_integrate(method, GROUPS, g0, V0, top_rhs, (0.0, 1.0), N,
                                      every=N // 2)

    Ns = step_counts(method.order, 1.0, lambda N: top_errors(run(N)).min(), N_CAP)
    e_can, e_mk, diffs = [], [], []
    for N in Ns:
        can = run(N)
        ref = mk.integrate(method, GROUPS, g0, V0, top_rhs, (0.0, 1.0), N, every=N // 2)
        assert can.info["n_recentred"] >= 2          # |xi| passes pi/2 within t <= 1
        e_can.append(top_errors(can))
        e_mk.append(top_errors(ref))
        diffs.append(np.max([pose_errors(can.pose(k), ref.pose(k))
                             for k in range(len(can.t))], axis=0))
    e_can, e_mk, diffs = map(np.array, (e_can, e_mk, diffs))
    for i, name in enumerate(GROUPS):
        assert_slope(Ns, e_can[:, i], method.order, f"{method.name} ODEvec1 {name}")
        # both are O(h^p) approximations of the same solution
        assert np.all(diffs[:, i] <= e_can[:, i] + e_mk[:, i] + 1e-14)
        assert np.all(e_can[:, i] <= 10.0 * e_mk[:, i] + 1e-13)
        assert np.all(e_mk[:, i] <= 10.0 * e_can[:, i] + 1e-13)


MANY_TURNS_T, MANY_TURNS_N = 12.0, 600     # the attitude turns ~7 times (|xi| would reach 45)


def test_canonical_survives_many_turns():
    """Re-centring whenever |xi| >= pi/2 keeps eq. (ODEvec1) as accurate as MK."""
    T, N = MANY_TURNS_T, MANY_TURNS_N
    g0, V0 = top_exact(0.0)
    traj = vs.canonical_integrate("RK4", GROUPS, g0, V0, top_rhs, (0.0, T), N, every=N // 8)
    assert traj.info["n_recentred"] > 2 * 14
    assert np.all(np.isfinite(traj.R)) and np.all(np.isfinite(traj.r))
    errs = top_errors(traj)
    ref = top_errors(mk.integrate("RK4", GROUPS, g0, V0, top_rhs, (0.0, T), N, every=N // 8))
    assert np.all(errs < 1e-3)          # the COM falls to ~120 m/s: errors ~1e-4
    assert np.all(errs < 2 * ref + 1e-12)


def test_canonical_global_chart_refused_at_pi():
    """Without re-centring, the global chart (paper's remark, appendix B) would leave the
    domain |xi| < pi of unique exponential coordinates after about half a turn (and run
    into the dexp^{-1} singularity at 2 pi): the step that would carry |xi| to pi is
    refused with a ValueError naming it."""
    T, N = MANY_TURNS_T, MANY_TURNS_N
    g0, V0 = top_exact(0.0)
    with pytest.raises(ValueError, match=r"ODEvec1.*step t = .*h = 0\.02 .*body \d.*>= pi.*"
                                         r"recenter_angle = inf"):
        vs.canonical_integrate("RK4", GROUPS, g0, V0, top_rhs, (0.0, T), N,
                               every=N // 8, recenter_angle=np.inf)


# --- |xi| < pi at every stage: a fixed-axis rotation with growing angular speed
# omega(t) = W_A + W_B t: the steps of h = 1 rotate by 1.4, 1.8, 2.2, 2.6, 3.0, 3.4 rad.
# Step 1 ends at |xi| = 1.4 < pi/2 (no re-centring by rule 1), step 2 would carry it to
# 3.2 > pi: the guard re-centres at the step start and redoes the step.  Step 6 rotates
# by more than pi itself: refused.
W_A, W_B = 1.2, 0.4


def ramp_angle(t):
    return W_A * t + 0.5 * W_B * t * t


def ramp_exact(t):
    R = rodrigues(ramp_angle(t) * XI)
    return R, P - R @ P


def ramp_vel(t, g):
    return ((W_A + W_B * t) / OMEGA0 * V_BODY)[None, :]


@pytest.fixture
def stage_angles(monkeypatch):
    """Spy on eq. (ODEvec1b): the |xi| of every chart coordinate at which dexp^{-1}_{-q}
    (hence the velocity field / rhs) is evaluated."""
    seen = []
    qdot = vs._qdot

    def spy(gms, q, V):
        seen.extend(np.linalg.norm(q[:, :3], axis=1))
        return qdot(gms, q, V)

    monkeypatch.setattr(vs, "_qdot", spy)
    return seen


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_canonical_chart_below_pi_at_every_stage(method, stage_angles):
    traj = vs.canonical_integrate_kinematic(method, ["SE3"], G_ID, ramp_vel, (0.0, 4.0), 4)
    assert len(stage_angles) >= 4 * len(method.active_stages)
    assert max(stage_angles) < np.pi           # every evaluation, also of redone steps
    assert 2.4 < traj.info["max_stage_angle"] < np.pi      # accepted stages + step ends
    # rule 1 re-centres after steps 2, 3, 4; the guard once more at the start of step 2,
    # where q would reach ramp_angle(2) = 3.2 (explicit Euler: 1.2 + 1.6 = 2.8 < pi)
    assert traj.info["n_recentred"] == (3 if method.name == "ExplicitEuler" else 4)
    if method.quadrature_order >= 2:                      # q' = V(t) linear in t: exact
        for k, t in enumerate(traj.t):
            R_ex, r_ex = ramp_exact(t)
            assert np.abs(traj.R[k, 0] - R_ex).max() < 1e-12
            assert np.abs(traj.r[k, 0] - r_ex).max() < 1e-12


@pytest.mark.parametrize("method", ["RK4", "DOPRI5"])
def test_canonical_oversized_step_refused(method, stage_angles):
    """Step 6 (t = 5, h = 1) rotates by 3.4 rad > pi from a centred chart: ValueError."""
    with pytest.raises(ValueError, match=r"ODEvec1 .*step t = 5, h = 1 .*body 0 .*>= pi "
                                         r".*even in a chart centred at the start of the step"
                                         r".*reduce the step size"):
        vs.canonical_integrate_kinematic(method, ["SE3"], G_ID, ramp_vel, (0.0, 6.0), 6)
    assert max(stage_angles) < np.pi
    # the same with re-centring after every step (the MK-equivalent chart), and for a
    # single step from the identity (h = 2.6 s: 4.5 rad)
    with pytest.raises(ValueError, match="t = 5, h = 1 "):
        vs.canonical_integrate_kinematic(method, ["SE3"], G_ID, ramp_vel, (0.0, 6.0), 6,
                                         recenter_angle=0.0)
    with pytest.raises(ValueError, match="t = 0, h = 2.6"):
        vs.canonical_step_kinematic(method, ["SE3"], G_ID, 0.0, 2.6, ramp_vel)


def test_canonical_dynamics_fast_rotation_below_pi(stage_angles):
    """The symmetric top with steps of ~1.6 rad (h = 0.6 s): every stage keeps |xi| < pi,
    and the result is still an RK4 approximation (sanity, not accuracy)."""
    g0, V0 = top_exact(0.0)
    traj = vs.canonical_integrate("RK4", GROUPS, g0, V0, top_rhs, (0.0, 12.0), 20)
    assert max(stage_angles) < np.pi and traj.info["max_stage_angle"] < np.pi
    assert max(stage_angles) > 0.5 * np.pi
    assert np.all(np.isfinite(traj.R)) and np.all(np.isfinite(traj.V))
    for R in traj.R[:, 0]:
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-13)


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_canonical_fixed_axis(method):
    """Corollary 1 holds for eq. (ODEvec1) too (remark in section 'significance'): SE3
    exponential coordinates reproduce the fixed-axis motion exactly, SO3xR3 ones do not."""
    h, n = 1.0 / OMEGA0, 40                                   # 1 rad per step, 6 turns
    traj = vs.canonical_integrate_kinematic(method, ["SE3"], G_ID, vel_se3, (0.0, n * h), n)
    for k, t in enumerate(traj.t):
        R_ex, r_ex = axis_exact(t)
        assert np.abs(traj.R[k, 0] - R_ex).max() < 1e-12
        assert np.abs(traj.r[k, 0] - r_ex).max() < 1e-12
    assert traj.info["n_recentred"] == n // 2    # |xi| = 2 rad >= pi/2 every second step
    trm = vs.canonical_integrate_kinematic(method, ["SO3xR3"], G_ID, vel_mixed, (0.0, 3.5), 7)
    R_ex, r_ex = axis_exact(3.5)
    assert np.abs(trm.R[-1, 0] - R_ex).max() < 1e-12
    assert joint_violation(trm.R[-1, 0], trm.r[-1, 0]) > 1e-10


# --------------------------------------------------------------------------- ODEvec2
@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_dependent_order_and_agreement_with_mk(method):
    g0, V0 = top_exact(0.0)

    @memo
    def run(N):
        return vs.dependent_integrate(method, GROUPS, g0, V0, top_rhs, (0.0, 1.0), N,
                                      every=N // 2)

    Ns = step_counts(method.order, 1.0, lambda N: top_errors(run(N)).min(), N_CAP)
    e_dep, e_mk, diffs = [], [], []
    for N in Ns:
        dep = run(N)
        ref = mk.integrate(method, GROUPS, g0, V0, top_rhs, (0.0, 1.0), N, every=N // 2)
        e_dep.append(top_errors(dep))
        e_mk.append(top_errors(ref))
        diffs.append(np.max([pose_errors(dep.pose(k), ref.pose(k))
                             for k in range(len(dep.t))], axis=0))
    e_dep, e_mk, diffs = map(np.array, (e_dep, e_mk, diffs))
    for i, name in enumerate(GROUPS):
        assert_slope(Ns, e_dep[:, i], method.order, f"{method.name} ODEvec2 {name}")
        assert np.all(diffs[:, i] <= e_dep[:, i] + e_mk[:, i] + 1e-14)
        assert np.all(e_dep[:, i] <= 10.0 * e_mk[:, i] + 1e-13)


def _constraint_residuals(state):
    res = []
    for i, kind in enumerate(state.kinds):
        x = state.body(i)
        res.append(abs(np.linalg.norm(x[:4]) - 1.0))
        if kind == "dq":
            res.append(abs(np.dot(x[:4], x[4:8])))
    return np.array(res)


@pytest.mark.parametrize("normalize", [True, False])
def test_dependent_normalisation(normalize):
    g0, V0 = top_exact(0.0)
    state = vs.dependent_from_poses(GROUPS, g0)
    assert state.kinds == ("dq", "ep") and state.x.shape == (15,)
    assert _constraint_residuals(state).max() < 1e-15
    V, h = V0, 0.1
    worst = 0.0
    for k in range(30):
        state, V = vs.dependent_step("Heun", GROUPS, state, V, k * h, h, top_rhs,
                                     normalize=normalize)
        worst = max(worst, _constraint_residuals(state).max())
    if normalize:
        assert worst < 1e-14
    else:
        assert worst > 1e-6          # RK does not preserve |Q| = 1 (nor Q . Qe = 0)
    # the represented poses are proper (orthonormal R) either way
    for R, _ in vs.dependent_poses(GROUPS, state):
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-14)


def test_dependent_coordinates_round_trip(rng):
    g = []
    for _ in range(2):
        R = rodrigues(rng.standard_normal(3) * 1.5)
        g.append((R, rng.standard_normal(3)))
    state = vs.dependent_from_poses(GROUPS, g)
    assert pose_errors(vs.dependent_poses(GROUPS, state), g).max() < 1e-14
    x = state.body(0)
    np.testing.assert_allclose(x, dualquat.from_pose(*g[0]), atol=1e-15)
    np.testing.assert_allclose(state.body(1)[:4], quaternion.from_matrix(g[1][0]), atol=1e-15)


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_dependent_fixed_axis(method):
    """Dual quaternions (SE3): RK keeps Qh in the commutative subalgebra span{1, Vh}, so the
    normalised result lies on the screw subgroup: the joint is satisfied to round-off, only
    the rotation angle carries the O(h^p) error.  Euler parameters + position (SO3xR3):
    the joint is violated."""
    h, n = 0.5, 9
    traj = vs.dependent_integrate_kinematic(method, ["SE3"], G_ID, vel_se3, (0.0, n * h), n)
    for k in range(len(traj.t)):
        assert joint_violation(traj.R[k, 0], traj.r[k, 0]) < 1e-13
    trm = vs.dependent_integrate_kinematic(method, ["SO3xR3"], G_ID, vel_mixed, (0.0, n * h), n)
    assert joint_violation(trm.R[-1, 0], trm.r[-1, 0]) > 1e-10


def test_dependent_step_accepts_poses_and_matches_integrate():
    g0, V0 = top_exact(0.0)
    st, V1 = vs.dependent_step("RK4", GROUPS, g0, V0, 0.0, 0.05, top_rhs)
    traj = vs.dependent_integrate("RK4", GROUPS, g0, V0, top_rhs, (0.0, 0.05), 1)
    assert pose_errors(vs.dependent_poses(GROUPS, st), traj.final_pose).max() == 0.0
    np.testing.assert_array_equal(V1, traj.V[-1])
    ch, V2 = vs.canonical_step("RK4", GROUPS, g0, V0, 0.0, 0.05, top_rhs)
    assert isinstance(ch, vs.ChartState) and ch.n_recentred == 0
    traj = vs.canonical_integrate("RK4", GROUPS, g0, V0, top_rhs, (0.0, 0.05), 1)
    assert pose_errors(vs.chart_poses(GROUPS, ch), traj.final_pose).max() == 0.0
    np.testing.assert_array_equal(V2, traj.V[-1])
