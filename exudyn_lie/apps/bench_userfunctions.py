"""Python user functions in ``python -m exudyn_lie bench --sections userfunctions``.

The heavy top (:mod:`exudyn_lie.models.heavy_top`) integrated with MK-RK4 on SE(3) by the
compiled stepper (``Simulator.Advance``), three ways, interleaved inside every repetition:

* ``compiled``: the model as it is (no Python in the step);
* ``zero load``: plus a ``LoadTorqueVector`` whose ``loadVectorUserFunction`` returns zeros;
* ``PD torque``: plus a ``TorsionalSpringDamper`` between the ground and the top whose
  ``springTorqueUserFunction`` is a PD controller of the spin angle about the body's z axis
  tracking a ramp: ``tau = kp (phi - w_ref t) + kd (phidot - w_ref)`` with a saturation
  (a controller as Exudyn's examples write it: scalar arithmetic on the arguments);
* ``spring force``: plus a ``SpringDamper`` between a ground point and a point of the top
  whose ``springForceUserFunction`` is a hardening spring with damping
  (``f = k u (1 + (u / u0)^2) + d udot + f0``);
* ``force``: plus a ``LoadForceVector`` at a point of the top (off its frame origin) whose
  ``loadVectorUserFunction`` is a rotating force of growing amplitude.

Each user function is called once per evaluated stage (4 per RK4 step) from the compiled
stage through ``mbs/external.py`` (one call through the C API per stage, no array boxed);
the torsional spring's angle and rate come from the compiled stage (``mbs/external_probes.py``).
Reported: the cost per step of each, the user function's own cost per call (the same Python
function called on its own with the same arguments, ``timeit``), and the **overhead per
call** = (step with the user function - compiled step - calls x own cost) / calls.
Target: overhead <= 2 us per call.  Times are the thread's CPU time
(``time.thread_time``: the stepper and the user functions run in the calling thread), medians
of the interleaved repetitions; on a machine shared with other jobs the wall clock also
counts the time the scheduler gives to others, which CPU time leaves out.
"""
from __future__ import annotations

import math
import time
import timeit
import warnings

import numpy as np

TARGET_OVERHEAD_US = 2.0
CLOCK = time.thread_time
H = 1e-4
KINDS = ("compiled", "zero", "pd", "spring", "force")
TITLES = {"compiled": "compiled", "zero": "zero user load", "pd": "PD torque",
          "spring": "spring force", "force": "force at a point"}
KP, KD, WREF, TAU_MAX = 50.0, 5.0, 0.5, 20.0
U0 = 0.1


def zero_load(mbs, t, loadVector):
    return [0.0, 0.0, 0.0]


def pd_torque(mbs, t, itemNumber, rotation, angularVelocity, stiffness, damping, offset):
    """PD control of the spin angle to the ramp ``WREF t``, saturated at ``TAU_MAX``."""
    tau = KP * (rotation - WREF * t) + KD * (angularVelocity - WREF)
    return max(-TAU_MAX, min(TAU_MAX, tau))


def rotating_force(mbs, t, loadVector):
    """A force turning about the vertical, its amplitude growing with t."""
    a = loadVector[0] * (1.0 + t)
    return [a * math.cos(3.0 * t), a * math.sin(3.0 * t), 0.0]


def spring_force(mbs, t, itemNumber, deltaL, deltaL_t, stiffness, damping, force):
    """A hardening spring with damping."""
    return stiffness * deltaL * (1.0 + (deltaL / U0) ** 2) + damping * deltaL_t + force


def build(kind):
    """The heavy top with the user function ``kind`` ('compiled', 'zero', 'pd', 'spring'), assembled."""
    import exudyn as exu
    from exudyn_lie import models
    mbs, info = models.build("heavy_top")
    body = info.bodies[0].objectIndex
    if kind == "zero":
        mk = mbs.AddMarker(exu.itemInterface.MarkerBodyRigid(bodyNumber=body, localPosition=[0, 0, 0]))
        mbs.AddLoad(exu.itemInterface.LoadTorqueVector(markerNumber=mk, loadVector=[0, 0, 0],
                                                       loadVectorUserFunction=zero_load))
    elif kind == "pd":
        mG = mbs.AddMarker(exu.itemInterface.MarkerBodyRigid(bodyNumber=info.ground, localPosition=[0, 0, 0]))
        mB = mbs.AddMarker(exu.itemInterface.MarkerBodyRigid(bodyNumber=body, localPosition=[0, 0, 0]))
        mbs.AddObject(exu.itemInterface.TorsionalSpringDamper(markerNumbers=[mG, mB], stiffness=KP, damping=KD,
                                                              springTorqueUserFunction=pd_torque))
    elif kind == "force":
        mB = mbs.AddMarker(exu.itemInterface.MarkerBodyRigid(bodyNumber=body, localPosition=[0.02, 0.0, 0.2]))
        mbs.AddLoad(exu.itemInterface.LoadForceVector(markerNumber=mB, loadVector=[0.5, 0, 0],
                                                      loadVectorUserFunction=rotating_force))
    elif kind == "spring":
        mG = mbs.AddMarker(exu.itemInterface.MarkerBodyPosition(bodyNumber=info.ground, localPosition=[0.3, 0.2, 1.5]))
        mB = mbs.AddMarker(exu.itemInterface.MarkerBodyPosition(bodyNumber=body, localPosition=[0.0, 0.0, 0.2]))
        mbs.AddObject(exu.itemInterface.SpringDamper(markerNumbers=[mG, mB], stiffness=5.0, damping=0.1,
                                                     referenceLength=1.0, force=0.5,
                                                     springForceUserFunction=spring_force))
    mbs.Assemble()
    return mbs


