"""Dynamics of the compiled kernel: invariants, an independent derivation, orders, and
the paper's claims at kernel level (heavy top, spherical double pendulum)."""
import warnings

import numpy as np
import pytest

from exudyn_lie.models import heavy_top as HT
from exudyn_lie.mbs import GROUND, ConstraintError, Scene, Simulator, StepSizeError

# --------------------------------------------------------------------------- scenes
BOX = (0.8, 0.4, 0.1)          # free body of section "Unconstrained Rigid Body"
M_BOX = 86.4
THETA0 = np.diag([1.224, 4.68, 5.76])


def free_body_off_com(group_frame_at_com=False, omega0=(10 * np.pi, 2 * np.pi, 0), vcom=(10, 0, 0)):
    """The paper's free body with the frame at P, COM at r0 = (0.4, 0, 0) (body)."""
    sc = Scene()
    c = np.array([0.4, 0, 0])
    om = np.array(omega0, float)
    if group_frame_at_com:
        sc.AddBody(M_BOX, THETA0, R0=np.eye(3), r0=c, omega0=om, vel0=vcom)
    else:
        ThetaP = THETA0 + M_BOX * (np.dot(c, c) * np.eye(3) - np.outer(c, c))
        # frame origin velocity: v_P = v_C + omega x (P - C) = v_C + omega x (-c)
        sc.AddBody(M_BOX, ThetaP, com=c, R0=np.eye(3), r0=[0, 0, 0], omega0=om,
                   vel0=np.array(vcom, float) - np.cross(om, c))
    return sc


def heavy_top(spring=True):
    """Heavy top (section "Heavy Top"), the one builder of the models."""
    return HT.scene(spring=spring)


def double_pendulum():
    """Spherical double pendulum: aluminium boxes 0.2 x 0.1 x 0.05 m."""
    a, b_, c = 0.2, 0.1, 0.05
    m = 2700 * a * b_ * c
    Th = m / 12 * np.diag([b_**2 + c**2, a**2 + c**2, a**2 + b_**2])
    sc = Scene(gravity=[0, 0, -9.81])
    w1 = np.array([10.0, 0, 0])
    w2 = np.array([10 * np.pi, 10 * np.pi, 20 * np.pi])
    b1 = sc.AddBody(m, Th, r0=[a / 2, 0, 0], omega0=w1, vel0=np.cross(w1, [a / 2, 0, 0]))
    v2 = np.cross(w1, [a, 0, 0]) + np.cross(w2, [a / 2, 0, 0])
    b2 = sc.AddBody(m, Th, r0=[a + a / 2, 0, 0], omega0=w2, vel0=v2)
    sc.AddSphericalJoint(GROUND, b1, [0, 0, 0], name="joint1")
    sc.AddSphericalJoint(b1, b2, [a, 0, 0], name="joint2")
    return sc


