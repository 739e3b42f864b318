"""Convergence order of every catalogue method, on problems with exact solutions.

(i)   plain RK on a scalar nonlinear, non-autonomous ODE (y = 1/(1 + t^2));
(ii)  the MK stepper (eq. MK1) on SE3 x SO3xR3 (one body each) with prescribed,
      time- and configuration-dependent velocity fields;
(iii) the MK stepper on the dynamics (eq. ODE2): a torque-free symmetric top whose
      frame origin is offset from the COM, under gravity (closed-form solution).

Exact solutions are evaluated with an independent matrix-exponential oracle (scaling and
squaring of a Taylor polynomial), not with the package's group maps.  The order is the
slope of log(error) vs log(h) fitted over 4 step sizes chosen from the method's order so
that the errors stay in the asymptotic range and well above round-off (rule:
:func:`step_counts`, from the order and one pilot run; no per-order table).
"""
import numpy as np
import pytest

from exudyn_lie.groups import se3, so3xr3
from exudyn_lie.integrators import METHODS
import reference_mk as mk
from exudyn_lie.integrators.tableau import extrapolated_euler
from vector_space_oracle import rk_integrate, rk_step

SLOPE_LO, SLOPE_HI = 0.3, 0.5      # accepted band: [order - 0.3, order + 0.5]


