"""Planar four-bar mechanism (paper, section "Planar 4-Bar Mechanism").

Three links between two ground pivots: crank (body 1), coupler (body 2), rocker
(body 3).  Joint 1: revolute ground - crank at A0; joint 2: revolute crank - coupler at
B; joint 3: revolute coupler - rocker at C; joint 4: spherical rocker - ground at D0.
All revolute axes along the world z axis; the mechanism moves in the x-y plane.

The paper's claims: the orientation constraints are satisfied exactly by both
formulations (planar motion: rotations about z stay rotations about z in both
groups); the SE(3) update exactly preserves the lower-pair constraints restricting
bodies 1 and 3 to a subgroup (joints 1 and 4: corollary 1, lemma 1 with G1 = {I});
the coupler joints 2 and 3 connect bodies whose relative motion is no product of
subgroups: same order with both groups (corollary 3).

Gaps filled (the figure with the geometry is missing, and the printed initial
velocities fit no four-bar with identity initial rotations), see ``info.choices``:

* Grashof crank-rocker: ground link L0 = 0.5 m (paper), crank L1 = 0.1 m, coupler
  L2 = 0.45 m, rocker L3 = 0.3 m (s + l = 0.6 <= p + q = 0.75, shortest link = crank,
  adjacent to the ground: a crank-rocker; transmission angle between 61 and 105 deg).
  A0 = (0, 0, 0), D0 = (L0, 0, 0); crank initially vertical, B = (0, L1, 0); C the
  upper intersection (open configuration).  (A first choice, L1 = 0.2, L2 = 0.5,
  L3 = 0.4 m, drifted so far at dt = 1e-2 without stabilisation - 17 cm at joint 2 -
  that the integration blew up after 0.74 s with both groups.)
* Links: aluminium bars L x 0.04 x 0.02 m (length along body x, thickness along z),
  body frames at the COMs (link midpoints), R_i(0) = Rz(link angle).
* Crank speed omega0 = 10 pi rad/s (paper); coupler and rocker angular velocities and
  all COM velocities from the velocity constraints (loop closure at t = 0).
* Joint 4 is spherical (as in the paper).  This removes two of the three redundant
  rows of four parallel revolute joints; one redundant row remains (the out-of-plane
  translation of joint 4 is implied by the planarity enforced by joints 1-3): 18
  rows, rank 17, one degree of freedom.  The kernel detects it and uses its
  rank-revealing solve; Exudyn's implicit solvers need the full-pivoting dense
  solver (``linearSolver.solverType = EigenDense``, ``ignoreSingularJacobian = True``).
* No gravity or applied forces (the paper mentions none); time span 1 s (about five
  crank revolutions; the paper does not give it).  With omega0 = 10 pi rad/s, dt =
  1e-2 s is a coarse step (h omega up to 0.5): the coupler joints drift by centimetres
  there with both groups - which does not affect the paper's claims.
"""
import numpy as np

import exudyn as exu
from exudyn.utilities import InertiaCuboid

from ._common import ALUMINIUM, GROUND, Claim, ModelInfo, add_body, new_system, record_joint, rot_z

NAME = "planar_four_bar"
L0, L1, L2, L3 = 0.5, 0.1, 0.45, 0.3
WIDTH, THICK = 0.04, 0.02
OMEGA0 = 10 * np.pi


def geometry(L0=L0, L1=L1, L2=L2, L3=L3):
    """Pivot and joint points A0, B, C, D0 of the initial configuration."""
    A0 = np.zeros(3)
    D0 = np.array([L0, 0.0, 0.0])
    B = np.array([0.0, L1, 0.0])
    # C: |C - B| = L2, |C - D0| = L3, upper solution
    d = D0 - B
    dist = np.linalg.norm(d)
    a = (L2 ** 2 - L3 ** 2 + dist ** 2) / (2 * dist)
    h = np.sqrt(L2 ** 2 - a ** 2)
    e = d / dist
    n = np.array([-e[1], e[0], 0.0])
    C1, C2 = B + a * e + h * n, B + a * e - h * n
    C = C1 if C1[1] > C2[1] else C2
    return A0, B, C, D0


