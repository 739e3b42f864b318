"""Ordinary Exudyn scripts with one item the compiled kernel does not read (issue 17, Checks).

One builder per foreign item kind, written as Exudyn's TestModels are
(``SC = exu.SystemContainer(); mbs = SC.AddSystem()``, ``exudyn.utilities``, sensors,
``simulationSettings``).  Every model couples the foreign item to a rigid body with
``NodeRigidBodyRotVecLG`` (a joint, a constraint or a contact), so that the Lie group
update of that body matters.  The parameters keep every model smooth over the simulated
interval (contacts stay closed, friction stays in its regularised zone, no pre-step
controller that switches once per step): only then can a run show the method's order.

Each builder returns a :class:`ForeignModel`; ``builder(h=..., T=...)`` sets the step and the
end time of ``simulationSettings``; ``h`` defaults to the script's own step.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

import exudyn as exu
from exudyn.utilities import (InertiaCuboid, InertiaCylinder, InertiaSphere, LoadMassProportional,
                              LoadTorqueVector, MarkerBodyMass, MarkerBodyPosition, MarkerBodyRigid,
                              MarkerNodeCoordinate, MarkerNodePosition, NodeGenericData,
                              NodeGenericODE1, NodeGenericODE2, NodePointGround, ObjectANCFCable, ObjectANCFCable2D,
                              ObjectBeamGeometricallyExact, ObjectConnectorCoordinate,
                              ObjectConnectorHydraulicActuatorSimple, ObjectConnectorRollingDiscPenalty,
                              ObjectContactSphereSphere, ObjectGenericODE1, ObjectGenericODE2, ObjectJointSpherical,
                              ObjectKinematicTree, MarkerKinematicTreeRigid, RotationMatrixX, RotationMatrixZ,
                              SensorBody, SensorNode, SensorObject)
from exudyn.beams import GenerateBeamElementsAlongLine

O = exu.OutputVariableType
ROTVEC = exu.NodeType.RotationRotationVector


@dataclass
class ForeignModel:
    """A built script: ``mbs`` (assembled), ``simulationSettings``, the sensors and the
    foreign item (its Exudyn type name and object index)."""
    name: str
    mbs: object
    simulationSettings: object
    sensors: dict
    foreign: str
    foreignIndex: int
    scriptStep: float
    SC: object = field(repr=False, default=None)


def settings(T, h):
    """simulationSettings of the scripts: end time T, step h, sensors every step, no file."""
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = T
    ss.timeIntegration.numberOfSteps = int(round(T / h))
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = h
    ss.show.statistics = False
    ss.timeIntegration.newton.relativeTolerance = 1e-10
    ss.timeIntegration.newton.absoluteTolerance = 1e-10
    ss.timeIntegration.generalizedAlpha.spectralRadius = 0.9
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    return ss


def _new():
    SC = exu.SystemContainer()
    return SC, SC.AddSystem()


def _body_sensors(mbs, body):
    return dict(position=mbs.AddSensor(SensorBody(bodyNumber=body, storeInternal=True, outputVariableType=O.Position)),
                omega=mbs.AddSensor(SensorBody(bodyNumber=body, storeInternal=True,
                                               outputVariableType=O.AngularVelocityLocal)))


def _finish(name, SC, mbs, T, h, hScript, sensors, foreign):
    mbs.Assemble()
    h = hScript if h is None else h
    return ForeignModel(name, mbs, settings(T, h), sensors, mbs.GetObject(foreign)["objectType"], int(foreign),
                        hScript, SC)


# --------------------------------------------------------------------------- 1. ANCF cable 2D
def cable2d_pendulum(h=None, T=0.3):
    """A box (RotVecLG) hanging by a spherical joint from the lower end of a vertical
    ObjectANCFCable2D (4 elements, 1 m, light axial damping), the cable's upper node pinned; the box
    spins about a tilted axis and swings.  The cable's axial modes (omega ~ 800 rad/s) limit
    the explicit step: the script step 1e-2 s is beyond it."""
    SC, mbs = _new()
    L, ne, g = 1.0, 4, [0, -9.81, 0]
    cable = ObjectANCFCable2D(massPerLength=0.5, bendingStiffness=0.5, axialStiffness=500,
                              bendingDamping=0.0, axialDamping=0.2)
    beam = GenerateBeamElementsAlongLine(mbs, [0, 0, 0], [0, -L, 0], ne, cable, gravity=g,
                                         groundConstraintsStart=[1, 1, 0, 0])
    mTip = mbs.AddMarker(MarkerBodyPosition(bodyNumber=beam["elements"][-1], localPosition=[L / ne, 0, 0]))
    a = 0.1
    body = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.2, a, 0.05]), referencePosition=[0, -L - 0.5 * a, 0],
                               initialVelocity=list(np.cross([0.5, 2.0, 1.0], [0, -0.5 * a, 0])),
                               initialAngularVelocity=[0.5, 2.0, 1.0],
                               gravity=g, nodeType=ROTVEC)
    mB = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[0, 0.5 * a, 0]))
    mbs.AddObject(ObjectJointSpherical(markerNumbers=[mTip, mB]))
    return _finish("cable2d_pendulum", SC, mbs, T, h, 1e-2, _body_sensors(mbs, body), beam["elements"][-1])


# --------------------------------------------------------------------------- 2. ANCF cable 3D
def cable3d_pendulum(h=None, T=0.3, bendingDamping=1e-3):
    """As :func:`cable2d_pendulum` with the 3D ObjectANCFCable (NodePointSlope1) and with
    bending damping: it puts a real eigenvalue of about -1.3e3 1/s
    (Exudyn's ComputeODE2Eigenvalues) into the model, which limits the explicit step far
    below the oscillating modes' limit (``bendingDamping=1e-2``: -1.3e4 1/s)."""
    SC, mbs = _new()
    L, ne, g = 1.0, 4, [0, -9.81, 0]
    cable = ObjectANCFCable(massPerLength=0.5, bendingStiffness=0.5, axialStiffness=500,
                            bendingDamping=bendingDamping, axialDamping=0.2)
    beam = GenerateBeamElementsAlongLine(mbs, [0, 0, 0], [0, -L, 0], ne, cable, gravity=g,
                                         groundConstraintsStart=[1, 1, 1, 0, 0, 0])
    mTip = mbs.AddMarker(MarkerBodyPosition(bodyNumber=beam["elements"][-1], localPosition=[L / ne, 0, 0]))
    a = 0.1
    body = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.2, a, 0.05]), referencePosition=[0, -L - 0.5 * a, 0],
                               initialVelocity=list(np.cross([0.5, 2.0, 1.0], [0, -0.5 * a, 0])),
                               initialAngularVelocity=[0.5, 2.0, 1.0],
                               gravity=g, nodeType=ROTVEC)
    mB = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[0, 0.5 * a, 0]))
    mbs.AddObject(ObjectJointSpherical(markerNumbers=[mTip, mB]))
    return _finish("cable3d_pendulum", SC, mbs, T, h, 1e-2, _body_sensors(mbs, body), beam["elements"][-1])


