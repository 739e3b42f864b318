"""Bench section ``items``: what a point mass costs per step against a rigid body.

The same chain of ``n`` bodies hanging from the ground under gravity, once as point masses
(``Scene.AddPointMass``, group R3) and once as rigid bodies (SE3, SO3xR3), in two variants:

* ``springs``: consecutive members and the first one to the ground joined by point-to-point
  spring-dampers (no constraint rows);
* ``distance``: the same links as distance constraints (one index-1 row per link).

Per step of the compiled kernel (``Simulator.Advance``, MK-RK4, h = 1e-3 s): (a run of 2m
steps - a run of m steps) / m, so that the fixed cost of a call cancels; the variants are
interleaved in every round (the machine's speed drifts) and the median over the rounds is
reported.
"""
from __future__ import annotations

import time

import numpy as np

KINDS = ("point", "SE3", "SO3xR3")
VARIANTS = ("springs", "distance")


def chain(kind, variant, n=10):
    """A chain of ``n`` point masses or rigid bodies (see the module docstring)."""
    from ..mbs import GROUND, Scene
    sc = Scene(gravity=(0, 0, -9.81))
    for i in range(n):
        r0 = (0.5 * (i + 1), 0.0, 0.0)
        v0 = (0.0, 0.1 * i, 0.05)
        if kind == "point":
            sc.AddPointMass(1.0, r0=r0, vel0=v0)
        else:
            sc.AddBody(1.0, np.diag([0.01, 0.02, 0.03]), r0=r0, vel0=v0, omega0=(0.1, 0.2, 0.3))
    for i in range(n):
        a = GROUND if i == 0 else i - 1
        pa = (0.0, 0.0, 0.0)
        if variant == "springs":
            sc.AddSpringDamper(a, pa, i, (0, 0, 0), 500.0, 1.0, 0.5)
        else:
            sc.AddDistanceConstraint(a, pa, i, (0, 0, 0), 0.5)
    return sc


def per_step(m=200, h=1e-3, repeats=7, n=10):
    """{(kind, variant): median seconds per step} (see the module docstring)."""
    from ..mbs import Simulator
    sims = {}
    for v in VARIANTS:
        for k in KINDS:
            sims[(k, v)] = Simulator(chain(k, v, n), "RK4", "SE3" if k == "point" else k)
            sims[(k, v)].Advance(2, h)               # compile / warm up
    times = {key: [] for key in sims}
    for _ in range(repeats):
        for key, sim in sims.items():
            t0 = time.perf_counter()
            sim.Advance(m, h)
            t1 = time.perf_counter()
            sim.Advance(2 * m, h)
            t2 = time.perf_counter()
            times[key].append(((t2 - t1) - (t1 - t0)) / m)
    return dict(n=n, h=h, steps=m, repeats=repeats,
                perstep={f"{k}/{v}": float(np.median(times[(k, v)])) for (k, v) in sims})


def report_lines(p):
    """The BENCHMARKS.md section (empty without the measurement)."""
    if not p:
        return []
    us = lambda x: f"{1e6 * x:.3g} us"   # noqa: E731
    ps = p["perstep"]
    L = ["## 9. Point masses against rigid bodies",
         "",
         f"A chain of {p['n']} members hanging from the ground under gravity, linked by spring-dampers or by "
         f"distance constraints; compiled kernel (`Simulator.Advance`), MK-RK4, h = {p['h']:g} s; per step = "
         f"(a run of {2 * p['steps']} steps - a run of {p['steps']} steps) / {p['steps']}; medians of "
         f"{p['repeats']} interleaved rounds.",
         "",
         "| links | point masses (R3) | rigid bodies SE3 | rigid bodies SO3xR3 | point / cheaper rigid |",
         "|---|---|---|---|---|"]
    for v in VARIANTS:
        pt, se, so = ps[f"point/{v}"], ps[f"SE3/{v}"], ps[f"SO3xR3/{v}"]
        L.append(f"| {v} | {us(pt)} | {us(se)} | {us(so)} | {pt / min(se, so):.2f} |")
    L.append("")
    return L


if __name__ == "__main__":
    print("\n".join(report_lines(per_step())))
