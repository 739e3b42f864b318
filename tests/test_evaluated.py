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
from exudyn.utilities import (InertiaCuboid, LoadForceVector, MarkerBodyPosition, MarkerNodeCoordinate, NodeGenericODE2,
                              ObjectGenericODE2, ObjectGround, SensorObject)

import exudyn_lie as exl
from exudyn_lie import models
from exudyn_lie.groups import so3
from exudyn_lie.errors import StepSizeError
from exudyn_lie.bridge.reader import BridgeError

from test_bridge_common import new_mbs, quiet_settings

TOL = 1e-8


def _final_state(mbs):
    """(configuration, velocities) in mbs: the ODE2 coordinates, with the rotation vector of
    every RotVecLG node replaced by its rotation matrix (the branch of the rotation vector: its
    own test below)."""
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
    """The final state on both paths; the unstabilised method on both (stabilization=None: the
    two integrations themselves compared, not two projections)."""
    kw.setdefault("stabilization", None)
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


def test_rotvec_quat_inverts_quat_rotvec(rng):
    """The quaternion of a rotation vector (the evaluated path's continuity rule) and back, at
    |p| from 1e-9 to 2 pi - 1e-3, both branches of the series; a unit quaternion; the series and
    the closed form agree at their switch."""
    from exudyn_lie.mbs.rotation_parameters import quat_rotvec, rotvec_quat
    q, back = np.empty(4), np.empty(3)
    for t in (1e-9, 1e-5, 0.99e-4, 1.01e-4, 0.3, 3.0, np.pi, 4.0, 2 * np.pi - 1e-3):
        x = rng.normal(size=3)
        p = t * x / np.linalg.norm(x)
        rotvec_quat(p, q)
        quat_rotvec(q, back)
        assert abs(q @ q - 1.0) < 1e-15 and np.abs(back - p).max() < 4e-15 * max(1.0, t), (t, back - p)
    a, b = np.empty(4), np.empty(4)
    ta, tb = 1e-4 * (1 - 1e-12), 1e-4 * (1 + 1e-12)
    rotvec_quat(np.array([0.0, 0.0, ta]), a)
    rotvec_quat(np.array([0.0, 0.0, tb]), b)
    assert abs(a[3] / ta - b[3] / tb) < 1e-15          # sin(t/2) / t: series and closed form


def test_rotation_vector_continuity_through_the_turnover_equals_the_compiled_paths():
    """Rotations about a tilted axis through 2 pi, one write within the turnover window (where
    rotvec_row writes the short vector of the same rotation): the evaluated path's rule
    (``_rotvec_continuous``, the last quaternion kept) writes the compiled path's vectors
    (``rotvec_row`` with its quaternion) at every angle; continuing from the written rotation vector
    instead left the long branch after the turnover."""
    from exudyn_lie.bridge.evaluated_kernels import _rotvec_continuous
    from exudyn_lie.bridge.node_writers import rotvec_row
    n = np.array([0.3, -0.4, 0.866])
    n /= np.linalg.norm(n)
    qe, qc = np.array([1.0, 0, 0, 0]), np.array([1.0, 0, 0, 0])
    pe, pc, qnew, z = np.zeros(3), np.zeros(3), np.zeros(4), np.zeros(3)
    for theta in (0.5, 2.0, 3.5, 5.0, 6.2, 2 * np.pi - 5e-9, 2 * np.pi + 0.3, 2 * np.pi + 1.0, 9.0):
        R = so3.exp(theta * n)
        _rotvec_continuous(R, qe, pe, qnew)
        qe[:] = qnew
        rotvec_row(R, z, z, qc, False, pc, z.copy(), z.copy(), np.zeros(4))
        assert np.abs(pe - pc).max() < 1e-12, (theta, pe, pc)
        assert np.abs(so3.exp(pe) - R).max() < 1e-12