# --------------------------------------------------------------------------- 3. sphere-sphere contact
SPHERE_GAP_SENSOR = "position"


def sphere_contact(h=None, T=0.5):
    """A spherical pendulum (a sphere of radius 0.1 on a massless arm: the body frame at the
    sphere's centre, the spherical joint 0.5 m above it) leaning on a fixed sphere through
    ObjectContactSphereSphere (penalty 1e4 N/m, frictionless, linear model): gravity presses
    it against the fixed sphere while it swings out of plane and spins about its arm; the
    contact stays closed (smooth force), starting at the static penetration."""
    SC, mbs = _new()
    r, Lp, m, k = 0.1, 0.5, 1.0, 1e4
    g = [0, -9.81, 0]
    phi = 0.06                                            # inclination of the arm, away from the fixed sphere
    p0 = np.array([-Lp * np.sin(phi), -Lp * np.cos(phi), 0])
    delta = m * 9.81 * np.sin(phi) / k                    # static penetration
    xFixed = p0[0] + np.sqrt((2 * r - delta) ** 2 - 0.0)  # the fixed sphere at the height of the bob
    mbs.CreateGround(referencePosition=[0, 0, 0])
    nFixed = mbs.AddNode(NodePointGround(referenceCoordinates=[xFixed, p0[1], 0]))
    omega = np.array([0.2, 0, 0]) + 1.0 * p0 / Lp         # out-of-plane swing + spin about the arm
    R0 = RotationMatrixZ(-phi)
    body = mbs.CreateRigidBody(inertia=InertiaSphere(m, r), referencePosition=list(p0), referenceRotationMatrix=R0,
                               initialVelocity=list(np.cross(omega, p0)),
                               initialAngularVelocity=list(omega), gravity=g, nodeType=ROTVEC)
    mbs.CreateSphericalJoint(itemNumbers=[0, body], position=[0, 0, 0])
    mFixed = mbs.AddMarker(MarkerNodePosition(nodeNumber=nFixed))
    mBall = mbs.AddMarker(MarkerBodyRigid(bodyNumber=body))
    nData = mbs.AddNode(NodeGenericData(initialCoordinates=[-delta, 0, 0, 0], numberOfDataCoordinates=4))
    oC = mbs.AddObject(ObjectContactSphereSphere(markerNumbers=[mFixed, mBall], nodeNumber=nData, spheresRadii=[r, r],
                                                 contactStiffness=k, contactDamping=0.0, impactModel=0))
    sens = _body_sensors(mbs, body)
    return _finish("sphere_contact", SC, mbs, T, h, 1e-3, sens, oC)


