"""Coordinate items on the rotation coordinate of 2D rigid bodies (``NodeRigidBody2D``
coordinate 2, the angle ``phi`` of ``R = Rz(phi)``): ``ObjectConnectorCoordinate``,
``ObjectConnectorCoordinateSpringDamper`` (compiled and with a user function) and
``LoadCoordinate``, mixed with position coordinates; the angle is tracked over turns
(mbs/coordinate_angles.py).

* the row's J and eta against finite differences (both planar groups);
* Exudyn's own M, f, g, C_q at random states, with angles of several turns;
* a spinning 2D body on an angle spring: the spring sees the total angle (turns), as Exudyn;
* a planar gear pair against native generalized-alpha at a fine step.
"""
import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import (LoadCoordinate, MarkerBodyRigid, MarkerNodeCoordinate, NodePoint, NodePointGround,
                              NodeRigidBody2D, ObjectConnectorCoordinate, ObjectConnectorCoordinateSpringDamper,
                              ObjectGround, ObjectJointRevolute2D, ObjectMassPoint, ObjectRigidBody2D)

import exudyn_lie as exl
from exudyn_lie.mbs import GROUND, AngleCoordinate, Scene
from exudyn_lie.mbs.compiled import compile_carried, compile_scene, make_work
from exudyn_lie.mbs.diagnostics import constraint_jacobian
from test_bridge_common import compare, new_mbs, quiet_settings, random_state

TOL = 1e-11


# ---------------------------------------------------------------------------- kernel row
def _planar_exp(group, R, r, X):
    from exudyn_lie.groups import se3, so3xr3
    if group == "SE2":
        ER, Er = se3.exp(X)
        return R @ ER, r + R @ Er
    ER, Er = so3xr3.exp(X)
    return R @ ER, r + Er


@pytest.mark.parametrize("group", ["SE2", "SO2xR2"])
def test_rotation_coordinate_row_against_finite_differences(group, rng):
    """h, J and eta of a coordinate constraint between the angle of one 2D body and the angle
    (or the x position) of another: J = finite differences of h along the planar twists,
    eta = -(finite difference of J V along the motion)."""
    for endB in ("angle", "position"):
        sc = Scene()
        for k in range(2):
            sc.AddBody2D(rng.uniform(0.5, 2), rng.uniform(0.1, 0.3), position=rng.normal(size=2),
                         angle=rng.uniform(-3, 3) + 7 * k)
        angles = [np.arctan2(b.R0[1, 0], b.R0[0, 0]) for b in sc.bodies]
        angles[1] += 2 * np.pi                  # one turn on: the tracked angle keeps it
        axB = AngleCoordinate(None, angles[1]) if endB == "angle" else 0
        sc.AddCoordinateConstraint(0, AngleCoordinate(None, angles[0]), 1, axB, factor=-1.7, constant=0.3)
        sd, _ = compile_scene(sc, [group, group])
        wk = make_work(sd, 4, carried=compile_carried(sc))
        R = np.array([b.R0 for b in sc.bodies])
        r = np.array([b.r0 for b in sc.bodies])
        V = np.zeros((2, 6))
        V[:, 2:5] = rng.normal(size=(2, 3))
        h0, J, eta = constraint_jacobian(sd, wk, R, r, V)
        qB = angles[1] if endB == "angle" else r[1, 0]
        assert abs(h0[0] - (-1.7 * qB - angles[0] - 0.3)) < 1e-12
        eps = 1e-6
        for i in range(2):
            for k in (2, 3, 4):
                X = np.zeros(6)
                X[k] = eps
                Rp, rp, Rm, rm = R.copy(), r.copy(), R.copy(), r.copy()
                Rp[i], rp[i] = _planar_exp(group, R[i], r[i], X)
                Rm[i], rm[i] = _planar_exp(group, R[i], r[i], -X)
                fd = (constraint_jacobian(sd, wk, Rp, rp, V)[0] - constraint_jacobian(sd, wk, Rm, rm, V)[0]) / (2 * eps)
                assert abs(fd[0] - J[0, 6 * i + k]) < 1e-8

        def JV(tau):
            Rt, rt = R.copy(), r.copy()
            for i in range(2):
                Rt[i], rt[i] = _planar_exp(group, R[i], r[i], tau * V[i])
            return constraint_jacobian(sd, wk, Rt, rt, V)[1] @ V.reshape(-1)
        assert abs(-eta[0] - (JV(eps) - JV(-eps))[0] / (2 * eps)) < 1e-7


