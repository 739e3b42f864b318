"""Implicit Munthe-Kaas methods (ESDIRK3, mbs/implicit.py): the tableau's properties, the order of
convergence on stiff and constrained models against fine references, the paper's corollary 1 for an
implicit method, the Newton matrix against central differences, stiffness from 1e2 to 1e10, and the
drop-in's own choice of method in SolveDynamic."""
import numpy as np
import pytest

import exudyn as exu
from exudyn.utilities import (MarkerNodePosition, NodePoint, ObjectConnectorSpringDamper, ObjectGround,
                              ObjectMassPoint, MarkerBodyPosition, LoadForceVector)

import exudyn_lie as exl
from exudyn_lie.errors import StepSizeError
from exudyn_lie.integrators import stability as S
from exudyn_lie.integrators.tableau import ESDIRK3, METHODS, get_method
from exudyn_lie.mbs import GROUND, Scene, Simulator
from exudyn_lie.mbs.implicit import newton_jacobian

from test_bridge_common import quiet_settings


# --------------------------------------------------------------------------- the tableau
def test_esdirk3_is_found_by_name_and_is_not_an_explicit_method():
    assert get_method("esdirk3") is ESDIRK3 and get_method("ESDIRK3(2)4L[2]SA") is ESDIRK3
    assert ESDIRK3 not in METHODS
    assert ESDIRK3.implicit and not get_method("RK4").implicit
    assert ESDIRK3.achieved_order() == 3 and ESDIRK3.order_hat == 2 and ESDIRK3.dense.order == 3
    assert not ESDIRK3.fsal                      # its last stage is solved, not evaluated at the result


def test_esdirk3_is_l_stable_and_its_embedded_method_a_stable():
    assert S.is_a_stable(ESDIRK3)
    # L-stable: R(z) ~ C / z for z -> -inf (0.0287 at -1e2, 2.9e-6 at -1e6)
    R = np.abs(S.stability_function(ESDIRK3, [-1e2, -1e4, -1e6]))
    assert np.all(R * [1e2, 1e4, 1e6] < 3.0)
    assert S.is_a_stable(ESDIRK3, ESDIRK3.b_hat)                            # bounded at infinity
    assert S.stability_radius(ESDIRK3) == np.inf
    with pytest.raises(ValueError, match="rational"):
        S.stability_coefficients(ESDIRK3)
    # the explicit methods' polynomial and the general rational form agree
    z = np.array([-0.3 + 0.8j, -2.0, 1.5j])
    c = [float(x) for x in S.stability_coefficients("RK4")]
    assert np.allclose(S.stability_function("RK4", z), np.polyval(c[::-1], z), rtol=1e-14)


def test_a_diagonally_implicit_tableau_needs_one_gamma_and_an_explicit_first_stage():
    from exudyn_lie.integrators.butcher import ButcherTableau
    with pytest.raises(ValueError, match="ESDIRK"):
        ButcherTableau(name="bad", order=1, A=[[0, 0, 0], [0.25, 0.25, 0], [0.2, 0.3, 0.5]], b=[0.3, 0.3, 0.4],
                       c=[0, 0.5, 1.0])
    with pytest.raises(ValueError, match="ESDIRK"):
        ButcherTableau(name="bad2", order=1, A=[[0.5, 0], [0, 0.5]], b=[0.5, 0.5], c=[0.5, 0.5])


# --------------------------------------------------------------------------- models
def chain(k, damping, n=5):
    """A revolute pendulum to the ground followed by bodies on stiff Cartesian and torsional springs."""
    sc = Scene(gravity=[0, 0, -9.81])
    prev = GROUND
    for i in range(n):
        b = sc.AddBody(1.0, np.diag([0.01, 0.02, 0.03]), r0=[0.5 * (i + 1), 0, 0], omega0=[0.1 * i, 0.3, 0.2])
        if prev == GROUND:
            sc.AddRevoluteJoint(GROUND, b, [0, 0, 0], axis=[0, 1, 0])
            sc.AddSpringDamper(GROUND, [0, 0, 0], b, [-0.5, 0, 0], stiffness=10.0)
        else:
            stiff_link(sc, prev, b, k, damping)
        prev = b
    return sc


def stiff_link(sc, prev, b, k, damping):
    """Bodies ``prev`` and ``b`` on a Cartesian spring of stiffness ``k`` between their ends and a
    torsional spring of ``0.01 k``."""
    sc.AddCartesianSpringDamper(prev, [0.25, 0, 0], b, [-0.25, 0, 0], stiffness=[k] * 3, damping=[damping] * 3)
    sc.AddTorsionalSpringDamper(prev, b, stiffness=0.01 * k, damping=0.01 * damping)


