"""Rotation parameters written back to EP, Rxyz and RotVecLG nodes on Exudyn's continuous branch
however far apart the outputs are (mbs/rotation_parameters.py: tracked after every accepted
step): a free body spinning about two turns, outputs every step, every 50 steps, every 600 steps
(3.6 rad apart, more than pi) and only at the end, against a fine native generalized-alpha run
(whose coordinates Exudyn integrates continuously: EP sign, Tait-Bryan angles over turns, and
the RotVecLG vector turning over at |theta| = 2 pi by Exudyn's Lie group update)."""
import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import InertiaCuboid, SensorNode

import exudyn_lie as exl

T = 2.4
OMEGA0 = [0.3, 0.2, 6.0]          # turns 14 rad about ~z (small nutation: Rxyz stays regular)
NODES = ("RotationEulerParameters", "RotationRxyz", "RotationRotationVector")


def spinner(nodeType, period):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    b = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.1, 0.2, 0.3]), referencePosition=[0, 0, 0],
                            initialAngularVelocity=OMEGA0, nodeType=getattr(exu.NodeType, nodeType),
                            gravity=[0, 0, 0])
    n = mbs.GetObject(b)["nodeNumber"]
    s = mbs.AddSensor(SensorNode(nodeNumber=n, outputVariableType=exu.OutputVariableType.Coordinates,
                                 storeInternal=True)) if period else None
    mbs.Assemble()
    return SC, mbs, n, s


def run(nodeType, nsteps, period, lie, method="RK4"):
    """(final coordinates, sensor rows (time, coordinates) or None); DOPRI5: adaptive steps
    (tolerances 1e-10, dense outputs)."""
    SC, mbs, n, s = spinner(nodeType, period)
    ss = exu.SimulationSettings()
    ss.timeIntegration.numberOfSteps = nsteps
    ss.timeIntegration.endTime = T
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = period if period else T
    if lie:
        ss.timeIntegration.absoluteTolerance = ss.timeIntegration.relativeTolerance = 1e-10
        exl.SolveDynamic(mbs, ss, method=method, showProgress=False)
    else:
        ss.timeIntegration.generalizedAlpha.spectralRadius = 1.0
        exu.SolveDynamic(mbs, ss)
    q = np.array(mbs.GetNodeOutput(n, exu.OutputVariableType.Coordinates))
    return q, (mbs.GetSensorStoredData(s) if s is not None else None)


@pytest.fixture(scope="module")
def native():
    """Native generalized-alpha at h = 1e-5 (sensor every 0.05 s) and 2e-5 (its error bound)."""
    return {t: (run(t, 240000, 0.05, False), run(t, 120000, 0.05, False)) for t in NODES}


@pytest.mark.slow
@pytest.mark.parametrize("nodeType", NODES)
def test_written_parameters_follow_exudyns_branch(nodeType, native):
    """exl RK4 at h = 1e-3 with outputs every step, every 50 / 600 steps and only at the end:
    the same final coordinates (to 1e-12 among themselves) equal to native's to its own error,
    and the sensor rows at every 0.05 s (outputs every 50 steps) equal to native's there."""
    (qn, dn), (qn2, dn2) = native[nodeType]
    errNative = np.abs(dn - dn2).max()
    assert errNative < 1e-6, errNative
    if nodeType == "RotationRotationVector":            # native turns the vector over at 2 pi
        th = np.linalg.norm(dn[:, 4:7], axis=1)
        assert th.max() > 1.8 * np.pi and np.all(th <= 2 * np.pi + 1e-9)
    elif nodeType == "RotationEulerParameters":          # native EP change sign over a turn (reference 1)
        assert dn[:, 4].min() + 1 < -0.9 and dn[:, 4].max() + 1 > 0.9
    else:
        assert dn[:, 6].max() > 4 * np.pi                # the third angle goes on over turns
    finals = {}
    for every in (1, 50, 600, 2400):
        q, d = run(nodeType, 2400, every * 1e-3 if every < 2400 else 0, True)
        finals[every] = q
        assert np.abs(q - qn).max() < 10 * errNative + 1e-8, (every, q, qn)
        if every == 50:
            assert d.shape == dn.shape
            assert np.abs(d - dn).max() < 10 * errNative + 1e-8, (np.abs(d - dn).max(axis=0))
    for every in (50, 600, 2400):
        assert np.abs(finals[every] - finals[1]).max() < 1e-12, every


@pytest.mark.slow
@pytest.mark.parametrize("nodeType", NODES)
def test_adaptive_dense_outputs_follow_exudyns_branch(nodeType, native):
    """Adaptive DOPRI5 (tolerances 1e-10, steps <= 1e-3) with outputs 0.6 s apart (3.6 rad of
    spin, dense output: tracked values nearest those at the step's end) and only at the end:
    equal to native's (measured 4.1e-9 EP, 1.5e-9 Rxyz, 2.8e-10 RotVecLG)."""
    (qn, dn), (qn2, dn2) = native[nodeType]
    errNative = np.abs(dn - dn2).max()
    for period in (0.6, 0):
        q, d = run(nodeType, 2400, period, True, method="DOPRI5")
        assert np.abs(q - qn).max() < 10 * errNative + 1e-8, (period, q, qn)
        if period:
            ref = dn[np.isin(np.round(dn[:, 0], 9), np.round(d[:, 0], 9))]
            assert ref.shape == d.shape and len(d) >= 4
            assert np.abs(d - ref).max() < 10 * errNative + 1e-8, np.abs(d - ref).max(axis=0)


@pytest.mark.slow
def test_rolling_disc_spinning_more_than_a_turn_keeps_exudyns_ep_sign():
    """The corpus rolling disc (ObjectJointRollingDisc, EP node) spinning 7 rad in 1 s with only
    the final state written (one output): its Euler parameters end with the sign of Exudyn's
    continuous path (total e0 < 0; before the tracking the write-back took e0 > 0, 5.4 off) and
    agree with native generalized-alpha at h = 5e-6 to 4.2e-8 (measured; native's own error)."""
    import importlib
    disc = importlib.import_module("item_corpus.rollingDisc")
    out = {}
    for lie, n in ((False, 200000), (True, 400)):
        mbs, ss = disc.Build(spin=-7.0)
        ss.timeIntegration.numberOfSteps = n
        ss.timeIntegration.verboseMode = 0
        ss.solution.file.write = False
        ss.solution.sensors.active = False
        if lie:
            exl.SolveDynamic(mbs, ss, method="RK4")
        else:
            ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
            exu.SolveDynamic(mbs, ss)
        sd = mbs.systemData
        out[lie] = np.r_[sd.GetODE2Coordinates(), sd.GetODE2Coordinates_t()]
    assert out[False][3] + 1.0 < -0.5                   # native: e0 changed sign
    assert np.abs(out[True] - out[False]).max() < 1e-6, np.abs(out[True] - out[False]).max()
