"""Lean scenes (mbs/presence.py): a scene with only the common features compiles none of the
other features' code, and runs the same solution as when it is compiled full.

* which scenes are lean: every force element registered ``lean`` and the lower-pair and
  distance row kinds; one item of any other kind makes the scene full;
* the same scene compiled lean and full (``compiled.LEAN_SCENES``) gives bit-identical states
  and multipliers, with every row kind and force element of a lean scene present;
* the lean stage's LLVM IR has none of the absent features' functions (the full one has them);
* the same for a run-time switch made a compile-time one: the projection after each step
  (only with stabilisation).
"""
import numpy as np
import pytest

from exudyn_lie.groups import so3
from exudyn_lie.mbs import GROUND, Scene, Simulator, compiled, force_elements, kernel
from exudyn_lie.mbs.codes import ROW_DIST, ROW_ROT, ROW_TRANS_LOCAL, ROW_TRANS_WORLD


def lean_scene():
    """Two bodies with every lean feature: gravity, a load, a point-to-point spring, a
    spherical joint (world rows), a cylindrical joint (local translation and rotation rows), a distance
    constraint."""
    sc = Scene()
    sc.gravity = np.array([0.0, -9.81, 0.0])
    for k in range(3):
        sc.AddBody(mass=1.0 + k, inertia=np.diag([0.1, 0.2, 0.15]) * (1 + k), com=[0.05, 0.0, 0.02],
                   R0=so3.exp(np.array([0.1 * k, 0.2, -0.1])), r0=[0.5 * k, 0.0, 0.0], omega0=[0.3, -0.2, 0.5 * k],
                   vel0=[0.0, 0.0, 0.0])
    sc.AddSphericalJoint(GROUND, 0, position=[0.0, 0.0, 0.0])
    sc.AddCylindricalJoint(0, 1, position=[0.25, 0.0, 0.0], axis=[0, 0, 1])
    sc.AddDistanceConstraint(GROUND, [1.5, 0.5, 0.0], 2, [0.0, 0.0, 0.0], distance=0.55)
    sc.AddSpringDamper(1, [0.25, 0.0, 0.0], 2, [-0.25, 0.0, 0.0], stiffness=200.0, damping=1.0)
    sc.AddForce(2, [0.0, 0.0, 1.5])
    return sc


def run(sc, lean, group="SE3", monkeypatch=None):
    monkeypatch.setattr(compiled, "LEAN_SCENES", lean)
    sim = Simulator(sc, "RK4", group, projectInitial=True)
    sim.Advance(200, 1e-3)
    return sim


def test_lean_scene_has_every_lean_feature():
    sc = lean_scene()
    assert compiled.scene_is_lean(sc)
    kinds = {k for j in sc.joints for k, _, _ in compiled.joint_rows_of(j)}
    assert {ROW_TRANS_WORLD, ROW_TRANS_LOCAL, ROW_ROT, ROW_DIST} <= kinds
    lean = [e.name for e in force_elements.ELEMENTS if e.lean]
    assert lean == ["spring"]


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_lean_and_full_give_identical_states(group, monkeypatch):
    sc = lean_scene()
    a = run(sc, True, group, monkeypatch)
    assert a.sd.rowsAll is None and a.sd.cartesianBodies is None and a.wk.path.rollingDiscs is None
    b = run(sc, False, group, monkeypatch)
    assert b.sd.rowsAll is True and b.sd.cartesianBodies is not None and b.wk.path.rollingDiscs is not None
    for x, y in ((a.R, b.R), (a.r, b.r), (a.V, b.V), (a.wk.lam, b.wk.lam)):
        assert np.array_equal(x, y)
    # a real motion, constrained: the check is not vacuous
    assert np.abs(a.V).max() > 0.1 and np.abs(a.wk.lam).max() > 1.0