def test_rotation_vector_is_written_on_the_compiled_paths_branch_beyond_pi():
    """A free RotVecLG body spinning at about 6 rad/s for 1.2 s (|theta| passes pi and the turnover
    at 2 pi): the evaluated path writes the rotation vector coordinates the compiled path writes
    (Exudyn's branch: the sign-continuous quaternion, bridge/node_writers.rotvec_row), not only the
    same rotation.  Before, its continuity rule read the previous rotation vector as a quaternion
    (one entry beyond the array) and wrote another branch (5.2 rad apart in a held-rate model,
    tests/test_rotation_coordinate_marker.py)."""
    def build():
        mbs = new_mbs()
        mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.3, 0.1, 0.2]), referencePosition=[0, 0, 0],
                            referenceRotationMatrix=np.eye(3), initialAngularVelocity=[3.0, -2.0, 5.0],
                            nodeType=exu.NodeType.RotationRotationVector)
        mbs.Assemble()
        return mbs
    out = {}
    for ev in ("compiled", "exudyn"):
        mbs = build()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            exl.SolveDynamic(mbs, quiet_settings(1.2, 1200), evaluation=ev, method="RK4", showProgress=False)
        out[ev] = np.array(mbs.systemData.GetODE2Coordinates())
    theta = np.linalg.norm(out["compiled"][3:6])
    assert np.pi < theta < 2 * np.pi - 0.1, theta        # on the long branch at the end
    assert np.abs(out["exudyn"] - out["compiled"]).max() < 1e-9, (out["exudyn"], out["compiled"])


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


def _fine_native_pendulum(T):
    """The final configuration of :func:`_pendulum_with_generic_ode2` by native generalized-alpha
    (no damping) at 50,000 steps: the fine reference."""
    ref = _pendulum_with_generic_ode2()
    ssn = quiet_settings(T, 50000)
    ssn.timeIntegration.generalizedAlpha.spectralRadius = 1.0
    ssn.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    ref.SolveDynamic(ssn)
    return _final_state(ref)[0]


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
    qn = _fine_native_pendulum(T)
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


def _stiff_generic_ode2():
    """One GenericODE2 coordinate on a spring of 1e8 (omega = 1e4 rad/s), released from 0.01."""
    mbs = new_mbs()
    n = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0], initialCoordinates=[0.01],
                                    initialCoordinates_t=[0.0], numberOfODE2Coordinates=1))
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[n], massMatrix=np.eye(1), stiffnessMatrix=np.array([[1e8]])))
    mbs.Assemble()
    return mbs


def test_stiff_generic_ode2_beyond_stability_limit_raises_step_size_error():
    mbs = _stiff_generic_ode2()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(StepSizeError, match="stability limit") as e:
            exl.SolveDynamic(mbs, quiet_settings(0.1, 100), showProgress=False, method="RK4")
    # omega = 1e4 rad/s; RK4's imaginary-axis limit 2 sqrt(2): stable up to 2.83e-4 s; the
    # suggested step (0.9 of it) runs, bounded
    assert "stable up to h = 0.000283 s" in str(e.value)
    sugg = float(str(e.value).rsplit("step size of ", 1)[1].split(" s")[0])
    assert sugg == pytest.approx(0.9 * 2 * np.sqrt(2) / 1e4, rel=5e-3)      # printed with 3 digits
    mbs.systemData.SetODE2Coordinates([0.01], configuration=exu.ConfigurationType.Initial)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, quiet_settings(0.01, int(np.ceil(0.01 / sugg))), showProgress=False)
    assert abs(_final_state(mbs)[0][0]) <= 0.0101


def test_stiff_generic_ode2_without_a_method_runs_implicitly(capsys):
    """No method named: the check at the start finds RK4 unstable at the script's step and the run
    takes ESDIRK3 (one line says so); L-stable, it stays bounded."""
    mbs = _stiff_generic_ode2()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, quiet_settings(0.1, 100), showProgress=False)
    assert "RK4 is not stable at the step h = 0.001 s" in capsys.readouterr().out
    assert abs(_final_state(mbs)[0][0]) <= 0.01


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
    """An EvaluatedModel and its problem of an assembled mbs (Exudyn's solver initialised)."""
    from exudyn_lie.bridge.evaluated import EvaluatedModel, Layout
    from exudyn_lie.bridge.evaluated_problem import EvaluatedProblem
    solver = exu.MainSolverImplicitSecondOrder()
    solver.InitializeSolver(mbs, quiet_settings())
    sd, cur = mbs.systemData, exu.ConfigurationType.Current
    q = sd.GetODE2Coordinates(configuration=cur, copy=False)
    qt = sd.GetODE2Coordinates_t(configuration=cur, copy=False)
    layout = Layout(mbs, {})
    model = EvaluatedModel(mbs, solver, layout, q, qt)
    st = EvaluatedProblem(model, exl.get_method("RK4"))
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
        r0, n = (int(x) for x in sim.sd.jointIndex[ji.sceneJoint, 2:4])
        expect = eta_pkg[r0:r0 + n] + Cq[ji.aeRows] @ pk["PdV"]
        d = np.abs(eta[ji.aeRows] - expect)
        assert np.all(d <= 1e-9 * scale), (d, err[ji.aeRows])
        assert np.all(d <= 10 * err[ji.aeRows] + 1e-12 * scale)     # the estimate is not too optimistic
        worst = max(worst, float(np.max(d)) / scale)
    solver.FinalizeSolver(mbs, quiet_settings())
    assert worst < 1e-9


