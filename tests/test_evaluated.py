"""The Exudyn-evaluated path (bridge/evaluated*.py): Exudyn evaluates M, f, C_q and the
velocity-level constraints, exudyn_lie integrates with the same Munthe-Kaas stages.

Main test: on models the compiled kernel supports, ``evaluation='exudyn'`` computes the same
trajectory as the compiled path.  The two differ only by eta, which this path obtains by a
central difference of the velocity-level constraints with a relative error of about
eps^(2/3) ~ 4e-11 (bridge/evaluated.py); over a short horizon that stays far below 1e-8."""
import warnings

import numpy as np
import pytest

import exudyn as exu
from exudyn.utilities import (InertiaCuboid, LoadForceVector, MarkerNodeCoordinate, NodeGenericODE2,
                              ObjectGenericODE2, ObjectGround, SensorObject)

import exudyn_lie as exl
from exudyn_lie import models
from exudyn_lie.errors import StepSizeError
from exudyn_lie.bridge.reader import BridgeError

from test_bridge_common import new_mbs, quiet_settings

TOL = 1e-8


def _final_state(mbs):
    """(configuration, velocities) in mbs: the ODE2 coordinates, with the rotation vector of
    every RotVecLG node replaced by its rotation matrix (a rotation vector near |pi| may be
    written on either branch: each path keeps it continuous from its own last output)."""
    sd = mbs.systemData
    q = np.array(sd.GetODE2Coordinates())
    parts, lg = [], np.zeros(len(q), bool)
    for n in range(sd.NumberOfNodes()):
        if mbs.GetNode(n)["nodeType"] == "RigidBodyRotVecLG":
            lg[np.asarray(sd.GetNodeLTGODE2(n))[3:]] = True
            parts.append(np.asarray(mbs.GetNodeOutput(n, exu.OutputVariableType.RotationMatrix)).ravel())
    return np.concatenate([q[~lg]] + parts), np.array(sd.GetODE2Coordinates_t())


def _rel(a, b):
    return float(np.max(np.abs(a - b)) / max(1.0, np.max(np.abs(b))))


def _both_paths(build, T, h, **kw):
    out = {}
    for ev in ("compiled", "exudyn"):
        mbs = build()
        ss = quiet_settings(T, int(round(T / h)))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            exl.SolveDynamic(mbs, ss, evaluation=ev, showProgress=False, **kw)
        out[ev] = _final_state(mbs)
    return out


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_heavy_top_same_trajectory_as_compiled(group):
    out = _both_paths(lambda: models.build("heavy_top", mbs=new_mbs())[0], 0.1, 1e-3, liegroup=group)
    (q0, v0), (q1, v1) = out["compiled"], out["exudyn"]
    assert _rel(q1, q0) < TOL and _rel(v1, v0) < TOL


def _pendulum_with_generic_ode2(mbs=None):
    mbs = new_mbs() if mbs is None else mbs
    g = mbs.AddObject(ObjectGround())
    b = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.2, 0.1, 0.05]), referencePosition=[0.5, 0, 0],
                            initialAngularVelocity=[0, 0, 2], initialVelocity=[0, 1, 0], gravity=[0, -9.81, 0],
                            nodeType=exu.NodeType.RotationRotationVector)
    mbs.CreateSphericalJoint(itemNumbers=[g, b], position=[0, 0, 0])
    n = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0, 0], initialCoordinates=[0.1, 0],
                                    initialCoordinates_t=[0, 0], numberOfODE2Coordinates=2))
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[n], massMatrix=np.diag([1.0, 2.0]),
                                    stiffnessMatrix=np.array([[100.0, -20], [-20, 50]])))
    mbs.Assemble()
    return mbs


def test_generic_ode2_with_joint_runs_automatically_and_matches_native():
    """A model with an item the kernel lacks takes the path by itself, with one warning
    naming the item; the trajectory agrees with a fine native generalized-alpha run."""
    T = 0.5
    mbs = _pendulum_with_generic_ode2()
    ss = quiet_settings(T, 500)
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        exl.SolveDynamic(mbs, ss, showProgress=False)
    msgs = [str(x.message) for x in w if "exudyn_lie" in str(x.message)]
    assert len(msgs) == 1 and "ObjectGenericODE2" in msgs[0] and "us per step" in msgs[0]
    q = _final_state(mbs)[0]
    ref = _pendulum_with_generic_ode2()
    ssn = quiet_settings(T, 50000)
    ssn.timeIntegration.generalizedAlpha.spectralRadius = 1.0
    ssn.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    ref.SolveDynamic(ssn)
    qn = _final_state(ref)[0]
    # RK4 at h = 1e-3 against the fine reference (its own error ~1e-10)
    assert _rel(q, qn) < 1e-7


def test_compiled_refuses_foreign_item():
    mbs = _pendulum_with_generic_ode2()
    with pytest.raises(BridgeError, match="GenericODE2"):
        exl.SolveDynamic(mbs, quiet_settings(0.01, 10), evaluation="compiled")


def test_bad_evaluation_keyword():
    mbs = _pendulum_with_generic_ode2()
    with pytest.raises(BridgeError, match="evaluation"):
        exl.SolveDynamic(mbs, quiet_settings(0.01, 10), evaluation="python")


