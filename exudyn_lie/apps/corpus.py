"""``python -m exudyn_lie corpus PATH [PATH ...]``: run ordinary Exudyn scripts natively and
through :func:`exudyn_lie.SolveDynamic`, unedited, and report what happens.

Every script (a ``.py`` file, or every ``*.py`` in a folder, not recursive; ``--match GLOB``
filters the file names) runs in a fresh interpreter (:mod:`.corpus_child`) with a time
limit:

1. **native**: as written, with graphics off (no window opens, nothing waits for a user);
2. **exl**: the same, with every ``SolveDynamic`` the script calls (``mbs.SolveDynamic``,
   ``exu.SolveDynamic``, ``SolveDynamic`` from ``exudyn.solver``) passed with the same
   arguments to ``exudyn_lie.SolveDynamic``.  Only when the native run reached a dynamic
   solve: otherwise the two runs would be the same;
3. **fine** (``--fine K``, default 10; 0: not): where exudyn_lie ran, natively with
   ``numberOfSteps`` times K in every ``SolveDynamic``: the reference for both, since
   Exudyn's generalized-alpha at the script's step is only second order.

The working directory of the runs is a copy of the script's folder (under ``OUT/cwd``), so
data files are found and files the script writes to relative paths do not land in its
source tree; one copy per job (``--jobs``), so scripts that run at the same time do not write
into each other's files (Exudyn's Examples share names such as ``solution/sensorPos.txt``).

Outcomes per script: native ``ok`` / ``error`` (class and first line) / ``timeout`` /
``died``; exudyn_lie ``ok``; ``refused`` (a ``SceneError`` / ``BridgeError``: input
exudyn_lie does not support, e.g. the first unsupported item, raised before ``mbs`` is
touched); ``stopped`` (a ``SimulationError`` during the run: ``StepSizeError``,
``ConstraintError``); ``crashed`` (any other exception out of ``exudyn_lie.SolveDynamic``,
a ``BridgeError`` that says "internal", a process that died during the solve, or an error
after ``exudyn_lie.SolveDynamic`` returned that the native run does not have: a bug or a
drop-in gap of exudyn_lie); ``timeout``; ``native error`` (the exl run failed with the
same error, class and first line, as the native run, e.g. in the script's own user
function).  ``exudynTestGlobals.testResult`` of the runs and the relative differences
``|a - b| / max(|a|, |b|)`` of exl against native and against the fine native run; for
every script, testResult or not (Exudyn's Examples set none), the final states of the solves
(ODE2 and ODE1 coordinates) against the fine native run, relative to the state's largest
entry, and the runs to look at: exl off the fine state by more than 1e-3 and by more than
10 times native's own difference.

Writes ``corpus.md`` and ``corpus.json`` to ``--out`` (default ``./corpus_results``), the
output of every run to ``OUT/logs``; one progress line per script.
"""
from __future__ import annotations

import argparse
import fnmatch
import hashlib
import json
import os
import queue
import re
import shlex
import shutil
import signal
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from . import versions
from .corpus_timing import render_timing, timing_summary

CHILD = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus_child.py")
PACKAGE_PARENT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXL_STATUSES = ("ok", "refused", "stopped", "crashed", "timeout", "native error")
RIGID_BODY_TYPES = ("ObjectRigidBody", "ObjectRigidBody2D")
REL_BUCKETS = (1e-10, 1e-6, 1e-3, 1e-1)
_LIVE = set()                  # the child processes running now (killed on an interrupt)
_LIVE_LOCK = threading.Lock()
_STOP = threading.Event()      # set on an interrupt: no new child starts


# ---------------------------------------------------------------------------------------------
# collecting scripts and their working directories

def collect_scripts(paths, match=None):
    """Absolute paths of the scripts: files as given, folders' ``*.py`` sorted by name;
    ``match``: a glob on the file name.  Raises FileNotFoundError for a missing path."""
    out = []
    for p in paths:
        p = Path(p)
        if p.is_dir():
            files = sorted(q for q in p.glob("*.py") if q.is_file())
        elif p.is_file():
            files = [p]
        else:
            raise FileNotFoundError(f"no such file or folder: {p}")
        for f in files:
            if match and not fnmatch.fnmatch(f.name, match):
                continue
            f = str(f.resolve())
            if f not in out:
                out.append(f)
    return out


