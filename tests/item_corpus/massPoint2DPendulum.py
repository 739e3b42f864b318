"""A planar pendulum: a NodePoint2D + ObjectMassPoint2D on an ObjectConnectorDistance to the
ground, gravity as LoadMassProportional."""
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
    n0 = mbs.AddNode(NodePoint2D(referenceCoordinates=[1, 0], initialVelocities=[0, 0.5]))
    o0 = mbs.AddObject(ObjectMassPoint2D(mass=0.5, nodeNumber=n0))
    m0 = mbs.AddMarker(MarkerNodePosition(nodeNumber=n0))
    mbs.AddObject(ObjectConnectorDistance(markerNumbers=[mGround, m0], distance=1))
    mMass = mbs.AddMarker(MarkerBodyMass(bodyNumber=o0))
    mbs.AddLoad(LoadMassProportional(markerNumber=mMass, loadVector=[0, -9.81, 0]))
    mbs.Assemble()
    simulationSettings = exu.SimulationSettings()
    simulationSettings.timeIntegration.endTime = 1
    simulationSettings.timeIntegration.numberOfSteps = 100
    return mbs, simulationSettings


if __name__ == "__main__":
    mbs, simulationSettings = Build()
    exl.SolveDynamic(mbs, simulationSettings)
    print(mbs.GetNodeOutput(0, exu.OutputVariableType.Position))
