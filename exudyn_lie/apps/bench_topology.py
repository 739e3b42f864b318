"""Cost per step against the topology of the joint graph: ``python -m exudyn_lie bench
--sections topology``.

Four families of N rigid bars (mass 1 kg, length 0.5 m, slender-rod inertia about the
COM, the body frame at the COM) joined by spherical joints, gravity along -z, integrated
with MK-RK4 on SE(3) by the compiled stepper (``Simulator.Advance``) at h = 1e-4:

* ``chain``: bar i hangs from bar i-1, bar 0 from the ground (a path graph);
* ``star``: every bar hangs from one hub bar (the hub from the ground): one body carries
  N - 1 joints;
* ``tree``: a binary tree, bar i hangs from bar (i - 1) // 2;
* ``ladder``: two chains of N/2 bars side by side, rung k (a ball joint between the k-th
  bars of both chains, k >= 1) closing N/2 - 1 loops.

The index-1 solve is chosen when the scene is compiled (``mbs.compiled.choose_solve``, ``solve_plan``): the
tree solve (``mbs.tree_solve``, linear in N) for the star and the binary tree, the band
Cholesky for the chain (bandwidth 5) and the ladder (loops); the ``solve`` column says which.

Reported: us per step and per body, the exponent fitted to log(us per step) against
log N (least squares over N >= 20), the star's cost per body against the chain's at
N = 160, and the ladder's cost against its number of loops.  Targets: exponent
<= 1.1 for every tree (chain, star, binary tree), star per body <= 2x chain per body at
N = 160.  Times: medians of interleaved repetitions (``time.perf_counter``).
"""
from __future__ import annotations

import time
import warnings

import numpy as np

H = 1e-4
NS = (10, 20, 40, 80, 160, 320, 640, 1000)
NS_QUICK = (10, 20, 40, 80, 160)
MAX_N = {}                      # (the star was capped at 320 while its band Cholesky cost ~N^3 per step)
TARGET_EXPONENT = 1.1
TARGET_STAR_OVER_CHAIN = 2.0
L = 0.5


def parent_of(kind, i, N):
    """Parent body of bar i (-1: the ground) in a tree family."""
    if i == 0:
        return -1
    if kind == "chain":
        return i - 1
    if kind == "star":
        return 0
    if kind == "tree":
        return (i - 1) // 2
    raise KeyError(kind)