def display_names(scripts):
    """File names, or paths relative to the scripts' common folder when names repeat."""
    names = [os.path.basename(s) for s in scripts]
    if len(set(names)) == len(names):
        return names
    common = os.path.commonpath([os.path.dirname(s) for s in scripts])
    return [os.path.relpath(s, common) for s in scripts]


def working_copy(script_dir, root, slot=0):
    """A copy of the script's folder under ``root`` (one per folder, job slot and invocation)."""
    tag = hashlib.sha1(script_dir.encode()).hexdigest()[:8]
    dest = Path(root) / (f"{os.path.basename(script_dir)}_{tag}" + (f"_{slot}" if slot else ""))
    if dest.exists():
        shutil.rmtree(dest)
    skip = os.path.realpath(root)

    def ignore(folder, names):            # __pycache__, and the output folder if it is inside
        return [n for n in names if n == "__pycache__" or os.path.realpath(os.path.join(folder, n)) == skip]
    shutil.copytree(script_dir, dest, symlinks=True, ignore=ignore)
    return str(dest)


# ---------------------------------------------------------------------------------------------
# one run of one script in a child process

def child_env(mode):
    env = dict(os.environ)
    env["MPLBACKEND"] = "Agg"
    env["EXUDYN_SUPPRESS_UI_WINDOW_OPEN"] = "1"
    env["PYTHONUNBUFFERED"] = "1"
    # bytecode caching on, as an installed package has it (bench_startup.py too): with
    # PYTHONDONTWRITEBYTECODE every exudyn_lie run compiled the package's modules from source
    # again, about 0.1 s of its set-up (0.26 s against 0.15 s inside SolveDynamic of
    # sensorUserFunctionTest.py)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    if mode == "exl":      # the native run imports nothing of exudyn_lie
        env["EXUDYN_LIE_TRACEBACK"] = "1"      # the report names where in exudyn_lie an error arose
        env["PYTHONPATH"] = PACKAGE_PARENT + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def read_events(path):
    events = []
    try:
        with open(path, encoding="utf-8") as f:
            for line in f:
                try:
                    events.append(json.loads(line))
                except json.JSONDecodeError:     # a line cut by the time limit
                    pass
    except FileNotFoundError:
        pass
    return events


def _log_tail(path, lines=3):
    try:
        text = Path(path).read_text(errors="replace").strip().splitlines()
    except OSError:
        return ""
    return " | ".join(text[-lines:])[:300]


def run_script(mode, script, cwd, timeout, logdir, stem, factor=None):
    """Run ``script`` once (mode 'native', 'exl' or 'fine' with ``factor``); returns the run's record."""
    log = os.path.join(logdir, f"{stem}.{mode}.log")
    events_path = os.path.join(logdir, f"{stem}.{mode}.events")
    if os.path.exists(events_path):
        os.remove(events_path)
    tic = time.perf_counter()
    timed_out = False
    with open(log, "wb") as lf:
        argv = [sys.executable, CHILD, mode, script, events_path] + ([str(factor)] if factor else [])
        proc = subprocess.Popen(argv, cwd=cwd, stdout=lf,
                                stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, env=child_env(mode),
                                start_new_session=True)
        with _LIVE_LOCK:
            _LIVE.add(proc)
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            timed_out = True
        finally:
            _kill_session(proc)           # the script's own subprocesses end with it
            with _LIVE_LOCK:
                _LIVE.discard(proc)
        rc = proc.wait()
    wall = time.perf_counter() - tic
    return run_record(mode, read_events(events_path), timed_out, rc, wall, log)


def _kill_session(proc):
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


def kill_running_children():
    """End the sessions of the children still running (after an interrupt)."""
    with _LIVE_LOCK:
        procs = list(_LIVE)
    for proc in procs:
        _kill_session(proc)


