"""Bench section ``params``: the cost of parameters changed during a solve.

Exudyn's ``serialRobotTest``: a 6-link robot (``exudyn.robotics``, redundant coordinates,
6 revolute joints) whose 12 joint-torque ``LoadTorqueVector`` s are set by a PD controller
in a pre-step function every step.  Per step, medians of repeated ``exl.SolveDynamic`` runs
(MK-RK4, h = 1e-3 s; one Exudyn step per step in every variant, so the rows differ only in
the pre-step function; per step = (run of 2n steps - run of n steps) / n, so that the fixed
cost of a solve cancels):

* ``none``: no pre-step function (the loads stay as they are);
* ``empty``: a pre-step function that returns True (Exudyn's loop and the bridge's hook
  every step, nothing changes);
* ``compute``: the PD law evaluated (``GetObjectOutput`` of 6 joints, the static torques),
  no load set;
* ``control``: the full controller, 12 ``SetLoadParameter`` calls per step (Exudyn's call,
  the bridge's record, and before the next step the re-read of the 12 loads into the
  compiled load rows, :mod:`exudyn_lie.bridge.params`);
* ``exudynSet``: 12 ``SetLoadParameter`` calls per step outside a solve (Exudyn's own call);
* ``watched``: the same calls recorded by a :class:`~exudyn_lie.bridge.params.ParameterWatch`
  and applied after each step's 12 calls (the bridge's work in a controlled solve);
* ``native``: Exudyn's generalized-alpha with the full controller (for scale).

``control - compute`` is what setting the 12 loads costs per step in a solve (a difference of
two noisy runs); ``watched - exudynSet`` is the bridge's own part, measured directly.
"""
from __future__ import annotations

import time

import numpy as np


def robot(controller="control"):
    """The serialRobotTest model; ``controller`` one of None, 'empty', 'compute', 'control'."""
    import exudyn as exu
    from exudyn.rigidBodyUtilities import HT2translation, HTtranslate
    from exudyn.robotics import Robot, RobotBase, RobotLink, RobotTool, StdDH2HT
    from exudyn.robotics.motion import ProfileConstantAcceleration, Trajectory
    from exudyn.utilities import MarkerBodyRigid, ObjectGround
    O = exu.OutputVariableType
    mbs = exu.SystemContainer().AddSystem()
    rb = Robot(gravity=[0, 0, 9.81], base=RobotBase(), tool=RobotTool(HT=HTtranslate([0, 0, 0.1])),
               referenceConfiguration=[])
    for m, com, J, dh in ((20, [0, 0, 0], [1e-8, 0.35, 1e-8], [0, 0, 0, np.pi / 2]),
                          (17.4, [-0.3638, 0.006, 0.2275], [0.13, 0.524, 0.539], [0, 0, 0.4318, 0]),
                          (4.8, [-0.0203, -0.0141, 0.07], [0.066, 0.086, 0.0125], [0, 0.15, 0.0203, -np.pi / 2]),
                          (0.82, [0, 0.019, 0], [0.0018, 0.0013, 0.0018], [0, 0.4318, 0, np.pi / 2]),
                          (0.34, [0, 0, 0], [0.0003, 0.0004, 0.0003], [0, 0, 0, -np.pi / 2]),
                          (0.09, [0, 0, 0.032], [0.00015, 0.00015, 4e-5], [0, 0, 0, 0])):
        rb.AddLink(RobotLink(mass=m, COM=com, inertia=np.diag(J), localHT=StdDH2HT(dh)))
    traj = Trajectory([0] * 6, 0)
    traj.Add(ProfileConstantAcceleration([0, np.pi / 8, np.pi * 0.25, 0, np.pi / 8, 0], 0.25))
    traj.Add(ProfileConstantAcceleration([0] * 6, 1e6))
    P = np.array([40000, 40000, 40000, 100, 100, 10])
    D = np.array([400, 400, 100, 1, 1, 0.05])
    g = mbs.AddObject(ObjectGround(referencePosition=HT2translation(rb.GetBaseHT())))
    base = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g, localPosition=[0, 0, 0]))
    rd = rb.CreateRedundantCoordinateMBS(mbs, baseMarker=base)
    joints, u0, u1 = rd["jointList"], rd["unitTorque0List"], rd["unitTorque1List"]
    l0, l1 = rd["jointTorque0List"], rd["jointTorque1List"]

    def pd(mbs, t):
        q = [mbs.GetObjectOutput(j, O.Rotation)[2] for j in joints]
        static = rb.StaticTorques(rb.JointHT(q))
        out = []
        for i, j in enumerate(joints):
            om = mbs.GetObjectOutput(j, O.AngularVelocityLocal)[2]
            u, v, a = traj.EvaluateCoordinate(t, i)
            out.append(-(P[i] * (q[i] - u) + D[i] * (om - v)) - static[i])
        return out

    def control(mbs, t):
        for i, tau in enumerate(pd(mbs, t)):
            mbs.SetLoadParameter(l0[i], "loadVector", list(tau * u0[i]))
            mbs.SetLoadParameter(l1[i], "loadVector", list(tau * u1[i]))
        return True

    fns = {None: None, "empty": lambda mbs, t: True, "compute": lambda mbs, t: bool(pd(mbs, t)) or True,
           "control": control}
    if fns[controller] is not None:
        mbs.SetPreStepUserFunction(fns[controller])
    mbs.Assemble()
    return mbs, (l0, l1, u0, u1)


