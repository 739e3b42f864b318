"""Shared pieces of the paper's model builders.

Every builder in :mod:`exudyn_lie.models` creates an ordinary Exudyn model with Exudyn's own
``MainSystem.Create*`` helpers and returns ``(mbs, info)``.  :class:`ModelInfo` records
what is needed to run and to judge the model without re-reading Exudyn's internals:

* per body: Exudyn object / node index, mass, inertia about the body frame origin,
  centre of mass, initial pose and velocity (body-fixed angular velocity, world
  velocity of the frame origin);
* per joint (named ``joint1``, ``joint2``... as in the paper): object index, kind, the
  two bodies (``GROUND = -1``) and the joint frames on both sides (read back from the
  markers Exudyn created, so that the violation measures of
  :mod:`exudyn_lie.models.geometry` use exactly Exudyn's joint frames);
* springs, gravity, the time span, analytic reference solutions (free bodies),
  numbers quoted by the paper, and the claims the paper makes about the model;
* ``choices``: every value the paper does not give, with the reason.

Conventions: SI units; ``R`` maps body to world; the body frame is Exudyn's node frame
(the body reference point); inertia is about that point (``RigidBodyInertia``).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional

import numpy as np

import exudyn as exu

GROUND = -1
ALUMINIUM = 2700.0          # kg/m^3, the paper's material
G = 9.81                    # m/s^2, the paper's gravity

# locked relative axes (tx, ty, tz, rx, ry, rz) of the joints as Exudyn defines them
JOINT_AXES = {
    "spherical": (1, 1, 1, 0, 0, 0),
    "revolute": (1, 1, 1, 1, 1, 0),     # ObjectJointRevoluteZ: free rotation about joint z
    "prismatic": (0, 1, 1, 1, 1, 1),    # ObjectJointPrismaticX: free translation along joint x
    "universal": (1, 1, 1, 0, 0, 1),    # ObjectJointGeneric: free rotations about x (on A), y (on B)
    "cylindrical": (1, 1, 0, 1, 1, 0),
}


@dataclass
class BodyData:
    name: str
    objectIndex: int
    nodeIndex: int
    mass: float
    inertia: np.ndarray          # 3x3 about the body frame origin, body coordinates
    com: np.ndarray              # centre of mass in body coordinates
    R0: np.ndarray
    r0: np.ndarray
    omega0: np.ndarray           # body-fixed
    vel0: np.ndarray             # world velocity of the frame origin
    massMarker: Optional[int] = None     # MarkerBodyMass of the gravity load (if any)
    gravityLoad: Optional[int] = None    # LoadMassProportional (if any)

    @property
    def inertiaCOM(self):
        c = self.com
        return self.inertia - self.mass * (np.dot(c, c) * np.eye(3) - np.outer(c, c))


@dataclass
class JointData:
    name: str                    # 'joint1', 'joint2', ... (paper numbering)
    objectIndex: int
    kind: str                    # key of JOINT_AXES
    bodyA: int                   # model body index, GROUND = -1
    bodyB: int
    posA: np.ndarray             # joint frame origin on A (body coordinates; world for ground)
    rotA: np.ndarray             # joint frame orientation on A
    posB: np.ndarray
    rotB: np.ndarray
    description: str = ""
    markers: tuple = ()          # Exudyn marker indices (A side, B side)

    @property
    def lockedAxes(self):
        return JOINT_AXES[self.kind]


@dataclass
class SpringData:
    name: str
    objectIndex: int
    bodyA: int
    posA: np.ndarray
    bodyB: int
    posB: np.ndarray
    stiffness: float
    referenceLength: float
    markers: tuple = ()


@dataclass
class Claim:
    """What the paper says about one joint (or, for a free body, its COM / rotation).

    ``kind`` (judged by :func:`exudyn_lie.apps.claims.judge`): ``'exact_SE3'`` /
    ``'exact_SO3xR3'`` (that group at round-off, the other >= 1e3 worse at dt = 1e-2),
    ``'exact_both'``, ``'SE3_exact'`` (nothing claimed for SO3xR3), ``'same_order'``,
    ``'SO3xR3_better'``, ``'SE3_better'``, ``'SE3_better_large_step'``,
    ``'identical_rotation'``, ``'identical_drift'``; ``measure``: ``'position'`` /
    ``'rotation'`` (rows of a joint), ``'com'`` (COM drift from the exact solution),
    ``'orientation'`` (eps_r against the exact rotation), ``'energy'`` (|E - E0|);
    ``ref`` names the paper's statement (corollary 1, lemma 1, corollary 3, ...)."""
    target: str                  # joint name, or 'body1' for free bodies
    measure: str
    kind: str
    ref: str
    text: str