# --------------------------------------------------------------------------- 4. GenericODE2 + constraint
def generic_ode2(h=None, T=0.5):
    """A box (RotVecLG) on a spherical joint 0.5 m above its centre, whose x displacement is
    tied by an ObjectCoordinateConstraint to the first coordinate of a two-mass oscillator
    given as ObjectGenericODE2 (mass, stiffness and damping matrices)."""
    SC, mbs = _new()
    g = [0, -9.81, 0]
    p0 = np.array([0, -0.5, 0])
    omega = np.array([0.5, 1.0, 2.0])
    v0 = np.cross(omega, p0)
    body = mbs.CreateRigidBody(inertia=InertiaCuboid(500, [0.2, 0.12, 0.08]), referencePosition=list(p0),
                               initialVelocity=list(v0), initialAngularVelocity=list(omega), gravity=g, nodeType=ROTVEC)
    mbs.CreateSphericalJoint(itemNumbers=[mbs.CreateGround(), body], position=[0, 0, 0])
    nG = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0, 0], initialCoordinates=[0, 0],
                                      initialCoordinates_t=[v0[0], 0], numberOfODE2Coordinates=2))
    M = np.diag([0.5, 0.3])
    K = np.array([[300.0, -100.0], [-100.0, 100.0]])
    D = 0.02 * K
    oG = mbs.AddObject(ObjectGenericODE2(nodeNumbers=[nG], massMatrix=M, stiffnessMatrix=K, dampingMatrix=D))
    nB = mbs.GetObject(body)["nodeNumber"]
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nB, coordinate=0)),
                                                            mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nG, coordinate=0))]))
    sens = _body_sensors(mbs, body)
    sens["generic"] = mbs.AddSensor(SensorNode(nodeNumber=nG, storeInternal=True, outputVariableType=O.Coordinates))
    return _finish("generic_ode2", SC, mbs, T, h, 1e-3, sens, oG)


