"""Adaptive Munthe-Kaas steps (issue 18): the PI controller, HINIT, the minimum step,
FSAL reuse, tolerance proportionality on a rigid body with an exact solution, and dense
output on the group (order, and exactness of SE3 subgroup motions between steps)."""
import numpy as np
import pytest

from exudyn_lie.groups import se3, so3, so3xr3
from exudyn_lie.integrators import control as C
import reference_mk as mk
import reference_mk_adaptive as MA
from exudyn_lie.integrators.tableau import BS3, DOPRI5, RK4, Vern6
from exudyn_lie.mbs.simulator import StepSizeError
from exudyn_lie.models._torque_free import TorqueFreeRotation

# ------------------------------------------------------------------ the test problem
# A free asymmetric body tumbling (torque-free, frame at the COM: Euler-Poinsot, exact by
# elliptic functions) while its COM falls under gravity; body 0 on SE3 (body-fixed twist,
# translation coupled to the rotation), body 1 on SO3xR3 (mixed velocity).
INERTIA = np.array([0.3, 0.5, 0.9])
W0 = np.array([1.1, -0.6, 1.7])
GRAV = np.array([0.0, 0.0, -9.81])
VC0 = np.array([0.4, 0.2, 3.0])
RC0 = np.array([0.1, -0.2, 0.3])
EXACT = TorqueFreeRotation(INERTIA, np.eye(3), W0)
GROUPS = [se3, so3xr3]


def rhs(t, g, V):
    out = np.empty((len(g), 6))
    for i, (R, _) in enumerate(g):
        w, v = V[i, :3], V[i, 3:]
        out[i, :3] = np.cross(INERTIA * w, w) / INERTIA          # Euler's equations
        out[i, 3:] = -np.cross(w, v) + R.T @ GRAV if i == 0 else GRAV
    return out


def exact(t):
    R = EXACT.R(t)[0]
    w = EXACT.omega(t)[0]
    r = RC0 + VC0 * t + 0.5 * GRAV * t * t
    rd = VC0 + GRAV * t
    return [(R, r), (R.copy(), r.copy())], np.array([np.r_[w, R.T @ rd], np.r_[w, rd]])


def achieved_error(traj):
    """Largest global error over the output times in the solver's own norm with
    atol = rtol = 1 (control.tolerances(1, 1)): each kind divided by 1 + its size, so that
    error / tol is directly comparable with the requested tolerance."""
    tol1 = C.tolerances(1.0, 1.0)
    worst = 0.0
    for k, t in enumerate(traj.t):
        g_ex, V_ex = exact(t)
        dPhi = np.zeros((2, 6))
        for i in range(2):
            dPhi[i, :3] = so3.log(np.ascontiguousarray(g_ex[i][0].T @ traj.R[k, i]))
            dPhi[i, 3:] = traj.r[k, i] - g_ex[i][1]
        r_ex = np.array([p[1] for p in g_ex])
        worst = max(worst, C.weighted_rms(dPhi, traj.V[k] - V_ex, r_ex, traj.r[k], V_ex,
                                          traj.V[k], tol1))
    return worst


G0, V0 = exact(0.0)
T_END = 3.0
T_OUT = np.linspace(0.0, T_END, 7)
TOLS = 10.0 ** -np.arange(3, 11)


def run(method, tol, **kw):
    return MA.integrate_adaptive(method, GROUPS, G0, V0, rhs, (0.0, T_END), rtol=tol, atol=tol,
                                 t_eval=kw.pop("t_eval", T_OUT), **kw)


# ------------------------------------------------------------------ tolerance proportionality
def test_dopri5_tolerance_proportionality():
    """Achieved error against tol = 1e-3 .. 1e-10: slope 1 +- 0.15 and error/tol in
    [0.1, 10] (the pair's 5th-order solution with the 4th-order estimate: error per step
    ~ tol, global error ~ tol)."""
    errs = np.array([achieved_error(run(DOPRI5, tol)) for tol in TOLS])
    slope = np.polyfit(np.log(TOLS), np.log(errs), 1)[0]
    assert abs(slope - 1.0) <= 0.15, (slope, errs)
    assert np.all((errs / TOLS >= 0.1) & (errs / TOLS <= 10.0)), errs / TOLS


