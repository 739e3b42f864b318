"""Bench section ``evaluated``: the cost of the path on which Exudyn evaluates the model.

``python -m exudyn_lie bench --sections evaluated``.  A chain of N boxes (RotVecLG nodes,
0.2 x 0.1 x 0.05 m aluminium, spherical joints, gravity, the first hanging from the ground,
each tilted so that the chain swings), N = 1, 10, 50, **with one foreign item**: a 1-DOF
oscillator given as ObjectGenericODE2 (m = 1 kg, k = 100 N/m) tied to the last box's x
coordinate by a CoordinateSpringDamper.  Per step (MK-RK4, h = 1e-3 s, one Exudyn step per
step): the median interval between two calls of a pre-step user function that records the
time (the same ~1 us function in every variant; the set-up of a solve does not enter;
``accelerations=False``, so that the function does not ask for q_tt every step); medians of
interleaved repetitions:

* ``evaluated``: ``exl.SolveDynamic`` on the chain with the oscillator (``evaluation='auto'``
  picks the Exudyn-evaluated path: Exudyn computes M, f, C_q and the velocity-level
  constraints at every stage);
* ``compiled``: ``exl.SolveDynamic`` on the same chain without the oscillator (the compiled
  kernel; the oscillator is the only item it does not read);
* ``native``: Exudyn's generalized-alpha on the chain with the oscillator (Newton, default
  tolerances, spectral radius 0.9);
* ``calls``: Exudyn's own calls of one stage (M, f, C_q with their dense copies, the
  velocity-level constraints twice for the central difference that gives eta, ...), each
  timed inside runs of the evaluated path interleaved with the timed runs
  (:func:`_timing_solver_class`), per method.

Per stage = per step / 4 (RK4).  ``overhead`` = evaluated per stage - calls: what the path
adds around Exudyn's calls (Python, the index-1 solve, the Lie group update).  Targets:
overhead <= 30 us per stage for one body; linear growth with N (exponent of the
evaluated cost per step over N = 10 ... 50 <= 1.2).
"""
from __future__ import annotations

import time
import warnings

import numpy as np

H = 1e-3
NS = (1, 10, 50)
STAGES = 4
TARGET_OVERHEAD_US = 30.0
TARGET_EXPONENT = 1.2


def chain(N, foreign=True):
    """The chain of N boxes (module docstring), assembled; with ``foreign`` the oscillator."""
    import exudyn as exu
    from exudyn.utilities import (InertiaCuboid, MarkerNodeCoordinate, NodeGenericODE2,
                                  ObjectConnectorCoordinateSpringDamper, ObjectGenericODE2, RotationMatrixX)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    a, b, c = 0.2, 0.1, 0.05
    prev, top = mbs.CreateGround(), np.zeros(3)
    body = None
    for i in range(N):
        R = RotationMatrixX(0.3 + 0.1 * (i % 3))
        axis = R @ np.array([0, -1.0, 0])
        body = mbs.CreateRigidBody(inertia=InertiaCuboid(2700, [a, b, c]), referencePosition=list(top + 0.5 * a * axis),
                                   referenceRotationMatrix=R @ np.array([[0, 1.0, 0], [-1.0, 0, 0], [0, 0, 1]]),
                                   gravity=[0, -9.81, 0], nodeType=exu.NodeType.RotationRotationVector)
        mbs.CreateSphericalJoint(itemNumbers=[prev, body], position=list(top))
        prev, top = body, top + a * axis
    if foreign:
        nG = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0], initialCoordinates=[0.01],
                                          initialCoordinates_t=[0], numberOfODE2Coordinates=1))
        mbs.AddObject(ObjectGenericODE2(nodeNumbers=[nG], massMatrix=np.eye(1), stiffnessMatrix=100 * np.eye(1)))
        nB = mbs.GetObject(body)["nodeNumber"]
        mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=[
            mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nB, coordinate=0)),
            mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nG, coordinate=0))], stiffness=50.0, damping=0.0))
    mbs.Assemble()
    return mbs


def settings(n, h=H):
    import exudyn as exu
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = n * h
    ss.timeIntegration.numberOfSteps = n
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = h
    ss.timeIntegration.generalizedAlpha.spectralRadius = 0.9
    return ss


