"""A point mass (NodePoint + ObjectMassPoint) on a spring-damper to the ground, with gravity
and a force load (LoadForceVector on a MarkerNodePosition)."""
import exudyn as exu
from exudyn.utilities import *  # noqa: F401,F403

import exudyn_lie as exl

_KEEP = []


def Build():
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    _KEEP.append(SC)       # the container must outlive mbs
    oGround = mbs.AddObject(ObjectGround())
    mGround = mbs.AddMarker(MarkerBodyPosition(bodyNumber=oGround, localPosition=[0, 0, 0]))
    n0 = mbs.AddNode(NodePoint(referenceCoordinates=[1, 0, 0], initialVelocities=[0, 1.5, 0.5]))
    mbs.AddObject(ObjectMassPoint(mass=2, nodeNumber=n0))
    m0 = mbs.AddMarker(MarkerNodePosition(nodeNumber=n0))
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mGround, m0], stiffness=400, damping=2,
                                              referenceLength=0.8))
    mbs.AddLoad(LoadForceVector(markerNumber=m0, loadVector=[0, 0, -2 * 9.81]))
    mbs.Assemble()
    simulationSettings = exu.SimulationSettings()
    simulationSettings.timeIntegration.endTime = 1
    simulationSettings.timeIntegration.numberOfSteps = 100
    return mbs, simulationSettings


if __name__ == "__main__":
    mbs, simulationSettings = Build()
    exl.SolveDynamic(mbs, simulationSettings)
    print(mbs.GetNodeOutput(0, exu.OutputVariableType.Position))
