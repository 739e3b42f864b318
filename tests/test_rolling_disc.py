"""Exudyn's ``ObjectJointRollingDisc`` in the compiled kernel (row kind ``ROW_ROLL``,
mbs/rolling_disc_rows.py): velocity-level rows ``J V = 0``, ``J V' = eta = -Jdot V``.

* eta against finite differences of ``J(g) V`` along ``g exp(tau V)`` (both groups, ground or
  body plane, every subset of the three axes, unnormalised plane normal / disc axis);
* Exudyn as the oracle at random states: ``J = C_{q_t} P`` (Exudyn's ``ComputeJacobianAE``
  w.r.t. the velocity coordinates, this joint has no position Jacobian) and ``J V`` = Exudyn's
  algebraic equations; M and f as for every item;
* bad input refused before ``mbs`` is touched, with the item named;
* a rolling coin (Exudyn's TestModels/rollingCoinTest.py) against native generalized-alpha at a
  fine step, and RK4's convergence order on it.
"""
import itertools

import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import (InertiaCuboid, MarkerBodyPosition, MarkerBodyRigid, NodeRigidBody2D, ObjectGround,
                              ObjectJointRollingDisc, ObjectRigidBody2D, RigidBodyInertia, RotationMatrixX,
                              RotationMatrixY, RotationMatrixZ)

import exudyn_lie as exl
from exudyn_lie.mbs import GROUND, Scene
from test_bridge_common import (CUR, NODE_TYPES, compare, new_mbs, package, quiet_settings, random_state)
from test_kernel_joints import finite_differences, random_rotation

AXIS_SUBSETS = [ax for ax in itertools.product((0, 1), repeat=3) if any(ax)]


# ---------------------------------------------------------------------------- kernel row
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("ground_side", ["none", "A"])
def test_rolling_disc_eta_against_finite_differences(group, ground_side, rng):
    for ax in AXIS_SUBSETS:
        sc = Scene()
        for _ in range(2):
            sc.AddBody(rng.uniform(0.5, 2), np.diag(rng.uniform(0.1, 0.3, 3)), R0=random_rotation(rng),
                       r0=rng.normal(size=3))
        A = GROUND if ground_side == "A" else 0
        sc.AddRollingDisc(A, 1, rng.uniform(0.2, 1.0), posA=rng.normal(size=3), rotA=random_rotation(rng),
                          posB=rng.normal(size=3) * 0.2, rotB=random_rotation(rng),
                          planeNormal=rng.normal(size=3), discAxis=rng.normal(size=3), constrainedAxes=ax)
        J, eta, _, Jdot_V = finite_differences(sc, group, rng)
        assert J.shape == (sum(ax), 12) and np.max(np.abs(Jdot_V)) > 0.05
        np.testing.assert_allclose(-eta, Jdot_V, atol=1e-8 * max(1.0, np.abs(Jdot_V).max()), rtol=0)
        if ground_side == "A":
            assert np.all(J[:, :6] == 0)


# ---------------------------------------------------------------------------- Exudyn as the oracle
def disc_model(nodes=("RotVecLG", "EP"), axes=(1, 1, 1), normal=(0, 0, 1), discAxis=(1, 0, 0)):
    """A disc rolling on the ground and a second disc rolling on a moving 3D body (the plane),
    markers with local rotations and offsets (Exudyn requires a zero offset of marker 0 on a body)."""
    mbs = new_mbs()
    g = mbs.AddObject(ObjectGround(referencePosition=[0, 0, 0.05], referenceRotation=RotationMatrixZ(0.2)))
    plate = mbs.CreateRigidBody(inertia=InertiaCuboid(500, [1, 1, 0.1]), referencePosition=[2, 0, 0],
                                referenceRotationMatrix=RotationMatrixX(0.1), nodeType=NODE_TYPES[nodes[0]],
                                initialAngularVelocity=[0.2, -0.1, 0.4], initialVelocity=[0.1, 0.2, -0.1],
                                gravity=[0, 0, -9.81])
    discs = [mbs.CreateRigidBody(inertia=InertiaCuboid(800, [0.05, 0.5, 0.5]), referencePosition=[x, 0.1, 0.3],
                                 referenceRotationMatrix=RotationMatrixY(0.3) @ RotationMatrixZ(0.5),
                                 nodeType=NODE_TYPES[nodes[k % 2]], initialAngularVelocity=[3, 1, 2],
                                 initialVelocity=[0.2, -0.3, 0.1], gravity=[0, 0, -9.81])
             for k, x in enumerate((0.0, 2.0))]
    for k, (plane, disc) in enumerate(zip((g, plate), discs)):
        m0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=plane, localHT=exu.HT(rotation=RotationMatrixY(0.1 * k),
                                                                            translation=[0.1, -0.2, 0.05][:3 - 3 * k]
                                                                            or [0, 0, 0])))
        m1 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=disc, localHT=exu.HT(rotation=RotationMatrixX(0.4),
                                                                           translation=[0.02, 0.01, -0.03])))
        mbs.AddObject(ObjectJointRollingDisc(markerNumbers=[m0, m1], constrainedAxes=list(axes), discRadius=0.25,
                                             planeNormal=list(normal), discAxis=list(discAxis)))
    mbs.Assemble()
    return mbs


