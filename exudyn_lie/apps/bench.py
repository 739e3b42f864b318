"""``python -m exudyn_lie bench``: run time against error, versus Exudyn's native solvers.

Sections (``--sections``, default all):

* ``wp``      work-precision diagrams: CPU time of the time loop against the final
  configuration error, per model, for exudyn_lie (SE3, SO3xR3, auto x RK4, DOPRI5,
  RK6; fixed steps) and Exudyn's native solvers (GeneralizedAlpha, its modified-Newton
  variant and TrapezoidalIndex2 for constrained models; RK44, RK67, DOPRI5 with
  RotVecLG nodes for free bodies).  The reference is exudyn_lie RK6 on SE3 at a very
  small step, cross-checked by DOPRI5 on SO3xR3 at the same step.  Step sizes are
  refined (and coarsened) round by round until every curve spans the accuracy band
  1e-4 ... 1e-8 or hits the time budget;
* ``perstep`` cost of one step at h = 1e-3 (MK-RK4 against one generalized-alpha step);
* ``scaling`` chains of N boxes with spherical joints, cost per step against N;
* ``startup`` first run with an empty numba cache (compile) and a warm start, in
  fresh interpreters: import time and the first solve's fixed cost (:mod:`.bench_startup`);
* ``overhead`` the drop-in ``exl.SolveDynamic`` (Exudyn's loop, sensors, solution file,
  write-back) against the integration alone, on the heavy top;
* ``groups``  one compiled SE(3) exp + dexpinv evaluation (the group work per body and stage);
* ``mujoco``  MuJoCo (optional, ``pip install .[bench]``) as a peer on the heavy top and the
  double pendulum: agreement, cost per step, work-precision
  (:mod:`exudyn_lie.apps.bench_mujoco`; skipped with one line without MuJoCo).
* ``planar``  the planar four-bar of 2D bodies against the 3D planar four-bar, per step, and
  SE2's maps against SE3's on planar screws (:mod:`.bench_planar`).
* ``params``  parameters changed during a solve: serialRobotTest's PD controller (12 load
  vectors per step) against the same model without it (:mod:`.bench_params`).
* ``items``   a point mass against a rigid body per step (:mod:`.bench_items`).
* ``userfunctions``  Python user functions: the heavy top with a zero user load, a PD
  torque, a spring force and a force at a point, overhead per call against the compiled step
  (:mod:`.bench_userfunctions`).
* ``topology``  chain, star, binary tree and ladder of N bodies: cost per step against N,
  fitted exponents (:mod:`.bench_topology`).
* ``evaluated``  the path on which Exudyn evaluates the model (items the kernel does not read):
  chains of 1, 10, 50 bodies with one foreign item, per step and per stage, against the
  compiled path and generalized-alpha (:mod:`.bench_evaluated`).
* ``stiff``  stiff models (a chain on stiff spring-dampers, an ANCF cable with a rigid body, a
  penalty contact): the implicit ESDIRK3 against Exudyn's generalized-alpha, work against
  precision (:mod:`.bench_stiff`).
* ``particles``  a particle system of GeneralContact spheres (the evaluated path): time per step and
  time at equal error against Exudyn's explicit RK44 and explicit Euler (:mod:`.bench_particles`).

Every sweep runs through Exudyn's ``exudyn.processing.ParameterVariation`` with
multiprocessing (:func:`exudyn_lie.apps.bench_runs.sweep`); every time is the
median over repeated runs inside one worker; competitors are compared as ratios of
times measured in the same invocation.  Writes ``BENCHMARKS.md``, ``bench_results.json``
and PNG figures into ``--out``.
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import sys
import time

import numpy as np

from . import bench_runs as BR
from . import bench_wp as WP
from . import versions

EXL_GROUPS = ("SE3", "SO3xR3", "auto")
EXL_METHODS = ("RK4", "DOPRI5", "RK6")
NATIVE_CONSTRAINED = ("GeneralizedAlpha", "GeneralizedAlpha-mN", "TrapezoidalIndex2")
NATIVE_FREE = ("RK44", "RK67", "DOPRI5")
EPS_LEVELS = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8)
SECTIONS = ("wp", "perstep", "scaling", "startup", "overhead", "groups", "mujoco", "params", "items",
            "userfunctions", "topology", "adaptive", "planar", "evaluated", "check",
            "stabilization", "stiff", "particles")
TARGET_RATIO = 10.0
# absolute per-step targets (MK-RK4, SE3, median step, this 2-core machine)
KERNEL_STEP_TARGETS_US = {"heavytop": 3.0, "doublependulum": 6.0}
OUTPUT_KINDS = {"sensor": "a position sensor", "sensor+file": "sensor + solution file"}


# --------------------------------------------------------------------------- configuration
class Config:
    def __init__(self, args):
        q = args.quick
        self.quick = q
        self.models = [BR.resolve_model(m) for m in args.models.split(",") if m.strip()] if args.models else (
            ["heavytop", "doublependulum"] if q else list(BR.BENCH_MODELS))
        self.T = float(args.end_time) if args.end_time else (0.1 if q else 1.0)
        self.repeat = int(args.repeat) if args.repeat else (3 if q else 5)
        self.budget = float(args.budget) if args.budget else (0.3 if q else 10.0)
        self.rounds = int(args.rounds) if args.rounds else (3 if q else 8)
        self.jobs = int(args.jobs) if args.jobs else (os.cpu_count() or 1)
        self.href = float(args.href) if args.href else (1e-4 if q else 2.5e-5)
        self.sections = [s.strip() for s in args.sections.split(",")] if args.sections else (
            list(SECTIONS))
        for s in self.sections:
            if s not in SECTIONS:
                raise SystemExit(f"bench: unknown section {s!r}; choose from {', '.join(SECTIONS)}")
        self.chainN = [int(x) for x in args.chain.split(",")] if args.chain else (
            [1, 2, 4, 8] if q else [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000])
        self.gaChainMax = int(args.ga_chain_max) if args.ga_chain_max else (8 if q else 1000)
        self.coldStart = not q if args.cold is None else args.cold
        self.out = os.path.abspath(args.out)
        self.figdir = os.path.join(self.out, "bench_figures")
        self.progress = not args.no_progress
        self.exlGroups = tuple(args.groups.split(",")) if args.groups else EXL_GROUPS
        self.exlMethods = tuple(args.methods.split(",")) if args.methods else EXL_METHODS


def parse_args(argv):
    p = argparse.ArgumentParser(prog="python -m exudyn_lie bench", description=__doc__.split("\n\n")[0].replace("``", ""),
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="short version: T = 0.1 s, heavy top and double "
                   "pendulum, small budgets, chains up to N = 8, warm start only")
    p.add_argument("--models", default=None, help=f"comma list of models ({', '.join(BR.BENCH_MODELS)})")
    p.add_argument("--sections", default=None, help=f"comma list of {', '.join(SECTIONS)} (default all)")
    p.add_argument("--end-time", default=None, help="integration time T of the work-precision runs "
                   "[s] (default 1, quick 0.1)")
    p.add_argument("--repeat", default=None, help="repetitions per timing (median; default 5, quick 3; "
                   "runs estimated over 1 s use 3)")
    p.add_argument("--budget", default=None, help="largest time of one run [s] when refining a curve "
                   "(default 10, quick 0.3)")
    p.add_argument("--rounds", default=None, help="refinement rounds (default 8, quick 3)")
    p.add_argument("--jobs", default=None, help="worker processes of ParameterVariation (default: all cores)")
    p.add_argument("--href", default=None, help="step of the reference solution (default 2.5e-5, quick 1e-4)")
    p.add_argument("--chain", default=None, help="comma list of chain lengths N for the scaling section")
    p.add_argument("--ga-chain-max", default=None, help="largest N of the generalized-alpha chain runs")
    p.add_argument("--groups", default=None, help="exudyn_lie groups (default SE3,SO3xR3,auto)")
    p.add_argument("--methods", default=None, help="exudyn_lie methods (default RK4,DOPRI5,RK6)")
    cold = p.add_mutually_exclusive_group()
    cold.add_argument("--cold", dest="cold", action="store_true", default=None,
                      help="measure the cold start (empty numba cache; default unless --quick)")
    cold.add_argument("--no-cold", dest="cold", action="store_false")
    p.add_argument("--wait-quiet", type=float, default=0.0, help="wait up to this many seconds for a "
                   "1-minute load average below 1.0 before measuring")
    p.add_argument("--out", default="bench_results", help="output directory (BENCHMARKS.md, bench_results.json, "
                   "bench_figures/; default ./bench_results)")
    p.add_argument("--no-progress", action="store_true", help="no progress lines")
    p.add_argument("--readme", default=None, metavar="FILE", help="also write the summary (targets, work-precision "
                   "ratios) into the generated block of FILE (the repository's docs/BENCH.md)")
    return p.parse_args(argv)


def loadavg():
    try:
        with open("/proc/loadavg") as f:
            return [float(x) for x in f.read().split()[:3]]
    except OSError:
        return [float("nan")] * 3


def cpu_name():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


class Log:
    def __init__(self, on):
        self.on = on
        self.t0 = time.perf_counter()

    def __call__(self, *a):
        if self.on:
            print(f"[bench {time.perf_counter() - self.t0:7.1f} s]", *a, flush=True)


# --------------------------------------------------------------------------- competitors
class Competitor:
    """One curve of a work-precision diagram: a solver (and group) over levels k; level k
    is ``nsteps = Nbase 2^k`` (fixed step) or ``tol = 10^(-3-k)`` (native DOPRI5)."""

    def __init__(self, model, kind, solver, group=None):
        self.model = model
        self.kind = kind
        self.solver = solver
        self.group = group
        self.param = "tol" if (kind == "native" and solver == "DOPRI5") else "steps"
        self.h0 = 2e-2 if kind == "exl" else 1e-2
        self.results = {}          # level -> result
        self.errors = {}           # level -> error

    @property
    def label(self):
        return f"{self.solver} {self.group}" if self.kind == "exl" else self.solver

    @property
    def key(self):
        return (self.model, self.kind, self.solver, self.group)

    def case(self, k, T, repeat):
        c = dict(kind=self.kind, model=self.model, solver=self.solver, T=T, repeat=repeat, level=k,
                 role="wp")
        if self.kind == "exl":
            c["group"] = self.group
        if self.param == "tol":
            c["tol"] = 10.0 ** (-3 - k)
        else:
            c["nsteps"] = self.nsteps(k, T)
        return c

    def nsteps(self, k, T):
        return int(round(max(1, round(T / self.h0)) * 2.0 ** k))

    def valid_level(self, k, T):
        if self.param == "tol":
            return -2 <= k <= 9
        return self.nsteps(k, T) >= 2 and self.nsteps(k, T) <= 5_000_000

    def points(self):
        return [(self.errors[k], self.results[k]["time"]) for k in sorted(self.errors)]

    def ok_levels(self):
        return sorted(k for k in self.errors if np.isfinite(self.errors[k]))


def competitors_for(model, constrained, cfg):
    comps = [Competitor(model, "exl", m, g) for g in cfg.exlGroups for m in cfg.exlMethods]
    comps += [Competitor(model, "native", s) for s in (NATIVE_CONSTRAINED if constrained else NATIVE_FREE)]
    return comps


def _est(res):
    return res["time"] if res and np.isfinite(res.get("time", np.nan)) else np.nan


def next_levels(comp, cfg, eps_lo, eps_hi):
    """Levels to add after a round: finer until the curve is below eps_lo (or the budget,
    or stagnation), coarser until it is above eps_hi (or unstable)."""
    T = cfg.T
    new = []
    done = set(comp.results)
    ok = comp.ok_levels()
    if not ok:
        # nothing ran: try finer levels (coarse steps may all be unstable)
        kmax = max(done) if done else 0
        if kmax < 12 and all(not comp.results[k]["ok"] for k in done):
            worst = max((_est(comp.results[k]) for k in done), default=np.nan)
            if not (np.isfinite(worst) and worst * 4 > cfg.budget):
                new += [kmax + 1, kmax + 2]
        return [k for k in new if comp.valid_level(k, T) and k not in done]
    kfin = max(ok)
    efin = comp.errors[kfin]
    tfin = comp.results[kfin]["time"]
    factor = 2.0 if comp.param == "steps" else 1.8
    stagnant = False
    if len(ok) >= 2:
        kprev = ok[-2]
        # no gain from the last refinement near the reference floor (round-off)
        stagnant = efin > 0.7 * comp.errors[kprev] and efin < 1e-9
    failed_finer = any(k > kfin and not comp.results[k]["ok"] for k in done)
    if efin > eps_lo and not stagnant and not failed_finer:
        for j in (1, 2):
            if tfin * factor ** j <= cfg.budget:
                new.append(kfin + j)
    kcoarse = min(ok)
    ecoarse = comp.errors[kcoarse]
    coarse_failed = any(k < kcoarse for k in done)      # a coarser level ran and failed
    if ecoarse < eps_hi and not coarse_failed:
        new += [kcoarse - 1, kcoarse - 2]
    return [k for k in new if comp.valid_level(k, T) and k not in done]


# --------------------------------------------------------------------------- work precision
def run_wp(cfg, log, out):
    T = cfg.T
    models = {}
    for m in cfg.models:
        title, nb, nj, constrained, redundant = BR.model_summary(m)
        models[m] = dict(title=title, nb=nb, nj=nj, constrained=constrained, redundant=redundant,
                         comps=competitors_for(m, constrained, cfg))
    # references
    cases = []
    Nref = int(round(T / cfg.href))
    for m in cfg.models:
        cases.append(dict(kind="exl", model=m, solver="RK6", group="SE3", T=T, nsteps=Nref, repeat=1, role="ref"))
        cases.append(dict(kind="exl", model=m, solver="DOPRI5", group="SO3xR3", T=T, nsteps=Nref, repeat=1,
                          role="refcheck"))
    if "wp" in cfg.sections:
        for m in cfg.models:
            for c in models[m]["comps"]:
                cases += [c.case(k, T, cfg.repeat) for k in range(4) if c.valid_level(k, T)]
    refs = {}
    perstep = []
    if "perstep" in cfg.sections:
        # one process: the absolute cost per step of a single core, nothing running beside it
        pcases = perstep_cases(cfg, models)
        log(f"per step: {len(pcases)} runs, one at a time, load {loadavg()[0]:.2f}")
        perstep = BR.sweep(pcases, jobs=1)
    pending = cases
    for rnd in range(cfg.rounds + 1):
        if not pending:
            break
        pending.sort(key=lambda c: -c.get("est", 0.0))
        log(f"round {rnd}: {len(pending)} runs on {cfg.jobs} worker(s) (ParameterVariation), load {loadavg()[0]:.2f}")
        tic = time.perf_counter()
        results = BR.sweep(pending, jobs=cfg.jobs)
        log(f"round {rnd} done in {time.perf_counter() - tic:.1f} s")
        for c, r in zip(pending, results):
            role = c["role"]
            if role in ("ref", "refcheck"):
                refs.setdefault(c["model"], {})[role] = r
                if not r["ok"]:
                    raise SystemExit(f"bench: reference run failed for {c['model']}: {r['message']}")
            else:
                comp = next(x for x in models[c["model"]]["comps"]
                            if x.key == (c["model"], c["kind"], c["solver"], c.get("group")))
                comp.results[c["level"]] = r
        # errors
        for m in cfg.models:
            ref = refs[m]["ref"]
            for comp in models[m]["comps"]:
                for k, r in comp.results.items():
                    if k not in comp.errors:
                        comp.errors[k] = WP.final_error(r, ref) if r["ok"] else np.nan
                        r["error"] = comp.errors[k]
                        r["velocityError"] = WP.velocity_error(r, ref) if r["ok"] else np.nan
        if "wp" not in cfg.sections or rnd == cfg.rounds:
            break
        pending = []
        for m in cfg.models:
            for comp in models[m]["comps"]:
                for k in next_levels(comp, cfg, eps_lo=0.5 * EPS_LEVELS[-1], eps_hi=2.0 * EPS_LEVELS[0]):
                    # estimated time from the nearest level that ran
                    near = min(comp.results, key=lambda j: abs(j - k))
                    est = _est(comp.results[near])
                    fac = (2.0 if comp.param == "steps" else 1.8) ** (k - near)
                    est = est * fac if np.isfinite(est) else 0.0
                    rep = cfg.repeat if est < 1.0 else 3
                    c = comp.case(k, T, rep)
                    c["est"] = est * rep
                    pending.append(c)
    for m in cfg.models:
        r, rc = refs[m]["ref"], refs[m]["refcheck"]
        models[m]["refUncertainty"] = WP.final_error(rc, r)
        models[m]["refTime"] = r["time"]
        models[m]["refNative"] = WP.native_reference_check(
            {c.solver: [(c.results[k].get("h", np.nan), c.errors[k]) for k in c.ok_levels()]
             for c in models[m]["comps"] if c.kind == "native" and c.param == "steps"})
    out["models"] = models
    out["perstep"] = perstep
    out["refs"] = refs


def summarize_wp(cfg, models):
    """Per model: time to accuracy per competitor and the ratios."""
    summary = {}
    for m, md in models.items():
        rows = []
        for eps in EPS_LEVELS:
            tt = {}
            for comp in md["comps"]:
                t, flag = WP.time_to_accuracy(comp.points(), eps)
                tmax = max((comp.results[k]["time"] for k in comp.ok_levels()), default=np.nan)
                tt[comp.label if comp.kind == "exl" else "native " + comp.label] = (t, flag, comp.kind, tmax)
            exl = {k: v for k, v in tt.items() if v[2] == "exl" and np.isfinite(v[0])}
            nat = {k: v for k, v in tt.items() if v[2] == "native" and np.isfinite(v[0])}
            best_exl = min(exl, key=lambda k: exl[k][0]) if exl else None
            best_nat = min(nat, key=lambda k: nat[k][0]) if nat else None
            row = dict(eps=eps, times=tt, bestExl=best_exl, bestNative=best_nat)
            if best_exl and best_nat:
                row["ratio"] = nat[best_nat][0] / exl[best_exl][0]
                row["ratioBound"] = ""
            elif best_exl:
                # no native solver reached eps.  Each native solver would need more than its
                # longest (most accurate) run, so the fastest of them needs more than the
                # shortest of those times: a valid lower bound (min, not max, over the solvers)
                tn = min((v[3] for k, v in tt.items() if v[2] == "native" and np.isfinite(v[3])), default=np.nan)
                row["ratio"] = tn / exl[best_exl][0]
                row["ratioBound"] = ">"
            else:
                row["ratio"] = np.nan
                row["ratioBound"] = ""
            # informative only: native time extrapolated beyond its most accurate run
            ext = {}
            for comp in md["comps"]:
                if comp.kind == "native":
                    te = WP.extrapolate_time(comp.points(), eps)
                    if np.isfinite(te):
                        ext[comp.label] = te
            row["extrapNative"] = min(ext.items(), key=lambda kv: kv[1]) if ext else None
            if row["ratioBound"] == ">" and row["extrapNative"] and best_exl:
                row["ratioExtrap"] = row["extrapNative"][1] / exl[best_exl][0]
            else:
                row["ratioExtrap"] = np.nan
            rk = tt.get("RK4 SE3")
            if rk and np.isfinite(rk[0]) and best_nat:
                row["ratioRK4SE3"] = nat[best_nat][0] / rk[0]
            else:
                row["ratioRK4SE3"] = np.nan
            rows.append(row)
        summary[m] = rows
    return summary


# --------------------------------------------------------------------------- per step
PERSTEP_H = (1e-3, 1e-4)


def perstep_cases(cfg, models):
    n = 200 if cfg.quick else 1000
    rep = max(cfg.repeat, 5) if not cfg.quick else cfg.repeat
    cases = []
    for m in cfg.models:
        constrained = models[m]["constrained"]
        for h in PERSTEP_H:
            base = dict(model=m, T=n * h, nsteps=n, repeat=rep, role="perstep", h=h)
            for g in ("SE3", "SO3xR3"):
                cases.append(dict(base, kind="exl", solver="RK4", group=g))
            natives = ["GeneralizedAlpha", "GeneralizedAlpha-mN"]
            natives += ["TrapezoidalIndex2"] if constrained else ["RK44", "RK67"]
            for s in natives:
                cases.append(dict(base, kind="native", solver=s))
    return cases


def summarize_perstep(perstep):
    """{model: {h: {competitor: dict(us, newton, ok, message, times)}}}"""
    rows = {}
    for r in perstep:
        c = r["case"]
        key = f"{c['solver']} {c['group']}" if c["kind"] == "exl" else c["solver"]
        d = rows.setdefault(c["model"], {}).setdefault(c["h"], {})
        d[key] = dict(us=r["time"] / c["nsteps"] * 1e6 if r["ok"] else np.nan,
                      newton=(r.get("newton", 0) / c["nsteps"]) if r["ok"] and c["kind"] == "native" else np.nan,
                      ok=r["ok"], message=r["message"], times=r["times"])
    return rows


def _ga_step(d):
    """Cheaper of the two generalized-alpha variants (full / modified Newton)."""
    ga = [(d[k]["us"], k) for k in ("GeneralizedAlpha", "GeneralizedAlpha-mN") if k in d and d[k]["ok"]]
    return min(ga) if ga else (np.nan, None)


# --------------------------------------------------------------------------- scaling
SCALING_H = 1e-4


def run_scaling(cfg, log, out):
    h = SCALING_H
    cases = []
    for N in cfg.chainN:
        n_exl = int(np.clip(0.15 / (4e-6 * N), 20, 20000))
        cases.append(dict(kind="exl", model=f"chain{N}", solver="RK4", group="SE3", T=n_exl * h,
                          nsteps=n_exl, repeat=cfg.repeat if N <= 200 else 3, role="scaling",
                          est=n_exl * 4e-6 * N * cfg.repeat + 5e-5 * N ** 2))
        for sparse in (False, True):
            if N > cfg.gaChainMax or (not sparse and N > 50):
                continue            # the dense solver is O(N^3) per step
            n_ga = int(np.clip(0.3 / (30e-6 * N), 5, 5000))
            cases.append(dict(kind="native", model=f"chain{N}", solver="GeneralizedAlpha", T=n_ga * h,
                              nsteps=n_ga, repeat=3, sparse=sparse, role="scaling", tolFallback=True,
                              est=n_ga * 30e-6 * N * 3 * (1 if sparse else max(1.0, N / 20) ** 2)))
    cases.sort(key=lambda c: -c["est"])
    log(f"scaling: {len(cases)} runs on {cfg.jobs} worker(s) (ParameterVariation), load {loadavg()[0]:.2f}")
    tic = time.perf_counter()
    res = BR.sweep(cases, jobs=cfg.jobs)
    log(f"scaling done in {time.perf_counter() - tic:.1f} s")
    rows = {}
    for c, r in zip(cases, res):
        N = int(c["model"][5:])
        d = rows.setdefault(N, {})
        key = "exl" if c["kind"] == "exl" else ("GAsparse" if c.get("sparse") else "GAdense")
        d[key] = dict(us=r["time"] / c["nsteps"] * 1e6 if r["ok"] else np.nan, setup=r.get("setup", np.nan),
                      build=r.get("build", np.nan), ok=r["ok"], message=r["message"], nsteps=c["nsteps"],
                      newton=(r.get("newton", 0) / c["nsteps"]) if r["ok"] and key != "exl" else np.nan,
                      newtonTol=r.get("newtonTol", np.nan))
    # the faster Exudyn linear solver at each N
    for N, d in rows.items():
        ga = [d[k] for k in ("GAdense", "GAsparse") if k in d and d[k]["ok"]]
        if ga:
            best = min(ga, key=lambda x: x["us"])
            d["GA"] = dict(best, solver="dense" if best is d.get("GAdense") else "sparse")
        elif "GAsparse" in d or "GAdense" in d:
            d["GA"] = d.get("GAsparse", d.get("GAdense"))
    Ns = sorted(rows)
    fits = {}
    for key in ("exl", "GA", "GAdense", "GAsparse"):
        N = [n for n in Ns if key in rows[n]]
        t = [rows[n][key]["us"] for n in N]
        fits[key] = dict(all=WP.fit_exponent(N, t),
                         large=WP.fit_exponent([n for n in N if n >= 10], [rows[n][key]["us"] for n in N if n >= 10]),
                         N=N, us=t)
    out["scaling"] = dict(rows=rows, fits=fits)


# --------------------------------------------------------------------------- report
def _fmt_t(t, flag=""):
    if not np.isfinite(t):
        return "n/r"
    s = f"{t * 1e3:.3g} ms" if t < 1 else f"{t:.3g} s"
    return ("<= " if flag == "upper" else "") + s


def _fmt_r(r, bound=""):
    if not np.isfinite(r):
        return "n/a"
    return f"{bound}{r:.3g}x" if r < 100 else f"{bound}{r:.0f}x"


PROFILE_NOTES = """\
Profile before optimising; this records what was measured and changed (or proposed).

