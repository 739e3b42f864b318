"""exl.SolveDynamic's solverType (argument, else timeIntegration.solverType, as Exudyn reads
them): explicit types select Exudyn's tableau, implicit ones are replaced as documented, the
rest are refused before mbs is touched (exudyn_lie/bridge/solvertype.py)."""
import warnings

import numpy as np
import pytest

import exudyn as exu

import exudyn_lie as exl
from exudyn_lie.bridge import BridgeError
from exudyn_lie.bridge.solvertype import EXPLICIT, REFUSED
from exudyn_lie.integrators import get_method

from test_bridge_errors import assert_unchanged, snapshot
from test_bridge_solve import data, free_body, settings

DST = exu.DynamicSolverType


def fixed_settings(T, h, solverType=None):
    """Fixed steps h also for Exudyn's ODE23 / DOPRI5: no step-size control (both flags
    False, docs/ADAPTIVE.md) and tolerances no step can violate (Exudyn stops at a rejected
    step when the control is off)."""
    ss = settings(T, h)
    ti = ss.timeIntegration
    ti.automaticStepSize = False
    ti.adaptiveStep = False
    ti.absoluteTolerance = ti.relativeTolerance = 1e10
    if solverType is not None:
        ti.solverType = solverType
    return ss


def exl_run(T, h, **kw):
    mbs, b, s = free_body()
    ss = kw.pop("ss", None) or fixed_settings(T, h)
    exl.SolveDynamic(mbs, ss, liegroup="SO3xR3", **kw)
    return mbs, data(mbs, s), mbs.systemData.GetODE2Coordinates()


def native_run(T, h, solverType):
    mbs, b, s = free_body()
    mbs.SolveDynamic(fixed_settings(T, h, solverType))
    return data(mbs, s)


def test_every_explicit_type_of_exudyn_is_mapped():
    explicit = {n for n in dir(DST) if not n.startswith("_") and n not in ("name", "value")} - set(REFUSED) \
        - {"GeneralizedAlpha", "TrapezoidalIndex2"}
    assert explicit == set(EXPLICIT)


@pytest.mark.parametrize("name", [n for n, tab in EXPLICIT.items() if not tab.partitioned])
def test_explicit_type_is_its_tableau_and_agrees_with_exudyns_run(name):
    """solverType=X runs exactly method=EXPLICIT[X] (bit-identical), also when X comes from
    the settings; on an unconstrained RotVecLG body Exudyn's explicit Lie group solver makes
    the same SO3xR3 Munthe-Kaas update, so with the same tableau and h the two agree to
    round-off (measured ~5e-15 on sensor values of size 0.77).  VelocityVerlet: this body's
    damping and gyroscopic forces depend on the velocity, where Exudyn's scheme and the partitioned
    tableau differ by their order-1 errors: tests/test_velocity_verlet.py (type, method and setting
    alike there, and against Exudyn's run where they agree)."""
    T, h = 0.3, 1e-3
    tab = EXPLICIT[name]
    mbs, by_type, q = exl_run(T, h, solverType=getattr(DST, name))
    assert mbs.sys["lieGroupSolver"].tableau is tab
    _, by_method, q2 = exl_run(T, h, method=tab)
    _, by_setting, q3 = exl_run(T, h, ss=fixed_settings(T, h, getattr(DST, name)))
    assert np.array_equal(by_type, by_method) and np.array_equal(by_type, by_setting)
    assert np.array_equal(q, q2) and np.array_equal(q, q3)
    native = native_run(T, h, getattr(DST, name))
    assert native.shape == by_type.shape
    assert np.max(np.abs(native - by_type)) < 1e-13


@pytest.mark.parametrize("name,classical", [("RK33", "RK3"), ("RK67", "RK6")])
def test_exudyns_rk33_rk67_are_not_the_classical_rk3_rk6(name, classical):
    """The agreement above identifies the coefficients: at h = 1e-2 Exudyn's RK33 / RK67 agree
    with exudyn_lie's RK33 / RK67 to round-off, while the catalogue's Kutta RK3 / Butcher RK6
    (same orders, other tableaus) differ by their O(h^p) errors (measured 2.8e-4 / 5.8e-8)."""
    T, h = 0.3, 1e-2
    native = native_run(T, h, getattr(DST, name))
    same = exl_run(T, h, solverType=getattr(DST, name))[1]
    other = exl_run(T, h, method=classical)[1]
    assert np.max(np.abs(native - same)) < 1e-13
    assert np.max(np.abs(native - other)) > 1e-9