def _settings(T, h):
    import exudyn as exu
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = T
    ss.timeIntegration.numberOfSteps = int(round(T / h))
    ss.timeIntegration.verboseMode = 0
    ss.solution.file.write = False
    ss.solution.sensors.writePeriod = h
    ss.timeIntegration.generalizedAlpha.spectralRadius = 0.5
    ss.timeIntegration.generalizedAlpha.computeInitialAccelerations = True
    return ss


def parameter_updates(T=0.2, h=1e-3, repeats=7):
    """Per-step times (median of ``repeats``, variants interleaved in every round because
    the machine's speed drifts) of the variants in the module docstring; seconds."""
    import exudyn_lie as exl
    from exudyn_lie.bridge.params import ParameterWatch
    n = int(round(T / h))
    variants = ("none", "empty", "compute", "control", "native")
    times = {v: [] for v in variants}
    def run(v, TT):
        mbs, _loads = robot({"native": "control", "none": None}.get(v, v))
        ss = _settings(TT, h)
        tic = time.perf_counter()
        if v == "native":
            mbs.SolveDynamic(ss)
        else:
            exl.SolveDynamic(mbs, ss, showProgress=False, substeps=1, stabilization=None)
        return time.perf_counter() - tic

    for _ in range(repeats):
        for v in variants:
            # per step without the fixed cost of a solve (reading, compiling, Exudyn's set-up):
            # a run of 2n steps minus a run of n steps
            times[v].append((run(v, 2 * T) - run(v, T)) / n)
        # the 12 calls per step alone, and with the bridge's watch: wrapped calls + the
        # re-read into the compiled rows before the next step (ParameterWatch.apply)
        mbs, (l0, l1, u0, u1) = robot(None)
        solver = exl.LieGroupSolver(mbs)
        solver.Run(0.0, h, writeBack=False)
        vecs = [[list(1e-3 * k * u0[i]) for i in range(6)] + [list(1e-3 * k * u1[i]) for i in range(6)]
                for k in range(n)]
        loads = list(l0) + list(l1)
        for key in ("exudynSet", "watched"):
            watch = ParameterWatch(solver) if key == "watched" else None
            tic = time.perf_counter()
            if watch is not None:
                with watch:
                    for k in range(n):
                        for l, v in zip(loads, vecs[k]):
                            mbs.SetLoadParameter(l, "loadVector", v)
                        watch.apply(k * h)
            else:
                for k in range(n):
                    for l, v in zip(loads, vecs[k]):
                        mbs.SetLoadParameter(l, "loadVector", v)
            times.setdefault(key, []).append((time.perf_counter() - tic) / n)
    out = {v: float(np.median(x)) for v, x in times.items()}
    out.update(T=T, h=h, steps=n, repeats=repeats)
    out["setLoads"] = out["control"] - out["compute"]
    out["bridgeOwn"] = out["watched"] - out["exudynSet"]
    return out