| # | finding (how measured) | change | what it bought |
|---|---|---|---|
| 1 | heavy top MK-RK4 step 45 us on the first kernel (before commit fbdaab1, which already has the change); `perf record` showed the time in numba's atomic reference counting (`NRT_incref/decref`) of the many array views and namedtuple fields passed between the stage functions | compile the kernel functions with `_nrt=False` (no NRT: the kernel is allocation-free, so no reference counting is emitted) | re-measured on the current kernel (commit 016c7ad): a copy of the package with every `_nrt=False` replaced by `_nrt=True` (own `NUMBA_CACHE_DIR`) against the package itself, `bench_runs.run_case(dict(kind="exl", model="heavytop", solver="RK4", group="SE3", T=1, nsteps=1000, repeat=7))`: 16.9 us -> 1.97 us per step (8.6x) |
{extra}"""


def targets_lines(cfg, out):
    """The table of speed targets (shared by BENCHMARKS.md and docs/BENCH.md)."""
    L = []
    A = L.append
    summ = out.get("wpSummary", {})
    ps = out.get("perstepSummary", {})
    A("| target | measured | holds |")
    A("|---|---|---|")
    for m in ("heavytop", "doublependulum"):
        if m in summ:
            rs = [r["ratio"] for r in summ[m]]
            worst = min(rs) if rs and all(np.isfinite(rs)) else np.nan
            ok = np.isfinite(worst) and worst >= TARGET_RATIO
            A(f"| work-precision, {m}: exudyn_lie reaches 1e-4 ... 1e-8 in <= 1/10 of the fastest native time | smallest ratio "
              f"{_fmt_r(worst)} ({', '.join(_fmt_r(r['ratio'], r['ratioBound']) + ' at ' + format(r['eps'], '.0e') for r in summ[m])}) "
              f"| {'yes' if ok else 'no'} |")
    for m, dh in ps.items():
        cells, holds = [], True
        for h, d in sorted(dh.items(), reverse=True):
            a = d.get("RK4 SE3", {}).get("us", np.nan)
            g, gk = _ga_step(d)
            if np.isfinite(a) and np.isfinite(g):
                cells.append(f"h = {h:g}: {a:.3g} us vs {g:.3g} us ({gk}, {g / a:.3g}x)")
                holds = holds and a <= g
            else:
                cells.append(f"h = {h:g}: GA failed")
        A(f"| cost per step, {m}: MK-RK4 (SE3) step <= one GA step (cheaper of full / modified Newton) | {'; '.join(cells)} | "
          f"{'yes' if holds and any('vs' in c for c in cells) else 'no'} |")
    for m, target in KERNEL_STEP_TARGETS_US.items():
        if m not in ps:
            continue
        us = {h: d.get("RK4 SE3", {}).get("us", np.nan) for h, d in ps[m].items()}
        ok = all(np.isfinite(u) and u <= target for u in us.values())
        A(f"| cost per step, {m}: median MK-RK4 (SE3) step <= {target:g} us (absolute target) | "
          + "; ".join(f"h = {h:g}: {u:.3g} us" for h, u in sorted(us.items(), reverse=True))
          + f" | {'yes' if ok else 'no'} |")
    sc = out.get("scaling")
    if sc:
        p = sc["fits"]["exl"]["large"]
        if not np.isfinite(p):
            p = sc["fits"]["exl"]["all"]
        A(f"| scaling, chain: cost per step ~ N^p, p <= 1.2 | p = {sc['fits']['exl']['large']:.3f} (N >= 10), "
          f"{sc['fits']['exl']['all']:.3f} (all N); N = {min(sc['rows'])} ... {max(sc['rows'])} | "
          f"{'yes' if np.isfinite(p) and p <= 1.2 else 'no'} |")
    from .bench_startup import target_lines as startup_target_lines
    L += startup_target_lines(out.get("startup"))
    ov = out.get("overhead")
    if ov:
        for period, d in ov["periods"].items():
            x = d["sensor"]
            A(f"| SolveDynamic bridge: sensor machinery < 10 % of a SolveDynamic run (heavy top, h = {ov['h']:g} s, a sensor "
              f"every {d['steps']} steps) | {100 * x['outputs']:.1f} % of {1e3 * x['bridge']:.3g} ms "
              f"(Exudyn's own sensor loop {100 * x['exudyn'] / x['bridge']:.1f} %, the bridge's per-output calls "
              f"{100 * x['bridgeOnly']:.1f} %) | {'yes' if x['outputs'] < 0.10 else 'no'} |")
            x = d["sensor+file"]
            A(f"| SolveDynamic bridge: its own part of the sensor and solution-file machinery < 10 % (the file alone costs "
              f"Exudyn {1e3 * x['gaFile']:.3g} ms in a native generalized-alpha solve of the same run; a sensor and "
              f"the file every {d['steps']} steps) | {100 * x['bridgeOnly']:.1f} % of {1e3 * x['bridge']:.3g} ms "
              f"(all outputs {100 * x['outputs']:.1f} %) | {'yes' if x['bridgeOnly'] < 0.10 else 'no'} |")
    gm = out.get("groups")
    if gm:
        A("| group maps: one compiled SE(3) exp + dexpinv (group work of one body in one MK stage) | "
          + ", ".join(f"{us:.3g} us at \\|xi\\| = {float(a):g}" for a, us in gm.items()) + " | - |")
    from .bench_mujoco import target_lines as mujoco_target_lines
    L += mujoco_target_lines(out.get("mujoco"))
    from .bench_userfunctions import target_lines as uf_target_lines
    L += uf_target_lines(out.get("userfunctions"))
    from .bench_topology import target_lines as topo_target_lines
    L += topo_target_lines(out.get("topology"))
    from .bench_evaluated import target_lines as evaluated_target_lines
    L += evaluated_target_lines(out.get("evaluated"))
    A(f"| parallel sweeps through exudyn.processing.ParameterVariation | "
      f"`exudyn_lie.apps.bench_runs.sweep`, {cfg.jobs} processes | yes |")
    return L


def wp_compact_lines(out):
    """Per model: the time ratio (fastest native / fastest exudyn_lie) at each accuracy."""
    summ = out.get("wpSummary", {})
    if not summ:
        return []
    L = ["| model | " + " | ".join(f"{e:.0e}" for e in EPS_LEVELS) + " |",
         "|---|" + "---|" * len(EPS_LEVELS)]
    for m, rows in summ.items():
        cells = []
        for r in rows:
            cells.append(f"{_fmt_r(r['ratio'], r['ratioBound'])} ({r['bestExl']})" if r["bestExl"] else "n/r")
        L.append(f"| {m} | " + " | ".join(cells) + " |")
    return L


def readme_summary(cfg, out):
    env = out["env"]
    L = [f"Measured on {env['cpu']} ({env['cores']} cores, load {env['loadStart'][0]:.2f} at the start), "
         f"{env['date'][:10]}; exudyn {env['exudyn']}, numba {env['numba']}.", ""]
    L += targets_lines(cfg, out)
    wp = wp_compact_lines(out)
    if wp:
        L += ["", f"Work-precision (final state at T = {cfg.T:g} s against a reference solution): CPU time of the "
                  f"fastest native Exudyn solver that reaches the accuracy over the fastest exudyn_lie variant "
                  f"(named); '>' = no native solver reached it (a lower bound: the shortest of the native solvers' "
                  f"longest runs, at most {cfg.budget:g} s each, over the exudyn_lie time).", ""] + wp
        chk = [f"{m} ({_fmt_rn(md.get('refNative'))})" for m, md in out.get("models", {}).items()]
        if chk:
            L += ["", "The reference is exudyn_lie RK6 (SE3) at a small step; Exudyn's own most accurate fixed-step "
                      "run checks it independently (distance to the reference, observed order over its two finest "
                      "steps / nominal order): " + "; ".join(chk) + "."]
    return "\n".join(L) + "\n"


def _fmt_rn(rn):
    if not rn:
        return "no native check"
    return (f"{rn['solver']} {rn['err']:.1e}, order {rn['order']:.1f}/{rn['nominal']}"
            + ("" if rn["converges"] else ", NOT converging"))


def _ref_native_text(rn):
    """One sentence: does Exudyn's own most accurate run converge to the reference?"""
    if not rn:
        return "Native check of the reference: no native solver finished two runs."
    verdict = ("its error still falls at the solver's order, so Exudyn's solution converges to the reference "
               "(no model difference above this error)" if rn["converges"] else
               "**its error no longer falls at the solver's order: a difference between Exudyn's model and the "
               "reference cannot be excluded at this level**")
    return (f"Native check of the reference: Exudyn {rn['solver']} at h = {rn['h']:.3g} s is {rn['err']:.2g} "
            f"from it, observed order {rn['order']:.2f} over its two finest runs (nominal {rn['nominal']}): "
            f"{verdict}.")


