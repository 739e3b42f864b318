"""One stepper for fixed and adaptive steps (mbs/stepper.py): ``mk_steps`` is compiled once
per controller type, fixed steps with ``stepper.Control``, adaptive steps with
``adaptive.AdaptiveControl``; there is no second loop."""
import warnings

import numpy as np

from exudyn_lie import models
from exudyn_lie.bridge import SceneFromExudyn
from exudyn_lie.mbs import Simulator, adaptive, stepper


def _heavy_top(method):
    mbs, _ = models.build("heavy_top")
    mbs.Assemble()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Simulator(SceneFromExudyn(mbs), method, "SE3")


def _controller_types():
    return {sig[3].instance_class for sig in stepper.mk_steps.signatures}


def test_fixed_and_adaptive_steps_run_the_one_stepper():
    fixed = _heavy_top("DOPRI5")
    fixed.Advance(20, 1e-3)
    ad = _heavy_top("DOPRI5")
    ad.SetAdaptive(rtol=1e-8, atol=1e-8)
    Ro, ro, Vo = ad.AdvanceTo(0.02, np.array([0.01, 0.02]))
    assert {stepper.Control, adaptive.AdaptiveControl} <= _controller_types()
    assert not hasattr(adaptive, "mk_adaptive_steps")
    # the same motion: adaptive at a tight tolerance against 1 ms fixed steps (DOPRI5's error
    # at h = 1 ms on the heavy top is far below 1e-6)
    np.testing.assert_allclose(ro[-1], fixed.r, atol=1e-6)
    np.testing.assert_allclose(Vo[-1], fixed.V, atol=1e-5)
    assert ad.adaptiveCounters[0] > 0