def run_record(mode, events, timed_out, rc, wall, log):
    solves, open_solves, direct, inventory = [], {}, [], set()
    exit_ev = None
    for ev in events:
        kind = ev.get("ev")
        if kind == "solve":
            s = dict(n=ev["n"], solverType=ev.get("solverType"), status="running")
            solves.append(s)
            open_solves[ev["n"]] = s
            inventory.update(ev.get("inventory") or ())
        elif kind in ("solve_end", "solve_error"):
            s = open_solves.pop(ev["n"], None)
            if s is not None:
                s["seconds"] = ev.get("seconds")
                s["timing"] = ev.get("timing")
                s["state"] = ev.get("state")
                s["status"] = "ok" if kind == "solve_end" else "error"
                if kind == "solve_error":
                    s["exl"] = ev.get("exl")
                    s["error"] = {k: ev.get(k) for k in ("cls", "module", "msg", "where", "whereExl", "tb")}
        elif kind == "direct_solver":
            direct.append(ev["call"])
        elif kind == "exit":
            exit_ev = ev
    if timed_out:
        status, error = "timeout", None
    elif exit_ev is not None:
        status, error = exit_ev["status"], exit_ev.get("error")
    else:
        status = "died"
        error = dict(cls="died", module="", msg=f"the process ended without a report (exit code {rc}): "
                     f"{_log_tail(log)}", where="", whereExl="", tb="")
    return dict(mode=mode, status=status, wall=round(wall, 3), rc=rc, error=error,
                testResult=exit_ev.get("testResult") if exit_ev else None,
                solves=solves, inSolve=any(s["status"] == "running" for s in solves),
                directSolvers=direct, inventory=sorted(inventory), log=log)


# ---------------------------------------------------------------------------------------------
# classification

def error_line(err):
    if not err:
        return ""
    return f"{err.get('cls')}: {err.get('msg')}" if err.get("msg") else str(err.get("cls"))


def _key(err):
    return (err.get("cls"), err.get("msg"))


def native_errors(native):
    """(class, first line) of the errors of the native run: in its solves and at its end."""
    errs = {_key(s["error"]) for s in native["solves"] if s["status"] == "error"}
    if native["status"] == "error" and native["error"]:
        errs.add(_key(native["error"]))
    return errs


def exl_outcome(native, exl):
    """(status, reason) of the exl run; see the module doc for the statuses."""
    if exl is None:
        return None, ""
    failed = [s for s in exl["solves"] if s["status"] == "error"]
    if failed:
        s = failed[0]
        err = s["error"]
        if s.get("exl") == "refusal":
            return "refused", error_line(err)
        if s.get("exl") == "stop":
            return "stopped", error_line(err)
        if _key(err) in native_errors(native):      # e.g. the script's own user function failed
            return "native error", error_line(err)
        where = err.get("whereExl") or err.get("where")
        return "crashed", f"{error_line(err)} (at {where})" if where else error_line(err)
    if exl["status"] == "timeout":
        return "timeout", ("in exudyn_lie.SolveDynamic" if exl["inSolve"] else "outside exudyn_lie.SolveDynamic")
    if exl["status"] == "ok":
        return "ok", ""
    if exl["status"] == "bootstrap error":
        return "crashed", f"the exl run could not start: {error_line(exl['error'])}"
    if exl["status"] == "died":
        during = " during exudyn_lie.SolveDynamic" if exl["inSolve"] else ""
        return "crashed", f"process died{during}: {exl['error']['msg']}"
    err = exl["error"] or {}
    if _key(err) in native_errors(native):
        return "native error", error_line(err)
    where = err.get("where")
    return "crashed", f"after exudyn_lie.SolveDynamic returned: {error_line(err)}" + (f" (at {where})" if where else "")


def relative_difference(a, b):
    """|a - b| / max(|a|, |b|) for two numbers (0 when equal), else None."""
    if not isinstance(a, (int, float)) or not isinstance(b, (int, float)):
        return None
    if a == b:
        return 0.0
    return abs(a - b) / max(abs(a), abs(b))


STATE_FLOOR = 1e-12      # the least scale of a state (round-off of a state at rest is not a difference of 1)


def state_difference(a, b):
    """The largest difference of the final states of the solves of two runs (records),
    paired by their number, relative to the larger state's largest entry: ``max |a - b| /
    max(|a|_inf, |b|_inf, STATE_FLOOR)``; None without a pair of finished solves of equal size.  The
    comparison for scripts that set no testResult (most Examples)."""
    if not a or not b:
        return None
    sb = {s["n"]: s.get("state") for s in b["solves"] if s["status"] == "ok"}
    worst = None
    for s in a["solves"]:
        x, y = s.get("state") if s["status"] == "ok" else None, sb.get(s["n"])
        if not x or not y or len(x) != len(y):
            continue
        # (a floor: a model at rest, zero natively, 3e-17 here, was a relative difference of 1)
        scale = max(max(abs(v) for v in x), max(abs(v) for v in y), STATE_FLOOR)
        d = max(abs(u - v) for u, v in zip(x, y)) / scale
        worst = d if worst is None else max(worst, d)
    return worst


