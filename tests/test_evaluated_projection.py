"""The Exudyn-evaluated path's constraint stabilisation (bridge/evaluated_projection.py): after every
Exudyn step, Gauss-Newton onto Exudyn's own position level and the mass-orthogonal projection onto its
velocity level, the compiled path's rule; the drop-in's default on both paths."""
import warnings

import numpy as np
import pytest

import exudyn as exu

import exudyn_lie as exl
from exudyn_lie.bridge.evaluated_projection import PROJECT_ABOVE
from exudyn_lie.bridge.reader import BridgeError

from test_bridge_common import double_pendulum, oracle


def _double_pendulum():
    return double_pendulum(swinging=True)


def _run(stabilization, evaluation="exudyn", h=0.02, T=2.0, method="RK4"):
    """RK4 at a coarse step (h = 20 ms); returns mbs and the drift warnings."""
    mbs = _double_pendulum()
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps, ss.timeIntegration.endTime = int(round(T / h)), T
    ss.solution.file.write = False
    ss.timeIntegration.verboseMode = 0
    kw = {} if stabilization == "auto" else {"stabilization": stabilization}
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        exl.SolveDynamic(mbs, ss, method=method, evaluation=evaluation, showProgress=False, **kw)
    return mbs, [str(w.message) for w in rec if "drift: Exudyn's residual" in str(w.message)]


def _residuals(mbs):
    """Exudyn's position-level residual and velocity-level residual C_q q_t of the joints at the final
    state (ComputeAlgebraicEquations / ComputeJacobianAE, test_bridge_common.oracle), each relative to
    the scale of the projection's trigger (PROJECT_ABOVE: of max(1, max |q|), max(1, max |q_t|))."""
    sd = mbs.systemData
    q, qt = np.array(sd.GetODE2Coordinates()), np.array(sd.GetODE2Coordinates_t())
    _, _, g, C = oracle(mbs, q, qt, sd.GetTime())
    qa = q + np.array(sd.GetODE2Coordinates(configuration=exu.ConfigurationType.Reference))
    return (float(np.max(np.abs(g))) / max(1.0, float(np.max(np.abs(qa)))),
            float(np.max(np.abs(C @ qt))) / max(1.0, float(np.max(np.abs(qt)))))


def test_default_holds_exudyns_constraints_where_none_drifts():
    """At a step where unstabilised RK4 lets the joints drift past the run-time check's tolerance
    (a drift warning), the default ('position') ends on Exudyn's constraints at both levels within
    the projection's trigger (1e-10 of the scale), without a warning; 'position' named is the default."""
    mbs, drift = _run(None)
    g, gv = _residuals(mbs)
    assert drift and g > 1e-5, (g, drift)
    for stab in ("auto", "position"):
        mbs, drift = _run(stab)
        g, gv = _residuals(mbs)
        assert not drift and g <= PROJECT_ABOVE and gv <= PROJECT_ABOVE, (stab, g, gv, drift)


def test_velocity_stabilization_holds_the_velocity_level_only():
    """'velocity' projects q_t onto C_q q_t = 0 after every step: the velocity level holds, the
    positions still drift (less than without it)."""
    g0, _ = _residuals(_run(None)[0])
    mbs, _ = _run("velocity")
    g, gv = _residuals(mbs)
    assert gv <= PROJECT_ABOVE and 1e-9 < g < g0, (g, gv, g0)


def test_the_paths_agree_with_the_default_stabilization():
    """Both paths project onto the same constraints by the same rule: the final positions agree to
    the methods' error at this step (RK4, h = 5 ms), far below the drift of unstabilised runs."""
    out = {}
    for ev in ("compiled", "exudyn"):
        mbs, _ = _run("auto", evaluation=ev, h=0.005, T=1.0)
        out[ev] = np.array(mbs.systemData.GetODE2Coordinates())
    d = float(np.max(np.abs(out["compiled"] - out["exudyn"])))
    assert d < 1e-5, d


@pytest.mark.parametrize("method,h", [("RK4", 0.05), ("RK4", 0.1), ("ESDIRK3", 0.1)])
def test_coarse_steps_do_not_stop_a_projected_run(method, h):
    """The run-time check stays an oracle under projection by judging the corrections the velocity
    level does not explain (bridge/evaluated_projection.py); a method at a coarse step (ESDIRK3:
    order 3) makes large local errors at the position level, which are such corrections too: they
    must not stop the run as a defect would (its rate rule, constraint_check.UNEXPLAINED_RATE, and
    the velocity level's own drift, METHOD_ERROR_RATIO).  RK4 at 0.1 s is at omega h ~ 1: one step's
    projection corrects 0.09 m of a 1.5 m model at t = 1 s, faster than the rate rule allows; the
    velocity level drifts by as much there, which a moving offset left out does not make it do
    (test_trust.py::test_check_stops_a_velocity_level_that_leaves_the_offset_out).
    (Methods the suite compiles anyway on this path: each other one is a compile of minutes.)"""
    mbs, _ = _run("auto", h=h, T=2.0, method=method)
    g, gv = _residuals(mbs)
    assert g <= PROJECT_ABOVE and gv <= PROJECT_ABOVE, (g, gv)


def test_unknown_stabilization_is_refused_on_the_evaluated_path():
    mbs = _double_pendulum()
    with pytest.raises(BridgeError, match="unknown stabilization"):
        exl.SolveDynamic(mbs, exu.SimulationSettings(), evaluation="exudyn", stabilization="baumgarte")