# --------------------------------------------------------------------------- free bodies
C_BOX = np.array([0.4, 0, 0])
OMEGA_BOX = np.array([10 * np.pi, 2 * np.pi, 0])
VCOM_BOX = np.array([10.0, 0, 0])


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_free_body_off_com_conserves_momentum_at_order(group):
    """Frame off the COM: the linear momentum m v_c and the angular momentum about the
    world origin (x_c x m v_c + R Theta_c omega) are conserved by the exact motion; RK4
    keeps them up to its truncation error, which must be small and fall at order 4 when
    the step is halved -- checked for both, in both groups (measured: SE3 |dp|/|p| =
    1.6e-7, |dL|/|L| = 1.6e-5; SO3xR3 1.7e-8, 1.0e-6 at h = 1e-3; ratios 15.5-16)."""
    T, h = 1.0, 1e-3
    drift = []
    for hh in (2 * h, h):
        sim = Simulator(free_body_off_com(), "RK4", group)
        p0, L0 = sim.Momentum()
        np.testing.assert_allclose(p0, M_BOX * VCOM_BOX, rtol=1e-14)
        sim.Run(T, hh, outputEvery=100)
        p1, L1 = sim.Momentum()
        drift.append((np.linalg.norm(p1 - p0) / np.linalg.norm(p0),
                      np.linalg.norm(L1 - L0) / np.linalg.norm(L0)))
    (dp2, dL2), (dp1, dL1) = drift
    # (the angular momentum about the world origin carries the COM position error of the
    # SE3 update for this fast-spinning translating body: ~1.6e-5 at h = 1e-3)
    assert dp1 < 1e-6 and dL1 < 1e-4, drift
    # the drifts are far above round-off (~1e-15), so the ratios measure the order
    assert dp1 > 1e-12 and dL1 > 1e-12, drift
    assert 12 < dp2 / dp1 < 22, drift
    assert 12 < dL2 / dL1 < 22, drift


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_free_body_off_com_matches_analytic_torque_free_solution(group):
    """An independent derivation: the exact Euler-Poinsot motion (Jacobi elliptic
    functions, models/_torque_free.py) of the body about its COM, which moves uniformly.
    The kernel integrates the body with its frame 0.4 m off the COM (inertia about the
    frame, coupling terms in M); its orientation, frame origin r = x_c - R c and body
    angular velocity must match the exact ones along the whole run, with errors falling
    at order 4 (measured at T = 1 s, h = 1e-3: |R - R_ex| 4.2e-8 in both groups, |r -
    r_ex| 8.0e-7 (SE3) / 5.7e-8 (SO3xR3))."""
    from exudyn_lie.models._torque_free import TorqueFreeRotation
    T = 1.0
    tf = TorqueFreeRotation(np.diag(THETA0), np.eye(3), OMEGA_BOX)
    errs = []
    for h in (2e-3, 1e-3):
        sim = Simulator(free_body_off_com(), "RK4", group)
        res = sim.Run(T, h, outputEvery=int(round(0.05 / h)))
        Rex = tf.R(res.times)
        wex = tf.omega(res.times)
        xc = C_BOX + np.outer(res.times, VCOM_BOX)                     # the COM moves uniformly
        rex = xc - np.einsum("nij,j->ni", Rex, C_BOX)
        errs.append((np.max(np.abs(res.R[:, 0] - Rex)), np.max(np.abs(res.r[:, 0] - rex)),
                     np.max(np.abs(res.omega[:, 0] - wex))))
    (eR2, er2, ew2), (eR1, er1, ew1) = errs
    assert eR1 < 1e-7 and er1 < 2e-6 and ew1 < 1e-6, errs
    for a, b in ((eR2, eR1), (er2, er1), (ew2, ew1)):
        assert 12 < a / b < 22, errs


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_free_body_off_com_matches_com_frame(group):
    """The motion equals that of the same body described with its frame at the COM
    (different inertia matrix, no coupling terms)."""
    T, h = 1.0, 1e-3
    resP = Simulator(free_body_off_com(), "RK4", group).Run(T, h, outputEvery=100)
    simC = Simulator(free_body_off_com(group_frame_at_com=True), "RK4", "SE3")
    resC = simC.Run(T, h / 4, outputEvery=400)
    xcP = resP.r[-1, 0] + resP.R[-1, 0] @ C_BOX
    np.testing.assert_allclose(xcP, resC.r[-1, 0], atol=1e-6)
    np.testing.assert_allclose(resP.R[-1, 0], resC.R[-1, 0], atol=1e-6)
    # the COM moves uniformly: x_c(t) = x_c(0) + v_c t
    np.testing.assert_allclose(xcP, C_BOX + VCOM_BOX * T, atol=1e-6)