def run(sc, method, group, T, h):
    sim = Simulator(sc, method, group, projectInitial=True)
    sim.Run(T, h, outputEvery=int(round(T / h)))
    return sim


def slope(hs, errs):
    return np.polyfit(np.log(hs), np.log(errs), 1)[0]


# --------------------------------------------------------------------------- order and corollary 1
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_order_three_on_a_constrained_chain(group):
    """Springs of 1e4 (|lambda| ~ 1e2, resolved by the steps): the classical order 3."""
    T = 0.2
    ref = run(chain(1e4, 0.0), "RK4", group, T, 1e-5)
    hs = np.array([1e-3, 5e-4, 2.5e-4, 1.25e-4])
    errs = [np.abs(run(chain(1e4, 0.0), "ESDIRK3", group, T, h).r - ref.r).max() for h in hs]
    assert 2.6 <= slope(hs, errs) <= 3.4, errs


def test_stiff_damped_chain_converges_at_the_stage_order_at_least():
    """Springs of 1e6 critically damped (|lambda| up to ~4e3, h |lambda| up to 16 here): RK4 is
    unstable at the larger steps; ESDIRK3 converges, at least at its stage order 2 (the order a
    stiff problem may reduce it to)."""
    T = 0.2
    ref = run(chain(1e6, 2000.0), "RK4", "SE3", T, 1e-5)
    hs = np.array([4e-3, 2e-3, 1e-3, 5e-4])
    errs = [np.abs(run(chain(1e6, 2000.0), "ESDIRK3", "SE3", T, h).r - ref.r).max() for h in hs]
    assert slope(hs, errs) >= 1.9, errs
    assert errs[0] < 1e-4
    with pytest.raises(StepSizeError):
        run(chain(1e6, 2000.0), "RK4", "SE3", T, 4e-3)


def test_fixed_steps_newton_tolerance_follows_the_local_error():
    """Fixed steps: the next step's Newton tolerance is a hundredth of the embedded estimate of the
    last step's local error (relative to its velocity scale, that of the step's start and of its last
    stage's explicit part), within [NEWTON_TOL, FIXED_TOL_MAX]
    (implicit.follow_local_error); recomputed here from the stages the step left behind.  At coarse
    steps of the stiff chain it is looser than NEWTON_TOL: fewer iterations than with NEWTON_TOL held
    (implicit_run.set_newton_tolerance), the same result within a hundredth of the method's error
    (against RK4 at h = 1e-5); at fine steps it is NEWTON_TOL."""
    from exudyn_lie.mbs import implicit as I
    from exudyn_lie.mbs.implicit_run import set_newton_tolerance
    T, h = 0.05, 2e-3
    ref = run(chain(1e6, 2000.0), "RK4", "SE3", T, 1e-5)
    sim = run(chain(1e6, 2000.0), "ESDIRK3", "SE3", T, h)
    tab, nw, wk = sim.method, sim.method.newton, sim.wk
    est = np.max(np.abs(h * np.einsum("j,jik->ik", (tab.b - tab.bhat)[tab.stages], wk.Vd[tab.stages])) * nw.axes)
    vscale = max(np.max(np.abs(wk.Vb) * nw.axes), np.max(np.abs(nw.W) * nw.axes), 1e-300)
    expected = min(I.FIXED_TOL_MAX, max(I.NEWTON_TOL, I.FIXED_KAPPA * est / vscale))
    assert nw.par[I.NP_TOL] == pytest.approx(expected, rel=1e-12) and expected > 10 * I.NEWTON_TOL
    held = Simulator(chain(1e6, 2000.0), "ESDIRK3", "SE3", projectInitial=True)
    set_newton_tolerance(held, I.NEWTON_TOL)
    held.Run(T, h, outputEvery=int(round(T / h)))
    assert held.method.newton.par[I.NP_TOL] == I.NEWTON_TOL
    assert sim.newtonCounters["iterations"] < held.newtonCounters["iterations"]
    err = np.abs(held.r - ref.r).max()
    assert np.abs(sim.r - held.r).max() < 1e-2 * err, (np.abs(sim.r - held.r).max(), err)
    fine = run(chain(1e6, 2000.0), "ESDIRK3", "SE3", 2e-3, 1e-5)
    assert fine.method.newton.par[I.NP_TOL] == I.NEWTON_TOL


