"""The stability check before a run of a named explicit method counts the run's length.

Explicit methods of order 5 and above (DOPRI5, RK67) leave the imaginary axis at the origin: an
undamped oscillation grows by ``|R(i h omega)| - 1 = O((h omega)^(p+2))`` in every step.  The check
counted any growth as instability and refused Exudyn's ``solverExplicitODE1ODE2test.py`` (RK67 at
h omega = 1, 20 steps: 1 % in all), which Exudyn runs.  Over the run's steps a growth of at most
``RUN_GROWTH`` (10 %) is now the method's error, not instability (mbs/stiffness.largest_stable_step).
"""
import warnings

import numpy as np
import pytest

import exudyn as exu
from exudyn.itemInterface import NodeGenericODE2, ObjectGenericODE2

import exudyn_lie as exl
from exudyn_lie.errors import StepSizeError
from exudyn_lie.integrators.stability import stability_coefficients
from exudyn_lie.integrators.tableau import get_method
from exudyn_lie.mbs.stiffness import RUN_GROWTH, largest_stable_step

OMEGA, H = 10.0, 0.1


def test_largest_stable_step_over_a_run():
    rk67 = get_method("RK67")
    ev = np.array([1j * OMEGA, -1j * OMEGA])
    strict = largest_stable_step(rk67, ev)
    assert 0.015 < strict < 0.02                      # |R(iy)| > 1 from y = 0.19 on
    h20, h1000 = largest_stable_step(rk67, ev, 20), largest_stable_step(rk67, ev, 1000)
    assert h1000 < H < h20
    c = np.array([float(x) for x in stability_coefficients(rk67)])
    growth = abs(np.polyval(c[::-1], 1j * OMEGA * h20)) ** 20
    assert growth == pytest.approx(RUN_GROWTH, rel=1e-6)
    rk4 = get_method("RK4")                  # no growth inside (0, 2 sqrt 2): the edge, where |R| rises steeply
    assert largest_stable_step(rk4, ev, 20) == pytest.approx(largest_stable_step(rk4, ev), rel=1e-3)


def _oscillator(T):
    """Two undamped masses on springs (omega = 10 and 7.07 1/s), as Exudyn's test's ODE2 part."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    n = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0, 0], initialCoordinates=[1, 0],
                                    initialCoordinates_t=[0, 0], numberOfODE2Coordinates=2))
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[n], massMatrix=np.diag([2.0, 2.0]),
                                    stiffnessMatrix=np.diag([200.0, 100.0]), forceVector=[0, 1]))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime, ss.timeIntegration.numberOfSteps = T, int(round(T / H))
    ss.timeIntegration.verboseMode = 0
    ss.solutionSettings.writeSolutionToFile = False
    return mbs, ss


def _run(T, native):
    mbs, ss = _oscillator(T)
    if native:
        mbs.SolveDynamic(ss, solverType=exu.DynamicSolverType.RK67)
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            exl.SolveDynamic(mbs, ss, solverType=exu.DynamicSolverType.RK67, showProgress=False)
    return np.array(mbs.systemData.GetODE2Coordinates())


def test_a_short_run_beyond_the_strict_limit_runs_as_exudyn_and_a_long_one_stops():
    """RK67 at h omega = 1: 20 steps run (Exudyn's own RK67 at the same step agrees, the exact
    solution x = cos(omega t) is 2.5e-3 away from both); 1000 steps grow 1.7 times: StepSizeError."""
    T = 2.0
    got, nat = _run(T, False), _run(T, True)
    exact = np.cos(OMEGA * T)
    print(f"\nRK67, h omega = 1, 20 steps: exudyn_lie {got[0]:.10f}, Exudyn {nat[0]:.10f}, exact {exact:.10f}")
    assert abs(got[0] - nat[0]) < 1e-9
    assert 1e-3 < abs(got[0] - exact) < 5e-2
    with pytest.raises(StepSizeError, match="beyond the stability limit"):
        _run(100.0, False)
