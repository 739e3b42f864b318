"""Time-dependent coordinate constraints (mbs/row_drives.py): ObjectConnectorCoordinate with
``velocityLevel=True`` (row kind ROW_COORD_VEL), ``offsetUserFunction`` and ``offsetUserFunction_t``.

* the derivatives of an offset function (fourth-order central differences) against the analytic ones;
* J and eta of a velocity-level row are those of the position-level row (finite-difference tested in
  test_coordinate_items), its h is 0;
* Exudyn as the oracle: ``ComputeAlgebraicEquations`` (position level at time t with the offset
  function; velocity level) and ``ComputeJacobianAE`` (``C_q`` of position-level rows, ``C_qdot`` of
  velocity-level rows) at random states and times, against the kernel's residuals and J;
* the initial check uses the moving offset at the start time; errors name the item;
* the item corpus scripts (tests/item_corpus) velocityLevelCoordinate, prescribedCrank and
  velocityDriveUserFunction solved by exl.SolveDynamic (RK4) at 2h, h, h/2 against a native
  generalized-alpha reference at a fine step: the fitted order is 4 and every constraint holds.
"""
import importlib
import warnings

import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import (MarkerNodeCoordinate, Node1D, NodePoint, NodePointGround, ObjectConnectorCoordinate,
                              ObjectMass1D, ObjectMassPoint, RotationMatrixX, RotationMatrixZ)

import exudyn_lie as exl
from exudyn_lie.bridge.reader import BridgeError
from exudyn_lie.mbs import GROUND, Scene, SceneError, Simulator
from exudyn_lie.mbs.row_drives import offset_and_derivatives
from exudyn_lie.mbs.diagnostics import constraint_jacobian
from test_bridge_common import CUR, add_body, new_mbs, package, quiet_settings, random_state
from test_kernel_joints import random_rotation


# ---------------------------------------------------------------------------- offset derivatives
@pytest.mark.parametrize("t", [0.0, 0.37, 12.3])
def test_offset_derivatives_against_analytic(t):
    """A 1 Hz harmonic plus a slower one: value exact, rate and acceleration to the accuracy
    the step was chosen for (module text: ~5e-11 relative at 1 Hz)."""
    w = 2 * np.pi

    def c(s):
        return 0.3 * np.sin(w * s + 0.2) + 1.5 * np.cos(0.7 * s)
    cd = 0.3 * w * np.cos(w * t + 0.2) - 1.05 * np.sin(0.7 * t)
    cdd = -0.3 * w * w * np.sin(w * t + 0.2) - 0.735 * np.cos(0.7 * t)
    v, vd, vdd = offset_and_derivatives(c, t, "test")
    assert v == c(t)
    assert abs(vd - cd) < 1e-9 * 0.3 * w
    assert abs(vdd - cdd) < 1e-9 * 0.3 * w * w


# ---------------------------------------------------------------------------- kernel rows
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_velocity_level_row_has_the_position_rows_J_and_eta_and_no_h(group, rng):
    def scene(vel):
        sc = Scene()
        for _ in range(2):
            sc.AddBody(rng.uniform(0.5, 2), np.diag(rng.uniform(0.1, 0.3, 3)), com=rng.normal(size=3) * 0.1,
                       R0=random_rotation(rng), r0=rng.normal(size=3))
        sc.AddCoordinateConstraint(0, 1, 1, 2, factor=-1.3, constant=0.4, velocityLevel=vel)
        return sc
    state = rng.bit_generator.state
    sp = scene(False)
    rng.bit_generator.state = state
    sv = scene(True)
    for trial in range(3):
        R = np.array([random_rotation(rng) for _ in range(2)])
        r = rng.normal(size=(2, 3))
        V = rng.normal(size=(2, 6))
        out = []
        for sc in (sp, sv):
            sim = Simulator(sc, "RK4", group, projectInitial=True)
            out.append(constraint_jacobian(sim.sd, sim.wk, R, r, V))
        (hp, Jp, ep), (hv, Jv, ev) = out
        assert hv[0] == 0.0 and abs(hp[0]) > 1e-3
        np.testing.assert_array_equal(Jv, Jp)
        np.testing.assert_array_equal(ev, ep)


