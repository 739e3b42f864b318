"""Run the paper's models with exudyn_lie (through the Exudyn bridge) and with Exudyn's
native solvers, and reduce every run to the same measures.

* :func:`run_lie` - MK-RK4 on ``SE3`` or ``SO3xR3`` via
  :class:`exudyn_lie.bridge.LieGroupSolver` (the Exudyn model is read by
  ``SceneFromExudyn``; the compiled ``Simulator.Run`` path, compiled once per model and
  group, many step sizes) - the fast path of ``python -m exudyn_lie paper``;
* :func:`run_solve_dynamic` - the same MK-RK4 run through the drop-in
  ``exudyn_lie.SolveDynamic(mbs, simulationSettings, method='RK4', liegroup=...)``, i.e.
  inside Exudyn's own time loop; every step is recorded by Exudyn sensors (node states
  and the joint markers) and the measures are computed from what Exudyn sees in ``mbs``,
  not from the package's arrays (the paper tests assert the claims on these runs);
* :func:`run_native` - ``exudyn.SolveDynamic`` with GeneralizedAlpha /
  TrapezoidalIndex2 (constrained models) or RK44 / DOPRI5 (free bodies), states read
  from node sensors (:func:`models.run_native`).

Both give a :class:`RunData`: the body states at the output times and, computed from
them with :mod:`.geometry` and :mod:`.energy` (the same formulas for every solver),
the violation of every joint, the COM drift and orientation error against the exact
solution (free bodies), and the total energy.  Runs of the fast path also keep the
kernel's own diagnostics (``kernelPosition`` / ``kernelRotation`` / ``kernelEnergy``),
runs through ``SolveDynamic`` the joint violations computed from Exudyn's own marker
outputs (``markerPosition`` / ``markerRotation``), so that both can be cross-checked.
"""
from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from typing import Dict, Optional

import numpy as np

from ..models.energy import energies
from ..models.geometry import com_positions, joint_violations, orientation_error

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
    markerPosition: Dict[str, np.ndarray] = field(default_factory=dict)   # from Exudyn's marker sensors
    markerRotation: Dict[str, np.ndarray] = field(default_factory=dict)
    native: bool = False
    via: str = ""                   # 'Run' (fast path), 'SolveDynamic' or 'native'

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
            self.solver = LieGroupSolver(info.mbs, method=method, liegroup=group, projectInitial=False)  # paper: strict
        sc = self.solver.scene
        objs = list(sc.bodyObject)
        self.bodyMap = [objs.index(b.objectIndex) for b in info.bodies]
        jmap = {ji.objectIndex: ji.sceneJoint for ji in sc.joints_info}
        self.jointMap = {j.name: jmap[j.objectIndex] for j in info.joints}

    def run(self, stepSize, endTime=None, outputPeriod=None, keep_states=False):
        """One run; ``outputPeriod`` None: every step is stored (the maxima are over the whole run)."""
        info = self.info
        endTime = info.endTime if endTime is None else endTime
        every = 1 if outputPeriod is None else output_every(stepSize, outputPeriod)
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
            return RunData(info.name, self.group, stepSize, False, msg, wall, np.zeros(0), via="Run")
        bm = self.bodyMap
        rd = RunData(info.name, self.group, stepSize, ok, msg, float(res.cpuTime), res.times.copy(), via="Run")
        measure(info, rd, res.R[:, bm], res.r[:, bm], res.omega[:, bm], res.vel[:, bm], keep_states)
        for name, k in self.jointMap.items():
            rd.kernelPosition[name] = res.jointPositionViolation[:, k].copy()
            rd.kernelRotation[name] = res.jointRotationViolation[:, k].copy()
        rd.kernelEnergy = res.totalEnergy.copy()
        return rd


def run_lie(info, group, stepSize, endTime=None, outputPeriod=None, keep_states=False):
    """A single MK-RK4 run (see :class:`LieRunner` for several step sizes)."""
    return LieRunner(info, group).run(stepSize, endTime, outputPeriod, keep_states)


# --------------------------------------------------------------------------- through SolveDynamic
@dataclass
class _Sensors:
    nodes: list                 # per body: (Position, RotationMatrix, AngularVelocityLocal, Velocity)
    markers: dict               # joint name -> ((Position, RotationMatrix or None) side A, ... side B)


def exudyn_sensors(info):
    """Exudyn sensors (stored internally, no files) on every body node - position,
    rotation matrix, local angular velocity, velocity - and on both markers of every
    joint - position, and the rotation matrix where the joint has rotation rows.  Added
    to ``info.mbs`` once (kept on ``info``); the caller assembles."""
    import exudyn as exu
    old = getattr(info, "_exudynSensors", None)
    if old is not None:
        return old
    mbs = info.mbs
    ovt = exu.OutputVariableType

    def add(kind, **kw):
        return mbs.AddSensor(kind(storeInternal=True, writeToFile=False, **kw))

    nodes = [tuple(add(exu.itemInterface.SensorNode, nodeNumber=b.nodeIndex, outputVariableType=v)
                   for v in (ovt.Position, ovt.RotationMatrix, ovt.AngularVelocityLocal, ovt.Velocity))
             for b in info.bodies]
    markers = {}
    for j in info.joints:
        rot = any(j.lockedAxes[3:])
        markers[j.name] = tuple(
            (add(exu.itemInterface.SensorMarker, markerNumber=m, outputVariableType=ovt.Position),
             add(exu.itemInterface.SensorMarker, markerNumber=m, outputVariableType=ovt.RotationMatrix)
             if rot else None) for m in j.markers)
    info._exudynSensors = _Sensors(nodes, markers)
    return info._exudynSensors


