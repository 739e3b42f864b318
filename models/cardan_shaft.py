"""Cardanic transmission (paper, section "Cardanic Transmission").

Input shaft (body 1) on a revolute joint to the ground (joint 1), connected to the
drive shaft (body 2) by a universal (Hooke) joint (joint 2).  omega_1 = (0, pi, 0),
omega_2 = (pi, pi, 0) rad/s (body-fixed); initially both shafts aligned along the
3-axis.

Claims:

* joint 1: body 1's COM frame lies on the revolute axis, so its motion is a pure
  rotation about the frame origin - a subgroup of both SE(3) and SO(3)xR3: both
  updates satisfy joint 1 exactly;
* joint 2, position: body 2 rotates about the fixed cross centre (revolute axis
  through it), an SO(3) subgroup of SE(3) but, with body 2's frame away from that
  point, no subgroup of SO(3)xR3: SE(3) exact, SO(3)xR3 step-size dependent
  (corollary 1);
* joint 2, orientation (one row, the Cardan condition): no subgroup, lemma 1 fails:
  both groups the same order (corollary 3).

Gaps filled (see ``info.choices``):

* Shafts: solid aluminium cylinders, radius 0.02 m, length 0.3 m, axis = body y (so
  that the printed omega_1 = (0, pi, 0) is a spin about the shaft axis); body frames
  at the COMs; R_i(0) = Rx(90 deg) maps body y to world z: "aligned along the 3-axis".
* Joint 1: revolute about world z through body 1's COM at the origin.
* Cross centre X = (0, 0, -0.2) on the revolute axis (so it never moves); body 2's
  COM at (0, 0, -0.4), 0.2 m from X: the drive shaft hangs below the input shaft.
* Universal joint axes: world x fixed in body 1 (= body 1's x axis), world y fixed in
  body 2 (= body 2's -z axis); the locked relative rotation is about the shaft axis.
  The relative angular velocity omega_2 - omega_1 = (pi, 0, 0) is about the body-1
  cross axis, so the initial velocities satisfy the constraints; v_1 = 0 and v_2 =
  omega_2 x (COM_2 - X) = (0, 0.2 pi, 0) m/s.
* Gravity (0, 0, -9.81), no drive torque.  The paper mentions no forces; without a
  restoring force the free drive shaft keeps folding about the cross axis (initial
  rate pi rad/s) through a 90 deg bend, the Hooke joint's singular configuration,
  where the motion becomes so violent that RK4 at dt = 1e-2 blew up (t = 1.58 s) with
  both groups and Exudyn's generalized-alpha failed.  Hanging in gravity, the drive
  shaft swings like a pendulum (bend below about 30 deg) while it spins with the input
  shaft - a regular Cardan transmission.  Gravity does not change the subgroup
  structure the claims rest on.
* Time span 4 s (two input revolutions; not given in the paper).
"""
import numpy as np

import exudyn as exu
from exudyn.utilities import InertiaCylinder

from ._common import ALUMINIUM, G, GROUND, Claim, ModelInfo, add_body, new_system, record_joint, rot_x

NAME = "cardan_shaft"
RADIUS, LENGTH = 0.02, 0.3
CROSS = np.array([0.0, 0.0, -0.2])
COM2 = np.array([0.0, 0.0, -0.4])
OMEGA1 = np.array([0.0, np.pi, 0.0])
OMEGA2 = np.array([np.pi, np.pi, 0.0])