# ---------------------------------------------------------------------------- Exudyn as the oracle
def UFpos(mbs, t, itemNumber, lOffset):
    return lOffset + 0.2 * np.sin(3 * t) + 0.1 * t * t


def UFvel(mbs, t, itemNumber, lOffset):
    return 0.5 * np.cos(2 * t) - lOffset


def drive_model(nodes=("RotVecLG", "EP")):
    """Rigid bodies, a point mass, a Mass1D and a ground node with coordinate constraints of
    each kind: position level with offsetUserFunction, velocity level with a constant offset
    and with offsetUserFunction_t (the other user function set too: Exudyn ignores it)."""
    mbs = new_mbs()
    b0 = add_body(mbs, nodes[0], [1, 0, 0], RotationMatrixZ(0.3), gravity=[0, 0, -9.81])
    b1 = add_body(mbs, nodes[1], [1.5, 0.3, 0.1], RotationMatrixX(0.7), omega=(-0.4, 0.6, 0.2), vel=(0.3, -0.1, 0.2))
    n0, n1 = mbs.GetObject(b0)["nodeNumber"], mbs.GetObject(b1)["nodeNumber"]
    np3 = mbs.AddNode(NodePoint(referenceCoordinates=[0.2, 0.4, -0.3], initialVelocities=[0.1, 0.2, 0.3]))
    mbs.AddObject(ObjectMassPoint(mass=1.3, nodeNumber=np3))
    n1d = mbs.AddNode(Node1D(referenceCoordinates=[0.3], initialVelocities=[0.4]))
    mbs.AddObject(ObjectMass1D(nodeNumber=n1d, mass=0.7))
    ng = mbs.AddNode(NodePointGround(referenceCoordinates=[0.3, 0.1, 0.2]))

    def mc(n, k):
        return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=k))
    kw = [dict(factor1=1.7, offset=0.05, offsetUserFunction=UFpos),                           # position, uf
          dict(factor1=-0.5, offset=0.2, velocityLevel=True),                                 # velocity, offset
          dict(factor1=2.0, offset=0.1, velocityLevel=True, offsetUserFunction_t=UFvel,
               offsetUserFunction=UFpos),                                                     # velocity, uf_t
          dict(offset=-0.1, offsetUserFunction=UFpos, offsetUserFunction_t=UFvel),           # position, uf
          dict(factor1=1.0, offset=0.3, velocityLevel=True)]                                  # velocity, ground
    for ((na, ka), (nb, kb)), k in zip([((n0, 0), (n1, 1)), ((np3, 1), (n1, 0)), ((n1d, 0), (n0, 2)),
                                        ((ng, 0), (n1d, 0)), ((n1, 2), (ng, 0))], kw):
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mc(na, ka), mc(nb, kb)], **k))
    mbs.Assemble()
    return mbs


def exudyn_rows(mbs, q, qt, t):
    """Exudyn's residuals g (ComputeAlgebraicEquations) and the Jacobians C_q and C_qdot
    (ComputeJacobianAE with the ODE2 resp. ODE2_t factor) at (q, qt, t)."""
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
    C = []
    for fq, fqt in ((1.0, 0.0), (0.0, 1.0)):
        solver.ComputeJacobianODE2RHS(mbs, scalarFactor_ODE2=0., scalarFactor_ODE2_t=0., scalarFactor_ODE1=0.)
        solver.ComputeJacobianAE(mbs, scalarFactor_ODE2=fq, scalarFactor_ODE2_t=fqt, scalarFactor_ODE1=1.,
                                 velocityLevel=False)
        C.append(np.array(solver.GetSystemJacobian())[n2:n2 + nae, :n2].copy())
    solver.FinalizeSolver(mbs, ss)
    return g, C[0], C[1]


