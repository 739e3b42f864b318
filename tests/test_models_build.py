"""The paper's mechanisms as Exudyn models: data, consistency, and native solvers.

* every builder returns an Exudyn model whose items match its ``info`` (checked against
  the bridge's independent reading of the mbs, ``SceneFromExudyn``);
* the paper's numbers (masses, inertias, T0, E(0)) come out of the models;
* initial positions and velocities satisfy every joint;
* every model runs with Exudyn's own solvers (short span).
"""
import contextlib
import io

import numpy as np
import pytest

import exudyn as exu
from exudyn_lie import models
from exudyn_lie.models.energy import energies
from exudyn_lie.models.geometry import joint_velocity_violations, joint_violations

ALL = models.MODELS


@pytest.mark.parametrize("name", ALL)
def test_builds_consistent_and_documented(name):
    mbs, info = models.build(name)
    assert info.name == name and info.mbs is mbs
    assert info.endTime > 0 and info.choices, "time span and filled gaps must be documented"
    assert [j.name for j in info.joints] == [f"joint{k + 1}" for k in range(len(info.joints))]
    models.check_initial_consistency(info, tol=1e-12)
    # the module docstring documents the model (and its choices)
    assert len(models.module(name).__doc__ or "") > 200
    for c in info.claims:
        assert c.kind in ("exact_SE3", "exact_SO3xR3", "exact_both", "SE3_exact", "same_order",
                          "SO3xR3_better", "SE3_better", "SE3_better_large_step", "identical_rotation",
                          "identical_drift")
        if c.measure in ("position", "rotation"):
            info.joint(c.target)


@pytest.mark.parametrize("name", ALL)
def test_info_matches_the_exudyn_model(name):
    """Bodies, joint frames and springs in ``info`` equal what the bridge reads from mbs."""
    from exudyn_lie.bridge import SceneFromExudyn
    mbs, info = models.build(name)
    mbs.Assemble()
    sc = SceneFromExudyn(mbs)
    assert sc.nBodies == len(info.bodies)
    for b in info.bodies:
        k = sc.body_of_object(b.objectIndex)
        B = sc.bodies[k]
        assert B.mass == pytest.approx(b.mass, rel=1e-14)
        np.testing.assert_allclose(B.inertia, b.inertia, atol=1e-14)
        np.testing.assert_allclose(B.com, b.com, atol=1e-15)
        np.testing.assert_allclose(B.R0, b.R0, atol=1e-14)
        np.testing.assert_allclose(B.r0, b.r0, atol=1e-15)
        np.testing.assert_allclose(B.omega0, b.omega0, atol=1e-12)
        np.testing.assert_allclose(B.vel0, b.vel0, atol=1e-12)
    jmap = {ji.objectIndex: ji.sceneJoint for ji in sc.joints_info}
    for j in info.joints:
        J = sc.joints[jmap[j.objectIndex]]
        assert tuple(J.constrainedAxes) == j.lockedAxes
        np.testing.assert_allclose(J.posA, j.posA, atol=1e-14)
        np.testing.assert_allclose(J.posB, j.posB, atol=1e-14)
        if any(j.lockedAxes[3:]):
            np.testing.assert_allclose(J.rotA, j.rotA, atol=1e-12)
            np.testing.assert_allclose(J.rotB, j.rotB, atol=1e-12)
    assert len(sc.springs) == len(info.springs)
    for s, S in zip(info.springs, sc.springs):
        assert S.stiffness == s.stiffness and S.referenceLength == s.referenceLength
    np.testing.assert_allclose(sc.gravity, info.gravity)


def test_paper_data():
    fb = models.build("free_body_com_rotation")[1].bodies[0]
    assert fb.mass == pytest.approx(86.4)
    np.testing.assert_allclose(np.diag(fb.inertia), [1.224, 4.68, 5.76], rtol=1e-12)
    off = models.build("free_body_offset_rotation")[1]
    np.testing.assert_allclose(np.diag(off.bodies[0].inertia), [1.224, 18.504, 19.584], rtol=1e-12)
    assert off.computed["T0"] == pytest.approx(696.399, abs=5e-4)          # paper: T0 = 696.399 J
    top = models.build("heavy_top")[1]
    assert top.bodies[0].mass == pytest.approx(21.6)
    np.testing.assert_allclose(np.diag(top.bodies[0].inertia), [0.36, 0.306, 0.09], rtol=1e-12)
    assert top.computed["E0"] == pytest.approx(2500.69, abs=5e-3)
    assert top.computed["E0_spring_without_half"] == pytest.approx(5000.69, abs=5e-3)   # the paper's number
    assert top.springs[0].referenceLength == 0.0
    np.testing.assert_allclose(top.bodies[0].vel0, [0, 0.25, 0])
    rp = models.build("rp_mechanism")[1]
    assert rp.bodies[0].mass == pytest.approx(6.82825, abs=1e-5)
    assert rp.bodies[1].mass == pytest.approx(0.864)
    np.testing.assert_allclose(np.diag(rp.bodies[0].inertiaCOM), [0.0507567, 0.0507567, 0.0986682], atol=1e-7)
    np.testing.assert_allclose(np.diag(rp.bodies[1].inertiaCOM), [0.0002304, 0.0029952, 0.0029952], atol=1e-10)
    dp = models.build("spherical_double_pendulum")[1]
    assert dp.bodies[0].mass == pytest.approx(2.7)
    np.testing.assert_allclose(dp.bodies[1].omega0, [10 * np.pi, 10 * np.pi, 20 * np.pi])


