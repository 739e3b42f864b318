"""A rigid body on a spherical joint to the ground, driven by an
ObjectConnectorLinearSpringDamper along the ground marker's x axis."""
import exudyn as exu
from exudyn.utilities import *  # noqa: F401,F403

import exudyn_lie as exl

_KEEP = []


def Build():
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    _KEEP.append(SC)       # the container must outlive mbs
    oGround = mbs.CreateGround(referencePosition=[0, 0, 0])
    b0 = mbs.CreateRigidBody(inertia=InertiaCuboid(density=1000, sideLengths=[0.5, 0.1, 0.1]),
                             referencePosition=[0.25, 0, 0], initialAngularVelocity=[0, 0, 1],
                             initialVelocity=[0, 0.25, 0], gravity=[0, 0, -9.81],
                             nodeType=exu.NodeType.RotationEulerParameters)
    mbs.CreateSphericalJoint(itemNumbers=[oGround, b0], position=[0, 0, 0])
    mG = mbs.AddMarker(MarkerBodyRigid(bodyNumber=oGround, localPosition=[0.6, 0.3, 0]))
    mB = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b0, localPosition=[0.25, 0, 0]))
    mbs.AddObject(ObjectConnectorLinearSpringDamper(markerNumbers=[mG, mB], axisMarker0=[1, 0, 0], stiffness=500,
                                                    damping=2, offset=-0.1))
    mbs.Assemble()
    simulationSettings = exu.SimulationSettings()
    simulationSettings.timeIntegration.endTime = 1
    simulationSettings.timeIntegration.numberOfSteps = 100
    return mbs, simulationSettings


if __name__ == "__main__":
    mbs, simulationSettings = Build()
    exl.SolveDynamic(mbs, simulationSettings)
    print(mbs.GetNodeOutput(0, exu.OutputVariableType.Position))
