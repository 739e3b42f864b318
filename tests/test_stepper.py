"""The one compiled Munthe-Kaas stepper (exudyn_lie.mbs.stepper): against the Python
reference oracle, the skipped stages, the right-hand side evaluated in Python, and a
user's own Butcher tableau end to end (Simulator, SolveDynamic, StepSizeError)."""
import math
import re
import warnings

import numpy as np
import pytest

from exudyn_lie import Simulator, StepSizeError
from exudyn_lie.models import heavy_top as HT
from exudyn_lie.integrators import ButcherTableau, get_method
import reference_mk as mk
from exudyn_lie.integrators.stability import stability_coefficients, stability_radius
from exudyn_lie.mbs import stepper
from exudyn_lie.mbs.methods import needed_stages


def _two_bodies(python_force=None):
    """The paper's heavy top (the models' one builder) with a second body on a revolute joint."""
    sc = HT.scene()
    b = 0
    b2 = sc.AddBody(mass=2.0, inertia=[0.1, 0.2, 0.3], com=[0.1, 0, 0], r0=[1.0, 0, 0], omega0=[0.3, 0.1, 2.0])
    sc.AddRevoluteJoint(b, b2, [1.0, 0, 0], axis=[0, 0, 1])
    if python_force is not None:
        sc.AddPythonForce(python_force)
    return sc


def _sim(method="RK4", liegroup="SE3", python_force=None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Simulator(_two_bodies(python_force), method=method, liegroup=liegroup, projectInitial=True)


# ------------------------------------------------------------------ against the oracle
@pytest.mark.parametrize("method", ["ExplicitEuler", "RK4", "DOPRI5", "RK6"])
@pytest.mark.parametrize("liegroup", ["SE3", "SO3xR3"])
def test_one_step_equals_the_reference_oracle(method, liegroup):
    """One compiled step equals tests/reference_mk.py's step with the same right-hand side
    (the simulator's own index-1 accelerations) to round-off."""
    sim = _sim(method, liegroup)
    sim.Advance(3, 1e-3)                                  # a generic state
    t, R, r, V = sim.t, sim.R.copy(), sim.r.copy(), sim.V.copy()
    h = 2e-3

    def rhs(tt, g, VV):
        Rg = np.array([x[0] for x in g])
        rg = np.array([x[1] for x in g])
        assert sim._evaluate(tt, np.ascontiguousarray(Rg), np.ascontiguousarray(rg), np.ascontiguousarray(VV)) == 0
        return sim.wk.Vd[0].copy()

    g1, V1 = mk.mk_step(method, [liegroup] * 2, [(R[i], r[i]) for i in range(2)], V, t, h, rhs)
    sim.R[:], sim.r[:], sim.V[:], sim.t = R, r, V, t
    sim.Advance(1, h)
    for i in range(2):
        np.testing.assert_allclose(sim.R[i], g1[i][0], rtol=0, atol=1e-13)
        np.testing.assert_allclose(sim.r[i], g1[i][1], rtol=0, atol=1e-13)
    np.testing.assert_allclose(sim.V, V1, rtol=1e-12, atol=1e-12)


# ------------------------------------------------------------------ skipped stages
def test_needed_stages():
    assert needed_stages(*get_method("RK4").arrays()[:2]).tolist() == [0, 1, 2, 3]
    assert needed_stages(*get_method("DOPRI5").arrays()[:2]).tolist() == [0, 1, 2, 3, 4, 5]
    # a zero-weight stage that a weighted later stage uses is needed; one no stage uses is not
    A = np.array([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1.0, 0]])
    assert needed_stages(A, np.array([0.5, 0.0, 0.5, 0.0])).tolist() == [0, 1, 2]


@pytest.mark.parametrize("liegroup", ["SE3", "SO3xR3"])
def test_dopri5_without_its_7th_stage_is_bit_identical(liegroup):
    """DOPRI5's 7th (FSAL) stage has b_7 = 0 and no later stage: skipping it changes no bit."""
    runs = []
    for stages in (None, np.arange(7, dtype=np.int64)):
        sim = _sim("DOPRI5", liegroup)
        if stages is not None:
            m = sim.method
            sim.method = m._replace(stages=stages)
        assert len(sim.method.stages) == (6 if stages is None else 7)
        sim.Advance(200, 2e-3)
        runs.append((sim.R.copy(), sim.r.copy(), sim.V.copy(), sim.Accelerations()[0]))
    for a, b in zip(*runs):
        assert np.array_equal(a, b)


