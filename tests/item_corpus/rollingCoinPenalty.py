"""A coin (r = 1 cm, 1 kg) dropped from 1 cm onto the ground, spinning about its axis at
40 rad/s, with ObjectConnectorRollingDiscPenalty (penalty contact k = 1e5 N/m, d = 1e4 N s/m,
regularised dry friction 0.8, rolling friction 0.2): Exudyn's TestModels/rollingCoinPenaltyTest.py
without graphics and sensors (its data coordinates start at 0: no contact until the first
step's end state is stored)."""
import exudyn as exu
import numpy as np
from exudyn.utilities import *  # noqa: F401,F403

import exudyn_lie as exl

_KEEP = []


def Build(tEnd=0.5, h=1e-4):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    _KEEP.append(SC)       # the container must outlive mbs
    phi0 = 5. / 180. * np.pi
    g = [0, 0, -9.81]
    m, r = 1, 0.01
    p0 = [r * np.sin(phi0), 0, r * np.cos(phi0) + 0.01]
    initialRotation = RotationMatrixY(phi0)
    omega0 = [40, 0, 0]
    v0 = Skew(omega0) @ initialRotation @ [0, 0, r]
    inertiaRing = RigidBodyInertia(mass=1, inertiaTensor=np.diag([0.5 * m * r ** 2, 0.25 * m * r ** 2,
                                                                   0.25 * m * r ** 2]))
    dict0 = mbs.CreateRigidBody(referencePosition=p0, referenceRotationMatrix=initialRotation, initialVelocity=v0,
                                initialAngularVelocity=omega0, inertia=inertiaRing, gravity=g, returnDict=True)
    b0 = dict0['bodyNumber']
    oGround = mbs.AddObject(ObjectGround())
    markerGround = mbs.AddMarker(MarkerBodyRigid(bodyNumber=oGround, localPosition=[0, 0, 0]))
    markerBody0J0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b0, localPosition=[0, 0, 0]))
    nGeneric = mbs.AddNode(NodeGenericData(initialCoordinates=[0, 0, 0], numberOfDataCoordinates=3))
    mbs.AddObject(ObjectConnectorRollingDiscPenalty(markerNumbers=[markerGround, markerBody0J0], nodeNumber=nGeneric,
                                                    discRadius=r, dryFriction=[0.8, 0.8],
                                                    dryFrictionProportionalZone=1e-2, rollingFrictionViscous=0.2,
                                                    contactStiffness=1e5, contactDamping=1e4))
    mbs.Assemble()
    simulationSettings = exu.SimulationSettings()
    simulationSettings.timeIntegration.numberOfSteps = int(round(tEnd / h))
    simulationSettings.timeIntegration.endTime = tEnd
    simulationSettings.solutionSettings.writeSolutionToFile = False
    simulationSettings.timeIntegration.generalizedAlpha.useIndex2Constraints = True
    simulationSettings.timeIntegration.generalizedAlpha.useNewmark = True
    simulationSettings.timeIntegration.generalizedAlpha.spectralRadius = 0.5
    simulationSettings.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    return mbs, simulationSettings


if __name__ == "__main__":
    mbs, simulationSettings = Build()
    exl.SolveDynamic(mbs, simulationSettings)
    print(mbs.GetObjectOutput(2, exu.OutputVariableType.Position))