@dataclass
class ModelInfo:
    name: str
    title: str
    section: str
    mbs: object
    SC: object
    bodies: List[BodyData]
    joints: List[JointData]
    springs: List[SpringData]
    gravity: np.ndarray
    endTime: float
    nodeType: object
    ground: Optional[int] = None
    exact: Optional[Callable] = None      # exact(t array) -> dict(R=(nt,nb,3,3), r=(nt,nb,3), com=(nt,nb,3))
    paper: Dict[str, float] = field(default_factory=dict)
    computed: Dict[str, float] = field(default_factory=dict)
    claims: List[Claim] = field(default_factory=list)
    choices: List[str] = field(default_factory=list)
    redundantConstraints: bool = False    # rank-deficient constraint Jacobian (planar four-bar)
    builder: Optional[Callable] = None
    buildArgs: Dict = field(default_factory=dict)
    sensors: Optional[list] = None

    @property
    def constrained(self):
        return len(self.joints) > 0

    @property
    def objects(self):
        return [b.objectIndex for b in self.bodies]

    @property
    def nodes(self):
        return [b.nodeIndex for b in self.bodies]

    def joint(self, name):
        for j in self.joints:
            if j.name == name:
                return j
        raise KeyError(f"{self.name} has no joint {name!r}; joints: {[j.name for j in self.joints]}")

    def initial_energy(self):
        """(kinetic, gravity, spring) energy of the initial state, from the info data."""
        from .energy import energies
        R = np.array([b.R0 for b in self.bodies])[None]
        r = np.array([b.r0 for b in self.bodies])[None]
        om = np.array([b.omega0 for b in self.bodies])[None]
        ve = np.array([b.vel0 for b in self.bodies])[None]
        return energies(self, R, r, om, ve)[0]


# ---------------------------------------------------------------------------- building
def new_system(mbs=None):
    """A MainSystem linked to a SystemContainer (the container must be kept alive)."""
    if mbs is not None:
        return mbs, None
    SC = exu.SystemContainer()
    return SC.AddSystem(), SC


def add_body(mbs, bodies, name, inertia, R0=None, r0=(0, 0, 0), omega0=(0, 0, 0), vel0=(0, 0, 0),
             gravity=(0, 0, 0), nodeType=exu.NodeType.RotationRotationVector):
    """Create an Exudyn rigid body and record it.

    ``inertia``: a ``RigidBodyInertia`` about the body frame origin (its ``com`` may be
    offset); ``omega0`` is BODY-FIXED (the paper's convention; Exudyn's
    ``initialAngularVelocity`` is global, converted here); ``vel0`` the world velocity of
    the frame origin."""
    R0 = np.eye(3) if R0 is None else np.asarray(R0, float)
    omega0 = np.asarray(omega0, float)
    d = mbs.CreateRigidBody(name=name, inertia=inertia, referencePosition=list(map(float, r0)),
                            referenceRotationMatrix=R0, initialVelocity=list(map(float, vel0)),
                            initialAngularVelocity=list(R0 @ omega0), gravity=list(map(float, gravity)),
                            nodeType=nodeType, returnDict=True)
    bodies.append(BodyData(name, int(d["bodyNumber"]), int(d["nodeNumber"]), float(inertia.mass),
                           np.array(inertia.inertiaTensor, float), np.array(inertia.com, float), R0.copy(),
                           np.array(r0, float), omega0.copy(), np.array(vel0, float),
                           d.get("markerBodyMass"), d.get("loadNumber")))
    return d["bodyNumber"]