# ------------------------------------------------------------------ right-hand side in Python
def test_python_forces_run_in_the_compiled_stepper():
    """A Python force equals the same force as a compiled load (to round-off: the sums are
    ordered differently) and is called once per evaluated stage."""
    calls = []

    def force(t, st):
        calls.append(t)
        F = np.zeros((2, 3))
        F[1] = [3.0, -2.0, 1.0]
        return F, np.zeros((2, 3))

    sim_py = _sim("DOPRI5", python_force=force)
    sc = _two_bodies()
    sc.AddForce(1, [3.0, -2.0, 1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim_c = Simulator(sc, method="DOPRI5", liegroup="SE3", projectInitial=True)
    n0 = len(calls)
    sim_py.Advance(50, 2e-3)
    assert len(calls) - n0 == 50 * 6                      # 6 evaluated stages of DOPRI5
    sim_c.Advance(50, 2e-3)
    np.testing.assert_allclose(sim_py.V, sim_c.V, rtol=1e-11, atol=1e-11)
    np.testing.assert_allclose(sim_py.r, sim_c.r, rtol=1e-12, atol=1e-12)


def test_python_force_exception_keeps_the_last_step():
    class Boom(Exception):
        pass

    def force(t, st):
        if t > 0.01:
            raise Boom("from the user's force")
        return np.zeros((2, 3)), np.zeros((2, 3))

    sim = _sim("RK4", python_force=force)
    with pytest.raises(Boom, match="from the user's force"):
        sim.Advance(100, 1e-3)
    assert 0.009 < sim.t <= 0.011 and np.all(np.isfinite(sim.V))
    t = sim.t
    R = sim.R.copy()
    sim2 = _sim("RK4", python_force=lambda t, st: (np.zeros((2, 3)), np.zeros((2, 3))))
    sim2.Advance(int(round(t / 1e-3)), 1e-3)
    assert np.array_equal(sim2.R, R)                      # the last accepted step, unchanged


# ------------------------------------------------------------------ a user's own tableau
def _ralston3():
    """Ralston's third-order method: not in the catalogue."""
    return ButcherTableau(name="MyRalston3", order=3, A=[[0, 0, 0], ["1/2", 0, 0], [0, "3/4", 0]],
                          b=["2/9", "1/3", "4/9"], c=[0, "1/2", "3/4"])


def test_stability_radius_from_the_coefficients():
    tab = _ralston3()
    # every 3-stage third-order method has R(z) = 1 + z + z^2/2 + z^3/6
    assert stability_coefficients(tab) == stability_coefficients("RK3")
    assert stability_radius(tab) == stability_radius("RK3")
    rk4 = get_method("RK4")
    mine = ButcherTableau(name="MyRK4", order=4, A=rk4._exact_coeffs[0], b=rk4._exact_coeffs[1],
                          c=rk4._exact_coeffs[2])
    assert stability_radius(mine) == stability_radius("RK4")


def test_custom_tableau_in_simulator_with_step_size_error():
    from exudyn_lie.apps import stress_models as M
    k = 1e6
    tab = _ralston3()
    hmax = 2.5 / math.sqrt(k)
    sim = Simulator(M.spring_mass(k), tab, "SE3")
    h = 1.0 / 13          # endTime a multiple of the step (no last-step warning), far beyond hmax
    assert h > 30 * hmax
    with pytest.raises(StepSizeError, match="method MyRalston3") as ei:
        sim.Run(1.0, h)
    sugg = float(re.search(r"try a step size of ([0-9.eE+-]+) s", str(ei.value)).group(1))
    assert sugg < h
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = Simulator(M.spring_mass(k), tab, "SE3").Run(0.05, sugg, outputEvery=10_000)   # must not raise
    assert res.method == "MyRalston3"


def test_custom_tableau_equal_coefficients_bit_identical():
    rk4 = get_method("RK4")
    mine = ButcherTableau(name="MyRK4", order=4, A=rk4._exact_coeffs[0], b=rk4._exact_coeffs[1],
                          c=rk4._exact_coeffs[2])
    a, b = _sim(rk4), _sim(mine)
    a.Advance(100, 1e-3)
    b.Advance(100, 1e-3)
    assert np.array_equal(a.R, b.R) and np.array_equal(a.V, b.V)


def test_custom_tableau_in_solve_dynamic():
    exu = pytest.importorskip("exudyn")
    import exudyn_lie as exl
    from exudyn.utilities import SensorBody
    from exudyn_lie.models import heavy_top

    def build():
        mbs, info = heavy_top.build()
        body = info.bodies[0].objectIndex
        sensor = mbs.AddSensor(SensorBody(bodyNumber=body, storeInternal=True,
                                          outputVariableType=exu.OutputVariableType.Position))
        mbs.Assemble()
        return info.SC, mbs, body, sensor
    rk4 = get_method("RK4")
    mine = ButcherTableau(name="MyRK4", order=4, A=rk4._exact_coeffs[0], b=rk4._exact_coeffs[1],
                          c=rk4._exact_coeffs[2])
    out = []
    for method in ("RK4", mine, _ralston3()):
        SC, mbs, body, sensor = build()
        ss = exu.SimulationSettings()
        ss.timeIntegration.endTime = 0.2
        ss.timeIntegration.numberOfSteps = 200
        ss.solution.file.write = False
        assert exl.SolveDynamic(mbs, ss, method=method, liegroup="SE3", showProgress=False)
        out.append((np.array(mbs.systemData.GetODE2Coordinates()), mbs.GetSensorStoredData(sensor)))
    assert np.array_equal(out[0][0], out[1][0]) and np.array_equal(out[0][1], out[1][1])
    # the third-order method against the fourth-order one at h = 1e-3: its own error, about
    # (h omega)^3 with omega ~ 20 rad/s (3.2e-6 measured), not equal and not far off
    d = np.max(np.abs(out[2][0] - out[0][0]))
    assert 1e-8 < d < 1e-4
    with pytest.raises(exl.bridge.BridgeError, match="ButcherTableau"):
        exl.SolveDynamic(build()[1], ss, method=42)


def test_fixed_step_control_is_the_default():
    sim = _sim()
    assert sim.control.kind == stepper.CONTROL_FIXED
