"""BLAS runs on one thread inside ``exl.SolveDynamic`` (bridge/blas_threads.py) and gets its
threads back afterwards.  The model is the segment beam of test_zero_inertia_2d.py: it takes
the Exudyn-evaluated path, whose dense KKT solve is numpy's LAPACK."""
import numpy as np
import pytest

threadpoolctl = pytest.importorskip("threadpoolctl")

import exudyn_lie as exl
from test_zero_inertia_2d import build


def _blas_threads():
    """{library file: threads} of the BLAS libraries loaded now."""
    return {lib["filepath"]: lib["num_threads"] for lib in threadpoolctl.threadpool_info() if lib["user_api"] == "blas"}


def test_one_blas_thread_inside_the_solve_and_the_user_limit_back_after():
    before = _blas_threads()
    if not before:
        pytest.skip("numpy's BLAS is not one threadpoolctl knows")
    mbs, ss, s = build()
    ss.timeIntegration.numberOfSteps, ss.timeIntegration.endTime = 20, 0.02
    seen = []

    def preStep(mbs, t):
        seen.append(_blas_threads())
        return True

    mbs.SetPreStepUserFunction(preStep)
    with threadpoolctl.threadpool_limits(limits=2, user_api="blas"):
        exl.SolveDynamic(mbs, ss, evaluation="exudyn")
        after = _blas_threads()
    # numpy's BLAS, loaded before the call (numba's first compilation may load scipy's during it,
    # which the kernels do not call)
    assert seen and all(n[f] == 1 for n in seen for f in before)
    assert all(after[f] == 2 for f in before)
    assert np.all(np.isfinite(mbs.GetSensorStoredData(s)))
