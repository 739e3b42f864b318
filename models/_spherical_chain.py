"""Spherical n-bar pendulum: n equal boxes in a chain of spherical joints, in gravity.

The paper's double pendulum (section "Spherical Double Pendulum in the Gravity Field")
and the spherical three-bar and four-bar pendulums it mentions ("similar results were
obtained") share this builder.

* Links: flat boxes a x b x c = 0.2 x 0.1 x 0.05 m along the axes of their COM frames,
  aluminium (rho = 2700 kg/m^3): m = 2.7 kg, Theta = diag(0.0028125, 0.0095625, 0.01125).
* Initial configuration: all R_i = I, the chain along the world x axis,
  C_i(0) = (I, ((i - 1/2) a, 0, 0)); joint 1 (ground - body 1) at the origin, joint k
  (body k-1 - body k) at ((k - 1) a, 0, 0).
* Gravity (0, 0, -9.81).
* Initial angular velocities (body-fixed): omega_1 = (10, 0, 0), omega_2 = (10 pi, 10 pi,
  20 pi) rad/s (paper); the three-bar adds omega_3 = (-10 pi, 0, 10 pi), the four-bar also
  omega_4 = (0, 10 pi, -10 pi) rad/s (chosen: same magnitude class, not in the paper).
* Initial COM velocities from the joint velocity constraints, outward along the chain:
  v_i = v(joint i) + omega_i x (x_i - p_i).

Claims: joint 1 restricts body 1 to rotations about a fixed point (an SO(3) subgroup of
SE(3)): SE(3) satisfies it exactly (corollary 1), SO(3)xR3 does not.  The inner joints
connect bodies whose motions form no subgroup: both groups satisfy them with the same
order (corollary 3).  The total energy drift is larger for SO(3)xR3 at large steps.
"""
import numpy as np

import exudyn as exu
from exudyn.utilities import InertiaCuboid

from ._common import (ALUMINIUM, G, GROUND, Claim, ModelInfo, add_body, new_system, point_velocity,
                      record_joint)

SIDES = (0.2, 0.1, 0.05)
OMEGAS = [np.array([10.0, 0.0, 0.0]), np.array([10 * np.pi, 10 * np.pi, 20 * np.pi]),
          np.array([-10 * np.pi, 0.0, 10 * np.pi]), np.array([0.0, 10 * np.pi, -10 * np.pi])]


def _pi_text(w):
    """(-10 pi, 0, 10 pi) for a vector of multiples of pi."""
    return ", ".join("0" if x == 0 else f"{x / np.pi:g} pi" for x in w)


def build_chain(n, name, title, mbs=None, nodeType=exu.NodeType.RotationRotationVector, endTime=5.0):
    if not 1 <= n <= len(OMEGAS):
        raise ValueError(f"spherical chain: n must be 1..{len(OMEGAS)}")
    mbs, SC = new_system(mbs)
    a = SIDES[0]
    gravity = np.array([0.0, 0.0, -G])
    oGround = mbs.CreateGround(referencePosition=[0, 0, 0])
    bodies, joints = [], []
    objs = []
    vjoint = np.zeros(3)                  # velocity of the current joint point
    for i in range(n):
        pj = np.array([i * a, 0.0, 0.0])
        xc = np.array([(i + 0.5) * a, 0.0, 0.0])
        w = OMEGAS[i]
        v = vjoint + np.cross(w, xc - pj)
        o = add_body(mbs, bodies, f"link{i + 1}", InertiaCuboid(density=ALUMINIUM, sideLengths=list(SIDES)),
                     r0=xc, omega0=w, vel0=v, gravity=gravity, nodeType=nodeType)
        objs.append(o)
        prev = oGround if i == 0 else objs[i - 1]
        oJ = mbs.CreateSphericalJoint(name=f"joint{i + 1}", itemNumbers=[prev, o], position=list(pj))
        record_joint(mbs, joints, f"joint{i + 1}", oJ, "spherical", GROUND if i == 0 else i - 1, i,
                     "ground - link1" if i == 0 else f"link{i} - link{i + 1}")
        vjoint = point_velocity(bodies, i, np.array([a / 2, 0.0, 0.0]))
    section = ("Spherical Double Pendulum in the Gravity Field" if n <= 2 else
               "named at the end of 'Spherical Double Pendulum in the Gravity Field' ('similar results were "
               "obtained'), no section or data of its own")
    info = ModelInfo(name=name, title=title, section=section,
                     mbs=mbs, SC=SC, bodies=bodies, joints=joints, springs=[], gravity=gravity,
                     endTime=float(endTime), nodeType=nodeType, ground=int(oGround))
    info.computed["E0"] = float(info.initial_energy().sum())
    info.choices += [
        "Links: boxes 0.2 x 0.1 x 0.05 m aluminium (rho = 2700): m = 2.7 kg, "
        "Theta = diag(0.0028125, 0.0095625, 0.01125) kg m^2.",
        "Initial configuration along the world x axis, R_i = I; gravity (0, 0, -9.81).",
        "COM velocities from the velocity constraints: v_1 = omega_1 x (a/2, 0, 0) = 0, "
        "v_2 = v(joint 2) + omega_2 x (a/2, 0, 0) = (0, 2 pi, -pi) m/s, and so on outward.",
        f"Time span {endTime:g} s (the paper does not give it).",
    ]
    if n > 2:
        chosen = ", ".join(f"omega_{i + 1} = ({_pi_text(OMEGAS[i])}) rad/s" for i in range(2, n))
        info.choices.append(f"{chosen} (the paper only says 'similar results were obtained' for a three-bar and "
                            f"a four-bar pendulum; values chosen, same magnitude class as omega_2).")
    info.claims.append(Claim("joint1", "position", "exact_SE3", "corollary 1",
                             "Joint 1 restricts body 1 to a subgroup (rotations about a fixed point): SE(3) "
                             "satisfies it to computation precision, SO(3)xR3 does not."))
    for j in joints[1:]:
        info.claims.append(Claim(j.name, "position", "same_order", "corollary 3",
                                 f"{j.name}: no subgroup; both formulations achieve a similar constraint "
                                 f"satisfaction (same order)."))
    if n == 2:
        info.claims.append(Claim("energy", "energy", "SE3_better_large_step", "double pendulum",
                                 "The total-energy drift becomes significant for SO(3)xR3 with the large step."))
    return mbs, info