def suspect(rec):
    """exudyn_lie's final state is far from the fine native one while native's is near it:
    a run to look at (another model, or a chaotic motion; the note of each says which)."""
    d, dn = rec.get("stateDiffFine"), rec.get("stateDiffNativeFine")
    return d is not None and dn is not None and d > 1e-3 and d > 10 * dn


def refusal_key(reason):
    """The first unsupported thing named in a refusal: an item type ('ObjectMassPoint2D'), an
    item type with its option ('ObjectConnectorCoordinate: velocityLevel=True'), 'solverType=...', else the message up to its first ';' with numbers as '#'."""
    msg = reason.split(": ", 1)[1] if ": " in reason else reason
    m = re.search(r"of type (\w+) is not supported", msg)
    if m:
        return m.group(1)
    m = re.match(r"(?:object|load|marker|node|sensor) \d+ \('[^']*'\) (\w+): (.+?)(?: is | are |;|$)", msg)
    if m:                                   # an option of an item: 'ObjectConnectorCoordinate: velocityLevel=True'
        return f"{m.group(1)}: {m.group(2)}"[:100]
    m = re.match(r"solverType=(\S+)", msg)
    if m:
        return f"solverType={m.group(1)}"
    return re.sub(r"\b\d+(\.\d+)?\b", "#", msg.split(";")[0])[:100]


def classify(name, script, native, exl):
    if native["solves"]:
        dynamic = "yes"
    elif native["status"] == "ok":
        dynamic = "no"
    else:
        dynamic = "not reached"
    status, reason = exl_outcome(native, exl)
    tn = native["testResult"]
    te = exl["testResult"] if exl else None
    rec = dict(name=name, script=script, dynamic=dynamic, native=native, exl=exl, exlStatus=status,
               exlReason=reason, testResult=[tn, te], relDiff=relative_difference(tn, te),
               stateDiff=state_difference(native, exl) if status == "ok" else None,
               inventory=native["inventory"])
    rec["firstRefusal"] = refusal_key(reason) if status == "refused" else None
    rec["fine"] = rec["fineFactor"] = rec["testResultFine"] = rec["relDiffFine"] = rec["relDiffNativeFine"] = None
    rec["stateDiffFine"] = rec["stateDiffNativeFine"] = None
    return rec


def wants_fine_reference(rec):
    """A native run at a finer step is worth it where exudyn_lie ran and both set a number
    or both gave a final state."""
    return rec["exlStatus"] == "ok" and (rec["relDiff"] is not None or rec.get("stateDiff") is not None)


def add_fine_reference(rec, fine, factor):
    """The fine native run: its testResult and the relative differences of exl and of the
    native run at the script's step against it."""
    rec["fine"], rec["fineFactor"] = fine, factor
    tf = fine["testResult"] if fine["status"] == "ok" else None
    rec["testResultFine"] = tf
    rec["relDiffFine"] = relative_difference(rec["testResult"][1], tf)
    rec["relDiffNativeFine"] = relative_difference(rec["testResult"][0], tf)
    if fine["status"] == "ok":
        rec["stateDiffFine"] = state_difference(rec["exl"], fine)
        rec["stateDiffNativeFine"] = state_difference(rec["native"], fine)


def unsupported_types(inventory):
    """Item types of an inventory that are not in exudyn_lie's supported lists (None if the
    lists are not available)."""
    try:
        from ..bridge import reader
        # (names only: "NodeGenericData (data only)" is listed with a note)
        supported = {t.split(" ")[0] for t in reader.SUPPORTED_NODES + reader.SUPPORTED_OBJECTS
                     + reader.SUPPORTED_MARKERS + reader.SUPPORTED_LOADS}
    except (ImportError, AttributeError):
        return None
    return sorted(t for t in inventory if t not in supported)


# ---------------------------------------------------------------------------------------------
# summary and report

def _count(values, keys=None):
    out = {}
    for v in values:
        out[v] = out.get(v, 0) + 1
    if keys:
        return {k: out.get(k, 0) for k in keys} | {k: n for k, n in out.items() if k not in keys}
    return dict(sorted(out.items(), key=lambda kv: (-kv[1], str(kv[0]))))


