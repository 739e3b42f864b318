"""RP mechanism (paper, section "RP Mechanisms").

A cylindrical aluminium ring (body 1) on a revolute joint to the ground (joint 1) and
a bar (body 2) on a prismatic joint to the ring (joint 2), coupled by a longitudinal
spring along the prismatic joint; gravity (0, 0, -9.81).

Paper data: m1 = 6.82825 kg, Theta_1 = diag(0.0507567, 0.0507567, 0.0986682), m2 = 0.864
kg, Theta_2 = diag(0.0002304, 0.0029952, 0.0029952) (about the COMs), spring 1e4 N/m,
omega_10 = omega_20 = (0, 0, 20 pi) rad/s, v_10 = r_11 x omega_10, v_20 = r_21 x omega_20
+ (0, 0, 1) m/s (prismatic joint speed 1 m/s), r_1i the position of the joint-1 axis
relative to the COM of body i.

Claim (the paper: "an example where lemma 1 applies"): body 1 rotates about a fixed
axis (SO(2)), body 2 rotates about the same axis and slides along it (SO(2) x R, a
cylinder subgroup); the joint actions commute, so the SE(3) update satisfies both joints
exactly for any step size, while SO(3)xR3 (only submanifolds of its subgroups) depends
on the step size.  Joint 1, a lower pair to the ground, is body 1's motion constraint
(corollary 1; lemma 1 with G1 = {I}); joint 2, between the two moving bodies, is
lemma 1 proper.

Gaps filled (see ``info.choices``):

* Ring: outer radius 0.15 m, inner 0.08 m, height 0.05 m, axis = body z; these give the
  paper's m1 and Theta_1 (``InertiaCylinder(2700, 0.05, 0.15, axis=2, innerRadius=0.08)``).
* Bar: 0.2 x 0.04 x 0.04 m along body x (gives m2 and Theta_2).
* Joint 1: revolute about the world z axis through the origin; the ring centre (COM)
  at (0.1, 0, 0), so the axis runs through the ring wall, off the COM.
* Joint 2: prismatic along the world z axis (parallel to the revolute axis), through
  the bar's COM at (0.2, 0, 0.1): a vertical guide on the ring wall (0.1 m from the
  ring centre), 0.2 m off the revolute axis.  Both bodies start with R = I, so the
  paper's body-fixed angular velocities (0, 0, 20 pi) apply literally.  The two COMs
  sit at different distances from the axis on purpose: with the bar COM straight above
  the ring COM (same radius and phase) the SO(3)xR3 position updates of both bodies
  would err identically and the prismatic joint would hold exactly by coincidence,
  hiding the paper's point.
* Spring: from the ring point (0.2, 0, 0) (on the prismatic axis) to the bar's COM, so
  it acts along the slide; stiffness 1e4 N/m, reference length = initial distance
  0.1 m (passed explicitly).
* v_10 = (0, 2 pi, 0), v_20 = (0, 4 pi, 1) m/s; time span 2 s (20 revolutions; the
  paper does not give it).
"""
import numpy as np

import exudyn as exu
from exudyn.utilities import InertiaCuboid, InertiaCylinder

from ._common import (ALUMINIUM, G, GROUND, Claim, ModelInfo, SpringData, add_body, new_system,
                      record_joint, spring_markers)

NAME = "rp_mechanism"
RING = dict(outer=0.15, inner=0.08, height=0.05)
BAR = (0.2, 0.04, 0.04)
RING_COM = np.array([0.1, 0.0, 0.0])
BAR_COM = np.array([0.2, 0.0, 0.1])
SPRING_RING = np.array([0.2, 0.0, 0.0])   # spring anchor on the ring (world, t = 0), on the prismatic axis
OMEGA = np.array([0.0, 0.0, 20 * np.pi])
SLIDE_SPEED = 1.0
STIFFNESS = 1e4