# ---------------------------------------------------------------------------- Exudyn as the oracle
def planar_model(userFunction=False, turns=3):
    """Two 2D bodies (one on a revolute 2D joint, turned by ``turns`` full turns), a point mass, a
    ground node: a coordinate constraint between the two angles (a gear), coordinate springs
    angle-ground, angle-position, coordinate loads on an angle and a position."""
    mbs = new_mbs()
    g = mbs.AddObject(ObjectGround())
    nodes = []
    for k, (p, phi, v) in enumerate((([0.5, 0.2], 0.4, [0, 0, 1.5]), ([1.5, -0.3], -0.7, [0.1, -0.2, -0.75]))):
        n = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[p[0], p[1], phi],
                                        initialCoordinates=[0, 0, 2 * np.pi * turns * (k == 0)],
                                        initialVelocities=v))
        mbs.AddObject(ObjectRigidBody2D(nodeNumber=n, mass=1 + k, inertia=0.2 + 0.1 * k))
        nodes.append(n)
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[mbs.AddMarker(MarkerBodyRigid(bodyNumber=g,
                                                                                     localPosition=[0.5, 0.2, 0])),
                                                       mbs.AddMarker(MarkerBodyRigid(bodyNumber=1))]))
    npt = mbs.AddNode(NodePoint(referenceCoordinates=[0.2, 0.4, -0.3], initialVelocities=[0.1, 0.2, 0.3]))
    mbs.AddObject(ObjectMassPoint(mass=1.3, nodeNumber=npt))
    ng = mbs.AddNode(NodePointGround(referenceCoordinates=[0.3, 0.1, 0.2]))

    def mc(n, k):
        return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=k))

    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mc(nodes[1], 2), mc(nodes[0], 2)], factor1=-0.5,
                                            offset=-0.5 * (2 * np.pi * turns)))
    kw = {}
    if userFunction:
        kw = dict(springForceUserFunction=lambda mbs, t, i, u, v, k, d, off: k * (u - off) + 0.3 * u ** 3 + d * v)
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mc(ng, 0), mc(nodes[0], 2)], stiffness=4,
                                                        damping=0.3, offset=0.2, **kw))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mc(nodes[1], 2), mc(npt, 1)], stiffness=25,
                                                        damping=0.1, offset=0.1, **kw))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mc(nodes[1], 0), mc(nodes[1], 2)],
                                                        stiffness=5, **kw))
    mbs.AddLoad(LoadCoordinate(markerNumber=mc(nodes[1], 2), load=0.7))
    mbs.AddLoad(LoadCoordinate(markerNumber=mc(nodes[0], 2), load=-0.4,
                               **(dict(loadUserFunction=lambda mbs, t, load: load * (1 + t)) if userFunction else {})))
    mbs.Assemble()
    return mbs


@pytest.mark.parametrize("userFunction", [False, True])
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_rotation_coordinates_same_as_exudyn(group, userFunction, rng):
    mbs = planar_model(userFunction)
    for trial in range(3):
        q, qt = random_state(mbs, rng, scale=0.3)
        c = compare(mbs, group, q, qt, 0.2 + trial)
        for key in ("M", "f", "g", "J"):
            assert c[key] < TOL, f"{key}: relative deviation {c[key]:.3g} from Exudyn (trial {trial})"
        assert c["nrows"] == 3