@pytest.mark.parametrize("kw", [{}, dict(spring=False, tilt=0.3, omega0=[150.0, 0.4, -0.3])])
def test_heavy_top_scene_is_the_exudyn_model(kw):
    """The one heavy-top builder: the kernel scene of heavy_top.scene() is the Exudyn model
    of heavy_top.build() as the bridge reads it (inertia to 1 ulp; the initial state to round-off: Exudyn stores the angular
    velocity in world components)."""
    from exudyn_lie.bridge import SceneFromExudyn
    from exudyn_lie.models import heavy_top
    mbs, info = heavy_top.build(**kw)
    mbs.Assemble()
    read, own = SceneFromExudyn(mbs), heavy_top.scene(**kw)
    a, b = read.bodies[0], own.bodies[0]
    assert a.mass == pytest.approx(b.mass, rel=1e-15)
    np.testing.assert_allclose(a.inertia, b.inertia, rtol=1e-15, atol=0)
    for key in ("com", "R0", "r0", "omega0", "vel0"):
        np.testing.assert_allclose(getattr(a, key), getattr(b, key), rtol=1e-13, atol=1e-14, err_msg=key)
    np.testing.assert_array_equal(read.gravity, own.gravity)
    assert len(read.springs) == len(own.springs) == (1 if kw.get("spring", True) else 0)
    for x, y in zip(read.springs, own.springs):
        assert (x.bodyA, x.bodyB, x.stiffness, x.referenceLength) == (y.bodyA, y.bodyB, y.stiffness, y.referenceLength)
        np.testing.assert_array_equal(x.posA, y.posA)
    (ja,), (jb,) = read.joints, own.joints
    assert ja.constrainedAxes == jb.constrainedAxes == (1, 1, 1, 0, 0, 0)
    np.testing.assert_allclose(ja.posB, jb.posB, atol=1e-15)


def test_rp_mechanism_subgroup_geometry():
    """Prismatic axis parallel to the revolute axis, both COMs off the revolute axis."""
    info = models.build("rp_mechanism")[1]
    j1, j2 = info.joints
    z1 = j1.rotA[:, 2]                    # revolute axis (ground frame, world)
    x2 = info.bodies[0].R0 @ j2.rotA[:, 0]  # prismatic axis in world
    assert abs(abs(z1 @ x2) - 1) < 1e-14
    for b in info.bodies:
        assert np.linalg.norm(np.cross(z1, b.r0 + b.R0 @ b.com - j1.posA)) > 0.05


def test_planar_four_bar_is_a_grashof_crank_rocker():
    from exudyn_lie.models import planar_four_bar as pf
    L0, L1, L2, L3 = pf.L0, pf.L1, pf.L2, pf.L3
    s, l = min(L0, L1, L2, L3), max(L0, L1, L2, L3)
    assert s + l <= L0 + L1 + L2 + L3 - s - l and s == L1 and L0 == 0.5
    info = pf.build()[1]
    assert info.bodies[0].omega0[2] == pytest.approx(10 * np.pi)
    assert info.joints[3].kind == "spherical"


def test_cardan_shaft_frames():
    """Body 1's COM frame on the revolute axis; body 2's frame away from the cross centre,
    which lies on the revolute axis."""
    from exudyn_lie.models import cardan_shaft as cs
    info = cs.build()[1]
    j1, j2 = info.joints
    b1, b2 = info.bodies
    axis = j1.rotA[:, 2]
    assert np.linalg.norm(np.cross(axis, b1.r0 - j1.posA)) < 1e-15
    cross = b1.r0 + b1.R0 @ j2.posA
    assert np.linalg.norm(np.cross(axis, cross - j1.posA)) < 1e-15
    assert np.linalg.norm(b2.r0 - cross) > 0.1


@pytest.mark.parametrize("name", ALL)
def test_runs_with_a_native_solver(name):
    """Every model runs with Exudyn's own solvers: the implicit DAE solvers for the
    constrained models (on Euler-parameter nodes), RK44 / DOPRI5 on RotVecLG nodes for the
    free bodies; the violations read from the sensors are small."""
    info0 = models.build(name)[1]
    for solver in models.native_solvers_for(info0):
        nt = (exu.NodeType.RotationEulerParameters if info0.constrained
              else exu.NodeType.RotationRotationVector)
        mbs, info = models.build(name, nodeType=nt)
        with contextlib.redirect_stdout(io.StringIO()):
            res = models.run_native(info, solver, stepSize=1e-4, endTime=0.05, outputPeriod=1e-3)
        assert res.ok, f"{name} {solver}: {res.message}"
        assert res.times[-1] == pytest.approx(0.05)
        for j in info.joints:
            pv, rv = joint_violations(j, res.R, res.r)
            assert pv.max() < 1e-5 and rv.max() < 1e-5, (name, solver, j.name, pv.max(), rv.max())
            assert joint_velocity_violations(j, res.R, res.r, res.omega, res.vel).max() < 1e-3
        E = energies(info, res.R, res.r, res.omega, res.vel).sum(axis=1)
        assert abs(E[-1] - E[0]) <= 1e-4 * max(1.0, abs(E[0]))


def test_explicit_native_solvers_refuse_joints():
    info = models.build("heavy_top")[1]
    with pytest.raises(ValueError, match="refuse joints"):
        models.run_native(info, "RK44", 1e-3)


def test_native_rotvec_explicit_free_body_matches_exact():
    """Exudyn's RK44 with RotVecLG nodes (its explicit Lie group update) on the free body
    at the COM: the translation is exact (SO(3)xR3-type update), as for MK-RK4 SO3xR3."""
    mbs, info = models.build("free_body_com_translation")
    res = models.run_native(info, "RK44", 1e-3)
    ex = info.exact(res.times)
    xc = res.r + np.einsum("nbij,bj->nbi", res.R, np.array([b.com for b in info.bodies]))
    assert np.abs(xc - ex["com"]).max() < 1e-9