def write_report(cfg, out, cmdline):
    os.makedirs(cfg.out, exist_ok=True)
    L = []
    A = L.append
    A("# exudyn_lie benchmarks")
    A("")
    A(f"Generated by the command `{cmdline}` (see `python -m exudyn_lie bench --help`); "
      f"do not edit by hand. Raw data: `bench_results.json`; figures: `bench_figures/`.")
    A("")
    env = out["env"]
    A(f"* date: {env['date']}; machine: {env['cpu']}, {env['cores']} cores; Python {env['python']}, "
      f"numpy {env['numpy']}, numba {env['numba']}, exudyn {env['exudyn']}")
    A(f"* load average (1/5/15 min) at start: {env['loadStart']}, at end: {env['loadEnd']}"
      + ("" if env["loadStart"][0] < 1.0 else " - **the machine was busy; timings are noisy**"))
    A(f"* sweeps: `exudyn.processing.ParameterVariation(useMultiProcessing=True, numberOfThreads={cfg.jobs})`; "
      f"every time is the median over repeated runs inside one worker ({cfg.repeat} repetitions, 3 for runs "
      f"over 1 s); ratios compare times measured in this invocation")
    A("* timed: exudyn_lie `Simulator.Advance(n, h)` (the compiled time loop) and Exudyn "
      "`MainSolver*.SolveSteps` (Exudyn's time loop, solution file and sensors off); set-up "
      "(reading the model, `Simulator(...)`, `InitializeSolver`) excluded and reported separately")
    A("")
    summ = out.get("wpSummary", {})
    ps = out.get("perstepSummary", {})
    sc = out.get("scaling")
    su = out.get("startup")
    A("## Targets")
    A("")
    L += targets_lines(cfg, out)
    A("")
    # ---- work precision
    if "models" in out and "wp" in cfg.sections:
        A("## 1. Work-precision")
        A("")
        A(f"Final configuration error at T = {cfg.T:g} s: the largest over all bodies of |r - r_ref| [m] "
          f"(body frame origin) and the rotation angle of R_ref^T R [rad]. Reference: exudyn_lie RK6 on SE3 "
          f"with h = {cfg.href:g} s; 'ref. uncertainty' is its distance to DOPRI5 on SO3xR3 at the same step "
          f"(a different method and group). Time to reach an accuracy: log-log interpolation on each "
          f"competitor's Pareto front; 'n/r' = not reached within the time budget ({cfg.budget:g} s per "
          f"run); '<=' = even the largest step is more accurate (upper bound); a ratio '>x' means no native "
          f"solver reached the accuracy and x is the shortest of the native solvers' longest runs over the "
          f"exudyn_lie time (a lower bound: each native solver needs more than its longest run); the last "
          f"column then extrapolates the native time along the slope of its two most accurate runs (at most "
          f"3 decades; informative, not used for the verdict).")
        A("")
        for m, md in out["models"].items():
            A(f"### {m}: {md['title']} ({md['nb']} bodies, {md['nj']} joints)")
            A("")
            A(f"Reference: {md['refTime']:.3g} s, ref. uncertainty {md['refUncertainty']:.2g}. "
              f"{_ref_native_text(md.get('refNative'))} Figure: `bench_figures/wp_{m}.png`")
            A("")
            A(f"![work-precision {m}](bench_figures/wp_{m}.png)")
            A("")
            floor = all(comp.errors[k] < 1e-12 for comp in md["comps"] for k in comp.ok_levels())
            if floor:
                A("Every run of every solver is exact to round-off (errors < 1e-12): this motion is integrated "
                  "exactly by all of them, so there is no accuracy/time trade-off; the times are those of the "
                  "cheapest runs (upper bounds) and the ratios say nothing about accuracy.")
                A("")
            A("| accuracy | best exudyn_lie | MK-RK4 SE3 | fastest native | ratio (native / best exl) | "
              "ratio (native / RK4 SE3) | >= 10x | native extrapolated (informative) |")
            A("|---|---|---|---|---|---|---|---|")
            for r in summ[m]:
                tt = r["times"]
                be = r["bestExl"]
                bn = r["bestNative"]
                rk = tt.get("RK4 SE3", (np.nan, "", "", np.nan))
                A(f"| {r['eps']:.0e} | {be + ': ' + _fmt_t(tt[be][0], tt[be][1]) if be else 'n/r'} | "
                  f"{_fmt_t(rk[0], rk[1])} | {bn[7:] + ': ' + _fmt_t(tt[bn][0], tt[bn][1]) if bn else 'n/r'} | "
                  f"{_fmt_r(r['ratio'], r['ratioBound'])} | {_fmt_r(r['ratioRK4SE3'])} | "
                  f"{'yes' if np.isfinite(r['ratio']) and r['ratio'] >= TARGET_RATIO else 'no'} | "
                  + (f"{r['extrapNative'][0]}: ~{_fmt_t(r['extrapNative'][1])}, ~{_fmt_r(r['ratioExtrap'])}"
                     if r.get("extrapNative") and np.isfinite(r.get("ratioExtrap", np.nan)) else "-") + " |")
            A("")
            A("<details><summary>all competitors: time to accuracy, observed order, runs</summary>")
            A("")
            A("| competitor | " + " | ".join(f"{e:.0e}" for e in EPS_LEVELS) + " | order | smallest error | runs (failed) |")
            A("|---|" + "---|" * (len(EPS_LEVELS) + 3))
            for comp in md["comps"]:
                lab = comp.label if comp.kind == "exl" else "native " + comp.label
                cells = [_fmt_t(*r["times"][lab][:2]) for r in summ[m]]
                hs = [(comp.results[k].get("h", np.nan), comp.errors[k]) for k in comp.ok_levels()
                      if comp.errors[k] > 50 * max(md["refUncertainty"], 1e-14)]
                order = WP.observed_order(hs) if comp.param == "steps" else np.nan
                emin = min((comp.errors[k] for k in comp.ok_levels()), default=np.nan)
                nfail = sum(1 for r in comp.results.values() if not r["ok"])
                A(f"| {'exudyn_lie ' if comp.kind == 'exl' else 'Exudyn '}{comp.label} | " + " | ".join(cells)
                  + f" | {order:.2f} | {emin:.2g} | {len(comp.results)} ({nfail}) |")
            A("")
            A("</details>")
            A("")
    # ---- per step
    if ps:
        A("## 2. Cost per step")
        A("")
        A("Median CPU time of one step of the time loop (1000 steps from the initial state, one process at a time, "
          "nothing else running); for the implicit "
          "solvers the mean number of Newton iterations per step in brackets. The last column compares one "
          "MK-RK4 step (SE3) with the cheaper generalized-alpha variant at the same step size.")
        A("")
        keys = ["RK4 SE3", "RK4 SO3xR3", "GeneralizedAlpha", "GeneralizedAlpha-mN", "TrapezoidalIndex2", "RK44", "RK67"]
        A("| model | h | " + " | ".join(("exudyn_lie " if " " in k else "Exudyn ") + k for k in keys)
          + " | GA / MK-RK4 SE3 |")
        A("|---|---|" + "---|" * (len(keys) + 1))
        for m, dh in ps.items():
            for h, d in sorted(dh.items(), reverse=True):
                cells = []
                for k in keys:
                    if k not in d:
                        cells.append("-")
                    elif not d[k]["ok"]:
                        cells.append("failed")
                    else:
                        cells.append(f"{d[k]['us']:.3g} us" + (f" ({d[k]['newton']:.2g})" if np.isfinite(d[k]["newton"]) else ""))
                a = d.get("RK4 SE3", {}).get("us", np.nan)
                g, gk = _ga_step(d)
                A(f"| {m} | {h:g} | " + " | ".join(cells) + f" | {_fmt_r(g / a) if np.isfinite(a) and np.isfinite(g) else 'n/a'} |")
        A("")
    # ---- scaling
    if sc:
        A("## 3. Scaling: chain of N boxes with spherical joints")
        A("")
        A("Boxes 0.05 x 0.1 x 0.2 m (aluminium), spherical joints, hanging in gravity, starting as a rigid "
          "pendulum rotating about the top joint at 2 / max(1, L[m]) rad/s (the chain then swings and whips); "
          f"h = {SCALING_H:g} s for both. "
          "exudyn_lie MK-RK4 on SE3 (band Cholesky of J M^-1 J^T in reverse Cuthill-McKee order); Exudyn "
          "generalized-alpha (full Newton, tol 1e-10) with the dense (`EXUdense`, N <= 50) and the sparse "
          "(`EigenSparse`, which requires `lieGroupAddTangentOperator=False`) linear solver; the GA column "
          "shows the faster of the two. Newton tolerance 1e-10 as in the other sections; where Exudyn's Newton "
          "cannot reach it (large N: the residual of thousands of equations stalls above 1e-10) the run is "
          "repeated at 1e-8, then 1e-6 (shown as 'tol'). Set-up = `Simulator(...)` (exudyn_lie) or "
          "`InitializeSolver` (Exudyn).")
        A("")
        A("![scaling](bench_figures/scaling.png)")
        A("")
        A("| N | exudyn_lie us/step | us/step/body | exudyn_lie set-up | GA us/step (Newton/step) | GA set-up | GA / exudyn_lie |")
        A("|---|---|---|---|---|---|---|")
        for N in sorted(sc["rows"]):
            d = sc["rows"][N]
            e = d.get("exl", {})
            g = d.get("GA", {})
            eu, gu = e.get("us", np.nan), g.get("us", np.nan)
            A(f"| {N} | {eu:.4g} | {eu / N:.3g} | {e.get('setup', np.nan):.3g} s | "
              + (f"{gu:.4g} ({g['newton']:.2g}, {g['solver']}, tol {g['newtonTol']:.0e})" if g and g["ok"] else
                 ("failed: " + g["message"][:60] if g else "-"))
              + f" | {g.get('setup', np.nan):.3g} s | {_fmt_r(gu / eu) if np.isfinite(gu) and np.isfinite(eu) else '-'} |")
        f = sc["fits"]
        A("")
        A(f"Fitted exponent of cost per step ~ N^p: exudyn_lie p = {f['exl']['large']:.3f} for N >= 10 "
          f"({f['exl']['all']:.3f} over all N); Exudyn GA (faster solver) p = {f['GA']['large']:.3f} for N >= 10 "
          f"({f['GA']['all']:.3f} over all N); GA EigenSparse p = {f['GAsparse']['large']:.3f}, GA EXUdense "
          f"p = {f['GAdense']['large']:.3f} (N >= 10).")
        A("")
    # ---- start-up
    from .bench_startup import report_lines as startup_report_lines
    L += startup_report_lines(su)
    # ---- bridge overhead, group maps
    ov = out.get("overhead")
    if ov:
        A("## 5. Bridge overhead")
        A("")
        A(f"The paper's heavy top (`models.build('heavy_top')` plus a position sensor), MK-RK4 SE3, h = {ov['h']:g} s, "
          f"{ov['steps']} steps; medians of repeated runs. Integration alone (`Simulator.Advance` in one call): "
          f"{1e3 * ov['kernel']:.3g} ms; `exl.SolveDynamic` without outputs (integration + the fixed cost of a "
          f"solve: reading the model, compiling the scene, Exudyn's set-up): {1e3 * ov['none']:.3g} ms. 'Exudyn "
          f"alone' is Exudyn's time loop with an empty Newton hook and the same outputs (a native solve pays it "
          f"too); with the solution file it is the larger of that and the sensor loop plus what the file costs "
          f"Exudyn's generalized-alpha in the same run ('file in GA': an empty hook leaves the coordinates "
          f"constant, which Exudyn formats faster than real ones). Output share = (SolveDynamic - SolveDynamic "
          f"without outputs) / SolveDynamic; the bridge's part subtracts Exudyn's own cost (per output: the Python hook and the copy of one row of node coordinates; "
          f"the outputs are integrated and converted a chunk at a time, one kernel call per chunk; with the "
          f"solution file, also the accelerations and joint multipliers its default export asks for).")
        A("")
        A("| outputs | every | Exudyn alone | file in GA | exl.SolveDynamic | output share | the bridge's part |")
        A("|---|---|---|---|---|---|---|")
        for period, d in ov["periods"].items():
            for key in ("sensor", "sensor+file"):
                x = d[key]
                A(f"| {OUTPUT_KINDS[key]} | {d['steps']} steps ({d['outputs']} outputs) | "
                  f"{1e3 * x['exudyn']:.3g} ms | {(format(1e3 * x['gaFile'], '.3g') + ' ms') if key == 'sensor+file' else '-'} | "
                  f"{1e3 * x['bridge']:.3g} ms | "
                  f"{100 * x['outputs']:.1f} % | "
                  f"{100 * x['bridgeOnly']:.1f} % |")
        A("")
    gm = out.get("groups")
    if gm:
        A("## 6. Group maps")
        A("")
        A("One compiled SE(3) `exp_into` + `dexpinv_apply_into` pair (the group work of one body in one MK stage), "
          "called 10^6 times from a numba loop over 1024 random screws of the given size; median of 7 runs.")
        A("")
        A("| \\|xi\\| | branch | us per exp + dexpinv |")
        A("|---|---|---|")
        for a, us in gm.items():
            branch = ("Taylor series of both" if float(a) < 0.6 else
                      "closed-form exp, Taylor dexpinv" if float(a) < 2.59 else "closed forms of both")
            A(f"| {float(a):g} | {branch} | {us:.4f} |")
        A("")
    from .bench_params import report_lines as _params_lines
    L += _params_lines(out.get("params"))
    from .bench_items import report_lines as _items_lines
    L += _items_lines(out.get("items"))
    if out.get("adaptive"):
        from .bench_adaptive import report_lines as _adaptive_lines
        L += _adaptive_lines(out["adaptive"], out["adaptive"].get("figures", ()))
    from .bench_planar import report_lines as _planar_lines
    L += _planar_lines(out.get("planar"))
    if out.get("particles"):
        from .bench_particles import report_lines as _particle_lines
        L += _particle_lines(out["particles"])
    if out.get("stiff"):
        from .bench_stiff import report_lines as _stiff_lines
        L += _stiff_lines(out["stiff"]["models"], out["stiff"].get("figures", ()))
    # ---- profile notes
    A("## 7. Profile and optimisation record")
    A("")
    A(PROFILE_NOTES.format(extra=out.get("profileExtra", "")))
    A("")
    if out.get("userfunctions"):
        from .bench_userfunctions import report_lines as uf_report_lines
        L += uf_report_lines(out["userfunctions"])
    if out.get("topology"):
        from .bench_topology import report_lines as topo_report_lines
        L += topo_report_lines(out["topology"])
    if out.get("evaluated"):
        from .bench_evaluated import report_lines as evaluated_report_lines
        L += evaluated_report_lines(out["evaluated"])
    if out.get("mujoco"):
        from .bench_mujoco import report_lines as mujoco_report_lines
        L += mujoco_report_lines(out["mujoco"], out["mujoco"].get("figure"))
    with open(os.path.join(cfg.out, "BENCHMARKS.md"), "w") as f:
        f.write("\n".join(L))