# ---------------------------------------------------------------------------- dynamics
def _final(mbs, h, T, lie):
    ss = quiet_settings(endTime=T, nsteps=int(round(T / h)))
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    ss.timeIntegration.newton.relativeTolerance = 1e-12
    ss.timeIntegration.newton.absoluteTolerance = 1e-14
    (exl.SolveDynamic(mbs, ss, method="RK4") if lie else exu.SolveDynamic(mbs, ss))
    return np.array(mbs.systemData.GetODE2Coordinates()), np.array(mbs.systemData.GetODE2Coordinates_t())


def spinner():
    """A 2D disc on a revolute 2D joint, spinning at 20 rad/s against an angle spring to the
    ground (k (phi - 0) with phi growing past several turns) and a constant coordinate torque."""
    mbs = new_mbs()
    g = mbs.AddObject(ObjectGround())
    n = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[0, 0, 0], initialVelocities=[0, 0, 20.0]))
    mbs.AddObject(ObjectRigidBody2D(nodeNumber=n, mass=1, inertia=0.5))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[mbs.AddMarker(MarkerBodyRigid(bodyNumber=g)),
                                                       mbs.AddMarker(MarkerBodyRigid(bodyNumber=1))]))
    ng = mbs.AddNode(NodePointGround())
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ng, coordinate=0)),
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=2))], stiffness=2.0, damping=0.05))
    mbs.AddLoad(LoadCoordinate(markerNumber=mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=2)),
                               load=3.0))
    mbs.Assemble()
    return mbs


@pytest.mark.slow
def test_spinning_angle_spring_tracks_turns_as_exudyn():
    """phi reaches 10.7 rad (more than 1.5 turns; Exudyn's coordinate is the total angle, and
    only the final state is written back): exl RK4 at h = 1e-3 agrees with native
    generalized-alpha at 1e-5 (difference to 2e-5: 6.7e-10) to 2.2e-10 (measured), turns
    included (the angle spring sees the total angle, and the write-back keeps it: Work.bodyAngles)."""
    T = 1.0
    qa, _ = _final(spinner(), 2e-5, T, False)
    qn, vn = _final(spinner(), 1e-5, T, False)
    assert abs(qn[2]) > 1.5 * 2 * np.pi
    ql, vl = _final(spinner(), 1e-3, T, True)
    assert np.abs(ql - qn).max() < 1e-8, (ql, qn)          # the total angle, turns included
    assert np.abs(qa - qn).max() < 1e-8
    assert np.abs(vl - vn).max() < 1e-8


@pytest.mark.slow
def test_gear_model_agrees_with_fine_generalized_alpha():
    """The oracle's planar model (gear constraint, angle springs, loads; compiled items; a body
    three turns on) over 0.5 s: native generalized-alpha at 4e-5 / 2e-5 / 1e-5 is second order
    (differences 2.9e-8, 7.3e-9, measured), its Richardson extrapolation the reference (checked
    against that of the coarser pair: 2.4e-12); exl RK4 at 4e-3, 2e-3, 1e-3: errors 2.1e-7,
    1.3e-8, 8.2e-10 (measured), order 4."""
    T = 0.5
    nat = {h: _final(planar_model(), h, T, False)[0] for h in (4e-5, 2e-5, 1e-5)}
    d1, d2 = np.abs(nat[4e-5] - nat[2e-5]).max(), np.abs(nat[2e-5] - nat[1e-5]).max()
    assert 3.5 < d1 / d2 < 4.5
    ref = nat[1e-5] + (nat[1e-5] - nat[2e-5]) / 3
    assert np.abs(ref - (nat[2e-5] + (nat[2e-5] - nat[4e-5]) / 3)).max() < 1e-10
    err = {h: np.abs(_final(planar_model(), h, T, True)[0] - ref).max() for h in (4e-3, 2e-3, 1e-3)}
    assert err[1e-3] < 1e-8, err
    assert np.log2(err[4e-3] / err[2e-3]) > 3.6 and np.log2(err[2e-3] / err[1e-3]) > 3.6, err
