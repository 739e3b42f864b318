"""What ``exl.SolveDynamic`` does with each field of Exudyn's ``simulationSettings``.

The bridge runs Exudyn's own time loop (``MainSolverImplicitSecondOrder``: InitializeSolver,
SolveSteps, FinalizeSolver) on a copy of the settings whose Newton iteration is replaced by
the Munthe-Kaas step.  So everything the loop does around a step works as natively (outputs,
console, real time, pauses), and everything that tunes Exudyn's own step (Newton, the
linear solver, generalized-alpha, step-size control) has no object.  :data:`SETTINGS` gives
the status of every field by the longest matching prefix (a test walks every field of
``exu.SimulationSettings()``); :func:`check_settings` refuses what would be ignored silently
otherwise.
"""
from __future__ import annotations

from ..groups import canonical_name
from .params import IGNORED, LIVE, REFUSED
from .reader import BridgeError

HONOURED = LIVE

_STEP = "tunes Exudyn's own time step (Newton iteration, linear solver, step-size control), which exudyn_lie's " \
        "explicit fixed step replaces"
_LOOP = "done by Exudyn's own time loop, which the bridge runs"

#: (field prefix, status, reason); the longest matching prefix applies
SETTINGS = (
    ("timeIntegration.startTime", HONOURED, "start of the fixed steps"),
    ("timeIntegration.endTime", HONOURED, "end of the fixed steps"),
    ("timeIntegration.numberOfSteps", HONOURED, "the fixed step h = (endTime - startTime) / numberOfSteps"),
    ("timeIntegration.verboseMode", HONOURED, _LOOP + " (it counts output periods as steps)"),
    ("timeIntegration.verboseModeFile", HONOURED, _LOOP),
    ("timeIntegration.stepInformation", HONOURED, _LOOP),
    ("timeIntegration.realtime", HONOURED, _LOOP),
    ("timeIntegration.simulateInRealtime", HONOURED, _LOOP),
    ("timeIntegration.realtimeFactor", HONOURED, _LOOP),
    ("timeIntegration.realtimeWaitMicroseconds", HONOURED, _LOOP),
    # adaptive steps (docs/ADAPTIVE.md): with a method that has an embedded pair (DOPRI5, BS3 = ODE23, Vern6)
    ("timeIntegration.adaptiveStep", HONOURED, "True (Exudyn's default) with an embedded pair: adaptive steps with "
                                               "error control on the group; False, or a method without a pair: fixed "
                                               "steps"),
    ("timeIntegration.absoluteTolerance", HONOURED, "adaptive steps: atol of every SI quantity (rad, m, rad/s, m/s)"),
    ("timeIntegration.relativeTolerance", HONOURED, "adaptive steps: rtol"),
    ("timeIntegration.minimumStepSize", HONOURED, "adaptive steps: a step below it stops with StepSizeError "
     "(after the drop-in's own switch to ESDIRK3: accepted at it, docs/IMPLICIT.md)"),
    ("timeIntegration.initialStepSize", HONOURED, "adaptive steps: the first step if automaticStepSize and > 0"),
    ("timeIntegration.automaticStepSize", HONOURED, "adaptive steps: False starts at the largest step, as Exudyn; "
                                                    "True with initialStepSize = 0: Hairer's HINIT"),
    ("timeIntegration.stepSizeSafety", HONOURED, "adaptive steps: the PI controller's safety factor"),
    ("timeIntegration.stepSizeMaxIncrease", HONOURED, "adaptive steps: the largest growth of a step"),
    ("timeIntegration.solverType", HONOURED, "read as Exudyn reads it (when SolveDynamic's solverType is None): "
                                             "an explicit type selects its tableau, the implicit ones are replaced "
                                             "by method=...; see bridge/solvertype.py"),
    ("timeIntegration.discontinuous", IGNORED, "compiled path: the data coordinates of contacts (penalty rolling "
                                               "disc) are updated after every step from its end state, as Exudyn's "
                                               "PostNewton does, and no step is repeated (Exudyn's discontinuous "
                                               "iteration would repeat it with the updated data); the "
                                               "Exudyn-evaluated path runs Exudyn's own iteration and, with data "
                                               "coordinates, a PostNewtonUserFunction or a GeneralContact, its step "
                                               "reduction (adaptiveStep, useRecommendedStepSize, minimumStepSize)"),
    ("timeIntegration.reuseConstantMassMatrix", HONOURED, "Exudyn-evaluated path: True, a mass matrix that all "
                                                          "bodies declare constant is evaluated once, as Exudyn's "
                                                          "own solvers do; False: at every stage"),
    ("timeIntegration", IGNORED, _STEP),       # newton, generalizedAlpha, explicit, adaptive steps, tolerances
    ("solution.restart.continueIfAvailable", REFUSED, "True: exudyn_lie does not continue from a restart file"),
    ("solution", HONOURED, _LOOP + ": solution and restart files, sensors, their periods, image recording"),
    ("solutionSettings", HONOURED, _LOOP + " (deprecated names of solution.*)"),
    ("pauseAfterEachStep", HONOURED, _LOOP + " (one Exudyn step per step then)"),
    ("show", HONOURED, _LOOP + " (Exudyn's statistics of its loop)"),
    ("displayComputationTime", HONOURED, _LOOP),
    ("displayGlobalTimers", HONOURED, _LOOP),
    ("displayStatistics", HONOURED, _LOOP),
    ("consolePrecision", HONOURED, _LOOP),
    ("outputPrecision", HONOURED, _LOOP),
    ("cleanUpMemory", HONOURED, _LOOP),
    ("linearSolver", IGNORED, _STEP),
    ("linearSolverSettings", IGNORED, _STEP),
    ("linearSolverType", IGNORED, _STEP),
    ("parallel", IGNORED, "threads of Exudyn's own Newton iteration; exudyn_lie's kernel runs in one thread"),
    ("staticSolver", IGNORED, "used by Exudyn's static solver only"),
)