@pytest.mark.parametrize("nodes", [("RotVecLG", "EP"), ("Rxyz", "RotVecLG")], ids=lambda p: "-".join(p))
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_drives_same_as_exudyn(nodes, group, rng):
    """Per row: a position-level row's h(q, t) and J against Exudyn's g and C_q P; a
    velocity-level row's J V - w(t) and J against Exudyn's g and C_qdot P (P: the map from
    the kernel's velocity coordinates to Exudyn's qdot)."""
    mbs = drive_model(nodes)
    for trial in range(3):
        q, qt = random_state(mbs, rng)
        t = 0.3 + 0.7 * trial
        g, Cq, Cqt = exudyn_rows(mbs, q, qt, t)
        pk = package(mbs, group, q, qt, t)
        sim, sc, P, J = pk["sim"], pk["scene"], pk["P"], pk["J"]
        JV = J @ sim.V.reshape(-1) - sim.wk.rdrive[1]
        nvel = 0
        for ji in sc.joints_info:
            q0 = int(sim.sd.jointIndex[ji.sceneJoint, 2])
            ae = int(ji.aeRows[0])
            vel = bool(mbs.GetObject(ji.objectIndex)["velocityLevel"])
            Ce = (Cqt if vel else Cq)[ae] @ P
            assert np.max(np.abs(J[q0] - Ce)) < 1e-11 * max(1.0, np.max(np.abs(Ce)))
            assert np.max(np.abs((Cq if vel else Cqt)[ae])) == 0.0       # Exudyn: the other Jacobian is empty
            mine = JV[q0] if vel else pk["h"][q0]
            assert abs(mine - g[ae]) < 1e-11 * max(1.0, abs(g[ae])), (ji, mine, g[ae])
            if vel:
                assert pk["h"][q0] == 0.0
            nvel += vel
        assert nvel == 3 and len(sc.joints_info) == 5


# ---------------------------------------------------------------------------- start, errors
def slider_mbs(uf, startTime=0.0, x0=0.0, v0=0.0):
    mbs = new_mbs()
    ng = mbs.AddNode(NodePointGround())
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ng, coordinate=0))
    n = mbs.AddNode(Node1D(referenceCoordinates=[0.0], initialCoordinates=[x0], initialVelocities=[v0]))
    mbs.AddObject(ObjectMass1D(nodeNumber=n, mass=1.0))
    mx = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=0))
    o = mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mg, mx], offsetUserFunction=uf, name="drive"))
    mbs.Assemble()
    ss = quiet_settings(endTime=startTime + 0.5, nsteps=50)
    ss.timeIntegration.startTime = startTime
    return mbs, ss, o, n


@pytest.mark.parametrize("startTime", [0.0, 0.75])
def test_initial_state_is_projected_onto_the_moving_offset_at_the_start(startTime):
    """x(t) = 0.2 sin(2 t): an initial state at rest at 0 is projected onto x(t0), xdot(t0) (the
    warning says so), and the solve follows the prescribed motion to the end."""
    def uf(mbs, t, i, off):
        return 0.2 * np.sin(2 * t)
    mbs, ss, o, n = slider_mbs(uf, startTime)
    with pytest.warns(RuntimeWarning, match="projected onto them"):
        exl.SolveDynamic(mbs, ss)
    T = startTime + 0.5
    x = float(np.atleast_1d(mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates))[0])
    v = float(np.atleast_1d(mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates_t))[0])
    assert abs(x - 0.2 * np.sin(2 * T)) < 1e-10
    assert abs(v - 0.4 * np.cos(2 * T)) < 1e-9


def test_consistent_start_is_not_projected():
    """At t0 = 0.75 with x(t0), xdot(t0) set: no projection (no warning)."""
    def uf(mbs, t, i, off):
        return 0.2 * np.sin(2 * t)
    mbs, ss, o, n = slider_mbs(uf, 0.75, 0.2 * np.sin(1.5), 0.4 * np.cos(1.5))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        exl.SolveDynamic(mbs, ss)