# ---------------------------------------------------------------------------- Exudyn evaluates everything
def _pendulum_with_load_user_function(mbs=None):
    mbs = new_mbs() if mbs is None else mbs
    g = mbs.AddObject(ObjectGround())
    b = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.2, 0.1, 0.05]), referencePosition=[0.5, 0, 0],
                            gravity=[0, -9.81, 0], nodeType=exu.NodeType.RotationRotationVector)
    mbs.CreateSphericalJoint(itemNumbers=[g, b], position=[0, 0, 0])
    m = mbs.AddMarker(MarkerBodyPosition(bodyNumber=b, localPosition=[0.1, 0, 0]))
    mbs.AddLoad(LoadForceVector(markerNumber=m, loadVector=[0, 0, 0],
                                loadVectorUserFunction=lambda mbs, t, lv: [0, 0, 50 * np.sin(20 * t)]))
    mbs.Assemble()
    return mbs


def test_user_functions_see_the_stage_time():
    """A time-dependent load user function evaluated by Exudyn at every stage: the same
    trajectory as the compiled path, which calls the user function itself at the stage
    times (measured 1.9e-11 after 0.5 s; with the step's start time instead the trajectories
    would differ at first order in h)."""
    out = _both_paths(_pendulum_with_load_user_function, 0.2, 1e-3)
    (q0, v0), (q1, v1) = out["compiled"], out["exudyn"]
    assert _rel(q1, q0) < TOL and _rel(v1, v0) < TOL


def _cable_with_mass_point(mbs=None, ne=4):
    """An ANCF cable (ObjectANCFCable2D) pinned at one end by coordinate constraints, with a
    MassPoint2D hanging from the other end on a revolute joint, under gravity."""
    from exudyn.utilities import (CoordinateConstraint, LoadMassProportional, MarkerBodyMass, MarkerNodePosition,
                                  NodePoint2D, NodePoint2DSlope1, NodePointGround, ObjectANCFCable2D,
                                  ObjectMassPoint2D, RevoluteJoint2D)
    mbs = new_mbs() if mbs is None else mbs
    L = 1.0
    nodes = [mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=[i * L / ne, 0, 1, 0])) for i in range(ne + 1)]
    cables = [mbs.AddObject(ObjectANCFCable2D(nodeNumbers=[nodes[i], nodes[i + 1]], length=L / ne,
                                              massPerLength=1.0, bendingStiffness=0.5,
                                              axialStiffness=1e4)) for i in range(ne)]
    nG = mbs.AddNode(NodePointGround())
    for c in (0, 1):
        mbs.AddObject(CoordinateConstraint(markerNumbers=[
            mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nG, coordinate=c)),
            mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=c))]))
    nm = mbs.AddNode(NodePoint2D(referenceCoordinates=[L, 0]))
    mbs.AddObject(ObjectMassPoint2D(mass=0.5, nodeNumber=nm))
    mbs.AddObject(RevoluteJoint2D(markerNumbers=[mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[-1])),
                                                 mbs.AddMarker(MarkerNodePosition(nodeNumber=nm))]))
    for c in cables:
        mbs.AddLoad(LoadMassProportional(markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=c)),
                                         loadVector=[0, -9.81, 0]))
    mbs.AddLoad(LoadForceVector(markerNumber=mbs.AddMarker(MarkerNodePosition(nodeNumber=nm)),
                                loadVector=[0, -0.5 * 9.81, 0]))
    mbs.Assemble()
    return mbs, nm