def test_stiff_generic_ode2_beyond_stability_limit_raises_step_size_error():
    mbs = new_mbs()
    n = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0], initialCoordinates=[0.01],
                                    initialCoordinates_t=[0.0], numberOfODE2Coordinates=1))
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[n], massMatrix=np.eye(1), stiffnessMatrix=np.array([[1e8]])))
    mbs.Assemble()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(StepSizeError, match="stability limit") as e:
            exl.SolveDynamic(mbs, quiet_settings(0.1, 100), showProgress=False)
    # omega = 1e4 rad/s; RK4's imaginary-axis limit 2 sqrt(2): stable below 2.83e-4 s; the
    # suggested step (0.9 of it) runs, bounded
    sugg = float(str(e.value).rsplit("step size of ", 1)[1].split(" s")[0])
    assert 0.8 * 2 * np.sqrt(2) / 1e4 < sugg < 2 * np.sqrt(2) / 1e4
    mbs.systemData.SetODE2Coordinates([0.01], configuration=exu.ConfigurationType.Initial)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, quiet_settings(0.01, int(np.ceil(0.01 / sugg))), showProgress=False)
    assert abs(_final_state(mbs)[0][0]) <= 0.0101


# ---------------------------------------------------------------------------- cross-validation
def _paper(name):
    return lambda: models.build(name, mbs=new_mbs())[0]


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("name", models.MODELS)
def test_paper_models_same_trajectory_as_compiled(name, group):
    """Every paper mechanism, both groups, MK-RK4 at h = 1e-3 for 50 steps (measured: at
    most 1.4e-10 relative after 100 steps, rp_mechanism)."""
    out = _both_paths(_paper(name), 0.05, 1e-3, liegroup=group)
    (q0, v0), (q1, v1) = out["compiled"], out["exudyn"]
    assert _rel(q1, q0) < TOL and _rel(v1, v0) < TOL


@pytest.mark.parametrize("seed", range(6))
def test_random_mechanisms_same_trajectory_as_compiled(seed):
    """Random chains / trees of all joint types with a spring; their random initial twists
    are projected onto the constraints by both paths (the mass-orthogonal projection is
    the same in both velocity coordinates)."""
    from exudyn_lie.apps.stress_models import exudyn_from_spec, random_mechanism
    spec = random_mechanism(seed, max_bodies=5)
    for group in ("SE3", "SO3xR3"):
        out = _both_paths(lambda: exudyn_from_spec(spec)[0], 0.05, 1e-3, liegroup=group)
        (q0, v0), (q1, v1) = out["compiled"], out["exudyn"]
        assert _rel(q1, q0) < TOL and _rel(v1, v0) < TOL, (spec.describe(), group)


def _evaluated_model(mbs):
    """An EvaluatedModel and stepper of an assembled mbs (Exudyn's solver initialised)."""
    from exudyn_lie.bridge.evaluated import EvaluatedModel, Layout
    from exudyn_lie.bridge.evaluated_stepper import EvaluatedStepper
    solver = exu.MainSolverImplicitSecondOrder()
    solver.InitializeSolver(mbs, quiet_settings())
    sd, cur = mbs.systemData, exu.ConfigurationType.Current
    q = sd.GetODE2Coordinates(configuration=cur, copy=False)
    qt = sd.GetODE2Coordinates_t(configuration=cur, copy=False)
    layout = Layout(mbs, {})
    model = EvaluatedModel(mbs, solver, layout, q, qt)
    st = EvaluatedStepper(model, exl.get_method("RK4"))
    return solver, model, st


@pytest.mark.parametrize("seed", range(4))
def test_eta_by_differentiation_matches_compiled_eta(seed):
    """At a random state (not on the constraints: eta is a function of any state) Exudyn's
    eta by the central difference equals the compiled kernel's eta in Exudyn's coordinates:
    eta_exu = eta_pkg + C Pdot V (q_t = P V, so C a = J Vdot + C Pdot V); Richardson's
    estimate bounds the difference."""
    from test_bridge_common import package, random_state
    from exudyn_lie.apps.stress_models import exudyn_from_spec, random_mechanism
    rng = np.random.default_rng(seed)
    mbs = exudyn_from_spec(random_mechanism(seed + 3, max_bodies=4))[0]
    q, qt = random_state(mbs, rng, scale=0.3)
    groups = ["SE3"] * len([n for n in range(mbs.systemData.NumberOfNodes())
                            if mbs.GetNode(n)["nodeType"] == "RigidBodyRotVecLG"])
    pk = package(mbs, groups, q, qt)
    solver, model, st = _evaluated_model(mbs)
    model.q[:] = q
    model.qt[:] = qt
    st.read_state(model.q, model.qt)
    eta, err = model.eta_error(0.0, st.R, st.r, st.prev, st.qv)
    _, _, Cq = model.mass_force_jacobian(0.0)
    Cq = np.array(Cq)
    sim, sc = pk["sim"], pk["scene"]
    h, J, eta_pkg = sim.jacobian()
    worst = 0.0
    scale = max(1.0, float(np.max(np.abs(eta))))
    for ji in sc.joints_info:
        r0, n = (int(x) for x in sim.sd.jint[ji.sceneJoint, 2:4])
        expect = eta_pkg[r0:r0 + n] + Cq[ji.aeRows] @ pk["PdV"]
        d = np.abs(eta[ji.aeRows] - expect)
        assert np.all(d <= 1e-9 * scale), (d, err[ji.aeRows])
        assert np.all(d <= 10 * err[ji.aeRows] + 1e-12 * scale)     # the estimate is not too optimistic
        worst = max(worst, float(np.max(d)) / scale)
    solver.FinalizeSolver(mbs, quiet_settings())
    assert worst < 1e-9
