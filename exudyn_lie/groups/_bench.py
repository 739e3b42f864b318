"""Micro-benchmark of the group hot path (not a test).

    /tmp/venv/bin/python -c "from exudyn_lie.groups._bench import main; main()"
"""
import time

import numpy as np
from numba import njit

from . import se3


@njit(cache=True)
def _loop_se3_exp_dexpinv(Xs, Vs, n):
    """n evaluations of se3.exp_into + se3.dexpinv_apply_into (MK stage pattern)."""
    R = np.empty((3, 3))
    r = np.empty(3)
    k = np.empty(6)
    acc = 0.0
    m = Xs.shape[0]
    for it in range(n):
        j = it % m
        X = Xs[j]
        se3.exp_into(X, R, r)
        se3.dexpinv_apply_into(X, Vs[j], k)
        acc += R[0, 1] + r[2] + k[0] + k[5]
    return acc


def bench_se3_exp_dexpinv(n=10 ** 6, angle=0.05, repeats=5, seed=0):
    """Median over `repeats` of the cost in microseconds of one compiled
    se3.exp_into + se3.dexpinv_apply_into pair, called from an njit loop.

    The arguments cycle through 1024 random screws with |xi| = `angle` (the size
    of a Munthe-Kaas stage increment h*V; the default takes the Taylor branch,
    angle > 0.61 exercises the closed forms of exp, angle > 2.59 those of dexpinv).
    """
    rng = np.random.default_rng(seed)
    Xs = rng.normal(size=(1024, 6))
    Xs[:, 0:3] *= angle / np.linalg.norm(Xs[:, 0:3], axis=1)[:, None]
    Vs = rng.normal(size=(1024, 6))
    _loop_se3_exp_dexpinv(Xs, Vs, 10)          # compile / load from cache
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        _loop_se3_exp_dexpinv(Xs, Vs, n)
        times.append(time.perf_counter() - t0)
    return float(np.median(times)) / n * 1e6


def main():
    for angle in (0.05, 1.0, 3.0):
        print("SE3 exp_into + dexpinv_apply_into, |xi| = %4.2f: %.4f us/call"
              % (angle, bench_se3_exp_dexpinv(angle=angle)))


if __name__ == "__main__":
    main()
