"""``exudyn_lie.GetSolveTiming()``: where a SolveDynamic call's time went (set-up, numba's
compilation, the time loop), on both paths."""
import exudyn as exu
import pytest

import exudyn_lie as exl
from exudyn_lie.models import heavy_top


def _solve(**kw):
    mbs, _ = heavy_top.build()
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps = 200
    ss.timeIntegration.endTime = 0.2
    ss.solutionSettings.writeSolutionToFile = False
    exl.SolveDynamic(mbs, ss, showProgress=False, **kw)
    return exl.GetSolveTiming()


@pytest.mark.parametrize("evaluation,path", [("compiled", "compiled"), ("exudyn", "evaluated")])
def test_the_parts_add_up_to_the_call(evaluation, path):
    _solve(evaluation=evaluation)                   # any compilation happens here
    t = _solve(evaluation=evaluation)
    assert t["path"] == path
    assert t["compile"] == 0.0                      # the second call of a kind compiles nothing
    assert t["loop"] > 0 and t["setup"] > 0
    assert t["setup"] + t["compile"] + t["loop"] == pytest.approx(t["total"], rel=1e-9)


def test_a_failed_call_is_timed_too():
    from exudyn_lie.errors import SimulationError
    mbs, _ = heavy_top.build()
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps = 2            # h = 0.5 s: far beyond RK4's stability on the heavy top
    ss.timeIntegration.endTime = 1.0
    ss.solutionSettings.writeSolutionToFile = False
    with pytest.raises(SimulationError):
        exl.SolveDynamic(mbs, ss, showProgress=False, stabilization=None, method="RK4")
    t = exl.GetSolveTiming()
    assert t["total"] > 0 and t["setup"] + t["compile"] + t["loop"] == pytest.approx(t["total"], rel=1e-9)
