"""Coordinate items on the rotation coordinates of 3D rigid nodes (issue 16, item 4):
``ObjectConnectorCoordinate``, ``ObjectConnectorCoordinateSpringDamper`` (compiled and with a
user function) and ``LoadCoordinate`` on coordinates 3.. of NodeRigidBodyRotVecLG, EP and
Rxyz nodes, as Exudyn defines them (mbs/node_coordinates.py, mbs/oblique_solve.py):

* the parameter's value, gradient G and bias Gdot omega against finite differences, both
  sides of the dexpinv switch point;
* the rows (h, J = G, eta) against finite differences on both c-spaces;
* Exudyn's own M, f, g, C_q at random states: f (springs, loads) mapped to the body twist;
  C_q = G for EP / Rxyz; for RotVecLG C_q is the force direction C = e_k (checked against the
  kernel's ObliquePlan rows), while g = h and J = G (the finite differences);
* the non-symmetric solve is compiled only for scenes with such rows (LLVM IR of the stage);
* TestModels-style scripts per node type against native generalized-alpha at a fine step:
  RK4 errors of order 4.
"""
import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import (LoadCoordinate, MarkerNodeCoordinate, NodePointGround, ObjectConnectorCoordinate,
                              ObjectConnectorCoordinateSpringDamper)

import exudyn_lie as exl
from exudyn_lie.groups import se3, so3, so3xr3
from exudyn_lie.mbs import GROUND, RotationParameterCoordinate, Scene, Simulator
from exudyn_lie.mbs.node_coordinates import (PARAM_EULER_PARAMETERS, PARAM_ROTATION_VECTOR, PARAM_TAIT_BRYAN, U_SWITCH, _coef_D_dD,
                                             node_parameter, param_code)
from exudyn_lie.mbs.oblique_solve import force_direction_rows
from exudyn_lie.mbs.rotation_parameters import nearest_tait_bryan, quat_of
from exudyn_lie.mbs.diagnostics import constraint_jacobian
from test_bridge_common import (add_body, box_on_spherical_joint, compare, new_mbs, oracle, package, quiet_settings,
                                random_state)

KINDS = {"RotVecLG": (PARAM_ROTATION_VECTOR, 3), "EP": (PARAM_EULER_PARAMETERS, 4), "Rxyz": (PARAM_TAIT_BRYAN, 3)}
PARAMETRISATIONS = {"RotVecLG": "rotationVector", "EP": "eulerParameters", "Rxyz": "taitBryanXYZ"}   # the kernel's names
TOL = 1e-11


# ---------------------------------------------------------------------------- the parameter
def _value(code, R, prev):
    return node_parameter(code, R, prev, np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3))[0]


@pytest.mark.parametrize("kind", list(KINDS))
def test_parameter_gradient_and_bias_against_finite_differences(kind, rng):
    """qdot_k = G . omega and d/dt (G . omega) at frozen omega = bias, by central differences
    along R exp(s omega), at small, medium and large rotations (RotVecLG: up to 2.5 rad)."""
    pk, n = KINDS[kind]
    for k in range(n):
        code = param_code(pk, k)
        for angle in (1e-3, 0.5, 2.5):
            x = rng.normal(size=3)
            R = so3.exp(x * angle / np.linalg.norm(x))
            w = rng.normal(size=3)
            prev = np.zeros(4)
            (nearest_tait_bryan(R, np.zeros(4), prev) if pk == PARAM_TAIT_BRYAN else quat_of(R, prev))
            G, C, tmp = np.zeros(3), np.zeros(3), np.zeros(3)
            v, bias = node_parameter(code, R, prev, w, G, C, tmp)
            e = 1e-6
            rate = (_value(code, R @ so3.exp(e * w), prev) - _value(code, R @ so3.exp(-e * w), prev)) / (2 * e)
            assert abs(rate - G @ w) < 1e-8 * max(1.0, abs(rate)), (k, angle)

            def Gw(s):
                G2 = np.zeros(3)
                node_parameter(code, R @ so3.exp(s * w), prev, w, G2, np.zeros(3), tmp)
                return G2 @ w
            bfd = (Gw(e) - Gw(-e)) / (2 * e)
            assert abs(bias - bfd) < 1e-7 * max(1.0, abs(bfd)), (k, angle, bias, bfd)
            if pk == PARAM_ROTATION_VECTOR:
                assert np.array_equal(C, np.eye(3)[k])        # Exudyn's e_k on the local omega
            else:
                assert np.array_equal(C, G)