def test_offset_user_function_raising_names_the_item():
    def uf(mbs, t, i, off):
        if t > 0.2:
            raise ZeroDivisionError("boom")
        return 0.0
    mbs, ss, o, n = slider_mbs(uf)
    with pytest.raises(ZeroDivisionError, match=r"object \d+ ObjectConnectorCoordinate \('drive'\) "
                                                r"offsetUserFunction raised at t = .*boom"):
        exl.SolveDynamic(mbs, ss)


def test_offset_user_function_returning_nan_names_the_item():
    mbs, ss, o, n = slider_mbs(lambda mbs, t, i, off: np.nan if t > 0.1 else 0.0)
    with pytest.raises(ValueError, match=r"ObjectConnectorCoordinate \('drive'\) offsetUserFunction returned nan"):
        exl.SolveDynamic(mbs, ss)


def test_changing_the_offset_function_during_the_solve_stops_it():
    mbs, ss, o, n = slider_mbs(lambda mbs, t, i, off: 0.0)

    def pre(mbs, t):
        if t > 0.1:
            mbs.SetObjectParameter(o, "offsetUserFunction", lambda mbs, t, i, off: 0.1)
        return True
    mbs.SetPreStepUserFunction(pre)
    with pytest.raises(BridgeError, match="offsetUserFunction' changed during the solve"):
        exl.SolveDynamic(mbs, ss, evaluation="compiled")       # ('auto': the evaluated path continues)


@pytest.mark.parametrize("evaluation", ["auto", "exudyn"])
def test_offset_function_changed_during_the_solve_is_followed(evaluation):
    """A pre-step function replaces the offset function at t > 0.1 s by one that leaves the old one
    at t = 0.2 s (a cubic added: no jump).  'auto' hands the run to the Exudyn-evaluated path, which
    reads the new function; on that path from the start ('exudyn') the change is recorded and the
    rows read again.  x(T) follows the new function to 1e-5 m (the old one would end 0.135 m away;
    the new one's third derivative jumps at 0.2 s, where RK4 at h = 0.01 s without projection on
    the evaluated path loses 3e-6 m)."""
    def uf0(mbs, t, i, off):
        return 0.2 * np.sin(2 * t)

    def uf1(mbs, t, i, off):
        return 0.2 * np.sin(2 * t) + 5.0 * max(0.0, t - 0.2) ** 3
    mbs, ss, o, n = slider_mbs(uf0, 0.0, 0.0, 0.4)

    def pre(mbs, t):
        if t > 0.1:
            mbs.SetObjectParameter(o, "offsetUserFunction", uf1)
        return True
    mbs.SetPreStepUserFunction(pre)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exl.SolveDynamic(mbs, ss, evaluation=evaluation)
    x = float(np.atleast_1d(mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates))[0])
    assert abs(x - uf1(None, 0.5, 0, 0)) < 1e-5, (x, uf1(None, 0.5, 0, 0), uf0(None, 0.5, 0, 0))


def test_scene_offset_must_be_callable():
    sc = Scene()
    sc.AddBody(1.0, np.eye(3))
    with pytest.raises(SceneError, match="callable"):
        sc.AddCoordinateConstraint(GROUND, 0, 0, 0, offset=0.5)


# ---------------------------------------------------------------------------- corpus scripts
SCRIPTS = ["velocityLevelCoordinate", "prescribedCrank", "velocityDriveUserFunction"]
H_REF = 5e-6


def _final(name, h, native=False):
    mbs, ss = importlib.import_module(f"item_corpus.{name}").Build()
    T = ss.timeIntegration.endTime
    ss.timeIntegration.numberOfSteps = int(round(T / h))
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.active = False
    if native:
        ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
        exu.SolveDynamic(mbs, ss)
    else:
        exl.SolveDynamic(mbs, ss, method="RK4")
    sd = mbs.systemData
    return mbs, np.r_[sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t()]