def build(mbs=None, nodeType=exu.NodeType.RotationRotationVector, endTime=2.0, joint1="revolute"):
    """Create the RP mechanism in ``mbs`` (a new MainSystem if None); returns (mbs, info).

    ``joint1='cylindrical'`` replaces the revolute joint by a cylindrical one (the paper
    notes the same accuracy in that case)."""
    mbs, SC = new_system(mbs)
    gravity = np.array([0.0, 0.0, -G])
    oGround = mbs.CreateGround(referencePosition=[0, 0, 0])
    bodies, joints, springs = [], [], []
    axis_point = np.zeros(3)
    ring = InertiaCylinder(density=ALUMINIUM, length=RING["height"], outerRadius=RING["outer"], axis=2,
                           innerRadius=RING["inner"])
    bar = InertiaCuboid(density=ALUMINIUM, sideLengths=list(BAR))
    v1 = np.cross(axis_point - RING_COM, OMEGA)                     # r_11 x omega_10
    v2 = np.cross(axis_point - BAR_COM, OMEGA) + np.array([0, 0, SLIDE_SPEED])
    oRing = add_body(mbs, bodies, "ring", ring, r0=RING_COM, omega0=OMEGA, vel0=v1, gravity=gravity,
                     nodeType=nodeType)
    oBar = add_body(mbs, bodies, "bar", bar, r0=BAR_COM, omega0=OMEGA, vel0=v2, gravity=gravity,
                    nodeType=nodeType)
    if joint1 == "revolute":
        oJ1 = mbs.CreateRevoluteJoint(name="joint1", itemNumbers=[oGround, oRing], position=list(axis_point),
                                      axis=[0, 0, 1])
    elif joint1 == "cylindrical":
        oJ1 = mbs.CreateGenericJoint(name="joint1", itemNumbers=[oGround, oRing], position=list(axis_point),
                                     constrainedAxes=[1, 1, 0, 1, 1, 0])
    else:
        raise ValueError("joint1 must be 'revolute' or 'cylindrical'")
    record_joint(mbs, joints, "joint1", oJ1, joint1, GROUND, 0, f"{joint1} ground - ring (z axis)")
    oJ2 = mbs.CreatePrismaticJoint(name="joint2", itemNumbers=[oRing, oBar], position=list(BAR_COM),
                                   axis=[0, 0, 1])
    record_joint(mbs, joints, "joint2", oJ2, "prismatic", 0, 1, "prismatic ring - bar (along z)")
    L0 = float(np.linalg.norm(BAR_COM - SPRING_RING))
    pRing = SPRING_RING - RING_COM                  # ring body coordinates (R = I)
    oS = mbs.CreateSpringDamper(name="spring", itemNumbers=[oRing, oBar], localPosition0=list(pRing),
                                localPosition1=[0, 0, 0], stiffness=STIFFNESS, referenceLength=L0)
    springs.append(SpringData("spring", int(oS), 0, pRing, 1, np.zeros(3), STIFFNESS, L0,
                              spring_markers(mbs, oS)))

    info = ModelInfo(name=NAME, title="RP mechanism (revolute + prismatic, spring along the slide)",
                     section="RP Mechanisms", mbs=mbs, SC=SC, bodies=bodies, joints=joints, springs=springs,
                     gravity=gravity, endTime=float(endTime), nodeType=nodeType, ground=int(oGround),
                     builder=build, buildArgs=dict(nodeType=nodeType, endTime=endTime, joint1=joint1))
    info.computed["E0"] = float(info.initial_energy().sum())
    info.computed["m1"] = float(ring.mass)
    info.computed["m2"] = float(bar.mass)
    info.paper.update(m1=6.82825, m2=0.864)
    info.choices += [
        f"Ring: outer radius 0.15, inner 0.08, height 0.05 m, aluminium -> m1 = {ring.mass:.6g} kg (paper 6.82825), "
        f"Theta_1 = diag({', '.join(f'{x:.6g}' for x in np.diag(ring.inertiaTensor))}) (paper 0.0507567, "
        f"0.0507567, 0.0986682).",
        f"Bar: 0.2 x 0.04 x 0.04 m aluminium along body x -> m2 = {bar.mass:.6g} kg (paper 0.864), Theta_2 = "
        f"diag({', '.join(f'{x:.6g}' for x in np.diag(bar.inertiaTensor))}) (paper 0.0002304, 0.0029952, 0.0029952).",
        "Joint 1: revolute about the world z axis through the origin; ring COM at (0.1, 0, 0) (off the axis).",
        "Joint 2: prismatic along world z (parallel to the revolute axis) through the bar COM at (0.2, 0, 0.1), a "
        "guide on the ring wall (off the revolute axis): body 2 moves on the cylinder subgroup SO(2) x R. The COMs "
        "are at different radii (0.1, 0.2 m): with equal radius and phase SO(3)xR3 would keep joint 2 by "
        "coincidence.",
        "Both bodies start with R = I, so the paper's body-fixed omega = (0, 0, 20 pi) applies to both.",
        "Spring from the ring point (0.2, 0, 0) on the prismatic axis to the bar COM, k = 1e4 N/m, reference "
        "length = initial distance 0.1 m (given explicitly).",
        "v_10 = r_11 x omega = (0, 2 pi, 0), v_20 = r_21 x omega + (0, 0, 1) = (0, 4 pi, 1) m/s.",
        "Time span 2 s (not given in the paper).",
    ]
    ground = "corollary 1 (joint to the ground: lemma 1 with G1 = {I})"
    info.claims += [
        Claim("joint1", "position", "exact_SE3", ground,
              "joint1: body 1 rotates about the fixed revolute axis (SO(2), a subgroup of SE(3)): SE(3) satisfies "
              "the joint exactly, SO(3)xR3 depends on the step size."),
        Claim("joint1", "rotation", "SE3_exact", ground,
              "joint1 orientation rows: exact with SE(3); nothing claimed for SO(3)xR3."),
        Claim("joint2", "position", "exact_SE3", "lemma 1",
              "joint2: both bodies move in SE(3) subgroups (SO(2), SO(2) x R) whose relative motion is a subgroup "
              "(the prismatic joint commutes with the revolute): SE(3) satisfies the joint exactly, SO(3)xR3 "
              "depends on the step size."),
        Claim("joint2", "rotation", "SE3_exact", "lemma 1",
              "joint2 orientation rows: exact with SE(3) (lemma 1); nothing claimed for SO(3)xR3."),
    ]
    return mbs, info