# --------------------------------------------------------------------------- 5. GenericODE1 actuator
def generic_ode1(h=None, T=0.5):
    """A first-order actuator: an ObjectGenericODE1 state tau (torque) with
    tau' = (-tau + u(theta, omega)) / Ta, u a PD law of the angle of a box (RotVecLG) on a
    stiff spherical pivot (gravity pulls it down); the torque acts through a LoadTorqueVector whose
    user function reads the ODE1 coordinate."""
    SC, mbs = _new()
    g = [0, -9.81, 0]
    Ta, kp, kd = 0.05, 20.0, 2.0
    body = mbs.CreateRigidBody(inertia=InertiaCuboid(500, [0.6, 0.06, 0.06]), referencePosition=[0.3, 0, 0],
                               initialAngularVelocity=[0, 0, 1.0], initialVelocity=[0, 0.3, 0],
                               gravity=g, nodeType=ROTVEC)
    nB = mbs.GetObject(body)["nodeNumber"]
    # a stiff pivot (penalty spring): Exudyn's explicit RK44 then gives the fine reference
    # (its implicit solvers start ODE1 coordinates with a zero rate and do not converge here)
    mbs.CreateCartesianSpringDamper(itemNumbers=[mbs.CreateGround(), body], localPosition0=[0, 0, 0],
                                    localPosition1=[-0.3, 0, 0], stiffness=[1e4] * 3, damping=[5.0] * 3)
    tau0 = -kp * (0 - 0.5) - kd * 1.0                  # the PD law at t = 0: the actuator starts at rest (zero rate)
    nA = mbs.AddNode(NodeGenericODE1(referenceCoordinates=[0], initialCoordinates=[tau0], numberOfODE1Coordinates=1))

    def rhs(mbs, t, itemNumber, q):
        theta = mbs.GetNodeOutput(nB, O.Rotation)[2]
        om = mbs.GetNodeOutput(nB, O.AngularVelocity)[2]
        return [(-kp * (theta - 0.5) - kd * om) / Ta]

    oA = mbs.AddObject(ObjectGenericODE1(nodeNumbers=[nA], systemMatrix=np.array([[-1.0 / Ta]]), rhsVector=[0.0],
                                         rhsUserFunction=rhs))
    mB = mbs.AddMarker(MarkerBodyRigid(bodyNumber=body, localPosition=[0, 0, 0]))

    def torque(mbs, t, load):
        return [0, 0, float(np.atleast_1d(mbs.GetNodeOutput(nA, O.Coordinates))[0])]

    mbs.AddLoad(LoadTorqueVector(markerNumber=mB, loadVector=[0, 0, 0], loadVectorUserFunction=torque))
    sens = _body_sensors(mbs, body)
    sens["torque"] = mbs.AddSensor(SensorNode(nodeNumber=nA, storeInternal=True, outputVariableType=O.Coordinates))
    return _finish("generic_ode1", SC, mbs, T, h, 1e-3, sens, oA)


# --------------------------------------------------------------------------- 6. hydraulic actuator
def hydraulic_arm(h=None, T=0.5):
    """hydraulicActuatorSimpleTest in 3D: an arm (RotVecLG box, 1 m, 20 kg) on a stiff
    spherical pivot, lifted by an ObjectConnectorHydraulicActuatorSimple (two chamber pressures as
    NodeGenericODE1 coordinates) with fixed valve openings; oil bulk modulus 2e8 Pa."""
    SC, mbs = _new()
    L, m, g = 1.0, 20.0, [0, -9.81, 0]
    body = mbs.CreateRigidBody(inertia=InertiaCuboid(m / (L * 0.1 * 0.1), [L, 0.1, 0.1]), referencePosition=[0.5 * L, 0, 0],
                               gravity=g, nodeType=ROTVEC, initialAngularVelocity=[0, 0, 0.0])
    ground = mbs.CreateGround()
    # a stiff spherical pivot (penalty spring): see generic_ode1
    mbs.CreateCartesianSpringDamper(itemNumbers=[ground, body], localPosition0=[0, 0, 0], localPosition1=[-0.5 * L, 0, 0],
                                    stiffness=[1e5] * 3, damping=[20.0] * 3)
    mG = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0, -0.25 * L, 0]))
    mR = mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[-0.25 * L, 0, 0]))
    LH0 = np.sqrt(2) * 0.25 * L
    A = 0.01
    # static pressures: the actuator force (p0 - p1) A balances gravity about the joint
    lever = 0.25 * L * np.sin(np.pi / 4)
    dp = m * 9.81 * 0.5 * L / lever / A
    nP = mbs.AddNode(NodeGenericODE1(referenceCoordinates=[0, 0], initialCoordinates=[2e6 + dp, 2e6],
                                     numberOfODE1Coordinates=2))
    oH = mbs.AddObject(ObjectConnectorHydraulicActuatorSimple(
        markerNumbers=[mG, mR], nodeNumbers=[nP], offsetLength=LH0, strokeLength=0.5 * LH0,
        chamberCrossSection0=A, chamberCrossSection1=A, hoseVolume0=0.5, hoseVolume1=0.5,
        valveOpening0=0.004, valveOpening1=-0.004, oilBulkModulus=2e8, actuatorDamping=1e3,
        nominalFlow=2e-5, systemPressure=2e7, tankPressure=0.0, useChamberVolumeChange=False))
    sens = _body_sensors(mbs, body)
    sens["pressures"] = mbs.AddSensor(SensorNode(nodeNumber=nP, storeInternal=True, outputVariableType=O.Coordinates))
    sens["distance"] = mbs.AddSensor(SensorObject(objectNumber=oH, storeInternal=True, outputVariableType=O.Distance))
    return _finish("hydraulic_arm", SC, mbs, T, h, 1e-3, sens, oH)