def test_dexpinv_coefficient_derivative_is_continuous_at_its_switch():
    """D and dD/du of dexpinv (RotVecLG's gradient) agree on both sides of the series/closed
    switch, and dD/du matches a difference quotient of D."""
    u0 = U_SWITCH
    lo, hi = _coef_D_dD(u0 * (1 - 1e-12)), _coef_D_dD(u0 * (1 + 1e-12))
    # the closed forms' cancellation there: D ~ 1e-14 relative (as so3.coef_D), dD/du ~ 1e-12
    assert abs(lo[0] - hi[0]) < 2e-14 * lo[0] and abs(lo[1] - hi[1]) < 1e-12 * lo[1], (lo, hi)
    assert abs(so3.coef_D(u0 * (1 - 1e-12)) - so3.coef_D(u0 * (1 + 1e-12))) < 2e-14 * lo[0]
    for u in (1e-6, 0.1, 0.3, 0.5, 2.0, 20.0):
        e = 1e-6 * max(u, 1e-3)
        fd = (_coef_D_dD(u + e)[0] - _coef_D_dD(u - e)[0]) / (2 * e)
        assert abs(fd - _coef_D_dD(u)[1]) < 1e-7 * abs(fd), u


# ---------------------------------------------------------------------------- kernel rows
def _group_exp(group, R, r, X):
    if group == "SE3":
        ER, Er = se3.exp(X)
        return R @ ER, r + R @ Er
    ER, Er = so3xr3.exp(X)
    return R @ ER, r + Er


def _two_body_scene(rng, kindA, kindB, kA=1, kB=2):
    sc = Scene()
    for i in range(2):
        x = rng.normal(size=3)
        sc.AddBody(mass=1.5 + i, inertia=np.diag([0.1, 0.2, 0.3]) * (1 + i), com=rng.normal(size=3) * 0.1,
                   R0=so3.exp(1.2 * x / np.linalg.norm(x)), r0=rng.normal(size=3),
                   omega0=rng.normal(size=3), vel0=rng.normal(size=3))
    sc.AddCoordinateConstraint(0, RotationParameterCoordinate(PARAMETRISATIONS[kindA], kA), 1,
                               RotationParameterCoordinate(PARAMETRISATIONS[kindB], kB), factor=-1.3, constant=0.2)
    return sc


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("kinds", [("RotVecLG", "EP"), ("Rxyz", "RotVecLG"), ("EP", "Rxyz")])
def test_rows_against_finite_differences(group, kinds, rng):
    """h = f q_B - q_A - c with q the node parameters; J = d h / d(twist) by central
    differences along g exp(s X), eta = -(d/dt J) V along the motion at frozen V."""
    sc = _two_body_scene(rng, *kinds)
    from exudyn_lie.mbs.compiled import compile_carried, compile_scene, make_work
    sd, _ = compile_scene(sc, [group, group])
    wk = make_work(sd, 4, carried=compile_carried(sc))
    R = np.array([b.R0 for b in sc.bodies])
    r = np.array([b.r0 for b in sc.bodies])
    V = rng.normal(size=(2, 6))
    h0, J, eta = constraint_jacobian(sd, wk, R, r, V)
    e = 1e-6
    for trial in range(3):
        X = rng.normal(size=(2, 6))
        Rp, rp, Rm, rm = R.copy(), r.copy(), R.copy(), r.copy()
        for b in range(2):
            Rp[b], rp[b] = _group_exp(group, R[b], r[b], e * X[b])
            Rm[b], rm[b] = _group_exp(group, R[b], r[b], -e * X[b])
        fd = (constraint_jacobian(sd, wk, Rp, rp, V)[0] - constraint_jacobian(sd, wk, Rm, rm, V)[0]) / (2 * e)
        assert abs(fd[0] - J[0] @ X.reshape(-1)) < 1e-8 * max(1, np.abs(J).max())

    def JV(s):
        Rs, rs = R.copy(), r.copy()
        for b in range(2):
            Rs[b], rs[b] = _group_exp(group, R[b], r[b], s * V[b])
        return constraint_jacobian(sd, wk, Rs, rs, V)[1][0] @ V.reshape(-1)
    assert abs(-(JV(e) - JV(-e)) / (2 * e) - eta[0]) < 1e-7 * max(1, abs(eta[0]))


