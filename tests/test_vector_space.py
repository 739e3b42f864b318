"""Vector-space formulations (eqs. ODEvec1, ODEvec2) versus the MK method (eq. MK1).

Problems (exact solutions, independent of the package's group maps):
* the torque-free symmetric top with COM offset under gravity (as in
  test_mk_convergence.py), one SE3 body and one SO3xR3 body;
* the paper's fixed-axis rotation (eq. TrapSol).
"""
import numpy as np
import pytest

from exudyn_lie.groups import dualquat, quaternion
from exudyn_lie.integrators import METHODS, mk
from exudyn_lie.integrators import vector_space as vs

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


# step counts per order (asymptotic range, see test_mk_convergence.py)
SCHEDULE = {1: 16, 2: 16, 3: 16, 4: 16, 5: 16, 6: 8}


def step_counts(order):
    n0 = SCHEDULE.get(order, 4)
    return [n0 * 2 ** k for k in range(4)]


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
    Ns = step_counts(method.order)
    g0, V0 = top_exact(0.0)
    e_can, e_mk, diffs = [], [], []
    for N in Ns:
        can = vs.canonical_integrate(method, GROUPS, g0, V0, top_rhs, (0.0, 1.0), N,
                                     every=N // 2)
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


def test_canonical_global_chart_breaks_down():
    """Without re-centring, the global chart (paper's remark, appendix B) runs into the
    dexp^{-1} singularity at |xi| = 2 pi after about one turn: the result is garbage."""
    T, N = MANY_TURNS_T, MANY_TURNS_N
    g0, V0 = top_exact(0.0)
    with np.errstate(all="ignore"):
        traj = vs.canonical_integrate("RK4", GROUPS, g0, V0, top_rhs, (0.0, T), N,
                                      every=N // 8, recenter_angle=np.inf)
        errs = top_errors(traj)
    assert traj.info["n_recentred"] == 0
    assert not np.all(np.isfinite(errs)) or errs.max() > 1e-1


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
    Ns = step_counts(method.order)
    g0, V0 = top_exact(0.0)
    e_dep, e_mk, diffs = [], [], []
    for N in Ns:
        dep = vs.dependent_integrate(method, GROUPS, g0, V0, top_rhs, (0.0, 1.0), N,
                                     every=N // 2)
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