def _run(variant, N, n):
    """One solve of n steps: seconds per step, the median interval between Exudyn's pre-step
    user function calls (a function that only records the time, ~1 us, in every variant), so
    that the set-up of the solve does not enter.  ``variant`` 'calls': the evaluated path
    with Exudyn's calls timed one by one (:func:`_timing_solver_class`), returned per stage
    as the second value (else None); its time per step includes the timing wrappers (a
    Python call each) and is not reported."""
    import exudyn as exu
    import exudyn_lie as exl
    mbs = chain(N, foreign=(variant != "compiled"))
    ss = settings(n)
    stamps = []
    clock = time.perf_counter
    Timed = _timing_solver_class() if variant == "calls" else None

    def stamp(mbs, t):
        stamps.append(clock())
        if Timed is not None:
            Timed.on = len(stamps) > n // 4            # the steps whose intervals are used
        return True

    mbs.SetPreStepUserFunction(stamp)
    original = exu.MainSolverImplicitSecondOrder
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if variant == "native":
            mbs.SolveDynamic(ss)
        else:
            if Timed is not None:
                exu.MainSolverImplicitSecondOrder = Timed   # the path creates its solver from exudyn
            try:
                # accelerations=False: a pre-step function would otherwise ask for q_tt at every
                # step (one more evaluation per step); the four stages of RK4 are what is measured
                exl.SolveDynamic(mbs, ss, showProgress=False, substeps=1, accelerations=False)
            finally:
                exu.MainSolverImplicitSecondOrder = original
    d = np.diff(stamps)
    per = float(np.median(d[len(d) // 4:])) if len(d) else float("nan")
    parts = None
    if Timed is not None:
        # per method: the median duration of one call times its calls per stage (a stage is one
        # ComputeODE2RHS call; the mass matrix of this chain is constant, evaluated once): robust
        # against the rare call that the machine interrupts
        stages = len(Timed.acc.get("ComputeODE2RHS", ()))
        parts = {k: float(np.median(v)) * len(v) / stages for k, v in Timed.acc.items()} if stages else {}
    return per, parts


def _timing_solver_class():
    """A subclass of ``exu.MainSolverImplicitSecondOrder`` whose methods add their wall time
    (``time.perf_counter`` around the call, ~0.1 us) to the list ``cls.acc[name]``; results
    pass through unchanged."""
    import exudyn as exu
    base = exu.MainSolverImplicitSecondOrder
    names = [k for k in dir(base) if k[:1].isupper() and callable(getattr(base, k))
             and not k.startswith(("Initialize", "Finalize", "SolveSystem", "SolveSteps"))]
    clock = time.perf_counter

    def wrap(name, fn):
        def timed(self, *a, **kw):
            t0 = clock()
            out = fn(self, *a, **kw)
            cls = type(self)
            if cls.on:
                cls.acc.setdefault(name, []).append(clock() - t0)
            return out
        return timed

    attrs = {k: wrap(k, getattr(base, k)) for k in names}
    attrs.update(acc={}, on=False)
    return type("TimedMainSolver", (base,), attrs)


def fit_exponent(Ns, t):
    Ns, t = np.asarray(Ns, float), np.asarray(t, float)
    ok = (Ns >= 10) & np.isfinite(t) & (t > 0)
    if ok.sum() < 2:
        return float("nan")
    return float(np.polyfit(np.log(Ns[ok]), np.log(t[ok]), 1)[0])


def measure(Ns=NS, n=40, repeat=3, log=None):
    """Per-step seconds of every variant and N (module docstring)."""
    variants = ("evaluated", "compiled", "native")
    rows = {}
    for N in Ns:
        nn = max(8, n // max(1, N // 10))               # fewer steps for the long chains
        times = {v: [] for v in variants}
        errors = {}
        for v in variants:                              # warm up: compile, first Exudyn call
            try:
                _run(v, N, 3)
            except Exception as e:                      # a path that cannot run this model: say why
                errors[v] = f"{type(e).__name__}: {e}"
        parts = []
        for _ in range(repeat):
            for v in variants:                          # interleaved: the machine's speed drifts
                if v not in errors:
                    times[v].append(_run(v, N, nn)[0])
            if "evaluated" not in errors:
                parts.append(_run("calls", N, nn)[1])
        keys = set().union(*parts) if parts else set()
        callParts = {k: float(np.median([p.get(k, 0.0) for p in parts])) for k in keys}
        callParts["total"] = sum(callParts.values()) if parts else float("nan")
        row = {v: (float(np.median(times[v])) if times[v] else float("nan")) for v in variants}
        row["callParts"] = callParts
        row["calls"] = callParts["total"]
        row["errors"] = errors
        row["steps"] = nn
        row["evaluatedPerStage"] = row["evaluated"] / STAGES
        row["overheadPerStage"] = row["evaluatedPerStage"] - row["calls"]
        rows[N] = row
        if log:
            log(f"evaluated N = {N:3d}: evaluated {1e6 * row['evaluated']:9.1f} us/step "
                f"({1e6 * row['evaluatedPerStage']:.1f} us/stage, Exudyn's calls {1e6 * row['calls']:.1f} us, "
                f"overhead {1e6 * row['overheadPerStage']:.1f} us), compiled {1e6 * row['compiled']:.2f} us/step, "
                f"native {1e6 * row['native']:.1f} us/step" + (f"; failed: {errors}" if errors else ""))
    res = dict(h=H, rows=rows, stages=STAGES,
               exponent=fit_exponent(list(rows), [r["evaluated"] for r in rows.values()]),
               exponentNative=fit_exponent(list(rows), [r["native"] for r in rows.values()]),
               exponentCalls=fit_exponent(list(rows), [r["calls"] for r in rows.values()]))
    return res


def run_section(cfg, log):
    from .bench import loadavg
    log("Exudyn-evaluated path: chains of 1, 10, 50 bodies with one foreign item")
    res = measure(NS, n=10 if cfg.quick else 100, repeat=3 if cfg.quick else 7, log=log)
    res["load"] = loadavg()
    return res


def target_lines(res):
    if not res:
        return []
    r1 = res["rows"].get(1)
    L = []
    if r1 is not None:
        o = 1e6 * r1["overheadPerStage"]
        L.append(f"| Exudyn-evaluated path: overhead per stage around Exudyn's calls, 1 body + 1 foreign item "
                 f"<= {TARGET_OVERHEAD_US:g} us | {o:.3g} us ({1e6 * r1['evaluatedPerStage']:.3g} us per stage, "
                 f"Exudyn's calls {1e6 * r1['calls']:.3g} us) | {'yes' if o <= TARGET_OVERHEAD_US else 'no'} |")
    for N in sorted(res["rows"]):
        r = res["rows"][N]
        o, c = 1e6 * r["overheadPerStage"], 1e6 * r["calls"]
        L.append(f"| Exudyn-evaluated path, {N} bod{'y' if N == 1 else 'ies'}: overhead per stage <= Exudyn's own calls (issue 32) | "
                 f"{o:.3g} us against {c:.3g} us | {'yes' if o <= c else 'no'} |")
    e = res["exponent"]
    L.append(f"| Exudyn-evaluated path: cost per step ~ N^p, p <= {TARGET_EXPONENT:g} (N = 10 ... 50) | p = {e:.2f} "
             f"(Exudyn's calls alone {res['exponentCalls']:.2f}, generalized-alpha {res['exponentNative']:.2f}) | "
             f"{'yes' if e <= TARGET_EXPONENT else 'no'} |")
    return L


def report_lines(res):
    if not res:
        return []
    L = ["## Exudyn-evaluated path", "",
         f"A chain of N boxes (RotVecLG, spherical joints) with one foreign item (a GenericODE2 oscillator on the "
         f"last box), MK-RK4 at h = {res['h']:g} s; 'compiled' is the same chain without the oscillator; 'native' is "
         f"Exudyn's generalized-alpha on the chain with it; 'calls' are Exudyn's own evaluation calls of one stage "
         f"(M, f, C_q with their dense copies, the velocity-level constraints twice), timed directly; overhead = evaluated per stage - calls. Load average "
         f"{res.get('load', '?')}.", "",
         "| N | evaluated us/step | us/stage | Exudyn's calls us/stage | overhead us/stage | compiled us/step | "
         "generalized-alpha us/step | evaluated / compiled | evaluated / native |",
         "|---|---|---|---|---|---|---|---|---|"]
    for N, r in sorted(res["rows"].items()):
        ev, co, na = r["evaluated"], r["compiled"], r["native"]
        L.append(f"| {N} | {1e6 * ev:.4g} | {1e6 * r['evaluatedPerStage']:.4g} | {1e6 * r['calls']:.4g} | "
                 f"{1e6 * r['overheadPerStage']:.4g} | {1e6 * co:.4g} | {1e6 * na:.4g} | {ev / co:.3g} | "
                 f"{ev / na:.3g} |")
        for v, msg in r.get("errors", {}).items():
            L.append(f"| {N} | {v} failed: {msg[:200]} | | | | | | | |")
    L += ["", f"Growth exponents over N = 10 ... 50: evaluated {res['exponent']:.2f}, Exudyn's calls "
              f"{res['exponentCalls']:.2f}, generalized-alpha {res['exponentNative']:.2f}.", "",
          "Exudyn's calls per stage inside a run, us (calls below 0.5 us per stage left out):", "",
          "| N | calls |", "|---|---|"]
    for N, r in sorted(res["rows"].items()):
        parts = sorted(((k, v) for k, v in r["callParts"].items() if k not in ("total", "stages") and v >= 5e-7),
                       key=lambda kv: -kv[1])
        L.append(f"| {N} | " + ", ".join(f"{k} {1e6 * v:.3g}" for k, v in parts) + " |")
    L += ["", "GetSystemMassMatrix and GetSystemJacobian are dense copies of (ODE2 + AE coordinates)^2 entries: "
              "they grow with N^2.", ""]
    return L


if __name__ == "__main__":
    import sys
    Ns = tuple(int(x) for x in sys.argv[1].split(",")) if len(sys.argv) > 1 else NS
    r = measure(Ns, n=10, log=print)
    print("\n".join(report_lines(r)))