# --------------------------------------------------------------------------- 7. rolling disc (penalty)
def rolling_disc(h=None, T=0.5):
    """A coin (RotVecLG cylinder, r = 0.1 m) rolling on the ground through
    ObjectConnectorRollingDiscPenalty (penalty 1e5 N/m, friction 0.5 in its regularised
    zone): leaning 0.2 rad, it rolls on a curve.  Starts at its static penetration with no
    slip.  (The compiled kernel reads this item now: tests/test_rolling_disc_penalty.py uses
    the script; it is no longer a case of tests/test_foreign_items.py.)"""
    SC, mbs = _new()
    r, w, m = 0.1, 0.02, 1.0
    k, d, mu = 1e5, 50.0, 0.5
    tilt, vx = 0.2, 1.0
    R0 = RotationMatrixX(tilt) @ np.array([[0, 0, 1.0], [0, 1, 0], [-1.0, 0, 0]]).T @ np.eye(3)
    # disc axis = local x; R0 maps local x to the world axis [0, cos tilt, sin tilt] (rolling along x)
    ax = np.array([0, np.cos(tilt), np.sin(tilt)])
    R0 = np.column_stack([ax, np.cross([0, 0, 1.0], ax) * 0 + np.array([1.0, 0, 0]), np.cross(ax, [1.0, 0, 0])])
    pen = m * 9.81 / k
    c0 = np.array([0, 0, r * np.cos(tilt) - pen])
    omega = -vx / r * ax                                     # rolling without slip: v = omega x (c - contact)
    contact = c0 + r * np.cross(ax, np.cross(np.array([0, 0, -1.0]), ax)) / np.linalg.norm(np.cross(ax, np.cross([0, 0, -1.0], ax)))
    v0 = np.cross(omega, c0 - contact)
    body = mbs.CreateRigidBody(inertia=InertiaCylinder(m / (np.pi * r * r * w), w, r, axis=0), referencePosition=list(c0),
                               referenceRotationMatrix=R0, initialVelocity=list(v0), initialAngularVelocity=list(omega),
                               gravity=[0, 0, -9.81], nodeType=ROTVEC)
    ground = mbs.CreateGround()
    mG = mbs.AddMarker(MarkerBodyRigid(bodyNumber=ground))
    mD = mbs.AddMarker(MarkerBodyRigid(bodyNumber=body))
    nD = mbs.AddNode(NodeGenericData(initialCoordinates=[1e-6, 0, -1.0], numberOfDataCoordinates=3))
    oR = mbs.AddObject(ObjectConnectorRollingDiscPenalty(markerNumbers=[mG, mD], nodeNumber=nD, discRadius=r,
                                                          discAxis=[1, 0, 0], planeNormal=[0, 0, 1], contactStiffness=k,
                                                          contactDamping=d, dryFriction=[mu, mu],
                                                          dryFrictionProportionalZone=0.05))
    return _finish("rolling_disc", SC, mbs, T, h, 1e-3, _body_sensors(mbs, body), oR)