def make_plots(cfg, out):
    os.makedirs(cfg.figdir, exist_ok=True)
    files = []
    for m, md in out.get("models", {}).items():
        if "wp" not in cfg.sections:
            break
        curves = [(c.label, c.kind, c.solver, c.group, c.points()) for c in md["comps"]]
        path = os.path.join(cfg.figdir, f"wp_{m}.png")
        WP.plot_work_precision(path, f"{m}: {md['title']}, T = {cfg.T:g} s (median CPU time)", curves)
        files.append(path)
    sc = out.get("scaling")
    if sc:
        f = sc["fits"]
        series = [("exudyn_lie MK-RK4 SE3", f["exl"]["N"], np.array(f["exl"]["us"]) * 1e-6, f["exl"]["large"]),
                  ("Exudyn GA, EXUdense", f["GAdense"]["N"], np.array(f["GAdense"]["us"]) * 1e-6, f["GAdense"]["large"]),
                  ("Exudyn GA, EigenSparse", f["GAsparse"]["N"], np.array(f["GAsparse"]["us"]) * 1e-6,
                   f["GAsparse"]["large"])]
        path = os.path.join(cfg.figdir, "scaling.png")
        WP.plot_scaling(path, series, "chain of N bodies, spherical joints: cost per step")
        files.append(path)
    return files


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, (np.floating, float)):
        return float(x) if np.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, Competitor):
        return dict(label=x.label, kind=x.kind, solver=x.solver, group=x.group,
                    runs=[dict(level=k, error=x.errors.get(k), time=r["time"], times=r["times"], ok=r["ok"],
                               message=r["message"], steps=r.get("steps"), h=r.get("h"),
                               velocityError=r.get("velocityError"), newton=r.get("newton"),
                               setup=r.get("setup"), tol=r["case"].get("tol"))
                          for k, r in sorted(x.results.items())])
    return x


