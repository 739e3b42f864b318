"""Two small measurements of ``python -m exudyn_lie bench``:

* :func:`group_maps` (section ``groups``): the cost of one compiled SE(3) ``exp`` +
  ``dexpinv`` evaluation - the group work of one body in one Munthe-Kaas stage
  (``exp_into`` for the stage configuration, ``dexpinv_apply_into`` for ``k_j``, eq. MK1) -
  called from a numba loop, on both sides of the Taylor switches;
* :func:`bridge_overhead` (section ``overhead``): the share of a drop-in
  ``exl.SolveDynamic`` run spent outside the integration (Exudyn's time loop, sensors,
  solution file, the bridge's hook and write-back), on the paper's heavy top.
"""
from __future__ import annotations

import os
import tempfile
import time
import warnings

import numpy as np
from numba import njit

from ..groups import se3


@njit(cache=True)
def _loop_se3_exp_dexpinv(Xs, Vs, n):
    """n evaluations of se3.exp_into + se3.dexpinv_apply_into (the MK stage pattern)."""
    R = np.empty((3, 3))
    r = np.empty(3)
    k = np.empty(6)
    acc = 0.0
    m = Xs.shape[0]
    for it in range(n):
        j = it % m
        se3.exp_into(Xs[j], R, r)
        se3.dexpinv_apply_into(Xs[j], Vs[j], k)
        acc += R[0, 1] + r[2] + k[0] + k[5]
    return acc


def group_maps(angles=(0.05, 1.0, 3.0), n=10 ** 6, repeats=7, seed=0):
    """{|xi|: median us per exp + dexpinv pair} over 1024 random screws of each size
    (0.05: Taylor branches, the size of an MK stage increment h V; 1.0: closed-form exp;
    3.0: closed forms of exp and dexpinv)."""
    rng = np.random.default_rng(seed)
    out = {}
    for angle in angles:
        Xs = rng.normal(size=(1024, 6))
        Xs[:, 0:3] *= angle / np.linalg.norm(Xs[:, 0:3], axis=1)[:, None]
        Vs = rng.normal(size=(1024, 6))
        _loop_se3_exp_dexpinv(Xs, Vs, 10)          # compile / load from the cache
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            _loop_se3_exp_dexpinv(Xs, Vs, n)
            times.append(time.perf_counter() - t0)
        out[angle] = float(np.median(times)) / n * 1e6
    return out


def _settings(T, h, period, file, solution_path):
    import exudyn as exu
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = T
    ss.timeIntegration.numberOfSteps = int(round(T / h))
    ss.timeIntegration.verboseMode = 0
    ss.solution.sensors.active = True
    ss.solution.sensors.writePeriod = period
    ss.solution.file.write = file
    ss.solution.file.writePeriod = period
    ss.solution.file.name = solution_path
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = False
    return ss


def _heavy_top_with_sensor():
    import exudyn as exu
    from exudyn_lie import models
    mbs, info = models.build("heavy_top")
    mbs.AddSensor(exu.itemInterface.SensorBody(bodyNumber=info.bodies[0].objectIndex, storeInternal=True,
                                               outputVariableType=exu.OutputVariableType.Position))
    mbs.Assemble()
    return mbs, info