# --------------------------------------------------------------------------- 8. geometrically exact beam
def beam3d_pendulum(h=None, T=0.3):
    """A flexible pendulum: two ObjectBeamGeometricallyExact elements (NodeRigidBodyRotVecLG
    nodes, a soft section) hanging from a spherical joint, a box (RotVecLG) on a spherical
    joint at the lower end."""
    from exudyn.utilities import ObjectJointSpherical as Sph
    SC, mbs = _new()
    L, ne, g = 1.0, 2, [0, -9.81, 0]
    le = L / ne
    sec = exu.BeamSection()
    sec.stiffnessMatrix = np.diag([2e3, 1e3, 1e3, 1.0, 1.0, 1.0])
    sec.dampingMatrix = 1e-3 * sec.stiffnessMatrix
    sec.massPerLength = 0.5
    sec.inertia = np.diag([2e-3, 1e-3, 1e-3])
    rot = [0, 0, -0.5 * np.pi]                              # beam axis (local x) along -y
    nodes = [mbs.AddNode(exu.itemInterface.NodeRigidBodyRotVecLG(referenceCoordinates=[0, -le * i, 0] + rot))
             for i in range(ne + 1)]
    beams = [mbs.AddObject(ObjectBeamGeometricallyExact(nodeNumbers=[nodes[i], nodes[i + 1]], length=le,
                                                        sectionData=sec)) for i in range(ne)]
    for b in beams:
        mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=b)), loadVector=g))
    ground = mbs.CreateGround()
    mbs.AddObject(Sph(markerNumbers=[mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground)),
                                     mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[0]))]))
    a = 0.1
    body = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.2, a, 0.05]), referencePosition=[0, -L - 0.5 * a, 0],
                               initialAngularVelocity=[0.5, 2.0, 1.0],
                               initialVelocity=list(np.cross([0.5, 2.0, 1.0], [0, -0.5 * a, 0])),
                               gravity=g, nodeType=ROTVEC)
    mbs.AddObject(Sph(markerNumbers=[mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1])),
                                     mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[0, 0.5 * a, 0]))]))
    return _finish("beam3d_pendulum", SC, mbs, T, h, 1e-2, _body_sensors(mbs, body), beams[0])


# --------------------------------------------------------------------------- 9. kinematic tree
def kinematic_tree(h=None, T=0.5):
    """A two-link ObjectKinematicTree (revolute z joints, joint coordinates in a
    NodeGenericODE2) with a box (RotVecLG) hanging by a spherical joint from its last link
    (MarkerKinematicTreeRigid)."""
    SC, mbs = _new()
    g = [0, -9.81, 0]
    nT = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0, 0], initialCoordinates=[0.3, -0.2],
                                      initialCoordinates_t=[0, 0], numberOfODE2Coordinates=2))
    Lk = 0.4
    oT = mbs.AddObject(ObjectKinematicTree(nodeNumber=nT, gravity=g, jointTypes=[exu.JointType.RevoluteZ] * 2,
                                           linkParents=[-1, 0],
                                           jointTransformations=exu.Matrix3DList([np.eye(3), np.eye(3)]),
                                           jointOffsets=exu.Vector3DList([[0, 0, 0], [Lk, 0, 0]]),
                                           linkInertiasCOM=exu.Matrix3DList([np.diag([1e-3, 0.01, 0.01])] * 2),
                                           linkCOMs=exu.Vector3DList([[0.5 * Lk, 0, 0]] * 2),
                                           linkMasses=[1.0, 1.0], baseOffset=[0, 0, 0]))
    mK = mbs.AddMarker(MarkerKinematicTreeRigid(objectNumber=oT, linkNumber=1, localPosition=[Lk, 0, 0]))
    # the tip of link 1 in the initial configuration
    q = [0.3, -0.2]
    tip = Lk * np.array([np.cos(q[0]), np.sin(q[0]), 0]) + Lk * np.array([np.cos(q[0] + q[1]), np.sin(q[0] + q[1]), 0])
    a = 0.1
    body = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.2, a, 0.05]), referencePosition=list(tip - [0, 0.5 * a, 0]),
                               initialAngularVelocity=[0.5, 0.0, 1.0], initialVelocity=list(np.cross([0.5, 0, 1.0], [0, -0.5 * a, 0])),
                               gravity=g, nodeType=ROTVEC)
    mbs.AddObject(ObjectJointSpherical(markerNumbers=[mK, mbs.AddMarker(MarkerBodyPosition(bodyNumber=body,
                                                                                           localPosition=[0, 0.5 * a, 0]))]))
    sens = _body_sensors(mbs, body)
    sens["tree"] = mbs.AddSensor(SensorNode(nodeNumber=nT, storeInternal=True, outputVariableType=O.Coordinates))
    return _finish("kinematic_tree", SC, mbs, T, h, 1e-3, sens, oT)


