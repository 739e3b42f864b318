"""A small drive train of Node1D items: a RotationalMass1D driven by a LoadCoordinate, geared
(ObjectConnectorCoordinate, factor1) to a second one on a torsional coordinate spring, a piston
(ObjectMass1D on a line rotated by referenceRotation, with gravity through MarkerBodyMass)
coupled to the first rotor by a coordinate spring-damper and held by a spring at a rigid marker."""
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
    n0 = mbs.AddNode(Node1D(referenceCoordinates=[0], initialVelocities=[2.0]))
    mbs.AddObject(ObjectRotationalMass1D(nodeNumber=n0, inertia=0.5))
    n1 = mbs.AddNode(Node1D(referenceCoordinates=[0.3], initialVelocities=[-5.0]))
    mbs.AddObject(ObjectRotationalMass1D(nodeNumber=n1, inertia=1.5))
    m0 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n0, coordinate=0))
    m1 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n1, coordinate=0))
    mbs.AddLoad(LoadCoordinate(markerNumber=m0, load=1.5))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[m1, m0], factor1=-2.5))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mCground, m1], stiffness=40, damping=0.5))
    nP = mbs.AddNode(Node1D(referenceCoordinates=[0.1], initialVelocities=[0.3]))
    oP = mbs.AddObject(ObjectMass1D(nodeNumber=nP, mass=1.5, referencePosition=[0, 0, 0.2],
                                    referenceRotation=RotationMatrixY(-0.4)))
    mP = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nP, coordinate=0))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[m0, mP], stiffness=60, damping=0.2,
                                                        offset=0.05))
    mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=oP)),
                                     loadVector=[0, 0, -9.81]))
    oGround = mbs.AddObject(ObjectGround())
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[
        mbs.AddMarker(MarkerBodyRigid(bodyNumber=oGround)),
        mbs.AddMarker(MarkerBodyRigid(bodyNumber=oP, localPosition=[0, 0.1, 0]))], stiffness=30, referenceLength=0.3))
    mbs.Assemble()
    simulationSettings = exu.SimulationSettings()
    simulationSettings.timeIntegration.endTime = 1
    simulationSettings.timeIntegration.numberOfSteps = 100
    return mbs, simulationSettings


if __name__ == "__main__":
    mbs, simulationSettings = Build()
    exl.SolveDynamic(mbs, simulationSettings)
    print(mbs.systemData.GetODE2Coordinates())
