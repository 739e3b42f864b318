"""Output rows of a :class:`~.simulator.Simulator`: the one output loop of the kernel.

A Python call of a numba function unboxes every array it receives: the kernel's scene and
work tuples hold ~60 arrays, about as much time as a heavy-top step.  So the stepper
(:func:`~.stepper.mk_steps`) integrates a chunk of outputs in one call and records, at each
output, the state, the tracked rotation parameters and, if asked, the accelerations and
multipliers.  :class:`OutputRows` holds those rows for outputs every ``nsub`` fixed steps of
``h``; :class:`AdaptiveOutputRows` for outputs at given times on adaptive steps (dense output
on the group, no step shortened).  Their consumers: :func:`run` (the loop of :meth:`Simulator.Run`, a
:class:`Result` with diagnostics at every output) and the bridge (the coordinates of
the modelling system it reads, bridge/fast.py).
"""
import time as _time
from dataclasses import dataclass

import numpy as np

from ..errors import SimulationError
from ..userwarn import warn_user
from . import kernel, stepper
from .entry import call
from . import implicit_run
from .rotation_parameters import record_tracked
from .state import twist_to_world_velocity

CHUNK_SECONDS = 0.05        # aimed wall time of one chunk (progress, responsiveness)
CHUNK_DOUBLES = 1 << 22     # at most this many doubles of chunk buffers (32 MiB)
CHUNK_ROWS = 256            # at most this many outputs per chunk
ADAPTIVE_RUN_ROWS = 64      # outputs per chunk of an adaptive Run


@dataclass
class Result:
    """Outputs of :meth:`Simulator.Run` (one row per output time)."""
    times: np.ndarray
    R: np.ndarray
    r: np.ndarray
    V: np.ndarray
    omega: np.ndarray          # body-fixed angular velocity
    vel: np.ndarray            # world velocity of the body frame origin
    energy: np.ndarray         # (kinetic, gravity, springs)
    residuals: np.ndarray      # all constraint rows h(g)
    jointPositionViolation: np.ndarray   # per joint: norm of its translational rows
    jointRotationViolation: np.ndarray   # per joint: norm of its rotational rows
    groups: list
    method: str
    stepSize: float
    cpuTime: float = 0.0
    steps: int = 0
    # adaptive runs (rtol / atol): rejected steps and right-hand-side evaluations
    # (``steps`` counts the accepted ones); fixed-step runs: rhsEvaluations = steps x stages
    rejectedSteps: int = 0
    rhsEvaluations: int = 0
    adaptive: bool = False
    constraintProjections: int = 0     # adaptive runs with constraintTolerance: projections triggered

    @property
    def totalEnergy(self):
        return self.energy.sum(axis=1)

    @property
    def jointViolation(self):
        return np.hypot(self.jointPositionViolation, self.jointRotationViolation)


