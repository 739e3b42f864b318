"""``python -m exudyn_lie paper``: reproduce the examples of Müller & Terze.

Runs every model of :mod:`exudyn_lie.models` (the paper's mechanisms as Exudyn models) with
MK-RK4 on SE(3) and on SO(3)xR3 (through :class:`exudyn_lie.bridge.LieGroupSolver`,
compiled ``Run`` path) and with Exudyn's own solvers, at dt = 1e-2, 1e-3, 1e-4 s over
the paper's time spans; at dt >= 1e-3 the MK-RK4 runs are repeated through the drop-in
``exl.SolveDynamic`` (Exudyn's time loop, every step recorded by sensors) as a
cross-check.  Then it writes to ``--out`` (default ``./paper_results``):

* ``REPRODUCTION.md`` - set-up, a verdict per claim of the paper, the maximum violation
  per model / joint / group / step (and the same for Exudyn's solvers), energy drift,
  the heavy top's E(0), a cross-check of the kernel's diagnostics, the choices made
  where the paper has gaps, and run times.  Its first line names the command and
  holds the SHA-256 of the rest.
* one PNG figure per model: every measure over time, one column per step size, MK-RK4 on
  SE(3) and SO(3)xR3 and Exudyn's solvers on the same axes (:mod:`.plots`).

Options: ``--quick`` (dt = 1e-2 and 1e-3 only), ``--out DIR``, ``--jobs N`` (worker
processes, default 2), ``--models a,b`` (a subset), ``--no-figures``, ``--no-native``,
``--readme docs/PAPER.md`` (also rewrite that file's generated summary block).
"""
from __future__ import annotations

import argparse
import contextlib
import io
import multiprocessing as mp
import os
import shlex
import sys
import time
import warnings
from dataclasses import dataclass, field
from typing import Dict

from . import versions

DTS_FULL = (1e-2, 1e-3, 1e-4)
DTS_QUICK = (1e-2, 1e-3)
GROUPS = ("SE3", "SO3xR3")
IMPLICIT = ("GeneralizedAlpha", "TrapezoidalIndex2")
CROSSCHECK_MIN_DT = 1e-3        # the SolveDynamic cross-check runs at these step sizes and above
VIA_SOLVE_DYNAMIC = " SolveDynamic"     # result key suffix: ('SE3 SolveDynamic', dt)
README_BLOCK = "paper"


@dataclass
class Context:
    command: str
    dts: tuple
    jobs: int
    versions: Dict[str, str]
    infos: list = field(default_factory=list)
    results: Dict[str, dict] = field(default_factory=dict)      # model -> {(solver, dt): RunData}
    natives: Dict[str, list] = field(default_factory=dict)
    verdicts: list = field(default_factory=list)
    heavyTop: dict = None
    figures: Dict[str, list] = field(default_factory=dict)
    wallTime: float = 0.0
    planar: dict = None          # the extension section (apps/paper_planar.py), full runs only


def _task(args):
    """Worker: one model, either both MK-RK4 groups (``kind='lie'``) or its native solvers
    (``kind='native'``), all step sizes.  Returns (model, kind, runs, wall time)."""
    name, kind, dts = args
    import exudyn as exu
    from exudyn_lie import models
    from exudyn_lie.apps.runs import LieRunner, run_native, run_solve_dynamic
    tic = time.perf_counter()
    runs = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if kind == "lie":
            mbs, info = models.build(name)
            keep = info.exact is not None        # free bodies: keep R for the rotation comparison
            for g in GROUPS:
                lr = LieRunner(info, g)
                for dt in dts:
                    runs[(g, dt)] = lr.run(dt, keep_states=keep)
            for g in GROUPS:                     # the same runs through exl.SolveDynamic (cross-check)
                for dt in dts:
                    if dt >= CROSSCHECK_MIN_DT * (1 - 1e-9):
                        runs[(g + VIA_SOLVE_DYNAMIC, dt)] = run_solve_dynamic(info, g, dt)
        else:
            mbs, info = models.build(name)
            natives = tuple(models.native_solvers_for(info))
            for s in natives:
                nt = exu.NodeType.RotationEulerParameters if s in IMPLICIT else exu.NodeType.RotationRotationVector
                mbs, info = models.build(name, nodeType=nt)
                for dt in dts:
                    with contextlib.redirect_stdout(io.StringIO()):    # Exudyn's failure banners
                        runs[(s, dt)] = run_native(info, s, dt)
    return name, kind, runs, time.perf_counter() - tic


