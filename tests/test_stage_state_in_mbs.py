"""User functions that read the state from mbs (compiled path, bridge/stage_state.py).

A load's ``loadVectorUserFunction`` that reads its node's position and velocity with
``mbs.GetNodeOutput`` is a spring-damper written as a load.  In a native solve mbs holds the
iterate when Exudyn calls it; on the compiled path the drop-in called it at its stages with mbs
holding the last output (ten steps old in these runs), and integrated another model without a
sign.  Now the stage state is in mbs when such a function runs: the run equals the same spring
as Exudyn's compiled ``CartesianSpringDamper`` to round-off (same method, same forces at the same
stages).  And a ball dropped on a floor written as such a load bounces as generalized-alpha at a
fine step says (it ended 35 m high before)."""
import warnings

import numpy as np

import exudyn as exu
from exudyn.utilities import InertiaSphere, SensorBody

import exudyn_lie as exl
from exudyn_lie.bridge.stage_state import may_read_mbs

K, D, H, T = 400.0, 2.0, 1e-3, 0.5
O = exu.OutputVariableType


def body(mbs, z0=0.05, vx=0.2):
    return mbs.CreateRigidBody(referencePosition=[0, 0, z0], initialVelocity=[vx, 0, 0], gravity=[0, 0, -9.81],
                               inertia=InertiaSphere(1.0, 0.1), initialAngularVelocity=[0, 0, 1])


def settings(h=H, period=1e-2, tEnd=T):
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps, ss.timeIntegration.endTime = int(round(tEnd / h)), tEnd
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = period        # ten steps per Exudyn step
    return ss


def spring_model(asLoad):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    b = body(mbs)
    n = mbs.GetObject(b)["nodeNumber"]
    if asLoad:
        def UFload(mbs, t, load):
            p = mbs.GetNodeOutput(n, O.Position)
            v = mbs.GetNodeOutput(n, O.Velocity)
            return list(-K * np.asarray(p) - D * np.asarray(v))
        mbs.CreateForce(bodyNumber=b, loadVectorUserFunction=UFload)
    else:
        mbs.CreateCartesianSpringDamper(bodyNumbers=[mbs.CreateGround(), b], localPosition0=[0, 0, 0],
                                        stiffness=[K] * 3, damping=[D] * 3)
    s = mbs.AddSensor(SensorBody(bodyNumber=b, outputVariableType=O.Position, storeInternal=True))
    mbs.Assemble()
    return mbs, s


def exl_run(mbs, ss):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert exl.SolveDynamic(mbs, ss)


def test_a_load_that_reads_mbs_is_the_spring_it_writes():
    """(A rigid body, as in the other tests here: a point mass compiles kernel variants of its own;
    checked by hand, a point mass agreed to 2.8e-17.)"""
    out = []
    for asLoad in (True, False):
        mbs, s = spring_model(asLoad)
        exl_run(mbs, settings())
        out.append(np.asarray(mbs.GetSensorStoredData(s)))
    assert out[0].shape == out[1].shape and out[0].shape[0] == 51
    amplitude = np.abs(out[1][:, 1:]).max()
    assert amplitude > 0.04
    assert np.abs(out[0] - out[1]).max() < 1e-10       # (1.3e-11; 0.028 before)