def pendulum():
    """A body on a revolute joint to the ground whose frame is off the axis (corollary 1 needs the
    screw, not a pure rotation about the frame's origin), with a stiff torsional spring about it."""
    sc = Scene(gravity=[0, 0, -9.81])
    b = sc.AddBody(2.0, np.diag([0.02, 0.03, 0.04]), r0=[0.5, 0.2, 0.1], omega0=[0, 3.0, 0], name="arm")
    sc.AddRevoluteJoint(GROUND, b, [0.2, 0.2, 0.0], axis=[0, 1, 0], name="hinge")
    Y = [[1, 0, 0], [0, 0, 1], [0, -1, 0]]          # the spring's z axis along the joint's axis y
    sc.AddTorsionalSpringDamper(GROUND, b, rotA=Y, rotB=Y, stiffness=1e5, damping=0.0)
    return sc


def test_corollary_1_holds_for_the_implicit_method_on_se3_not_on_so3xr3():
    """A lower pair to the ground stays exact on SE3 (the stage solution is in the joint's
    subalgebra) and drifts on SO3xR3, without any projection; the torsional spring about the joint's
    axis makes h omega = 3.3 (RK4 blows up at this step)."""
    T, h = 1.0, 5e-3
    viol = {}
    for group in ("SE3", "SO3xR3"):
        sim = Simulator(pendulum(), "ESDIRK3", group, projectInitial=True)
        sim.Run(T, h, outputEvery=int(round(T / h)))
        _, _, pv, rv = sim.Diagnostics()
        viol[group] = max(pv.max(), rv.max())
    assert viol["SE3"] < 1e-12
    assert viol["SO3xR3"] > 1e-7


# --------------------------------------------------------------------------- the Newton matrix
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_newton_jacobian_matches_central_differences(group):
    """The compiled forward-difference Jacobians dF/dV and dF/dTheta (columns per body and algebra
    axis) against central differences of the simulator's own evaluation, at a moving state."""
    from exudyn_lie.mbs.bodies import exp_compose
    sim = Simulator(chain(1e4, 10.0, n=3), "ESDIRK3", group, projectInitial=True)
    sim.Run(0.05, 1e-3, outputEvery=50)
    nw, nb = sim.method.newton, sim.sd.nb
    R, r, V, t = sim.R.copy(), sim.r.copy(), sim.V.copy(), sim.t
    assert sim._evaluate(t, R, r, V) == 0
    A0 = sim.wk.Vd[0].copy()
    assert newton_jacobian(sim.sd, sim.wk, nw, t, R, r, V, A0) == 0
    Dv, Dth = nw.Dv.copy(), nw.Dth.copy()

    def F(X, dV):
        Rp, rp = np.empty_like(R), np.empty_like(r)
        for i in range(nb):
            exp_compose(int(sim.gid[i]), R[i], r[i], np.ascontiguousarray(X[i]), Rp[i], rp[i], np.empty((3, 3)),
                        np.empty(3))
        assert sim._evaluate(t, Rp, rp, np.ascontiguousarray(V + dV)) == 0
        return sim.wk.Vd[0].ravel().copy()

    e = 1e-6
    for col in range(6 * nb):
        d = np.zeros((nb, 6))
        d.flat[col] = e
        cv = (F(np.zeros((nb, 6)), d) - F(np.zeros((nb, 6)), -d)) / (2 * e)
        ct = (F(d, np.zeros((nb, 6))) - F(-d, np.zeros((nb, 6)))) / (2 * e)
        scale = 1.0 + np.abs(cv).max() + np.abs(ct).max()
        assert np.abs(Dv[:, col] - cv).max() <= 2e-5 * scale, col
        assert np.abs(Dth[:, col] - ct).max() <= 2e-5 * scale, col


# --------------------------------------------------------------------------- stiffness 1e2 .. 1e10
@pytest.mark.parametrize("k", [1e2, 1e4, 1e6, 1e8, 1e10])
def test_stiffness_range_no_nan_no_growth(k):
    """A body on an undamped spring released from rest, h = 1e-2 whatever k (h omega up to 1e3):
    finite, energy never above the initial one (L-stability damps what the step does not resolve)."""
    from exudyn_lie.apps import stress_models as M
    sim = Simulator(M.spring_mass(k), "ESDIRK3", "SE3")
    e0 = sim.Diagnostics()[0].sum()
    res = sim.Run(1.0, 1e-2, outputEvery=1)
    assert np.all(np.isfinite(res.r)) and np.all(np.isfinite(res.V))
    assert np.all(res.energy.sum(axis=1) <= e0 * (1 + 1e-9))


