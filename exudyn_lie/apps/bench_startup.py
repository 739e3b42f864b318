"""Bench section ``startup``: the fixed cost a script pays before its first step.

Each run is a fresh interpreter (:data:`STARTUP_SCRIPT`) that does what a short user script
does: import numpy and Exudyn (the script's own imports, not counted), import
``exudyn_lie`` and resolve ``exudyn_lie.SolveDynamic`` (the package imports lazily, so this
is where its modules and numba load), build the heavy top (``models.build``), and solve it
twice with the same settings (MK-RK4 on SE3, :data:`STEPS` steps of :data:`H` s).  The
*fixed cost of the first solve* is the first solve's time minus the second's: loading the
compiled kernel from numba's cache, typing the arguments of the compiled entry points, and
the first calls' set-up.  The kernel path does the same with ``Simulator(SceneFromExudyn(mbs))``
and ``Advance``.

Targets: warm cache (numba's cache beside the sources filled by an earlier run)
import <= 0.1 s and first-solve fixed cost <= 0.05 s; a first run ever (an empty
``NUMBA_CACHE_DIR``, everything compiled) <= 20 s wall on an idle machine (<= 30 s on a
loaded one; the load average is reported with it).  The children run with bytecode caching
on (``PYTHONDONTWRITEBYTECODE`` removed), as for an installed package whose ``.pyc`` files
pip wrote at install time.
"""
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

#: steps and step size of the two solves in a start-up run (heavy top)
STEPS, H = 100, 1e-3
IMPORT_TARGET_S = 0.1
FIRST_SOLVE_TARGET_S = 0.05
COLD_TARGET_IDLE_S, COLD_TARGET_LOADED_S = 20.0, 30.0
#: a 1-minute load average per core below this counts as an idle machine
IDLE_LOAD_PER_CORE = 0.25

STARTUP_SCRIPT = r"""
import json, sys, time
T, C = time.perf_counter, time.process_time
t0 = T()
import numpy as np
import exudyn as exu
t1, c1 = T(), C()
import numba                      # numba's own import, the first part of exudyn_lie's (reported apart)
tn = T()
import exudyn_lie
solve = exudyn_lie.SolveDynamic
t2, c2 = T(), C()
from exudyn_lie import models
path, steps, h = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])


def run():
    mbs, info = models.build("heavy_top")
    mbs.Assemble()
    tic, cic = T(), C()
    if path == "kernel":
        from exudyn_lie.bridge import SceneFromExudyn
        from exudyn_lie.mbs import Simulator
        sim = Simulator(SceneFromExudyn(mbs), "RK4", "SE3")
        sim.Advance(steps, h)
    else:
        ss = exu.SimulationSettings()
        ss.timeIntegration.numberOfSteps = steps
        ss.timeIntegration.endTime = steps * h
        ss.solution.file.write = False
        ss.solution.sensors.active = False
        solve(mbs, ss, method="RK4", liegroup="SE3", showProgress=False)
    return T() - tic, C() - cic


(first, firstCpu), (second, secondCpu) = run(), run()
print("BENCHJSON" + json.dumps(dict(userImports=t1 - t0, imports=t2 - t1, numbaImport=tn - t1, importsCpu=c2 - c1,
                                    firstSolve=first,
                                    secondSolve=second, firstFixedCpu=firstCpu - secondCpu, total=T() - t0)))
"""


def _loadavg():
    try:
        return list(os.getloadavg())
    except OSError:
        return [float("nan")] * 3


def startup_once(path, cache=None, steps=STEPS, h=H):
    """One fresh interpreter; ``cache``: a NUMBA_CACHE_DIR (None: the cache next to the
    sources, as a user has it after the first run)."""
    env = dict(os.environ)
    env.pop("NUMBA_CACHE_DIR", None)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    if cache:
        env["NUMBA_CACHE_DIR"] = cache
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    load = _loadavg()
    tic = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", STARTUP_SCRIPT, path, str(steps), repr(h)], env=env,
                       capture_output=True, text=True, cwd=root, timeout=1800)
    wall = time.perf_counter() - tic
    line = [x for x in p.stdout.splitlines() if x.startswith("BENCHJSON")]
    if p.returncode != 0 or not line:
        return dict(ok=False, wall=wall, load=load, message=(p.stderr.strip().splitlines() or ["?"])[-1][:300])
    d = json.loads(line[-1][len("BENCHJSON"):])
    d.update(ok=True, wall=wall, load=load, firstFixed=d["firstSolve"] - d["secondSolve"],
             notice="compiling the solver" in p.stderr)
    return d


def run_section(cfg, log):
    """``out["startup"]``: per path (kernel, bridge) the cold run (if ``cfg.coldStart``)
    and the medians of the warm runs."""
    res = {}
    nwarm = 5 if cfg.quick else 9
    for path in ("kernel", "bridge"):
        d = dict()
        if cfg.coldStart:
            with tempfile.TemporaryDirectory(prefix="exl_numba_cache_") as cache:
                log(f"start-up ({path}): cold run with an empty NUMBA_CACHE_DIR, load {_loadavg()[0]:.2f}")
                d["cold"] = startup_once(path, cache)
                d["cold"]["loadEnd"] = _loadavg()
                log(f"start-up ({path}): cold {d['cold']['wall']:.1f} s")
        log(f"start-up ({path}): {nwarm} warm runs (installed cache)")
        startup_once(path)             # make sure the installed cache holds every function
        warm = [startup_once(path) for _ in range(nwarm)]
        d["warmRuns"] = warm
        ok = [w for w in warm if w["ok"]]
        keys = ("wall", "imports", "numbaImport", "importsCpu", "firstSolve", "secondSolve", "firstFixed",
                "firstFixedCpu", "total", "userImports")
        d["warm"] = {k: float(np.median([w[k] for w in ok])) for k in keys} \
            if ok else dict(ok=False, message=warm[0].get("message", ""))
        if ok:
            d["warm"]["min"] = {k: float(np.min([w[k] for w in ok])) for k in keys}
            d["warm"]["load"] = float(np.median([w["load"][0] for w in ok]))
        log(f"start-up ({path}): warm imports {d['warm'].get('imports', np.nan):.3f} s, first-solve fixed cost "
            f"{d['warm'].get('firstFixed', np.nan):.3f} s")
        res[path] = d
    res["cores"] = os.cpu_count() or 1
    return res


