"""The stage right-hand side compiled once per kind of scene and called through its address
(mbs/rhs_address.py) by the functions outside the stage loop: the implicit stages' Newton
iteration (mbs/implicit.py, mbs/jacobian_groups.py), the dense output's extra stages
(mbs/adaptive.py); the time loop keeps its direct calls.  Read from the modules numba keeps for
linking, also for kinds loaded from the cache."""
import numba
import pytest

from exudyn_lie.apps import bench_topology as BT
from exudyn_lie.errors import SimulationError
from exudyn_lie.mbs import Simulator, implicit, stepper
from exudyn_lie.mbs.codes import EXT_RHS
from exudyn_lie.mbs.rhs_address import rhs_address


def _modules(dispatcher, sim, method=None):
    """The modules for linking of ``dispatcher``'s compiles for ``sim``'s SceneData and Work types
    (and, for the time loop, its method tuple's class)."""
    types = (numba.typeof(sim.sd), numba.typeof(sim.wk))
    return [str(cres.library._get_module_for_linking()) for sig, cres in dispatcher.overloads.items()
            if sig[:2] == types and (method is None or sig[2].instance_class.__name__ == method)]


def test_the_newton_iteration_holds_no_copy_of_the_right_hand_side():
    """ESDIRK3's stage solve (the Newton iteration, its Jacobians by columns and by groups) contains
    none of the right-hand side's code (numba would link it in and compile it again there);
    ``stage_rhs_at`` itself does, once, and its address is the one the Work holds; the time loop
    calls it directly (the fixed steps' watch)."""
    sim = Simulator(BT.build_scene("chain", 3), "ESDIRK3", "SE3")
    sim.Advance(3, 1e-3)
    assert sim.newtonCounters["iterations"] > 0
    rhs = _modules(stepper.stage_rhs_at, sim)
    assert len(rhs) == 1 and "stage_rhs_llvm_inlined" in rhs[0] and "joint_rows" in rhs[0]
    assert sim.wk.ext[EXT_RHS] == rhs_address(sim.sd, sim.wk) != 0
    loop = _modules(stepper.mk_steps, sim, "ImplicitMethod")
    tab = sim.method          # (the stage solve's own compile, loaded from the cache where it is there)
    implicit.solve_stage.compile(tuple(numba.typeof(a) for a in (sim.sd, sim.wk, tab.A, tab.c, tab.gamma, tab.newton,
                                                                  tab.stages, 1, 1e-3, 0.0, sim.R, sim.r, sim.V)))
    solve = _modules(implicit.solve_stage, sim)
    assert len(loop) == 1 and len(solve) == 1
    assert "stage_rhs_at" in loop[0] and "newton_iterate" in solve[0]
    assert "stage_rhs_llvm_inlined" not in solve[0] and "stage_rhs_at" not in solve[0]


def test_a_work_without_the_address_stops_with_an_error_not_a_crash():
    """The call reads the address from the Work: 0 is a status, not a jump to address 0."""
    sim = Simulator(BT.build_scene("chain", 3), "ESDIRK3", "SE3")
    sim.wk.ext[EXT_RHS] = 0
    with pytest.raises(SimulationError, match="without the address of the stage right-hand side"):
        sim.Advance(1, 1e-3)


def test_only_implicit_methods_and_adaptive_steps_load_the_address():
    """Fixed explicit steps, an embedded pair's too, never call through it: their Work has none (the
    separate library costs a process about 0.1 s); adaptive steps (the dense output's extra stages)
    get it when they start."""
    sim = Simulator(BT.build_scene("chain", 3), "DOPRI5", "SE3")
    assert sim.wk.ext[EXT_RHS] == 0
    sim.SetAdaptive(rtol=1e-6, atol=1e-8)
    assert sim.wk.ext[EXT_RHS] == rhs_address(sim.sd, sim.wk) != 0
