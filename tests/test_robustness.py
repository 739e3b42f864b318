"""Robustness of the kernel and the bridge: runs reach their end time or say why, bad
states are rejected before anything changes, a blow-up stops at the last accepted step
with a stable suggestion, and the bridge reports coordinate singularities passed between
outputs.  (The same behaviours are probed, with tables, by ``python -m exudyn_lie stress``.)
"""
import math
import warnings

import numpy as np
import pytest

from exudyn_lie.analysis import stress_models as M
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
    with pytest.raises(SimulationError, match="nanAfter50ms" if case == "nan" else "step size"):
        sim.Run(1.0, h, outputEvery=7)
    twin = Simulator(make(), "RK4", "SE3")
    n = int(round(sim.t / h))
    if n:
        twin.Advance(n, h)
    assert np.all(np.isfinite(sim.V))
    np.testing.assert_allclose(sim.V, twin.V, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(sim.R, twin.R, rtol=1e-12, atol=1e-12)


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
    with pytest.raises(StepSizeError) as ei:
        sim.Run(1.0, 30 * hmax)
    sugg = float(re.search(r"try a step size of ([0-9.eE+-]+) s", str(ei.value)).group(1))
    sim2 = Simulator(M.spring_mass(k), "RK4", "SE3")
    sim2.Run(1.0, sugg, outputEvery=10_000)        # must not raise


def test_step_size_error_states_time_step_and_suggestion():
    """Works today: time, step and a suggestion, and no NaN in the stopped state."""
    k = 1e6
    hmax = 2 * math.sqrt(2) / math.sqrt(k)
    sim = Simulator(M.spring_mass(k), "RK4", "SE3")
    with pytest.raises(StepSizeError, match=r"at t = [0-9.e+-]+ s with step size [0-9.e+-]+ s .*try a step size"):
        sim.Run(10.0, 1.02 * hmax)
    assert sim.t > 0 and np.all(np.isfinite(sim.V))


def _rxyz_run(sensor):
    exu = pytest.importorskip("exudyn")
    from exudyn.itemInterface import SensorNode

    from exudyn_lie import bridge
    from exudyn_lie.analysis.stress_cases import _exu_settings
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
