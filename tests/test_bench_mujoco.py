"""MuJoCo as a bench peer (issue 19, section 4): the MuJoCo models are the package's models.

MuJoCo is an optional bench dependency (``pip install .[bench]``): every test that needs
it skips without it; the skip path of the bench section is tested always.  No timing is
asserted (timing targets live in ``python -m exudyn_lie bench``)."""
import sys

import numpy as np
import pytest

from exudyn_lie.apps import bench_mujoco as BM


@pytest.fixture
def mujoco():
    return pytest.importorskip("mujoco", minversion="4.0.0")


def test_heavy_top_same_discrete_solution_as_mk_rk4_se3(mujoco):
    # 8 s at h = 1e-3: MuJoCo's RK4 (Munthe-Kaas on ball joints) = MK-RK4 on SE(3) to round-off
    ag = BM.agreement()
    assert ag["mujocoTime"] == pytest.approx(8.0, abs=1e-9)
    assert ag["dr"] <= 1e-12 and ag["dR"] <= 1e-12, ag
    # the bound discriminates: either run is far from the exact solution (discretisation error)
    assert ag["discretisation"] > 1e-8, ag
    assert ag["ok"]
    # the round-off floor: one ulp in the initial angular velocity moves the package's own run
    # (a positive distance), and the two implementations differ by no more than a few such floors
    assert 0.0 < ag["roundoff"] < 1e-10, ag
    assert max(ag["dr"], ag["dR"]) <= 10 * ag["roundoff"], ag


def test_heavy_top_agreement_needs_the_same_algorithm(mujoco):
    # the same comparison against MK-RK4 on SO(3)xR3 (another algorithm) fails the bound by far
    mbs, info = BM.build_info("heavytop")
    n, h = 1000, 1e-3
    sim = BM.exl_simulator(mbs, "RK4", "SO3xR3")
    sim.SetInitialState()
    sim.Advance(n, h)
    run = BM.MujocoRun(info, h)
    run.reset()
    run.step(n)
    R, r = run.state()
    assert max(BM.distance(R, r, sim.R, sim.r)) > 1e-8


def test_double_pendulum_converges_to_the_package_solution(mujoco):
    # relative joint coordinates: another discrete solution, but the same model, so the
    # difference to a fine exudyn_lie run falls at RK4's order
    mbs, info = BM.build_info("doublependulum")
    T = 0.5
    ref = BM.exl_simulator(mbs, "RK6", "SE3")
    ref.SetInitialState()
    ref.Advance(50000, T / 50000)
    run = BM.MujocoRun(info, 1e-3)
    errs = []
    for n in (1000, 2000, 4000, 8000):
        run.set_step(T / n)
        run.reset()
        run.step(n)
        assert run.ok()
        R, r = run.state()
        errs.append(max(BM.distance(R, r, ref.R, ref.r)))
    # a model difference d would make the errors level off at d (order -> 0 at the finest steps);
    # the reference's own error (RK6, h = 1e-5) is far below the finest MuJoCo error (~1e-8)
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all((orders > 3.5) & (orders < 4.6)), (errs, orders)


def test_mjcf_is_built_from_the_model_data(mujoco):
    for name in BM.MODELS:
        mbs, info = BM.build_info(name)
        run = BM.MujocoRun(info, 1e-3)
        m = run.m
        assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4
        assert m.opt.timestep == 1e-3
        assert m.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
        np.testing.assert_array_equal(m.opt.gravity, info.gravity)
        assert m.nbody == len(info.bodies) + 1 and m.njnt == len(info.joints) and m.ngeom == 0
        assert all(t == mujoco.mjtJoint.mjJNT_BALL for t in m.jnt_type)
        for i, b in enumerate(info.bodies):
            assert m.body_mass[i + 1] == b.mass
            np.testing.assert_allclose(m.body_ipos[i + 1], b.com, atol=1e-15)
            # MuJoCo stores principal moments (descending) and the principal frame
            np.testing.assert_allclose(np.sort(m.body_inertia[i + 1]), np.sort(np.linalg.eigvalsh(b.inertiaCOM)),
                                       rtol=1e-14)
        # the initial state is the package's: positions and angular velocities of every body
        run.reset()
        mujoco.mj_forward(m, run.d)
        R, r = run.state()
        for i, b in enumerate(info.bodies):
            np.testing.assert_allclose(r[i], b.r0, atol=1e-15)
            np.testing.assert_allclose(R[i], b.R0, atol=1e-15)
            w = np.zeros(6)
            mujoco.mj_objectVelocity(m, run.d, mujoco.mjtObj.mjOBJ_BODY, i + 1, w, 0)   # world axes
            np.testing.assert_allclose(w[:3], b.R0 @ b.omega0, atol=1e-13)
            # the frame origin's velocity (world) = the package's initial velocity of body i
            np.testing.assert_allclose(w[3:] + np.cross(w[:3], r[i] - run.d.xipos[i + 1]), b.vel0, atol=1e-13)
        if info.springs:
            s = info.springs[0]
            assert m.ntendon == 1 and m.tendon_stiffness[0] == s.stiffness
            np.testing.assert_array_equal(m.tendon_lengthspring[0], [0.0, 0.0])


