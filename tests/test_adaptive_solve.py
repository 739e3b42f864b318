"""SolveDynamic with adaptive steps (issue 18): Exudyn's step-size settings as Exudyn reads
them (docs/ADAPTIVE.md), sensors at Exudyn's output times by dense output, agreement with a
fine native reference and with a fine fixed-step run, refusals before mbs is touched."""
import numpy as np
import pytest

import exudyn as exu
from exudyn.utilities import RotationMatrixZ, SensorBody

import exudyn_lie as exl
from exudyn_lie.bridge.reader import BridgeError
from exudyn_lie.bridge.settings import HONOURED, setting_status
from exudyn_lie.mbs.simulator import StepSizeError
from exudyn_lie.models import heavy_top as HT

from test_bridge_common import add_body, new_mbs, quiet_settings

O = exu.OutputVariableType


def free_body():
    """A free body on a Cartesian spring with gravity and a body-fixed torque (no joints:
    Exudyn's explicit solvers can integrate it natively)."""
    mbs = new_mbs()
    g = mbs.CreateGround()
    b = add_body(mbs, "RotVecLG", [0.5, 0.1, 0], RotationMatrixZ(0.4), omega=(3.0, 2.0, 1.0), vel=(1, 0, 0.5),
                 com=(0.0, 0.0, 0), gravity=[0, 0, -9.81])
    mbs.CreateCartesianSpringDamper(itemNumbers=[g, b], localPosition0=[0.6, 0, 0.1], localPosition1=[0.1, 0, 0],
                                    stiffness=[300, 200, 100], damping=[0.5, 0.5, 0.5])
    s = mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position,
                                 localPosition=[0.1, 0.1, 0]))
    mbs.Assemble()
    return mbs, s


def settings(T, nsteps, tol=None, period=0.01):
    ss = quiet_settings(T, nsteps)
    ss.solution.sensors.active = True
    ss.solution.sensors.writePeriod = period
    if tol is not None:
        ss.timeIntegration.absoluteTolerance = tol
        ss.timeIntegration.relativeTolerance = tol
    return ss


def data(mbs, s):
    return np.asarray(mbs.GetSensorStoredData(s))


def test_the_settings_are_honoured_in_the_table():
    for f in ("adaptiveStep", "absoluteTolerance", "relativeTolerance", "minimumStepSize", "initialStepSize",
              "automaticStepSize", "stepSizeSafety", "stepSizeMaxIncrease"):
        assert setting_status("timeIntegration." + f)[0] == HONOURED
    assert setting_status("timeIntegration.newton.absoluteTolerance")[0] != HONOURED


def test_dopri5_is_adaptive_under_exudyns_default_and_matches_a_fine_native_reference():
    """Exudyn's default adaptiveStep = True: DOPRI5 runs adaptively, with outputs at Exudyn's
    times (every 0.01 s, its step grid: numberOfSteps = 200 bounds the step by
    h_max = 0.01 s as in Exudyn) from dense output.  Reference: Exudyn's own RK44 at
    h = 1e-4."""
    T = 2.0
    mbs, s = free_body()
    ref = settings(T, 20000)
    ref.timeIntegration.solverType = exu.DynamicSolverType.RK44
    mbs.SolveDynamic(ref)
    dref = data(mbs, s)
    for tol, lim in ((1e-6, 1e-5), (1e-9, 1e-8)):
        mbs, s = free_body()
        assert exl.SolveDynamic(mbs, settings(T, 200, tol), method="DOPRI5", showProgress=False)
        d = data(mbs, s)
        tm = mbs.sys["lieGroupSolver"].timing
        assert tm["adaptive"] and tm["rejected"] >= 0 and tm["accepted"] >= 200
        assert d.shape == dref.shape and np.abs(d[:, 0] - dref[:, 0]).max() < 1e-12   # the same output times
        err = np.abs(d[:, 1:] - dref[:, 1:]).max()
        assert err < lim, (tol, err)
    # the final state in mbs is the one at endTime (as in a native solve)
    assert mbs.systemData.GetTime() == pytest.approx(T)