def test_se3_update_is_frame_invariant():
    """The SE3 update does not depend on where the body frame sits (paper, section
    "Arbitrary Body-Fixed Reference Frame"): the frame-off-COM body reproduces the
    COM-frame body's motion to round-off at the same step; SO3xR3 does not."""
    c = np.array([0.4, 0, 0])
    gap = {}
    for group in ("SE3", "SO3xR3"):
        resP = Simulator(free_body_off_com(), "RK4", group).Run(1.0, 1e-2, outputEvery=10)
        resC = Simulator(free_body_off_com(group_frame_at_com=True), "RK4", group).Run(1.0, 1e-2, outputEvery=10)
        xcP = resP.r[:, 0] + np.einsum("nij,j->ni", resP.R[:, 0], c)
        gap[group] = max(np.max(np.abs(xcP - resC.r[:, 0])), np.max(np.abs(resP.R - resC.R)))
    assert gap["SE3"] < 1e-11, gap
    assert gap["SO3xR3"] > 1e-6, gap


def test_free_body_spatial_rotation_se3_keeps_com_fixed_off_com_frame():
    """Paper: frame off COM, pure spatial rotation about the COM -- the SE3 update keeps
    the COM in place to round-off for any step size; SO3xR3 does not."""
    drift = {}
    for group in ("SE3", "SO3xR3"):
        sim = Simulator(free_body_off_com(vcom=(0, 0, 0)), "RK4", group)
        res = sim.Run(1.0, 1e-2, outputEvery=1)
        xc = res.r[:, 0] + np.einsum("nij,j->ni", res.R[:, 0], [0.4, 0, 0])
        drift[group] = np.max(np.linalg.norm(xc - [0.4, 0, 0], axis=1))
    assert drift["SE3"] < 1e-12
    assert drift["SO3xR3"] > 1e-6


# --------------------------------------------------------------------------- energy order
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("method,order", [("RK4", 4), ("ExplicitMidpoint", 2)])
def test_energy_error_converges_at_method_order(method, order, group):
    """Heavy top with its spring (undamped, so conservative): the largest energy error
    over the run, max_t |E(t) - E(0)|, must fall by at least 2^order when h is halved.
    SO3xR3 shows exactly the method's order (measured ratios 13.9, 15.0 for RK4 and 3.97,
    3.98 for the midpoint rule); SE3, whose update keeps the top's rotation about the
    pivot exactly, shows one order more for this mechanism (measured 31.0, 30.1 and 8.0,
    7.5), so only the lower bound is asserted there.  (The error at the end time alone
    is not monotone in h for SO3xR3 with the midpoint rule.)"""
    T = 0.5
    hs = [2e-3, 1e-3, 5e-4] if order == 4 else [1e-3, 5e-4, 2.5e-4]
    errs = []
    for h in hs:
        sim = Simulator(heavy_top(spring=True), method, group)
        res = sim.Run(T, h, outputEvery=max(1, int(round(2e-3 / h))))
        E = res.totalEnergy
        errs.append(np.max(np.abs(E - E[0])))
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all(ratios > 0.75 * 2 ** order), (errs, ratios)
    if group == "SO3xR3":
        assert np.all(ratios < 1.3 * 2 ** order), (errs, ratios)


# --------------------------------------------------------------------------- paper claims
def max_violation(group, h, T=8.0, scene=heavy_top, joint=0):
    """Largest position violation of one joint over every step of the run."""
    sim = Simulator(scene(), "RK4", group)
    res = sim.Run(T, h, outputEvery=1)
    assert len(res.times) == int(round(T / h)) + 1
    return np.max(res.jointPositionViolation[:, joint])


def test_heavy_top_se3_exact_so3xr3_drifts_at_order_4():
    """Corollary 1: the top's motion is a subgroup (rotation about the pivot) of SE3 but
    not of SO3xR3.  The paper's claims with RK4 at 1e-2 and 1e-3 s over 8 s, checked at
    every step: SE3 <= 1e-12 throughout; SO3xR3 >= 1e-8, falling about 16x when the step
    is halved (measured: 1.3e-2, 8.7e-4 at 1e-2, 5e-3 s (15.3x); 1.4e-6 at 1e-3 s)."""
    for h in (1e-2, 1e-3):
        assert max_violation("SE3", h) <= 1e-12
    v1 = max_violation("SO3xR3", 1e-2)
    v2 = max_violation("SO3xR3", 5e-3)
    v3 = max_violation("SO3xR3", 1e-3)
    assert v1 >= 1e-8 and v3 >= 1e-8, (v1, v3)
    assert 12 < v1 / v2 < 20, (v1, v2)


