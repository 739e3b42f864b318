"""A board on two wheels (revolute joints), each wheel on the ground through
``mbs.CreateRollingDiscPenalty`` (k = 1e5 N/m, d = 1e3 N s/m, dry friction 0.4 with Exudyn's
default proportional zone), rolling at 2.5 m/s: Exudyn's TestModels/createRollingDiscPenaltyTest.py
without graphics (its data coordinates start at 0: no contact and no friction in the first step)."""
import exudyn as exu
import numpy as np
from exudyn.utilities import *  # noqa: F401,F403

import exudyn_lie as exl

_KEEP = []


def Build(tEnd=1.0, h=0.002):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    _KEEP.append(SC)       # the container must outlive mbs
    g = [0, 0, -9.81]
    m, r, L = 0.5, 0.1, 0.8
    omega0 = [0, 4 * 2 * np.pi, 0]
    v0 = Skew(omega0) @ [0, 0, r]
    inertiaRing = RigidBodyInertia(mass=1, inertiaTensor=np.diag([0.25 * m * r ** 2, 0.5 * m * r ** 2,
                                                                   0.25 * m * r ** 2]))
    oWheel0 = mbs.CreateRigidBody(referencePosition=[-0.5 * L, 0, r], initialVelocity=v0,
                                  initialAngularVelocity=omega0, inertia=inertiaRing, gravity=g)
    oWheel1 = mbs.CreateRigidBody(referencePosition=[0.5 * L, 0, r], initialVelocity=v0,
                                  initialAngularVelocity=omega0, inertia=inertiaRing, gravity=g)
    oBody = mbs.CreateRigidBody(referencePosition=[0, 0, r * 1.2], initialVelocity=v0,
                                inertia=InertiaCuboid(2800, sideLengths=[L, 0.5 * r, 0.5 * r]), gravity=g)
    mbs.CreateRevoluteJoint(bodyNumbers=[oWheel0, oBody], position=[0, 0, 0], axis=[0, 1, 0], useGlobalFrame=False)
    mbs.CreateRevoluteJoint(bodyNumbers=[oWheel1, oBody], position=[0, 0, 0], axis=[0, 1, 0], useGlobalFrame=False)
    oGround = mbs.AddObject(ObjectGround())
    discs = [mbs.CreateRollingDiscPenalty(bodyNumbers=[oGround, w], axisPosition=[0, 0, 0], axisVector=[0, 1, 0],
                                          discRadius=r, contactStiffness=1e5, contactDamping=1e3,
                                          dryFriction=[0.4, 0.4]) for w in (oWheel0, oWheel1)]
    mbs.Assemble()
    simulationSettings = exu.SimulationSettings()
    simulationSettings.timeIntegration.numberOfSteps = int(round(tEnd / h))
    simulationSettings.timeIntegration.endTime = tEnd
    simulationSettings.solutionSettings.sensorsWritePeriod = 0.005
    simulationSettings.timeIntegration.newton.useModifiedNewton = True
    mbs.sys["discs"] = discs
    return mbs, simulationSettings


if __name__ == "__main__":
    mbs, simulationSettings = Build()
    exl.SolveDynamic(mbs, simulationSettings)
    print(np.linalg.norm(mbs.GetObjectOutput(mbs.sys["discs"][0], exu.OutputVariableType.Position)))