def _buckets(values):
    out, lo = {}, None
    for hi in REL_BUCKETS:
        out[f"<= {hi:g}" if lo is None else f"({lo:g}, {hi:g}]"] = sum(d <= hi and (lo is None or d > lo) for d in values)
        lo = hi
    out[f"> {lo:g}"] = sum(d > lo for d in values)
    return out


def summarize(records):
    base = [r for r in records if r["native"]["status"] == "ok" and r["dynamic"] == "yes"]
    rigid = [r for r in base if any(t in r["inventory"] for t in RIGID_BODY_TYPES)]
    pairs = [r["relDiff"] for r in base if r["exlStatus"] == "ok" and r["relDiff"] is not None]
    fine = [r for r in base if r.get("relDiffFine") is not None]
    items = {}
    lists_available = True
    for r in base:
        unsup = unsupported_types(r["inventory"])
        if unsup is None:
            lists_available = False
            break
        # 'only': the one unsupported object / load type (nodes and markers come with them)
        others = [t for t in unsup if not t.startswith(("Node", "Marker"))] or unsup
        for t in unsup:
            contain, only = items.get(t, (0, 0))
            items[t] = (contain + 1, only + (others == [t]))
    s = dict(
        scripts=len(records),
        native=_count([r["native"]["status"] for r in records], ("ok", "error", "timeout", "died")),
        dynamic=_count([r["dynamic"] for r in records], ("yes", "no", "not reached")),
        directSolverOnly=sum(1 for r in records if r["dynamic"] == "no" and r["native"]["directSolvers"]),
        base=len(base),
        exl=_count([r["exlStatus"] for r in base], EXL_STATUSES),
        rigid=len(rigid), rigidOk=sum(r["exlStatus"] == "ok" for r in rigid),
        exlOnNativeFailures=_count([r["exlStatus"] for r in records
                                    if r["native"]["status"] != "ok" and r["exlStatus"]]),
        testResultPairs=len(pairs), relDiffBuckets=_buckets(pairs),
        fineReferences=len(fine), fineBuckets=_buckets([r["relDiffFine"] for r in fine]),
        exlCloserToFine=sum(r["relDiffFine"] <= r["relDiffNativeFine"] for r in fine),
        fineFailed=sum(1 for r in base if r.get("fine") and r["fine"]["status"] != "ok"),
        statePairs=sum(1 for r in base if r.get("stateDiffFine") is not None),
        stateBuckets=_buckets([r["stateDiffFine"] for r in base if r.get("stateDiffFine") is not None]),
        stateCloserToFine=sum(r["stateDiffFine"] <= r["stateDiffNativeFine"] for r in base
                              if r.get("stateDiffFine") is not None and r.get("stateDiffNativeFine") is not None),
        suspects=[r["name"] for r in base if suspect(r)],
        firstRefusal=_count([r["firstRefusal"] for r in base if r["firstRefusal"]]),
        unsupportedItems=(dict(sorted(items.items(), key=lambda kv: (-kv[1][0], kv[0])))
                          if lists_available else None),
        nativeErrors=_count([error_line(r["native"]["error"]) for r in records if r["native"]["status"] == "error"]),
        time=timing_summary(records),
    )
    return s


def _fmt_num(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.10g}"
    return str(v)[:40]


def _cell(text, width=160):
    text = str(text).replace("|", "\\|").replace("\n", " ")
    return text if len(text) <= width else text[:width - 1] + "…"


def _native_cell(r):
    n = r["native"]
    if n["status"] == "ok":
        return "ok"
    if n["status"] == "error":
        return "error: " + error_line(n["error"])
    return n["status"]


