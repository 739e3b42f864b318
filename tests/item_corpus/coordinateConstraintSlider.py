"""A rigid body whose y and z node coordinates are held by ObjectConnectorCoordinate (a slider
along x that may rotate), a second point mass coupled to its x coordinate with factor1 = 2 and
an offset, a coordinate spring-damper to the ground and a LoadCoordinate."""
import exudyn as exu
from exudyn.utilities import *  # noqa: F401,F403

import exudyn_lie as exl

_KEEP = []


def Build():
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    _KEEP.append(SC)       # the container must outlive mbs
    nGround = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mCground = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nGround, coordinate=0))
    b0 = mbs.CreateRigidBody(inertia=InertiaCuboid(density=1000, sideLengths=[0.4, 0.1, 0.1]).Translated([0.1, 0, 0]),
                             referencePosition=[0, 0, 0], initialVelocity=[0.5, 0, 0],
                             initialAngularVelocity=[0.5, 1, 2], gravity=[0, -9.81, 0],
                             nodeType=exu.NodeType.RotationRotationVector)
    nb = mbs.GetObject(b0)["nodeNumber"]
    for k in (1, 2):
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mCground, mbs.AddMarker(
            MarkerNodeCoordinate(nodeNumber=nb, coordinate=k))]))
    mx = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nb, coordinate=0))
    n1 = mbs.AddNode(NodePoint(referenceCoordinates=[1, 0, 0], initialVelocities=[0.25, 0, 0]))
    mbs.AddObject(ObjectMassPoint(mass=0.5, nodeNumber=n1))
    m1x = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n1, coordinate=0))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mx, m1x], factor1=2, offset=0))
    for k in (1, 2):
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mCground, mbs.AddMarker(
            MarkerNodeCoordinate(nodeNumber=n1, coordinate=k))]))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mCground, mx], stiffness=200, damping=1,
                                                        offset=0.05))
    mbs.AddLoad(LoadCoordinate(markerNumber=m1x, load=3))
    mbs.Assemble()
    simulationSettings = exu.SimulationSettings()
    simulationSettings.timeIntegration.endTime = 1
    simulationSettings.timeIntegration.numberOfSteps = 100
    return mbs, simulationSettings


if __name__ == "__main__":
    mbs, simulationSettings = Build()
    exl.SolveDynamic(mbs, simulationSettings)
    print(mbs.GetNodeOutput(0, exu.OutputVariableType.Position))
