"""``ObjectConnectorRollingDiscPenalty`` in the compiled kernel
(``mbs/rolling_disc_penalty_forces.py``): Exudyn's own ``ComputeODE2RHS`` at random states
(contact and no contact by the stored gap, the proportional ("sticking") zone and sliding by
the stored slip velocity, every friction option), the data-coordinate update after each step
against Exudyn's PostNewton, and the reader's refusals."""
import functools
import math
import re

import exudyn as exu
import numpy as np
import pytest
from exudyn.utilities import (MarkerBodyRigid, MarkerNodeRigid, NodeGenericData, ObjectConnectorRollingDiscPenalty,
                              RotationMatrixX, RotationMatrixY, RotationMatrixZ)

import exudyn_lie as exl
import foreign_models as FM
from exudyn_lie.bridge import BridgeError, SceneFromExudyn
from exudyn_lie.mbs.rolling_disc_penalty_forces import D_DATA
from test_bridge_common import INI, add_body, compare, new_mbs, random_state

TOL = 1e-11

# friction options: (dryFrictionAngle, viscousFriction, rollingViscousFriction, useLinearProportionalZone)
OPTIONS = {
    "plain": (0.0, [0.0, 0.0], 0.0, False),
    "viscous-linear": (0.0, [0.3, 0.7], 0.0, True),
    "angle": (0.4, [0.2, 0.1], 0.0, False),
    "rolling": (0.0, [0.0, 0.0], 0.05, False),
    "all": (-0.3, [0.1, 0.4], 0.08, True),
}


def disc_model(nodes=("RotVecLG", "EP"), plane="ground", option="all"):
    """A disc (body 0, nodes[0]) on the plane of the (rotated, shifted) ground or of a second
    rigid body (nodes[1]); a second penalty disc of body 1 on the ground.  Markers with offsets
    and rotations (the law uses marker positions and orientations)."""
    alpha, visc, roll, linear = OPTIONS[option]
    mbs = new_mbs()
    g = mbs.CreateGround(referencePosition=[0.1, -0.2, 0.05], referenceRotationMatrix=RotationMatrixY(0.1))
    b0 = add_body(mbs, nodes[0], [0.2, 0.1, 0.3], RotationMatrixZ(0.3) @ RotationMatrixY(0.2), gravity=[0, 0, -9.81])
    b1 = add_body(mbs, nodes[1], [0.8, 0.3, 0.1], RotationMatrixX(0.7), omega=(-0.4, 0.6, 0.2), vel=(0.3, -0.1, 0.2))
    mDisc = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b0, localHT=exu.HT(rotation=RotationMatrixX(0.3),
                                                                         translation=[0.05, -0.02, 0.01])))
    if plane == "ground":
        mPlane = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g, localHT=exu.HT(rotation=RotationMatrixZ(0.5),
                                                                             translation=[0.0, 0.1, -0.05])))
    else:
        mPlane = mbs.AddMarker(MarkerBodyRigid(bodyNumber=b1, localHT=exu.HT(rotation=RotationMatrixX(-0.2),
                                                                              translation=[0.1, 0.0, -0.05])))
    discs = []
    for m0, m1, axis, normal in [(mPlane, mDisc, [1, 0, 0], [0, 0, 1]),
                                 (mbs.AddMarker(MarkerBodyRigid(bodyNumber=g)),
                                  mbs.AddMarker(MarkerNodeRigid(nodeNumber=mbs.GetObject(b1)["nodeNumber"])),
                                  [0.6, 0.8, 0], list(np.array([0.1, 0, 1.0]) / np.sqrt(1.01)))]:
        nd = mbs.AddNode(NodeGenericData(initialCoordinates=[0, 0, 0], numberOfDataCoordinates=3))
        discs.append(mbs.AddObject(ObjectConnectorRollingDiscPenalty(
            markerNumbers=[m0, m1], nodeNumber=nd, discRadius=0.15, discAxis=axis, planeNormal=normal,
            contactStiffness=2e4, contactDamping=30.0, dryFriction=[0.6, 0.4], dryFrictionProportionalZone=0.05,
            viscousFriction=visc, dryFrictionAngle=alpha, rollingViscousFriction=roll,
            useLinearProportionalZone=linear)))
    mbs.Assemble()
    return mbs, discs