def test_generalized_alpha_given_is_the_default_without_warning():
    T, h = 0.1, 1e-3
    _, default, _ = exl_run(T, h, ss=settings(T, h))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mbs, given, _ = exl_run(T, h, ss=settings(T, h), solverType=DST.GeneralizedAlpha)
        _, given_dopri, _ = exl_run(T, h, ss=settings(T, h), solverType=DST.GeneralizedAlpha, method="DOPRI5")
    assert mbs.sys["lieGroupSolver"].tableau is get_method("RK4")
    assert np.array_equal(default, given)
    assert not np.array_equal(default, given_dopri)


@pytest.mark.parametrize("where", ["argument", "settings"])
def test_trapezoidal_index2_is_replaced_with_a_warning_naming_what_ran(where):
    T, h = 0.1, 1e-3
    _, default, _ = exl_run(T, h, ss=settings(T, h))
    ss = settings(T, h)
    kw = {}
    if where == "argument":
        kw["solverType"] = DST.TrapezoidalIndex2
    else:
        ss.timeIntegration.solverType = DST.TrapezoidalIndex2
    before = ss.timeIntegration.solverType
    with pytest.warns(RuntimeWarning, match=r"TrapezoidalIndex2 .*replaced.*method RK4 on the Lie groups "
                                            r"SO3xR3 \(1\)"):
        _, got, _ = exl_run(T, h, ss=ss, **kw)
    assert np.array_equal(default, got)
    assert ss.timeIntegration.solverType == before                          # settings unchanged
    with pytest.warns(RuntimeWarning, match=r"method DOPRI5"):
        exl_run(T, h, ss=settings(T, h), solverType=DST.TrapezoidalIndex2, method="DOPRI5")


def test_argument_takes_the_place_of_the_setting():
    T, h = 0.1, 1e-3
    mbs, _, _ = exl_run(T, h, ss=fixed_settings(T, h, DST.RK67), solverType=DST.RK44)
    assert mbs.sys["lieGroupSolver"].tableau.name == "RK4"
    mbs, _, _ = exl_run(T, h, ss=fixed_settings(T, h, DST.RK67), solverType=DST.RK44, method="rk-4")
    assert mbs.sys["lieGroupSolver"].tableau.name == "RK4"


def expect_refused(match, ss=None, **kw):
    mbs, b, s = free_body()
    snap = snapshot(mbs)
    with pytest.raises(BridgeError, match=match):
        exl.SolveDynamic(mbs, ss or settings(0.01, 1e-3), **kw)
    assert_unchanged(mbs, snap)


def test_types_without_counterpart_and_inconsistent_combinations_are_refused_untouched():
    expect_refused(r"solverType=DynamicSolverType.DVERK6: Exudyn 1.13.6's own SolveDynamic does not",
                   solverType=DST.DVERK6)
    expect_refused(r"simulationSettings.timeIntegration.solverType=DynamicSolverType.DVERK6",
                   ss=fixed_settings(0.01, 1e-3, DST.DVERK6))
    expect_refused(r"solverType=DynamicSolverType.VelocityVerlet \(the tableau VelocityVerlet\) and method='Heun'",
                   solverType=DST.VelocityVerlet, method="Heun")
    expect_refused(r"solverType=DynamicSolverType.RK44 \(the tableau RK4\) and method='DOPRI5' name different",
                   solverType=DST.RK44, method="DOPRI5")
    expect_refused(r"timeIntegration.solverType=DynamicSolverType.RK67 \(the tableau RK67\) and method='RK4'",
                   ss=fixed_settings(0.01, 1e-3, DST.RK67), method="RK4")
    expect_refused(r"solverType='RK44' is not an exudyn.DynamicSolverType", solverType="RK44")
    expect_refused(r"unknown method 'RK5'", solverType=DST.RK44, method="RK5")