def test_oblique_solve_compiled_only_for_scenes_that_need_it(rng):
    """A scene without RotVecLG rotation-coordinate constraints keeps the symmetric solve: its
    Work.tplan is None (band) and the compiled stage (index1.rhs) contains no LU of the
    non-symmetric solve; with such a row, tplan is an ObliquePlan and the stage calls it.
    The solution satisfies both equations of Exudyn's model: M Vdot = Q - C^T lambda and
    G Vdot = eta (checked densely).  (Read from the time loop's IR: the kinds the suite compiles
    anyway, no compile of its own.)"""
    from test_lean_scenes import time_loop_ir
    irs = {}
    for kind in ("EP", "RotVecLG"):
        sc = Scene()
        sc.AddBody(mass=2.0, inertia=np.diag([0.1, 0.2, 0.3]), com=[0.1, 0.05, -0.2], R0=so3.exp(np.array([0.3, -0.5, 0.7])),
                   r0=[0, 0, 0], omega0=[0.2, 0.9, -0.4], vel0=[0.1, 0, 0])
        sc.gravity = np.array([0.0, 0.0, -9.81])
        sc.AddCoordinateConstraint(GROUND, 0, 0, RotationParameterCoordinate(PARAMETRISATIONS[kind], 1), constant=0.0)
        sim = Simulator(sc, "RK4", "SE3", projectInitial=True)
        Vdot = sim.Accelerations()[0]
        irs[kind] = time_loop_ir(sim)
        if kind == "RotVecLG":
            plan = sim.wk.tplan
            assert type(plan).__name__ == "ObliquePlan"
            h, J, eta = constraint_jacobian(sim.sd, sim.wk, sim.R, sim.r, sim.V)
            force_direction_rows(plan, sim.wk.Jr)
            C = plan.Cr[:, 6:]                                       # side B: the body
            assert np.allclose(C, [[0, 1, 0, 0, 0, 0]])
            assert np.abs(J[0, :3] - C[0, :3]).max() > 0.1           # C != G here
            # Exudyn's model: M Vdot = Q - C^T lam (Q = M Vdot_free), G Vdot = eta
            M = sim.sd.M[0]
            Q = np.zeros((1, 6))
            from exudyn_lie.mbs import kernel
            kernel.compute_forces(sim.sd, sim.wk, 0.0, sim.R, sim.r, sim.V, Q)
            res = M @ Vdot[0] - Q[0]                                  # = -C^T lam
            lam = -res[1]
            assert np.abs(res + C[0] * lam).max() < 1e-12 * max(1, np.abs(Q).max())
            assert abs(J[0] @ Vdot[0] - eta[0]) < 1e-12 * max(1, np.abs(Vdot).max())
        else:
            assert sim.wk.tplan is None
    assert "oblique_schur_solve" in irs["RotVecLG"] and "lu_solve_inplace" in irs["RotVecLG"]
    assert "oblique_schur_solve" not in irs["EP"] and "lu_solve_inplace" not in irs["EP"]


