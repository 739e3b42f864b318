"""A first-order coordinate that becomes stiff during the run is watched (trust).

Exudyn's ``lugreFrictionTest.py`` (Examples) models LuGre friction as an ``ObjectGenericODE1``:
position X, velocity V and the bristle state Z, ``Zdot = V - Z |V| / G(V)`` with ``G ~ 1e-5``.  At
rest Z is not stiff (the check at the initial state passes RK4); once the mass slides, ``|V| / G``
is about 1e4 1/s and RK4 at the script's h = 5e-4 s is beyond its stability radius.  The stages'
watch reads the ODE2 bodies only, and the run went on with RK4 to the end, every value finite, 0.48
off a fine run.  Now the ODE1 coordinates' own modes (the eigenvalues of d(ydot)/dy at the last
stage, the mechanical state held; bridge/evaluated_stiffness.ode1_rate) join the watch: the run the
drop-in chooses switches to ESDIRK3, a named RK4 stops with a StepSizeError that says why.

The model here is the script's LuGre part with the pull started near break-away, so that sliding
begins after 0.1 s.  The reference, computed here: Exudyn's DOPRI5 at fixed steps of h/10 (5e-5 s,
stable there; 1e-11 from its adaptive run at tolerances 1e-11 and from its run at h/20, by hand).
"""
import warnings

import numpy as np
import pytest

import exudyn as exu
from exudyn.itemInterface import NodeGenericODE1, ObjectGenericODE1, SensorNode

import exudyn_lie as exl
from exudyn_lie.bridge import evaluated_problem
from exudyn_lie.errors import StepSizeError

K, MASS, S0, S2, FC, FS, VS = 2.0, 1.0, 1e5, 0.4, 1.0, 1.5, 1e-3     # lugreFrictionTest.py's values
S1 = np.sqrt(S0)
U0, VPULL = 0.74, 0.1            # the spring's end: U = U0 + VPULL t (the script: U0 = 0)
T, H = 0.5, 5e-4


def _lugre():
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    n = mbs.AddNode(NodeGenericODE1(referenceCoordinates=[0, 0, 0], initialCoordinates=[0, 0, 0],
                                    numberOfODE1Coordinates=3))

    def rhs(mbs, t, itemNumber, q):
        X, V, Z = q
        G = (FC + (FS - FC) * np.exp(-(V / VS) ** 2)) / S0
        Zt = V - Z * abs(V) / G
        return [V, (K * (U0 + VPULL * t - X) - (S0 * Z + S1 * Zt + S2 * V)) / MASS, Zt]

    mbs.AddObject(ObjectGenericODE1(nodeNumbers=[n], rhsUserFunction=rhs))
    s = mbs.AddSensor(SensorNode(nodeNumber=n, storeInternal=True,
                                 outputVariableType=exu.OutputVariableType.Coordinates))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime, ss.timeIntegration.numberOfSteps = T, int(round(T / H))
    ss.timeIntegration.verboseMode = 0
    ss.solutionSettings.writeSolutionToFile = False
    ss.solutionSettings.sensorsWritePeriod = 1e-2
    return mbs, ss, s


@pytest.fixture(scope="module")
def reference():
    mbs, ss, s = _lugre()
    ss.timeIntegration.numberOfSteps *= 10
    ss.timeIntegration.adaptiveStep = False
    mbs.SolveDynamic(ss, solverType=exu.DynamicSolverType.DOPRI5)
    return mbs.GetSensorStoredData(s)


def _error(series, reference):
    """Largest error of X and V over the sensor's rows, relative to their largest values."""
    assert series.shape == reference.shape
    return max(np.max(np.abs(series[:, c] - reference[:, c])) / np.max(np.abs(reference[:, c])) for c in (1, 2))


def _dropin(capsys):
    mbs, ss, s = _lugre()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")         # (the evaluated path's and the solver type's notices)
        exl.SolveDynamic(mbs, ss, solverType=exu.DynamicSolverType.TrapezoidalIndex2)
    return mbs.GetSensorStoredData(s), capsys.readouterr().out


def test_the_dropin_switches_when_the_friction_state_becomes_stiff(reference, capsys):
    series, out = _dropin(capsys)
    assert "RK4 became unstable after t = 0.1" in out and "ESDIRK3" in out and "d(ydot)/dy" in out
    assert _error(series, reference) < 1e-5          # (RK4 to the end: above 0.1, below)


def test_without_the_watch_rk4_runs_to_the_end_far_off(reference, capsys, monkeypatch):
    """The control: with the ODE1 rate taken as zero (the watch as it was), nothing stops the run
    and nothing says it is wrong; the assertion above could fail."""
    monkeypatch.setattr(evaluated_problem.EvaluatedProblem, "_ode1_rate", lambda self: 0.0)
    series, out = _dropin(capsys)
    assert "became unstable" not in out
    assert np.all(np.isfinite(series))
    assert _error(series, reference) > 0.1


def test_a_named_rk4_stops_and_says_why():
    mbs, ss, _ = _lugre()
    with warnings.catch_warnings(), pytest.raises(StepSizeError) as e:
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, ss, method="RK4")
    msg = str(e.value)
    assert "d(ydot)/dy" in msg and "first-order coordinates" in msg
    assert 0.1 < e.value.time < 0.2


def test_the_watch_costs_a_bounded_number_of_evaluations():
    """Forty ODE1 coordinates (decays, one of them stiff for RK4 at this step only while t > 0.05 s):
    the watch's Jacobian needs n1 + 1 evaluations of Exudyn's ODE1 right-hand side; it runs every
    ceil(41 / 16) = 3 steps, so each step costs at most about 16 more calls of the user function
    than RK4's 4 stages, and the stiff mode is still found (within 3 steps of its start)."""
    n1, h, T1 = 40, 1e-3, 0.1
    calls = [0]
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    n = mbs.AddNode(NodeGenericODE1(referenceCoordinates=[0] * n1, initialCoordinates=[1.0] * n1,
                                    numberOfODE1Coordinates=n1))

    def rhs(mbs, t, itemNumber, q):
        calls[0] += 1
        rates = -np.asarray(q)
        if t > 0.05:
            rates[7] *= 3.2e3                 # h |lambda| = 3.2 > RK4's 2.79: grows 1.8 times per step
        return rates
    mbs.AddObject(ObjectGenericODE1(nodeNumbers=[n], rhsUserFunction=rhs))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime, ss.timeIntegration.numberOfSteps = T1, int(round(T1 / h))
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    with warnings.catch_warnings(), pytest.raises(StepSizeError) as e:
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, ss, method="RK4")
    steps = int(round(e.value.time / h))
    assert 0.05 <= e.value.time <= 0.05 + 4 * h and "d(ydot)/dy" in str(e.value)
    assert calls[0] <= (4 + 16) * (steps + 1) + 200       # (200: the set-up's evaluations, a margin)