def set_data(mbs, values):
    """The data coordinates (slip velocity, gap) of every disc's NodeGenericData, initial and current."""
    sd = mbs.systemData
    x = np.array(sd.GetDataCoordinates(configuration=INI), float)
    for o, v in values.items():
        x[np.asarray(sd.GetNodeLTGData(mbs.GetObject(o)["nodeNumber"]), np.int64)] = v
    for cfg in (INI, exu.ConfigurationType.Current):
        sd.SetDataCoordinates(x, configuration=cfg)


# stored data: (lateral slip, longitudinal slip, gap); the proportional zone is |slip| <= 0.05
DATA = {
    "no contact": (0.01, -0.02, 0.3),
    "zone": (0.01, -0.02, -0.1),
    "sliding": (0.4, -0.3, -0.1),
    "zero slip": (0.0, 0.0, -0.1),
}


@pytest.mark.parametrize("option", list(OPTIONS))
@pytest.mark.parametrize("nodes,plane", [(("RotVecLG", "EP"), "ground"), (("EP", "Rxyz"), "body"),
                                         (("Rxyz", "RotVecLG"), "body")], ids=["RotVecLG-ground", "EP-body",
                                                                                 "Rxyz-body"])
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_forces_same_as_exudyn(option, nodes, plane, group, rng):
    mbs, discs = disc_model(nodes, plane, option)
    nonzero = 0
    for data in DATA.values():
        set_data(mbs, {discs[0]: data, discs[1]: DATA["zone"]})
        for trial in range(2):
            q, qt = random_state(mbs, rng, scale=0.1)
            qt *= 0.05 if trial == 0 else 1.0          # slip inside and beyond the proportional zone
            c = compare(mbs, group, q, qt, 0.1 + trial)
            assert c["f"] < TOL, f"{data}: relative deviation {c['f']:.3g} of f from Exudyn (trial {trial})"
            nonzero += np.max(np.abs(c["fvals"][1])) > 1.0
    assert nonzero == 2 * len(DATA)


def test_inactive_disc_has_no_force_and_keeps_its_data(rng):
    mbs, discs = disc_model()
    for o in discs:
        mbs.SetObjectParameter(o, "activeConnector", False)
    mbs.Assemble()
    set_data(mbs, {discs[0]: DATA["sliding"], discs[1]: DATA["zone"]})
    q, qt = random_state(mbs, rng, scale=0.1)
    c = compare(mbs, "SE3", q, qt)
    assert c["f"] < TOL


@pytest.mark.parametrize("case", ["disc on ground", "no data node", "two data coordinates"])
def test_bad_setups_are_refused(case):
    mbs, discs = disc_model()
    d = mbs.GetObject(discs[0])
    if case == "disc on ground":
        mbs.SetObjectParameter(discs[0], "markerNumbers", [d["markerNumbers"][1], d["markerNumbers"][0]])
        msg = "marker 1 \\(the disc\\) is on the ground"
    elif case == "no data node":
        mbs.SetObjectParameter(discs[0], "nodeNumber", 0)
        msg = "not a NodeGenericData"
    else:
        nd = mbs.AddNode(NodeGenericData(initialCoordinates=[0, 0], numberOfDataCoordinates=2))
        mbs.SetObjectParameter(discs[0], "nodeNumber", nd)
        msg = "3 finite data coordinates"
    with pytest.raises(BridgeError, match=msg):
        SceneFromExudyn(mbs, "items")


# --------------------------------------------------------------------------- solves
def _solve(model, **kw):
    import warnings
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        exl.SolveDynamic(model.mbs, model.simulationSettings, showProgress=False, **kw)
    return FM.final_state(model.mbs), [str(w.message) for w in rec]