def bridge_overhead(T=8.0, h=1e-3, periods=(0.01, 0.1), repeats=11):
    """Times (median of ``repeats``) of the heavy top, h = 1e-3 s, ``T`` s:

    * ``kernel``: ``Simulator.Advance(n, h)`` in one call (the integration alone);
    * ``none``: ``exl.SolveDynamic`` without any output (sensors and solution file off):
      the integration plus the fixed cost of a solve (reading the model, compiling the
      scene, Exudyn's InitializeSolver);
    * per output period and output kind (a position sensor; sensor + solution file):
      ``exudyn``: Exudyn's time loop with an empty Newton hook and the same outputs (what
      the outputs cost in Exudyn itself; a native solve pays it too), ``bridge``:
      ``exl.SolveDynamic``, ``ga``: Exudyn's generalized-alpha with the same outputs.
      ``outputs`` = (bridge - none) / bridge is the share of the output machinery
      (Exudyn's sensors / file and the bridge's per-output kernel calls and write-back),
      ``bridgeOnly`` = (bridge - none - exudynReal) / bridge the part the bridge adds to
      what a native solve pays too; ``exudynReal`` is ``exudyn``, or for the solution
      file the larger of it and the sensor loop plus the file's cost in the native
      generalized-alpha solve (``gaFile``: Exudyn formats changing full-precision
      numbers, not the constant ones of an empty hook)."""
    import exudyn as exu

    import exudyn_lie as exl
    n = int(round(T / h))
    path = os.path.join(tempfile.gettempdir(), f"exudyn_lie_bench_solution_{os.getpid()}.txt")

    def kernel():
        mbs, info = _heavy_top_with_sensor()
        sim = exl.LieGroupSolver(mbs, liegroup="SE3").sim
        t = time.perf_counter()
        sim.Advance(n, h)
        return time.perf_counter() - t

    def exudyn_only(period, file):
        mbs, info = _heavy_top_with_sensor()
        solver = exu.MainSolverImplicitSecondOrder()
        solver.SetUserFunctionNewton(mbs, lambda s, m, ss: True)
        ss = _settings(T, h, period, file, path)
        ss.timeIntegration.numberOfSteps = int(round(T / period))     # one Exudyn step per output, as the bridge
        t = time.perf_counter()
        solver.SolveSystem(mbs, ss)
        return time.perf_counter() - t

    def native_ga(period, file):
        """Exudyn's generalized-alpha on the same model and outputs: what the solution
        file costs a native solve with real (changing, full-precision) coordinates."""
        mbs, info = _heavy_top_with_sensor()
        ss = _settings(T, h, period, file, path)
        t = time.perf_counter()
        exu.SolveDynamic(mbs, ss, showHints=False)
        return time.perf_counter() - t

    def bridge(period, file, sensors=True):
        mbs, info = _heavy_top_with_sensor()
        ss = _settings(T, h, period, file, path)
        ss.solution.sensors.active = sensors
        t = time.perf_counter()
        exl.SolveDynamic(mbs, ss, liegroup="SE3", showProgress=False, stabilization=None)
        return time.perf_counter() - t

    # all variants in turn, round after round (the machine's speed drifts: measuring one
    # variant after the other would compare different moments); medians over the rounds
    variants = {("kernel",): kernel, ("none",): lambda: bridge(T, False, sensors=False)}
    for period in periods:
        for file in (False, True):
            key = "sensor+file" if file else "sensor"
            variants[(period, key, "exudyn")] = lambda p=period, f=file: exudyn_only(p, f)
            variants[(period, key, "bridge")] = lambda p=period, f=file: bridge(p, f)
            variants[(period, key, "ga")] = lambda p=period, f=file: native_ga(p, f)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        bridge(periods[0], True)                  # warm-up (numba cache, first calls)
        times = {k: [] for k in variants}
        for _ in range(repeats):
            for k, f in variants.items():
                times[k].append(f())
    med = {k: float(np.median(v)) for k, v in times.items()}
    none = med[("none",)]
    out = dict(T=T, h=h, steps=n, kernel=med[("kernel",)], none=none, periods={})
    for period in periods:
        rows = {}
        gaFile = med[(period, "sensor+file", "ga")] - med[(period, "sensor", "ga")]
        for key in ("sensor", "sensor+file"):
            e, b = med[(period, key, "exudyn")], med[(period, key, "bridge")]
            # Exudyn's own output cost: its loop with an empty hook writes constant
            # coordinates, which it formats faster than changing ones; with the solution
            # file, the file's cost in the native generalized-alpha solve (real numbers)
            # is the better measure, when larger
            eReal = max(e, med[(period, "sensor", "exudyn")] + gaFile) if key == "sensor+file" else e
            rows[key] = dict(exudyn=e, exudynReal=eReal, gaFile=gaFile, bridge=b, outputs=(b - none) / b,
                             bridgeOnly=(b - none - eReal) / b)
        out["periods"][period] = dict(steps=int(round(period / h)), outputs=int(round(T / period)), **rows)
    if os.path.exists(path):
        os.remove(path)
    return out


def timed_paper_solve(name, T, h, period, **kw):
    """One whole ``exl.SolveDynamic(**kw)`` of the paper model ``name`` at Exudyn's output
    period ``period`` with a position sensor on its first body (no file), step ``h``, ``T`` s:
    ``(seconds, mbs, info)`` (the benches of what the drop-in's options cost)."""
    import warnings

    import exudyn as exu

    import exudyn_lie as exl
    from exudyn_lie import models
    mbs, info = models.build(name)
    mbs.AddSensor(exu.itemInterface.SensorBody(bodyNumber=info.bodies[0].objectIndex, storeInternal=True,
                                               outputVariableType=exu.OutputVariableType.Position))
    mbs.Assemble()
    ss = _settings(T, h, period, False, "")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        t = time.perf_counter()
        exl.SolveDynamic(mbs, ss, showProgress=False, **kw)
        return time.perf_counter() - t, mbs, info


def constraint_check_cost(T=2.0, h=1e-3, period=0.01, repeats=11, models_=("heavy_top", "spherical_double_pendulum",
                                                                          "planar_four_bar")):
    """The run-time check of the constraints (``SolveDynamic(constraintCheck=...)``,
    bridge/constraint_check.py) at Exudyn's default output period of 0.01 s (a position
    sensor, no file), h = 1e-3 s, ``T`` s: per paper model the medians of ``repeats`` whole
    ``exl.SolveDynamic`` calls with the check on and off, interleaved round by round, and the
    check's share of the run ``(on - off) / off``.  The paper's models drift (no
    stabilisation), so the check also judges residuals above its tolerance at some outputs."""
    def one(name, check):
        return timed_paper_solve(name, T, h, period, liegroup="SE3", constraintCheck=check, stabilization=None)[0]

    out = {}
    for name in models_:
        one(name, True), one(name, False)                   # compile / warm up
        on, off = [], []
        for _ in range(repeats):
            on.append(one(name, True))
            off.append(one(name, False))
        a, b = float(np.median(on)), float(np.median(off))
        out[name] = dict(on=a, off=b, share=(a - b) / b, outputs=int(round(T / period)), perOutputUs=1e6 * (a - b) /
                         int(round(T / period)))
    return out