def _marker_frame(mbs, markerNumber):
    m = mbs.GetMarker(markerNumber)
    if "localHT" in m:
        HT = np.asarray(m["localHT"], float)
        return HT[:3, 3].copy(), HT[:3, :3].copy()
    return np.asarray(m["localPosition"], float).copy(), np.eye(3)


def record_joint(mbs, joints, name, oJoint, kind, bodyA, bodyB, description=""):
    """Record a joint created by an Exudyn ``Create*Joint`` helper, with the joint frames
    read back from its markers (and ``rotationMarker0/1`` if set)."""
    o = mbs.GetObject(oJoint)
    m0, m1 = o["markerNumbers"]
    pA, RA = _marker_frame(mbs, m0)
    pB, RB = _marker_frame(mbs, m1)
    if "rotationMarker0" in o:
        RA = RA @ np.asarray(o["rotationMarker0"], float)
        RB = RB @ np.asarray(o["rotationMarker1"], float)
    joints.append(JointData(name, int(oJoint), kind, bodyA, bodyB, pA, RA, pB, RB, description,
                            (int(m0), int(m1))))
    return oJoint


def spring_markers(mbs, oSpring):
    return tuple(int(m) for m in mbs.GetObject(oSpring)["markerNumbers"])


def world_point(bodies, b, p):
    if b == GROUND:
        return np.asarray(p, float)
    B = bodies[b]
    return B.r0 + B.R0 @ np.asarray(p, float)


def point_velocity(bodies, b, p):
    """World velocity of the body-fixed point ``p`` (body coordinates) at t = 0."""
    if b == GROUND:
        return np.zeros(3)
    B = bodies[b]
    return B.vel0 + np.cross(B.R0 @ B.omega0, B.R0 @ np.asarray(p, float))


def rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def check_initial_consistency(info, tol=1e-12):
    """Position and velocity residuals of every joint at t = 0 (from the info data);
    raises if the builder produced an inconsistent initial state."""
    from .geometry import joint_violations, joint_velocity_violations
    R = np.array([b.R0 for b in info.bodies])[None]
    r = np.array([b.r0 for b in info.bodies])[None]
    om = np.array([b.omega0 for b in info.bodies])[None]
    ve = np.array([b.vel0 for b in info.bodies])[None]
    for j in info.joints:
        pv, rv = joint_violations(j, R, r)
        vv = joint_velocity_violations(j, R, r, om, ve)
        scale = 1.0 + max(np.abs(ve).max(), np.abs(om).max())
        if pv[0] > tol or rv[0] > tol or vv[0] > tol * scale:
            raise AssertionError(f"{info.name}: {j.name} violated at t=0: position {pv[0]:.3g}, "
                                 f"rotation {rv[0]:.3g}, velocity {vv[0]:.3g}")


# ---------------------------------------------------------------------------- native solvers
NATIVE_SOLVERS = {
    # name: (DynamicSolverType, extra settings)
    "GeneralizedAlpha": "GeneralizedAlpha",
    "TrapezoidalIndex2": "TrapezoidalIndex2",
    "RK44": "RK44",
    "DOPRI5": "DOPRI5",
}


def native_solvers_for(info):
    """Exudyn's native baselines: implicit DAE solvers for constrained models (explicit
    ones refuse joints), explicit Lie group RK with RotVecLG nodes for free bodies."""
    return ["GeneralizedAlpha", "TrapezoidalIndex2"] if info.constrained else ["RK44", "DOPRI5"]