@functools.lru_cache(maxsize=None)
def smooth_reference():
    """Richardson-checked generalized-alpha (h0 = 1e-4 ... 1.25e-5) of the smooth rolling coin."""
    return FM.native_reference(FM.rolling_disc, 1e-4, 0.5)


def test_smooth_rolling_coin_is_compiled_and_converges_at_order_4():
    """tests/foreign_models.rolling_disc: the coin stays in contact and its stored slip stays in
    the proportional zone, so every stage uses the current slip (Exudyn's rule) and the law is
    smooth along the motion: MK-RK4 on the compiled path converges to the fine native reference
    at order 4 (errors at h = 2e-3 and 1e-3 s; measured order printed), and agrees with the
    Exudyn-evaluated path (evaluation='exudyn': Exudyn's own PostNewton after each step) at the
    same step to round-off.  The data coordinates in mbs after the run are Exudyn's PostNewton
    at the final state, and equal the kernel's own (Work.disc)."""
    ref, refErr, _ = smooth_reference()
    errs = []
    for h in (2e-3, 1e-3):
        m = FM.rolling_disc(h=h)
        y, warned = _solve(m)
        assert not [w for w in warned if "RollingDiscPenalty" in w], warned     # compiled: no evaluated-path note
        assert isinstance(m.mbs.sys["lieGroupSolver"], exl.LieGroupSolver)
        errs.append(FM.state_error(y, ref))
        sd = m.mbs.systemData
        dataMbs = np.asarray(sd.GetDataCoordinates(), float)[np.asarray(sd.GetNodeLTGData(
            m.mbs.GetObject(m.foreignIndex)["nodeNumber"]), np.int64)]
        np.testing.assert_allclose(m.mbs.sys["lieGroupSolver"].sim.wk.path.rollingDiscs[0, D_DATA:], dataMbs, rtol=0, atol=1e-12)
        assert dataMbs[2] < 0                                                  # in contact at the end
        if h == 2e-3:
            m2 = FM.rolling_disc(h=h)
            y2, _ = _solve(m2, evaluation="exudyn")
            assert np.abs(y - y2).max() < 1e-12, np.abs(y - y2).max()
    order = math.log2(errs[0] / errs[1])
    print(f"smooth rolling coin: MK-RK4 errors {errs[0]:.3e}, {errs[1]:.3e}; order {order:.2f}; "
          f"reference error {refErr:.1e}")
    assert errs[1] > 10 * refErr
    assert 3.4 <= order <= 4.8


def test_substeps_give_the_same_run_and_exudyn_does_not_repeat_steps():
    """Outputs every 10th step (10 kernel steps per Exudyn step): the same final state as one
    output per step, bit for bit, and Exudyn ran one PostNewton per output (no repeated step:
    its discontinuous iteration is limited to one pass on this path)."""
    out = []
    for period in (2e-3, 2e-2):
        m = FM.rolling_disc(h=2e-3)
        m.simulationSettings.solution.sensors.writePeriod = period
        m.simulationSettings.timeIntegration.discontinuous.iterationTolerance = 1e-30   # any error would repeat
        y, _ = _solve(m)
        out.append(y)
        it = m.mbs.sys["dynamicSolver"].it
        assert it.discontinuousIterationsCount == round(0.5 / period)
    assert np.array_equal(out[0], out[1])


def _coin(h, T, native=False, evaluation="auto", method="RK4"):
    """The coin's final state; ``method`` None: SolveDynamic's own choice."""
    from item_corpus import rollingCoinPenalty
    mbs, ss = rollingCoinPenalty.Build(T, h)
    ss.timeIntegration.verboseMode = 0
    if native:
        exu.SolveDynamic(mbs, ss)
    else:
        import warnings
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            exl.SolveDynamic(mbs, ss, showProgress=False, evaluation=evaluation, method=method)
    return FM.final_state(mbs)