# ---------------------------------------------------------------------------- Exudyn as the oracle
def oracle_model(node, userFunction=False):
    """Two bodies of node type ``node`` (3D, offset COM, gravity): a ConnectorCoordinate between
    rotation coordinate 1 of body 0 and rotation coordinate 2 of body 1 (factor -0.7, offset),
    a CoordinateSpringDamper from rotation coordinate 0 of body 1 to the ground, a second one
    between body 0's coordinate 2 and body 1's position coordinate 0, and a LoadCoordinate on
    body 0's rotation coordinate 0 (EP: the last Euler parameter)."""
    mbs = new_mbs()
    R0 = [so3.exp(np.array([0.3, -0.2, 0.4])), so3.exp(np.array([-0.5, 0.1, 0.2]))]
    bodies = [add_body(mbs, node, [0.3 * i, 0, 0], R0[i], gravity=(0, 0, -9.81)) for i in range(2)]
    nodes = [mbs.GetObject(b)["nodeNumber"] for b in bodies]
    ng = mbs.AddNode(NodePointGround())
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ng, coordinate=0))
    last = 6 if node == "EP" else 5

    def mc(i, k):
        return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[i], coordinate=k))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mc(0, 4), mc(1, 5)], factor1=-0.7, offset=0.05))
    kw = {}
    if userFunction:
        kw = dict(springForceUserFunction=lambda mbs, t, i, u, v, k, d, off: k * (u - off) + d * v + 0.3 * u ** 3)
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mg, mc(1, 3)], stiffness=40.0, damping=0.7,
                                                        offset=0.1, **kw))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[mc(0, 5), mc(1, 0)], stiffness=15.0,
                                                        damping=0.2, offset=-0.05))
    if userFunction:
        mbs.AddLoad(LoadCoordinate(markerNumber=mc(0, last), load=2.0, loadUserFunction=lambda mbs, t, load: load * 1.5))
    else:
        mbs.AddLoad(LoadCoordinate(markerNumber=mc(0, last), load=2.0))
    mbs.Assemble()
    return mbs


@pytest.mark.parametrize("userFunction", [False, True])
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("node", ["RotVecLG", "EP", "Rxyz"])
def test_same_as_exudyn_at_random_states(node, group, userFunction, rng):
    """M, f (spring, load: Exudyn's e_k on the node's velocity coordinates, mapped to the
    twist), g and C_q against Exudyn.  EP / Rxyz: the kernel's J equals C_q P.  RotVecLG: C_q P
    is the force direction C (ObliquePlan) and J is the gradient G of g (finite differences,
    test_rows_against_finite_differences); J = C only at theta = 0."""
    mbs = oracle_model(node, userFunction)
    for trial in range(3):
        q, qt = random_state(mbs, rng, scale=0.3)
        c = compare(mbs, group, q, qt, 0.1 + trial)
        for key in ("M", "f", "g") + (() if node == "RotVecLG" else ("J",)):
            assert c[key] < TOL, f"{key}: relative deviation {c[key]:.3g} from Exudyn (trial {trial})"
        assert c["nrows"] == 1
        if node == "RotVecLG":
            _, _, _, Ce = oracle(mbs, q, qt)
            pk = package(mbs, group, q, qt)
            sim, sc = pk["sim"], pk["scene"]
            plan = sim.wk.tplan
            force_direction_rows(plan, sim.wk.Jr)
            ji = sc.joints_info[0]
            Cx = Ce[ji.aeRows] @ pk["P"]
            Ck = np.zeros(12)
            Ck[:] = plan.Cr[0]
            Ckd = np.zeros(6 * sim.sd.nb)
            for side, b in ((0, sim.sd.jointIndex[0, 0]), (6, sim.sd.jointIndex[0, 1])):
                if b >= 0:
                    Ckd[6 * b:6 * b + 6] += Ck[side:side + 6]
            assert np.abs(Cx[0] - Ckd).max() < TOL
            assert np.abs(pk["J"][0] - Ckd).max() > 1e-3       # the gradient is not Exudyn's C_q