def test_heavy_top_against_a_fine_fixed_step_run_and_fewer_steps():
    """The paper's heavy top (a joint and a stiff spring): adaptive DOPRI5 at tol 1e-8
    against MK-RK4 at h = 5e-5 through the same bridge (sensor every 0.01 s)."""
    def run(method, n, tol=None, adaptive=True):
        mbs, info = HT.build(endTime=1.0)
        s = mbs.AddSensor(SensorBody(bodyNumber=info.bodies[0].objectIndex, storeInternal=True,
                                     outputVariableType=O.Position, localPosition=[0.0, 0.1, 0.2]))
        mbs.Assemble()
        ss = settings(1.0, n, tol)
        ss.timeIntegration.adaptiveStep = adaptive
        exl.SolveDynamic(mbs, ss, method=method, liegroup="SE3", showProgress=False)
        return data(mbs, s), mbs.sys["lieGroupSolver"].timing
    dref, _ = run("RK4", 20000)
    d, tm = run("DOPRI5", 100, 1e-8)
    assert d.shape == dref.shape and np.abs(d[:, 0] - dref[:, 0]).max() < 1e-12
    assert np.abs(d[:, 1:] - dref[:, 1:]).max() < 1e-6
    assert tm["accepted"] < 1000
    dfix, tmfix = run("DOPRI5", 1000, adaptive=False)           # adaptiveStep = False: fixed steps
    assert "adaptive" not in tmfix and tmfix["steps"] == 1000


def test_first_step_from_exudyns_settings():
    """automaticStepSize = False: the first step is h_max (as Exudyn); with
    automaticStepSize and initialStepSize > 0: initialStepSize; otherwise HINIT."""
    def first(auto, h0, n=50, tol=1e-6):
        mbs, s = free_body()
        ss = settings(0.5, n, tol)
        ss.timeIntegration.automaticStepSize = auto
        ss.timeIntegration.initialStepSize = h0
        exl.SolveDynamic(mbs, ss, method="DOPRI5", showProgress=False)
        return mbs.sys["lieGroupSolver"].sim.adaptiveRun.hInitial
    assert first(False, 0.0) == pytest.approx(0.01)
    assert first(True, 1e-5) == pytest.approx(1e-5)
    h = first(True, 0.0, n=5, tol=1e-10)            # HINIT below h_max = 0.1
    assert 1e-5 < h < 0.05


def test_minimum_step_size_stops_with_step_size_error():
    """Exudyn's minimumStepSize: a step below it stops with StepSizeError (time and step)
    instead of Exudyn's endless retries."""
    mbs, s = free_body()
    ss = settings(1.0, 10, 1e-12)
    ss.timeIntegration.minimumStepSize = 0.05
    with pytest.raises(StepSizeError) as ei:
        exl.SolveDynamic(mbs, ss, method="DOPRI5", showProgress=False)
    assert ei.value.step < 0.05 and 0.0 <= ei.value.time < 1.0
    assert "(Exudyn: timeIntegration.minimumStepSize)" in str(ei.value)


@pytest.mark.parametrize("field,value", [("absoluteTolerance", 0.0), ("stepSizeSafety", 1.5),
                                         ("minimumStepSize", 0.5), ("stepSizeMaxIncrease", 1.0)])
def test_bad_step_settings_are_refused_before_mbs_is_touched(field, value):
    mbs, s = free_body()
    q0 = np.array(mbs.systemData.GetODE2Coordinates())
    ss = settings(1.0, 10, 1e-6)
    setattr(ss.timeIntegration, field, value)
    with pytest.raises(BridgeError, match=field):
        exl.SolveDynamic(mbs, ss, method="DOPRI5", showProgress=False)
    assert np.array_equal(np.array(mbs.systemData.GetODE2Coordinates()), q0)
    # RK4 has no pair: the same settings do not concern it
    assert exl.SolveDynamic(mbs, ss, method="RK4", showProgress=False)


def test_bs3_as_odes23_through_solve_dynamic():
    mbs, s = free_body()
    assert exl.SolveDynamic(mbs, settings(0.5, 50, 1e-6), method="ODE23", showProgress=False)
    assert mbs.sys["lieGroupSolver"].tableau.name == "BS3"
    assert mbs.sys["lieGroupSolver"].timing["adaptive"]
