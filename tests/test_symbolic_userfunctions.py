"""Exudyn's symbolic user functions (``exudyn.symbolic``, ``CreateSymbolicUserFunction``): Exudyn
evaluates them itself, so the compiled reader hands the model to the Exudyn-evaluated path
(``NotCompiled``), where they act as in a native solve: the same run as Exudyn's RK44 at the same
step, as a Python user function gives (in the style of Exudyn's
``TestModels/symbolicUserFunctionTest.py``)."""
import warnings

import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import CreateSymbolicUserFunction, LoadCoordinate, MarkerNodeCoordinate

import exudyn_lie as exl

esym = exu.symbolic


def spring_force(mbs, t, itemNumber, deltaL, deltaL_t, stiffness, damping, force):
    return 10 * damping * deltaL_t + stiffness * esym.sign(deltaL) * (esym.abs(deltaL)) ** 1.2 + force


def load_force(mbs, t, load):
    return load * esym.sin(10 * (2 * np.pi) * t)


def model(symbolic):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.CreateGround()
    body = mbs.CreateMassPoint(referencePosition=[1.05, 0, 0], mass=1)
    kw = dict(springForceUserFunction=spring_force) if symbolic else {}
    co = mbs.CreateSpringDamper(itemNumbers=[ground, body], referenceLength=0.1, stiffness=100, damping=1, **kw)
    mc = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=0, coordinate=0))
    load = mbs.AddLoad(LoadCoordinate(markerNumber=mc, load=10, loadUserFunction=load_force if symbolic else 0))
    if symbolic:
        mbs.SetObjectParameter(co, "springForceUserFunction",
                               CreateSymbolicUserFunction(mbs, spring_force, "springForceUserFunction", co))
        mbs.SetLoadParameter(load, "loadUserFunction", CreateSymbolicUserFunction(mbs, load_force, "loadUserFunction",
                                                                                  load))
    mbs.Assemble()
    return mbs


def settings(h, T=2.0):
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = T
    ss.timeIntegration.numberOfSteps = int(round(T / h))
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    return ss


def test_symbolic_user_functions_take_the_evaluated_path_and_act_as_natively():
    h = 5e-3
    mbs = model(True)
    with pytest.raises(exl.BridgeError, match=r"springForceUserFunction of type Symbolic"):
        exl.SolveDynamic(mbs, settings(h), showProgress=False, evaluation="compiled")
    with pytest.warns(RuntimeWarning, match=r"Symbolic \(Exudyn evaluates it"):
        exl.SolveDynamic(mbs, settings(h), showProgress=False, solverType=exu.DynamicSolverType.RK44)
    assert mbs.sys["lieGroupSolver"].pathName == "evaluated"
    q = np.array(mbs.systemData.GetODE2Coordinates())
    native = model(True)
    exu.SolveDynamic(native, settings(h), solverType=exu.DynamicSolverType.RK44)
    qn = np.array(native.systemData.GetODE2Coordinates())
    assert np.abs(q - qn).max() < 1e-10 * max(1.0, np.abs(qn).max()), (q, qn)
    # the symbolic law is not the linear one: without the functions the run ends elsewhere
    plain = model(False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exl.SolveDynamic(plain, settings(h), showProgress=False, solverType=exu.DynamicSolverType.RK44)
    assert np.abs(np.array(plain.systemData.GetODE2Coordinates()) - qn).max() > 1e-3
