"""The paper's fixed-axis illustration (section 'significance of the configuration space',
eq. TrapSol, figure figRotConst).

A frame rotates with constant angular velocity omega0 about the fixed axis xi through the
world point p != 0; at t = 0 it is the identity at the origin.  Exact motion:

    C(t) = (R(t), p - R(t) p),   R(t) = exp(omega0 t xi^),

body-fixed twist (constant)  V = (omega0 xi, omega0 p x xi),
mixed velocity (configuration dependent)  V^m(g) = (omega0 xi, R (p x omega0 xi)).

The motion is a one-parameter subgroup of SE(3) (a revolute joint to the ground), so every
MK step on SE3 reproduces it exactly (corollary 1) for any step size with |Psi_j| < 2 pi:
with the constant body twist every stage has k_j = V and the stage arguments are
Psi_j = c_j h V, so the domain is  max_j c_j h omega0 < 2 pi  over the stages with
Psi_j != 0 (h omega0 < 2 pi for RK4, DOPRI5, RK6; < 4 pi for the midpoint rule; any h for
explicit Euler, which has no such stage).  At |Psi| = 2 pi dexp_{-Psi} is singular and
the stage equation of eq. (MK1) undefined; the stepper refuses stage arguments with
|xi| >= mk.STAGE_ANGLE_MAX = 2 pi (1 - sqrt(eps)) (2 pi - 9.4e-8).  Measured: exact to
round-off (<= 1.2e-13 over 12 steps) right up to that limit (h omega0 = 6.0, 6.2,
2 pi - 1e-3, 2 pi - 1.04e-7); without the guard 4e-2 at exactly 2 pi and 1e7 at 4 pi.
On SO3xR3 the rotation is exact but the position is the quadrature
r+ = r + h sum_j b_j R_j (p x omega0 xi), with error of the order of the quadrature (b, c)
-- the method's order, except Kutta's RK3 whose nodes/weights are Simpson's rule
(quadrature order 4).
"""
import numpy as np
import pytest

from exudyn_lie.groups import se3, so3, so3xr3
from exudyn_lie.integrators import METHODS, get_method
import reference_mk as mk
from test_mk_convergence import memo, step_counts

XI = np.array([1.0, 2.0, 2.0]) / 3.0          # unit axis, not a coordinate axis
P = np.array([0.4, -0.3, 1.1])                # point on the axis (world), p x xi != 0
OMEGA0 = 1.3
V_BODY = np.concatenate([OMEGA0 * XI, OMEGA0 * np.cross(P, XI)])
G0 = [(np.eye(3), np.zeros(3))]