def floor_model(h, k=1e6, d=50.0, z0=0.05, vx=0.2, tEnd=T):
    """A ball over a floor written as a load of stiffness ``k`` and damping ``d`` that reads the
    ball's position and velocity from mbs."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    b = body(mbs, z0, vx)
    n = mbs.GetObject(b)["nodeNumber"]

    def UFfloor(mbs, t, load):
        z = mbs.GetNodeOutput(n, O.Position)[2]
        vz = mbs.GetNodeOutput(n, O.Velocity)[2]
        return [0, 0, -k * z - d * vz if z < 0 else 0.0]
    mbs.CreateForce(bodyNumber=b, loadVectorUserFunction=UFfloor)
    s = mbs.AddSensor(SensorBody(bodyNumber=b, outputVariableType=O.Position, storeInternal=True))
    mbs.Assemble()
    return mbs, s, settings(h, tEnd=tEnd)


def three_runs(build):
    """``build(h)``'s sensor data through exudyn_lie at ``H``, and the reference (generalized-alpha at
    ``H / 20``): ``(data, largest position error, generalized-alpha's at H)``."""
    def native_run(mbs, ss):
        mbs.SolveDynamic(ss)
    runs = []
    for h, solve in ((H / 20, native_run), (H, native_run), (H, exl_run)):
        mbs, s, ss = build(h)
        solve(mbs, ss)
        runs.append(np.asarray(mbs.GetSensorStoredData(s)))
    ref, native, d = runs
    return d, np.abs(d - ref)[:, 1:].max(), np.abs(native - ref)[:, 1:].max()


def test_a_floor_written_as_a_load():
    _, err, native = three_runs(floor_model)
    print(f"\nlargest position error: exudyn_lie {err:.3g} m, generalized-alpha at the same step {native:.3g} m")
    assert err < native


def test_which_functions_may_read_mbs():
    def pure(mbs, t, load):
        return [0, 0, np.sin(t)]
    n = 0

    def reads(mbs, t, load):
        return mbs.GetNodeOutput(n, O.Position)

    def helper(t):
        return mbs_global.GetSensorValues(0)

    def calls_helper(mbs, t, load):
        return [0, 0, helper(t)]

    def state(mbs, t, load):
        return mbs.systemData.GetODE2Coordinates()[:3]

    class Controller:
        def __call__(self, mbs, t, load):
            return [0, 0, 0]
    assert not may_read_mbs(pure)
    assert may_read_mbs(reads) and may_read_mbs(calls_helper) and may_read_mbs(state)
    assert may_read_mbs(Controller()) and may_read_mbs(lambda mbs, t, load: mbs.GetSensorValues(0))


mbs_global = None


def resting_floor(h):
    """A ball dropped 10 um onto a floor written as a load (2.5e7 N/m, critically damped): the
    contact closes after 1.4 ms and stays closed, h omega = 5 at h = 1e-3 s, beyond RK4's radius."""
    return floor_model(h, k=2.5e7, d=1e4, z0=1e-5, vx=0.1, tEnd=0.1)


def test_a_contact_that_closes_during_the_run_switches_from_the_right_state(capsys):
    """The drop-in's RK4 sees the closed contact in its stages (mbs/stiffness.watch_stages) and does
    the step again with ESDIRK3 from the start of its Exudyn step: from mbs' state there, which the
    stage writes had moved 2 ms ahead (x 2 % off) until mbs is put back after the stepper returns."""
    mbs, s, ss = resting_floor(H / 50)
    mbs.SolveDynamic(ss)
    ref = np.asarray(mbs.GetSensorStoredData(s))
    mbs, s, ss = resting_floor(H)
    exl_run(mbs, ss)
    out = capsys.readouterr().out
    d = np.asarray(mbs.GetSensorStoredData(s))
    assert "RK4 became unstable" in out and "its stages show a mode beyond" in out and "ESDIRK3" in out
    assert np.abs(d[:, 1] - 0.1 * d[:, 0]).max() < 1e-12          # x = v t, unchanged by the restart
    assert np.abs(d - ref)[:, 1:].max() < 1e-9                     # at rest on the floor: -mg/k


def test_an_impact_inside_one_step_is_not_passed_with_energy_gained(capsys):
    """A ball dropped onto a floor load of 1e8 N/m: h omega = 10, the contact is shorter than the step.
    RK4 passed the impact in one step and gained energy (the ball rose to 1.08 m from 0.05 m); the
    watch saw only its last stage, which left the floor (h |lambda| = 1.7).  The stages inside the
    contact show h |lambda| = 10 (mbs/diagnostics.stage_rates, the largest over the stages): the
    step is done again with ESDIRK3.  The damped floor takes energy only: the ball never rises above
    its start, and stays within 0.05 m of generalized-alpha at h/20 (it damps the rebound more)."""
    d, err, native = three_runs(lambda h: floor_model(h, k=1e8, d=500.0, tEnd=0.3))
    out = capsys.readouterr().out
    print(f"\nlargest z {d[:, 3].max():.4g} m (start 0.05 m), largest position error {err:.3g} m "
          f"(generalized-alpha at the same step: {native:.3g} m)")
    assert d[:, 3].max() <= 0.05 + 1e-12 and err < 0.05
    assert "its stages show a mode beyond" in out


def test_an_impact_that_only_the_last_stage_touches_with_an_output_at_every_step(capsys):
    """The same drop with a sensor at every step.  The ball reaches the floor inside the step from
    0.100 s, and only RK4's last stage touches it: from the first stage that stage shows h |lambda| =
    1.9 (the force over the step's free motion), inside RK4's radius, and the step kicked the ball with
    h/6 of the force, 0.68 m/s where the contact had taken 0.06 m/s.  The next step was flagged, but
    the output at 0.101 s had been written: the run went on from the kicked state, 4.4e-2 m from
    generalized-alpha at h/20, half the rebound lost.  Now a step whose last stage alone shows a rate
    is checked at its end state (the rate there, differenced along the last stage's motion:
    mbs/stepper.fixed_step_watch), and this step is done again with ESDIRK3."""
    def build(h):
        mbs, s, ss = floor_model(h, k=1e8, d=500.0, tEnd=0.3)
        ss.solution.sensors.writePeriod = H
        return mbs, s, ss
    d, err, native = three_runs(build)
    out = capsys.readouterr().out
    print(f"\nlargest position error {err:.3g} m (generalized-alpha at the same step: {native:.3g} m)")
    assert "RK4 became unstable after t = 0.1 s" in out
    assert err < native                     # (2.6e-3 m against 3.8e-3; 4.4e-2 before)


def test_the_switch_with_fixed_steps_when_the_user_asks_for_them(capsys):
    """``timeIntegration.adaptiveStep = False``: after the switch ESDIRK3 keeps the script's fixed
    steps (new output chunks for its stepper, bridge/method_choice.replace_after_failure); the
    drop stays within 1e-2 m of generalized-alpha at h/20 (5.3e-3 m at commit 015d136).  (Only the
    exudyn_lie run has fixed steps: generalized-alpha's Newton iteration needs its own reductions.)"""
    runs = []
    for h, fixed in ((H / 20, False), (H, True)):
        mbs, s, ss = floor_model(h, k=1e8, d=500.0, tEnd=0.3)
        if fixed:
            ss.timeIntegration.adaptiveStep = False
            exl_run(mbs, ss)
        else:
            mbs.SolveDynamic(ss)
        runs.append(np.asarray(mbs.GetSensorStoredData(s)))
    ref, d = runs
    err = np.abs(d - ref)[:, 1:].max()
    out = capsys.readouterr().out
    print(f"\nlargest position error {err:.3g} m")
    assert "RK4 became unstable" in out and "adaptive steps" not in out
    assert d[:, 3].max() <= 0.05 + 1e-12 and err < 1e-2
