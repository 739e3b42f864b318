"""A double pendulum of point masses hung by distance constraints from an ObjectMassPoint on a
NodePointGround (Exudyn accepts a mass point on a ground node: it has no coordinates and stays
at the node's position), as in Exudyn's fourBarMechanismTest: a distance constraint and a
spring-damper from markers on the ground node, with gravity and the z coordinates held by
coordinate constraints on the ground node's coordinate.  (A body marker on that mass point
crashes Exudyn's own solver, and exudyn_lie refuses it.)"""
import exudyn as exu
from exudyn.utilities import *  # noqa: F401,F403

import exudyn_lie as exl

_KEEP = []


def Build():
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    _KEEP.append(SC)       # the container must outlive mbs
    n0 = mbs.AddNode(NodePointGround(referenceCoordinates=[0.2, 0.5, 0]))
    mbs.AddObject(ObjectMassPoint(physicsMass=0, nodeNumber=n0))
    n1 = mbs.AddNode(NodePoint(referenceCoordinates=[1.2, 0.5, 0], initialVelocities=[0, 0.3, 0]))
    n2 = mbs.AddNode(NodePoint(referenceCoordinates=[1.2, -0.5, 0]))
    for n in (n1, n2):
        o = mbs.AddObject(ObjectMassPoint(physicsMass=1.5, nodeNumber=n))
        mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=o)),
                                         loadVector=[0, -9.81, 0]))
    mNode0 = mbs.AddMarker(MarkerNodePosition(nodeNumber=n0))
    m1 = mbs.AddMarker(MarkerNodePosition(nodeNumber=n1))
    m2 = mbs.AddMarker(MarkerNodePosition(nodeNumber=n2))
    mbs.AddObject(ObjectConnectorDistance(markerNumbers=[mNode0, m1], distance=1.0))
    mbs.AddObject(ObjectConnectorDistance(markerNumbers=[m1, m2], distance=1.0))
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mNode0, m2], stiffness=20, damping=0.5,
                                              referenceLength=1.2))
    mc0 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n0, coordinate=0))
    for n in (n1, n2):
        mc = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=2))
        mbs.AddObject(CoordinateConstraint(markerNumbers=[mc0, mc]))
    mbs.Assemble()
    simulationSettings = exu.SimulationSettings()
    simulationSettings.timeIntegration.endTime = 1
    simulationSettings.timeIntegration.numberOfSteps = 200
    return mbs, simulationSettings


if __name__ == "__main__":
    mbs, simulationSettings = Build()
    exl.SolveDynamic(mbs, simulationSettings)
    print(mbs.GetNodeOutput(2, exu.OutputVariableType.Position))
