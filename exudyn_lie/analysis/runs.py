"""Run the paper's models with exudyn_lie (through the Exudyn bridge) and with Exudyn's
native solvers, and reduce every run to the same measures.

* :func:`run_lie` - MK-RK4 on ``SE3`` or ``SO3xR3`` via
  :class:`exudyn_lie.bridge.LieGroupSolver` (the Exudyn model is read by
  ``SceneFromExudyn``; the compiled ``Simulator.Run`` path, compiled once per model and
  group, many step sizes);
* :func:`run_native` - ``exudyn.SolveDynamic`` with GeneralizedAlpha /
  TrapezoidalIndex2 (constrained models) or RK44 / DOPRI5 (free bodies), states read
  from node sensors (:func:`models.run_native`).

Both give a :class:`RunData`: the body states at the output times and, computed from
them with :mod:`.geometry` and :mod:`.energy` (the same formulas for every solver),
the violation of every joint, the COM drift and orientation error against the exact
solution (free bodies), and the total energy.  Runs of exudyn_lie also keep the
kernel's own diagnostics (``kernelPosition`` / ``kernelRotation`` / ``kernelEnergy``)
so that they can be cross-checked.
"""
from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from typing import Dict, Optional

import numpy as np

from .energy import energies
from .geometry import com_positions, joint_violations, orientation_error

LIE_GROUPS = ("SE3", "SO3xR3")


def output_every(stepSize, period=1e-3):
    """Steps between stored outputs: every step for dt >= period, else period/dt."""
    return max(1, int(round(period / stepSize)))


@dataclass
class RunData:
    model: str
    solver: str                     # 'SE3', 'SO3xR3' (MK-RK4) or a native solver name
    stepSize: float
    ok: bool
    message: str
    cpuTime: float
    times: np.ndarray
    position: Dict[str, np.ndarray] = field(default_factory=dict)   # joint -> (nt,)
    rotation: Dict[str, np.ndarray] = field(default_factory=dict)
    energy: Optional[np.ndarray] = None          # total energy (nt,)
    energyParts: Optional[np.ndarray] = None     # (nt, 3): kinetic, gravity, spring
    comDrift: Optional[np.ndarray] = None        # |x_c - x_c,exact| (nt,), free bodies
    orientation: Optional[np.ndarray] = None     # eps_r = ||log(R^T R_num)|| (nt,), free bodies
    R: Optional[np.ndarray] = None
    kernelPosition: Dict[str, np.ndarray] = field(default_factory=dict)
    kernelRotation: Dict[str, np.ndarray] = field(default_factory=dict)
    kernelEnergy: Optional[np.ndarray] = None
    native: bool = False

    @property
    def label(self):
        return f"MK-RK4 {self.solver}" if not self.native else self.solver

    def energy_drift(self):
        if self.energy is None or len(self.energy) == 0:
            return np.zeros(0)
        return self.energy - self.energy[0]

    def max_position(self, joint):
        return _nanmax(self.position[joint])

    def max_rotation(self, joint):
        return _nanmax(self.rotation[joint])


def _nanmax(x):
    x = np.asarray(x)
    return float(np.max(x)) if x.size else float("nan")


def measure(info, rd: RunData, R, r, omega, vel, keep_states=False):
    """Fill the violation / drift / energy measures of ``rd`` from body states."""
    for j in info.joints:
        pv, rv = joint_violations(j, R, r)
        rd.position[j.name] = pv
        rd.rotation[j.name] = rv
    if len(rd.times):
        rd.energyParts = energies(info, R, r, omega, vel)
        rd.energy = rd.energyParts.sum(axis=1)
    else:
        rd.energy = np.zeros(0)
        rd.energyParts = np.zeros((0, 3))
    if info.exact is not None and len(rd.times):
        ex = info.exact(rd.times)
        rd.comDrift = np.linalg.norm(com_positions(info, R, r) - ex["com"], axis=-1).max(axis=1)
        rd.orientation = orientation_error(ex["R"], R).max(axis=1)
    if keep_states:
        rd.R = R
    return rd


# --------------------------------------------------------------------------- exudyn_lie
class LieRunner:
    """One :class:`exudyn_lie.bridge.LieGroupSolver` per (model, group): compiled once,
    run for several step sizes."""

    def __init__(self, info, group, method="RK4"):
        from exudyn_lie.bridge import LieGroupSolver
        if group not in LIE_GROUPS:
            raise ValueError(f"group must be one of {LIE_GROUPS}")
        self.info = info
        self.group = group
        info.mbs.Assemble()
        with warnings.catch_warnings():
            # the planar four-bar's redundant row is reported by the kernel; it is documented
            warnings.simplefilter("ignore", RuntimeWarning)
            self.solver = LieGroupSolver(info.mbs, method=method, liegroup=group)
        sc = self.solver.scene
        objs = list(sc.bodyObject)
        self.bodyMap = [objs.index(b.objectIndex) for b in info.bodies]
        jmap = {ji.objectIndex: ji.sceneJoint for ji in sc.joints_info}
        self.jointMap = {j.name: jmap[j.objectIndex] for j in info.joints}

    def run(self, stepSize, endTime=None, outputPeriod=1e-3, keep_states=False):
        info = self.info
        endTime = info.endTime if endTime is None else endTime
        every = output_every(stepSize, outputPeriod)
        ok, msg = True, ""
        tic = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            try:
                res = self.solver.Run(endTime, stepSize, outputEvery=every, writeBack=False)
            except Exception as e:     # SimulationError (blow-up), ConstraintError
                res, ok, msg = None, False, f"{type(e).__name__}: {e}"
        wall = time.perf_counter() - tic
        if res is None:
            return RunData(info.name, self.group, stepSize, False, msg, wall, np.zeros(0))
        bm = self.bodyMap
        rd = RunData(info.name, self.group, stepSize, ok, msg, float(res.cpuTime), res.times.copy())
        measure(info, rd, res.R[:, bm], res.r[:, bm], res.omega[:, bm], res.vel[:, bm], keep_states)
        for name, k in self.jointMap.items():
            rd.kernelPosition[name] = res.jointPositionViolation[:, k].copy()
            rd.kernelRotation[name] = res.jointRotationViolation[:, k].copy()
        rd.kernelEnergy = res.totalEnergy.copy()
        return rd


def run_lie(info, group, stepSize, endTime=None, outputPeriod=1e-3, keep_states=False):
    """A single MK-RK4 run (see :class:`LieRunner` for several step sizes)."""
    return LieRunner(info, group).run(stepSize, endTime, outputPeriod, keep_states)


# --------------------------------------------------------------------------- native
def run_native(info, solver, stepSize, endTime=None, outputPeriod=1e-3, keep_states=False):
    """Exudyn's own solver on the model (see :func:`models.run_native`)."""
    from models import run_native as _run
    period = max(stepSize, outputPeriod)
    res = _run(info, solver, stepSize, endTime=endTime, outputPeriod=period)
    rd = RunData(info.name, solver, stepSize, res.ok, res.message, res.cpuTime, res.times, native=True)
    return measure(info, rd, res.R, res.r, res.omega, res.vel, keep_states)