def connector_models():
    """One Exudyn model with one item of every compiled connector type (a spinning body on
    each); returns (mbs, {connector type: object index})."""
    import exudyn as exu
    from exudyn.utilities import (InertiaCuboid, MarkerBodyRigid, MarkerNodeCoordinate, NodeGenericData,
                                  NodePointGround)
    U = exu.utilities
    mbs = exu.SystemContainer().AddSystem()
    g = mbs.CreateGround()
    mG = mbs.AddMarker(MarkerBodyRigid(bodyNumber=g, localPosition=[0.2, 0.0, 0.1]))
    out = {}

    def body(k):
        b = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.4, 0.2, 0.1]), referencePosition=[k, 0.1, 0.2],
                                initialAngularVelocity=[0.3, -0.2, 2.0])
        return b, mbs.AddMarker(MarkerBodyRigid(bodyNumber=b, localPosition=[0.05, 0.02, -0.03]))

    items = {
        "ConnectorSpringDamper": lambda b, m: U.ObjectConnectorSpringDamper(markerNumbers=[mG, m], stiffness=100),
        "ConnectorCartesianSpringDamper": lambda b, m: U.ObjectConnectorCartesianSpringDamper(
            markerNumbers=[mG, m], stiffness=[100, 100, 100]),
        "ConnectorTorsionalSpringDamper": lambda b, m: U.ObjectConnectorTorsionalSpringDamper(
            markerNumbers=[mG, m], stiffness=10, nodeNumber=mbs.AddNode(NodeGenericData(
                initialCoordinates=[0.0], numberOfDataCoordinates=1))),
        "ConnectorCoordinateSpringDamper": lambda b, m: U.ObjectConnectorCoordinateSpringDamper(markerNumbers=[
            mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0)),
            mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.GetObject(b)["nodeNumber"], coordinate=0))],
            stiffness=100),
        "ConnectorLinearSpringDamper": lambda b, m: U.ObjectConnectorLinearSpringDamper(markerNumbers=[mG, m],
                                                                                        stiffness=100),
        "ConnectorRigidBodySpringDamper": lambda b, m: U.ObjectConnectorRigidBodySpringDamper(
            markerNumbers=[mG, m], stiffness=np.eye(6), damping=np.zeros((6, 6))),
        "ConnectorRollingDiscPenalty": lambda b, m: U.ObjectConnectorRollingDiscPenalty(
            markerNumbers=[mG, m], discRadius=0.2, contactStiffness=1e4, nodeNumber=mbs.AddNode(NodeGenericData(
                initialCoordinates=[0.0, 0.0, 0.0], numberOfDataCoordinates=3))),
    }
    for k, (name, make) in enumerate(items.items()):
        out[name] = int(mbs.AddObject(make(*body(k))))
    mbs.Assemble()
    return mbs, out


def connector_rereads(calls=1000, repeats=5):
    """Time of one re-read of a changed connector during a solve (``ParameterWatch``: the
    reader reads it again, its force element's registration rewrites its compiled row), per
    compiled connector type; median of ``repeats`` rounds of ``calls`` re-reads, types
    interleaved in every round; seconds."""
    import exudyn_lie as exl
    from exudyn_lie.bridge.params import ParameterWatch
    mbs, objects = connector_models()
    solver = exl.LieGroupSolver(mbs)
    watch = ParameterWatch(solver)
    times = {name: [] for name in objects}
    for _ in range(repeats):
        for name, o in objects.items():
            tic = time.perf_counter()
            for _ in range(calls):
                watch._rebuild([("object", o)], 0.0)
            times[name].append((time.perf_counter() - tic) / calls)
    return {name: float(np.median(x)) for name, x in times.items()}


def report_lines(p):
    """The BENCHMARKS.md section (empty without the measurement)."""
    if not p:
        return []
    us = lambda x: f"{1e6 * x:.3g} us"   # noqa: E731
    return [
        "## 8. Parameters changed during a solve",
        "",
        f"Exudyn's serialRobotTest (6 links, 12 `LoadTorqueVector` joint torques set by a PD controller in a "
        f"pre-step function every step), `exl.SolveDynamic` MK-RK4, h = {p['h']:g} s, one Exudyn step per step in "
        f"every row; per step = (a run of {2 * p['steps']} steps - a run of {p['steps']} steps) / {p['steps']} (the "
        f"fixed cost of a solve cancels); medians of {p['repeats']} interleaved rounds.",
        "",
        "| variant | per step |",
        "|---|---|",
        f"| no pre-step function (constant loads) | {us(p['none'])} |",
        f"| pre-step function that returns True | {us(p['empty'])} |",
        f"| the PD law evaluated, no load set | {us(p['compute'])} |",
        f"| the PD controller: 12 load vectors set per step | {us(p['control'])} |",
        f"| 12 `SetLoadParameter` calls outside a solve (Exudyn's own cost) | {us(p['exudynSet'])} |",
        f"| the same calls recorded by the bridge's watch, and its re-read of the 12 loads | {us(p['watched'])} |",
        f"| Exudyn's generalized-alpha with the PD controller | {us(p['native'])} |",
        "",
        f"Setting the 12 loads costs {us(p['setLoads'])} per step in the solve (controller minus the PD law alone, "
        f"a difference of two noisy runs); the bridge's own part, measured directly (recording the calls, re-reading "
        f"the 12 loads, writing their compiled rows), is {us(p['bridgeOwn'])} per step, "
        f"{100 * p['bridgeOwn'] / p['control']:.1f} % of a controlled step; without any pre-step function the "
        f"same model costs {us(p['none'])} per step.",
        "",
    ] + ([f"A changed connector (a live field or one of its markers) is read again by the reader and its force "
          f"element's compiled row rewritten by its registration: "
          + ", ".join(f"`{name}` {us(x)}" for name, x in p["reread"].items()) + " per re-read.", ""]
         if p.get("reread") else [])
