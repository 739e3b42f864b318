"""Robustness of the kernel and the bridge: runs reach their end time or say why, bad
states are rejected before anything changes, a blow-up stops at the last accepted step
with a stable suggestion, and the bridge reports coordinate singularities passed between
outputs.  (The same behaviours are probed, with tables, by ``python -m exudyn_lie stress``.)
"""
import contextlib
import math
import warnings

import numpy as np
import pytest

from exudyn_lie.apps import stress_models as M
from exudyn_lie.mbs import GROUND, Scene, SceneError, SimulationError, Simulator, StepSizeError


def small():
    sc = Scene(gravity=[0, 0, -9.81])
    b = sc.AddBody(2.0, np.diag([0.02, 0.03, 0.04]), r0=[0.3, 0, 0], name="arm")
    sc.AddRevoluteJoint(GROUND, b, [0, 0, 0], axis=[0, 1, 0], name="hinge")
    return sc


def test_run_reaches_end_time_and_says_the_last_step_is_shorter():
    sim = Simulator(small(), "RK4", "SE3")
    with pytest.warns(RuntimeWarning, match="not a multiple of stepSize.*last step of 0.1 s"):
        res = sim.Run(1.0, 0.3)
    assert sim.t == 1.0 and res.times[-1] == 1.0 and res.steps == 4
    twin = Simulator(small(), "RK4", "SE3")
    twin.Advance(3, 0.3)
    twin.Advance(1, 1.0 - 3 * 0.3)
    np.testing.assert_array_equal(sim.R, twin.R)


@pytest.mark.parametrize("endTime", [float("nan"), float("inf")])
def test_run_rejects_non_finite_end_time_clearly(endTime):
    sim = Simulator(small(), "RK4", "SE3")
    with pytest.raises(ValueError, match="endTime"):
        sim.Run(endTime, 1e-3)


def test_set_initial_state_rejects_non_rotation():
    sim = Simulator(small(), "RK4", "SE3")
    with pytest.raises(SceneError, match="rotation"):
        sim.SetInitialState(R=np.array([2 * np.eye(3)]))


def test_rejected_set_initial_state_leaves_state_unchanged():
    sim = Simulator(small(), "RK4", "SE3")
    sim.Advance(20, 1e-3)
    R, r, V, t = sim.R.copy(), sim.r.copy(), sim.V.copy(), sim.t
    with pytest.raises(SceneError, match="not finite"):
        sim.SetInitialState(omega=np.array([[np.nan, 0, 0]]))
    assert sim.t == t and np.array_equal(sim.R, R) and np.array_equal(sim.r, r) and np.array_equal(sim.V, V)


@pytest.mark.parametrize("mass", [-1.0, 0.0])
def test_mutated_body_data_is_revalidated(mass):
    sc = small()
    sc.bodies[0].mass = mass
    with pytest.raises(SceneError, match="mass"):
        Simulator(sc, "RK4", "SE3")


def test_spring_parameters_must_be_finite():
    sc = small()
    with pytest.raises(SceneError, match="finite"):
        sc.AddSpringDamper(GROUND, [0, 0, 0], 0, [0, 0, 0], stiffness=float("nan"))