def test_ancf_cable_with_mass_point_runs_automatically_and_matches_native():
    """MK-RK4 at h = 1e-3 against native generalized-alpha at h = 1e-6 (its error ~1e-12):
    measured 5.2e-9 m at the mass point after 0.1 s."""
    T = 0.1
    mbs, nm = _cable_with_mass_point()
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        exl.SolveDynamic(mbs, quiet_settings(T, 100), showProgress=False)
    msgs = [str(x.message) for x in w if "Exudyn evaluates" in str(x.message)]
    assert len(msgs) == 1 and "ObjectANCFCable2D" in msgs[0]
    ref, nr = _cable_with_mass_point()
    ss = quiet_settings(T, 100000)
    ss.timeIntegration.generalizedAlpha.spectralRadius = 1.0
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    ref.SolveDynamic(ss)
    p = np.array(mbs.GetNodeOutput(nm, exu.OutputVariableType.Position))
    pr = np.array(ref.GetNodeOutput(nr, exu.OutputVariableType.Position))
    assert np.max(np.abs(p - pr)) < 2e-8


def _ball_on_sphere(mbs=None, impactModel=0):
    """A rigid ball (RotVecLG) thrown onto a fixed sphere: ObjectContactSphereSphere with its
    data node (gap, tangential velocity, impact velocity, plastic deformation)."""
    from exudyn.utilities import InertiaSphere, MarkerBodyRigid, MarkerNodeRigid, NodeGenericData, \
        NodePointGround, ObjectContactSphereSphere
    mbs = new_mbs() if mbs is None else mbs
    radius, mass = 0.1, 1.6
    nG = mbs.AddNode(NodePointGround(referenceCoordinates=[0, -2 * radius, 0]))
    b = mbs.CreateRigidBody(referencePosition=[0, 0.05, 0], initialVelocity=[0.3, -2, 0],
                            initialAngularVelocity=[0, 0, 1], inertia=InertiaSphere(mass, radius),
                            gravity=[0, -9.81, 0], nodeType=exu.NodeType.RotationRotationVector)
    nD = mbs.AddNode(NodeGenericData(initialCoordinates=[0.1, 0, 0, 0], numberOfDataCoordinates=4))
    mbs.AddObject(ObjectContactSphereSphere(markerNumbers=[mbs.AddMarker(MarkerNodeRigid(nodeNumber=nG)),
                                                           mbs.AddMarker(MarkerBodyRigid(bodyNumber=b))],
                                            nodeNumber=nD, spheresRadii=[radius, radius], contactStiffness=1e5,
                                            contactDamping=20, impactModel=impactModel, restitutionCoefficient=0.7))
    mbs.Assemble()
    return mbs, b


@pytest.mark.parametrize("impactModel, tol", [(0, 2e-4), (2, 2e-3)])
def test_contact_with_data_coordinates_matches_native(impactModel, tol):
    """One MK step per Exudyn step so that PostNewton updates the contact's data coordinates
    after every step (and Exudyn's discontinuous iteration repeats the impact step: the
    hook restarts it from its saved start state).  The contact force has a kink at the
    impact and the impact velocity is taken at the end of the impact step: first order in
    h near the impact, for Exudyn's own solvers too.  Measured at h = 1e-4 against native
    generalized-alpha at h = 1e-6: 6.9e-5 (impactModel 0), 6.9e-4 (2; Exudyn's RK44 7e-5)."""
    T = 0.2
    mbs, b = _ball_on_sphere(impactModel=impactModel)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, quiet_settings(T, 2000), showProgress=False, liegroup="SO3xR3")
    ref, br = _ball_on_sphere(impactModel=impactModel)
    ss = quiet_settings(T, 200000)
    ss.timeIntegration.generalizedAlpha.spectralRadius = 1.0
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    ref.SolveDynamic(ss)
    O = exu.OutputVariableType
    x = np.r_[mbs.GetObjectOutputBody(b, O.Position, localPosition=[0, 0, 0]),
              mbs.GetObjectOutputBody(b, O.Velocity, localPosition=[0, 0, 0])]
    xr = np.r_[ref.GetObjectOutputBody(br, O.Position, localPosition=[0, 0, 0]),
               ref.GetObjectOutputBody(br, O.Velocity, localPosition=[0, 0, 0])]
    assert xr[4] > 0 or impactModel == 2          # the ball bounced (velocity up after the impact)
    assert np.max(np.abs(x - xr)) < tol