@dataclass
class NativeResult:
    solver: str
    stepSize: float
    times: np.ndarray
    R: np.ndarray                # (nt, nb, 3, 3)
    r: np.ndarray                # (nt, nb, 3)
    omega: np.ndarray            # (nt, nb, 3) body-fixed
    vel: np.ndarray              # (nt, nb, 3) world velocity of the frame origins
    cpuTime: float
    ok: bool = True
    message: str = ""


def _ensure_sensors(info):
    if info.sensors is not None:
        return info.sensors
    mbs = info.mbs
    ovt = exu.OutputVariableType
    sens = []
    for b in info.bodies:
        sens.append(tuple(mbs.AddSensor(exu.itemInterface.SensorNode(
            nodeNumber=b.nodeIndex, outputVariableType=v, storeInternal=True, writeToFile=False)) for v in
            (ovt.Position, ovt.RotationMatrix, ovt.AngularVelocityLocal, ovt.Velocity)))
    info.sensors = sens
    return sens


def native_settings(solver, stepSize, endTime, outputPeriod, redundant=False):
    """SimulationSettings for one of :data:`NATIVE_SOLVERS` with a fixed step size.

    ``redundant``: the model has redundant constraint rows; Exudyn then needs the
    full-pivoting dense solver (``EigenDense`` with ``ignoreSingularJacobian``), which
    resolves the singular system by least squares."""
    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.endTime = float(endTime)
    ti.numberOfSteps = int(round(endTime / stepSize))
    ti.verboseMode = 0
    ti.stepInformation = 0
    ti.automaticStepSize = False          # fixed steps, comparable with the MK runs
    if solver in ("GeneralizedAlpha", "TrapezoidalIndex2"):
        ti.adaptiveStep = False           # no step reduction after a Newton failure: the run stops there
    s.solution.file.write = False
    s.solution.sensors.writePeriod = float(outputPeriod)
    s.show.statistics = False
    s.show.computationTime = False
    if solver == "TrapezoidalIndex2":
        ti.generalizedAlpha.useIndex2Constraints = True
        ti.generalizedAlpha.useNewmark = True
        ti.generalizedAlpha.spectralRadius = 1.0
    if redundant:
        s.linearSolver.solverType = exu.LinearSolverType.EigenDense
        s.linearSolver.ignoreSingularJacobian = True
    return s


def body_states_from_sensors(data, nt):
    """(R, r, omega, vel), arrays over (time, body), from the stored data of each body's
    four node sensors (Position, RotationMatrix, AngularVelocityLocal, Velocity; column 0
    is the time), first ``nt`` rows."""
    nb = len(data)
    R = np.zeros((nt, nb, 3, 3))
    r = np.zeros((nt, nb, 3))
    om = np.zeros((nt, nb, 3))
    ve = np.zeros((nt, nb, 3))
    for i, (dp, dR, dw, dv) in enumerate(data):
        r[:, i] = dp[:nt, 1:4]
        R[:, i] = dR[:nt, 1:10].reshape(nt, 3, 3)
        om[:, i] = dw[:nt, 1:4]
        ve[:, i] = dv[:nt, 1:4]
    return R, r, om, ve


def _native_failure(mbs, error):
    """Why a native solve stopped, in Exudyn's words: its solver's error string and the step
    it failed in (``mbs.sys['dynamicSolver']``, stored by ``SolveDynamic``)."""
    solver = mbs.sys.get("dynamicSolver")
    text = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
    if solver is None:
        return f"{type(error).__name__}: {text}"
    it = solver.it
    h = it.currentStepSize
    return (f"Exudyn: '{solver.GetErrorString().strip()}' in the step from t = {it.currentTime - h:.4g} s to "
            f"{it.currentTime:.4g} s ({it.newtonStepsCount} Newton iterations in all)")


