"""Cost of the Exudyn bridge (sensors, solution file, write-back) on the heavy top.

Run:  python -m exudyn_lie.bridge.bench_overhead [--endTime 8] [--h 1e-3] [--period 0.01] [--reps 7]

Times (best of ``reps``, after a warm-up):

* ``kernel``   - ``Simulator.Advance(n, h)`` in one call: the integration alone;
* ``exudyn``   - Exudyn's time loop with an empty Newton hook and the same outputs: what
  the outputs cost in Exudyn itself (a native solve pays this too);
* ``bridge``   - ``exl.SolveDynamic`` with one position sensor (and optionally the
  solution file), all output periods = ``--period``.

Overhead = (bridge - kernel) / bridge: the share of the run spent outside the
integration (Exudyn's loop and outputs + the bridge's hook and write-back).
"""
import argparse
import time
import warnings

import exudyn as exu

import exudyn_lie as exl
from exudyn_lie.bridge.example_heavytop import build


def settings(T, h, period, file, sensors=True):
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = T
    ss.timeIntegration.numberOfSteps = int(round(T / h))
    ss.timeIntegration.verboseMode = 0
    ss.solution.sensors.active = sensors
    ss.solution.sensors.writePeriod = period
    ss.solution.file.write = file
    ss.solution.file.writePeriod = period
    ss.solution.file.name = "/tmp/exudyn_lie_bench_solution.txt"
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = False
    return ss


def best(fn, reps):
    out = []
    for _ in range(reps):
        out.append(fn())
    return min(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--endTime", type=float, default=8.0)
    ap.add_argument("--h", type=float, default=1e-3)
    ap.add_argument("--period", type=float, default=0.01)
    ap.add_argument("--reps", type=int, default=7)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore", DeprecationWarning)
    T, h, P = args.endTime, args.h, args.period
    n = int(round(T / h))

    def kernel():
        SC, mbs, body, sensor = build()
        sim = exl.LieGroupSolver(mbs, liegroup="SE3").sim
        t = time.perf_counter()
        sim.Advance(n, h)
        return time.perf_counter() - t

    def exudyn_only(file):
        SC, mbs, body, sensor = build()
        solver = exu.MainSolverImplicitSecondOrder()
        solver.SetUserFunctionNewton(mbs, lambda s, m, ss: True)
        ss = settings(T, h, P, file)
        ss.timeIntegration.numberOfSteps = int(round(T / P))      # one Exudyn step per output, as the bridge
        t = time.perf_counter()
        solver.SolveSystem(mbs, ss)
        return time.perf_counter() - t

    def bridge(file):
        SC, mbs, body, sensor = build()
        t = time.perf_counter()
        exl.SolveDynamic(mbs, settings(T, h, P, file), liegroup="SE3", showProgress=False)
        return time.perf_counter() - t

    bridge(True)                      # warm-up (numba cache load, first calls)
    k = best(kernel, args.reps)
    print(f"heavy top, h = {h:g} s, {n} steps, output period {P:g} s ({int(round(T / P))} outputs)")
    print(f"  kernel Simulator.Advance({n}) in one call : {1e3 * k:8.2f} ms  ({1e6 * k / n:.2f} us/step)")
    for file in (False, True):
        e = best(lambda: exudyn_only(file), args.reps)
        b = best(lambda: bridge(file), args.reps)
        what = "sensor + solution file" if file else "sensor"
        print(f"  [{what}] Exudyn loop + outputs alone : {1e3 * e:8.2f} ms")
        print(f"  [{what}] exl.SolveDynamic             : {1e3 * b:8.2f} ms   overhead (bridge - kernel)/bridge "
              f"= {100 * (b - k) / b:5.1f} %,  of which Exudyn's own outputs {100 * e / b:5.1f} %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
