"""Exudyn's step reduction after a failed discontinuous iteration, followed by the
Exudyn-evaluated path (bridge/solver.loop_settings' followSteps, bridge/time_loop.py's hook).

The model is Exudyn's ``contactCoordinateTest.py`` made small: a mass point dropped onto an
``ObjectContactCoordinate`` whose contact state is a data coordinate that Exudyn's PostNewton
switches.  With ``discontinuous.maxIterations = 2`` and ``ignoreMaxIterations = False`` a step
in which the contact opens or closes fails its discontinuous iteration; Exudyn then repeats it
from its start with a smaller step (``adaptiveStep``, Exudyn's default) and grows the step back
afterwards.  Before, exudyn_lie held Exudyn's loop to fixed steps and the run stopped with
"reduction of step size reached minimum step size", where Exudyn's own solve runs.  Reference:
generalized-alpha at a 1000 times finer step (0.2 s)."""
import warnings

import numpy as np
import pytest

import exudyn as exu
from exudyn.itemInterface import (LoadCoordinate, MarkerNodeCoordinate, MassPoint, NodeGenericData, NodePointGround,
                                  ObjectContactCoordinate, Point, SensorNode)

import exudyn_lie as exl

H, T = 2e-4, 0.05


def build(h=H, adaptiveStep=True):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    r, mass = 0.05, 0.25
    nData = mbs.AddNode(NodeGenericData(initialCoordinates=[1], numberOfDataCoordinates=1))
    n1 = mbs.AddNode(Point(referenceCoordinates=[0, 0, 0], initialCoordinates=[0, r + 0.002, 0],
                           initialVelocities=[0, -0.5, 0]))
    mbs.AddObject(MassPoint(physicsMass=mass, nodeNumber=n1))
    mG = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0))
    mN = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n1, coordinate=1))
    mbs.AddObject(ObjectContactCoordinate(markerNumbers=[mG, mN], nodeNumber=nData, contactStiffness=2e6,
                                          contactDamping=200, offset=r))
    mbs.AddLoad(LoadCoordinate(markerNumber=mN, load=-mass * 9.81))
    s = mbs.AddSensor(SensorNode(nodeNumber=n1, outputVariableType=exu.OutputVariableType.Position,
                                 storeInternal=True))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ti = ss.timeIntegration
    ti.numberOfSteps, ti.endTime = int(round(T / h)), T
    ti.minimumStepSize = 1e-10
    ti.verboseMode = 0
    ti.adaptiveStep = adaptiveStep
    ti.discontinuous.iterationTolerance = 1e-3       # the contact force's error accepted
    ti.discontinuous.maxIterations = 2
    ti.discontinuous.ignoreMaxIterations = False     # a step that fails is repeated smaller
    ti.adaptiveStepRecoverySteps = 0
    ti.adaptiveStepIncrease = 10
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = 1e-10          # every step
    return mbs, ss, s


def _height(mbs, s):
    d = np.asarray(mbs.GetSensorStoredData(s))
    return d[:, 0], d[:, 2]


def test_a_dropped_mass_follows_exudyns_reduced_steps_and_agrees_with_a_fine_native_run():
    mbs, ss, s = build(H / 1000)
    mbs.SolveDynamic(ss)
    _, yRef = _height(mbs, s)
    mbs, ss, s = build()
    mbs.SolveDynamic(ss, solverType=exu.DynamicSolverType.TrapezoidalIndex2)
    _, yNative = _height(mbs, s)
    mbs, ss, s = build()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, ss, solverType=exu.DynamicSolverType.TrapezoidalIndex2)
    t, y = _height(mbs, s)
    dt = np.diff(t)
    print(f"\nfinal height: exudyn_lie {abs(y[-1] - yRef[-1]):.3g} m from generalized-alpha at h/1000, "
          f"TrapezoidalIndex2 at h {abs(yNative[-1] - yRef[-1]):.3g} m; {len(t)} outputs, smallest step "
          f"{dt.min():.3g} s")
    assert t[-1] == pytest.approx(T, abs=1e-12)
    assert dt.min() < 0.5 * H and np.all(dt <= H * (1 + 1e-9))     # Exudyn's steps, reduced and grown back
    assert abs(y[-1] - yRef[-1]) < 1e-5
    assert np.min(y) < 0.05                                          # it was in contact


def test_without_adaptive_steps_the_run_stops_where_exudyns_own_stops():
    mbs, ss, s = build(adaptiveStep=False)
    with pytest.raises(exu.SolverError if hasattr(exu, "SolverError") else Exception):
        mbs.SolveDynamic(ss, solverType=exu.DynamicSolverType.TrapezoidalIndex2)
    mbs, ss, s = build(adaptiveStep=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(Exception, match="minimum step size"):
            exl.SolveDynamic(mbs, ss, solverType=exu.DynamicSolverType.TrapezoidalIndex2)