def simulator(mbs):
    from ..bridge import SceneFromExudyn
    from ..mbs import Simulator
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Simulator(SceneFromExudyn(mbs), "RK4", "SE3")


def own_cost_us(kind, n=20000):
    """The user function's own cost per call [us] (timeit, best of 5)."""
    if kind == "zero":
        f = lambda: zero_load(None, 0.1, [0.0, 0.0, 0.0])           # noqa: E731
    elif kind == "pd":
        f = lambda: pd_torque(None, 0.1, 3, 0.01, 0.4, KP, KD, 0.0)  # noqa: E731
    elif kind == "force":
        f = lambda: rotating_force(None, 0.1, [0.5, 0.0, 0.0])      # noqa: E731
    else:
        f = lambda: spring_force(None, 0.1, 3, 0.01, 0.4, 5.0, 0.1, 0.5)  # noqa: E731
    return min(timeit.repeat(f, number=n, repeat=5, timer=CLOCK)) / n * 1e6


def measure(steps=2000, repeat=7):
    """Per-step cost [us] (medians of ``repeat`` interleaved repetitions) and the overhead per
    user-function call."""
    sims = {k: simulator(build(k)) for k in KINDS}
    for s in sims.values():                 # compile / load, warm up
        s.SetInitialState()
        s.Advance(20, H)
    calls = len(sims["zero"].method.stages)
    times = {k: [] for k in sims}
    for _ in range(repeat):
        for k, s in sims.items():
            s.SetInitialState()
            t0 = CLOCK()
            s.Advance(steps, H)
            times[k].append((CLOCK() - t0) / steps * 1e6)
    us = {k: float(np.median(v)) for k, v in times.items()}
    res = dict(h=H, steps=steps, repeat=repeat, callsPerStep=calls, us=us, min={k: float(min(v)) for k, v in times.items()})
    for k in KINDS[1:]:
        own = own_cost_us(k)
        res[k] = dict(own=own, overhead=(us[k] - us["compiled"] - calls * own) / calls)
    return res


def run_section(cfg, log):
    from .bench import loadavg
    res = measure(steps=500 if cfg.quick else 2000, repeat=3 if cfg.quick else 7)
    res["load"] = loadavg()
    log(f"user functions (heavy top, RK4, h = {H:g}): compiled {res['us']['compiled']:.3g} us/step, "
        + ", ".join(f"{TITLES[k]} {res['us'][k]:.3g} (overhead {res[k]['overhead']:.3g} us/call)"
                    for k in KINDS[1:] if k in res))
    return res


def target_lines(res):
    if not res:
        return []
    L = []
    for k, title in (("zero", "zero user load"), ("pd", "PD-controller torque (springTorqueUserFunction)"),
                     ("spring", "spring force (springForceUserFunction)"),
                     ("force", "force at a point (loadVectorUserFunction)")):
        if k not in res:
            continue
        d = res[k]
        L.append(f"| Python user functions: heavy top with a {title}: step <= compiled step + user function's own cost + "
                 f"{TARGET_OVERHEAD_US:g} us per call | {res['us'][k]:.3g} us/step vs compiled "
                 f"{res['us']['compiled']:.3g}, own {d['own']:.2g} us x {res['callsPerStep']}: overhead "
                 f"{d['overhead']:.2g} us/call | {'yes' if d['overhead'] <= TARGET_OVERHEAD_US else 'no'} |")
    return L


def report_lines(res):
    L = ["## Python user functions", "",
         f"Heavy top, MK-RK4 SE3, h = {res['h']:g}, {res['steps']} steps, median of {res['repeat']} interleaved "
         f"repetitions, CPU time of the thread (load average {res.get('load', '?')}).", "",
         "| variant | us per step (median) | min | user function's own cost per call | overhead per call |",
         "|---|---|---|---|---|"]
    for k, title in TITLES.items():
        if k not in res["us"]:
            continue
        own = f"{res[k]['own']:.2g} us" if k in res else "-"
        ov = f"{res[k]['overhead']:.2g} us" if k in res else "-"
        L.append(f"| {title} | {res['us'][k]:.3g} | {res['min'][k]:.3g} | {own} | {ov} |")
    return L + [""]


if __name__ == "__main__":
    import json
    print(json.dumps(measure(), indent=1))