def build_scene(kind, N):
    """The scene of family ``kind`` with N bars (module docstring)."""
    from ..mbs import GROUND, Scene
    sc = Scene(gravity=[0, 0, -9.81])
    J = np.diag([1.0 / 12 * L * L, 1.0 / 12 * L * L, 1e-4])          # slender bar along its z axis

    def bar(top, tilt):
        # a bar hanging from the point `top`, tilted by `tilt` about x: COM half a length below
        c, s = np.cos(tilt), np.sin(tilt)
        R0 = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
        axis = R0 @ np.array([0, 0, -1.0])
        return sc.AddBody(1.0, J, R0=R0, r0=top + 0.5 * L * axis), top + L * axis

    if kind == "ladder":
        half = max(N // 2, 1)
        ends = {}
        for side, x in ((0, 0.0), (1, 0.6)):
            top = np.array([x, 0.0, 0.0])
            prev = GROUND
            for k in range(half):
                b, bottom = bar(top, 0.05 * (1 + side) * (k % 3 + 1))
                sc.AddSphericalJoint(prev, b, position=top)
                ends[(side, k)] = (b, bottom)
                prev, top = b, bottom
        # rung k: a ball joint between bar k of both sides at the lower end of side 0's bar
        # (a point of both bodies in the initial state, so the rungs start consistent)
        for k in range(1, half):
            b0, p0 = ends[(0, k)]
            b1, _ = ends[(1, k)]
            sc.AddSphericalJoint(b0, b1, position=p0)
        return sc
    tops = {-1: np.zeros(3)}
    for i in range(N):
        p = parent_of(kind, i, N)
        top = tops[p]
        b, bottom = bar(top, 0.1 + 0.3 * ((i * 7) % 5) / 5.0)
        sc.AddSphericalJoint(GROUND if p < 0 else p, b, position=top)
        tops[i] = bottom
    return sc


def simulator(kind, N):
    from ..mbs import Simulator
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Simulator(build_scene(kind, N), "RK4", "SE3", projectInitial=True)


def time_per_step(sim, budget=0.2, repeat=3):
    """us per step: ``repeat`` runs of about ``budget`` seconds each, median."""
    sim.Advance(2, H)
    t0 = time.perf_counter()
    sim.Advance(3, H)
    per = max((time.perf_counter() - t0) / 3, 1e-7)
    n = int(np.clip(budget / per, 3, 20000))
    out = []
    for _ in range(repeat):
        sim.SetInitialState()
        t0 = time.perf_counter()
        sim.Advance(n, H)
        out.append((time.perf_counter() - t0) / n * 1e6)
    return float(np.median(out))


def fit_exponent(N, t):
    N, t = np.asarray(N, float), np.asarray(t, float)
    ok = (N >= 20) & np.isfinite(t)
    if ok.sum() < 2:
        return np.nan
    return float(np.polyfit(np.log(N[ok]), np.log(t[ok]), 1)[0])


def measure(Ns=NS, budget=0.2, repeat=3, log=None):
    kinds = ("chain", "star", "tree", "ladder")
    rows = {k: {} for k in kinds}
    for N in Ns:
        for k in kinds:                                   # interleaved over the families
            if N > MAX_N.get(k, 10 ** 9):
                continue
            sim = simulator(k, N)
            us = time_per_step(sim, budget, repeat)
            solve = "band" if sim.wk.tplan is None else "tree"
            rows[k][N] = dict(us=us, perBody=us / N, rows=int(sim.sd.nrows), bandwidth=int(sim.sd.bandwidth),
                              loops=(max(N // 2, 1) - 1) if k == "ladder" else 0, solve=solve)
            if log:
                log(f"topology {k:6s} N = {N:4d}: {us:9.1f} us/step, {us / N:7.2f} us/body, "
                    f"rows {sim.sd.nrows}, bandwidth {sim.sd.bandwidth}, {solve} solve")
    fits = {k: fit_exponent(list(r), [d["us"] for d in r.values()]) for k, r in rows.items()}
    res = dict(h=H, rows=rows, fits=fits)
    if 160 in rows["star"] and 160 in rows["chain"]:
        res["starOverChain160"] = rows["star"][160]["perBody"] / rows["chain"][160]["perBody"]
    return res


def run_section(cfg, log):
    from .bench import loadavg
    res = measure(NS_QUICK if cfg.quick else NS, budget=0.1 if cfg.quick else 0.3, repeat=3, log=log)
    res["load"] = loadavg()
    return res


def target_lines(res):
    if not res:
        return []
    L_ = []
    for k in ("chain", "star", "tree"):
        e = res["fits"][k]
        L_.append(f"| topology, {k}: cost per step ~ N^p with p <= {TARGET_EXPONENT:g} (N >= 20) | p = {e:.2f} | "
                  f"{'yes' if e <= TARGET_EXPONENT else 'no'} |")
    r = res.get("starOverChain160")
    if r is not None:
        L_.append(f"| topology, star of 160 bodies per body <= {TARGET_STAR_OVER_CHAIN:g}x the chain per body | {r:.3g}x | "
                  f"{'yes' if r <= TARGET_STAR_OVER_CHAIN else 'no'} |")
    L_.append(f"| topology, ladder: cost vs loop count (informative) | p = {res['fits']['ladder']:.2f} | - |")
    return L_


def report_lines(res):
    L_ = ["## Topologies", "",
          f"MK-RK4 SE3, h = {res['h']:g}, spherical joints; load average {res.get('load', '?')}.", "",
          "| family | N | loops | rows | bandwidth | solve | us per step | us per body |",
          "|---|---|---|---|---|---|---|---|"]
    for k, r in res["rows"].items():
        for N, d in sorted(r.items()):
            L_.append(f"| {k} | {N} | {d['loops']} | {d['rows']} | {d['bandwidth']} | {d.get('solve', '-')} | "
                      f"{d['us']:.4g} | {d['perBody']:.3g} |")
    L_ += ["", "Fitted exponents (N >= 20): " + ", ".join(f"{k} {e:.2f}" for k, e in res["fits"].items()), ""]
    return L_


if __name__ == "__main__":
    import sys
    Ns = tuple(int(x) for x in sys.argv[1].split(",")) if len(sys.argv) > 1 else NS_QUICK
    r = measure(Ns, budget=0.1, log=print)
    print("exponents", {k: round(v, 3) for k, v in r["fits"].items()}, "star/chain per body at 160:",
          r.get("starOverChain160"))
