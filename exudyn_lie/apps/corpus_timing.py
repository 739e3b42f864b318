"""The time inside ``SolveDynamic`` in a corpus run: native against exudyn_lie, per script and
over the corpus, with exudyn_lie's time split into set-up (the fixed cost), numba's
compilation (a kind of model seen for the first time on the machine) and the time loop
(``exudyn_lie.GetSolveTiming``).

The *warm* time leaves out the compilation: what a script costs once the machine has compiled
its kind of model (the caches are per machine).  The ratios are taken over the scripts that
both runs finish; the median over those whose native solves take more than
:data:`SUBSTANTIAL` seconds (below it the fixed costs are the whole difference, shown apart).
"""
from __future__ import annotations

import statistics

SUBSTANTIAL = 0.05      # native seconds in SolveDynamic above which a ratio says something
SHORT = 0.02            # native seconds below which a script is a short run


def script_times(rec):
    """``dict(native, exl, setup, compile, loop, path)`` (seconds summed over the script's
    solves) of a script that both runs finished, else None."""
    nat, exl = rec["native"], rec.get("exl")
    if rec.get("exlStatus") != "ok" or not exl or nat["status"] != "ok":
        return None
    ns, es = nat["solves"], exl["solves"]
    if not ns or len(ns) != len(es) or any(s.get("seconds") is None for s in ns + es):
        return None
    out = dict(native=sum(s["seconds"] for s in ns), exl=sum(s["seconds"] for s in es), setup=0.0, compile=0.0,
               loop=0.0, path=set())
    for s in es:
        t = s.get("timing")
        if t is None:
            return None
        for k in ("setup", "compile", "loop"):
            out[k] += t[k]
        out["path"].add(t["path"] or "?")
    out["path"] = "+".join(sorted(out["path"]))
    out["warm"] = out["exl"] - out["compile"]
    return out


def timed_scripts(records):
    """``[(name, script_times)]`` of the scripts both runs finished, in record order."""
    return [(r["name"], t) for r in records if (t := script_times(r)) is not None]


def _median(values):
    return statistics.median(values) if values else None


def timing_summary(records):
    """The corpus figures: per path the median warm ratio exl / native over substantial
    scripts, how many are faster than native, the fixed cost added to short runs, and the
    compilation paid over the whole corpus."""
    rows = timed_scripts(records)
    big = [t for _, t in rows if t["native"] > SUBSTANTIAL]
    short = [t for _, t in rows if t["native"] < SHORT]
    paths = sorted({t["path"] for t in big})
    compiles = [(t["compile"], n) for n, t in rows]
    return dict(
        scripts=len(rows), substantial=len(big),
        medianWarmRatio=_median([t["warm"] / t["native"] for t in big]),
        medianRatio=_median([t["exl"] / t["native"] for t in big]),
        perPath={p: dict(scripts=sum(t["path"] == p for t in big),
                         medianWarmRatio=_median([t["warm"] / t["native"] for t in big if t["path"] == p]),
                         faster=sum(t["warm"] < t["native"] for t in big if t["path"] == p)) for p in paths},
        faster=sum(t["warm"] < t["native"] for t in big),
        short=len(short), shortMedianAdded=_median([t["warm"] - t["native"] for t in short]),
        shortMedianSetup=_median([t["setup"] for t in short]),
        medianSetup=_median([t["setup"] for _, t in rows]),
        compileTotal=sum(c for c, _ in compiles), compileMax=max(compiles, default=(0.0, None)),
        compiledScripts=sum(c > 0 for c, _ in compiles),
    )


def _s(v, digits=3):
    return "-" if v is None else f"{v:.{digits}g}"


def render_timing(records, s):
    """The report's section on time (Markdown lines)."""
    L = ["", "## Time inside `SolveDynamic`", "",
         "Seconds inside `SolveDynamic` (summed over a script's solves), native against exudyn_lie, whose time is "
         "split into set-up (reading the model, the solver, Exudyn's InitializeSolver: the fixed cost), numba's "
         "compilation (a kind of model new to this machine) and the time loop (`exudyn_lie.GetSolveTiming()`). "
         "*Warm*: without the compilation. Over the scripts both runs finish.", ""]
    if not s["scripts"]:
        return L + ["No script finished both ways."]
    L += [f"* scripts: {s['scripts']}; with native solves over {SUBSTANTIAL:g} s: {s['substantial']}",
          f"* **median warm ratio exudyn_lie / native** (native over {SUBSTANTIAL:g} s): "
          f"{_s(s['medianWarmRatio'])}; with compilation {_s(s['medianRatio'])}; faster than native: "
          f"{s['faster']} of {s['substantial']}"]
    L += [f"  * {p} path: {v['scripts']} scripts, median warm ratio {_s(v['medianWarmRatio'])}, faster: "
          f"{v['faster']}" for p, v in s["perPath"].items()]
    L += [f"* short runs (native under {SHORT:g} s): {s['short']}; exudyn_lie adds a median "
          f"{_s(s['shortMedianAdded'])} s warm, of which set-up {_s(s['shortMedianSetup'])} s; median set-up over "
          f"all scripts {_s(s['medianSetup'])} s",
          f"* compilation: {_s(s['compileTotal'])} s in all, in {s['compiledScripts']} scripts; the most in one "
          f"script {_s(s['compileMax'][0])} s" + (f" (`{s['compileMax'][1]}`)" if s["compileMax"][1] else ""),
          "", "| script | path | native s | exudyn_lie s | set-up s | compile s | loop s | warm / native |",
          "|---|---|---|---|---|---|---|---|"]
    for name, t in timed_scripts(records):
        ratio = f"{t['warm'] / t['native']:.3g}" if t["native"] > 0 else "-"
        L.append(f"| `{name}` | {t['path']} | {t['native']:.4g} | {t['exl']:.4g} | {t['setup']:.3g} | "
                 f"{t['compile']:.3g} | {t['loop']:.4g} | {ratio} |")
    return L
