"""Planar rigid bodies (issue 16, item 1): the groups SE(2) and SO(2) x R^2, Exudyn's
NodeRigidBody2D / ObjectRigidBody2D, ObjectJointRevolute2D / ObjectJointPrismatic2D and the
markers, loads and connectors on 2D bodies, mixed with 3D bodies.

* group identities as for SE(3): exp/log, dexp dexpinv = I, dexp against finite differences
  of exp and against the ad-series, on both sides of every Taylor switch; the maps equal the
  restriction of SE(3)'s / SO(3) x R^3's to the plane;
* Exudyn as the oracle: M, f, g, C_q at random states (``ComputeMassMatrix``,
  ``ComputeODE2RHS``, ``ComputeJacobianAE``) for every item on 2D bodies, in both c-spaces;
* J and eta of the 2D rows against finite differences along the planar group motions;
* corollary 1 in the plane; agreement with native generalized-alpha at a fine step.
"""
import numpy as np
import pytest

import exudyn as exu
from exudyn.utilities import (LoadForceVector, LoadMassProportional, LoadTorqueVector, MarkerBodyMass,
                              MarkerBodyPosition, MarkerBodyRigid, MarkerNodePosition, MarkerNodeRigid,
                              NodeRigidBody2D, ObjectConnectorSpringDamper, ObjectGround, ObjectJointPrismatic2D,
                              ObjectJointRevolute2D, ObjectRigidBody2D, RotationMatrixX, RotationMatrixZ)

from exudyn_lie.groups import GROUPS, se2, se3, so2xr2, so3, so3xr3
from exudyn_lie.mbs import GROUND, Scene, Simulator
from exudyn_lie.mbs.compiled import compile_carried, compile_scene, make_work
from exudyn_lie.mbs.diagnostics import constraint_jacobian

from test_bridge_common import NODE_TYPES, add_body, compare, new_mbs, random_state

PLANAR = {"SE2": (se2, se3), "SO2xR2": (so2xr2, so3xr3)}
# angles on both sides of every switch between closed form and Taylor branch used by the planar maps
SWITCHES = [so3.T_SWITCH_EXP, so3.T_SWITCH_DEXPINV]
ANGLES = [0.0, 1e-9, 1e-4, 0.3, 1.0, 2.0, 3.0] + [t * f for t in SWITCHES for f in (1 - 1e-6, 1 + 1e-6)]


def planar_vec(rng, theta):
    X = np.zeros(6)
    X[2] = theta
    X[3:5] = rng.normal(size=2)
    return X


# ---------------------------------------------------------------------------- groups
@pytest.mark.parametrize("name", list(PLANAR))
def test_planar_group_identities(name, rng):
    G, G3 = PLANAR[name]
    assert GROUPS[name] is G
    for th in ANGLES:
        for sign in (1, -1):
            X = planar_vec(rng, sign * th)
            Y = planar_vec(rng, rng.normal())
            R, r = G.exp(X)
            # exp is the restriction of the 3D group's exp; log inverts it (|theta| <= pi)
            R3, r3 = G3.exp(X)
            np.testing.assert_allclose(R, R3, atol=1e-15)
            np.testing.assert_allclose(r, r3, atol=1e-15)
            np.testing.assert_allclose(G.log(R, r), X, atol=1e-14)
            # dexp dexpinv = I (6x6), and both equal the 3D maps on the plane
            np.testing.assert_allclose(G.dexp(X) @ G.dexpinv(X), np.eye(6), atol=1e-14)
            ax = [2, 3, 4]
            np.testing.assert_allclose(G.dexp(X)[np.ix_(ax, ax)], G3.dexp(X)[np.ix_(ax, ax)], atol=1e-15)
            np.testing.assert_allclose(G.dexpinv(X)[np.ix_(ax, ax)], G3.dexpinv(X)[np.ix_(ax, ax)], atol=1e-15)
            # against the ad-series (eq. dexp / dexpInvSeries), accurate for |theta| < 2
            if th < 2:
                np.testing.assert_allclose(G.dexp(X)[np.ix_(ax, ax)], G3.dexp_series(X, 60)[np.ix_(ax, ax)],
                                           atol=2e-15)
                np.testing.assert_allclose(G.dexpinv(X)[np.ix_(ax, ax)],
                                           G3.dexpinv_series(X, 60)[np.ix_(ax, ax)], atol=4e-15)
            # finite differences of exp: d/de exp(X + e Y) = hat(dexp_X Y) exp(X) (right-trivialised)
            e = 1e-6
            Rp, rp = G.exp(X + e * Y)
            Rm, rm = G.exp(X - e * Y)
            Ri, ri = G.inverse(R, r)
            dp = G3.log(*G3.compose(Rp, rp, Ri, ri))
            dm = G3.log(*G3.compose(Rm, rm, Ri, ri))
            np.testing.assert_allclose((dp - dm) / (2 * e), G.dexp(X) @ Y, atol=1e-8)


