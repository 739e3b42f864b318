"""One BLAS thread inside ``exudyn_lie.SolveDynamic``.

The Exudyn-evaluated path solves dense systems of tens to hundreds of unknowns per stage
(numpy's LAPACK: the KKT matrix, Newton matrices).  A multi-threaded BLAS (numpy's OpenBLAS
starts one thread per core) gains nothing at these sizes on an idle machine and loses a
factor of several on a busy one, where its threads wait for cores that another process
holds: two copies of ``kinematicTreeAndMBStest.py`` run side by side on two cores took
2.6 s for a solve that takes 0.57 s with one BLAS thread, and 0.57 s for both with one.
The limit is lifted when the call returns, so the user's own numpy work keeps its threads.
"""
from __future__ import annotations

import functools


def one_blas_thread(fn):
    """``fn`` with BLAS limited to one thread while it runs (threadpoolctl, which knows
    OpenBLAS, MKL and BLIS; without it, or without a BLAS it recognises, ``fn`` runs as is)."""
    @functools.wraps(fn)
    def call(*args, **kwargs):
        try:
            from threadpoolctl import threadpool_limits
        except ImportError:                                  # pragma: no cover - a dependency
            return fn(*args, **kwargs)
        with threadpool_limits(limits=1, user_api="blas"):
            return fn(*args, **kwargs)
    return call
