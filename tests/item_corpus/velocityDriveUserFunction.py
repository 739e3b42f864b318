"""ObjectConnectorCoordinate with velocityLevel=True and an offsetUserFunction_t: a motor rotor
(ObjectRotationalMass1D) run up along a smooth speed profile w(t) = 4 (1 - cos(pi t)) drives a
second rotor through a coordinate spring-damper; that rotor is geared to a third one by a
position-level ObjectConnectorCoordinate (factor1 = 0.5) loaded by a LoadCoordinate."""
import numpy as np
import exudyn as exu
from exudyn.utilities import *  # noqa: F401,F403

import exudyn_lie as exl

_KEEP = []


def UFspeed(mbs, t, itemNumber, lOffset):
    return 4 * (1 - np.cos(np.pi * t))


def Build():
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    _KEEP.append(SC)       # the container must outlive mbs
    nGround = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mCground = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nGround, coordinate=0))
    n0 = mbs.AddNode(Node1D(referenceCoordinates=[0], initialVelocities=[0]))
    mbs.AddObject(ObjectRotationalMass1D(nodeNumber=n0, inertia=0.5))
    n1 = mbs.AddNode(Node1D(referenceCoordinates=[0], initialVelocities=[0]))
    mbs.AddObject(ObjectRotationalMass1D(nodeNumber=n1, inertia=0.1))
    n2 = mbs.AddNode(Node1D(referenceCoordinates=[0], initialVelocities=[0]))
    mbs.AddObject(ObjectRotationalMass1D(nodeNumber=n2, inertia=0.3))
    m0, m1, m2 = (mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=0)) for n in (n0, n1, n2))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mCground, m0], velocityLevel=True,
                                            offsetUserFunction_t=UFspeed))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[m0, m1], stiffness=15, damping=0.05))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[m2, m1], factor1=0.5))        # q2 = 0.5 q1
    mbs.AddLoad(LoadCoordinate(markerNumber=m2, load=-0.4))
    mbs.Assemble()
    simulationSettings = exu.SimulationSettings()
    simulationSettings.timeIntegration.endTime = 1
    simulationSettings.timeIntegration.numberOfSteps = 100
    return mbs, simulationSettings


if __name__ == "__main__":
    mbs, simulationSettings = Build()
    exl.SolveDynamic(mbs, simulationSettings)
    print(mbs.systemData.GetODE2Coordinates())