@pytest.mark.parametrize("case", ["nan", "blowup"])
def test_state_after_step_size_error_is_the_last_accepted_step(case):
    if case == "nan":
        make = lambda: _with_nan_force(small())
        h = 1e-3
    else:
        make = lambda: M.spring_mass(1e6)
        h = 1.5 * 2 * math.sqrt(2) / 1e3
    sim = Simulator(make(), "RK4", "SE3")
    # a callback returning NaN is named (SimulationError); a blow-up is a StepSizeError
    with pytest.raises(SimulationError, match="nanAfter50ms" if case == "nan" else "step size"), \
            not_a_multiple(case != "nan"):
        sim.Run(1.0, h, outputEvery=7)
    twin = Simulator(make(), "RK4", "SE3")
    n = int(round(sim.t / h))
    if n:
        twin.Advance(n, h)
    assert np.all(np.isfinite(sim.V))
    np.testing.assert_allclose(sim.V, twin.V, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(sim.R, twin.R, rtol=1e-12, atol=1e-12)


def not_a_multiple(expected=True):
    """The step sizes here come from stability limits, so the span is not a multiple of
    them: the package warns (and shortens the last step); assert that warning."""
    if not expected:
        return contextlib.nullcontext()
    return pytest.warns(RuntimeWarning, match="is not a multiple of stepSize")


def _with_nan_force(sc):
    """A user force that turns NaN at t = 0.05 s: NaN arises mid-run, not at set-up
    (NaN parameters are rejected by the scene itself)."""
    def fn(t, state):
        F = np.zeros((len(sc.bodies), 3))
        if t > 0.05:
            F[:] = np.nan
        return F, np.zeros_like(F)
    sc.AddPythonForce(fn, name="nanAfter50ms")
    return sc


def test_suggested_step_is_stable():
    import re
    k = 1e6
    hmax = 2 * math.sqrt(2) / math.sqrt(k)
    sim = Simulator(M.spring_mass(k), "RK4", "SE3")
    with pytest.raises(StepSizeError) as ei, not_a_multiple():
        sim.Run(1.0, 30 * hmax)
    sugg = float(re.search(r"try a step size of ([0-9.eE+-]+) s", str(ei.value)).group(1))
    sim2 = Simulator(M.spring_mass(k), "RK4", "SE3")
    with not_a_multiple():
        sim2.Run(1.0, sugg, outputEvery=10_000)        # must not raise


def test_step_size_error_states_time_step_and_suggestion():
    """Works today: time, step and a suggestion, and no NaN in the stopped state."""
    k = 1e6
    hmax = 2 * math.sqrt(2) / math.sqrt(k)
    sim = Simulator(M.spring_mass(k), "RK4", "SE3")
    with pytest.raises(StepSizeError, match=r"at t = [0-9.e+-]+ s with step size [0-9.e+-]+ s .*try a step size"), \
            not_a_multiple():
        sim.Run(10.0, 1.02 * hmax)
    assert sim.t > 0 and np.all(np.isfinite(sim.V))


def _rxyz_run(sensor):
    exu = pytest.importorskip("exudyn")
    from exudyn.itemInterface import SensorNode

    from exudyn_lie import bridge
    from exudyn_lie.apps.stress_cases import _exu_settings
    mbs, b, node = M.exudyn_tumbling_body(exu.NodeType.RotationRxyz, omega0=(0.3, 3.0, 0.2))
    if sensor:
        mbs.AddSensor(SensorNode(nodeNumber=node, storeInternal=True,
                                 outputVariableType=exu.OutputVariableType.Coordinates))
        mbs.Assemble()
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        bridge.SolveDynamic(mbs, _exu_settings(1.5, 1500, sensor), method="RK4", liegroup="SE3", showProgress=False)
    return [str(w.message) for w in rec if "Rxyz" in str(w.message)]


def test_bridge_warns_rxyz_singularity_with_output_every_step():
    assert _rxyz_run(sensor=True)


def test_bridge_warns_rxyz_singularity_crossed_between_outputs():
    assert _rxyz_run(sensor=False)


# --------------------------------------------------------------------------- stage-argument domain
def spinner(omega=100.0, torque=0.0, python_force=False):
    """A box spinning about its principal z axis, frame at the COM, no translation: the
    exact motion R(t) = exp(omega t e_z) is a one-parameter subgroup of both groups, so
    both MK updates reproduce it for any step (no stability limit from the spin).  A
    body-fixed torque about z makes omega grow linearly."""
    sc = Scene()
    b = sc.AddBody(1.0, np.diag([0.1, 0.2, 0.3]), omega0=[0, 0, omega], name="spinner")
    if torque:
        sc.AddTorque(b, [0, 0, torque], bodyFixed=True)
    if python_force:
        sc.AddPythonForce(lambda t, st: (np.zeros((1, 3)), np.zeros((1, 3))), name="zero")
    return sc


def _suggestion(msg):
    import re
    return float(re.search(r"try a step size of ([0-9.eE+-]+) s", msg).group(1))


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_stage_argument_below_the_bound_runs_exactly(group):
    """|omega| h = 6.2 < kernel.STAGE_ARG_MAX (2 pi - 9.4e-8): the stages' rotation arguments
    reach 6.2 rad and the run goes on, on the exact motion."""
    from exudyn_lie.groups import so3
    from exudyn_lie.mbs import kernel
    h = 6.2 / 100.0
    assert 6.2 < kernel.STAGE_ARG_MAX < 2 * np.pi
    sim = Simulator(spinner(), "RK4", group)
    sim.Advance(20, h)
    np.testing.assert_allclose(sim.R[0], so3.exp(np.array([0, 0, 100.0 * sim.t])), atol=1e-12)


@pytest.mark.parametrize("python_force", [False, True])
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_stage_argument_near_2pi_is_stopped_with_step_size_error(group, python_force):
    """|omega| h = 2 pi: dexp^-1 of the MK stage equation is singular at the last stage's
    argument Psi_4 = h k_3 (|Psi_4| = |omega| h).  The compiled time loop (and the Python
    stage loop of scenes with callbacks) stops before evaluating that stage, with a
    StepSizeError stating the time, the step and a suggested step; the state is
    untouched, and the suggested step runs."""
    import re
    from exudyn_lie.mbs import kernel
    h = 2 * np.pi / 100.0
    sim = Simulator(spinner(python_force=python_force), "RK4", group)
    R0, V0 = sim.R.copy(), sim.V.copy()
    bound = re.escape(f"{kernel.STAGE_ARG_MAX:.4g} = 2 pi - {2 * np.pi - kernel.STAGE_ARG_MAX:.2g}")
    with pytest.raises(StepSizeError, match=r"\|Psi\| = 6.283 rad, is beyond " + bound + " .*"
                                            r"at t = 0 s with step size 0.0628 s .*try a step size") as ei:
        sim.Advance(20, h)
    assert sim.t == 0.0 and np.array_equal(sim.R, R0) and np.array_equal(sim.V, V0)
    sugg = _suggestion(str(ei.value))
    assert 100.0 * sugg <= np.pi + 1e-9
    Simulator(spinner(python_force=python_force), "RK4", group).Advance(int(1.0 / sugg), sugg)


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_stage_argument_guard_mid_run_keeps_last_accepted_step(group):
    """A torque spins the box up from |omega| h = 6.0 (h = 0.06 s, domega/dt = 10/0.3
    rad/s^2): the stage argument crosses the guard after two steps; the error gives
    that time, and the simulator holds the last accepted step (equal to a twin advanced
    to it)."""
    h = 0.06
    sim = Simulator(spinner(torque=10.0), "RK4", group)
    with pytest.raises(StepSizeError, match=r"MK stage, \|Psi\| = 6\.[23]\d* rad.* at t = [0-9.]+ s") as ei:
        sim.Advance(40, h)
    from exudyn_lie.mbs import kernel
    n = int(round(sim.t / h))
    assert n >= 1 and f"at t = {sim.t:.6g} s" in str(ei.value)
    # |Psi_4| = h |k_3| ~ h omega(t + h/2), omega(t) = 100 + (10 / 0.3) t: the failing step
    # is the first whose mid-step rate crosses the bound (here the step from t = 0.12 s)
    omega = lambda t: 100.0 + 10.0 / 0.3 * t
    assert omega(sim.t + h / 2) * h > kernel.STAGE_ARG_MAX >= omega(sim.t - h / 2) * h, sim.t
    twin = Simulator(spinner(torque=10.0), "RK4", group)
    twin.Advance(n, h)
    np.testing.assert_array_equal(sim.R, twin.R)
    np.testing.assert_array_equal(sim.V, twin.V)