class OutputRows:
    """Rows of outputs ``nsub`` fixed steps of ``h`` apart, integrated from the simulator's
    state a chunk per call (:meth:`integrate`).  ``doacc``: accelerations ``Vdo`` and
    multipliers ``lamo`` too.  ``extraPerRow``: doubles per row a consumer adds (for the
    memory bound ``CHUNK_DOUBLES``).  After a kernel failure the rows before it are kept,
    the simulator holds the last accepted step and :attr:`failure` the status."""

    def __init__(self, sim, nsub, h, doacc, maxRows=CHUNK_ROWS, extraPerRow=0):
        self.sim, self.nsub, self.h, self.doacc = sim, int(nsub), float(h), bool(doacc)
        nb, m = sim.sd.nb, sim.sd.nrows
        perRow = nb * 24 + m + int(extraPerRow)
        self.maxRows = max(1, min(int(maxRows), CHUNK_DOUBLES // max(perRow, 1)))
        M = self.maxRows
        self.Ro, self.ro = np.zeros((M, nb, 3, 3)), np.zeros((M, nb, 3))
        self.Vo, self.Vdo, self.lamo = np.zeros((M, nb, 6)), np.zeros((M, nb, 6)), np.zeros((M, m))
        self.Po = np.zeros((M, nb, 4))          # tracked angles / node rotation parameters per row
        self.size = 1                   # outputs in the next chunk (adapted to CHUNK_SECONDS)
        self.failure = None
        self._ep = {}

    def integrate(self, nout, vmax):
        """Integrate the next ``min(nout, size)`` outputs from ``sim.t``; returns (rows
        computed, the rows' times).  ``vmax``: the stepper's blow-up bound."""
        sim, h, nsub = self.sim, self.h, self.nsub
        n = max(1, min(int(nout), self.size))
        clock = sim._clock
        t0, k0 = clock.start(h)         # step k at t0 + k h, however the steps are chunked (mbs/clock.py)
        at = lambda k: t0 + (k0 + k) * h     # noqa: E731 - the time after this call's k-th step
        acc = n if self.doacc else 0
        # where a blow-up's step suggestion linearises (stiffness.suggest_step)
        sim._segmentStart = (clock.t, sim.R.copy(), sim.r.copy(), sim.V.copy())
        total, done = n * nsub, 0
        while True:
            if done % nsub == 0:         # whole output periods, their outputs from row done // nsub on
                o = done // nsub
                args = (sim.sd, sim.wk, sim.method, sim.control, t0, k0 + done, h, total - done, sim.R, sim.r,
                        sim.V, float(vmax), nsub, self.Ro[o:n], self.ro[o:n], self.Vo[o:n], self.Po[o:n],
                        self.Vdo[o:acc], self.lamo[o:acc])
                st, d = call(self._ep, "mk", stepper.mk_steps, args)
            else:                        # the rest of a period after a step in parts: one step at a time
                st, d = sim._mk_steps(1, h, at(done))
                if d and (done + 1) % nsub == 0:
                    self._record((done + 1) // nsub - 1, at(done + 1))
            done += d
            if st == kernel.STATUS_OK and done < total:
                continue
            if st != kernel.STATUS_NEWTON or not sim.tableau.implicit:
                break
            st = implicit_run.substeps(sim, h, at(done))      # an implicit step that failed, in parts
            if st != kernel.STATUS_OK:
                break
            done += 1
            if done % nsub == 0:
                self._record(done // nsub - 1, at(done))
            if done == total:
                break
        rows = done // nsub
        if st != kernel.STATUS_OK and self.doacc and rows > 0 and np.isnan(self.Vdo[rows - 1, 0, 0]):
            rows -= 1                   # its accelerations failed: not an output
        clock.advance(done)             # on a failure: the last accepted step
        self.failure = None if st == kernel.STATUS_OK else st
        if rows > 8:
            return rows, at(np.arange(1, rows + 1) * nsub)
        times = np.empty(rows)          # one step per call where a user function runs between steps:
        for o in range(rows):           # numpy's arange and arithmetic per call cost more than the rows
            times[o] = at((o + 1) * nsub)
        return rows, times

    def _record(self, o, t):
        """Output row ``o`` of the state at ``t`` (as ``stepper.record_output``; the accelerations
        and multipliers from one evaluation at it, NaN if it fails)."""
        sim = self.sim
        self.Ro[o], self.ro[o], self.Vo[o] = sim.R, sim.r, sim.V
        wk = sim.wk
        record_tracked(wk.track.trackCodes, wk.path.bodyAngles, wk.path.bodyParameters, self.Po[o])
        if self.doacc:
            if sim._evaluate(t, sim.R, sim.r, sim.V) == kernel.STATUS_OK:
                self.Vdo[o], self.lamo[o] = wk.Vd[0], wk.lam
            else:
                self.Vdo[o, 0, 0] = np.nan

    def adapt(self, seconds, rows):
        """The next chunk's size from the wall time of this one."""
        if rows > 0 and self.maxRows > 1:
            per = max(seconds / rows, 1e-9)
            self.size = max(1, min(self.maxRows, int(CHUNK_SECONDS / per)))


class AdaptiveOutputRows(OutputRows):
    """Rows of outputs at given times on adaptive steps (after ``sim.SetAdaptive``;
    :mod:`.adaptive`), each from the dense output on the group of the step that contains
    it.  Accelerations and multipliers at an output (``doacc``) are one evaluation of the
    equations of motion at its state (not counted as integration work)."""

    def integrate_at(self, tEnd, tout):
        """The outputs at the times ``tout`` (at most ``maxRows``; sorted, in ``[sim.t,
        tEnd]``), stepping towards ``tEnd``; returns the rows computed."""
        sim = self.sim
        n = len(tout)
        st, rows = sim.AdvanceToInto(tEnd, np.ascontiguousarray(tout, dtype=float), self.Ro[:n], self.ro[:n],
                                     self.Vo[:n], self.Po[:n])
        if self.doacc and rows > 0:
            wk = sim.wk
            keep0, keepLam = wk.Vd[0].copy(), wk.lam.copy()     # stage 1 / dense data of the step
            for o in range(rows):
                est = sim._evaluate(float(tout[o]), self.Ro[o], self.ro[o], self.Vo[o])
                if est != kernel.STATUS_OK:
                    rows, st = o, est
                    break
                self.Vdo[o] = wk.Vd[0]
                self.lamo[o] = wk.lam
            wk.Vd[0] = keep0
            wk.lam[:] = keepLam
        self.failure = None if st == kernel.STATUS_OK else st
        return rows


def _fixed_segments(t0, endTime, h, every):
    """``(nsub, h, outputs)`` of a fixed-step run: whole steps with an output every
    ``every`` of them, the remainder as one output, then one shorter step that lands exactly
    on ``endTime`` (if the span is not a multiple of ``h``)."""
    span = endTime - t0
    nsteps = int(np.floor(span / h + 1e-9))
    hlast = span - nsteps * h
    if hlast <= 1e-9 * max(1.0, abs(endTime)):
        hlast = 0.0
    if hlast > 0:
        warn_user(f"exudyn_lie: endTime - startTime = {span:.6g} s is not a multiple of stepSize = {h:.6g} s; "
                  f"{nsteps} steps of {h:.6g} s and a last step of {hlast:.6g} s end exactly at endTime")
    segs = [(every, h, nsteps // every)]
    if nsteps % every:
        segs.append((nsteps % every, h, 1))
    if hlast > 0:
        segs.append((1, hlast, 1))
    return [s for s in segs if s[2] > 0], nsteps, hlast > 0


def _output_grid(t0, endTime, stepSize, outputEvery):
    """Output times of an adaptive run without ``outputTimes``: every ``stepSize *
    outputEvery`` and at ``endTime``; only the ends without ``stepSize``."""
    if stepSize is None:
        return np.array([t0, endTime])
    dt = float(stepSize) * max(1, int(outputEvery))
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"stepSize must be positive and finite, got {stepSize}")
    nfull = int(np.floor((endTime - t0) / dt + 1e-9))
    tout = t0 + dt * np.arange(nfull + 1)
    if endTime - tout[-1] > 1e-9 * max(1.0, abs(endTime)):
        return np.append(tout, endTime)
    tout[-1] = endTime
    return tout


def _check_times(t0, endTime, stepSize, adaptive):
    if not adaptive:
        if stepSize is None:
            raise ValueError("Run needs a stepSize (fixed steps) or rtol / atol (adaptive steps)")
        h = float(stepSize)
        if not np.isfinite(h) or h <= 0:
            raise ValueError(f"stepSize must be positive and finite, got {stepSize}")
    if not np.isfinite(t0):
        raise ValueError(f"startTime must be finite, got {t0}")
    if not np.isfinite(endTime):
        raise ValueError(f"endTime must be finite, got {endTime}")
    if endTime < t0:
        raise ValueError(f"endTime {endTime} is before the start time {t0}")


def rows_and_energy(sim, R, r, V, times, e, h, k, n):
    """The constraint residuals ``h`` and energies ``e`` of output rows ``k .. k+n-1`` (:func:`run`):
    one call of the kernel's diagnostics per chunk through its resolved entry point (numba typing
    the scene's tuples cost 40 us per call), one per row where rows have moving offsets (set by
    time from Python)."""
    wk = sim.wk
    for j in (range(k, k + n) if sim._drives else (k,)):
        m = 1 if sim._drives else n
        sim._drives_at(times[j])
        call(sim._entries, "all_rows", kernel.all_rows,
             (sim.sd, wk, R[j:j + m], r[j:j + m], V[j:j + m], h[j:j + m], wk.Jr, wk.eta, e[j:j + m]))


def run(sim, endTime, stepSize=None, outputEvery=1, startTime=None, progress=False, *, rtol=None, atol=None,
        outputTimes=None, maxStep=None, minStep=0.0, firstStep=None, constraintTolerance=None):
    """:meth:`Simulator.Run`: output rows (fixed or adaptive steps) a chunk at a time, the
    diagnostics of every row right after its chunk, then a :class:`Result`."""
    adaptive = rtol is not None or atol is not None
    t0 = sim.t if startTime is None else float(startTime)
    endTime = float(endTime)
    _check_times(t0, endTime, stepSize, adaptive)
    if constraintTolerance is not None and not adaptive:
        raise ValueError("constraintTolerance needs adaptive steps (rtol= / atol=); fixed steps project "
                         "with Simulator(stabilization='position' or 'velocity')")
    sim.t = t0
    if adaptive:
        span = endTime - t0
        sim.SetAdaptive(rtol=1e-3 if rtol is None else rtol, atol=1e-6 if atol is None else atol,
                        maxStep=span if maxStep is None else min(maxStep, span), minStep=minStep,
                        firstStep=firstStep, constraintTolerance=constraintTolerance)
        times = np.asarray(_output_grid(t0, endTime, stepSize, outputEvery) if outputTimes is None else outputTimes,
                           dtype=np.float64)
        # outputs at or before the start are the state itself (below); the rest by dense output
        segments = [(AdaptiveOutputRows(sim, 1, 0.0, False, maxRows=ADAPTIVE_RUN_ROWS),
                     int(np.count_nonzero(times > t0)))]
        h = None
    else:
        h = float(stepSize)
        segs, nsteps, landing = _fixed_segments(t0, endTime, h, max(1, int(outputEvery)))
        segments = [(OutputRows(sim, nsub, hs, False), count) for nsub, hs, count in segs]
        last = segments[-1][0] if landing else None           # the shorter step onto endTime
        times = np.zeros(1 + sum(c for _, c in segments))
    nout = times.size
    nb, m = sim.sd.nb, sim.sd.nrows
    R, r, V = np.zeros((nout, nb, 3, 3)), np.zeros((nout, nb, 3)), np.zeros((nout, nb, 6))
    energy, res = np.zeros((nout, 3)), np.zeros((nout, m))

    def record(k, n, Ro, ro, Vo, tk):
        R[k:k + n], r[k:k + n], V[k:k + n], times[k:k + n] = Ro[:n], ro[:n], Vo[:n], tk[:n]
        rows_and_energy(sim, R, r, V, times, energy, res, k, n)

    k = 0
    while k < nout and (times[k] <= t0 if adaptive else k == 0):     # outputs at the start: the state
        record(k, 1, sim.R[None], sim.r[None], sim.V[None], times[k:k + 1] if adaptive else [t0])
        k += 1
    cpu, tlast = 0.0, _time.time()
    for rows, count in segments:
        end = k + count
        while k < end:
            tic = _time.perf_counter()
            n = 0
            if adaptive:
                n = rows.integrate_at(endTime, times[k:min(end, k + rows.maxRows)])
                tk = times[k:k + n].copy()
            else:
                n, tk = rows.integrate(end - k, sim.vmax)      # (the clock's times: t0 + steps h)
            cpu += _time.perf_counter() - tic
            if rows.failure is not None:              # the state: the last accepted step
                sim.RaiseStatus(rows.failure, sim._ad.step if adaptive else rows.h)
            if n == 0:
                raise SimulationError(f"internal: no output reached at t = {sim.t:.6g} s")
            if not adaptive:
                # chunks of 1, 2, 4, ... rows (a stage's time does not depend on them: mbs/clock.py)
                rows.size = min(rows.maxRows, 2 * rows.size)
                if rows is last:                      # the shorter last step lands on endTime
                    tk = [endTime]
                    sim.t = endTime
            record(k, n, rows.Ro, rows.ro, rows.Vo, tk)
            k += n
            if progress and _time.time() - tlast > 2.0:
                tlast = _time.time()
                print(f"exudyn_lie: t = {sim.t:.4g} / {endTime:.4g} s", flush=True)
    if adaptive and sim.t < endTime:                   # outputs done before endTime: step on to it
        segments[0][0].integrate_at(endTime, times[:0])
        if segments[0][0].failure is not None:
            sim.RaiseStatus(segments[0][0].failure, sim._ad.step)
    pv, rv = sim.JointViolations(res)
    omega, vel = twist_to_world_velocity(np.tile(sim.gid, nout), R.reshape(-1, 3, 3), V.reshape(-1, 6))
    omega, vel = omega.reshape(nout, nb, 3), vel.reshape(nout, nb, 3)
    if adaptive:
        acc, rej, nrhs = sim.adaptiveCounters
        return Result(times.copy(), R, r, V, omega, vel, energy, res, pv, rv, list(sim.groups), sim.tableau.name,
                      float(sim._ad.hInitial), cpu, acc, rejectedSteps=rej, rhsEvaluations=nrhs, adaptive=True,
                      constraintProjections=sim.constraintProjections)
    steps = nsteps + (1 if landing else 0)
    return Result(times, R, r, V, omega, vel, energy, res, pv, rv, list(sim.groups), sim.tableau.name, h, cpu,
                  steps, rhsEvaluations=steps * len(sim.method.stages))