@pytest.mark.slow
@pytest.mark.parametrize("name", SCRIPTS)
def test_drive_script_converges_to_native_fine_step_with_order_4(name):
    """Reference: generalized-alpha at H_REF; its own convergence is checked: it differs from
    the run at 2 H_REF by less than a tenth of RK4's error at the finest step (the native run
    does not converge below ~1e-7 on prescribedCrank: 6.5e-8 between 1e-5 and 5e-6 s, 9.7e-8
    between 5e-6 and 2.5e-6 s, measured; hence the steps 2h, h, h/2 with RK4's errors well above
    it).  RK4 at twice, once and half the script's step h: the slope of the log-log fit is
    4 +- 0.5, the error at h below 1e-4, and every ConnectorCoordinate's constraint equation
    (Exudyn's own, position or velocity level) holds at the end to the integration error."""
    _, ref = _final(name, H_REF, native=True)
    _, r2 = _final(name, 2 * H_REF, native=True)
    refErr = np.abs(ref - r2).max()
    mbs0, ss0 = importlib.import_module(f"item_corpus.{name}").Build()
    h0 = ss0.timeIntegration.endTime / ss0.timeIntegration.numberOfSteps
    hs = np.array([2 * h0, h0, h0 / 2])
    errs, drift = [], []
    for h in hs:
        mbs, x = _final(name, h)
        errs.append(np.abs(x - ref).max())
        drift.append(max(abs(float(np.atleast_1d(mbs.GetObjectOutput(o, exu.OutputVariableType.ConstraintEquation))[0]))
                         for o in range(mbs.systemData.NumberOfObjects())
                         if mbs.GetObject(o)["objectType"] == "ConnectorCoordinate"))
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    print(f"{name}: errors {errs}, slope {slope:.3f}, constraint drift {drift}, reference H_REF vs 2 H_REF "
          f"{refErr:.2g}")
    assert refErr < 0.1 * errs[-1]
    # no stabilisation: the constraints drift by the integration error, at most (Exudyn's own equations)
    assert all(d <= e for d, e in zip(drift, errs))
    assert errs[1] < 1e-4
    assert 3.5 < slope < 4.5


def test_a_driven_run_does_not_follow_how_its_outputs_are_chunked(monkeypatch, tmp_path):
    """A stage's time is one product from the run's start (mbs/clock.py), so the output chunks, which
    the bridge sizes by the wall time (``outputs.CHUNK_SECONDS``), cannot change a time-dependent
    model's result: one output per call of the stepper against as many as a chunk holds, to the bit."""
    from exudyn_lie.mbs import outputs
    integrate = outputs.OutputRows.integrate
    finals, sizes = [], []

    def spy(self, nout, vmax):
        sizes[-1] = max(sizes[-1], min(nout, self.size))
        return integrate(self, nout, vmax)
    monkeypatch.setattr(outputs.OutputRows, "integrate", spy)
    for seconds in (0.0, 1e9):
        monkeypatch.setattr(outputs, "CHUNK_SECONDS", seconds)
        sizes.append(0)
        mbs, ss = importlib.import_module("item_corpus.prescribedCrank").Build()
        ss.timeIntegration.numberOfSteps = 1000
        ss.timeIntegration.verboseMode = 0
        ss.solution.file.name = str(tmp_path / f"chunks{len(sizes)}.txt")
        ss.solution.file.writePeriod = 0.01             # an output every ten steps
        exl.SolveDynamic(mbs, ss, method="RK4")
        sd = mbs.systemData
        finals.append(np.r_[sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t()])
    assert sizes[0] == 1 and sizes[1] > 10, sizes
    assert np.array_equal(finals[0], finals[1]), np.abs(finals[0] - finals[1]).max()


