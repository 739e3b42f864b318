"""How a ``SolveDynamic`` run is laid out on Exudyn's time loop, from the simulation settings
(the same rules on both paths): the step size, the integration steps per Exudyn step, whether
accelerations and multipliers must be written, and the adaptive step control.

Sub-stepping: one Exudyn step is one *output period*; the hook integrates ``k`` steps of size
``h = (endTime - startTime) / numberOfSteps`` inside it.  ``k`` is the largest common divisor
of the number of steps and of every active output period (solution file, sensors, restart
file, image recording) measured in steps, so outputs happen at exactly the times of a native
solve.  With a pre- or post-step user function ``k = 1`` (they are called every step, as
natively).  ``substeps=`` overrides the choice.
"""
from __future__ import annotations

import math

import numpy as np

from .reader import BridgeError
from .settings import check_settings

MAX_SUBSTEPS = 1000          # at most this many internal steps per Exudyn step (progress, renderer)


def time_settings(ss):
    """(numberOfSteps, startTime, endTime, step size) of the settings, checked."""
    ti = ss.timeIntegration
    nsteps = int(ti.numberOfSteps)
    t0, tEnd = float(ti.startTime), float(ti.endTime)
    if nsteps < 1 or not (np.isfinite(t0) and np.isfinite(tEnd)) or tEnd <= t0:
        raise BridgeError(f"timeIntegration: need numberOfSteps >= 1 and endTime > startTime, got "
                          f"numberOfSteps={ti.numberOfSteps}, startTime={t0}, endTime={tEnd}")
    return nsteps, t0, tEnd, (tEnd - t0) / nsteps


def period_steps(period, h):
    """Output period in steps: an integer >= 1, or 1 if it is not a multiple of h."""
    if period <= 0:
        return 1
    n = period / h
    k = int(round(n))
    if k < 1 or abs(n - k) > 1e-9 * max(1.0, n):
        return 1
    return k


def plan_substeps(mbs, ss, nsteps, h, substeps):
    """``(k, userStep)``: integration steps per Exudyn step (module docstring) and whether a
    pre- or post-step user function runs (then one Exudyn step per step: user step functions
    run, and Exudyn pauses, after every step)."""
    check_settings(ss)
    userStep = bool(mbs.GetPreStepUserFunction()) or bool(mbs.GetPostStepUserFunction())
    if substeps is not None:
        k = int(substeps)
        if k < 1 or nsteps % k:
            raise BridgeError(f"substeps={substeps} must be a positive divisor of numberOfSteps={nsteps}")
        return k, userStep
    if userStep or ss.pauseAfterEachStep:
        return 1, userStep
    sol = ss.solution
    k = nsteps
    if sol.file.write:
        k = math.gcd(k, period_steps(sol.file.writePeriod, h))
    if sol.sensors.active and mbs.systemData.NumberOfSensors() > 0:
        k = math.gcd(k, period_steps(sol.sensors.writePeriod, h))
    if sol.restart.write:
        k = math.gcd(k, period_steps(sol.restart.writePeriod, h))
    if sol.recordImagesInterval > 0:
        k = math.gcd(k, period_steps(sol.recordImagesInterval, h))
    if k > MAX_SUBSTEPS:
        k = max(d for d in range(1, MAX_SUBSTEPS + 1) if k % d == 0)
    return k, userStep


def needs_accelerations(mbs, ss, userStep, multiplierObjects=None):
    """True if something can read the accelerations or the multipliers: a user step function,
    the solution file's export of them, the restart file (it stores ODE2_tt and the AE
    coordinates), an acceleration or user-function sensor, or a sensor of an object in
    ``multiplierObjects`` (None: any object, whose outputs may read the multipliers)."""
    if userStep:
        return True
    exp = ss.solution.file.export
    if ss.solution.file.write and (exp.accelerations or exp.algebraicCoordinates):
        return True
    if ss.solution.restart.write:
        return True
    if ss.solution.sensors.active:
        for s in range(mbs.systemData.NumberOfSensors()):
            d = mbs.GetSensor(s)
            st = d.get("sensorType", "")
            if st == "UserFunction" or "Acceleration" in str(d.get("outputVariableType", "")):
                return True
            if st == "Object" and (multiplierObjects is None or int(d.get("objectNumber", -1)) in multiplierObjects):
                return True
    return False


def adaptive_settings(tableau, ss, h, constraintTolerance=None):
    """Keywords of :meth:`Simulator.SetAdaptive <exudyn_lie.mbs.Simulator.SetAdaptive>` from
    Exudyn's settings, or None for fixed steps (docs/ADAPTIVE.md).  Adaptive: a method with an
    embedded pair and ``timeIntegration.adaptiveStep`` (Exudyn's default True); tolerances
    ``absoluteTolerance`` / ``relativeTolerance`` (with L = 1 m, T = 1 s: every SI quantity, as
    Exudyn applies them to every coordinate); the largest step ``(endTime - startTime) /
    numberOfSteps`` (Exudyn: CSolverBase.cpp, no maximumStepSize); ``minimumStepSize``; the
    first step ``initialStepSize`` if ``automaticStepSize`` and it is > 0, h_max without
    ``automaticStepSize`` (as Exudyn), else Hairer's HINIT (Exudyn starts at h_max and rejects
    its way down); the PI controller with Exudyn's ``stepSizeSafety`` and
    ``stepSizeMaxIncrease``."""
    ti = ss.timeIntegration
    if tableau.b_hat is None or not ti.adaptiveStep:
        if constraintTolerance is not None:
            raise BridgeError(f"constraintTolerance needs adaptive steps: a method with an embedded pair "
                              f"(DOPRI5, ODE23, Vern6; here {tableau.name}) and timeIntegration.adaptiveStep "
                              f"= True (here {ti.adaptiveStep}); fixed steps project with stabilization="
                              f"'position' or 'velocity'")
        return None
    atol, rtol = float(ti.absoluteTolerance), float(ti.relativeTolerance)
    hmin, h0 = float(ti.minimumStepSize), float(ti.initialStepSize)
    safety, inc = float(ti.stepSizeSafety), float(ti.stepSizeMaxIncrease)
    bad = [f"{name} = {v}" for name, v, ok in (
        ("absoluteTolerance", atol, atol > 0), ("relativeTolerance", rtol, rtol >= 0),
        ("minimumStepSize", hmin, 0 <= hmin < h), ("initialStepSize", h0, h0 >= 0),
        ("stepSizeSafety", safety, 0 < safety <= 1), ("stepSizeMaxIncrease", inc, inc > 1)) if not ok]
    if bad:
        raise BridgeError(f"timeIntegration: {', '.join(bad)} cannot control adaptive steps (need "
                          f"absoluteTolerance > 0, relativeTolerance >= 0, 0 <= minimumStepSize < (endTime - "
                          f"startTime) / numberOfSteps = {h:g}, initialStepSize >= 0, 0 < stepSizeSafety <= 1, "
                          f"stepSizeMaxIncrease > 1); or set timeIntegration.adaptiveStep = False for fixed steps")
    if not ti.automaticStepSize:
        first = h
    elif h0 > 0:
        first = min(h0, h)
    else:
        first = None
    return dict(rtol=rtol, atol=atol, maxStep=h, minStep=hmin, firstStep=first, safety=safety,
                maxIncrease=inc, constraintTolerance=constraintTolerance)