# --------------------------------------------------------------------------- 10. FFRF reduced order
def truss_fem(length=0.5, width=0.1, bays=4, EA=2e3, nodeMass=0.05):
    """A small finite element model without external files: a box truss of ``bays`` bays
    (nodes on four longitudinal lines, bars along the edges, rungs and diagonals), lumped
    node masses; returned as an exudyn.FEM.FEMinterface (sparse M and K)."""
    import scipy.sparse as sp
    from exudyn.FEM import FEMinterface
    pts = np.array([[length * i / bays, y, z] for i in range(bays + 1)
                    for (y, z) in ((0, 0), (width, 0), (width, width), (0, width))])
    bars = set()
    for i in range(bays + 1):
        bars |= {(4 * i + j, 4 * i + (j + 1) % 4) for j in range(4)} | {(4 * i, 4 * i + 2)}
        if i < bays:
            bars |= {(4 * i + j, 4 * (i + 1) + j) for j in range(4)} | {(4 * i + j, 4 * (i + 1) + (j + 1) % 4)
                                                                        for j in range(4)}
    n = 3 * len(pts)
    K = np.zeros((n, n))
    for p, q in sorted(bars):
        d = pts[q] - pts[p]
        k = EA / np.linalg.norm(d) ** 3 * np.outer(d, d)
        for r, c, sg in ((p, p, 1), (q, q, 1), (p, q, -1), (q, p, -1)):
            K[3 * r:3 * r + 3, 3 * c:3 * c + 3] += sg * k
    fem = FEMinterface()
    fem.nodes = {"Position": pts}
    fem.massMatrix = sp.csr_matrix(np.eye(n) * nodeMass)
    fem.stiffnessMatrix = sp.csr_matrix(K)
    fem.surface = []
    fem.elements = []
    return fem


def ffrf_pendulum(h=None, T=0.3):
    """A flexible pendulum: an ObjectFFRFreducedOrder (a box truss, 6 eigenmodes, rigid body
    node RotVecLG) on a spherical joint at its first mesh node, a box (RotVecLG) on a
    spherical joint at its far end."""
    from exudyn.FEM import ObjectFFRFreducedOrderInterface
    from exudyn.utilities import MarkerSuperElementPosition
    SC, mbs = _new()
    g = [0, -9.81, 0]
    fem = truss_fem()
    fem.ComputeEigenmodes(6, excludeRigidBodyModes=6, useSparseSolver=False)
    cms = ObjectFFRFreducedOrderInterface(fem, rigidBodyNodeType=exu.NodeType.RotationRotationVector)
    w = np.array([0.5, 0, 1.0])
    d = cms.AddObjectFFRFreducedOrder(mbs, positionRef=[0, 0, 0], initialAngularVelocity=list(w), gravity=g)
    oF = d["oFFRFreducedOrder"]
    ground = mbs.CreateGround()
    mbs.AddObject(ObjectJointSpherical(markerNumbers=[
        mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground)),
        mbs.AddMarker(MarkerSuperElementPosition(bodyNumber=oF, meshNodeNumbers=[0], weightingFactors=[1.0]))]))
    tipNode = 4 * 4
    tip = fem.nodes["Position"][tipNode]
    a, wB = 0.1, np.array([0.5, 2.0, 1.0])
    body = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.2, a, 0.05]), referencePosition=list(tip - [0, 0.5 * a, 0]),
                               initialAngularVelocity=list(wB),
                               initialVelocity=list(np.cross(w, tip) + np.cross(wB, [0, -0.5 * a, 0])),
                               gravity=g, nodeType=ROTVEC)
    mbs.AddObject(ObjectJointSpherical(markerNumbers=[
        mbs.AddMarker(MarkerSuperElementPosition(bodyNumber=oF, meshNodeNumbers=[tipNode], weightingFactors=[1.0])),
        mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[0, 0.5 * a, 0]))]))
    return _finish("ffrf_pendulum", SC, mbs, T, h, 1e-2, _body_sensors(mbs, body), oF)


BUILDERS = {f.__name__: f for f in (cable2d_pendulum, cable3d_pendulum, sphere_contact, generic_ode2, generic_ode1,
                                     hydraulic_arm, rolling_disc, beam3d_pendulum, kinematic_tree, ffrf_pendulum)}