def test_planar_maps_are_as_fast_as_the_restriction():
    """Not a timing assertion: the planar maps call no 3D map (closed forms in theta only)."""
    import inspect
    src = inspect.getsource(se2.exp_into.py_func) + inspect.getsource(se2.dexpinv_apply_into.py_func)
    assert "se3." not in src and "so3.exp" not in src


# ---------------------------------------------------------------------------- Exudyn oracle
def planar_model(kind):
    """Two 2D bodies (one with its COM off the node), ground, and the items of ``kind``."""
    mbs = new_mbs()
    g = mbs.AddObject(ObjectGround(referencePosition=[0.1, 0.2, 0]))
    n0 = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[1, 2, 0.3], initialVelocities=[0.1, 0.2, 0.5]))
    b0 = mbs.AddObject(ObjectRigidBody2D(nodeNumber=n0, mass=2, inertia=0.3, centerOfMass=[0.1, -0.05]))
    n1 = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[2, 2.5, -0.3], initialVelocities=[0.1, -0.2, 0.5]))
    b1 = mbs.AddObject(ObjectRigidBody2D(nodeNumber=n1, mass=1.5, inertia=0.2))
    m0 = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b0, localPosition=[0.5, 0.1, 0.2]))
    # the ground point coincides with m0 initially (random states start near consistency)
    mg = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g, localPosition=[1.3481162, 2.0432938, 0]))
    m1p = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b1, localPosition=[-0.5, 0.1, 0]))
    m1n = mbs.AddMarker(MarkerNodePosition(nodeNumber=n1))
    m0r = mbs.AddMarker(MarkerNodeRigid(nodeNumber=n0))
    for b in (b0, b1):
        mm = mbs.AddMarker(MarkerBodyMass(bodyNumber=b))
        mbs.AddLoad(LoadMassProportional(markerNumber=mm, loadVector=[0, -9.81, 0]))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[mg, m0]))
    if kind == "revolute_chain":
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[m0, m1p]))
    elif kind == "prismatic":
        m1r = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b1, localPosition=[0.2, -0.1, 0]))
        mbs.AddObject(ObjectJointPrismatic2D(markerNumbers=[m0r, m1r], axisMarker0=[np.cos(.4), np.sin(.4), 0],
                                             normalMarker1=[-np.sin(.2), np.cos(.2), 0]))
    mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[mg, m1n], stiffness=100, damping=2, referenceLength=0.5))
    mbs.AddLoad(LoadForceVector(markerNumber=m1p, loadVector=[1, 2, 3]))
    mbs.AddLoad(LoadForceVector(markerNumber=m0, loadVector=[0.5, -1, 0], bodyFixed=True))
    mbs.AddLoad(LoadTorqueVector(markerNumber=m0r, loadVector=[0, 0, 0.7]))
    if kind == "mixed_3d":
        # a 3D body (RotVecLG) tied to a 2D body by a revolute 2D joint and a spring
        b3 = add_body(mbs, "RotVecLG", [1.5, 2.5, 0.0], RotationMatrixZ(0.2) @ RotationMatrixX(0.1),
                      gravity=[0, -9.81, 0])
        m3 = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b3, localPosition=[0.0, 0.0, 0.0]))
        m1b = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b1, localPosition=[-0.5, 0.0, 0.0]))
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[m1b, m3]))
        m3b = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b3, localPosition=[0.1, 0.2, 0.3]))
        mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[m0, m3b], stiffness=50, damping=1,
                                                  referenceLength=0.3))
    mbs.Assemble()
    return mbs


@pytest.mark.parametrize("group", ["SE3", "SO3xR3", "auto"])
@pytest.mark.parametrize("kind", ["revolute_chain", "prismatic", "mixed_3d"])
def test_same_M_f_jacobian_as_exudyn_2d(kind, group, rng):
    mbs = planar_model(kind)
    for trial in range(2):
        q, qt = random_state(mbs, rng, scale=0.05)
        c = compare(mbs, group, q, qt, 0.37 + trial)
        assert c["nrows"] >= 4
        for key in ("M", "f", "g", "J"):
            assert c[key] < 1e-11, f"{kind} {group} {key}: relative deviation {c[key]:.3g} from Exudyn"


# ---------------------------------------------------------------------------- finite differences of J, eta
def planar_scene(rng):
    sc = Scene()
    for _ in range(2):
        m = rng.uniform(0.5, 3.0)
        sc.AddBody2D(m, rng.uniform(0.05, 0.2), position=rng.normal(size=2), angle=rng.normal(),
                     com=rng.normal(size=2) * 0.05)
    # revolute 2D (world x, y rows) and prismatic 2D (local translation row + rotation row)
    sc.AddJoint(0, 1, (1, 1, 0, 0, 0, 0), posA=rng.normal(size=3) * 0.3, posB=rng.normal(size=3) * 0.3,
                worldTranslation=True)
    sc.AddJoint(GROUND, 0, (1, 0, 0, 0, 0, 1), posA=rng.normal(size=3) * 0.3, rotA=RotationMatrixZ(0.7),
                posB=rng.normal(size=3) * 0.3, rotB=RotationMatrixZ(-0.4))
    return sc