def test_double_pendulum_joint1_exact_joint2_same_order():
    T = 1.0
    for h in (1e-2, 1e-3):
        assert max_violation("SE3", h, T, double_pendulum, 0) <= 1e-12
    j2 = {g: max_violation(g, 1e-2, T, double_pendulum, 1) for g in ("SE3", "SO3xR3")}
    assert 0.05 < j2["SE3"] / j2["SO3xR3"] < 20, j2
    assert max_violation("SO3xR3", 1e-2, T, double_pendulum, 0) > 1e-9


# --------------------------------------------------------------------------- bad input
def test_inconsistent_initial_velocity_is_reported_and_projectable():
    sc = heavy_top()
    sc.bodies[0].vel0 = np.array([1.0, 0, 0])
    with pytest.raises(ConstraintError, match="velocity constraints"):
        Simulator(sc, "RK4", "SE3")
    sim = Simulator(sc, "RK4", "SE3", projectInitial=True)
    h, J, eta = sim.jacobian()
    assert np.max(np.abs(J @ sim.V.reshape(-1))) < 1e-12


def test_inconsistent_initial_position_is_reported_and_projectable():
    sc = heavy_top()
    sc.bodies[0].r0 = np.array([0.55, 0.02, 0])
    with pytest.raises(ConstraintError, match="initial configuration"):
        Simulator(sc, "RK4", "SE3")
    sim = Simulator(sc, "RK4", "SE3", projectInitial=True)
    assert np.max(np.abs(sim.jacobian()[0])) < 1e-12


def test_step_size_blow_up_is_stopped_with_a_suggestion():
    sc = Scene()
    b = sc.AddBody(1.0, np.eye(3) * 0.01, r0=[1, 0, 0])
    sc.AddSpringDamper(GROUND, [0, 0, 0], b, [0, 0, 0], stiffness=1e6, referenceLength=0.5)
    sim = Simulator(sc, "RK4", "SE3")
    with pytest.raises(StepSizeError, match="step size"):
        sim.Run(10.0, 0.1)


def test_redundant_planar_fourbar_runs_and_singular_names_joints():
    """Four revolute joints close a planar four-bar: 3 redundant rows; the warning names
    all four joints and the rank, and it runs.  (A system that becomes singular during a
    run: test_full_rank_system_becoming_singular_mid_run_names_the_joints.)"""
    sc = Scene(gravity=[0, -9.81, 0])
    pts = [np.array([0, 0, 0.]), np.array([0, 0.2, 0]), np.array([0.5, 0.4, 0]), np.array([0.5, 0, 0])]
    bodies = []
    for k in range(3):
        mid = 0.5 * (pts[k] + pts[k + 1])
        bodies.append(sc.AddBody(1.0, np.diag([0.01, 0.01, 0.02]), r0=mid))
    sc.AddRevoluteJoint(GROUND, bodies[0], pts[0], name="rev1")
    sc.AddRevoluteJoint(bodies[0], bodies[1], pts[1], name="rev2")
    sc.AddRevoluteJoint(bodies[1], bodies[2], pts[2], name="rev3")
    sc.AddRevoluteJoint(bodies[2], GROUND, pts[3], name="rev4")
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        sim = Simulator(sc, "RK4", "SE3")
    msgs = [str(x.message) for x in w if "redundant" in str(x.message)]
    assert msgs and all(f"rev{i}" in msgs[0] for i in (1, 2, 3, 4)), msgs
    assert "rank 17 of 20" in msgs[0], msgs
    assert sorted(sim.redundantJoints) == ["rev1", "rev2", "rev3", "rev4"]
    res = sim.Run(0.5, 1e-3, outputEvery=50)
    assert np.all(np.isfinite(res.r))
    assert np.max(res.jointViolation) < 1e-6