def hat3(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def rot(t):
    """R(t) = exp(omega0 t xi^) by Rodrigues' formula (unit axis)."""
    K = hat3(XI)
    a = OMEGA0 * t
    return np.eye(3) + np.sin(a) * K + (1.0 - np.cos(a)) * K @ K


def exact(t):
    R = rot(t)
    return R, P - R @ P


def vel_se3(t, g):
    return V_BODY[None, :]


def vel_mixed(t, g):
    R, _ = g[0]
    return np.concatenate([OMEGA0 * XI, R @ np.cross(P, OMEGA0 * XI)])[None, :]


def joint_violation(R, r):
    """Revolute joint to ground: body point p stays at p and the axis stays xi."""
    return max(np.abs(r + R @ P - P).max(), np.abs(R @ XI - XI).max())


# step sizes: tiny, moderate, 1 rad per step, > pi/2 per step, 3, 6.0 and 6.2 rad per step
# (6.0 and 6.2: stage arguments |Psi| up to 6.2 rad for the methods with c_j = 1)
STEP_SIZES = [1e-3, 0.1, 1.0 / OMEGA0, 2.0, 3.0 / OMEGA0, 6.0 / OMEGA0, 6.2 / OMEGA0]


def max_stage_node(method):
    """max c_j over the evaluated stages with a nonzero stage argument Psi_j = c_j h V
    (0 if there is none, e.g. explicit Euler)."""
    return max([method.c[j] for j in method.active_stages if j > 0 and method.c[j] > 0.0],
               default=0.0)


def domain_limit(method):
    """Largest h omega0 of the SE3 exactness domain: max_j c_j h omega0 < STAGE_ANGLE_MAX."""
    cmax = max_stage_node(method)
    return np.inf if cmax == 0.0 else mk.STAGE_ANGLE_MAX / cmax


def assert_exact(traj, tol=1e-12):
    scale = 1.0 + np.linalg.norm(P)
    for k, t in enumerate(traj.t):
        R_ex, r_ex = exact(t)
        R, r = traj.R[k, 0], traj.r[k, 0]
        assert np.abs(R - R_ex).max() <= tol
        assert np.abs(r - r_ex).max() <= tol * scale
        assert joint_violation(R, r) <= tol * scale


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
@pytest.mark.parametrize("h", STEP_SIZES)
def test_se3_update_exact_for_any_step(method, h):
    n_steps = 12
    traj = mk.integrate_kinematic(method, [se3], G0, vel_se3, (0.0, n_steps * h), n_steps)
    assert_exact(traj)


# distance of the largest stage argument c_max h omega0 from 2 pi: 1e-3, 1e-6, and just
# inside the guard (2 pi - STAGE_ANGLE_MAX = 9.4e-8)
GAPS = [1e-3, 1e-6, 2 * np.pi - mk.STAGE_ANGLE_MAX + 1e-8]


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
@pytest.mark.parametrize("gap", GAPS)
def test_se3_update_exact_up_to_the_domain_limit(method, gap):
    """Exact to round-off for stage arguments right up to |Psi| = 2 pi - 1.04e-7."""
    cmax = max_stage_node(method)
    if cmax == 0.0:                          # no stage argument: no limit at all
        h = (4 * np.pi - gap) / OMEGA0
    else:
        h = (2 * np.pi - gap) / (cmax * OMEGA0)
        assert cmax * h * OMEGA0 < mk.STAGE_ANGLE_MAX
    n_steps = 12
    traj = mk.integrate_kinematic(method, [se3], G0, vel_se3, (0.0, n_steps * h), n_steps)
    assert_exact(traj)


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_stage_argument_guard_beyond_the_domain(method):
    """Stage arguments at (or beyond) 2 pi - 9.4e-8 are refused with a clear error naming
    the stage, body, group and step size; explicit Euler has no stage argument."""
    cmax = max_stage_node(method)
    hw_list = [mk.STAGE_ANGLE_MAX + 1e-9, 2 * np.pi, 2 * np.pi + 0.1, 4 * np.pi]
    if cmax == 0.0:
        for hw in hw_list:
            traj = mk.integrate_kinematic(method, [se3], G0, vel_se3, (0.0, 3 * hw / OMEGA0), 3)
            assert_exact(traj)
        return
    for group, vel in (("SE3", vel_se3), ("SO3xR3", vel_mixed)):
        for hw in hw_list:
            h = hw / (cmax * OMEGA0)
            with pytest.raises(ValueError) as exc:
                mk.integrate_kinematic(method, [group], G0, vel, (0.0, 2 * h), 2)
            msg = str(exc.value)
            assert f"h = {h:.17g}" in msg and f"group {group}" in msg and "body 0" in msg
            assert "stage" in msg and "2 pi" in msg and "reduce the step size" in msg
            assert method.name in msg
    # the guard sits exactly at STAGE_ANGLE_MAX: a hair inside still runs
    h = (mk.STAGE_ANGLE_MAX - 1e-9) / (cmax * OMEGA0)
    assert_exact(mk.integrate_kinematic(method, [se3], G0, vel_se3, (0.0, 2 * h), 2))


def test_stage_angle_max_is_where_dexp_loses_half_the_digits():
    """kappa(dexp_xi) = (t/2)/|sin(t/2)| (SO3 block) equals 1/sqrt(eps) at STAGE_ANGLE_MAX."""
    t = mk.STAGE_ANGLE_MAX
    kappa = np.linalg.cond(so3.dexp(t * XI))
    assert kappa == pytest.approx((t / 2) / abs(np.sin(t / 2)), rel=1e-3)
    assert kappa == pytest.approx(1.0 / np.sqrt(np.finfo(float).eps), rel=1e-3)


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_se3_update_exact_many_turns(method):
    """200 steps of 1 rad: ~32 turns, still exact up to accumulated round-off."""
    h, n_steps = 1.0 / OMEGA0, 200
    traj = mk.integrate_kinematic(method, ["SE3"], G0, vel_se3, (0.0, n_steps * h), n_steps,
                                  every=n_steps)
    R_ex, r_ex = exact(n_steps * h)
    assert np.abs(traj.R[-1, 0] - R_ex).max() <= 1e-12
    assert np.abs(traj.r[-1, 0] - r_ex).max() <= 1e-12 * (1.0 + np.linalg.norm(P))


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_so3xr3_rotation_exact_position_not(method):
    h, n_steps = 0.5, 7                 # 0.65 rad per step
    traj = mk.integrate_kinematic(method, [so3xr3], G0, vel_mixed, (0.0, n_steps * h), n_steps)
    pos_err = []
    for k, t in enumerate(traj.t):
        R_ex, r_ex = exact(t)
        assert np.abs(traj.R[k, 0] - R_ex).max() <= 1e-12          # rotation exact
        pos_err.append(np.abs(traj.r[k, 0] - r_ex).max())
    assert max(pos_err) > 1e-10                                     # position is not
    assert joint_violation(traj.R[-1, 0], traj.r[-1, 0]) > 1e-10   # joint violated


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
def test_so3xr3_position_error_order(method):
    """Position error at T = 2 (2.6 rad, not a full turn); step counts from the order rule
    of test_mk_convergence.py (N = 4..32 for the catalogue)."""
    T = 2.0
    R_ex, r_ex = exact(T)
    q = method.quadrature_order                 # == order, except RK3 (Simpson): 4

    @memo
    def error_of(N):
        traj = mk.integrate_kinematic(method, [so3xr3], G0, vel_mixed, (0.0, T), int(N),
                                      every=int(N))
        return np.abs(traj.r[-1, 0] - r_ex).max()

    Ns = np.array(step_counts(q, T, error_of, 32))
    errs = np.array([error_of(N) for N in Ns])
    assert np.all(errs > 1e-13)
    slope = np.polyfit(np.log(T / Ns), np.log(errs), 1)[0]
    assert q >= method.order
    assert q - 0.3 <= slope <= q + 0.5, f"{method.name}: slope {slope:.3f}, expected {q}"


def test_rk3_quadrature_superconvergence_is_the_reason():
    assert get_method("RK3").quadrature_order == 4
    assert all(m.quadrature_order == m.order for m in METHODS if m.name != "RK3")


@pytest.mark.parametrize("t_i", [0.0, 0.7])
@pytest.mark.parametrize("h", [0.05, 0.5, 2.0])
def test_explicit_midpoint_closed_form(t_i, h):
    """eq. (TrapSol): with constant V the midpoint scheme gives xi_{i+1} = h V exactly, so
    C_{i+1} = C_i exp(h V); on SO3xR3 r_{i+1} = r_i + h v_{i+1/2}."""
    tab = get_method("ExplicitMidpoint")
    g_i = [exact(t_i)]
    Phi = mk.mk_increment_kinematic(tab, [se3], g_i, t_i, h, vel_se3)
    np.testing.assert_allclose(Phi[0], h * V_BODY, rtol=0, atol=1e-15)
    R1, r1 = mk.mk_step_kinematic(tab, [se3], g_i, t_i, h, vel_se3)[0]
    R_ex, r_ex = exact(t_i + h)
    np.testing.assert_allclose(R1, R_ex, atol=1e-14)
    np.testing.assert_allclose(r1, r_ex, atol=1e-14)
    # SO3xR3: xi-part exact, position r_i + h v_{i+1/2} with v_{i+1/2} = R(t_i + h/2)(p x w)
    Phi_m = mk.mk_increment_kinematic(tab, [so3xr3], g_i, t_i, h, vel_mixed)
    v_half = rot(t_i + 0.5 * h) @ np.cross(P, OMEGA0 * XI)
    np.testing.assert_allclose(Phi_m[0, :3], h * OMEGA0 * XI, rtol=0, atol=1e-15)
    np.testing.assert_allclose(Phi_m[0, 3:], h * v_half, rtol=0, atol=1e-14)
    R1m, r1m = mk.mk_step_kinematic(tab, [so3xr3], g_i, t_i, h, vel_mixed)[0]
    np.testing.assert_allclose(R1m, R_ex, atol=1e-14)
    np.testing.assert_allclose(r1m, g_i[0][1] + h * v_half, atol=1e-14)
    assert np.abs(r1m - r_ex).max() > 1e-6 * h ** 3