# ---------------------------------------------------------------------------- dynamics
def _consistent_omega(node, k, R0, omega):
    """World omega (CreateRigidBody's initialAngularVelocity) whose local R0^T omega has
    G . omega_local = 0 for rotation coordinate k: a consistent initial velocity."""
    pk, _ = KINDS[node]
    prev = np.zeros(4)
    (nearest_tait_bryan(R0, np.zeros(4), prev) if pk == PARAM_TAIT_BRYAN else quat_of(R0, prev))
    G = np.zeros(3)
    node_parameter(param_code(pk, k), R0, prev, np.zeros(3), G, np.zeros(3), np.zeros(3))
    w = R0.T @ np.asarray(omega, float)
    return R0 @ (w - (G @ w) / (G @ G) * G)


def locked_model(node):
    """TestModels style: a box (offset COM, gravity) on a spherical joint at its node, with
    rotation coordinate 1 of its node (RotVecLG: theta_1; EP: p_1; Rxyz: the middle angle, so
    that the motion stays away from the Tait-Bryan singularity, where the gradient of the other
    angles is unbounded) locked to the ground by an ObjectConnectorCoordinate; a consistent
    initial omega."""
    mbs = new_mbs()
    R0 = so3.exp(np.array([0.2, -0.3, 0.5]))
    om = _consistent_omega(node, 1, R0, [1.5, -2.0, 3.0])
    n, ng = box_on_spherical_joint(mbs, node, R0, om, com=(0.15, 0.05, -0.1))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ng, coordinate=0)),
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=4))]))
    mbs.Assemble()
    return mbs


def spring_model(node):
    """TestModels style: a free box (offset COM, gravity, spinning) with an
    ObjectConnectorCoordinateSpringDamper from the ground to its rotation coordinate 1 and a
    LoadCoordinate on its last rotation coordinate."""
    mbs = new_mbs()
    R0 = so3.exp(np.array([0.4, 0.1, -0.3]))
    b = add_body(mbs, node, [0, 0, 0], R0, omega=(2.0, -1.0, 4.0), vel=(0.1, 0, 0.2), com=(0.1, 0.05, -0.08),
                 gravity=(0, 0, -9.81))
    n = mbs.GetObject(b)["nodeNumber"]
    ng = mbs.AddNode(NodePointGround())
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ng, coordinate=0)),
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=4))], stiffness=2.0, damping=0.01, offset=0.2))
    mbs.AddLoad(LoadCoordinate(markerNumber=mbs.AddMarker(MarkerNodeCoordinate(
        nodeNumber=n, coordinate=6 if node == "EP" else 5)), load=0.05))
    mbs.Assemble()
    return mbs


def _final(make, node, h, T, lie):
    mbs = make(node)
    ss = quiet_settings(endTime=T, nsteps=int(round(T / h)))
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    # 1e-13 / 1e-15 makes Exudyn's Newton fail on the RotVecLG constraint (its Jacobian e_k is
    # not the constraint's gradient, so Newton converges only linearly)
    ss.timeIntegration.newton.relativeTolerance = 1e-11
    ss.timeIntegration.newton.absoluteTolerance = 1e-13
    (exl.SolveDynamic(mbs, ss, method="RK4") if lie else exu.SolveDynamic(mbs, ss))
    return np.array(mbs.systemData.GetODE2Coordinates())