def _figure_task(args):
    """Worker: the figure of one model (all solvers on the same axes); returns (model, file names)."""
    name, runs, dts, natives, out = args
    from exudyn_lie import models
    from exudyn_lie.apps.plots import plot_model
    info = models.build(name)[1]
    paths = plot_model(info, runs, dts, out, solvers=GROUPS, natives=natives)
    return name, [os.path.basename(p) for p in paths]


def _warm_up():
    """Load (or compile) the numba kernel once in the parent, before the workers fork."""
    from exudyn_lie import models
    from exudyn_lie.apps.runs import LieRunner
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name in ("heavy_top", "planar_four_bar"):
            mbs, info = models.build(name)
            LieRunner(info, "SE3").run(1e-3, endTime=0.01)


def _say(msg):
    print(msg, flush=True)


def run_all(model_names=None, dts=DTS_FULL, jobs=2, native=True, out=None, progress=_say):
    """Run everything (and draw the figures into ``out`` unless it is None).
    Returns (infos, results, natives, figures)."""
    from exudyn_lie import models
    names = list(model_names or models.MODELS)
    infos = [models.build(n)[1] for n in names]
    natives = {i.name: (models.native_solvers_for(i) if native else []) for i in infos}
    kinds = ("lie", "native") if native else ("lie",)
    # longest first (the implicit solvers on the pendulum chains, then the big MK runs)
    cost = {i.name: len(i.bodies) * i.endTime for i in infos}
    tasks = sorted([(i.name, k, tuple(dts)) for i in infos for k in kinds],
                   key=lambda t: -cost[t[0]] * (1.5 if t[1] == "native" and natives[t[0]][0] in IMPLICIT else 1))
    results = {i.name: {} for i in infos}
    figures = {i.name: [] for i in infos}
    progress(f"exudyn_lie paper: {len(infos)} models x (MK-RK4 SE3, SO3xR3"
             f"{', Exudyn native' if native else ''}) x dt = {', '.join(f'{d:g}' for d in dts)}; "
             f"{len(tasks)} tasks on {jobs} process(es)")
    tic = time.perf_counter()
    _warm_up()
    progress(f"  kernel ready ({time.perf_counter() - tic:.1f} s)")

    def collect(k, res):
        name, kind, runs, wall = res
        results[name].update(runs)
        bad = [f"{s} dt={dt:g}" + (f" at t={rd.times[-1]:.3g} s" if len(rd.times) else "")
               for (s, dt), rd in runs.items() if not rd.ok]
        label = "MK-RK4 SE3+SO3xR3" if kind == "lie" else "Exudyn " + "+".join(natives[name])
        progress(f"  [{k:2d}/{len(tasks)}] {name:27s} {label:38s} {wall:6.1f} s"
                 + (f"  (stopped: {', '.join(bad)})" if bad else ""))

    fig_tasks = lambda: [(i.name, {key: rd for key, rd in results[i.name].items() if key[0] in GROUPS
                                   or key[0] in natives[i.name]}, tuple(dts), tuple(natives[i.name]), out)
                         for i in infos]
    if jobs > 1 and len(tasks) > 1:
        ctx = mp.get_context("fork")
        with ctx.Pool(jobs) as pool:
            for k, res in enumerate(pool.imap_unordered(_task, tasks), 1):
                collect(k, res)
            if out is not None:                  # one figure per model, once all its runs are in
                for name, figs in pool.imap_unordered(_figure_task, fig_tasks()):
                    figures[name] += figs
    else:
        for k, t in enumerate(tasks, 1):
            collect(k, _task(t))
        if out is not None:
            for name, figs in map(_figure_task, fig_tasks()):
                figures[name] += figs
    return infos, results, natives, figures