def render(records, summary, command, wall, timeout, fine=None):
    s = summary
    v = versions()
    L = [f"# Exudyn scripts through exudyn_lie.SolveDynamic", "",
         f"Generated by `{command}` ({wall:.0f} s; time limit {timeout:g} s per run; "
         + ", ".join(f"{k} {val}" for k, val in v.items()) + f", Python {sys.version.split()[0]}).", "",
         "Each script ran unedited in a fresh process, natively and with every `SolveDynamic` passed to "
         "`exudyn_lie.SolveDynamic` (same arguments); graphics off; bytecode caching on, as for an installed "
         "package. The second run only where the native run reached a `SolveDynamic`.", "",
         "## Summary", "",
         f"* scripts: {s['scripts']}",
         "* native: " + ", ".join(f"{k} {n}" for k, n in s["native"].items()),
         f"* `SolveDynamic` called: yes {s['dynamic']['yes']}, no {s['dynamic']['no']} "
         f"({s['directSolverOnly']} of them call a `MainSolver*` directly, not swapped), "
         f"not reached (native run failed first) {s['dynamic']['not reached']}",
         f"* **native ok and calling `SolveDynamic`: {s['base']}**; through exudyn_lie: "
         + ", ".join(f"{k} {n}" for k, n in s["exl"].items()),
         f"* of these, with rigid bodies (`ObjectRigidBody` / `ObjectRigidBody2D`): {s['rigid']}, "
         f"run to the end through exudyn_lie: {s['rigidOk']}",
         f"* testResult of both runs (exudyn_lie ok): {s['testResultPairs']} scripts; relative difference "
         + ", ".join(f"{k}: {n}" for k, n in s["relDiffBuckets"].items()),
         ]
    if s["fineReferences"] or s["fineFailed"]:
        L.append(f"* against a native run with {fine}x the steps (the script's step is no reference: "
                 f"generalized-alpha is 2nd order): {s['fineReferences']} scripts"
                 + (f" ({s['fineFailed']} more: the fine run failed or timed out)" if s["fineFailed"] else "")
                 + "; exudyn_lie's relative difference " + ", ".join(f"{k}: {n}" for k, n in s["fineBuckets"].items())
                 + f"; exudyn_lie at the script's step closer to it than native at the script's step: "
                 f"{s['exlCloserToFine']}")
    if s["statePairs"]:
        L.append(f"* final states (every script, testResult or not) against the native run with {fine}x the "
                 f"steps: {s['statePairs']} scripts; exudyn_lie's largest difference relative to the state's "
                 f"largest entry " + ", ".join(f"{k}: {n}" for k, n in s["stateBuckets"].items())
                 + f"; exudyn_lie closer to it than native at the script's step: {s['stateCloserToFine']}")
        L.append(f"* **to look at** (exudyn_lie off the fine state by more than 1e-3 and by more than 10x "
                 f"native's difference): {len(s['suspects'])}" + (": " + ", ".join(f"`{n}`" for n in s["suspects"])
                                                                  if s["suspects"] else ""))
    if s["exlOnNativeFailures"]:
        L.append("* exudyn_lie on scripts whose native run failed after reaching `SolveDynamic` (not counted "
                 "above): " + ", ".join(f"{k} {n}" for k, n in s["exlOnNativeFailures"].items()))
    L += ["", "## What stops exudyn_lie first (refusals, native ok)", "",
          "| first unsupported item / reason | scripts |", "|---|---|"]
    L += [f"| `{_cell(k)}` | {n} |" for k, n in s["firstRefusal"].items()] or ["| (none) | 0 |"]
    if s["unsupportedItems"] is not None:
        L += ["", "## Item types exudyn_lie does not read (native ok, `SolveDynamic` called)", "",
              "From the item types in `mbs` at the solve, against exudyn_lie's supported lists "
              "(`exudyn_lie.bridge.reader.SUPPORTED_*`; `GeneralContact` is not an item).", "",
              "| item type | scripts that contain it | scripts where it is the only unsupported object / load type "
              "(node and marker types not counted beside one) |",
              "|---|---|---|"]
        L += [f"| `{k}` | {c} | {o} |" for k, (c, o) in s["unsupportedItems"].items()] or ["| (none) | 0 | 0 |"]
    crashed = [r for r in records if r["exlStatus"] == "crashed"]
    L += ["", f"## Crashes: bugs or drop-in gaps of exudyn_lie ({len(crashed)})", ""]
    if not crashed:
        L.append("None.")
    for r in crashed:
        L.append(f"* `{r['name']}`: {_cell(r['exlReason'], 400)}")
        tb = next((sv["error"]["tb"] for sv in r["exl"]["solves"] if sv["status"] == "error"), None)
        tb = tb or ((r["exl"]["error"] or {}).get("tb"))
        if tb:
            L += ["", "  ```", *("  " + line for line in tb.splitlines()), "  ```", ""]
    timeouts = [r for r in records if r["exlStatus"] == "timeout"]
    if timeouts:
        L += ["", f"## exudyn_lie runs that reached the time limit ({len(timeouts)})", ""]
        L += [f"* `{r['name']}`: {r['exlReason']} (native: {_native_cell(r)}, {r['native']['wall']:.1f} s)"
              for r in timeouts]
    L += render_timing(records, s["time"])
    if s["nativeErrors"]:
        L += ["", "## Native failures (not counted against exudyn_lie)", "", "| native error | scripts |", "|---|---|"]
        L += [f"| {_cell(k, 200)} | {n} |" for k, n in s["nativeErrors"].items()]
    L += ["", "## All scripts", "",
          "| script | native | s | SolveDynamic | exudyn_lie | s | testResult native | testResult exudyn_lie "
          "| rel. diff | testResult native, fine step | rel. diff exudyn_lie vs fine "
          "| final state vs fine: exudyn_lie, native | reason |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in records:
        e = r["exl"]
        L.append("| " + " | ".join([
            f"`{r['name']}`", _cell(_native_cell(r), 80), f"{r['native']['wall']:.1f}", r["dynamic"],
            r["exlStatus"] or "", f"{e['wall']:.1f}" if e else "", _fmt_num(r["testResult"][0]),
            _fmt_num(r["testResult"][1]), f"{r['relDiff']:.2e}" if r["relDiff"] is not None else "",
            _fine_cell(r), f"{r['relDiffFine']:.2e}" if r.get("relDiffFine") is not None else "",
            _state_cell(r), _cell(r["exlReason"], 120)]) + " |")
    return "\n".join(L) + "\n"


def _state_cell(r):
    d, dn = r.get("stateDiffFine"), r.get("stateDiffNativeFine")
    if d is None:
        return ""
    return f"{d:.1e}, {dn:.1e}" + (" **look**" if suspect(r) else "")


def _fine_cell(r):
    f = r.get("fine")
    if not f:
        return ""
    if f["status"] != "ok":
        return f"x{r['fineFactor']}: {f['status']}"
    return f"x{r['fineFactor']}: {_fmt_num(r['testResultFine'])}"


def progress_line(i, total, r):
    n = r["native"]
    tr = ""
    if r["relDiff"] is not None:
        tr = f" | testResult {_fmt_num(r['testResult'][0])} / {_fmt_num(r['testResult'][1])} (rel {r['relDiff']:.1e})"
        if r.get("relDiffFine") is not None:
            tr += f"; native x{r['fineFactor']} {_fmt_num(r['testResultFine'])}: exl rel {r['relDiffFine']:.1e}"
        elif r.get("fine"):
            tr += f"; native x{r['fineFactor']} {r['fine']['status']}"
    if r.get("stateDiffFine") is not None:
        tr += f" | state vs x{r['fineFactor']}: exl {r['stateDiffFine']:.1e}, native {r['stateDiffNativeFine']:.1e}"
    exl = ""
    if r["exl"] is not None:
        exl = f" | exl {r['exlStatus']} {r['exl']['wall']:.1f} s" + (f": {r['exlReason']}" if r["exlReason"] else "")
    elif r["dynamic"] == "no":
        exl = " | no SolveDynamic"
    line = f"[{i:{len(str(total))}d}/{total}] {r['name']}: native {_native_cell(r)} {n['wall']:.1f} s{exl}{tr}"
    return line if len(line) <= 240 else line[:239] + "…"


# ---------------------------------------------------------------------------------------------

def run_corpus(scripts, outdir, timeout=120.0, jobs=1, log=print, fine=10):
    """Run every script natively and (when it reaches SolveDynamic) through exudyn_lie, and
    where exudyn_lie ran and both set testResult, natively with ``fine`` times the steps
    (0: not); returns the records in the order of ``scripts``."""
    outdir = Path(outdir).resolve()        # the children run in the scripts' working copies
    logdir = outdir / "logs"
    logdir.mkdir(parents=True, exist_ok=True)
    jobs = max(1, jobs)
    cwds = {(d, k): working_copy(d, outdir / "cwd", k) for d in sorted({os.path.dirname(s) for s in scripts})
            for k in range(jobs)}
    slots = queue.SimpleQueue()            # a job's slot: its own working copies
    for k in range(jobs):
        slots.put(k)
    names = display_names(scripts)
    records = [None] * len(scripts)
    lock = threading.Lock()
    done = [0]

    def one(i):
        script = scripts[i]
        stem = f"{i:04d}_{Path(script).stem}"
        slot = slots.get()

        def run(mode, factor=None):
            if _STOP.is_set():
                raise KeyboardInterrupt
            return run_script(mode, script, cwds[os.path.dirname(script), slot], timeout, str(logdir), stem, factor)
        try:
            native = run("native")
            exl = run("exl") if native["solves"] else None
            rec = classify(names[i], script, native, exl)
            if fine and wants_fine_reference(rec):
                add_fine_reference(rec, run("fine", fine), fine)
        finally:
            slots.put(slot)
        with lock:
            records[i] = rec
            done[0] += 1
            log(progress_line(done[0], len(scripts), rec))

    _STOP.clear()
    pool = ThreadPoolExecutor(max_workers=jobs)
    try:
        for f in [pool.submit(one, i) for i in range(len(scripts))]:
            f.result()
    except BaseException:                  # Ctrl-C / SIGTERM: stop now, not at the next time limit
        _STOP.set()
        try:
            signal.signal(signal.SIGINT, signal.SIG_IGN)     # a second Ctrl-C must not cut the clean-up
        except ValueError:                                   # not the main thread
            pass
        pool.shutdown(wait=False, cancel_futures=True)
        kill_running_children()
        raise
    pool.shutdown()
    return records


def _terminate(signum, frame):
    raise KeyboardInterrupt(f"signal {signum}")


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    ap = argparse.ArgumentParser(
        prog="python -m exudyn_lie corpus",
        description="Run Exudyn scripts natively and with SolveDynamic swapped for exudyn_lie.SolveDynamic "
                    "(scripts unedited, graphics off); writes corpus.md and corpus.json.")
    ap.add_argument("paths", nargs="+", metavar="PATH", help="a script, or a folder (its *.py files)")
    ap.add_argument("--out", default="corpus_results", help="output directory (default ./corpus_results)")
    ap.add_argument("--timeout", type=float, default=120.0, help="time limit per run in seconds (default 120)")
    ap.add_argument("--jobs", type=int, default=1, help="scripts run in parallel (default 1)")
    ap.add_argument("--match", default=None, metavar="GLOB", help="only file names matching GLOB, e.g. 'rigid*'")
    ap.add_argument("--fine", type=int, default=10, metavar="K",
                    help="where exudyn_lie ran and both runs set testResult or gave a final state, also run natively with K times "
                         "numberOfSteps as the reference (default 10; 0: not)")
    args = ap.parse_args(argv)
    try:
        scripts = collect_scripts(args.paths, args.match)
    except FileNotFoundError as e:
        print(f"exudyn_lie corpus: {e}", file=sys.stderr)
        return 2
    if not scripts:
        print("exudyn_lie corpus: no scripts found", file=sys.stderr)
        return 2
    command = "python -m exudyn_lie corpus " + " ".join(shlex.quote(a) for a in argv)
    print(f"exudyn_lie corpus: {len(scripts)} scripts, time limit {args.timeout:g} s, {args.jobs} job(s)")
    tic = time.perf_counter()
    signal.signal(signal.SIGTERM, _terminate)
    try:
        records = run_corpus(scripts, args.out, args.timeout, args.jobs, fine=args.fine)
    except KeyboardInterrupt:
        print("exudyn_lie corpus: interrupted; the running scripts were stopped, no report written", file=sys.stderr)
        return 130
    wall = time.perf_counter() - tic
    summary = summarize(records)
    out = Path(args.out)
    (out / "corpus.md").write_text(render(records, summary, command, wall, args.timeout, args.fine))
    (out / "corpus.json").write_text(json.dumps(dict(command=command, versions=versions(), timeout=args.timeout,
                                                     fine=args.fine,
                                                     wall=round(wall, 1), summary=summary, scripts=records),
                                                indent=1, default=repr))
    print(f"exudyn_lie corpus: wrote {out / 'corpus.md'} and corpus.json ({wall:.0f} s): native ok "
          f"{summary['native'].get('ok', 0)} of {summary['scripts']}; of {summary['base']} native-ok scripts "
          f"calling SolveDynamic: " + ", ".join(f"{k} {n}" for k, n in summary["exl"].items()))
    return 0
