"""Shared, once-per-process runs for the paper tests (tests/test_paper_*.py).

``lie_runs()`` integrates every model of :mod:`models` with MK-RK4 on SE3 and SO3xR3
at dt = 1e-2 and 1e-3 through the Exudyn bridge (:class:`exudyn_lie.bridge.LieGroupSolver`),
recording every step - exactly the runs of ``python -m exudyn_lie paper --quick``.
"""
import functools
import os
import warnings

import models

DTS = (1e-2, 1e-3)
GROUPS = ("SE3", "SO3xR3")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
README = os.path.join(ROOT, "README.md")


@functools.lru_cache(maxsize=None)
def lie_runs():
    """{model: (info, {(group, dt): RunData})}"""
    from exudyn_lie.analysis.runs import LieRunner
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for name in models.MODELS:
            mbs, info = models.build(name)
            runs = {}
            for g in GROUPS:
                lr = LieRunner(info, g)
                for dt in DTS:
                    runs[(g, dt)] = lr.run(dt, keep_states=info.exact is not None)
            out[name] = (info, runs)
    return out


def all_claims():
    """(model, claim index, claim) for every claim of every model (no runs needed)."""
    out = []
    for name in models.MODELS:
        info = models.build(name)[1]
        for k, c in enumerate(info.claims):
            out.append((name, k, c))
    return out