def test_sensors_record_the_same_as_on_the_compiled_path():
    """Exudyn's sensors (position, joint force = the multipliers, acceleration) at every
    output, from t = 0, as on the compiled path (measured: 1e-12, 3e-12 and 5e-12 relative)."""
    from exudyn.utilities import SensorBody
    from exudyn_lie.models import heavy_top as HT
    O = exu.OutputVariableType
    out = {}
    for ev in ("compiled", "exudyn"):
        mbs, info = HT.build(mbs=new_mbs())
        b, j = info.bodies[0].objectIndex, info.joints[0].objectIndex
        sensors = [mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Position)),
                   mbs.AddSensor(SensorObject(objectNumber=j, storeInternal=True, outputVariableType=O.Force)),
                   mbs.AddSensor(SensorBody(bodyNumber=b, storeInternal=True, outputVariableType=O.Acceleration))]
        mbs.Assemble()
        ss = quiet_settings(0.1, 100)
        ss.solution.sensors.active = True
        ss.solution.sensors.writePeriod = 0.01
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            exl.SolveDynamic(mbs, ss, evaluation=ev, showProgress=False)
        out[ev] = [np.array(mbs.GetSensorStoredData(s)) for s in sensors]
    for a, c in zip(out["exudyn"], out["compiled"]):
        assert a.shape == c.shape == (11, 4)
        np.testing.assert_array_equal(a[:, 0], c[:, 0])
        assert np.max(np.abs(a - c)) <= 1e-10 * np.max(np.abs(c))


def test_stiffness_that_appears_during_the_run_raises_step_size_error():
    """A contact 10^7 times stiffer than in the test above closes during the run: no stiffness
    at the start (the ball flies freely), then omega = sqrt(k/m) = 7.9e5 rad/s at h = 1e-4
    (h omega = 79).  The estimate from the stages stops the run instead of letting the ball
    leave at 5e6 m/s, with a step near the stability limit 2.8 / 7.9e5 = 3.5e-6 s.  (Fixed steps:
    with Exudyn's default ``discontinuous.useRecommendedStepSize`` the contact asks for steps
    below ``minimumStepSize`` at the impact, and the run stops there as Exudyn's own solve does,
    the last assertion.)"""
    mbs, b = _ball_on_sphere()
    mbs.SetObjectParameter(1, "contactStiffness", 1e12)
    ss = quiet_settings(0.2, 2000)
    ss.timeIntegration.discontinuous.useRecommendedStepSize = False
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(StepSizeError, match="beyond the stability limit") as e:
            exl.SolveDynamic(mbs, ss, showProgress=False, method="RK4")
    sugg = float(str(e.value).rsplit("step size of ", 1)[1].split(" s")[0])
    assert 1e-6 < sugg < 1e-5
    assert float(str(e.value).split("at t = ")[1].split(" s")[0]) > 0.01      # raised at the impact, not at the start
    for solve in (lambda mbs, ss: mbs.SolveDynamic(ss),
                  lambda mbs, ss: exl.SolveDynamic(mbs, ss, showProgress=False, method="RK4")):
        mbs, b = _ball_on_sphere()
        mbs.SetObjectParameter(1, "contactStiffness", 1e12)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with pytest.raises(exu.SolverError):
                solve(mbs, quiet_settings(0.2, 2000))


def _generic_ode1(A):
    from exudyn.utilities import NodeGenericODE1, ObjectGenericODE1
    mbs = new_mbs()
    n = mbs.AddNode(NodeGenericODE1(referenceCoordinates=[0, 0], initialCoordinates=[1, 0],
                                    numberOfODE1Coordinates=2))
    mbs.AddObject(ObjectGenericODE1(nodeNumbers=[n], systemMatrix=np.asarray(A, float), rhsVector=[0, 0]))
    mbs.Assemble()
    return mbs


def test_ode1_coordinates_integrate_with_the_same_tableau():
    """ObjectGenericODE1 y' = A y: RK4 at h = 1e-3 against expm(A) (measured 2.7e-13); a
    stiff A beyond RK4's limit stops with StepSizeError before the run."""
    from scipy.linalg import expm
    A = np.array([[0, 1.0], [-4.0, -0.1]])
    mbs = _generic_ode1(A)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, quiet_settings(1.0, 1000), showProgress=False)
    y = np.array(mbs.systemData.GetODE1Coordinates())
    assert np.max(np.abs(y - expm(A) @ [1.0, 0.0])) < 1e-11
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(StepSizeError, match="stable up to h = 0.000283 s"):
            exl.SolveDynamic(_generic_ode1([[0, 1.0], [-1e8, 0.0]]), quiet_settings(1.0, 1000), showProgress=False,
                             method="RK4")


