"""LLVM inline attributes set by name (exudyn_lie/_noinline.py): the stage right-hand side is
inlined by LLVM into the explicit time loops, the group maps stay calls."""
import numba
import pytest
from numba import njit

from exudyn_lie import _noinline
from exudyn_lie.mbs import stepper


def test_the_stage_right_hand_side_is_registered_under_its_own_name():
    """A rename of the function would silently drop its ``alwaysinline`` (and leave every explicit
    stage a call that passes the scene's tuples field by field)."""
    f = stepper.stage_rhs_llvm_inlined.py_func
    assert (f.__module__, f.__qualname__) in _noinline._ALWAYS
    assert not stepper.stage_rhs_llvm_inlined.targetoptions.get("forceinline", False)


BIG = """
def {name}(x):
    s = 0.0
    for i in range(x.shape[0]):
        v = x[i]
        s += v * v * v - 3.0 * v * v + 1.0 / (1.0 + v * v) + (v if v > 0 else -v) * 0.5
        if s > 1e6:
            s = s / 7.0 + v
        elif s < -1e6:
            s = s * 0.25 - v
    for i in range(x.shape[0] - 1, -1, -1):
        x[i] = x[i] * s + (x[i - 1] if i > 0 else 0.0)
    return s
"""


def _calls_of(callee_name, caller, arg):
    caller(arg)
    ir = caller.inspect_llvm(caller.signatures[0])
    return [line for line in ir.splitlines() if "call " in line and callee_name in line]


@pytest.mark.skipif(bool(numba.config.BOUNDSCHECK), reason="the bounds audit (NUMBA_BOUNDSCHECK=1, README Tests) "
                    "changes the callee's code, and LLVM's own choice to keep its call with it")
def test_a_function_registered_by_name_is_inlined_by_llvm_without_forceinline(monkeypatch):
    """The same callee, compiled as a plain function: LLVM keeps the call (twice, the callee is
    not small) unless the callee's (module, qualname) is registered, then no call is left."""
    import numpy as np
    kept = _noinline._ALWAYS

    def build(name, register):
        ns = {"__name__": __name__}
        exec(BIG.format(name=name), ns)
        callee = njit(ns[name])
        if register:
            monkeypatch.setattr(_noinline, "_ALWAYS", kept | {(__name__, name)})

        @njit
        def caller(x):
            return callee(x) + callee(x[::-1].copy())
        return caller

    x = np.linspace(-1.0, 1.0, 9)
    assert _calls_of("plain_callee", build("plain_callee", False), x.copy())
    assert not _calls_of("registered_callee", build("registered_callee", True), x.copy())


def test_the_explicit_time_loops_hold_no_call_of_the_stage_right_hand_side():
    """RK4 and DOPRI5 on one scene: the time loop of each kind links the right-hand side's one
    compiled library and LLVM inlined every call of it (its module for linking, which numba keeps
    also for a kind loaded from the cache; ``inspect_llvm`` is empty there)."""
    import warnings
    from exudyn_lie.apps import bench_topology as BT
    from exudyn_lie.mbs import Simulator
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        Simulator(BT.build_scene("chain", 3), "RK4", "SE3").Advance(2, 1e-3)
        sim = Simulator(BT.build_scene("chain", 3), "DOPRI5", "SE3")
        sim.SetAdaptive(rtol=1e-6, atol=1e-6)
        sim.AdvanceTo(1e-3)
    kinds = {sig[2].instance_class.__name__: cres for sig, cres in stepper.mk_steps.overloads.items()
             if sig[2].instance_class.__name__ in ("Method", "AdaptiveMethod")}
    assert set(kinds) == {"Method", "AdaptiveMethod"}
    for name, cres in kinds.items():
        ir = str(cres.library._get_module_for_linking())
        assert "stage_rhs_llvm_inlined" in ir, name                   # linked into the time loop
        calls = [line for line in ir.splitlines() if "call " in line and "stage_rhs_llvm_inlined" in line]
        assert not calls, (name, calls[:2])