def _rotation_marker(info, j, side):
    """The joint's extra frame rotation on one side (``rotationMarker0/1`` of joints that
    have it, else I): the joint frame is Exudyn's marker rotation output times it."""
    o = info.mbs.GetObject(j.objectIndex)
    key = f"rotationMarker{side}"
    return np.asarray(o[key], float) if key in o else np.eye(3)


def marker_violations(info, j, data):
    """(position, rotation) violation of joint ``j`` from Exudyn's marker outputs alone:
    ``data`` = ((pA (nt,3), RA (nt,3,3) or None), (pB, RB)) - marker positions and
    rotation matrices (which include the marker's local frame) as Exudyn reports them.
    The rows are those of :func:`.geometry.joint_violations` with each side's frame
    taken as (marker position, marker rotation x rotationMarker)."""
    from dataclasses import replace
    (pA, RA), (pB, RB) = data
    nt = len(pA)
    eye = np.broadcast_to(np.eye(3), (nt, 3, 3))
    R = np.stack([eye if RA is None else RA, eye if RB is None else RB], axis=1)
    r = np.stack([pA, pB], axis=1)
    pseudo = replace(j, bodyA=0, bodyB=1, posA=np.zeros(3), posB=np.zeros(3),
                     rotA=_rotation_marker(info, j, 0), rotB=_rotation_marker(info, j, 1))
    return joint_violations(pseudo, R, r)


def solve_dynamic_settings(stepSize, endTime):
    """Exudyn SimulationSettings: ``endTime / stepSize`` steps, sensors written at every
    step (stored internally), no solution file, quiet."""
    import exudyn as exu
    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.endTime = float(endTime)
    ti.numberOfSteps = int(round(endTime / stepSize))
    ti.verboseMode = 0
    s.solution.file.write = False
    s.solution.sensors.writePeriod = float(stepSize)
    s.show.statistics = False
    s.show.computationTime = False
    return s


def run_solve_dynamic(info, group, stepSize, endTime=None, keep_states=False, method="RK4"):
    """MK-RK4 on ``group`` through ``exudyn_lie.SolveDynamic(mbs, simulationSettings,
    method='RK4', liegroup=group)`` - Exudyn's own time loop with the package as its
    integrator - recording EVERY step with Exudyn sensors (:func:`exudyn_sensors`).

    The measures are computed from the sensor data, i.e. from what Exudyn sees in
    ``mbs``: body states (node sensors) -> :func:`measure` (joint violations, COM drift,
    orientation error, energy, the same formulas as for every other run), and the joint
    violations once more from the joint markers' world positions / rotations
    (``markerPosition`` / ``markerRotation``, :func:`marker_violations`).  Runs start
    from the model's initial values in ``mbs`` (a model can be run several times)."""
    import contextlib
    import io

    import exudyn_lie as exl
    endTime = info.endTime if endTime is None else float(endTime)
    sens = exudyn_sensors(info)
    mbs = info.mbs
    mbs.Assemble()
    s = solve_dynamic_settings(stepSize, endTime)
    nsteps = s.timeIntegration.numberOfSteps
    ok, msg = True, ""
    tic = time.perf_counter()
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore", RuntimeWarning)
        try:
            exl.SolveDynamic(mbs, s, method=method, liegroup=group, showProgress=False, projectInitial=False,
                             stabilization=None)
        except Exception as e:       # SimulationError (blow-up), ConstraintError, Exudyn's SolverError
            ok, msg = False, f"{type(e).__name__}: {str(e).strip().splitlines()[0] if str(e).strip() else ''}"
    wall = time.perf_counter() - tic
    lgs = mbs.sys.get("lieGroupSolver") if hasattr(mbs, "sys") else None
    cpu = float(lgs.timing.get("integration", wall)) if lgs is not None and ok else wall
    get = mbs.GetSensorStoredData
    data = [[np.asarray(get(x)) for x in s4] for s4 in sens.nodes]
    nt = min(len(d) for s4 in data for d in s4) if data else 0
    times = data[0][0][:nt, 0].copy() if nt else np.zeros(0)
    if ok and (nt != nsteps + 1 or np.max(np.abs(times - stepSize * np.arange(nt))) > 1e-9 * endTime):
        ok, msg = False, (f"the sensors did not record every step: {nt} rows for {nsteps} steps "
                          f"(t = {times[0] if nt else float('nan'):g} .. {times[-1] if nt else float('nan'):g})")
    rd = RunData(info.name, group, stepSize, ok, msg, cpu, times, via="SolveDynamic")
    from exudyn_lie.models._common import body_states_from_sensors
    R, r, om, ve = body_states_from_sensors(data, nt)
    measure(info, rd, R, r, om, ve, keep_states)
    for j in info.joints:
        sides = []
        for sP, sR in sens.markers[j.name]:
            p = np.asarray(get(sP))[:nt, 1:4]
            Rm = None if sR is None else np.asarray(get(sR))[:nt, 1:10].reshape(nt, 3, 3)
            sides.append((p, Rm))
        rd.markerPosition[j.name], rd.markerRotation[j.name] = marker_violations(info, j, sides)
    return rd


# --------------------------------------------------------------------------- native
def run_native(info, solver, stepSize, endTime=None, outputPeriod=None, keep_states=False):
    """Exudyn's own solver on the model (see :func:`models.run_native`); ``outputPeriod``
    None: sensors record every step."""
    from exudyn_lie.models import run_native as _run
    period = stepSize if outputPeriod is None else max(stepSize, outputPeriod)
    res = _run(info, solver, stepSize, endTime=endTime, outputPeriod=period)
    rd = RunData(info.name, solver, stepSize, res.ok, res.message, res.cpuTime, res.times, native=True, via="native")
    return measure(info, rd, res.R, res.r, res.omega, res.vel, keep_states)