def test_bs3_tolerance_proportionality():
    """BS3 meets the same targets (measured: slope 0.99, error/tol 3.6-4.3)."""
    errs = np.array([achieved_error(run(BS3, tol)) for tol in TOLS])
    slope = np.polyfit(np.log(TOLS), np.log(errs), 1)[0]
    assert abs(slope - 1.0) <= 0.15, (slope, errs)
    assert np.all((errs / TOLS >= 0.1) & (errs / TOLS <= 10.0)), errs / TOLS


def test_vern6_error_falls_with_tol_and_stays_below_it():
    """Vern6 over-delivers at tight tolerances (measured: slope 1.16, error/tol falling from
    0.21 at 1e-3 to 0.014 at 1e-10; not yet in its asymptotic range, where the global error of
    the 6th-order solution under a 5th-order estimate is proportional to tol): asserted are
    a slope within 1 +- 0.3 and error/tol in [0.005, 10]."""
    errs = np.array([achieved_error(run(Vern6, tol)) for tol in TOLS])
    slope = np.polyfit(np.log(TOLS), np.log(errs), 1)[0]
    assert abs(slope - 1.0) <= 0.3, (slope, errs)
    assert np.all((errs / TOLS >= 0.005) & (errs / TOLS <= 10.0)), errs / TOLS


# ------------------------------------------------------------------ agreement with mk.py
def test_step_result_is_bit_identical_to_the_reference_mk_step():
    """One adaptive step with a given h computes the same g+, V+ as mk.mk_step (the
    fixed-step reference; for DOPRI5 the FSAL stage is the step's result)."""
    h = 0.05
    tr = MA.integrate_adaptive(DOPRI5, GROUPS, G0, V0, rhs, (0.0, h), rtol=1.0, atol=1.0, h0=h)
    g1, V1 = mk.mk_step(DOPRI5, GROUPS, G0, V0, 0.0, h, rhs)
    assert tr.stats.accepted == 1
    for i in range(2):
        assert np.array_equal(tr.R[-1, i], g1[i][0]) and np.array_equal(tr.r[-1, i], g1[i][1])
    assert np.array_equal(tr.V[-1], V1)


def test_fsal_saves_one_evaluation_per_accepted_step():
    """rhs evaluations = 2 (HINIT) + 6 per attempted step + 1 (first step's stage 1) for
    DOPRI5 (7 stages, the first reused); a non-FSAL count would be 7 per attempt."""
    tr = run(DOPRI5, 1e-6, t_eval=[T_END])
    st = tr.stats
    assert st.rhs_evaluations == 2 + 6 * (st.accepted + st.rejected)
    tr = run(BS3, 1e-6, t_eval=[T_END])
    st = tr.stats
    assert st.rhs_evaluations == 2 + 3 * (st.accepted + st.rejected)


# ------------------------------------------------------------------ the controller
def test_pi_controller_constants():
    P = C.controller_params(4)
    assert P[C.P_EXPO] == pytest.approx(1 / 5 - 0.75 * 0.04)          # 0.17 for DOPRI5
    assert P[C.P_SAFETY] == 0.9 and P[C.P_FAC_MIN] == 0.2 and P[C.P_FAC_MAX] == 10.0
    S = C.controller_state()
    # tiny error: growth limited to 10x
    assert C.control_step(P, S, 1.0, 1e-30) == C.STATUS_ACCEPT and S[C.S_H] == pytest.approx(10.0)
    # large error: reduction limited to 0.2x
    S = C.controller_state()
    assert C.control_step(P, S, 1.0, 1e30) == C.STATUS_REJECT and S[C.S_H] == pytest.approx(0.2)
    # PI: h_new = h * safety * err^-expo * err_old^beta
    S = C.controller_state()
    C.control_step(P, S, 1.0, 0.5)
    assert S[C.S_H] == pytest.approx(0.9 * 0.5 ** -0.17 * 1e-4 ** 0.04)
    C.control_step(P, S, 1.0, 0.3)
    assert S[C.S_H] == pytest.approx(0.9 * 0.3 ** -0.17 * 0.5 ** 0.04)


def test_no_growth_right_after_a_rejection():
    P = C.controller_params(4)
    S = C.controller_state()
    assert C.control_step(P, S, 1.0, 3.0) == C.STATUS_REJECT
    h = S[C.S_H]
    assert h < 1.0
    assert C.control_step(P, S, h, 1e-6) == C.STATUS_ACCEPT       # would grow 10x
    assert S[C.S_H] == h                                           # but stays at h
    assert C.control_step(P, S, h, 1e-6) == C.STATUS_ACCEPT
    assert S[C.S_H] > 5 * h                                        # growth allowed again
    assert S[C.S_N_ACCEPT] == 2 and S[C.S_N_REJECT] == 1