def build(mbs=None, nodeType=exu.NodeType.RotationRotationVector, endTime=1.0, lengths=None):
    """Create the four-bar in ``mbs`` (a new MainSystem if None); returns (mbs, info).

    ``lengths``: (L0, L1, L2, L3) to override the default crank-rocker."""
    mbs, SC = new_system(mbs)
    lengths = tuple(lengths or (L0, L1, L2, L3))
    A0, B, C, D0 = geometry(*lengths)
    z = np.array([0.0, 0.0, 1.0])
    # loop closure at velocity level: w3 z x (C - D0) = w1 z x (B - A0) + w2 z x (C - B)
    vB = OMEGA0 * np.cross(z, B - A0)
    M = np.column_stack([-np.cross(z, C - B)[:2], np.cross(z, C - D0)[:2]])
    w2, w3 = np.linalg.solve(M, vB[:2])
    oGround = mbs.CreateGround(referencePosition=[0, 0, 0])
    bodies, joints = [], []
    links = [("crank", A0, B, OMEGA0, A0, np.zeros(3)), ("coupler", B, C, w2, B, vB),
             ("rocker", D0, C, w3, D0, np.zeros(3))]
    objs = []
    for name, P, Q, w, Pv, vP in links:
        L = np.linalg.norm(Q - P)
        ang = np.arctan2(Q[1] - P[1], Q[0] - P[0])
        xc = 0.5 * (P + Q)
        vc = vP + np.cross(w * z, xc - Pv)
        inertia = InertiaCuboid(density=ALUMINIUM, sideLengths=[L, WIDTH, THICK])
        objs.append(add_body(mbs, bodies, name, inertia, R0=rot_z(ang), r0=xc, omega0=(0, 0, w), vel0=vc,
                             nodeType=nodeType))
    oCrank, oCoupler, oRocker = objs
    for jname, items, pos, kind, bA, bB, desc in [
            ("joint1", [oGround, oCrank], A0, "revolute", GROUND, 0, "revolute ground - crank (A0)"),
            ("joint2", [oCrank, oCoupler], B, "revolute", 0, 1, "revolute crank - coupler (B)"),
            ("joint3", [oCoupler, oRocker], C, "revolute", 1, 2, "revolute coupler - rocker (C)"),
            ("joint4", [oRocker, oGround], D0, "spherical", 2, GROUND, "spherical rocker - ground (D0)")]:
        if kind == "revolute":
            oJ = mbs.CreateRevoluteJoint(name=jname, itemNumbers=items, position=list(pos), axis=[0, 0, 1])
        else:
            oJ = mbs.CreateSphericalJoint(name=jname, itemNumbers=items, position=list(pos))
        record_joint(mbs, joints, jname, oJ, kind, bA, bB, desc)

    info = ModelInfo(name=NAME, title="Planar four-bar (crank-rocker, joints R-R-R-S)",
                     section="Planar 4-Bar Mechanism", mbs=mbs, SC=SC, bodies=bodies, joints=joints,
                     springs=[], gravity=np.zeros(3), endTime=float(endTime), nodeType=nodeType,
                     ground=int(oGround), builder=build, buildArgs=dict(nodeType=nodeType, endTime=endTime, lengths=lengths),
                     redundantConstraints=True)
    info.computed["E0"] = float(info.initial_energy().sum())
    info.computed["omega2_0"] = float(w2)
    info.computed["omega3_0"] = float(w3)
    info.choices += [
        f"Grashof crank-rocker: L0 = {lengths[0]} (paper), crank L1 = {lengths[1]}, coupler L2 = {lengths[2]}, "
        f"rocker L3 = {lengths[3]} m; A0 = (0,0,0), D0 = ({lengths[0]},0,0), crank vertical, B = (0, {lengths[1]}, 0), "
        f"C = ({C[0]:.5f}, {C[1]:.5f}, 0) (open configuration).",
        f"Links: aluminium bars L x {WIDTH} x {THICK} m, frames at the COMs, R_i(0) = Rz(link angle).",
        f"Crank omega0 = 10 pi rad/s (paper); from the velocity constraints omega2 = {w2:.6g} rad/s, "
        f"omega3 = {w3:.6g} rad/s and the COM velocities (the paper's printed velocities fit no four-bar "
        f"with identity initial rotations).",
        "Joint 4 spherical (paper). One redundant row remains (out-of-plane translation of joint 4, implied "
        "by the planarity from joints 1-3): 18 rows, rank 17. exudyn_lie uses its rank-revealing solve; "
        "Exudyn's implicit solvers run with the full-pivoting EigenDense solver (ignoreSingularJacobian = True).",
        "No gravity (the paper mentions none); time span 1 s, about five crank revolutions (not given in the "
        "paper).",
    ]
    info.claims += [
        Claim("joint1", "position", "exact_SE3", "corollary 1 (joint to the ground: lemma 1 with G1 = {I})",
              "Body 1 rotates about a fixed axis (subgroup): SE(3) keeps joint 1 exactly."),
        Claim("joint4", "position", "exact_SE3", "corollary 1 (joint to the ground: lemma 1 with G1 = {I})",
              "Body 3 rotates about a fixed axis (subgroup): SE(3) keeps joint 4 exactly."),
        Claim("joint2", "position", "same_order", "corollary 3", "Coupler joint: same order for both groups."),
        Claim("joint3", "position", "same_order", "corollary 3", "Coupler joint: same order for both groups."),
    ]
    for j in ("joint1", "joint2", "joint3"):
        info.claims.append(Claim(j, "rotation", "exact_both", "planar 4-bar",
                                 "The orientation constraints are exactly satisfied by both formulations."))
    return mbs, info