def wait_quiet(seconds, log):
    if seconds <= 0:
        return
    t0 = time.time()
    while time.time() - t0 < seconds:
        la = loadavg()[0]
        if la < 1.0:
            log(f"load {la:.2f} < 1.0: starting")
            return
        log(f"waiting for a quiet machine (load {la:.2f})")
        time.sleep(min(30.0, max(1.0, seconds - (time.time() - t0))))


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parse_args(argv)
    if args.readme and not os.path.exists(args.readme):
        raise SystemExit(f"bench: --readme {args.readme}: no such file")
    cfg = Config(args)
    log = Log(cfg.progress)
    cmdline = "python -m exudyn_lie bench" + ("" if not argv else " " + " ".join(argv))
    wait_quiet(args.wait_quiet, log)
    out = dict(env=dict(date=datetime.datetime.now().isoformat(timespec="seconds"), cpu=cpu_name(),
                        cores=os.cpu_count(), python=platform.python_version(), **versions(), loadStart=loadavg(),
                        command=cmdline, jobs=cfg.jobs, T=cfg.T, quick=cfg.quick))
    log(f"models {cfg.models}, sections {cfg.sections}, T = {cfg.T:g} s, load {out['env']['loadStart']}")
    if "startup" in cfg.sections:           # first, on a quiet machine
        from . import bench_startup
        out["startup"] = bench_startup.run_section(cfg, log)
    if "wp" in cfg.sections or "perstep" in cfg.sections:
        run_wp(cfg, log, out)
        if "wp" in cfg.sections:
            out["wpSummary"] = summarize_wp(cfg, out["models"])
        if "perstep" in cfg.sections:
            out["perstepSummary"] = summarize_perstep(out["perstep"])
            for m, dh in out["perstepSummary"].items():
                for h, d in sorted(dh.items(), reverse=True):
                    g, gk = _ga_step(d)
                    a = d.get("RK4 SE3", {}).get("us", np.nan)
                    log(f"per step {m:15s} h = {h:g}: MK-RK4 SE3 {a:.3g} us, SO3xR3 "
                        f"{d.get('RK4 SO3xR3', {}).get('us', np.nan):.3g} us; "
                        + (f"{gk} {g:.3g} us ({g / a:.3g}x)" if gk else "generalized-alpha failed"))
    if "scaling" in cfg.sections:
        run_scaling(cfg, log, out)
    if "overhead" in cfg.sections:
        from .bench_micro import bridge_overhead
        log("bridge overhead (heavy top, SolveDynamic vs the integration alone)")
        # 11 rounds in the quick run too: a run is a few ms, and the shares are differences of
        # medians (3 rounds gave 1.9-9.4 % for the same code in three runs)
        out["overhead"] = bridge_overhead(T=2.0 if cfg.quick else 8.0, repeats=11)
    if "stabilization" in cfg.sections:
        from .bench_stabilization import stabilization_cost
        log("holding the joints (SolveDynamic's default stabilization='position' against None; output every "
            "0.01 s, h = 1e-3 s)")
        out["stabilization"] = stabilization_cost(T=2.0 if cfg.quick else 8.0, repeats=7 if cfg.quick else 11)
        log("... and on the Exudyn-evaluated path (evaluation='exudyn': the projections on Exudyn's residuals)")
        out["stabilizationEvaluated"] = stabilization_cost(T=0.5 if cfg.quick else 2.0, repeats=3 if cfg.quick else 7,
                                                           evaluation="exudyn")
        for key, path in (("stabilization", ""), ("stabilizationEvaluated", " (evaluated)")):
            for name, d in out[key].items():
                log(f"stabilization{path} {name:26s}: default {1e3 * d['on']:.3g} ms, None {1e3 * d['off']:.3g} ms, "
                    f"+{100 * d['share']:.0f} %; largest joint violation at t = {d['T']:g} s: {d['violationOn']:.1e} "
                    f"against {d['violationOff']:.1e}")
    if "check" in cfg.sections:
        from .bench_micro import constraint_check_cost
        log("run-time constraint check (SolveDynamic, output every 0.01 s, h = 1e-3 s): check on / off")
        out["check"] = constraint_check_cost(T=2.0 if cfg.quick else 8.0, repeats=7 if cfg.quick else 11)
        for name, d in out["check"].items():
            log(f"constraint check {name:26s}: on {1e3 * d['on']:.3g} ms, off {1e3 * d['off']:.3g} ms, "
                f"share {100 * d['share']:.1f} % ({d['perOutputUs']:.2g} us per output)")
    if "groups" in cfg.sections:
        from .bench_micro import group_maps
        log("group maps (SE3 exp + dexpinv)")
        out["groups"] = group_maps(n=10 ** 5 if cfg.quick else 10 ** 6)
    if "mujoco" in cfg.sections:
        from . import bench_mujoco
        out["mujoco"] = bench_mujoco.run_section(cfg, log)
    if "params" in cfg.sections:
        from .bench_params import connector_rereads, parameter_updates
        log("parameters changed during a solve (serialRobotTest PD controller)")
        out["params"] = parameter_updates(T=0.1 if cfg.quick else 0.5, repeats=3 if cfg.quick else 7)
        out["params"]["reread"] = connector_rereads(calls=200 if cfg.quick else 1000)
    if "items" in cfg.sections:
        from .bench_items import per_step as items_per_step
        log("point masses against rigid bodies")
        out["items"] = items_per_step(m=100 if cfg.quick else 200, repeats=3 if cfg.quick else 7)
    if "userfunctions" in cfg.sections:
        from . import bench_userfunctions
        out["userfunctions"] = bench_userfunctions.run_section(cfg, log)
    if "topology" in cfg.sections:
        from . import bench_topology
        out["topology"] = bench_topology.run_section(cfg, log)
    if "evaluated" in cfg.sections:
        from . import bench_evaluated
        out["evaluated"] = bench_evaluated.run_section(cfg, log)
    if "adaptive" in cfg.sections:
        from . import bench_adaptive
        out["adaptive"] = bench_adaptive.run_section(cfg, log)
    if "stiff" in cfg.sections:
        from . import bench_stiff
        out["stiff"] = dict(models=bench_stiff.run_section(cfg, log))
    if "particles" in cfg.sections:
        from . import bench_particles
        out["particles"] = bench_particles.run_section(cfg, log)
    if "planar" in cfg.sections:
        from .bench_planar import planar_section
        log("planar four-bar of 2D bodies vs the 3D planar four-bar; SE2 vs SE3 maps")
        out["planar"] = planar_section(quick=cfg.quick)
    out["env"]["loadEnd"] = loadavg()
    out["profileExtra"] = PROFILE_EXTRA
    os.makedirs(cfg.out, exist_ok=True)
    out["figures"] = make_plots(cfg, out)
    if out.get("mujoco", {}).get("wp"):
        from .bench_mujoco import plot as mujoco_plot
        out["figures"].append(mujoco_plot(out["mujoco"], os.path.join(cfg.figdir, "wp_mujoco.png")))
        out["mujoco"]["figure"] = "bench_figures/wp_mujoco.png"
    if out.get("adaptive"):
        from .bench_adaptive import plot as adaptive_plot
        figs = adaptive_plot(out["adaptive"], cfg.figdir)
        out["figures"] += figs
        out["adaptive"]["figures"] = [os.path.join("bench_figures", os.path.basename(f)) for f in figs]
    if out.get("stiff"):
        from .bench_stiff import plot as stiff_plot
        figs = stiff_plot(out["stiff"]["models"], cfg.figdir)
        out["figures"] += figs
        out["stiff"]["figures"] = [os.path.join("bench_figures", os.path.basename(f)) for f in figs]
    write_report(cfg, out, cmdline)
    if args.readme:
        from .generated import update_file_block
        update_file_block(args.readme, "bench", cmdline, readme_summary(cfg, out))
    dump = {k: v for k, v in out.items() if k not in ("refs", "perstep")}
    dump["refs"] = {m: {k: dict(time=r["time"], steps=r["steps"]) for k, r in d.items()} for m, d in out.get("refs", {}).items()}
    with open(os.path.join(cfg.out, "bench_results.json"), "w") as f:
        json.dump(_jsonable(dump), f, indent=1)
    log(f"wrote {os.path.join(cfg.out, 'BENCHMARKS.md')} and {len(out['figures'])} figures")
    return 0


