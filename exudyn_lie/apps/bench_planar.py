"""Bench section ``planar``: planar mechanisms of 2D bodies.

* per step: the paper's planar four-bar made of 2D bodies (``models.planar_2d.four_bar``:
  ObjectRigidBody2D, four ObjectJointRevolute2D, 8 constraint rows) against the paper's 3D
  planar four-bar (``models.planar_four_bar``: RotVecLG bodies, three revolute joints and a
  spherical one, 18 rows of rank 17, rank-revealing solve), ``Simulator.Advance`` with MK-RK4,
  h = 1e-3 s, on the c-spaces SE3 (the 2D bodies on SE2) and SO3xR3 (SO2xR2).  Per step =
  (a run of 2n steps - a run of n steps) / n, medians of interleaved rounds;
* group maps: the planar closed forms (``se2.exp_into`` + ``se2.dexpinv_apply_into``) against
  SE(3)'s maps on the same planar screws (the restriction), per call from a numba loop.
"""
from __future__ import annotations

import time
import warnings

import numpy as np
from numba import njit

from ..groups import se2, se3


def _simulator(kind, group):
    from ..bridge import SceneFromExudyn
    from ..mbs import Simulator
    from .. import models
    from ..models import planar_2d
    if kind == "2D":
        mbs, info = planar_2d.build("four_bar")
    else:
        mbs, info = models.build("planar_four_bar")
        mbs.Assemble()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = Simulator(SceneFromExudyn(mbs), "RK4", group)
    return sim, (mbs, info)


def four_bar_per_step(n=500, h=1e-3, repeats=7):
    """{(kind, group): seconds per step} and the row counts."""
    sims = {(k, g): _simulator(k, g) for k in ("2D", "3D") for g in ("SE3", "SO3xR3")}
    times = {key: [] for key in sims}
    for key, (sim, _) in sims.items():          # warm-up (compiled already, caches)
        sim.SetInitialState()
        sim.Advance(10, h)
    for _ in range(repeats):
        for key, (sim, _) in sims.items():
            sim.SetInitialState()
            tic = time.perf_counter()
            sim.Advance(n, h)
            t1 = time.perf_counter() - tic
            sim.SetInitialState()
            tic = time.perf_counter()
            sim.Advance(2 * n, h)
            t2 = time.perf_counter() - tic
            times[key].append((t2 - t1) / n)
    out = {f"{k}/{g}": float(np.median(v)) for (k, g), v in times.items()}
    out["rows"] = {k: int(sims[(k, "SE3")][0].sd.nrows) for k in ("2D", "3D")}
    out["groups"] = {f"{k}/{g}": list(sims[(k, g)][0].groups) for (k, g) in sims}
    out.update(n=n, h=h, repeats=repeats)
    return out


@njit(cache=True)
def _maps_loop(which, Xs, reps, R, r, out):
    s = 0.0
    for it in range(reps):
        X = Xs[it % Xs.shape[0]]
        if which == 0:
            se2.exp_into(X, R, r)
            se2.dexpinv_apply_into(X, X, out)
        else:
            se3.exp_into(X, R, r)
            se3.dexpinv_apply_into(X, X, out)
        s += r[0] + out[3]
    return s


def planar_maps(n=10 ** 6, repeats=7, angle=1.0):
    """us per exp + dexpinv pair: SE2's closed forms vs SE3's maps on planar screws."""
    rng = np.random.default_rng(0)
    Xs = np.zeros((1024, 6))
    Xs[:, 2] = angle * rng.uniform(-1, 1, 1024)
    Xs[:, 3:5] = rng.normal(size=(1024, 2))
    R, r, out = np.zeros((3, 3)), np.zeros(3), np.zeros(6)
    res = {}
    for which in (0, 1):
        _maps_loop(which, Xs, 10, R, r, out)
    t = {0: [], 1: []}
    for _ in range(repeats):
        for which in (0, 1):
            tic = time.perf_counter()
            _maps_loop(which, Xs, n, R, r, out)
            t[which].append((time.perf_counter() - tic) / n * 1e6)
    res["SE2"] = float(np.median(t[0]))
    res["SE3 restricted"] = float(np.median(t[1]))
    res.update(n=n, angle=angle)
    return res


def planar_section(quick=False):
    return dict(fourBar=four_bar_per_step(n=200 if quick else 1000, repeats=3 if quick else 7),
                maps=planar_maps(n=10 ** 5 if quick else 10 ** 6, repeats=3 if quick else 7))


def report_lines(p):
    """The BENCHMARKS.md section (empty without the measurement)."""
    if not p:
        return []
    fb, mp = p["fourBar"], p["maps"]
    us = lambda x: f"{1e6 * x:.3g} us"   # noqa: E731
    L = ["## Planar mechanisms of 2D bodies", "",
         f"The paper's planar four-bar, per step of `Simulator.Advance` (MK-RK4, h = {fb['h']:g} s; per step = "
         f"(run of {2 * fb['n']} steps - run of {fb['n']}) / {fb['n']}, medians of {fb['repeats']} interleaved "
         f"rounds): made of 2D bodies (ObjectRigidBody2D, four ObjectJointRevolute2D, {fb['rows']['2D']} rows) "
         f"and the paper's 3D version (RotVecLG bodies, revolute x3 + spherical, {fb['rows']['3D']} rows, rank "
         f"{fb['rows']['3D'] - 1}).", "",
         "| c-space | 2D bodies (group) | 3D bodies | 2D / 3D |", "|---|---|---|---|"]
    for g, g2 in (("SE3", "SE2"), ("SO3xR3", "SO2xR2")):
        a, b = fb[f"2D/{g}"], fb[f"3D/{g}"]
        L.append(f"| {g} | {us(a)} ({g2}) | {us(b)} | {a / b:.2f} |")
    L += ["", f"Group maps, one exp + dexpinv pair per call from a numba loop over 1024 planar screws "
          f"(|theta| <= {mp['angle']:g}), {mp['n']} calls, median of rounds: SE2's closed forms "
          f"{mp['SE2']:.4f} us, SE(3)'s maps restricted to the plane {mp['SE3 restricted']:.4f} us.", ""]
    return L


if __name__ == "__main__":
    import json
    import sys
    res = planar_section(quick="--quick" in sys.argv)
    print(json.dumps(res, indent=1))
    print("\n".join(report_lines(res)))