@pytest.mark.parametrize("node", ["EP", "Rxyz"])
def test_other_rigid_nodes_in_vector_space_converge_to_the_compiled_path(node):
    """Euler-parameter (with its unit-norm algebraic equation) and Rxyz nodes are vector-space
    coordinates on this path (q_t = the parameters' rates), while the compiled path integrates
    the same bodies on the group: two discretisations of the same ODE, so they differ by RK4's
    truncation error, O(h^4) (measured at h = 1e-3 after 0.1 s: 1e-9 in q, 2e-8 in q_t); halving
    h divides the difference by about 16."""
    from test_bridge_common import NODE_TYPES
    build = lambda: models.build("heavy_top", mbs=new_mbs(), nodeType=NODE_TYPES[node])[0]
    d = []
    for h in (1e-3, 5e-4):
        out = _both_paths(build, 0.1, h)
        (q0, v0), (q1, v1) = out["compiled"], out["exudyn"]
        d.append(max(_rel(q1, q0), _rel(v1, v0)))
    assert d[0] < 1e-7
    assert d[1] < d[0] / 10, d


def test_post_newton_user_function_is_called_by_exudyn_after_every_step():
    """An mbs-level PostNewtonUserFunction (refused by the compiled path) takes the
    Exudyn-evaluated path, where Exudyn's PostNewton calls it after every MK step with the end
    state; here it switches a load on once the pendulum's tip passes below y = -0.05 (a
    discontinuity it reports, so that Exudyn repeats the step with the load on), against native
    generalized-alpha at h = 1e-5 (first order in h at the switch: both runs switch within one
    step of the crossing)."""
    O = exu.OutputVariableType

    def build():
        mbs = _pendulum_with_load_user_function()
        mbs.SetLoadParameter(0, "loadVectorUserFunction", 0)
        calls = []

        def post_newton(mbs, t):
            calls.append(t)
            y = mbs.GetObjectOutputBody(1, O.Position, localPosition=[0.1, 0, 0])[1]
            if y < -0.05 and mbs.GetLoadParameter(0, "loadVector")[2] == 0:
                mbs.SetLoadParameter(0, "loadVector", [0, 0, 20.0])
                return [1e3, -1]                # the state switched: repeat the step
            return [0, -1]
        mbs.SetPostNewtonUserFunction(post_newton)
        return mbs, calls

    mbs, calls = build()
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        exl.SolveDynamic(mbs, quiet_settings(0.3, 3000), showProgress=False)
    assert any("PostNewtonUserFunction" in str(x.message) for x in w)
    assert len(calls) >= 3000
    ref, _ = build()
    ss = quiet_settings(0.3, 30000)
    ss.timeIntegration.generalizedAlpha.spectralRadius = 1.0
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    ss.timeIntegration.generalizedAlpha.lieGroupSimplifiedKinematicRelations = True
    ss.timeIntegration.newton.useModifiedNewton = False
    ss.timeIntegration.newton.relativeTolerance = 1e-9
    ss.timeIntegration.newton.absoluteTolerance = 1e-9
    ref.SolveDynamic(ss)
    p = np.array(mbs.GetObjectOutputBody(1, O.Position, localPosition=[0.1, 0, 0]))
    pr = np.array(ref.GetObjectOutputBody(1, O.Position, localPosition=[0.1, 0, 0]))
    assert mbs.GetLoadParameter(0, "loadVector")[2] == 20.0 and abs(pr[2]) > 0.05     # the load acted: 6 cm in z
    # the switch is found at the end of the step that crosses: time error <= h = 1e-4, so the
    # position error is about h * (20 N / 1 kg) * 0.25 s = 5e-4 (measured 3.6e-4)
    assert np.max(np.abs(p - pr)) < 1e-3


