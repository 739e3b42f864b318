"""Two 2D rigid bodies on ObjectJointRevolute2D joints to the ground, geared by an
ObjectConnectorCoordinate on their angle coordinates (NodeRigidBody2D coordinate 2, factor1),
the first driven by a LoadCoordinate, the second on a coordinate spring-damper to the ground,
gravity on off-centre masses."""
import exudyn as exu
from exudyn.utilities import *  # noqa: F401,F403

import exudyn_lie as exl

_KEEP = []


def Build():
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    _KEEP.append(SC)       # the container must outlive mbs
    oGround = mbs.AddObject(ObjectGround())
    nGround = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mCground = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nGround, coordinate=0))
    nodes = []
    for k, (x, w) in enumerate(((0.0, 3.0), (0.5, -1.5))):
        n = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[x, 0, 0], initialVelocities=[0, 0, w]))
        b = mbs.AddObject(ObjectRigidBody2D(nodeNumber=n, mass=1 + k, inertia=0.05 + 0.1 * k))
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[
            mbs.AddMarker(MarkerBodyRigid(bodyNumber=oGround, localPosition=[x, 0, 0])),
            mbs.AddMarker(MarkerBodyRigid(bodyNumber=b))]))
        mbs.AddLoad(Force(markerNumber=mbs.AddMarker(MarkerBodyPosition(bodyNumber=b, localPosition=[0.1, 0, 0])),
                          loadVector=[0, -9.81 * (1 + k), 0]))
        nodes.append(n)
    ma = [mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=2)) for n in nodes]
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[ma[1], ma[0]], factor1=-0.5))
    mbs.AddLoad(LoadCoordinate(markerNumber=ma[0], load=0.8))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mCground, ma[1]], stiffness=2, damping=0.1))
    mbs.Assemble()
    simulationSettings = exu.SimulationSettings()
    simulationSettings.timeIntegration.endTime = 1
    simulationSettings.timeIntegration.numberOfSteps = 100
    return mbs, simulationSettings


if __name__ == "__main__":
    mbs, simulationSettings = Build()
    exl.SolveDynamic(mbs, simulationSettings)
    print(mbs.systemData.GetODE2Coordinates())