def build(mbs=None, nodeType=exu.NodeType.RotationRotationVector, endTime=4.0):
    """Create the Cardan shaft in ``mbs`` (a new MainSystem if None); returns (mbs, info)."""
    mbs, SC = new_system(mbs)
    gravity = np.array([0.0, 0.0, -G])
    oGround = mbs.CreateGround(referencePosition=[0, 0, 0])
    bodies, joints = [], []
    R0 = rot_x(np.pi / 2)                         # body y -> world z
    shaft = lambda: InertiaCylinder(density=ALUMINIUM, length=LENGTH, outerRadius=RADIUS, axis=1)
    o1 = add_body(mbs, bodies, "input_shaft", shaft(), R0=R0, r0=(0, 0, 0), omega0=OMEGA1, vel0=(0, 0, 0),
                  gravity=gravity, nodeType=nodeType)
    v2 = np.cross(R0 @ OMEGA2, COM2 - CROSS)
    o2 = add_body(mbs, bodies, "drive_shaft", shaft(), R0=R0, r0=COM2, omega0=OMEGA2, vel0=v2,
                  gravity=gravity, nodeType=nodeType)
    oJ1 = mbs.CreateRevoluteJoint(name="joint1", itemNumbers=[oGround, o1], position=[0, 0, 0], axis=[0, 0, 1])
    record_joint(mbs, joints, "joint1", oJ1, "revolute", GROUND, 0, "revolute ground - input shaft")
    oJ2 = mbs.CreateGenericJoint(name="joint2", itemNumbers=[o1, o2], position=list(CROSS),
                                 rotationMatrixAxes=np.eye(3), constrainedAxes=[1, 1, 1, 0, 0, 1])
    record_joint(mbs, joints, "joint2", oJ2, "universal", 0, 1, "universal joint input - drive shaft")

    info = ModelInfo(name=NAME, title="Cardan transmission (revolute + universal joint)",
                     section="Cardanic Transmission", mbs=mbs, SC=SC, bodies=bodies, joints=joints, springs=[],
                     gravity=gravity, endTime=float(endTime), nodeType=nodeType, ground=int(oGround),
                     builder=build, buildArgs=dict(nodeType=nodeType, endTime=endTime))
    info.computed["E0"] = float(info.initial_energy().sum())
    info.choices += [
        f"Shafts: aluminium cylinders r = {RADIUS} m, length {LENGTH} m, axis = body y; frames at the COMs; "
        f"R(0) = Rx(90 deg) (body y -> world z: both shafts along the 3-axis).",
        "Joint 1: revolute about world z through body 1's COM (origin).",
        "Cross centre X = (0, 0, -0.2) on the revolute axis; body 2's COM at (0, 0, -0.4), 0.2 m from X (hanging).",
        "Universal joint (CreateGenericJoint, constrainedAxes [1,1,1,0,0,1]): world x fixed in body 1, world y "
        "fixed in body 2; the spin about the shaft axis is transmitted.",
        "omega_1 = (0, pi, 0), omega_2 = (pi, pi, 0) rad/s body-fixed (paper): relative rotation about the body-1 "
        "cross axis; v_1 = 0, v_2 = omega_2 x (COM_2 - X) = (0, 0.2 pi, 0) m/s.",
        "Gravity (0, 0, -9.81) with the drive shaft hanging below the cross (not in the paper): without a restoring "
        "force the shaft folds through the Hooke joint's singular 90 deg bend, where RK4 at dt = 1e-2 blew up and "
        "Exudyn's generalized-alpha failed; hanging, it swings below ~30 deg. No drive torque.",
        "Time span 4 s, two input revolutions (not given in the paper).",
    ]
    info.claims += [
        Claim("joint1", "position", "exact_both", "Cardan / corollary 1",
              "Body 1's frame is on the revolute axis: pure rotation, both formulations satisfy joint 1."),
        Claim("joint1", "rotation", "exact_both", "Cardan / corollary 1",
              "Joint 1 orientation: both formulations exact."),
        Claim("joint2", "position", "exact_SE3", "corollary 1",
              "Body 2 rotates about the cross centre (SO(3) subgroup of SE(3)): SE(3) keeps the position "
              "constraints of joint 2, SO(3)xR3 does not."),
        Claim("joint2", "rotation", "same_order", "lemma 1 fails / corollary 3",
              "The Hooke joint is no subgroup: the orientation constraint is satisfied with the same accuracy "
              "by both updates."),
    ]
    return mbs, info