def test_adaptive_and_implicit_steps_run_a_lean_scene_full(monkeypatch):
    """The lean kinds serve fixed explicit steps only: an implicit method and adaptive steps compile
    a lean scene full (the kinds the drop-in compiles anyway).  Switched after fixed steps
    (SetAdaptive, SetMethod), the state goes on, and so does a load written during the run
    (LoadRow, as the bridge's parameter changes write it): the same states to the bit as the scene
    compiled full from the start."""
    assert Simulator(lean_scene(), "ESDIRK3", "SE3", projectInitial=True).sd.rowsAll is True
    sim = Simulator(lean_scene(), "RK4", "SE3", projectInitial=True)
    sim.SetMethod("ESDIRK3")
    assert sim.sd.rowsAll is True
    out = {}
    for lean in (True, False):
        monkeypatch.setattr(compiled, "LEAN_SCENES", lean)
        sim = Simulator(lean_scene(), "DOPRI5", "SE3", projectInitial=True)
        assert (sim.sd.rowsAll is None) == lean
        sim.Advance(20, 1e-3)
        sim.LoadRow(0)[0][:] = [0.0, 4.0, -2.0]          # the load on body 2, changed during the run
        before = (sim.t, sim.R.copy(), sim.V.copy())
        sim.SetAdaptive(rtol=1e-8, atol=1e-8)
        assert sim.sd.rowsAll is True and sim.wk.path.rollingDiscs is not None
        assert sim.t == before[0] and np.array_equal(sim.R, before[1]) and np.array_equal(sim.V, before[2])
        assert np.array_equal(sim.LoadRow(0)[0], [0.0, 4.0, -2.0])
        sim.AdvanceTo(0.05)
        sim.SetMethod("ESDIRK3")
        sim.Advance(10, 1e-3)
        out[lean] = (sim.t, sim.R.copy(), sim.r.copy(), sim.V.copy())
    assert out[True][0] == pytest.approx(0.06)
    for x, y in zip(out[True], out[False]):
        assert np.array_equal(x, y)
    assert np.abs(out[True][3]).max() > 0.1


def _add_non_lean(sc, kind):
    if kind == "cartesian":
        sc.AddCartesianSpringDamper(1, [0.25, 0, 0], 2, [-0.25, 0, 0], stiffness=[10.0, 10.0, 10.0],
                                    damping=[0.1, 0.1, 0.1])
    elif kind == "torsional":
        sc.AddTorsionalSpringDamper(1, 2, stiffness=5.0, damping=0.1)
    elif kind == "coordinate row":
        sc.AddCoordinateConstraint(GROUND, 2, 0, 1, constant=0.0)


@pytest.mark.parametrize("kind", ["cartesian", "torsional", "coordinate row"])
def test_one_other_item_makes_a_scene_full(kind):
    sc = lean_scene()
    _add_non_lean(sc, kind)
    assert not compiled.scene_is_lean(sc)
    sd, _ = compiled.compile_scene(sc, ["SE3"] * sc.nBodies)
    assert sd.rowsAll is True
    assert all(sd._asdict()[f] is not None for f in force_elements.scene_fields())


def test_stabilization_makes_a_scene_full_with_the_switches_at_run_time(monkeypatch):
    """Stabilisation (like an offset function or probes) compiles the scene full, where it is a
    run-time switch as are the row drives and probes: the kernel kinds a first run compiles are one
    per method kind, not one per combination of features.  The full scene steps as the lean one
    (the projection of the velocity-stabilised run aside: same states without it, bit for bit)."""
    sc = lean_scene()
    assert compiled.scene_is_lean(sc) and not compiled.scene_is_lean(sc, "velocity")
    sim = Simulator(sc, "RK4", "SE3", stabilization="velocity", projectInitial=True)
    assert sim.sd.rowsAll is True and sim.sd.stabilization == kernel.STAB_VELOCITY
    assert sim.wk.drive is not None and sim.wk.drive[0] == 0 and sim.wk.probe.shape[0] == 0
    sim.Advance(100, 1e-3)
    assert np.abs(sim._residuals_and_JV()[1]).max() < 1e-12
    full = run(lean_scene(), False, "SE3", monkeypatch)
    assert full.sd.stabilization == kernel.STAB_NONE and full.wk.drive[0] == 0
    lean = run(lean_scene(), True, "SE3", monkeypatch)
    assert np.array_equal(full.V, lean.V) and np.abs(lean.V).max() > 0.1