def test_heavy_top_spring_force_is_c_times_p0_minus_r(mujoco):
    # the tendon's passive force at a moved state equals the package's spring c (p0 - r), plus nothing else
    from exudyn_lie.models.heavy_top import P0, STIFFNESS
    mbs, info = BM.build_info("heavytop")
    run = BM.MujocoRun(info, 1e-3)
    run.reset()
    rng = np.random.default_rng(1)
    q = rng.normal(size=4)
    run.d.qpos[:] = q / np.linalg.norm(q)
    mujoco.mj_forward(run.m, run.d)
    r = run.d.xpos[1].copy()
    F = STIFFNESS * (P0 - r)
    # generalised force of a world force F at the COM on the ball joint: torque (r - pivot) x F in body axes
    R = run.d.xmat[1].reshape(3, 3)
    expected = R.T @ np.cross(r, F)
    np.testing.assert_allclose(run.d.qfrc_passive, expected, rtol=1e-12, atol=1e-9)


def test_refuses_models_it_cannot_build_the_same(mujoco):
    from exudyn_lie import models
    mbs, info = models.build("planar_four_bar")
    with pytest.raises(ValueError, match="revolute"):
        BM.mjcf_from_info(info, 1e-3)
    mbs, info = models.build("spherical_double_pendulum")
    j = info.joints[1]      # a second joint from the ground to link2 closes a loop
    info.joints.append(type(j)("joint3", j.objectIndex, "spherical", -1, 1, j.posA, j.rotA, j.posB, j.rotB))
    with pytest.raises(ValueError, match="joint3.*loop"):
        BM.mjcf_from_info(info, 1e-3)
    mbs, info = models.build("free_body_com_rotation")
    with pytest.raises(ValueError, match="no joint"):
        BM.mjcf_from_info(info, 1e-3)


def test_section_skips_with_one_line_without_mujoco(monkeypatch):
    monkeypatch.setitem(sys.modules, "mujoco", None)      # import mujoco raises ImportError
    lines = []
    res = BM.run_section(object(), lines.append)
    assert "not installed" in res["skipped"] and "pip install" in res["skipped"]
    assert lines == [res["skipped"]]
    rows = BM.target_lines(res)
    assert len(rows) == 1 and "skipped" in rows[0]
    assert res["skipped"] in "\n".join(BM.report_lines(res))


def test_bench_section_quick(mujoco, tmp_path):
    import json

    from exudyn_lie.apps import bench
    assert bench.main(["--quick", "--sections", "mujoco", "--out", str(tmp_path), "--no-progress"]) == 0
    text = (tmp_path / "BENCHMARKS.md").read_text()
    assert "## 8. MuJoCo as a peer" in text
    assert "MK-RK4 (SE3) step >= 3x cheaper than MuJoCo's RK4 step" in text
    assert "MK-RK4 (SE3) step >= 2x cheaper than MuJoCo's RK4 step" in text
    fig = tmp_path / "bench_figures" / "wp_mujoco.png"
    assert fig.exists() and fig.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    data = json.loads((tmp_path / "bench_results.json").read_text())["mujoco"]
    assert data["agreement"]["ok"]
    for name in BM.MODELS:
        for d in data["perstep"][name].values():
            assert d["exl"] > 0 and d["mujoco"] > 0 and d["rolloutSame"]
        curves = data["wp"][name]["curves"]
        # the same step sizes on both sides; on the heavy top the same errors (same discrete solution)
        assert [p["n"] for p in curves["MuJoCo RK4"]] == [p["n"] for p in curves["RK4 SE3"]]
        if name == "heavytop":
            for a, b in zip(curves["MuJoCo RK4"], curves["RK4 SE3"]):
                assert a["err"] == pytest.approx(b["err"], rel=1e-6, abs=1e-13)