def run_native(info, solver, stepSize, endTime=None, outputPeriod=None):
    """Integrate the model with one of Exudyn's own solvers (fixed step) and return the
    body states at the output times (read from node sensors).

    ``solver``: 'GeneralizedAlpha' (index 3, Exudyn's default spectral radius 0.9),
    'TrapezoidalIndex2' (index 2, trapezoidal rule), 'RK44' or 'DOPRI5' (explicit, Lie
    group update for RotVecLG nodes; free bodies only: Exudyn refuses joints there)."""
    if solver not in NATIVE_SOLVERS:
        raise ValueError(f"unknown native solver {solver!r}; use one of {list(NATIVE_SOLVERS)}")
    if solver in ("RK44", "DOPRI5") and info.constrained:
        raise ValueError(f"{info.name}: Exudyn's explicit solvers refuse joints; use "
                         f"GeneralizedAlpha or TrapezoidalIndex2")
    endTime = info.endTime if endTime is None else float(endTime)
    outputPeriod = max(stepSize, 1e-2) if outputPeriod is None else outputPeriod
    sens = _ensure_sensors(info)
    mbs = info.mbs
    mbs.Assemble()
    s = native_settings(solver, stepSize, endTime, outputPeriod, info.redundantConstraints)
    stype = getattr(exu.DynamicSolverType, NATIVE_SOLVERS[solver])
    tic = time.perf_counter()
    ok, msg = True, ""
    try:
        res = mbs.SolveDynamic(s, solverType=stype)
        if res is False:
            ok, msg = False, "SolveDynamic returned False"
    except Exception as e:  # Exudyn raises on Newton failure etc.
        ok, msg = False, _native_failure(mbs, e)
    cpu = time.perf_counter() - tic
    nb = len(info.bodies)
    data = [[mbs.GetSensorStoredData(x) for x in s4] for s4 in sens]
    nt = min(len(d[0]) for d in data)
    if nt == 0:
        return NativeResult(solver, stepSize, np.zeros(0), np.zeros((0, nb, 3, 3)), np.zeros((0, nb, 3)),
                            np.zeros((0, nb, 3)), np.zeros((0, nb, 3)), cpu, False, msg or "no output")
    times = data[0][0][:nt, 0].copy()
    R, r, om, ve = body_states_from_sensors(data, nt)
    if ok and times[-1] < endTime - 0.5 * stepSize:
        ok, msg = False, f"stopped at t = {times[-1]:.4g} s"
    return NativeResult(solver, stepSize, times, R, r, om, ve, cpu, ok, msg)


def run_native_default_steps(info, solver, stepSize, endTime=None):
    """The fixed-step native run of :func:`run_native` again with Exudyn's default step
    control (``adaptiveStep = True``: after a failed Newton iteration the step is reduced
    and later recovers): ``(ok, time reached [s], steps taken, message)``."""
    endTime = info.endTime if endTime is None else float(endTime)
    mbs = info.mbs
    mbs.Assemble()
    s = native_settings(solver, stepSize, endTime, max(stepSize, 1e-2), info.redundantConstraints)
    s.timeIntegration.adaptiveStep = True
    stype = getattr(exu.DynamicSolverType, NATIVE_SOLVERS[solver])
    ok, msg = True, ""
    try:
        if mbs.SolveDynamic(s, solverType=stype) is False:
            ok, msg = False, "SolveDynamic returned False"
    except Exception as e:  # Exudyn raises when even the reduced step fails
        ok, msg = False, _native_failure(mbs, e)
    solver_ = mbs.sys.get("dynamicSolver")
    it = solver_.it if solver_ is not None else None
    reached = float(it.currentTime) if it is not None else float("nan")
    steps = int(it.currentStepIndex) if it is not None else -1
    if ok and reached < endTime - 0.5 * stepSize:
        ok, msg = False, f"stopped at t = {reached:.4g} s"
    return ok, reached, steps, msg