# ---------------------------------------------------------------------------- projections and drift
def driven_scene(velocityLevel=False):
    """A body driven along x (x = 0.1 sin(2 pi t), or its rate at velocity level), y and z
    held, a second body hanging from it on a spring (something to integrate)."""
    w = 2 * np.pi
    sc = Scene()
    a = sc.AddBody(1.0, np.diag([0.1, 0.2, 0.3]), vel0=[0.1 * w, 0, 0])
    b = sc.AddBody(0.5, np.diag([0.05, 0.05, 0.05]), r0=[0, -0.5, 0], vel0=[0.0, 0.0, 0.2], omega0=[0.3, 0.1, 0.2])
    if velocityLevel:
        sc.AddCoordinateConstraint(GROUND, 0, a, 0, velocityLevel=True, offset=lambda t: 0.1 * w * np.cos(w * t))
    else:
        sc.AddCoordinateConstraint(GROUND, 0, a, 0, offset=lambda t: 0.1 * np.sin(w * t))
    sc.AddCoordinateConstraint(GROUND, 1, a, 1)
    sc.AddCoordinateConstraint(GROUND, 2, a, 2)
    sc.AddSpringDamper(a, [0, 0, 0], b, [0.05, 0, 0], stiffness=200.0, damping=0.5, referenceLength=0.45)
    sc.gravity = np.array([0, -9.81, 0])
    return sc


@pytest.mark.parametrize("velocityLevel", [False, True])
def test_projection_after_a_step_uses_the_offset_at_the_steps_end(velocityLevel):
    """Explicit midpoint (its last stage at t + h/2): with stabilization the state after each
    step satisfies the rows at t + h, h(g, t + h) = 0 (position level) and J V = w(t + h)."""
    sim = Simulator(driven_scene(velocityLevel), "ExplicitMidpoint", "SE3",
                    stabilization="velocity" if velocityLevel else "position")
    res = sim.Run(0.5, 1e-3, outputEvery=50)
    assert np.max(np.abs(res.residuals)) < 1e-12
    h, JV = sim._residuals_and_JV()
    assert np.max(np.abs(JV)) < 1e-12
    if not velocityLevel:
        assert abs(sim.r[0, 0] - 0.1 * np.sin(2 * np.pi * 0.5)) < 1e-12


def test_constraint_tolerance_of_adaptive_steps_uses_the_moving_offset():
    """Adaptive DOPRI5 with a constraint tolerance: every output (dense ones projected when
    their drift exceeds it) satisfies h(g, t) = 0 at its own time to the tolerance, and the
    driven coordinate follows x(t)."""
    sim = Simulator(driven_scene(), "DOPRI5", "SE3")
    res = sim.Run(1.0, outputTimes=np.linspace(0, 1, 41), rtol=1e-4, atol=1e-6, constraintTolerance=1e-9)
    assert np.max(np.abs(res.residuals)) <= 1e-9
    np.testing.assert_allclose(res.r[:, 0, 0], 0.1 * np.sin(2 * np.pi * res.times), atol=1e-9)


# ---------------------------------------------------------------------------- the Exudyn-evaluated path
def evaluated_drive_model():
    """Three Mass1D driven by coordinate constraints beside an ObjectGenericODE2 oscillator (an
    item the compiled kernel lacks: Exudyn evaluates the model): x0 by an offsetUserFunction
    without offsetUserFunction_t (Exudyn's velocity-level equation omits its rate), x1 at
    velocity level by offsetUserFunction_t, x2 at velocity level with a constant offset."""
    from exudyn.utilities import NodeGenericODE2, ObjectGenericODE2
    mbs = new_mbs()
    ng = mbs.AddNode(NodePointGround())
    mg = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ng, coordinate=0))
    nodes = []
    for k, (x0, v0) in enumerate(((0.0, 0.0), (0.0, 0.5), (0.2, 0.7))):
        n = mbs.AddNode(Node1D(referenceCoordinates=[0.0], initialCoordinates=[x0], initialVelocities=[v0]))
        mbs.AddObject(ObjectMass1D(nodeNumber=n, mass=1.0 + k))
        nodes.append(n)
    mk = [mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=0)) for n in nodes]
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mg, mk[0]], name="x0",
                                            offsetUserFunction=lambda mbs, t, i, o: 0.3 * (1 - np.cos(2 * np.pi * t))))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mg, mk[1]], velocityLevel=True, name="x1",
                                            offsetUserFunction_t=lambda mbs, t, i, o: 0.5 * np.cos(2 * t)))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[mg, mk[2]], velocityLevel=True, offset=0.7, name="x2"))
    nO = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0], initialCoordinates=[0.1], initialCoordinates_t=[0],
                                     numberOfODE2Coordinates=1))
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[nO], massMatrix=np.eye(1), stiffnessMatrix=np.eye(1)))
    mbs.Assemble()
    return mbs, nodes