@pytest.mark.slow
def test_exudyn_rolling_coin_penalty_test_model():
    """Exudyn's TestModels/rollingCoinPenaltyTest.py (tests/item_corpus/rollingCoinPenalty.py): a
    coin dropped onto the ground with a stiff, strongly damped penalty contact (k = 1e5 N/m,
    d = 1e4 N s/m on 1 kg, r = 1 cm).

    * At the script's step (1e-4 s) explicit RK4 is far beyond its stability limit at the
      impact: a StepSizeError names a stable step (about 2.6e-6 s).
    * Below it the compiled run agrees with Exudyn's generalized-alpha at a fine step
      (h0 = 2.5e-7 s, T = 0.1 s: fall, impact at 0.045 s, rolling).  The law switches by the
      stored data (contact from the step after the penetrating one, the proportional zone by
      the stored slip): both solvers place such events on step boundaries, so neither
      converges at a clean order (native: first order, step-halving differences printed;
      compiled: measured errors 6.3e-6, 4.6e-6 at 1e-6, 5e-7 s against this reference, whose
      own error is about its last step-halving difference, 1.5e-6).  Asserted: agreement
      within 1e-5 on a state of magnitude 17 (the spin at the end), i.e. at the reference's accuracy."""
    from exudyn_lie.errors import StepSizeError
    with pytest.raises(StepSizeError, match=r"try a step size of [0-9.e-]+ s or smaller") as ei:
        _coin(1e-4, 0.1)
    hSuggested = float(re.search(r"step size of ([0-9.e-]+) s or smaller", str(ei.value)).group(1))
    assert 1e-6 < hSuggested < 1e-5
    T = 0.1
    nat = {h: _coin(h, T, native=True) for h in (5e-7, 2.5e-7)}
    ref = nat[2.5e-7]
    natErr = np.abs(nat[5e-7] - ref).max()
    errs = {h: np.abs(_coin(h, T) - ref).max() for h in (1e-6, 5e-7)}
    print(f"rolling coin penalty: native step-halving difference at 2.5e-7 s {natErr:.2e}; compiled errors "
          + ", ".join(f"h = {h:g}: {e:.2e}" for h, e in errs.items()) + f"; spin {np.abs(ref).max():.1f}")
    assert np.abs(ref).max() > 10.0
    for h, e in errs.items():
        assert e < 1e-5, (h, e)


def test_parameters_changed_by_a_pre_step_function_are_honoured():
    """activeConnector (off at 0.1 s: no force, and the data stay as they are, as in Exudyn, whose
    PostNewton skips an inactive connector; on again at 0.104 s) and the friction law
    (dryFriction, viscousFriction from 0.12 s) set by a pre-step user function: the compiled run
    re-reads the disc (Work.disc) and equals the Exudyn-evaluated run, in which Exudyn reads the
    changed item itself, at the same step to round-off."""
    out = []
    for evaluation in ("auto", "exudyn"):
        m = FM.rolling_disc(h=2e-3, T=0.2)
        o = m.foreignIndex

        def pre(mbs, t, o=o):
            if abs(t - 0.1) < 1e-9:
                mbs.SetObjectParameter(o, "activeConnector", False)
            elif abs(t - 0.104) < 1e-9:
                mbs.SetObjectParameter(o, "activeConnector", True)
            elif abs(t - 0.12) < 1e-9:
                mbs.SetObjectParameter(o, "dryFriction", [0.3, 0.4])
                mbs.SetObjectParameter(o, "viscousFriction", [0.1, 0.0])
            return True
        m.mbs.SetPreStepUserFunction(pre)
        y, _ = _solve(m, evaluation=evaluation)
        out.append(y)
        if evaluation == "auto":
            assert isinstance(m.mbs.sys["lieGroupSolver"], exl.LieGroupSolver)
    y0, _ = _solve(FM.rolling_disc(h=2e-3, T=0.2))
    assert np.abs(out[0] - y0).max() > 1e-3                     # the changes matter
    assert np.abs(out[0] - out[1]).max() < 1e-10, np.abs(out[0] - out[1]).max()