@pytest.mark.parametrize("space", ["SE3", "SO3xR3"])
def test_2d_rows_against_finite_differences(space, rng):
    sc = planar_scene(rng)
    sd, _ = compile_scene(sc, [space, space])
    G = se2 if space == "SE3" else so2xr2
    wk = make_work(sd, 4, carried=compile_carried(sc))
    R = np.array([b.R0 for b in sc.bodies])
    r = np.array([b.r0 for b in sc.bodies])
    V = np.zeros((2, 6))
    V[:, 2:5] = rng.normal(size=(2, 3))

    def moved(i, X):
        ER, Er = G.exp(X)
        if space == "SE3":
            return R[i] @ ER, r[i] + R[i] @ Er
        return R[i] @ ER, r[i] + Er

    h0, J, eta = constraint_jacobian(sd, wk, R, r, V)
    eps = 1e-6
    for i in range(2):
        for k in (2, 3, 4):
            X = np.zeros(6)
            X[k] = eps
            Rp, rp, Rm, rm = R.copy(), r.copy(), R.copy(), r.copy()
            Rp[i], rp[i] = moved(i, X)
            Rm[i], rm[i] = moved(i, -X)
            fd = (constraint_jacobian(sd, wk, Rp, rp, V)[0] - constraint_jacobian(sd, wk, Rm, rm, V)[0]) / (2 * eps)
            np.testing.assert_allclose(J[:, 6 * i + k], fd, atol=1e-8)

    def JV(tau):
        Rt, rt = R.copy(), r.copy()
        for i in range(2):
            Rt[i], rt[i] = moved(i, tau * V[i])
        return constraint_jacobian(sd, wk, Rt, rt, V)[1] @ V.reshape(-1)

    np.testing.assert_allclose(-eta, (JV(eps) - JV(-eps)) / (2 * eps), atol=1e-7)


# ---------------------------------------------------------------------------- corollary 1 in the plane
def pendulum_scene():
    """A 2D bar (COM frame) pinned at its end to the ground origin, gravity -y."""
    sc = Scene(gravity=(0, -9.81, 0))
    L = 0.5
    b = sc.AddBody2D(1.0, L ** 2 / 12, position=(L / 2, 0), angle=0.0, omega=2.0, velocity=(0, 2.0 * L / 2))
    sc.AddJoint(GROUND, b, (1, 1, 0, 0, 0, 0), posA=(0, 0, 0), posB=(-L / 2, 0, 0), worldTranslation=True)
    return sc


def max_violation(space, h, T=2.0):
    sim = Simulator(pendulum_scene(), "RK4", space)
    res = sim.Run(T, h, outputEvery=1)
    return np.max(res.jointPositionViolation[:, 0])


def test_corollary_1_planar_pendulum_exact_on_se2_not_on_so2xr2():
    """The pendulum's motion (rotation about the pivot) is a one-parameter subgroup of SE(2),
    not of SO(2) x R^2: the pivot stays put to round-off on SE2, and drifts at order 4 on
    SO2xR2 (RK4, no stabilisation)."""
    for h in (1e-2, 1e-3):
        assert max_violation("SE3", h) <= 1e-13
    v1 = max_violation("SO3xR3", 1e-2)
    v2 = max_violation("SO3xR3", 5e-3)
    assert v1 >= 1e-8, v1
    assert 12 < v1 / v2 < 20, (v1, v2)


def test_2d_bodies_run_on_the_planar_subgroups():
    sc = pendulum_scene()
    assert Simulator(sc, "RK4", "SE3").groups == ["SE2"]
    assert Simulator(sc, "RK4", "SO3xR3").groups == ["SO2xR2"]
    assert Simulator(sc, "RK4", "auto").groups == ["SE2"]
    # users name the c-space; the planar groups follow from it (a planar name is refused)
    with pytest.raises(ValueError, match="unknown Lie group 'SE2'.*2D bodies then run on SE2"):
        Simulator(sc, "RK4", "SE2")
    sc3 = Scene()
    sc3.AddBody(1.0, np.eye(3))
    with pytest.raises(ValueError, match="planar group"):
        compile_scene(sc3, ["SE2"])


def test_paper_extension_planar_claims_hold():
    """The extension section of the paper reproduction (apps/paper_planar.py) at dt = 1e-2, 1e-3:
    every claim holds (corollary 1 for the joints to ground, same order elsewhere)."""
    from exudyn_lie.apps.paper_planar import planar_extension, report_lines
    ext = planar_extension((1e-2, 1e-3))
    bad = [r for r in ext["rows"] if not r["holds"]]
    assert not bad, bad
    assert len(ext["rows"]) == 9 and "Extension: planar" in report_lines(ext)[0]