def sliding_plane_pair(x0, v=1.0):
    """A free body translating along x at speed v (no forces: the exact motion is
    uniform), with three one-row generic joints that hold along that motion:

    * planeA: the ground origin lies in the body's x-z plane, ``(R e_y) . (0 - r) = 0``
      (row on the body side: J = (x e_z, -e_y) at R = I, r = (x, 0, 0));
    * planeB: the body origin stays in the world plane y = 0 (J = (0, e_y));
    * zlock: ... and in the world plane z = 0 (J = (0, e_z)).

    planeA + planeB = (x e_z, 0): full rank except at x = 0, where planeA and planeB
    become linearly dependent (zlock stays independent).  Near x = 0 the smallest pivot of
    J M^-1 J^T is about 25 x^2 against a largest diagonal of 0.5 (m = 2 kg, Theta_z = 0.04)."""
    sc = Scene()
    b = sc.AddBody(2.0, np.diag([0.02, 0.03, 0.04]), r0=[x0, 0, 0], vel0=[v, 0, 0], name="slider")
    sc.AddJoint(b, GROUND, (0, 1, 0, 0, 0, 0), name="planeA")
    sc.AddJoint(GROUND, b, (0, 1, 0, 0, 0, 0), name="planeB")
    sc.AddJoint(GROUND, b, (0, 0, 1, 0, 0, 0), name="zlock")
    return sc


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_full_rank_system_becoming_singular_mid_run_names_the_joints(group):
    """Full rank at the start (x = -0.05 m), singular when the body reaches x = 0 at
    t = 0.05 s (the last stage of the step from 0.049 s lands there, to round-off): the
    run stops with a ConstraintError naming the two dependent joints (not the third),
    at the last accepted step."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")           # no redundancy warning at set-up
        sim = Simulator(sliding_plane_pair(-0.05), "RK4", group)
    assert not sim.redundantJoints and not sim.sd.redundant
    with pytest.raises(ConstraintError, match="singular constraint Jacobian") as ei:
        sim.Run(0.1, 1e-3, outputEvery=1)
    msg = str(ei.value)
    names = msg.split("constraints of joints ")[1].split(" are linearly dependent")[0].split(", ")
    assert sorted(names) == ["planeA", "planeB"], msg
    assert sim.t == pytest.approx(0.049, abs=1e-12), msg
    assert "t = 0.049 s" in msg
    # the state is the last accepted step: the exact uniform motion at t = 0.049 s
    np.testing.assert_allclose(sim.r[0], [-0.05 + sim.t, 0, 0], atol=1e-14)
    np.testing.assert_allclose(sim.R[0], np.eye(3), atol=1e-15)


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_near_singular_start_one_rank_rule(group):
    """The set-up check and the time loop apply one rule (exudyn_lie/mbs/linalg.py): a
    Cholesky pivot of J M^-1 J^T at or below 1e-12 x its row's diagonal.  The smallest
    eigenvalue of the Jacobi-scaled S is about 25 x0^2 here: x0 = 1e-7 (2.5e-13) is
    numerically singular, so construction says so (naming planeA and planeB, rank 2 of 3)
    and switches to the rank-revealing solve, and the run -- moving away from x = 0 -- goes
    through; x0 = 1e-6 (2.5e-11) is regular: no warning, band path, and the run goes
    through too."""
    for x0, singular in ((1e-7, True), (1e-6, False), (0.0, True)):
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always")
            sim = Simulator(sliding_plane_pair(x0), "RK4", group)
        msgs = [str(w.message) for w in rec if "constraints among joints" in str(w.message)]
        assert bool(msgs) == singular, (x0, msgs)
        assert sim.sd.redundant == singular
        if singular:
            assert "redundant" in msgs[0] and "rank 2 of 3" in msgs[0], msgs
            assert sorted(sim.redundantJoints) == ["planeA", "planeB"], msgs
        res = sim.Run(0.1, 1e-3, outputEvery=10)        # no ConstraintError at step 1
        np.testing.assert_allclose(res.r[-1, 0], [x0 + 0.1, 0, 0], atol=1e-13)
        assert np.max(res.jointViolation) < 1e-14