def _cart(h, native=False):
    from item_corpus import rollingDiscPenaltyCart
    mbs, ss = rollingDiscPenaltyCart.Build(1.0, h)
    ss.timeIntegration.verboseMode = 0
    ss.solution.sensors.active = False
    if native:
        exu.SolveDynamic(mbs, ss)
    else:
        exl.SolveDynamic(mbs, ss, showProgress=False)
    return FM.final_state(mbs)


@pytest.mark.slow
def test_exudyn_create_rolling_disc_penalty_test_model():
    """Exudyn's TestModels/createRollingDiscPenaltyTest.py (tests/item_corpus/rollingDiscPenaltyCart.py):
    a board on two wheels (revolute joints: index-1 rows beside the contact forces), each wheel
    on a penalty rolling disc with *no* proportional zone (dryFrictionProportionalZone = 0: Coulomb
    friction in the stored slip direction, a force that flips with the slip).  Such a law has no
    smooth solution to converge to at a method's order; both solvers converge at about first
    order (native generalized-alpha: step-halving differences 0.015, 0.0042 at 1e-4 ... 2.5e-5 s,
    measured).  Asserted: the compiled run converges towards the fine native run (errors fall
    with h; measured 0.061, 0.022, 0.013 at 2.5e-4, 1.25e-4, 6.25e-5 s, observed orders 1.45, 0.79,
    on a state of magnitude 12.6, the last one within 5x the reference's own step-halving
    difference 4.2e-3)."""
    ref = _cart(2.5e-5, native=True)
    natErr = np.abs(_cart(5e-5, native=True) - ref).max()
    errs = [np.abs(_cart(h) - ref).max() for h in (2.5e-4, 1.25e-4, 6.25e-5)]
    print(f"create rolling disc penalty: native step-halving difference {natErr:.2e}; compiled errors "
          f"{', '.join(f'{e:.3e}' for e in errs)}; observed orders "
          f"{', '.join(f'{math.log2(errs[i] / errs[i + 1]):.2f}' for i in range(2))}; magnitude {np.abs(ref).max():.1f}")
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 5 * natErr



@pytest.mark.slow
def test_rolling_coin_impact_at_the_scripts_step_with_the_method_chosen_by_itself():
    """The same script at its own step (1e-4 s) with SolveDynamic's default: RK4 until its stages blow
    up at the impact (0.045 s; the contact's damping, h d / m = 1), then ESDIRK3 from Exudyn's state
    at the start of that Exudyn step (bridge/method_choice.replace_after_failure) with the steps
    ``method='ESDIRK3'`` takes, adaptive (Exudyn's ``adaptiveStep``).  With fixed steps, as before,
    the friction, whose direction is the last step's slip (data coordinates), chattered after the
    impact: just after it (T = 0.0455 s) the state was 2.0 off generalized-alpha at 1e-6 s
    (velocities of about 15; fixed steps of 5e-5 s, measured by hand: 0.033).  Now 4.7e-3, as the
    named method; generalized-alpha at the script's step: 0.045."""
    T = 0.0455
    ref = _coin(1e-6, T, native=True)
    native = np.abs(_coin(1e-4, T, native=True) - ref).max()
    auto = np.abs(_coin(1e-4, T, method=None) - ref).max()
    named = np.abs(_coin(1e-4, T, method="ESDIRK3") - ref).max()
    print(f"\nrolling coin just after the impact (T = {T} s), against generalized-alpha at 1e-6 s: the method chosen "
          f"by itself {auto:.3g}, method='ESDIRK3' (adaptive steps) {named:.3g}, generalized-alpha at the script's "
          f"step {native:.3g}")
    assert auto < 0.5 * native
    assert auto == pytest.approx(named, rel=1e-6)

