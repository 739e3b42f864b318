"""Scripts with items the compiled kernel does not read (issue 17, Checks).

Each script of :mod:`foreign_models` (one foreign item kind each, coupled to a RotVecLG
rigid body) goes through ``exl.SolveDynamic`` unchanged: the solver must pick the path on
which Exudyn evaluates the model, say so in exactly one warning naming the item, and
either

* agree with a fine native reference to the order of the method (MK-RK4: the errors at
  h and h/2 fall by 2^4 = 16; asserted: observed order log2(e(h)/e(h/2)) in [3.4, 4.8],
  with both errors at least 10x the reference's own error estimate, so that the order is
  the method's and not the reference's), or
* stop with a StepSizeError that names a stable step (the ANCF cables and the
  geometrically exact beam at the script's step 1e-2 s; the FFRF truss runs there), after
  which a run at that step works.

The references are computed here, never stored: Exudyn's generalized-alpha (spectral
radius 0.9, order 2) at h0 ... h0/8, Richardson-extrapolated (``native_reference``; its own
error is the distance between two extrapolations), or Exudyn's explicit RK44 for the
scripts without joints (``native_reference_rk``; Exudyn's implicit solvers start ODE1
coordinates with a zero rate, which makes them first order there).
"""
import functools
import math
import re
import warnings

import numpy as np
import pytest
from exudyn.utilities import MarkerBodyRigid

import exudyn_lie as exl
from exudyn_lie.bridge import BridgeError
from exudyn_lie.errors import StepSizeError

import foreign_models as FM
from test_bridge_errors import assert_unchanged, snapshot

# name: (reference kind, h0 of the reference, h of the Lie group run, script step is unstable)
CASES = {
    "cable2d_pendulum": ("ga", 5e-5, 5e-4, True),
    "cable3d_pendulum": ("ga", 5e-5, 1e-3, True),
    "sphere_contact": ("ga", 1e-4, 4e-3, False),
    "generic_ode2": ("ga", 1e-4, 4e-3, False),
    "generic_ode1": ("rk", 2.5e-4, 1e-3, False),
    "hydraulic_arm": ("rk", 1e-3, 4e-3, False),
    "beam3d_pendulum": ("ga", 5e-5, 5e-4, True),
    "kinematic_tree": ("ga", 1e-4, 4e-3, False),
    "ffrf_pendulum": ("ga", 1e-4, 1e-3, True),
}
SLOW = {"beam3d_pendulum", "ffrf_pendulum", "kinematic_tree", "cable3d_pendulum", "cable2d_pendulum"}
ORDER_BAND = (3.4, 4.8)


def _param(names):
    return [pytest.param(n, marks=pytest.mark.slow) if n in SLOW else n for n in names]


def _T(name):
    return FM.BUILDERS[name].__defaults__[1]


@functools.lru_cache(maxsize=None)
def reference(name):
    kind, h0, _, _ = CASES[name]
    if kind == "rk":
        return FM.native_reference_rk(FM.BUILDERS[name], h0, _T(name))
    return FM.native_reference(FM.BUILDERS[name], h0, _T(name))


def solve_lie(model, **kw):
    """exl.SolveDynamic on the script; returns the final state and the warnings naming the
    foreign item."""
    short = model.foreign                       # e.g. 'ANCFCable2D' (Exudyn's objectType, without 'Object')
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        exl.SolveDynamic(model.mbs, model.simulationSettings, showProgress=False, **kw)
    naming = [str(w.message) for w in rec if short in str(w.message)]
    return FM.final_state(model.mbs), naming


@pytest.mark.parametrize("name", _param(CASES))
def test_native_reference_is_fine(name):
    """The reference itself: the native runs converge at their order, and the extrapolated
    reference's own error is far below the Lie group runs' errors (checked in the next test)."""
    kind = CASES[name][0]
    y, err, info = reference(name)
    print(f"{name}: native {kind} diffs {['%.2e' % d for d in info['diffs']]}, order {info['order']:.2f}, "
          f"reference error {err:.2e}")
    assert np.all(np.isfinite(y))
    nominal = 4.0 if kind == "rk" else 2.0
    assert abs(info["order"] - nominal) < 0.3
    assert err < 1e-6