def falling_on_a_wall():
    """A body that falls 5 cm onto a stiff, damped one-sided wall (a Python force, switched on inside
    a step: not in the Jacobian of the step's start)."""
    sc = Scene(gravity=[0, 0, -9.81])
    sc.AddBody(1.0, np.eye(3) * 1e-3, r0=[0, 0, 0.05])

    def wall(t, state):
        F = np.zeros((1, 3))
        z, vz = state.r[0, 2], state.vel[0, 2]
        if z < 0:
            F[0, 2] = max(0.0, -1e7 * z - 1e4 * vz)
        return F, np.zeros((1, 3))
    sc.AddPythonForce(wall)
    return sc


def test_newton_failure_in_a_step_is_retried_in_parts():
    """The fixed step is kept where Newton converges and divided where it does not; the run ends and
    agrees with RK4 at a step 30 times smaller (h |lambda| = 3 at the wall: RK4 is unstable at this
    step).  (At h = 1e-3 the contact lasts less than a step: the body bounces back to 0.044 m where
    the reference rests; the step, not the method, cannot resolve it.)"""
    sim = Simulator(falling_on_a_wall(), "ESDIRK3", "SO3xR3")
    sim.Run(0.3, 3e-4, outputEvery=1000)
    ref = Simulator(falling_on_a_wall(), "RK4", "SO3xR3")
    ref.Run(0.3, 1e-5, outputEvery=30000)
    assert sim.dividedSteps >= 1
    assert abs(sim.r[0, 2] - ref.r[0, 2]) < 1e-9 and abs(sim.V[0, 5]) < 1e-9


# --------------------------------------------------------------------------- the drop-in's choice
def stiff_mass_chain(mbs, k=1e8, n=4, damping=2e3):
    """Point masses on stiff springs in a line from the ground, a load on the last (h |lambda| >> 3
    at the script's step)."""
    ground = mbs.AddObject(ObjectGround())
    mg = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0, 0, 0]))
    prev = mg
    for i in range(n):
        nd = mbs.AddNode(NodePoint(referenceCoordinates=[0.1 * (i + 1), 0, 0], initialVelocities=[0, 0.1 * i, 0]))
        o = mbs.AddObject(ObjectMassPoint(physicsMass=1.0, nodeNumber=nd))
        m = mbs.AddMarker(MarkerBodyPosition(bodyNumber=o, localPosition=[0, 0, 0]))
        mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[prev, m], stiffness=k, damping=damping,
                                                  referenceLength=0.1))
        prev = m
    mbs.AddLoad(LoadForceVector(markerNumber=prev, loadVector=[0, 0, -10.0]))
    mbs.AddMarker(MarkerNodePosition(nodeNumber=nd))
    mbs.Assemble()
    return nd


def _solve(method=None, T=0.05, h=1e-3, native=False, factor=1):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    nd = stiff_mass_chain(mbs)
    ss = quiet_settings(T, int(round(T / h)) * factor)
    ss.timeIntegration.generalizedAlpha.spectralRadius = 0.9
    if native:
        ss.timeIntegration.newton.relativeTolerance = 1e-12
        ss.timeIntegration.newton.absoluteTolerance = 1e-12
        ss.timeIntegration.newton.useModifiedNewton = False
        exu.SolveDynamic(mbs, ss)
    elif method is None:
        exl.SolveDynamic(mbs, ss)
    else:
        exl.SolveDynamic(mbs, ss, method=method)
    return np.array(mbs.GetNodeOutput(nd, exu.OutputVariableType.Position))


def test_solve_dynamic_chooses_the_implicit_method_for_a_stiff_model(capsys):
    with pytest.raises(StepSizeError):
        _solve("RK4")                            # named: today's behaviour, the explicit method's error
    capsys.readouterr()
    p = _solve()                                 # no method named: one line says which and why
    out = capsys.readouterr().out
    assert "integrating with the L-stable implicit ESDIRK3" in out and "RK4 is not stable" in out
    fine = _solve(native=True, factor=100)        # generalized-alpha at a 100 times finer step
    native = _solve(native=True)                 # ... and at the script's step
    # measured: 4.9e-6 against generalized-alpha's 2.9e-5 at the same step
    assert np.abs(p - fine).max() < 0.5 * np.abs(native - fine).max()


def test_solve_dynamic_keeps_rk4_where_it_is_stable(capsys):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    stiff_mass_chain(mbs, k=1e2, damping=1.0)
    exl.SolveDynamic(mbs, quiet_settings(0.05, 50))
    assert "ESDIRK3" not in capsys.readouterr().out
    assert mbs.sys["lieGroupSolver"].tableau.name == "RK4"