@pytest.mark.slow
@pytest.mark.parametrize("make", [locked_model, spring_model])
@pytest.mark.parametrize("node", ["RotVecLG", "EP", "Rxyz"])
def test_models_agree_with_fine_generalized_alpha(node, make):
    """Each script solved natively by generalized-alpha at 2e-5 / 1e-5 / 5e-6 and by
    exl.SolveDynamic (RK4) at 8e-3 / 4e-3 / 2e-3 over 0.5 s; final coordinates (rotation
    parameters on Exudyn's branch).  The native runs converge with order 2 (measured 1.85-2.00);
    the reference is their Richardson extrapolation.  It agrees with exl RK4 at 1.25e-4 to
    < 1e-9 (measured 3e-12 .. 1.5e-10), so the native model is the one integrated, and the RK4
    errors at the three steps have order 4 (fitted slope; measured 3.83-4.05; e.g. RotVecLG
    locked: 6.2e-7, 3.9e-8, 2.6e-9).  Printed with -s."""
    T = 0.5
    nat = {h: _final(make, node, h, T, False) for h in (2e-5, 1e-5, 5e-6)}
    d1, d2 = np.abs(nat[2e-5] - nat[1e-5]).max(), np.abs(nat[1e-5] - nat[5e-6]).max()
    p = np.log2(d1 / d2)
    assert 1.7 < p < 2.3, (d1, d2)
    ref = nat[5e-6] + (nat[5e-6] - nat[1e-5]) / 3.0
    fine = np.abs(_final(make, node, 1.25e-4, T, True) - ref).max()
    assert fine < 1e-9, fine
    err = {h: np.abs(_final(make, node, h, T, True) - ref).max() for h in (8e-3, 4e-3, 2e-3)}
    slope = np.polyfit(np.log(list(err)), np.log(list(err.values())), 1)[0]
    print(f"{node} {make.__name__}: native differences {d1:.2g} {d2:.2g} (order {p:.2f}), |ref - RK4(1.25e-4)| "
          f"{fine:.2g}, RK4 errors " + " ".join(f"{e:.2g}" for e in err.values()) + f", slope {slope:.2f}")
    assert 3.6 < slope < 4.4, (slope, err)


def test_rotvec_constraint_refused_when_exudyn_evaluates():
    """The Exudyn-evaluated path would use Exudyn's C_q (e_k) as the constraint's gradient and
    hold omega_k instead of theta_k: refused before mbs is touched, naming the item; EP is taken."""
    for node, refused in (("RotVecLG", True), ("EP", False)):
        mbs = locked_model(node)
        q0 = np.array(mbs.systemData.GetODE2Coordinates())
        if refused:
            with pytest.raises(exl.BridgeError, match=r"object 3 .*ObjectConnectorCoordinate.*RotVecLG"):
                exl.SolveDynamic(mbs, quiet_settings(0.01, 10), evaluation="exudyn")
            assert np.array_equal(q0, mbs.systemData.GetODE2Coordinates())
        else:
            exl.SolveDynamic(mbs, quiet_settings(0.01, 10), evaluation="exudyn")


def spinning_model(node):
    """A free box spinning at about 9 rad/s (gravity, offset COM) with a weak
    CoordinateSpringDamper on rotation coordinate 2: in 0.6 s the rotation vector passes
    |theta| = pi (RotVecLG: Exudyn continues to 2 pi), the Euler parameters pass q0 = 0 and
    the Tait-Bryan angles leave (-pi, pi]."""
    mbs = new_mbs()
    b = add_body(mbs, node, [0, 0, 0], so3.exp(np.array([0.3, 0.2, 2.5])), omega=(0.5, 0.3, 9.0), vel=(0, 0, 0),
                 com=(0.05, 0.02, -0.03), gravity=(0, 0, -9.81))
    n = mbs.GetObject(b)["nodeNumber"]
    ng = mbs.AddNode(NodePointGround())
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ng, coordinate=0)),
        mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=5))], stiffness=0.5, damping=0.01))
    mbs.Assemble()
    return mbs


@pytest.mark.slow
@pytest.mark.parametrize("node", ["RotVecLG", "EP", "Rxyz"])
def test_tracked_branch_matches_exudyn_over_a_run(node):
    """The coordinate the spring sees is Exudyn's over the whole run (the branch tracked
    step by step): exl RK4 at 1e-3 against native generalized-alpha (Richardson of 2e-5 / 1e-5)
    after 0.6 s, when the parameters have left their principal range (RotVecLG |theta| = 3.79,
    EP q0 = -0.24, Rxyz third angle 5.96): 1.3e-10, 1.0e-10, 6e-11 (measured; printed with -s)."""
    T = 0.6
    nat = {h: _final(spinning_model, node, h, T, False) for h in (2e-5, 1e-5)}
    ref = nat[1e-5] + (nat[1e-5] - nat[2e-5]) / 3
    p = ref[3:] + np.asarray(spinning_model(node).GetNode(0)["referenceCoordinates"], float)[3:]     # total
    if node == "RotVecLG":
        assert np.linalg.norm(p) > np.pi + 0.3           # past pi: not the principal log
    elif node == "EP":
        assert p[0] < -0.2                                # q0 < 0: not the q0 >= 0 quaternion
    else:
        assert np.abs(p).max() > np.pi + 0.2             # beyond (-pi, pi]
    err = np.abs(_final(spinning_model, node, 1e-3, T, True) - ref).max()
    print(f"{node}: total parameters {p}, |exl - native| {err:.2g}")
    assert err < 1e-9, err