# ---------------------------------------------------------------------------- adaptive steps
def _adaptive_settings(T, nsteps, tol):
    ss = quiet_settings(T, nsteps)
    ss.timeIntegration.adaptiveStep = True
    ss.timeIntegration.absoluteTolerance = tol
    ss.timeIntegration.relativeTolerance = tol
    return ss


def test_adaptive_dopri5_with_a_foreign_item_against_fine_native():
    """The one stepper's adaptive steps on the Exudyn-evaluated path: DOPRI5 with Exudyn's
    tolerances on a pendulum with an ObjectGenericODE2 (an item the kernel lacks), 2 Exudyn
    steps (steps of at most 0.25 s), against native generalized-alpha at h = 1e-5 (its own error
    ~1e-9).  The error falls with the tolerance (measured: 7.9e-5 at 1e-4, 7.4e-9 at 1e-7), and
    the error control takes more steps for the tighter one (7 and 24, no rejection)."""
    T = 0.5
    qn = _fine_native_pendulum(T)
    err, steps = {}, {}
    for tol in (1e-4, 1e-7):
        mbs = _pendulum_with_generic_ode2()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            exl.SolveDynamic(mbs, _adaptive_settings(T, 2, tol), method="DOPRI5", showProgress=False)
        err[tol] = _rel(_final_state(mbs)[0], qn)
        steps[tol] = mbs.sys["lieGroupSolver"].problem.sim.adaptiveCounters[0]
    assert err[1e-7] < 3e-8, err
    assert err[1e-7] < err[1e-4] / 100, err
    assert steps[1e-7] > 2 * steps[1e-4] > 4, steps


def test_adaptive_steps_on_ode1_coordinates():
    """ObjectGenericODE1 y' = A y with adaptive DOPRI5 (tolerance 1e-10) against expm(A)."""
    from scipy.linalg import expm
    A = np.array([[0, 1.0], [-4.0, -0.1]])
    mbs = _generic_ode1(A)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, _adaptive_settings(1.0, 10, 1e-10), method="DOPRI5", showProgress=False)
    y = np.array(mbs.systemData.GetODE1Coordinates())
    assert np.max(np.abs(y - expm(A) @ [1.0, 0.0])) < 1e-8
    assert mbs.sys["lieGroupSolver"].problem.sim.adaptiveCounters[0] > 10


# ---------------------------------------------------------------------------- velocity-level joints
def test_rolling_disc_same_trajectory_as_compiled():
    """A nonholonomic joint (ObjectJointRollingDisc: Exudyn's Jacobian is C_qdot, no position
    level) on the Exudyn-evaluated path: the rolling coin of TestModels/rollingCoinTest.py gives
    the compiled path's trajectory and contact force (eta by the central difference of Exudyn's
    velocity-level equation)."""
    from test_rolling_disc import rolling_coin
    out, force = {}, {}
    for ev in ("compiled", "exudyn"):
        mbs, o = rolling_coin()
        ss = quiet_settings(0.1, 200)
        ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            exl.SolveDynamic(mbs, ss, evaluation=ev, stabilization=None, showProgress=False)
        out[ev] = _final_state(mbs)
        force[ev] = np.array(mbs.GetObjectOutput(o, exu.OutputVariableType.ForceLocal))
    (q0, v0), (q1, v1) = out["compiled"], out["exudyn"]
    assert _rel(q1, q0) < TOL and _rel(v1, v0) < TOL, (_rel(q1, q0), _rel(v1, v0))
    assert _rel(force["exudyn"], force["compiled"]) < 1e-6, force