def evaluate(ctx: Context):
    from exudyn_lie.apps.claims import heavy_top_energy_verdict, judge_model
    ctx.verdicts = []
    for info in ctx.infos:
        runs = {k: v for k, v in ctx.results[info.name].items() if k[0] in GROUPS}
        ctx.verdicts += judge_model(info, runs, ctx.dts)
        if info.name == "heavy_top":
            rd = ctx.results[info.name].get(("SE3", ctx.dts[0]))
            if rd is not None and len(rd.energy):
                ctx.heavyTop = heavy_top_energy_verdict(info, rd)
    return ctx.verdicts


def write(ctx: Context, out, readme=None):
    """REPRODUCTION.md into ``out``; with ``readme`` also the summary block of that file."""
    from exudyn_lie.apps.generated import update_file_block, with_header
    from exudyn_lie.apps.report import readme_summary, write_report
    text = with_header(ctx.command, write_report(ctx))
    path = os.path.join(out, "REPRODUCTION.md")
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    if readme:
        update_file_block(readme, README_BLOCK, ctx.command, readme_summary(ctx))
    return path


def parse_args(argv):
    ap = argparse.ArgumentParser(prog="python -m exudyn_lie paper",
                                 description="Reproduce Müller & Terze's examples: MK-RK4 on SE(3) vs SO(3)xR3 "
                                             "and Exudyn's native solvers; writes REPRODUCTION.md and figures.")
    ap.add_argument("--quick", action="store_true", help="dt = 1e-2 and 1e-3 only (< 1 minute)")
    ap.add_argument("--out", default="paper_results", help="output directory (default ./paper_results)")
    ap.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1),
                    help="worker processes (default: 2, or 1 on a single core)")
    ap.add_argument("--models", default=None, help="comma-separated subset of: " + ", ".join(_model_names()))
    ap.add_argument("--no-figures", action="store_true", help="skip the PNG figures")
    ap.add_argument("--no-native", action="store_true", help="skip Exudyn's native solvers")
    ap.add_argument("--readme", default=None, metavar="FILE",
                    help="also write the summary (verdicts, Tables 1-3) into the generated block of FILE "
                         "(the repository's docs/PAPER.md)")
    return ap.parse_args(argv)


def _model_names():
    from exudyn_lie import models
    return models.MODELS


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    args = parse_args(argv)
    names = None
    if args.models:
        names = [n.strip() for n in args.models.split(",") if n.strip()]
        unknown = [n for n in names if n not in _model_names()]
        if unknown:
            print(f"unknown model(s) {unknown}; available: {', '.join(_model_names())}", file=sys.stderr)
            return 2
    if args.readme and not os.path.exists(args.readme):
        print(f"--readme {args.readme}: no such file", file=sys.stderr)
        return 2
    os.makedirs(args.out, exist_ok=True)
    tic = time.perf_counter()
    dts = DTS_QUICK if args.quick else DTS_FULL
    command = "python -m exudyn_lie paper" + ("" if not argv else " " + " ".join(shlex.quote(a) for a in argv))
    ctx = Context(command=command, dts=dts, jobs=max(1, args.jobs), versions=versions())
    ctx.infos, ctx.results, ctx.natives, ctx.figures = run_all(
        names, dts, ctx.jobs, native=not args.no_native, out=None if args.no_figures else args.out)
    evaluate(ctx)
    if names is None:
        from exudyn_lie.apps.paper_planar import planar_extension
        ctx.planar = planar_extension(dts)
    ctx.wallTime = time.perf_counter() - tic
    path = write(ctx, args.out, args.readme)
    counts = {}
    for v in ctx.verdicts:
        counts[v.verdict] = counts.get(v.verdict, 0) + 1
    print(f"exudyn_lie paper: {', '.join(f'{n} {k}' for k, n in sorted(counts.items()))}; wrote {path} "
          f"({ctx.wallTime:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
