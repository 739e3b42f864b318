"""ObjectConnectorCoordinate with velocityLevel=True (constant offset): a rotor
(ObjectRotationalMass1D) turning at a prescribed speed, as the drives of Exudyn's sliderCrank3D
and ballBearing tests, winds up a coordinate spring to a second rotor; a rigid body (RotVec node)
whose x rate is tied to a Mass1D's rate (factor1, offset) while a spring pulls it back, its y and z
held by position-level coordinate constraints."""
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
    omega = 6.0
    n0 = mbs.AddNode(Node1D(referenceCoordinates=[0], initialVelocities=[omega]))
    mbs.AddObject(ObjectRotationalMass1D(nodeNumber=n0, inertia=0.5))
    n1 = mbs.AddNode(Node1D(referenceCoordinates=[0], initialVelocities=[0.0]))
    mbs.AddObject(ObjectRotationalMass1D(nodeNumber=n1, inertia=0.2))
    m0 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n0, coordinate=0))
    m1 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n1, coordinate=0))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mCground, m0], offset=omega, velocityLevel=True))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[m0, m1], stiffness=20, damping=0.1))

    b0 = mbs.CreateRigidBody(inertia=InertiaCuboid(density=1000, sideLengths=[0.2, 0.1, 0.1]),
                             referencePosition=[0, 0, 0], initialVelocity=[0.5, 0, 0],
                             initialAngularVelocity=[0.3, 0.5, 1], gravity=[0, -9.81, 0],
                             nodeType=exu.NodeType.RotationRotationVector)
    nb = mbs.GetObject(b0)["nodeNumber"]
    for k in (1, 2):
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mCground, mbs.AddMarker(
            MarkerNodeCoordinate(nodeNumber=nb, coordinate=k))]))
    mx = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nb, coordinate=0))
    nP = mbs.AddNode(Node1D(referenceCoordinates=[0.2], initialVelocities=[0.1]))
    mbs.AddObject(ObjectMass1D(nodeNumber=nP, mass=1.5))
    mP = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nP, coordinate=0))
    # 2 xdot_body - xdot_P = 0.9 (consistent with the initial velocities)
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mP, mx], factor1=2, offset=0.9, velocityLevel=True))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mCground, mP], stiffness=50, damping=0.2))
    mbs.Assemble()
    simulationSettings = exu.SimulationSettings()
    simulationSettings.timeIntegration.endTime = 1
    simulationSettings.timeIntegration.numberOfSteps = 100
    return mbs, simulationSettings


if __name__ == "__main__":
    mbs, simulationSettings = Build()
    exl.SolveDynamic(mbs, simulationSettings)
    print(mbs.systemData.GetODE2Coordinates())