# the kernel's step-size limits by their Exudyn settings (StepSizeError.setting)
EXUDYN_SETTING_OF = {"minimumStep": "timeIntegration.minimumStepSize"}


def name_exudyn_setting(e):
    """``e`` with the Exudyn setting behind its limit added to its message (a StepSizeError of
    the kernel names its own limit, e.g. the minimum step size, not Exudyn's setting)."""
    name = EXUDYN_SETTING_OF.get(getattr(e, "setting", None))
    if name is not None and e.args and name not in str(e.args[0]):
        e.args = (f"{e.args[0]} (Exudyn: {name})",) + tuple(e.args[1:])
    return e


def setting_status(path):
    """``(status, reason)`` of a settings field (dotted path), or None if not covered."""
    best = None
    for prefix, status, why in SETTINGS:
        if path == prefix or path.startswith(prefix + "."):
            if best is None or len(prefix) > len(best[0]):
                best = (prefix, status, why)
    return None if best is None else best[1:]


def check_settings(ss):
    """Refuse settings that exudyn_lie would otherwise ignore silently (reads only)."""
    if ss.solution.restart.continueIfAvailable:
        raise BridgeError("simulationSettings.solution.restart.continueIfAvailable = True: exudyn_lie does not "
                          "continue from a restart file (its state would be overwritten by the initial values); "
                          "set it to False, or continue with exudyn.SolveDynamic")


def positive_float(value, error):
    """``value`` as a finite positive float (a keyword of ``exl.SolveDynamic``), else raise
    ``error`` (the keyword's own message, already formatted)."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        v = float("nan")
    if not (v > 0.0 and v < float("inf")):
        raise error
    return v


def group_name(g, what):
    """A body group the user may name (``groups.canonical_name``): 'SE3', 'SO3xR3' or 'auto'."""
    key = canonical_name(g)
    if key in ("SE3", "SO3xR3", "auto"):
        return key
    raise BridgeError(f"{what}: unknown Lie group {g!r}; use 'SE3', 'SO3xR3' or 'auto' (or a mapping "
                      f"{{rigid-body object index: 'SE3' | 'SO3xR3'}})")


def liegroup_argument(liegroup):
    """``SolveDynamic``'s ``liegroup`` checked: a group name, or ``{object index: group}``
    without its 'auto' entries (the same rule on both paths)."""
    if isinstance(liegroup, str):
        return group_name(liegroup, "liegroup")
    if isinstance(liegroup, dict):
        out = {}
        for k, v in liegroup.items():
            try:
                key = int(k)
            except (TypeError, ValueError):
                raise BridgeError(f"liegroup mapping key {k!r} is not an Exudyn object index") from None
            g = group_name(v, f"liegroup[{key}]")
            if g != "auto":
                out[key] = g
        return out
    raise BridgeError(f"liegroup must be 'SE3', 'SO3xR3', 'auto' or a mapping {{object index: group}}, "
                      f"got {type(liegroup).__name__}")
