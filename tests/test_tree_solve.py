"""The tree solve of the index-1 system (mbs/tree_solve.py): its plan, the automatic choice
against the band Cholesky, and its results against the band solve of the same rows and
against the index-1 system itself (``J Vdot = eta``, ``Vdot = M^-1 (Q - J^T lambda)``)."""
import warnings

import numpy as np
import pytest

from exudyn_lie.apps import bench_topology as BT
from exudyn_lie.apps.stress_models import planar_fourbar, random_mechanism, scene_from_spec
from exudyn_lie.mbs import GROUND, Scene, Simulator
from exudyn_lie.mbs.compiled import TREE_MIN_BANDWIDTH, make_work
from exudyn_lie.mbs.diagnostics import constraint_jacobian
from exudyn_lie.mbs.tree_solve import P_ORDER, tree_plan
from exudyn_lie.mbs.codes import BODY_TWIST


def _sim(scene, group="SE3", solve=None, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = Simulator(scene, "RK4", group, projectInitial=True, **kw)
    if solve is not None:
        sim.wk = sim._make_work(solve)
    return sim


def _uses_tree(sim):
    return sim.wk.tplan is not None


def _pair(scene_fn, group="SE3", **kw):
    """The same scene served by the tree and by the band solve, from the same initial state."""
    a = _sim(scene_fn(), group, "tree", **kw)
    b = _sim(scene_fn(), group, "band", **kw)
    b.R[:], b.r[:], b.V[:] = a.R, a.r, a.V
    return a, b


def _state_diff(a, b):
    scale = max(1.0, np.abs(b.r).max(), np.abs(b.V).max())
    return max(np.abs(a.R - b.R).max(), np.abs(a.r - b.r).max() / scale, np.abs(a.V - b.V).max() / scale)


# --------------------------------------------------------------------------- plan and choice
def test_plan_of_tree_families_and_none_for_loops():
    for kind in ("chain", "star", "tree"):
        sd = _sim(BT.build_scene(kind, 12)).sd
        plan = tree_plan(sd.nb, sd.rowIndex)
        assert plan is not None, kind
        order = plan[:sd.nb, P_ORDER]
        assert sorted(order) == list(range(sd.nb))
        assert order[-1] == 0, "the grounded bar is the root, eliminated last"
    sd = _sim(BT.build_scene("ladder", 12)).sd
    assert tree_plan(sd.nb, sd.rowIndex) is None                 # rungs close loops
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sd = Simulator(planar_fourbar(joint4="universal-spherical"), "RK4", "SE3").sd
    assert tree_plan(sd.nb, sd.rowIndex) is None                 # a loop through the ground


def test_automatic_choice_by_bandwidth():
    assert _uses_tree(_sim(BT.build_scene("star", 24)))
    assert _uses_tree(_sim(BT.build_scene("tree", 24)))
    chain = _sim(BT.build_scene("chain", 24))
    assert not _uses_tree(chain) and chain.sd.bandwidth < TREE_MIN_BANDWIDTH
    assert not _uses_tree(_sim(BT.build_scene("ladder", 24)))
    with pytest.raises(Exception, match="loop"):
        make_work(_sim(BT.build_scene("ladder", 8)).sd, 4, "tree")


# --------------------------------------------------------------------------- against the band solve
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("kind", ["chain", "star", "tree"])
def test_trajectories_equal_band_solve(kind, group):
    a, b = _pair(lambda: BT.build_scene(kind, 24), group)
    a.Advance(300, 1e-3)
    b.Advance(300, 1e-3)
    assert _state_diff(a, b) < 1e-12


@pytest.mark.parametrize("stabilization", ["velocity", "position"])
def test_projections_equal_band_solve(stabilization):
    a, b = _pair(lambda: BT.build_scene("tree", 20), "SE3", stabilization=stabilization)
    a.Advance(200, 2e-3)
    b.Advance(200, 2e-3)
    assert _state_diff(a, b) < 1e-12


def _index1_residuals(sim, group="SE3"):
    """(|J Vdot - eta|, |Vdot - Vdot_ref|), relative, at the state of ``sim``: the index-1
    system checked directly; ``Vdot_ref = Vdot_free - A J^T lambda_ref`` with
    ``Vdot_free = M^-1 Q`` from the scene without joints and ``lambda_ref`` from numpy's
    dense least-squares solve of ``(J A J^T) lambda = J Vdot_free - eta``."""
    Vd, lam = sim.Accelerations()
    _, J, eta = constraint_jacobian(sim.sd, sim.wk, sim.R, sim.r, sim.V)
    free_scene = sim.scene
    joints, free_scene.joints = free_scene.joints, []
    try:
        free = Simulator(free_scene, "RK4", group)
    finally:
        free_scene.joints = joints
    free.R[:], free.r[:], free.V[:] = sim.R, sim.r, sim.V
    Vfree, _ = free.Accelerations()
    A = np.zeros((6 * sim.sd.nb, 6 * sim.sd.nb))
    for i in range(sim.sd.nb):
        D = np.eye(6)
        if not BODY_TWIST[sim.sd.gid[i]]:
            D[3:, 3:] = sim.R[i]
        A[6 * i:6 * i + 6, 6 * i:6 * i + 6] = D @ sim.sd.Minv[i] @ D.T
    lam_ref = np.linalg.lstsq(J @ A @ J.T, J @ Vfree.ravel() - eta, rcond=None)[0]
    pred = Vfree.ravel() - A @ (J.T @ lam_ref)
    scale = max(1.0, np.abs(Vd).max())
    return (np.abs(J @ Vd.ravel() - eta).max() / max(1.0, np.abs(eta).max(), np.abs(J).max() * scale),
            np.abs(Vd.ravel() - pred).max() / scale)


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_random_mechanisms_equal_band_solve_and_satisfy_index1(group):
    done, worst = 0, 0.0
    for seed in range(40):
        spec = random_mechanism(seed, max_bodies=9)
        if len(spec.bodies) < 3:
            continue
        a, b = _pair(lambda: scene_from_spec(spec), group)
        assert _uses_tree(a) and not _uses_tree(b)
        a.Advance(50, 1e-3)
        b.Advance(50, 1e-3)
        assert _state_diff(a, b) < 1e-11, spec.describe()
        Va, la = a.Accelerations()
        Vb, lb = b.Accelerations()
        assert np.abs(Va - Vb).max() <= 1e-12 * max(1.0, np.abs(Vb).max()), spec.describe()
        assert np.abs(la - lb).max() <= 1e-11 * max(1.0, np.abs(lb).max()), spec.describe()
        # the residuals of the index-1 system: at round-off, and not above the band solve's
        # (the joints' Jacobians of some random mechanisms are ill-conditioned: both reach ~1e-12)
        rJ, rV = _index1_residuals(a, group)
        rJb, rVb = _index1_residuals(b, group)
        assert rJ < 1e-12 and rV < 1e-10, (spec.describe(), rJ, rV)
        assert rJ <= 10 * rJb + 1e-14 and rV <= 10 * rVb + 1e-13, (spec.describe(), rJ, rJb, rV, rVb)
        worst = max(worst, rV / max(rVb, 1e-16))
        done += 1
    assert done >= 20
    print(f"{done} mechanisms, worst residual ratio tree / band {worst:.3g}")


def test_point_masses_and_planar_bodies_on_a_star():
    """Singular ``M^-1`` (point masses: no rotation; 2D bodies: off-plane zero) in the tree:
    2D bodies pinned in the plane (x, y locked: Exudyn's 2D revolute joint), point masses on
    rods (distance constraints) to a 2D hub."""
    pin = (1, 1, 0, 0, 0, 0)

    def scene():
        sc = Scene(gravity=[0, -9.81, 0])
        hub = sc.AddBody2D(2.0, 0.1, position=(0, 0), angle=0.1, omega=0.3)
        sc.AddJoint(GROUND, hub, pin)
        for k in range(6):
            ang = 2 * np.pi * k / 6
            p = 0.4 * np.array([np.cos(ang), np.sin(ang), 0.0])
            R = np.array([[np.cos(0.1), -np.sin(0.1), 0], [np.sin(0.1), np.cos(0.1), 0], [0, 0, 1]])
            if k % 2:
                b = sc.AddBody2D(0.5, 0.02, position=tuple(R @ (2 * p))[:2], angle=ang)
                sc.AddJoint(hub, b, pin, posA=p, posB=-p)
            else:
                b = sc.AddPointMass(0.3, r0=R @ (2 * p), vel0=(0.0, 0.1, 0.0))
                sc.AddDistanceConstraint(hub, p, b, (0, 0, 0), float(np.linalg.norm(p)))
        return sc
    a, b = _pair(scene)
    a.Advance(200, 1e-3)
    b.Advance(200, 1e-3)
    assert _state_diff(a, b) < 1e-12
    rJ, rV = _index1_residuals(a)
    assert rJ < 1e-13 and rV < 1e-12


def test_redundant_rows_on_a_tree_switch_to_the_pivoted_solve():
    sc = BT.build_scene("star", 20)
    sc.AddSphericalJoint(GROUND, 0, position=(0, 0, 0), name="duplicate")
    with pytest.warns(RuntimeWarning, match="redundant"):
        sim = Simulator(sc, "RK4", "SE3", projectInitial=True)
    assert sim.sd.redundant and not _uses_tree(sim)
    sim.Advance(100, 1e-3)
    rJ, rV = _index1_residuals(sim)
    assert rJ < 1e-12 and rV < 1e-11
