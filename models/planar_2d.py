"""Planar mechanisms of Exudyn 2D rigid bodies (issue 16, extension beside the paper's 3D
cases): ``NodeRigidBody2D`` + ``ObjectRigidBody2D`` links, ``ObjectJointRevolute2D`` and
``ObjectJointPrismatic2D``, gravity as ``LoadMassProportional``.

* ``pendulum``: one bar on a revolute joint to ground (corollary 1 in the plane: its motion
  is the subgroup of rotations about the pivot, a subgroup of SE(2) but not of SO(2) x R^2);
* ``slider_crank``: crank, connecting rod and slider (prismatic joint to ground along x);
* ``four_bar``: the paper's planar four-bar geometry (``planar_four_bar``: crank-rocker,
  L = 0.5, 0.1, 0.45, 0.3 m, crank speed 10 pi rad/s) made of 2D bodies with four
  revolute 2D joints: 8 independent rows, 1 DOF (the 3D version has 18 rows, rank 17).

Every builder returns ``(mbs, info)`` with ``info`` a dict: ``bodies`` (object indices),
``nodes``, ``joints`` (object indices), ``endTime`` and the scalars used.  The links are
uniform aluminium bars (``planar_four_bar.WIDTH`` x ``THICK`` cross-section), their frames at
the COMs; initial velocities satisfy the velocity constraints.
"""
import numpy as np

import exudyn as exu
from exudyn.utilities import (LoadMassProportional, MarkerBodyMass, MarkerBodyRigid, NodeRigidBody2D,
                              ObjectGround, ObjectJointPrismatic2D, ObjectJointRevolute2D, ObjectRigidBody2D)

from . import planar_four_bar as fb
from ._common import ALUMINIUM, new_system

G = 9.81
Z = np.array([0.0, 0.0, 1.0])
BUILDERS = ("pendulum", "slider_crank", "four_bar")


def _new(mbs, info):
    mbs, SC = new_system(mbs)
    info["SC"] = SC                         # the container must stay alive with mbs
    return mbs


def _bar(mbs, info, P, Q, w, Pv, vP, gravity):
    """A uniform bar from P to Q (frame at its midpoint, x along the bar), angular velocity
    w, moving so that the point Pv has velocity vP; gravity -y if ``gravity``."""
    L = float(np.linalg.norm(Q - P))
    m = ALUMINIUM * L * fb.WIDTH * fb.THICK
    J = m * (L ** 2 + fb.WIDTH ** 2) / 12.0
    ang = float(np.arctan2(Q[1] - P[1], Q[0] - P[0]))
    xc = 0.5 * (P + Q)
    vc = vP + np.cross(w * Z, xc - Pv)
    n = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[xc[0], xc[1], ang],
                                    initialVelocities=[vc[0], vc[1], w]))
    o = mbs.AddObject(ObjectRigidBody2D(nodeNumber=n, mass=m, inertia=J))
    if gravity:
        mm = mbs.AddMarker(MarkerBodyMass(bodyNumber=o))
        mbs.AddLoad(LoadMassProportional(markerNumber=mm, loadVector=[0.0, -G, 0.0]))
    info["nodes"].append(n)
    info["bodies"].append(o)
    info["length"].append(L)
    return o, ang, xc


def _revolute(mbs, info, oA, pA_world, oB, ground):
    """Revolute 2D joint at the world point p between bodies/ground (markers at p)."""
    markers = []
    for o in (oA, oB):
        if o == ground:
            loc = pA_world
        else:
            d = mbs.GetNode(mbs.GetObject(o)["nodeNumber"])["referenceCoordinates"]
            c, s = np.cos(d[2]), np.sin(d[2])
            rel = pA_world[:2] - np.asarray(d[:2])
            loc = np.array([c * rel[0] + s * rel[1], -s * rel[0] + c * rel[1], 0.0])
        markers.append(mbs.AddMarker(MarkerBodyRigid(bodyNumber=o, localPosition=list(loc))))
    info["joints"].append(mbs.AddObject(ObjectJointRevolute2D(markerNumbers=markers)))


def _info(**kw):
    d = dict(nodes=[], bodies=[], joints=[], length=[])
    d.update(kw)
    return d


def pendulum(mbs=None, L=0.5, angle=0.0, omega=0.0, endTime=2.0, gravity=True):
    """One bar, pivot at the origin, initially at ``angle`` from the x axis."""
    info = _info(name="pendulum_2d", endTime=endTime)
    mbs = _new(mbs, info)
    g = mbs.AddObject(ObjectGround())
    P = np.zeros(3)
    Q = L * np.array([np.cos(angle), np.sin(angle), 0.0])
    o, _, _ = _bar(mbs, info, P, Q, omega, P, np.zeros(3), gravity)
    _revolute(mbs, info, g, P, o, g)
    return mbs, info


