"""The paper's fixed-axis illustration (section 'significance of the configuration space',
eq. TrapSol, figure figRotConst).

A frame rotates with constant angular velocity omega0 about the fixed axis xi through the
world point p != 0; at t = 0 it is the identity at the origin.  Exact motion:

    C(t) = (R(t), p - R(t) p),   R(t) = exp(omega0 t xi^),

body-fixed twist (constant)  V = (omega0 xi, omega0 p x xi),
mixed velocity (configuration dependent)  V^m(g) = (omega0 xi, R (p x omega0 xi)).

The motion is a one-parameter subgroup of SE(3) (a revolute joint to the ground), so every
MK step on SE3 reproduces it exactly for any step size (corollary 1).  On SO3xR3 the
rotation is exact but the position is the quadrature r+ = r + h sum_j b_j R_j (p x omega0 xi),
with error of the order of the quadrature (b, c) -- the method's order, except Kutta's RK3
whose nodes/weights are Simpson's rule (quadrature order 4).
"""
import numpy as np
import pytest

from exudyn_lie.groups import se3, so3xr3
from exudyn_lie.integrators import METHODS, get_method, mk

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


# step sizes: tiny, moderate, 1 rad per step, > pi/2 per step, 3 rad per step
STEP_SIZES = [1e-3, 0.1, 1.0 / OMEGA0, 2.0, 3.0 / OMEGA0]


@pytest.mark.parametrize("method", METHODS, ids=lambda m: m.name)
@pytest.mark.parametrize("h", STEP_SIZES)
def test_se3_update_exact_for_any_step(method, h):
    n_steps = 12
    traj = mk.integrate_kinematic(method, [se3], G0, vel_se3, (0.0, n_steps * h), n_steps)
    scale = 1.0 + np.linalg.norm(P)
    for k, t in enumerate(traj.t):
        R_ex, r_ex = exact(t)
        R, r = traj.R[k, 0], traj.r[k, 0]
        assert np.abs(R - R_ex).max() <= 1e-12
        assert np.abs(r - r_ex).max() <= 1e-12 * scale
        assert joint_violation(R, r) <= 1e-12 * scale


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
    """Position error at T = 2 (2.6 rad, not a full turn) over N = 4..32 steps."""
    T = 2.0
    Ns = np.array([4, 8, 16, 32])
    R_ex, r_ex = exact(T)
    errs = []
    for N in Ns:
        traj = mk.integrate_kinematic(method, [so3xr3], G0, vel_mixed, (0.0, T), int(N),
                                      every=int(N))
        errs.append(np.abs(traj.r[-1, 0] - r_ex).max())
    errs = np.array(errs)
    assert np.all(errs > 1e-13)
    slope = np.polyfit(np.log(T / Ns), np.log(errs), 1)[0]
    q = method.quadrature_order                 # == order, except RK3 (Simpson): 4
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