def test_index2_settings_refused_for_rotvec_constraint():
    """With Exudyn's index-2 settings its model of the RotVecLG constraint is omega_k = 0 (not
    theta_k = const): refused before mbs is touched; the EP model (same model at both
    indices) runs."""
    for node, refused in (("RotVecLG", True), ("EP", False)):
        for how in ("useIndex2Constraints", "TrapezoidalIndex2"):
            mbs = locked_model(node)
            ss = quiet_settings(0.01, 10)
            if how == "useIndex2Constraints":
                ss.timeIntegration.generalizedAlpha.useIndex2Constraints = True
            else:
                ss.timeIntegration.solverType = exu.DynamicSolverType.TrapezoidalIndex2
            q0 = np.array(mbs.systemData.GetODE2Coordinates())
            if refused:
                with pytest.raises(exl.BridgeError, match=r"object 3 .*ObjectConnectorCoordinate.*index-2"):
                    exl.SolveDynamic(mbs, ss)
                assert np.array_equal(q0, mbs.systemData.GetODE2Coordinates())
            else:
                with pytest.warns(RuntimeWarning) if how == "TrapezoidalIndex2" else _nothing():
                    exl.SolveDynamic(mbs, ss)


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *a):
        return False


def _live_load_model(node):
    """spring_model with its LoadCoordinate's load changed by a preStepUserFunction at t = 0.2."""
    mbs = spring_model(node)
    k = mbs.systemData.NumberOfLoads() - 1

    def pre(mbs, t):
        mbs.SetLoadParameter(k, "load", 0.05 if t < 0.2 - 1e-9 else -0.3)     # from the step starting at 0.2
        return True
    mbs.SetPreStepUserFunction(pre)
    return mbs


@pytest.mark.slow
@pytest.mark.parametrize("node", ["RotVecLG", "EP"])
def test_live_coordinate_load_on_a_rotation_parameter(node):
    """LoadCoordinate's ``load`` changed during the solve (its compiled row: f0 of the
    coordinate-spring row) as Exudyn reads it, from the step starting at t = 0.2.  A load that
    jumps at a step boundary makes every solver first order (generalized-alpha weighs the new
    load at the step's end, RK4 uses it in all stages), so: the fine native run (Richardson of
    2e-5 / 1e-5) is the reference, exl RK4 at 1e-3 / 5e-4 converges to it with order 1 (error
    ratio about 2; measured EP 1.2e-4 / 5.9e-5), and its order-1 extrapolation agrees with it."""
    T = 0.4
    nat = {h: _final(_live_load_model, node, h, T, False) for h in (2e-5, 1e-5)}
    ref = nat[1e-5] + (nat[1e-5] - nat[2e-5]) / 3
    const = _final(spring_model, node, 1e-3, T, True)
    assert np.abs(const - ref).max() > 1e-3           # the change matters
    exl_h = {h: _final(_live_load_model, node, h, T, True) for h in (1e-3, 5e-4)}
    e1, e2 = (np.abs(exl_h[h] - ref).max() for h in (1e-3, 5e-4))
    assert 1.8 < e1 / e2 < 2.2, (e1, e2)
    extrapolated = 2 * exl_h[5e-4] - exl_h[1e-3]
    assert np.abs(extrapolated - ref).max() < 0.02 * e2, (np.abs(extrapolated - ref).max(), e2)