def test_evaluated_path_honours_moving_offsets_and_velocity_level_rows():
    """Exact solutions (the driven coordinates are prescribed): x0 = 0.3 (1 - cos 2 pi t) (before
    the fix the evaluated path left x0 at 0: Exudyn's velocity-level equation has no offset rate),
    x1 = 0.25 sin 2t, x2 = 0.2 + 0.7 t."""
    mbs, nodes = evaluated_drive_model()
    ss = quiet_settings(endTime=0.25, nsteps=250)
    with pytest.warns(RuntimeWarning, match="Exudyn evaluates the whole model"):
        exl.SolveDynamic(mbs, ss)
    T = 0.25
    x = [float(np.atleast_1d(mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates))[0]) for n in nodes]
    v = [float(np.atleast_1d(mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates_t))[0]) for n in nodes]
    assert abs(x[0] - 0.3 * (1 - np.cos(2 * np.pi * T))) < 1e-9
    assert abs(v[0] - 0.6 * np.pi * np.sin(2 * np.pi * T)) < 1e-8
    assert abs(x[1] - 0.25 * np.sin(2 * T)) < 1e-9
    assert abs(v[1] - 0.5 * np.cos(2 * T)) < 1e-9
    assert abs(x[2] - (0.2 + 0.7 * T)) < 1e-12 and abs(v[2] - 0.7) < 1e-12


@pytest.mark.parametrize("adaptive", [False, True], ids=["fixed", "adaptive"])
def test_run_rows_are_the_diagnostics_of_their_states(adaptive):
    """Simulator.Run's energies and residuals, computed a chunk of output rows at a time, are
    Simulator.Diagnostics of each row's own state and time: with moving offsets (rows evaluated one
    at a time, each at its time) and without (one call per chunk); fixed steps with a shorter
    landing step, and adaptive steps' dense outputs."""
    from exudyn_lie.apps import bench_topology as BT
    from exudyn_lie.bridge.reader import SceneFromExudyn
    kw = dict(rtol=1e-6, atol=1e-8) if adaptive else {}
    for sc, drives in ((SceneFromExudyn(drive_model(), "initial"), True), (BT.build_scene("chain", 3), False)):
        sim = Simulator(sc, "DOPRI5" if adaptive else "RK4", "SE3", projectInitial=True)
        res = sim.Run(endTime=0.0505, stepSize=1e-3, outputEvery=3, **kw)
        assert len(res.times) > 15 and res.times[-1] == 0.0505 and bool(sim._drives) == drives
        for k in range(len(res.times)):
            e, h = sim.Diagnostics(res.R[k], res.r[k], res.V[k], t=res.times[k])[:2]
            np.testing.assert_array_equal(res.energy[k], e)
            np.testing.assert_array_equal(res.residuals[k], h)
        moving = max(len(np.unique(res.residuals[:, q])) for q in range(res.residuals.shape[1]))
        assert len(np.unique(res.energy[:, 0])) > 10 and (not drives or moving > 10), moving
        # each row's residuals at its own time: the drives move the rows' offsets at about 1 per s, so
        # a row paired with a time one output off would show a residual of about 3e-3
        assert np.max(np.abs(res.residuals)) < 1e-6, np.max(np.abs(res.residuals))