# --------------------------------------------------------------------------- oracles
def cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def hat3(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def expm(M):
    """Matrix exponential: scaling and squaring with a degree-19 Taylor polynomial."""
    nrm = np.linalg.norm(M, 1)
    s = max(0, int(np.ceil(np.log2(nrm))) + 1) if nrm > 0 else 0
    X = M / 2.0 ** s
    E = np.eye(M.shape[0])
    term = np.eye(M.shape[0])
    for k in range(1, 20):
        term = term @ X / k
        E = E + term
    for _ in range(s):
        E = E @ E
    return E


def se3_hat(X):
    M = np.zeros((4, 4))
    M[:3, :3] = hat3(X[:3])
    M[:3, 3] = X[3:]
    return M


def se3_vee(M):
    return np.array([M[2, 1], M[0, 2], M[1, 0], *M[:3, 3]])


def pose_matrix(R, r):
    C = np.eye(4)
    C[:3, :3] = R
    C[:3, 3] = r
    return C


def pose_errors(g, g_exact):
    return np.array([max(np.abs(R - Re).max(), np.abs(r - re).max())
                     for (R, r), (Re, re) in zip(g, g_exact)])


def fitted_slope(hs, errs):
    return np.polyfit(np.log(hs), np.log(errs), 1)[0]


# ----------------------------------------------------------------------- step-count rule
ERR_FLOOR = 1e-14       # smallest predicted error at the finest step: ~50 eps, i.e. 10-100x
                        # above the round-off floor of these O(1) problems (1e-16 .. 4e-15)
N_PILOT = 4             # pilot run that calibrates the error constant C (coarse, so that
                        # it stays above round-off for high orders)
N_POINTS = 4            # step counts N_f/8, N_f/4, N_f/2, N_f


def step_counts(order, T, error_of, n_cap):
    """The step counts of a convergence test, derived from the order p (no per-order table).

    Error model err(h) = C h^p.  C is calibrated by a pilot run with N_PILOT steps
    (``error_of(N)`` -> error), the finest step is the largest one whose predicted error
    reaches ERR_FLOOR, h_f = (ERR_FLOOR / C)^(1/p); N_f = T/h_f rounded DOWN to a power of
    two (so the prediction stays >= ERR_FLOOR), clipped to [2^N_POINTS, n_cap] (n_cap: the
    cost limit, a power of two, binding for low orders), and the fitted step counts are
    N_f / 2^k, k = N_POINTS-1 .. 0.  Higher orders thus get coarser ranges automatically:
    e.g. on the vector-space problem p <= 4 -> 32..256 (cap), DOPRI5 -> 32..256, RK6 ->
    16..128; a new catalogue method of any order is handled by the same formula.
    """
    pilot = error_of(N_PILOT)
    n_f = n_cap
    if pilot > 0.0:
        C = pilot / (T / N_PILOT) ** order
        h_f = (ERR_FLOOR / C) ** (1.0 / order)
        n_f = min(n_cap, 2 ** int(np.floor(np.log2(T / h_f))))
    n_f = max(n_f, 2 ** N_POINTS)
    return [n_f >> k for k in range(N_POINTS - 1, -1, -1)]


def memo(f):
    """Cache ``f(N)`` (the pilot run is usually one of the fitted points)."""
    cache = {}

    def g(N):
        if N not in cache:
            cache[N] = f(N)
        return cache[N]
    return g


def assert_order(hs, errs, order, what):
    errs = np.asarray(errs)
    slope = fitted_slope(hs, errs)
    assert np.all(errs > 1e-15), f"{what}: errors reached round-off {errs}"
    assert order - SLOPE_LO <= slope <= order + SLOPE_HI, \
        f"{what}: fitted slope {slope:.3f}, expected {order} (errors {errs})"
    return slope


# --------------------------------------------------------------------------- (ii) kinematics
A6 = np.array([0.3, -0.5, 0.8, 0.4, 0.2, -0.6])
B6 = np.array([-0.7, 0.2, 0.4, -0.3, 0.9, 0.5])
a3 = np.array([0.6, -0.2, 0.9])
b3 = np.array([0.4, 0.8, -0.3])
p3 = np.array([0.5, -1.0, 0.7])
d3 = np.array([0.3, 0.2, -0.4])


def kin_exact(t):
    """Body 0 (SE3): g(t) = exp(t A) exp(sin(t) B).
    Body 1 (SO3xR3): R(t) = exp(t a^) exp(sin(t) b^), r(t) = R(t) p + t^2/2 d."""
    C = expm(t * se3_hat(A6)) @ expm(np.sin(t) * se3_hat(B6))
    R1 = expm(t * hat3(a3)) @ expm(np.sin(t) * hat3(b3))
    return [(C[:3, :3], C[:3, 3]), (R1, R1 @ p3 + 0.5 * t * t * d3)]


def kin_vel(t, g):
    """Body twist V = Ad_{g^-1} A + cos(t) B (= Ad_{exp(-sin t B)} A + cos t B on the exact
    solution); mixed velocity (omega, rdot) = (R^T a + cos(t) b, R (omega x p) + t d)."""
    (R0, r0), (R1, _) = g
    C = pose_matrix(R0, r0)
    V0 = se3_vee(np.linalg.solve(C, se3_hat(A6) @ C)) + np.cos(t) * B6
    w = R1.T @ a3 + np.cos(t) * b3
    V1 = np.concatenate([w, R1 @ cross(w, p3) + t * d3])
    return np.array([V0, V1])


KIN_G0 = [(np.eye(3), np.zeros(3)), (np.eye(3), p3.copy())]
KIN_GROUPS = [se3, so3xr3]


# --------------------------------------------------------------------------- (iii) dynamics
MASS = 2.0
THETA = np.diag([0.4, 0.4, 0.7])            # about the COM, symmetric (I1 = I2)
THETA_INV = np.linalg.inv(THETA)
D_COM = np.array([0.2, -0.1, 0.3])          # COM position in the body frame
GRAV = np.array([0.0, 0.0, -9.81])
W0 = np.array([1.2, -0.7, 2.0])             # initial body angular velocity
VC0 = np.array([0.5, 0.3, 1.0])             # initial COM velocity
RC0 = np.array([0.1, 0.2, 0.3])             # initial COM position
LAM = (THETA[2, 2] - THETA[0, 0]) * W0[2] / THETA[0, 0]
E3 = np.array([0.0, 0.0, 1.0])


def top_exact(t):
    """Torque-free symmetric top: omega(t) = exp(lam t e3^) omega0,
    R(t) = exp(t (omega0 + lam e3)^) exp(-lam t e3^); COM in free fall; frame origin
    r = r_c - R d.  Returns poses and velocities for an (SE3, SO3xR3) pair of bodies."""
    R = expm(t * hat3(W0 + LAM * E3)) @ expm(-LAM * t * hat3(E3))
    w = expm(LAM * t * hat3(E3)) @ W0
    rc = RC0 + VC0 * t + 0.5 * t * t * GRAV
    r = rc - R @ D_COM
    rdot = VC0 + GRAV * t - R @ cross(w, D_COM)
    g = [(R, r), (R.copy(), r.copy())]
    V = np.array([np.concatenate([w, R.T @ rdot]),     # SE3: body-fixed twist
                  np.concatenate([w, rdot])])          # SO3xR3: mixed velocity
    return g, V


def top_rhs(t, g, V):
    """Newton-Euler of a body whose frame origin is offset from the COM by d:
    Euler's equations about the COM; SE3: vdot = -w x (v + w x d) + R^T g - wdot x d;
    SO3xR3: rddot = g - R (w x (w x d)) - R (wdot x d)."""
    out = np.empty((2, 6))
    for i in range(2):
        R, _ = g[i]
        w, v = V[i, :3], V[i, 3:]
        wd = -THETA_INV @ cross(w, THETA @ w)
        out[i, :3] = wd
        if i == 0:
            out[i, 3:] = -cross(w, v + cross(w, D_COM)) + R.T @ GRAV - cross(wd, D_COM)
        else:
            out[i, 3:] = GRAV - R @ cross(w, cross(w, D_COM)) - R @ cross(wd, D_COM)
    return out


# --------------------------------------------------------------------------- tests
def test_top_rhs_matches_exact_solution():
    """Sanity of the test problem itself: the exact solution satisfies the ODE."""
    t, eps = 0.37, 1e-5
    gp, Vp = top_exact(t + eps)
    gm, Vm = top_exact(t - eps)
    g, V = top_exact(t)
    Vdot_fd = (Vp - Vm) / (2 * eps)
    np.testing.assert_allclose(top_rhs(t, g, V), Vdot_fd, atol=1e-8)
    R, r = g[0]
    Rdot = (gp[0][0] - gm[0][0]) / (2 * eps)
    rdot = (gp[0][1] - gm[0][1]) / (2 * eps)
    np.testing.assert_allclose(R.T @ Rdot, hat3(V[0, :3]), atol=1e-8)
    np.testing.assert_allclose(R.T @ rdot, V[0, 3:], atol=1e-8)
    np.testing.assert_allclose(rdot, V[1, 3:], atol=1e-8)


def test_kin_vel_matches_exact_solution():
    t, eps = 0.61, 1e-5
    gp, gm, g = kin_exact(t + eps), kin_exact(t - eps), kin_exact(t)
    V = kin_vel(t, g)
    C = pose_matrix(*g[0])
    Cdot = (pose_matrix(*gp[0]) - pose_matrix(*gm[0])) / (2 * eps)
    np.testing.assert_allclose(se3_vee(np.linalg.solve(C, Cdot)), V[0], atol=1e-8)
    R1 = g[1][0]
    R1dot = (gp[1][0] - gm[1][0]) / (2 * eps)
    np.testing.assert_allclose(R1.T @ R1dot, hat3(V[1, :3]), atol=1e-8)
    np.testing.assert_allclose((gp[1][1] - gm[1][1]) / (2 * eps), V[1, 3:], atol=1e-8)


def max_error_on_grid(traj_t, errors_at):
    """max_k errors_at(k, t_k) over the stored (coarse) output grid."""
    return np.max([errors_at(k, t) for k, t in enumerate(traj_t)], axis=0)


N_CAP_VECTOR, N_CAP_KIN, N_CAP_DYN = 256, 64, 128     # cost limits (powers of two)


def check_vector_space_rk_order(method):
    """(i) y' = -2 t y^2, y(0) = 1: y = 1/(1 + t^2), t in [0, 2] (nonlinear, non-autonomous).
    Error: max over t = 0, 1, 2."""
    def f(t, y):
        return -2.0 * t * y ** 2

    T = 2.0

    @memo
    def error_of(N):
        ts, Y = rk_integrate(method, f, [1.0], (0.0, T), N)
        sel = slice(None, None, N // 2)
        return np.abs(Y[sel, 0] - 1.0 / (1.0 + ts[sel] ** 2)).max()

    Ns = step_counts(method.order, T, error_of, N_CAP_VECTOR)
    errs = [error_of(N) for N in Ns]
    assert_order(T / np.array(Ns), errs, method.order, f"{method.name} vector RK")


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_vector_space_rk_order(method):
    check_vector_space_rk_order(method)


@pytest.mark.parametrize("order", [7, 8])
def test_step_count_rule_beyond_the_catalogue(order):
    """The step-count rule is not tuned to the catalogue's orders: explicit Euler
    extrapolated to order 7 and 8 (exact tableaus, 22 and 29 stages) passes test (i).
    (Not on (ii)/(iii): there these methods reach their own round-off floor, ~4e-14 and
    ~3e-13 from the large extrapolation weights, within two doublings of the step.)"""
    check_vector_space_rk_order(extrapolated_euler(order))


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_mk_kinematic_order_se3_and_so3xr3(method):
    """(ii) MK on the product SE3 x SO3xR3 with configuration/time dependent velocities.
    Error: max over t = 0, 0.5, 1 of the pose error, per body."""
    T = 1.0

    @memo
    def errors_of(N):
        traj = mk.integrate_kinematic(method, KIN_GROUPS, KIN_G0, kin_vel, (0.0, T), N,
                                      every=N // 2)
        return max_error_on_grid(traj.t, lambda k, t: pose_errors(traj.pose(k), kin_exact(t)))

    Ns = step_counts(method.order, T, lambda N: errors_of(N).min(), N_CAP_KIN)
    errs = np.array([errors_of(N) for N in Ns])
    hs = T / np.array(Ns)
    assert_order(hs, errs[:, 0], method.order, f"{method.name} MK SE3 kinematic")
    assert_order(hs, errs[:, 1], method.order, f"{method.name} MK SO3xR3 kinematic")


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_mk_dynamic_order_symmetric_top(method):
    """(iii) MK on eq. (ODE2) for the symmetric top (same tableau for V and g).
    Error: max over t = 0, 0.5, 1 of pose and velocity errors, per body."""
    T = 1.0
    g0, V0 = top_exact(0.0)

    def errors_at(traj, k, t):
        g_ex, V_ex = top_exact(t)
        return np.maximum(pose_errors(traj.pose(k), g_ex), np.abs(traj.V[k] - V_ex).max(axis=1))

    @memo
    def errors_of(N):
        traj = mk.integrate(method, ["SE3", "SO3xR3"], g0, V0, top_rhs, (0.0, T), N,
                            every=N // 2)
        return max_error_on_grid(traj.t, lambda k, t: errors_at(traj, k, t))

    Ns = step_counts(method.order, T, lambda N: errors_of(N).min(), N_CAP_DYN)
    errs = np.array([errors_of(N) for N in Ns])
    hs = T / np.array(Ns)
    assert_order(hs, errs[:, 0], method.order, f"{method.name} MK SE3 dynamics")
    assert_order(hs, errs[:, 1], method.order, f"{method.name} MK SO3xR3 dynamics")


# --------------------------------------------------------------------------- stepper details
@pytest.mark.parametrize("name", ["RK4", "DOPRI5", "RK6"])
def test_velocity_part_is_plain_rk(name):
    """With an rhs independent of g, V+ of mk_step equals a plain RK step of Vdot = F(t, V)."""
    rng = np.random.default_rng(1)
    M = rng.standard_normal((6, 6))

    def F(t, V):
        return (np.sin(t) * V @ M.T) + 0.1 * V ** 2

    g = [(np.eye(3), np.zeros(3)), (np.eye(3), np.ones(3))]
    V = rng.standard_normal((2, 6))
    _, V1 = mk.mk_step(name, ["SE3", "SO3xR3"], g, V, 0.3, 0.1, lambda t, g_, V_: F(t, V_))
    V2 = rk_step(name, F, 0.3, V, 0.1)
    np.testing.assert_allclose(V1, V2, rtol=0, atol=1e-15)


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_constant_twist_exact_for_every_method(method, rng):
    """For constant V (any group) every stage has k_j = V, so g+ = g exp(h V) exactly."""
    V = rng.standard_normal((2, 6))
    R0 = expm(hat3(rng.standard_normal(3)))
    g = [(R0, rng.standard_normal(3)), (R0.T.copy(), rng.standard_normal(3))]
    h = 0.7
    Phi = mk.mk_increment_kinematic(method, [se3, so3xr3], g, 0.0, h, lambda t, g_: V)
    np.testing.assert_allclose(Phi, h * V, rtol=0, atol=1e-14)
    g1 = mk.mk_step_kinematic(method, [se3, so3xr3], g, 0.0, h, lambda t, g_: V)
    C = pose_matrix(*g[0]) @ expm(h * se3_hat(V[0]))
    np.testing.assert_allclose(g1[0][0], C[:3, :3], atol=1e-13)
    np.testing.assert_allclose(g1[0][1], C[:3, 3], atol=1e-13)
    np.testing.assert_allclose(g1[1][0], g[1][0] @ expm(h * hat3(V[1, :3])), atol=1e-13)
    np.testing.assert_allclose(g1[1][1], g[1][1] + h * V[1, 3:], atol=1e-14)


def test_group_resolution_and_errors():
    g = [(np.eye(3), np.zeros(3))] * 2
    assert mk.resolve_groups("se3", 2) == (se3, se3)
    assert mk.resolve_groups(["SE3", so3xr3], 2) == (se3, so3xr3)
    with pytest.raises(ValueError, match="SO3xR3"):
        mk.resolve_groups(["SE3", "SE2"], 2)
    with pytest.raises(ValueError, match="2 groups given for 3 bodies"):
        mk.resolve_groups(["SE3", "SE3"], 3)
    with pytest.raises(ValueError, match="shape"):
        mk.mk_step("RK4", "SE3", g, np.zeros((3, 6)), 0.0, 0.1, lambda t, g_, V: V)
    with pytest.raises(ValueError, match="available"):
        mk.mk_step("RK5", "SE3", g, np.zeros((2, 6)), 0.0, 0.1, lambda t, g_, V: V)


def test_integrate_trajectory_layout():
    g0, V0 = top_exact(0.0)
    traj = mk.integrate("RK4", ["SE3", "SO3xR3"], g0, V0, top_rhs, (0.0, 0.5), 10, every=3)
    np.testing.assert_allclose(traj.t, [0.0, 0.15, 0.3, 0.45, 0.5])
    assert traj.R.shape == (5, 2, 3, 3) and traj.r.shape == (5, 2, 3) and traj.V.shape == (5, 2, 6)
    g_ex, _ = top_exact(0.5)
    assert pose_errors(traj.final_pose, g_ex).max() < 1e-5
    # the input poses are not modified
    np.testing.assert_array_equal(g0[0][0], top_exact(0.0)[0][0][0])