def test_the_minimum_step_stops_or_is_accepted_beyond_the_tolerance():
    """Without accept_min a retry below h_min stops (StepSizeError); with it the retry is made at
    h_min and a step there is accepted and counted, as Exudyn's explicit solvers continue; a NaN
    error still stops."""
    P = C.controller_params(4, h_min=0.1)
    S = C.controller_state()
    assert C.control_step(P, S, 0.3, 1e6) == C.STATUS_H_MIN
    P = C.controller_params(4, h_min=0.1, accept_min=True)
    S = C.controller_state()
    assert C.control_step(P, S, 0.3, 1e6) == C.STATUS_REJECT and S[C.S_H] == 0.1
    assert C.control_step(P, S, 0.1, 1e6) == C.STATUS_ACCEPT and S[C.S_H] == 0.1
    assert S[C.S_N_FLOOR] == 1 and S[C.S_N_ACCEPT] == 1 and S[C.S_N_REJECT] == 1
    assert C.control_step(P, S, 0.1, 0.5) == C.STATUS_ACCEPT and S[C.S_N_FLOOR] == 1     # within: not counted
    assert C.control_step(P, S, 0.1, np.nan) == C.STATUS_H_MIN
    with pytest.raises(ValueError, match="accept_min needs h_min > 0"):
        C.controller_params(4, accept_min=True)


def test_rejection_happens_and_the_next_step_does_not_grow():
    """A first step far too large (h0 = 1 s for tol 1e-8) is rejected, and the first accepted
    step after each rejection is not followed by a larger one."""
    tr = run(DOPRI5, 1e-8, h0=1.0, t_eval=[T_END])
    st = tr.stats
    assert st.rejected >= 1
    assert st.steps[0][1] < 1.0
    assert achieved_error(tr) < 1e-7


def test_minimum_step_raises_step_size_error_with_time_and_step():
    with pytest.raises(StepSizeError, match=r"minimum step") as exc:
        run(DOPRI5, 1e-10, h_min=0.1, t_eval=[T_END])   # the run settles at h ~ 0.02
    assert exc.value.step < 0.1 and 0.0 <= exc.value.time < T_END


def test_hinit_gives_a_sensible_first_step():
    """HINIT's step is within a factor 10 of the step the controller settles on, and
    scales like tol^(1/5) for DOPRI5."""
    hs = []
    for tol in (1e-4, 1e-9):
        tr = run(DOPRI5, tol, t_eval=[T_END])
        h_acc = np.median([h for _, h, _ in tr.stats.steps[:10]])
        assert 0.1 <= tr.stats.h_initial / h_acc <= 10.0
        hs.append(tr.stats.h_initial)
    assert hs[0] / hs[1] == pytest.approx(1e5 ** 0.2, rel=0.3)


def test_methods_without_a_pair_are_refused_and_pairs_found_by_name():
    with pytest.raises(ValueError, match="no embedded weights"):
        run(RK4, 1e-6)
    with pytest.raises(ValueError, match="no embedded weights"):
        run("rk4", 1e-6)
    assert MA.resolve_pair("ode23") is BS3 and MA.resolve_pair("Verner65") is Vern6
    assert MA.resolve_pair("dopri5") is DOPRI5


# ------------------------------------------------------------------ dense output on the group
@pytest.mark.parametrize("method", [BS3, DOPRI5, Vern6], ids=lambda m: m.name)
def test_dense_output_on_the_group_converges_at_its_order(method):
    """Fixed steps h (h0 = h, tolerances so loose that no step is rejected or changed would
    not hold: use the interpolant error within ONE step from the exact start instead):
    max over theta of the pose / velocity error of g exp(sigma(theta)) is O(h^(q+1))."""
    q = method.dense.order
    thetas = np.linspace(0.1, 0.9, 9)
    hs = 0.4 * 2.0 ** -(np.arange(0, 11) / 2)
    errs = []
    for h in hs:
        tr = MA.integrate_adaptive(method, GROUPS, G0, V0, rhs, (0.0, h), rtol=1e3, atol=1e3,
                                   h0=h, t_eval=thetas * h)
        assert tr.stats.accepted == 1 and tr.stats.rejected == 0
        e = 0.0
        for k, t in enumerate(tr.t):
            g_ex, V_ex = exact(t)
            for i in range(2):
                e = max(e, np.linalg.norm(so3.log(np.ascontiguousarray(g_ex[i][0].T @ tr.R[k, i]))),
                        np.abs(tr.r[k, i] - g_ex[i][1]).max(), np.abs(tr.V[k, i] - V_ex[i]).max())
        errs.append(e)
    errs = np.array(errs)
    keep = errs > 2e-11                 # above the round-off of the dense weights (Vern6: ~1e-12)
    hs, errs = hs[keep][-4:], errs[keep][-4:]
    assert len(hs) == 4
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    # Vern6's h^7 is not yet asymptotic above its double round-off floor (measured slope
    # 8.0 on h = 0.4 .. 0.05; the long-double test in test_embedded_pairs finds 7): only
    # the lower bound applies to it
    assert slope >= q + 1 - 0.3, (method.name, errs, slope)
    if method is not Vern6:
        assert slope <= q + 1 + 0.5, (method.name, errs, slope)