def time_loop_ir(sim):
    """The LLVM IR of the module for linking of ``sim``'s fixed-step time loop (``mk_steps`` for its
    SceneData and Work types and a Method tuple), which numba keeps also for a kind loaded from
    the cache: what the loop compiles, read without a compile of its own."""
    import numba
    from exudyn_lie.mbs import stepper
    loop = [cres for sig, cres in stepper.mk_steps.overloads.items()
            if sig[:2] == (numba.typeof(sim.sd), numba.typeof(sim.wk))
            and sig[2].instance_class.__name__ == "Method"]
    assert len(loop) == 1
    return str(loop[0].library._get_module_for_linking())


def test_lean_stage_has_no_code_of_absent_features(monkeypatch):
    """The time loop (RK4) of a lean scene contains none of the functions of the features it
    lacks; compiled full, the same scene's time loop contains them.  (Read from the time loop's
    module for linking, which numba keeps also for a kind loaded from the cache.)"""
    absent = ["rolling_disc_row", "coordinate_row", "node_parameter", "cartesian_forces", "torsional_forces",
              "rigid_spring_forces", "rolling_disc_penalty_forces", "coordinate_spring_forces", "linear_spring_forces"]
    irs = {}
    for lean in (True, False):
        monkeypatch.setattr(compiled, "LEAN_SCENES", lean)
        sim = Simulator(lean_scene(), "RK4", "SE3", projectInitial=True)
        sim.Advance(1, 1e-3)
        irs[lean] = time_loop_ir(sim)
    for name in absent:
        assert name not in irs[True], name
        assert name in irs[False], name
    assert "spring_forces" in irs[True]


def test_projection_compiled_only_with_stabilization():
    """Fixed steps without stabilisation (``SceneData.stabilization`` None) compile no
    projection (the time loop has none of its code); with ``stabilization='velocity'`` it is
    compiled, and the steps are projected."""
    irs, drift = {}, {}
    for stab in (None, "velocity"):
        sim = Simulator(lean_scene(), "RK4", "SE3", stabilization=stab, projectInitial=True)
        assert (sim.sd.stabilization is None) == (stab is None)
        sim.Advance(300, 2e-3)
        drift[stab] = np.abs(sim._residuals_and_JV()[1]).max()
        irs[stab] = time_loop_ir(sim)
    assert "projection7project" not in irs[None]
    assert "projection7project" in irs["velocity"]
    assert drift["velocity"] < 1e-12 < drift[None]


def test_python_force_without_probes_has_no_probe_table():
    """A Python force that reads no compiled kinematics leaves ``Work.probe`` None (the
    external call then compiles without the probes' code) and adds its force as before: a
    constant Python force equals the same compiled load to round-off."""
    F = np.array([0.0, 0.0, 1.5])

    def push(t, state):
        out = np.zeros((3, 3))
        out[2] = F
        return out, np.zeros((3, 3))

    sims = {}
    for py in (False, True):
        sc = lean_scene()
        if py:
            sc.AddPythonForce(push, name="push")
        else:
            sc.AddForce(2, F)
        sim = Simulator(sc, "RK4", "SE3", projectInitial=True)
        if py:
            assert sim.wk.probe is None
        sim.Advance(200, 1e-3)
        sims[py] = sim
    np.testing.assert_allclose(sims[True].r, sims[False].r, rtol=0, atol=1e-13)