def slider_crank(mbs=None, r=0.1, l=0.3, phi=np.pi / 3, omega=10.0, endTime=1.0, gravity=True):
    """Crank (ground pivot at the origin, length r, angle phi, angular velocity omega),
    connecting rod (length l), slider on the x axis (ObjectJointPrismatic2D to ground)."""
    info = _info(name="slider_crank_2d", endTime=endTime)
    mbs = _new(mbs, info)
    g = mbs.AddObject(ObjectGround())
    A = np.zeros(3)
    B = r * np.array([np.cos(phi), np.sin(phi), 0.0])
    C = np.array([B[0] + np.sqrt(l ** 2 - B[1] ** 2), 0.0, 0.0])
    vB = np.cross(omega * Z, B - A)
    # slider velocity along x: vC = vB + w2 z x (C - B), vC_y = 0
    w2 = -vB[1] / (C[0] - B[0])
    vC = vB + np.cross(w2 * Z, C - B)
    oc, _, _ = _bar(mbs, info, A, B, omega, A, np.zeros(3), gravity)
    orod, _, _ = _bar(mbs, info, B, C, w2, B, vB, gravity)
    # slider: a short block centred at C
    ms = 0.5
    ns = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[C[0], 0.0, 0.0], initialVelocities=[vC[0], 0.0, 0.0]))
    os_ = mbs.AddObject(ObjectRigidBody2D(nodeNumber=ns, mass=ms, inertia=ms * (0.05 ** 2 + 0.03 ** 2) / 12))
    if gravity:
        mm = mbs.AddMarker(MarkerBodyMass(bodyNumber=os_))
        mbs.AddLoad(LoadMassProportional(markerNumber=mm, loadVector=[0.0, -G, 0.0]))
    info["nodes"].append(ns)
    info["bodies"].append(os_)
    _revolute(mbs, info, g, A, oc, g)
    _revolute(mbs, info, oc, B, orod, g)
    _revolute(mbs, info, orod, C, os_, g)
    mg = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g, localPosition=[0.0, 0.0, 0.0]))
    msl = mbs.AddMarker(MarkerBodyRigid(bodyNumber=os_, localPosition=[0.0, 0.0, 0.0]))
    info["joints"].append(mbs.AddObject(ObjectJointPrismatic2D(markerNumbers=[mg, msl], axisMarker0=[1.0, 0.0, 0.0],
                                                               normalMarker1=[0.0, 1.0, 0.0])))
    info.update(r=r, l=l, phi=phi, omega=omega)
    return mbs, info


def four_bar(mbs=None, endTime=1.0, lengths=None, gravity=False):
    """The paper's planar four-bar (``planar_four_bar.geometry``) of 2D bodies: crank A0-B,
    coupler B-C, rocker D0-C, revolute 2D joints at A0, B, C, D0; no gravity (as the paper)."""
    lengths = tuple(lengths or (fb.L0, fb.L1, fb.L2, fb.L3))
    A0, B, C, D0 = fb.geometry(*lengths)
    vB = fb.OMEGA0 * np.cross(Z, B - A0)
    M = np.column_stack([-np.cross(Z, C - B)[:2], np.cross(Z, C - D0)[:2]])
    w2, w3 = np.linalg.solve(M, vB[:2])
    info = _info(name="four_bar_2d", endTime=endTime, omega=(fb.OMEGA0, w2, w3))
    mbs = _new(mbs, info)
    g = mbs.AddObject(ObjectGround())
    oc, _, _ = _bar(mbs, info, A0, B, fb.OMEGA0, A0, np.zeros(3), gravity)
    ok, _, _ = _bar(mbs, info, B, C, w2, B, vB, gravity)
    orr, _, _ = _bar(mbs, info, D0, C, w3, D0, np.zeros(3), gravity)
    _revolute(mbs, info, g, A0, oc, g)
    _revolute(mbs, info, oc, B, ok, g)
    _revolute(mbs, info, ok, C, orr, g)
    _revolute(mbs, info, orr, D0, g, g)
    return mbs, info


def build(name, mbs=None, **kw):
    """``(mbs, info)`` of the planar model ``name`` (one of :data:`BUILDERS`), assembled."""
    if name not in BUILDERS:
        raise KeyError(f"unknown planar model {name!r}; available: {', '.join(BUILDERS)}")
    mbs, info = globals()[name](mbs, **kw)
    mbs.Assemble()
    return mbs, info