# --------------------------------------------------------------------------- comparison
def final_state(mbs):
    """The state at the end of a run, chart-free: per RotVecLG node its position, rotation
    matrix, velocity and local angular velocity (so that rotation vectors that differ by a
    turn compare equal); per other node its coordinates and (ODE2) their rates; ODE1
    coordinates divided by their initial magnitude (pressures of 1e6 Pa).  Returns one
    vector; data coordinates are not states of the integration and are left out."""
    parts = []
    for i in range(mbs.systemData.NumberOfNodes()):
        t = str(mbs.GetNode(i)["nodeType"])
        if t in ("PointGround", "GenericData"):
            continue
        if t == "RigidBodyRotVecLG":
            parts += [mbs.GetNodeOutput(i, O.Position), np.ravel(mbs.GetNodeOutput(i, O.RotationMatrix)),
                      mbs.GetNodeOutput(i, O.Velocity), mbs.GetNodeOutput(i, O.AngularVelocityLocal)]
        elif t == "GenericODE1":
            q = np.atleast_1d(mbs.GetNodeOutput(i, O.Coordinates))
            scale = np.maximum(np.abs(np.atleast_1d(mbs.GetNode(i)["initialCoordinates"])), 1.0)
            parts.append(q / scale)
        else:
            parts += [np.atleast_1d(mbs.GetNodeOutput(i, O.Coordinates)), np.atleast_1d(mbs.GetNodeOutput(i, O.Coordinates_t))]
    return np.concatenate([np.ravel(p) for p in parts])


def solve_native(builder, h, T, solverType=None):
    """Exudyn's own solver (default generalized-alpha, spectral radius 0.9) at step h;
    returns :func:`final_state`."""
    m = builder(h=h, T=T)
    if solverType is not None:
        m.simulationSettings.timeIntegration.solverType = solverType
    m.mbs.SolveDynamic(m.simulationSettings)
    return final_state(m.mbs)


def native_reference_rk(builder, h0, T):
    """A fine native reference with Exudyn's explicit RK44 (models without joints): runs at
    h0, h0/2, h0/4; the reference is the finest, its error estimated by Richardson,
    |y(h0/2) - y(h0/4)| / 15.  Returns ``(y, err, info)`` as :func:`native_reference`."""
    ys = [solve_native(builder, h0 / 2 ** k, T, exu.DynamicSolverType.RK44) for k in range(3)]
    d = [np.abs(ys[k] - ys[k + 1]).max() for k in range(2)]
    info = dict(diffs=d, order=float(np.log2(d[0] / d[1])) if d[1] > 0 else np.inf, h0=h0)
    return ys[2], d[1] / 15.0, info


def native_reference(builder, h0, T, solverType=None):
    """A fine native reference by Richardson extrapolation of four native runs at h0, h0/2,
    h0/4, h0/8 (generalized-alpha is of order 2 on ODE2 coordinates; Exudyn starts ODE1
    coordinates with a zero rate, which adds an O(h) term there): y(h) = y* + a h + b h^2
    eliminated from three runs, y* = (8 y(h/4) - 6 y(h/2) + y(h)) / 3.  Returns
    ``(y*, err, info)`` with err the distance between the extrapolations from
    (h0, h0/2, h0/4) and (h0/2, h0/4, h0/8) (an upper estimate of the reference's own
    error), info the differences of successive runs and the observed order."""
    ys = [solve_native(builder, h0 / 2 ** k, T, solverType) for k in range(4)]
    ex = [(8 * ys[k + 2] - 6 * ys[k + 1] + ys[k]) / 3 for k in (0, 1)]
    d = [np.abs(ys[k] - ys[k + 1]).max() for k in range(3)]
    info = dict(diffs=d, order=float(np.log2(d[1] / d[2])) if d[2] > 0 else np.inf, h0=h0)
    return ex[1], float(np.abs(ex[0] - ex[1]).max()), info


def state_error(y, ref):
    """Largest absolute difference (m, rad/s, relative for ODE1 coordinates)."""
    return float(np.abs(np.asarray(y) - np.asarray(ref)).max())