def cold_target(load1, cores):
    """(target seconds, 'idle'/'loaded') for a cold run started at the 1-minute load ``load1``."""
    idle = np.isfinite(load1) and load1 / max(1, cores) <= IDLE_LOAD_PER_CORE
    return (COLD_TARGET_IDLE_S, "idle") if idle else (COLD_TARGET_LOADED_S, "loaded")


def target_lines(res):
    if not res:
        return []
    L = []
    cores = res.get("cores", os.cpu_count() or 1)
    for path in ("kernel", "bridge"):
        d = res.get(path)
        if not d:
            continue
        c = d.get("cold")
        if c:
            target, kind = cold_target(c["load"][0], cores)
            L.append(f"| start-up: first run ever, empty numba cache ({path} path) <= {target:g} s wall on {'an' if kind == 'idle' else 'a'} {kind} "
                     f"machine (<= {COLD_TARGET_IDLE_S:g} s idle, <= {COLD_TARGET_LOADED_S:g} s loaded) | "
                     f"{c['wall']:.3g} s wall, load average {c['load'][0]:.2f} at the start / "
                     f"{c.get('loadEnd', [np.nan])[0]:.2f} at the end on {cores} cores"
                     f"{', notice printed' if c.get('notice') else ''} | "
                     f"{'yes' if c.get('ok') and c['wall'] <= target else 'no'} |")
        w = d["warm"]
        if "wall" not in w:
            L.append(f"| start-up ({path} path) | failed: {w.get('message', '')} | no |")
            continue
        if path == "bridge":
            L.append(f"| start-up, warm cache: `import exudyn_lie` + `exudyn_lie.SolveDynamic` (after numpy and "
                     f"Exudyn) <= {IMPORT_TARGET_S:g} s | {w['imports']:.3g} s (median, min {w['min']['imports']:.3g} s; "
                     f"CPU {w['importsCpu']:.3g} s; of it numba's own import {w['numbaImport']:.3g} s; load {w['load']:.2f}) | "
                     f"{'yes' if w['imports'] <= IMPORT_TARGET_S else 'no'} |")
        L.append(f"| start-up, warm cache: first solve's fixed cost ({path} path; heavy top, {STEPS} steps: first "
                 f"minus second identical solve) <= {FIRST_SOLVE_TARGET_S:g} s | {w['firstFixed']:.3g} s (median, min "
                 f"{w['min']['firstFixed']:.3g} s; CPU {w['firstFixedCpu']:.3g} s; first {w['firstSolve']:.3g} s, second "
                 f"{w['secondSolve']:.3g} s) | "
                 f"{'yes' if w['firstFixed'] <= FIRST_SOLVE_TARGET_S else 'no'} |")
    return L


def report_lines(res):
    if not res:
        return []
    L = ["## 4. Start-up", "",
         "A fresh interpreter (subprocess) imports numpy and Exudyn, then `exudyn_lie` and its `SolveDynamic` "
         "('imports'), builds the heavy top with `models.build` and solves it twice, MK-RK4 on SE3, "
         f"{STEPS} steps of {H:g} s, either through the kernel (`Simulator(SceneFromExudyn(mbs)).Advance`) or through "
         "the drop-in `exudyn_lie.SolveDynamic(mbs, ss)`. The first solve's fixed cost is the first solve's time minus "
         "the second's. 'Cold': `NUMBA_CACHE_DIR` points to an empty directory, so every compiled function is "
         "compiled (the first run after a fresh install); 'warm': the installed cache (`__pycache__` next to the "
         "sources, filled by an earlier run; median of the warm runs, with the load average at their start; CPU: the "
         "process's CPU time of the same interval, which leaves out the time other jobs on the machine get). Wall = "
         "process start to exit.", "",
         "| path | cold: wall (load at start) | warm: wall | warm: imports (CPU) | warm: first solve / second solve | "
         "warm: first solve's fixed cost (CPU) | load |",
         "|---|---|---|---|---|---|---|"]
    for path in ("kernel", "bridge"):
        d = res.get(path)
        if not d:
            continue
        c = d.get("cold")
        w = d["warm"]
        cw = (f"{c['wall']:.3g} s ({c['load'][0]:.2f})" if c and c["ok"] else
              ("failed: " + c.get("message", "") if c else "not measured"))
        if "wall" in w:
            L.append(f"| {path} | {cw} | {w['wall']:.3g} s | {w['imports']:.3g} s ({w['importsCpu']:.3g} s) | "
                     f"{w['firstSolve']:.3g} s / {w['secondSolve']:.3g} s | {w['firstFixed']:.3g} s "
                     f"({w['firstFixedCpu']:.3g} s) | {w['load']:.2f} |")
        else:
            L.append(f"| {path} | {cw} | failed | - | - | - | - |")
    L.append("")
    return L