@pytest.mark.parametrize("what", ["positions", "velocities"])
def test_inconsistent_initial_state_is_refused_or_projected_by_the_one_rule(what):
    """The evaluated path checks the initial state by the compiled path's rule
    (mbs/initial_state.py): with projectInitial=False the error names the object, by default
    the state is projected onto Exudyn's own constraints with the warning, and the spherical
    joint then holds (its point on the body stays at the origin)."""
    from exudyn_lie.errors import ConstraintError

    def build():
        mbs = _pendulum_with_generic_ode2()
        n = [k for k in range(mbs.systemData.NumberOfNodes())
             if mbs.GetNode(k)["nodeType"] == "RigidBodyRotVecLG"][0]
        key = "initialCoordinates" if what == "positions" else "initialVelocities"
        v = np.array(mbs.GetNodeParameter(n, key), float)
        v[1] += 0.01 if what == "positions" else 0.5          # the joint's point moves off the origin
        mbs.SetNodeParameter(n, key, list(v))
        mbs.Assemble()
        return mbs, n

    mbs, n = build()
    match = "initial configuration violates" if what == "positions" else "initial velocities violate"
    with pytest.raises(ConstraintError, match=match + r" the .*constraints of objects 2 \('object2', ObjectJointSpherical\)"):
        exl.SolveDynamic(mbs, quiet_settings(0.01, 10), projectInitial=False, showProgress=False)
    mbs, n = build()
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        exl.SolveDynamic(mbs, quiet_settings(0.01, 10), showProgress=False)
    msgs = [str(x.message) for x in w if "projected onto them" in str(x.message)]
    assert len(msgs) == 1 and f"{what} of objects 2 ('object2', ObjectJointSpherical)" in msgs[0]
    p = np.array(mbs.GetNodeOutput(n, exu.OutputVariableType.Position))
    R = np.array(mbs.GetNodeOutput(n, exu.OutputVariableType.RotationMatrix)).reshape(3, 3)
    v = np.array(mbs.GetNodeOutput(n, exu.OutputVariableType.Velocity))
    om = np.array(mbs.GetNodeOutput(n, exu.OutputVariableType.AngularVelocity))
    arm = R @ np.array([-0.5, 0.0, 0.0])                    # the joint's point on the body
    assert np.linalg.norm(p + arm) < 1e-8
    assert np.linalg.norm(v + np.cross(om, arm)) < 1e-7


def _ep_bodies_on_a_spring():
    """Two rigid bodies on Euler parameters (Exudyn's default node) tumbling on a Cartesian spring:
    the only AE rows are the nodes' |p|^2 = 1."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    b = [mbs.CreateRigidBody(inertia=InertiaCuboid(500, [0.3, 0.2, 0.1]), referencePosition=[x, 0, 0],
                             initialVelocity=[0, 0.5 * x, 0], initialAngularVelocity=[1 + x, -2, 3 * x],
                             gravity=[0, -9.81, 0]) for x in (0.0, 1.0)]
    mbs.CreateCartesianSpringDamper(itemNumbers=b, localPosition0=[0.1, 0, 0], localPosition1=[-0.1, 0, 0],
                                    stiffness=[800] * 3, damping=[1] * 3)
    mbs.Assemble()
    return mbs


def test_eta_of_euler_parameter_rows_in_closed_form():
    """A model whose AE rows are Euler parameters' only: eta = -2 p_t . p_t without Exudyn's two
    velocity-level evaluations, the central difference's value at random states (to its error), and a
    run of the evaluated path the same as with the differences to round-off."""
    from test_bridge_common import random_state
    from exudyn_lie.bridge.evaluated import EvaluatedModel
    rng = np.random.default_rng(7)
    mbs = _ep_bodies_on_a_spring()
    solver, model, st = _evaluated_model(mbs)
    assert model._etaClosed and model.m == 2
    for _ in range(3):
        q, qt = random_state(mbs, rng, scale=0.3)
        model.q[:] = q
        model.qt[:] = qt
        st.read_state(model.q, model.qt)
        closed = model.eta(0.0, st.R, st.r, st.prev, st.qv)
        model._etaClosed = False
        diff, err = model.eta_error(0.0, st.R, st.r, st.prev, st.qv)
        model._etaClosed = True
        assert np.all(np.abs(closed - diff) <= 10 * err + 1e-12 * np.abs(closed).max()), (closed, diff, err)
        assert np.abs(closed).max() > 0.1
    solver.FinalizeSolver(mbs, quiet_settings())

    def run(closed):
        mbs = _ep_bodies_on_a_spring()
        ss = quiet_settings()
        ss.timeIntegration.numberOfSteps, ss.timeIntegration.endTime = 200, 0.2
        read = EvaluatedModel.read_rows

        def read_rows(self):
            read(self)
            self._etaClosed = self._etaClosed and closed
        EvaluatedModel.read_rows = read_rows
        try:
            exl.SolveDynamic(mbs, ss, evaluation="exudyn", method="RK4", showProgress=False)
        finally:
            EvaluatedModel.read_rows = read
        return np.array(mbs.systemData.GetODE2Coordinates())
    a, b = run(True), run(False)
    assert np.abs(a - b).max() <= 1e-10 * np.abs(b).max()
