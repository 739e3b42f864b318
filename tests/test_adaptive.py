"""Adaptive Munthe-Kaas steps (issue 18): the PI controller, HINIT, the minimum step,
FSAL reuse, tolerance proportionality on a rigid body with an exact solution, and dense
output on the group (order, and exactness of SE3 subgroup motions between steps)."""
import numpy as np
import pytest

from exudyn_lie.groups import se3, so3, so3xr3
from exudyn_lie.integrators import control as C
from exudyn_lie.integrators import mk
from exudyn_lie.integrators import mk_adaptive as MA
from exudyn_lie.integrators.tableau import BS3, DOPRI5, RK4, Vern6
from exudyn_lie.mbs.simulator import StepSizeError
from models._torque_free import TorqueFreeRotation

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


@pytest.mark.parametrize("method", [BS3, Vern6], ids=lambda m: m.name)
def test_other_pairs_converge_with_tol(method):
    """BS3 and Vern6: the achieved error falls with tol (slope within [0.8, 1.3]) and stays
    within a factor 30 of it (measured: BS3 error/tol 6-11, Vern6 0.01-0.4)."""
    errs = np.array([achieved_error(run(method, tol)) for tol in TOLS])
    slope = np.polyfit(np.log(TOLS), np.log(errs), 1)[0]
    assert 0.8 <= slope <= 1.3, (slope, errs)
    assert np.all((errs / TOLS > 1 / 30) | (TOLS < 1e-6)) and np.all(errs / TOLS < 30), errs / TOLS


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


def test_methods_without_a_pair_are_refused():
    with pytest.raises(ValueError, match="no embedded weights"):
        run(RK4, 1e-6)


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


def test_se3_fixed_screw_motion_stays_exact_between_steps():
    """A body pivoting about a fixed world axis (a revolute joint to the ground written as
    the rhs of a physical pendulum about a body point p off the frame origin): on SE3 every
    stage and every dense-output increment is a multiple of the same screw, so the pivot
    point p stays fixed and the axis keeps its direction at every output time to round-off;
    on SO3xR3 the pivot drifts at the level of the tolerance."""
    p = np.array([0.3, -0.2, 0.1])                    # pivot in body coordinates
    e3 = np.array([0.0, 0.0, 1.0])                    # axis (body = world at t = 0)
    d = np.array([0.5, 0.2, 0.0])                     # COM, body coordinates
    m_, I_p = 2.0, 0.7                                # mass, inertia about the pivot axis
    screw = np.r_[e3, np.cross(p, e3)]                # body twist per unit angular rate

    def pend_rhs(t, g, V):
        out = np.empty((1, 6))
        R = g[0][0]
        tau = np.cross(d - p, R.T @ (m_ * GRAV))[2] if True else 0.0
        wdot = tau / I_p
        if GR_[0] is se3:
            out[0] = wdot * screw
        else:                                         # mixed velocity: rdot = -R (w x p)
            w = V[0, :3]
            out[0, :3] = wdot * e3
            out[0, 3:] = -R @ np.cross(wdot * e3, p) - R @ np.cross(w, np.cross(w, p))
        return out

    R0 = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])   # axis e3 horizontal in world
    g0 = [(R0, -R0 @ p)]                              # pivot at the world origin
    results = {}
    for grp in (se3, so3xr3):
        GR_ = [grp]
        w0 = 2.0
        V0_ = w0 * screw if grp is se3 else np.r_[w0 * e3, -R0 @ np.cross(w0 * e3, p)]
        tr = MA.integrate_adaptive(DOPRI5, [grp], g0, V0_[None], pend_rhs, (0.0, 3.0),
                                   rtol=1e-6, atol=1e-6, t_eval=np.linspace(0, 3.0, 61))
        piv = np.array([tr.R[k, 0] @ p + tr.r[k, 0] for k in range(len(tr.t))])
        axis = np.array([tr.R[k, 0] @ e3 for k in range(len(tr.t))])
        results[grp.__name__] = (np.abs(piv).max(), np.abs(axis - R0 @ e3).max(),
                                 tr.stats.accepted)
    pivot_se3, axis_se3, n_se3 = results[se3.__name__]
    pivot_mixed, _, n_mixed = results[so3xr3.__name__]
    assert n_se3 < 61                                 # outputs between the steps
    assert pivot_se3 < 1e-14 and axis_se3 < 1e-14, results
    assert pivot_mixed > 1e-9, results