def _pendulum(group, p, e3, d, m_, I_p):
    """Right-hand side of a physical pendulum about the body axis e3 through the body point
    p (a revolute joint to the ground written as an ODE): angular acceleration
    wdot = e3 . ((d - p) x R^T m g) / I_p about the pivot.  SE3: Vdot = wdot (e3, p x e3)
    (the body twist is a multiple of that fixed screw); SO3xR3: omegadot = wdot e3 and
    rddot = -R (omegadot x p + omega x (omega x p)) (the pivot R p + r fixed)."""
    screw = np.r_[e3, np.cross(p, e3)]

    def f(t, g, V):
        R = g[0][0]
        wdot = np.cross(d - p, R.T @ (m_ * GRAV))[2] / I_p
        if group is se3:
            return (wdot * screw)[None]
        w = V[0, :3]
        out = np.empty((1, 6))
        out[0, :3] = wdot * e3
        out[0, 3:] = -R @ np.cross(wdot * e3, p) - R @ np.cross(w, np.cross(w, p))
        return out

    return f, screw


def test_se3_fixed_screw_motion_stays_exact_between_steps():
    """A pendulum on a fixed horizontal axis through a body point p off the frame origin:
    on SE3 every stage and every dense-output increment is a multiple of the same screw,
    so the pivot stays at the world origin and the axis keeps its direction at every output
    time between the steps to round-off; on SO3xR3 the pivot drifts (at the tolerance)."""
    p = np.array([0.3, -0.2, 0.1])
    e3 = np.array([0.0, 0.0, 1.0])
    d = np.array([0.5, 0.2, 0.0])
    R0 = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])   # the axis e3 horizontal in world
    g0 = [(R0, -R0 @ p)]                                    # pivot at the world origin
    w0 = 2.0
    out = {}
    for grp in (se3, so3xr3):
        f, screw = _pendulum(grp, p, e3, d, 2.0, 0.7)
        V0_ = w0 * screw if grp is se3 else np.r_[w0 * e3, -R0 @ np.cross(w0 * e3, p)]
        tr = MA.integrate_adaptive(DOPRI5, [grp], g0, V0_[None], f, (0.0, 3.0), rtol=1e-6,
                                   atol=1e-6, t_eval=np.linspace(0.0, 3.0, 61))
        pivot = max(np.abs(tr.R[k, 0] @ p + tr.r[k, 0]).max() for k in range(len(tr.t)))
        axis = max(np.abs(tr.R[k, 0] @ e3 - R0 @ e3).max() for k in range(len(tr.t)))
        out[grp] = (pivot, axis, tr.stats.accepted)
    pivot, axis, n_steps = out[se3]
    assert n_steps < 61                                     # outputs between the steps
    assert pivot < 1e-14 and axis < 1e-14, out
    assert out[so3xr3][0] > 1e-9, out