@pytest.mark.parametrize("name", _param(CASES))
def test_lie_group_run_agrees_with_fine_native_reference_to_order_4(name):
    _, _, h, _ = CASES[name]
    T = _T(name)
    ref, refErr, _ = reference(name)
    errs = []
    for hh in (h, h / 2):
        m = FM.BUILDERS[name](h=hh, T=T)
        y, naming = solve_lie(m)
        assert len(naming) == 1, f"{name}: expected one warning naming {m.foreign}, got {naming}"
        assert np.all(np.isfinite(y))
        errs.append(FM.state_error(y, ref))
        # the script's sensors: one row per step, the last at T with the final state
        data = m.mbs.GetSensorStoredData(m.sensors["position"])
        assert data.shape[0] == round(T / hh) + 1 and data[-1, 0] == pytest.approx(T)
        np.testing.assert_allclose(data[-1, 1:], m.mbs.GetSensorValues(m.sensors["position"]), rtol=0, atol=1e-12)
    order = math.log2(errs[0] / errs[1])
    print(f"{name}: MK-RK4 h = {h:g}: error {errs[0]:.3e}; h/2: {errs[1]:.3e}; observed order {order:.2f}; "
          f"reference error {refErr:.1e}")
    assert errs[1] > 10 * refErr, "the reference is not fine enough to measure the order"
    assert ORDER_BAND[0] <= order <= ORDER_BAND[1]


FLEXIBLE = [n for n, c in CASES.items() if c[3]]


@pytest.mark.parametrize("name", _param(FLEXIBLE))
def test_flexible_body_at_the_script_step_runs_or_names_a_stable_step(name):
    """The flexible bodies at the script's step (1e-2 s): either it is within RK4's stability
    limit and the run agrees with the reference, or a StepSizeError names a step, and the
    runs at that step h1 and at h1/2 work: finite, and converging (the error at h1/2 below
    the error at h1; near the stability limit RK4's own damping of the stiff modes, not
    its h^4 term, dominates the error, |R(i h omega)| = 0.83 per step at h omega = 2.5; the
    order-4 check is the test above)."""
    T = _T(name)
    m = FM.BUILDERS[name](T=T)
    assert m.scriptStep == 1e-2
    try:
        y, naming = solve_lie(m)
        h1, stopped = m.scriptStep, None
    except StepSizeError as e:
        stopped = str(e)
        found = re.search(r"step size of ([0-9.eE+-]+) s", stopped)
        assert found, stopped
        hs = float(found.group(1))
        assert 0 < hs < m.scriptStep
        h1 = T / math.ceil(T / hs)
        y, naming = solve_lie(FM.BUILDERS[name](h=h1, T=T))
    assert len(naming) == 1 and np.all(np.isfinite(y))
    y2, _ = solve_lie(FM.BUILDERS[name](h=h1 / 2, T=T))
    ref, _, _ = reference(name)
    e1, e2 = FM.state_error(y, ref), FM.state_error(y2, ref)
    print(f"{name}: script step 1e-2 s: " + (f"StepSizeError: {stopped}" if stopped else "runs")
          + f"; h1 = {h1:.3g} s: error {e1:.2e}; h1/2: {e2:.2e}")
    assert np.all(np.isfinite(y2))
    assert e2 < e1


# --------------------------------------------------------------------------- bad input
def _bad(name, edit):
    """The script ``name`` with ``edit(model)`` applied (and mbs assembled again)."""
    m = FM.BUILDERS[name](h=1e-3, T=0.01)
    edit(m)
    m.mbs.Assemble()
    return m


def _general_contact(m):
    mbs = m.mbs
    body = next(i for i in range(mbs.systemData.NumberOfObjects()) if mbs.GetObject(i)["objectType"] == "RigidBody")
    gc = mbs.AddGeneralContact()
    gc.SetFrictionPairings(np.zeros((1, 1)))
    gc.SetSearchTreeCellSize(numberOfCells=[2, 2, 2])
    gc.SetSearchTreeBox([-1, -1, -1], [1, 1, 1])
    gc.AddSphereWithMarker(mbs.AddMarker(MarkerBodyRigid(bodyNumber=body)), radius=0.05, contactStiffness=1e3,
                           contactDamping=0.0, frictionMaterialIndex=0)


def _nan_node(m):
    n = next(i for i in range(m.mbs.systemData.NumberOfNodes()) if m.mbs.GetNode(i)["nodeType"] == "GenericODE2")
    m.mbs.SetNodeParameter(n, "initialCoordinates", [float("nan"), 0.0])