# the optimisation record: what was measured, what changed, what it bought.  Every "before"
# number comes from a command of this repository run at the commit named in the row (check
# it out and run the command); "after" is this report.
PROFILE_EXTRA = """\
| 2 | where a stage goes: in a constrained step the constraint rows and the index-1 solve dominate; the Lie group maps are a small part (section 6: one SE(3) exp + dexpinv per body and stage, against the cost per step of section 2) | - (measurement) | tells where to look |
| 3 | cold start: numba's compile time grows steeply with the size of the namedtuples a compiled function receives (a 55-array `SceneData` and a 50-array `Work` were passed to every kernel function, and everything was IR-inlined into four separately compiled entry points) | only the entry points take the tuples; the working functions receive the few arrays they use and are compiled once (joint rows, spring and torsion forces, Schur solve, energies), the light per-stage ones stay inlined; `SceneData` packs each feature into a few tables, `Work` its 25 scratch vectors into two arrays; the accelerations for Exudyn's `q_tt` come from `mk_steps` with no step (one call site of the right-hand side instead of a second full compile) and the node write-back has one compiled entry | `bench --sections startup` at commit 3cb19c5: first run 38.8 s (kernel path) / 70.6 s (SolveDynamic); now: section 4. The cost per step did not change (section 2) |
| 4 | set-up was O(N^3): the redundancy check ran a dense SVD of the m x 6N constraint Jacobian, the consistency check built it (144 MB at N = 1000) | the kernel's own band Cholesky at the initial state decides (the SVD runs only for a singular system, to name its joints); J V is formed row by row | `bench --sections scaling --chain 300,1000` at commit 3cb19c5: set-up 0.59 s (N = 300), 21.9 s (N = 1000); now: section 3 |
| 5 | stabilisation ran a Python step loop with a dense least-squares projection per step | velocity and position projection compiled into the time loop, sharing the banded Schur complement of the index-1 solve | `stress --cases longrun` at commit f7e0786: 46 / 68 us per projected heavy-top step (SE3, velocity / position), 52 / 129 us (SO3xR3); now 3.5-4.1 us (STRESS.md, long runs) |
| 6 | blow-up handling: the rejected step was recomputed from the segment start, and the suggested step h/10 was itself unstable for large steps (one stress probe suggested 5.6e-10 s and ran for minutes) | the kernel keeps a copy of the last accepted state (18 doubles per body) and restores it; the suggestion is 0.8 r / rho with rho the spectral radius of the linearised equations (power iteration, a few right-hand sides) and r the tableau's stability half-disk radius | every suggested step is stable (STRESS.md, groupmaps) |
| 7 | bridge outputs: per Exudyn output step the hook made two compiled calls (the sub-steps, then the write-back), and each call unboxes every array it receives (~80 arrays of the scene and work tuples and the node table): ~5 us per output, a sixth of the ten heavy-top steps between two outputs at h = 1e-3 s and Exudyn's default period of 0.01 s | `mk_steps` records the state (and, from the first stage of the following step, the accelerations and multipliers) at each output of a chunk of up to 256 outputs; `write_rows` converts the chunk in one call; the hook copies one row into mbs | `bench --sections overhead` at commit 873fb9b: a sensor every 10 steps 15.4 % of the run (the bridge's calls 14.4 %); now: section 5 |
| 8 | tried and not kept: `inline="always"` on the leaf helpers (`body_point`, `apply_minv`, ...) and un-inlining the per-stage functions, after row 3 | - | no measurable change per step, cold start slower |
| 9 | the index-1 solve's band Cholesky was row-oriented `L L^T`: each entry of a row waited on the previous one, and every column paid a square root and a division; with the zero terms of world-axis translation rows (spherical joints) computed as well, and the Schur complement's assembly re-reading both rows' bodies per entry | right-looking band `L D L^T` (one division and one multiply-subtract per column on the dependency chain; same pivots `D_i = L_ii^2`, same rank rule; `tests/test_linalg.py`); world-axis translation rows skip their zero terms, and the assembly reads row q's bodies once per row (both bit-identical) | `bench --sections perstep --quick --models heavytop,doublependulum` at commit ac5b07e, twice interleaved with the change: heavy top 1.24-1.35 us, double pendulum 2.71-2.91 us per step; after 1.14-1.19 us and 2.10-2.23 us. The assembly, the same command at commit 4ea90cf, twice interleaved: heavy top 1.25-1.35 -> 1.02-1.09 us, double pendulum 2.27-2.32 -> 2.16-2.21 us; now: section 2. States differ at round-off (the paper block regenerated, 36 claims confirmed) |
"""
