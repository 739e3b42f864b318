"""ObjectConnectorCoordinate with an offsetUserFunction (prescribed motion): a planar crank
(NodeRigidBody2D) whose angle follows phi(t) = 2 t + 0.3 sin(2 pi t) drives a coupler bar on an
ObjectJointRevolute2D under gravity; and a slider (a NodePoint mass point) driven sinusoidally along
x, its y held, with a second mass point hanging on a spring from it."""
import numpy as np
import exudyn as exu
from exudyn.utilities import *  # noqa: F401,F403

import exudyn_lie as exl

_KEEP = []


def UFcrankAngle(mbs, t, itemNumber, lOffset):
    return lOffset + 2 * t + 0.3 * np.sin(2 * np.pi * t)


def UFsliderPosition(mbs, t, itemNumber, lOffset):
    return 0.1 * np.sin(2 * np.pi * t)


def Build():
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    _KEEP.append(SC)       # the container must outlive mbs
    nGround = mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0]))
    mCground = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nGround, coordinate=0))
    oGround = mbs.AddObject(ObjectGround())
    L = 0.4
    # the crank: phi(0) = 0, phidot(0) = 2 + 0.6 pi
    w0 = 2 + 0.6 * np.pi
    nC = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[0, 0, 0], initialVelocities=[0, 0, w0]))
    oC = mbs.AddObject(ObjectRigidBody2D(nodeNumber=nC, mass=1, inertia=0.02))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[mbs.AddMarker(MarkerBodyRigid(bodyNumber=oGround)),
                                                       mbs.AddMarker(MarkerBodyRigid(bodyNumber=oC))]))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mCground, mbs.AddMarker(
        MarkerNodeCoordinate(nodeNumber=nC, coordinate=2))], offsetUserFunction=UFcrankAngle))
    # the coupler hangs from the crank tip (L, 0), its centre L/2 further along x, at rest relative to it
    nB = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[1.5 * L, 0, 0],
                                     initialVelocities=[0, 1.5 * L * w0, w0]))
    oB = mbs.AddObject(ObjectRigidBody2D(nodeNumber=nB, mass=0.5, inertia=0.01))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[
        mbs.AddMarker(MarkerBodyRigid(bodyNumber=oC, localPosition=[L, 0, 0])),
        mbs.AddMarker(MarkerBodyRigid(bodyNumber=oB, localPosition=[-0.5 * L, 0, 0]))]))
    mbs.AddLoad(Force(markerNumber=mbs.AddMarker(MarkerBodyPosition(bodyNumber=oB)), loadVector=[0, -0.5 * 9.81, 0]))

    # the slider: x(t) = 0.1 sin(2 pi t) (x(0) = 0, xdot(0) = 0.2 pi), y = 0
    nS = mbs.AddNode(NodePoint(referenceCoordinates=[0, 1, 0], initialVelocities=[0.2 * np.pi, 0, 0]))
    mbs.AddObject(ObjectMassPoint(nodeNumber=nS, mass=2))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mCground, mbs.AddMarker(
        MarkerNodeCoordinate(nodeNumber=nS, coordinate=0))], offsetUserFunction=UFsliderPosition))
    for k in (1, 2):
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mCground, mbs.AddMarker(
            MarkerNodeCoordinate(nodeNumber=nS, coordinate=k))]))
    nH = mbs.AddNode(NodePoint(referenceCoordinates=[0, 0.7, 0], initialVelocities=[0.1, 0, 0.05]))
    mH = mbs.AddObject(ObjectMassPoint(nodeNumber=nH, mass=0.3))
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[
        mbs.AddMarker(MarkerNodePosition(nodeNumber=nS)), mbs.AddMarker(MarkerNodePosition(nodeNumber=nH))],
        stiffness=80, damping=0.3, referenceLength=0.25))
    mbs.AddLoad(Force(markerNumber=mbs.AddMarker(MarkerNodePosition(nodeNumber=nH)), loadVector=[0, -0.3 * 9.81, 0]))
    mbs.Assemble()
    simulationSettings = exu.SimulationSettings()
    simulationSettings.timeIntegration.endTime = 1
    simulationSettings.timeIntegration.numberOfSteps = 100
    return mbs, simulationSettings


if __name__ == "__main__":
    mbs, simulationSettings = Build()
    exl.SolveDynamic(mbs, simulationSettings)
    print(mbs.systemData.GetODE2Coordinates())