def _sliding_joint(m):
    """An ObjectJointSliding2D along the cable (Exudyn's ANCFslidingJoint2D example) with
    constrainRotation=True, whose rotation row Exudyn's Jacobian gives without its dependence on
    the sliding coordinate: refused (both formulations without it are integrated,
    tests/test_sliding_joint2d.py)."""
    from exudyn.utilities import MarkerBodyCable2DCoordinates, NodeGenericData, ObjectJointSliding2D
    mbs = m.mbs
    els = [i for i in range(mbs.systemData.NumberOfObjects()) if mbs.GetObject(i)["objectType"] == "ANCFCable2D"]
    body = next(i for i in range(mbs.systemData.NumberOfObjects()) if mbs.GetObject(i)["objectType"] == "RigidBody")
    L = mbs.GetObject(els[0])["length"]
    cm = [mbs.AddMarker(MarkerBodyCable2DCoordinates(bodyNumber=e)) for e in els]
    nd = mbs.AddNode(NodeGenericData(initialCoordinates=[0, 0.0], numberOfDataCoordinates=2))
    mbs.AddObject(ObjectJointSliding2D(name="slider", markerNumbers=[mbs.AddMarker(MarkerBodyRigid(bodyNumber=body)),
                                                                     cm[0]],
                                       slidingMarkerNumbers=cm, slidingMarkerOffsets=[i * L for i in range(len(els))],
                                       nodeNumber=nd, constrainRotation=True))


BAD = {
    "GeneralContact on the compiled path": ("generic_ode2", _general_contact, dict(evaluation="compiled"),
                                            r"GeneralContact.*evaluation='auto'"),
    "non-finite initial coordinate of the foreign item's node": ("generic_ode2", _nan_node, {},
                                                                 r"node \d+ .*NodeGenericODE2.*not finite"),
    "sliding joint, constrained rotation": ("cable2d_pendulum", _sliding_joint, {},
                                            r"object \d+ \('slider'\) ObjectJointSliding2D: constrainRotation=True"),
    "evaluation='compiled' with a foreign item": ("generic_ode2", lambda m: None, dict(evaluation="compiled"),
                                                  r"ObjectGenericODE2 is not supported"),
    "unknown evaluation": ("generic_ode2", lambda m: None, dict(evaluation="python"), r"evaluation must be"),
    "unknown stabilization with a foreign item": ("cable2d_pendulum", lambda m: None,
                                                  dict(stabilization="baumgarte"), r"unknown stabilization"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_invalid_foreign_setup_is_refused_before_mbs_is_touched(case):
    name, edit, kw, match = BAD[case]
    m = _bad(name, edit)
    snap = snapshot(m.mbs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(BridgeError, match=match):
            exl.SolveDynamic(m.mbs, m.simulationSettings, showProgress=False, **kw)
    assert_unchanged(m.mbs, snap)



@pytest.mark.slow
def test_strongly_damped_cable_gets_a_stable_step_from_the_damping():
    """The 3D cable with bending damping 1e-2: its fastest mode is a real eigenvalue
    (Exudyn's ComputeODE2Eigenvalues, damping included), far beyond the oscillating modes
    (820 rad/s); RK4 is stable on the negative real axis up to h |lambda| = 2.785.  At the
    script's step the StepSizeError must name a step within that limit, and the run at the
    named step works and agrees with the native reference (RK4 at ~2e-4 s: ~1e-6; 1e-4
    asserted)."""
    T = 0.3

    def build(h=1e-2, T=T):
        return FM.cable3d_pendulum(h=h, T=T, bendingDamping=1e-2)

    m = build()
    ev, _ = m.mbs.ComputeODE2Eigenvalues(computeComplexEigenvalues=True, useAbsoluteValues=False,
                                        constrainedCoordinates=[], convert2Frequencies=False, useSparseSolver=False)
    lam = float(np.abs(np.asarray(ev)).max())
    assert lam > 1e4                                     # the damped mode, not the 820 rad/s oscillation
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(StepSizeError) as info:         # (named: else ESDIRK3 runs, test_implicit.py)
            exl.SolveDynamic(m.mbs, m.simulationSettings, showProgress=False, method="RK4")
    found = re.search(r"step size of ([0-9.eE+-]+) s", str(info.value))
    assert found, str(info.value)
    hs = float(found.group(1))
    print(f"|lambda| = {lam:.4g} 1/s, RK4 limit {2.785 / lam:.3g} s; suggested {hs:.3g} s")
    assert hs * lam <= 2.785
    y, naming = solve_lie(build(h=T / math.ceil(T / hs)))
    assert len(naming) == 1 and np.all(np.isfinite(y))
    ref, refErr, _ = FM.native_reference(build, 5e-5, T)
    err = FM.state_error(y, ref)
    print(f"run at {hs:.3g} s: error {err:.2e} (reference error {refErr:.1e})")
    assert err < 1e-4
