"""A wheel (disc of radius 0.2 m, axis along its local x) rolling on the ground with
ObjectJointRollingDisc (constrainedAxes all locked), tilted and spinning, under gravity; after
Exudyn's TestModels/rollingCoinTest.py with a larger disc."""
import exudyn as exu
import numpy as np
from exudyn.utilities import *  # noqa: F401,F403

import exudyn_lie as exl

_KEEP = []


def Build(spin=-2.5):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    _KEEP.append(SC)       # the container must outlive mbs
    r, m, phi0 = 0.2, 2.0, 0.15
    A0 = RotationMatrixY(phi0)
    omega0 = np.array([spin, 0, 1.0])          # rolling about the disc axis + turning (spin = -7: the
    # disc turns more than 2 pi in 1 s; tests/test_node_parameter_tracking checks the sign of the
    # Euler parameters written then)
    pC = np.zeros(3)
    p0 = pC + A0 @ [0, 0, r]                   # centre above the contact point
    v0 = np.cross(omega0, p0 - pC)             # contact point at rest
    inertia = RigidBodyInertia(mass=m, inertiaTensor=np.diag([0.5 * m * r ** 2, 0.25 * m * r ** 2, 0.25 * m * r ** 2]))
    b0 = mbs.CreateRigidBody(referencePosition=list(p0), referenceRotationMatrix=A0, initialVelocity=list(v0),
                             initialAngularVelocity=list(omega0), inertia=inertia, gravity=[0, 0, -9.81])
    oGround = mbs.AddObject(ObjectGround())
    mbs.AddObject(ObjectJointRollingDisc(markerNumbers=[mbs.AddMarker(MarkerBodyRigid(bodyNumber=oGround)),
                                                        mbs.AddMarker(MarkerBodyRigid(bodyNumber=b0))],
                                         constrainedAxes=[1, 1, 1], discRadius=r))
    mbs.Assemble()
    simulationSettings = exu.SimulationSettings()
    simulationSettings.timeIntegration.endTime = 1
    simulationSettings.timeIntegration.numberOfSteps = 400      # the disc tips over: its motion needs h = 2.5e-3
    return mbs, simulationSettings


if __name__ == "__main__":
    mbs, simulationSettings = Build()
    exl.SolveDynamic(mbs, simulationSettings)
    print(mbs.GetNodeOutput(0, exu.OutputVariableType.Position))