def velocity_oracle(mbs, q, qt, t=0.0):
    """Exudyn's velocity Jacobian C_{q_t} and algebraic equations g (= C_{q_t} q_t) at (q, qt)."""
    sd = mbs.systemData
    ss = quiet_settings()
    solver = exu.MainSolverImplicitSecondOrder()
    solver.InitializeSolver(mbs, ss)
    n2, nae = solver.GetODE2size(), solver.GetAEsize()
    sd.SetODE2Coordinates(q, configuration=CUR)
    sd.SetODE2Coordinates_t(qt, configuration=CUR)
    sd.SetAECoordinates(np.zeros(nae), configuration=CUR)
    sd.SetTime(t)
    solver.ComputeAlgebraicEquations(mbs)
    g = np.array(solver.GetSystemResidual())[n2:n2 + nae].copy()
    solver.ComputeJacobianODE2RHS(mbs, scalarFactor_ODE2=0., scalarFactor_ODE2_t=0., scalarFactor_ODE1=0.)
    solver.ComputeJacobianAE(mbs, scalarFactor_ODE2=0., scalarFactor_ODE2_t=1., scalarFactor_ODE1=0.,
                             velocityLevel=False)
    C = np.array(solver.GetSystemJacobian())[n2:n2 + nae, :n2].copy()
    solver.FinalizeSolver(mbs, ss)
    return C, g


def rolling_rows(mbs, group, q, qt):
    """(package J, package J V, Exudyn C_t P, Exudyn g) on the rolling-disc rows."""
    C, g = velocity_oracle(mbs, q, qt)
    pk = package(mbs, group, q, qt)
    sim, sc, P = pk["sim"], pk["scene"], pk["P"]
    V = sim.V.reshape(-1)
    out = []
    for ji in sc.joints_info:
        if ji.objectType != "JointRollingDisc":
            continue
        r0, n = (int(x) for x in sim.sd.jint[ji.sceneJoint, 2:4])
        rows = np.arange(r0, r0 + n)
        out.append((pk["J"][rows], pk["J"][rows] @ V, C[ji.aeRows] @ P, g[ji.aeRows]))
        assert np.all(pk["h"][rows] == 0)                    # velocity-level rows: no position residual
    return out


@pytest.mark.parametrize("nodes", [("RotVecLG", "EP"), ("EP", "Rxyz"), ("Rxyz", "RotVecLG")],
                         ids=lambda p: "-".join(p))
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_rolling_disc_same_as_exudyn(nodes, group, rng):
    for axes, normal, dax in [((1, 1, 1), (0, 0, 1), (1, 0, 0)), ((1, 0, 1), (0.1, 0.2, 0.9), (0.9, 0.1, 0.2)),
                              ((0, 1, 0), (0, 0, 1), (0, 1, 0))]:
        mbs = disc_model(nodes, axes, normal, dax)
        for trial in range(2):
            q, qt = random_state(mbs, rng, scale=0.2)
            rows = rolling_rows(mbs, group, q, qt)
            assert len(rows) == 2
            for J, JV, Cx, gx in rows:
                assert J.shape[0] == sum(axes)
                scale = max(1.0, np.abs(Cx).max())
                assert np.max(np.abs(J - Cx)) < 1e-12 * scale
                assert np.max(np.abs(JV - gx)) < 1e-12 * max(1.0, np.abs(gx).max())
            c = compare(mbs, group, q, qt, 0.3)
            assert c["M"] < 1e-11 and c["f"] < 1e-11