def slack_rope(mbs):
    """A point mass falling 0.2 m on a slack rope to the ground that turns stiff (1e8 N/m, overdamped: it does not bounce) when taut:
    stable for RK4 at the start (no stiffness yet), not once the rope is taut."""
    ground = mbs.AddObject(ObjectGround())
    mg = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0, 0, 0]))
    nd = mbs.AddNode(NodePoint(referenceCoordinates=[0, 0, -0.8]))
    o = mbs.AddObject(ObjectMassPoint(physicsMass=1.0, nodeNumber=nd))
    m = mbs.AddMarker(MarkerBodyPosition(bodyNumber=o, localPosition=[0, 0, 0]))

    def rope(mbs, t, itemNumber, deltaL, deltaL_t, stiffness, damping, force):
        return stiffness * deltaL + damping * deltaL_t if deltaL > 0 else 0.0
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mg, m], stiffness=1e8, damping=1e5,
                                              referenceLength=1.0, springForceUserFunction=rope))
    mbs.AddLoad(LoadForceVector(markerNumber=m, loadVector=[0, 0, -9.81]))
    mbs.Assemble()
    return nd


def test_a_blow_up_of_the_default_method_continues_implicitly(capsys):
    """Without a method the run goes on, from Exudyn's state at the start of the failing step, with
    ESDIRK3 and says so once; the outputs are all there and the mass hangs on the rope at the end
    (static stretch m g / k = 1e-7 m), as generalized-alpha at a finer step has it."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    nd = slack_rope(mbs)
    ss = quiet_settings(1.0, 1000)
    assert exl.SolveDynamic(mbs, ss)
    out = capsys.readouterr().out
    assert out.count("became unstable") == 1 and "continuing from Exudyn's state" in out
    assert mbs.sys["lieGroupSolver"].tableau.name == "ESDIRK3"
    z = mbs.GetNodeOutput(nd, exu.OutputVariableType.Position)[2]
    SC2 = exu.SystemContainer()
    mbs2 = SC2.AddSystem()
    nd2 = slack_rope(mbs2)
    exu.SolveDynamic(mbs2, quiet_settings(1.0, 100000))
    assert abs(z - mbs2.GetNodeOutput(nd2, exu.OutputVariableType.Position)[2]) < 1e-6


def test_adaptive_steps_with_the_embedded_estimate_and_dense_output():
    """ESDIRK3's embedded order-2 weights control the step, its order-3 dense output serves the
    output times: on the stiff damped chain the outputs at 0.05 s apart agree with the fine reference
    to about the tolerance, with far fewer steps than an explicit pair needs: DOPRI5's stability
    radius 3.3 over the spectral radius of the linearised equations bounds its steps from below."""
    T, rtol = 0.2, 1e-5
    ref = run(chain(1e6, 2000.0), "RK4", "SE3", T, 1e-5)
    times = np.array([0.05, 0.1, 0.15, 0.2])
    refs = []
    sim_ref = Simulator(chain(1e6, 2000.0), "RK4", "SE3", projectInitial=True)
    for t in times:
        sim_ref.Run(t, 1e-5, outputEvery=5000, startTime=sim_ref.t)
        refs.append(sim_ref.r.copy())
    sim = Simulator(chain(1e6, 2000.0), "ESDIRK3", "SE3", projectInitial=True)
    res = sim.Run(T, rtol=rtol, atol=1e-2 * rtol, outputTimes=times)
    errs = [np.abs(res.r[k] - refs[k]).max() for k in range(len(times))]
    assert max(errs) < 1e-4, errs
    assert np.abs(sim.r - ref.r).max() < 1e-4
    explicitSteps = T * Simulator(chain(1e6, 2000.0), "RK4", "SE3", projectInitial=True).SpectralRadius() / 3.3
    assert res.steps < explicitSteps / 3, (res.steps, explicitSteps)
    assert sim.newtonCounters["stages"] >= 3 * res.steps


def test_planar_bodies_on_se2_and_so2xr2():
    """2D bodies (the planar subgroups: only their three algebra axes are Newton unknowns): a pendulum
    pinned to the ground with a stiff spring to a second bar; on SE2 the pivot holds to round-off
    (corollary 1 in the plane), both groups agree with RK4 at a step 100 times smaller."""
    def scene():
        sc = Scene(gravity=(0, -9.81, 0))
        L = 0.5
        b = sc.AddBody2D(1.0, L ** 2 / 12, position=(L / 2, 0), angle=0.0, omega=2.0, velocity=(0, 2.0 * L / 2))
        sc.AddJoint(GROUND, b, (1, 1, 0, 0, 0, 0), posA=(0, 0, 0), posB=(-L / 2, 0, 0), worldTranslation=True)
        c = sc.AddBody2D(0.5, L ** 2 / 24, position=(L + 0.1, 0))
        sc.AddSpringDamper(b, [L / 2, 0, 0], c, [-0.1, 0, 0], stiffness=1e6, damping=10.0, referenceLength=0.0)
        return sc
    T, h = 0.5, 2e-3
    for group in ("SE3", "SO3xR3"):
        sim = Simulator(scene(), "ESDIRK3", group)
        res = sim.Run(T, h, outputEvery=1)
        ref = Simulator(scene(), "RK4", group)
        ref.Run(T, h / 100, outputEvery=100 * int(round(T / h)))
        assert np.abs(sim.r - ref.r).max() < 1e-4
        if group == "SE3":
            assert np.max(res.jointPositionViolation[:, 0]) < 1e-13


# --------------------------------------------------------------------------- the band Newton matrix
def shuffled_chains(k, damping, n, seed=3):
    """Two chains of ``n`` bodies each on stiff Cartesian and torsional springs, each hanging
    from the ground on a revolute joint, with the bodies numbered at random: a sparse Newton
    matrix whose band appears only after renumbering (mbs/band_order.py)."""
    rng = np.random.default_rng(seed)
    sc = Scene(gravity=[0, 0, -9.81])
    order = rng.permutation(2 * n)
    bodies = [None] * (2 * n)
    for slot in order:
        c, i = divmod(int(slot), n)
        bodies[slot] = sc.AddBody(1.0, np.diag([0.01, 0.02, 0.03]), r0=[0.5 * (i + 1), c, 0],
                                  omega0=[0.1 * i, 0.3, 0.2 * (c + 1)])
    for c in range(2):
        prev = GROUND
        for i in range(n):
            b = bodies[c * n + i]
            if prev == GROUND:
                sc.AddRevoluteJoint(GROUND, b, [0, c, 0], axis=[0, 1, 0])
            else:
                stiff_link(sc, prev, b, k, damping)
            prev = b
    return sc


def test_band_newton_matrix_of_a_sparse_model_gives_the_dense_result():
    """24 bodies in two chains, numbered at random: the Newton matrix (n = 144) is factored as a
    band after the reverse Cuthill-McKee numbering, whose half-widths are a small part of n; the
    run equals the one with the dense matrix to far below the method's error (against RK4 at a
    fine step), with the same Newton work."""
    from exudyn_lie.mbs import implicit as I
    T, h = 0.05, 2e-3
    band = Simulator(shuffled_chains(1e6, 2000.0, 12), "ESDIRK3", "SE3", projectInitial=True)
    dense = Simulator(shuffled_chains(1e6, 2000.0, 12), "ESDIRK3", "SE3", projectInitial=True)
    dense.method.newton.par[I.NP_BAND] = 0.0
    for sim in (band, dense):
        sim.Run(T, h, outputEvery=int(round(T / h)))
    st = band.method.newton.st
    assert st[I.NS_BAND] == 1.0 and dense.method.newton.st[I.NS_BAND] == 0.0
    assert max(st[I.NS_KL], st[I.NS_KU]) <= 24, st[I.NS_KL:]          # 144 unknowns, 6 per body
    ref = run(shuffled_chains(1e6, 2000.0, 12), "RK4", "SE3", T, 1e-5)
    err = np.abs(dense.r - ref.r).max()
    assert 1e-9 < err < 1e-4
    assert np.abs(band.r - dense.r).max() < 1e-3 * err
    assert np.abs(band.V - dense.V).max() < 1e-3 * np.abs(dense.V - ref.V).max()
    counts, dcounts = band.newtonCounters, dense.newtonCounters
    assert abs(counts["iterations"] - dcounts["iterations"]) <= 0.05 * dcounts["iterations"], (counts, dcounts)


def test_newton_band_numbering_and_its_rows_of_dth():
    """implicit.newton_band on given Jacobians: two separate chains of bodies numbered at random
    get a band, and ``Db`` holds the rows of D_Theta in the band numbering (row a, column c at
    ``c - a + kl``); a lopsided pattern (every body depends on body 0, body 0 on none) whose band
    rows would be as long as the matrix's stays dense; below BAND_MIN_N unknowns no numbering."""
    from exudyn_lie.mbs import implicit as I
    from exudyn_lie.mbs.band_order import BAND_MIN_N
    rng = np.random.default_rng(5)
    nb = 24
    n = 6 * nb
    nw = I.newton_arrays(np.zeros(nb, np.int64))
    order = rng.permutation(nb)
    for c in range(2):
        chain_ = order[c * 12:(c + 1) * 12]
        for a, b in zip(chain_[:-1], chain_[1:]):
            for p, q in ((a, b), (b, a), (a, a)):
                nw.Dv[6 * p:6 * p + 6, 6 * q:6 * q + 6] = rng.standard_normal((6, 6))
                nw.Dth[6 * p:6 * p + 6, 6 * q:6 * q + 6] = rng.standard_normal((6, 6))
    I.newton_band(nw, n)
    kl, ku = int(nw.st[I.NS_KL]), int(nw.st[I.NS_KU])
    assert nw.st[I.NS_BAND] == 1.0 and kl + ku < n // 3
    P = nw.Dth[np.ix_(nw.perm, nw.perm)]
    assert np.all(np.tril(P, -kl - 1) == 0) and np.all(np.triu(P, ku + 1) == 0)
    for a in range(n):
        for c in range(max(0, a - kl), min(n - 1, a + ku) + 1):
            assert nw.Db[a, c - a + kl] == P[a, c]
        nz = np.nonzero(P[a])[0]              # the product's extent of row a, in band columns
        assert (nw.lo[a], nw.hi[a]) == ((nz[0], nz[-1]) if nz.size else (n, -1))
    lop = I.newton_arrays(np.zeros(nb, np.int64))
    lop.Dv[:, :6] = rng.standard_normal((n, 6))
    I.newton_band(lop, n)
    assert lop.st[I.NS_BAND] == 0.0
    small = I.newton_arrays(np.zeros(BAND_MIN_N // 6 - 1, np.int64))
    small.Dv[:6, 6:12] = 1.0
    I.newton_band(small, small.Dv.shape[0])
    assert small.st[I.NS_BAND] == 0.0 and small.Db.shape == (0, 0)


# --------------------------------------------------------------------------- Jacobians by groups of bodies
def _jacobian_state(n=12):
    """A simulator of the shuffled chains after a few steps, and F at its state (what the stages'
    Jacobian differences from)."""
    from exudyn_lie.mbs.stepper import stage_rhs_at
    sim = Simulator(shuffled_chains(1e6, 2000.0, n), "ESDIRK3", "SE3", projectInitial=True)
    sim.Run(0.004, 2e-3, outputEvery=2)
    A0 = np.zeros_like(sim.V)
    from exudyn_lie.mbs.stepper import copy_state
    copy_state(sim.R, sim.r, sim.V, sim.wk.Rs, sim.wk.rs, sim.wk.Vs)
    assert stage_rhs_at(sim.sd, sim.wk, sim.t, A0) == 0
    return sim, A0


def test_jacobian_by_groups_of_bodies_equals_the_one_column_by_column():
    """Two chains of 12 bodies on springs: a body's motion reaches its neighbours' accelerations
    only, so a few groups of bodies (a distance-2 colouring) take the place of the 24 bodies, and
    the Jacobian by groups is the one made column by column, entry for entry."""
    from exudyn_lie.mbs import implicit as I
    sim, A0 = _jacobian_state()
    dense = I.newton_arrays(sim.sd.gid)
    assert I.newton_jacobian(sim.sd, sim.wk, dense, sim.t, sim.R, sim.r, sim.V, A0) == 0
    ncol = int(dense.st[I.NS_COLORS])
    assert 3 <= ncol <= 6, ncol                          # 24 bodies
    for c in range(24):                                  # no two bodies of a group reach one body
        rows = [np.nonzero(dense.coupled[:, b])[0] for b in range(24) if dense.color[b] == c]
        allrows = np.concatenate(rows) if rows else np.zeros(0)
        assert len(set(allrows.tolist())) == len(allrows)
    from exudyn_lie.mbs.jacobian_groups import probe_coupling
    probed = I.newton_arrays(sim.sd.gid)                 # one evaluation per body finds the same pattern
    assert probe_coupling(sim.sd, sim.wk, sim.t, sim.R, sim.r, sim.V, A0, probed.Ap, probed.axes, probed.coupled,
                          probed.m6) == 0
    np.testing.assert_array_equal(probed.coupled, dense.coupled)
    grouped = I.newton_arrays(sim.sd.gid)
    for name in ("coupled", "color", "st"):
        getattr(grouped, name)[:] = getattr(dense, name)
    assert I.newton_jacobian_grouped(sim.sd, sim.wk, grouped, sim.t, sim.R, sim.r, sim.V, A0) == 0
    assert grouped.st[I.NS_GROUPED] == 1.0
    np.testing.assert_array_equal(grouped.Dv, dense.Dv)
    np.testing.assert_array_equal(grouped.Dth, dense.Dth)
    assert np.count_nonzero(dense.Dth) > 0.05 * dense.Dth.size


def test_jacobian_by_groups_sees_a_coupling_outside_its_pattern():
    """With a pattern that lacks the springs (each body alone) and bodies alternating between two
    groups, the neighbours' rows change outside the pattern: the differences by groups stop
    (NEW_COUPLING), and the Jacobian is made column by column, with the true pattern's groups."""
    from exudyn_lie.mbs import implicit as I
    from exudyn_lie.mbs.jacobian_groups import NEW_COUPLING, grouped_differences
    sim, A0 = _jacobian_state()
    nb = 24
    nw = I.newton_arrays(sim.sd.gid)
    nw.coupled[:] = np.eye(nb, dtype=np.uint8)
    nw.color[:] = np.arange(nb) % 2
    st = grouped_differences(sim.sd, sim.wk, sim.t, sim.R, sim.r, sim.V, A0, nw.Ap, nw.axes, nw.coupled,
                             nw.color, 2, nw.eps, nw.claim, nw.m6, nw.Dv, nw.Dth)
    assert st == NEW_COUPLING
    nw.st[I.NS_COLORS] = 2.0
    assert I.newton_jacobian_grouped(sim.sd, sim.wk, nw, sim.t, sim.R, sim.r, sim.V, A0) == 0
    assert nw.st[I.NS_GROUPED] == 0.0 and nw.st[I.NS_JACOBIANS] == 1.0
    dense = I.newton_arrays(sim.sd.gid)
    assert I.newton_jacobian(sim.sd, sim.wk, dense, sim.t, sim.R, sim.r, sim.V, A0) == 0
    np.testing.assert_array_equal(nw.Dth, dense.Dth)
    assert nw.st[I.NS_COLORS] == dense.st[I.NS_COLORS] > 2


def test_run_with_jacobians_by_groups_is_the_run_column_by_column():
    """The stiff chains over 100 steps: the Jacobians are made by groups (the first with the pattern
    probed), and the run is the same, bit for bit, as with every Jacobian made column by column."""
    from exudyn_lie.mbs import implicit as I
    T, h = 0.2, 2e-3
    sims = [Simulator(shuffled_chains(1e6, 2000.0, 12), "ESDIRK3", "SE3", projectInitial=True) for _ in range(2)]
    sims[1].method.newton.par[I.NP_GROUPS] = 0.0
    for sim in sims:
        sim.Run(T, h, outputEvery=int(round(T / h)))
    grouped, dense = (s.newtonCounters for s in sims)
    assert grouped["jacobians"] == dense["jacobians"] == grouped["groupedJacobians"] >= 2
    assert dense["groupedJacobians"] == 0
    np.testing.assert_array_equal(sims[0].r, sims[1].r)
    np.testing.assert_array_equal(sims[0].V, sims[1].V)


def test_a_wrong_pattern_of_the_groups_does_not_persist():
    """A pattern that lacks every spring, with all bodies in one group, passes the groups' own check
    (each body's rows are its own) and gives a wrong Jacobian: a stage that fails with it is solved
    again with one made column by column, or a slow one makes the next Jacobian find the pattern anew;
    with Newton's own iteration switched off the run ends where the run column by column ends, to
    the Newton tolerance, and the wrong pattern is gone."""
    from exudyn_lie.mbs import implicit as I
    T, h = 0.1, 2e-3
    sims = [Simulator(shuffled_chains(1e6, 2000.0, 12), "ESDIRK3", "SE3", projectInitial=True) for _ in range(2)]
    wrong, dense = sims
    dense.method.newton.par[I.NP_GROUPS] = 0.0
    for sim in sims:
        sim.method.newton.par[I.NP_MAXIT_FULL] = 0.0
    nw = wrong.method.newton
    nw.coupled[:] = np.eye(24, dtype=np.uint8)
    nw.color[:] = 0
    nw.st[I.NS_COLORS] = 1.0
    for sim in sims:
        sim.Run(T, h, outputEvery=int(round(T / h)))
    counts = wrong.newtonCounters
    assert counts["retries"] + counts["jacobians"] > dense.newtonCounters["jacobians"], counts
    assert nw.st[I.NS_COLORS] > 1.0 and nw.coupled.sum() > 24
    assert np.abs(wrong.r - dense.r).max() < 1e-8 and np.abs(wrong.V - dense.V).max() < 1e-6