# ------------------------------------------------------------------ the norm and its seam
def test_increment_difference_is_the_difference_of_the_two_mk_increments():
    """dPhi = h sum (b - b_hat) K from the stage arrays equals Phi(b) - Phi(b_hat) of two
    reference MK steps (mk.mk_increment with the tableau and with a copy whose weights are
    b_hat): the two solutions share the base point, their difference needs no chart."""
    from exudyn_lie.integrators.tableau import ButcherTableau
    h = 0.2
    tab_hat = ButcherTableau(name="DOPRI5_hat", A=DOPRI5._exact_coeffs[0],
                             b=["5179/57600", 0, "7571/16695", "393/640", "-92097/339200",
                                "187/2100", "1/40"], c=DOPRI5._exact_coeffs[2], order=4)
    assert np.array_equal(tab_hat.b, DOPRI5.b_hat)
    Phi, dV = mk.mk_increment(DOPRI5, GROUPS, G0, V0, 0.0, h, rhs)
    Phi_h, dV_h = mk.mk_increment(tab_hat, GROUPS, G0, V0, 0.0, h, rhs)
    st = MA._Step(DOPRI5, 2)
    st.sweep(GROUPS, mk.as_poses(G0), V0, 0.0, h, rhs, 0, DOPRI5.stages)
    dPhi, dVd = np.zeros((2, 6)), np.zeros((2, 6))
    C.increment_difference(DOPRI5.b - DOPRI5.b_hat, h, st.K, st.Vd, dPhi, dVd)
    np.testing.assert_allclose(dPhi, Phi - Phi_h, rtol=0, atol=1e-15)
    np.testing.assert_allclose(dVd, dV - dV_h, rtol=0, atol=1e-15)
    assert np.abs(dPhi).max() > 1e-6                      # a real estimate, not zero


def test_weighted_rms_scaling_by_kind():
    """One unit error per kind: sc = atol_kind + rtol size with atol_angle = atol,
    atol_length = atol L, atol_omega = atol / T, atol_vel = atol L / T; 12 components."""
    tol = C.tolerances(1e-3, 1e-2, length_scale=2.0, time_scale=0.5)
    r = np.array([[3.0, 4.0, 0.0]])                      # |r| = 5
    V = np.array([[0.0, 6.0, 8.0, 0.0, 0.0, 7.0]])       # |omega| = 10, |v| = 7
    for k, sc in [(0, 1e-3 + 1e-2), (3, 2e-3 + 5e-2), (6, 2e-3 + 1e-1), (9, 4e-3 + 7e-2)]:
        dPhi, dV = np.zeros((1, 6)), np.zeros((1, 6))
        (dPhi if k < 6 else dV)[0, k % 6] = sc           # one component at its scale
        assert C.weighted_rms(dPhi, dV, r, r, V, V, tol) == pytest.approx(np.sqrt(1 / 12))
    with pytest.raises(ValueError):
        C.tolerances(0.0, 1e-6)


def test_control_functions_run_inside_compiled_code():
    """The controller, the norm and HINIT are njit functions without allocation
    (_nrt=False): a compiled caller uses them directly."""
    from numba import njit

    @njit(cache=False)
    def loop(P, S, e, K, Vd, r, V, tol, dPhi, dV):
        h = C.hinit_second(C.hinit_first(1.0, 2.0), 2.0, 3.0, 5.0, 1.0)
        n_acc = 0
        for _ in range(20):
            err = C.embedded_error_norm(e, h, K, Vd, r, r, V, V, tol, dPhi, dV)
            C.count_rhs(S, 6.0)
            if C.control_step(P, S, h, err) == C.STATUS_ACCEPT:
                n_acc += 1
            h = S[C.S_H]
        return n_acc, h

    rng = np.random.default_rng(1)
    K, Vd = rng.normal(size=(7, 2, 6)), rng.normal(size=(7, 2, 6))
    n_acc, h = loop(C.controller_params(4), C.controller_state(), DOPRI5.b - DOPRI5.b_hat,
                    K, Vd, rng.normal(size=(2, 3)), rng.normal(size=(2, 6)),
                    C.tolerances(1e-6, 1e-6), np.zeros((2, 6)), np.zeros((2, 6)))
    assert 0 < n_acc <= 20 and h > 0


def test_stage_argument_beyond_2pi_is_a_rejection_not_an_error():
    """A first step whose stage arguments reach |Psi| = c h |omega| >= 2 pi (dexp^-1
    singular, eq. MK1 undefined) is rejected and retried with h / 5; the constant-twist
    motion (a one-parameter subgroup) is then exact."""
    V = np.array([[0.0, 0.0, 10.0, 0.0, 0.0, 0.0]])

    def still(t, g, V_):
        return np.zeros((1, 6))

    tr = MA.integrate_adaptive(DOPRI5, [se3], [(np.eye(3), np.zeros(3))], V, still, (0.0, 2.0),
                               rtol=1e-8, atol=1e-8, h0=1.0)
    assert tr.stats.rejected >= 1 and tr.stats.steps[0][1] == pytest.approx(0.2)
    c, s_ = np.cos(20.0), np.sin(20.0)
    np.testing.assert_allclose(tr.R[-1, 0], [[c, -s_, 0], [s_, c, 0], [0, 0, 1]], atol=1e-13)
