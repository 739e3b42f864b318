"""The mbs-level PreNewtonResidualUserFunction and SystemJacobianUserFunction on the
Exudyn-evaluated path, in the style of Exudyn's ``mainSystemUserFunctionsTest.py``
('ReplicateSpringDamper'): a load that a PreNewtonResidualUserFunction sets from the state before
every evaluation replicates a spring-damper, and a SystemJacobianUserFunction gives Exudyn's
Newton its Jacobian.  Exudyn calls the first before each Newton residual; exudyn_lie before each
stage's evaluation (bridge/evaluated.py), and adds the second to an implicit method's Jacobian
(bridge/evaluated_jacobian.py).  The reference is the same mass on a CoordinateSpringDamper,
evaluated by Exudyn too."""
import warnings

import numpy as np
import pytest

import exudyn as exu
from exudyn.itemInterface import (CoordinateSpringDamper, LoadCoordinate, MarkerNodeCoordinate, MassPoint,
                                  NodePointGround, Point, SensorNode)

import exudyn_lie as exl

K, D, MASS = 4000.0, 8.0, 2.0


def build(replicate, h=1e-3, T=0.5, stiff=1.0):
    mbs = exu.SystemContainer().AddSystem()
    # a free mass first: the spring's coordinate is ODE2 index 3, beyond the size of the user's
    # Jacobian container (Exudyn adds its triplets whatever that size, as the TestModel relies on)
    mbs.AddObject(MassPoint(physicsMass=MASS, nodeNumber=mbs.AddNode(Point(initialVelocities=[0, 0.1, 0]))))
    n = mbs.AddNode(Point(referenceCoordinates=[0, 0, 0], initialCoordinates=[0.1, 0, 0]))
    mbs.AddObject(MassPoint(physicsMass=MASS, nodeNumber=n))
    mN = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=0))
    k, d = K * stiff, D * stiff ** 0.5
    if replicate:
        load = mbs.AddLoad(LoadCoordinate(markerNumber=mN, load=0))
        mbs.Assemble()
        i = mbs.GetNodeODE2Index(n)

        def preNewton(mbs, t, newtonIt, discontinuousIt):
            u = mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates)[0]
            v = mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates_t)[0]
            mbs.SetLoadParameter(load, "load", -k * u - d * v)

        def jacobian(mbs, t, factorODE2, factorODE2_t, factorODE1):
            mc = exu.MatrixContainer()
            mc.SetWithSparseMatrix([[i, i, -factorODE2 * k - factorODE2_t * d]], 1, 1)    # (the size Exudyn ignores)
            return mc
        mbs.SetPreNewtonResidualUserFunction(preNewton)
        mbs.SetSystemJacobianUserFunction(jacobian)
    else:
        mG = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0))
        mbs.AddObject(CoordinateSpringDamper(markerNumbers=[mG, mN], stiffness=k, damping=d))
    s = mbs.AddSensor(SensorNode(nodeNumber=n, storeInternal=True, outputVariableType=exu.OutputVariableType.Coordinates))
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps, ss.timeIntegration.endTime = int(round(T / h)), T
    ss.timeIntegration.verboseMode = 0
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = False
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = T / 50
    return mbs, ss, s


def _x(mbs, s):
    return np.asarray(mbs.GetSensorStoredData(s))[:, 1]


@pytest.mark.parametrize("stiff, method", [(1.0, None), (1e4, None)])
def test_a_load_set_before_each_evaluation_replicates_the_spring_damper(stiff, method):
    """omega h = 0.045 at stiff 1: RK4; at stiff 1e4 (omega h = 4.5, beyond RK4) the drop-in takes
    the implicit ESDIRK3 for both models: its stability estimate and its Newton Jacobian hold the
    SystemJacobianUserFunction's part (without it the load is a constant in Exudyn's Jacobian, RK4
    is chosen and the runs part by 0.07 m).  Both runs evaluate the same forces in the same order:
    equal to rounding (measured: 0 m)."""
    mbs, ss, s = build(False, stiff=stiff)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, ss, showProgress=False, evaluation="exudyn")     # (the same path: no other kernel)
    ref = _x(mbs, s)
    mbs, ss, s = build(True, stiff=stiff)
    with pytest.warns(RuntimeWarning, match="PreNewtonResidualUserFunction"):
        exl.SolveDynamic(mbs, ss, showProgress=False)
    x = _x(mbs, s)
    print(f"\nstiffness x {stiff:g}: the replicated spring-damper {np.abs(x - ref).max():.3g} m from the item's run "
          f"(amplitude {np.abs(ref).max():.3g} m)")
    assert np.abs(x - ref).max() < 1e-9
    assert np.ptp(ref) > 0.05


def test_the_compiled_path_refuses_them():
    mbs, ss, s = build(True)
    with pytest.raises(exl.BridgeError if hasattr(exl, "BridgeError") else Exception,
                       match="PreNewtonResidualUserFunction|SystemJacobianUserFunction"):
        exl.SolveDynamic(mbs, ss, showProgress=False, evaluation="compiled")
