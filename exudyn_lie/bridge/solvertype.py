"""What ``exl.SolveDynamic`` does with Exudyn's ``solverType`` (argument or setting).

Exudyn 1.13.6's ``exudyn.SolveDynamic`` reads ``solverType`` from its argument, else from
``simulationSettings.timeIntegration.solverType`` (default GeneralizedAlpha): the argument
takes the place of the setting for the run.  The drop-in resolves the same effective type
and then:

* an explicit type is a Butcher tableau (Exudyn's ``CSolverExplicit.cpp``,
  ``ComputeButcherTableau``) and selects the same tableau of exudyn_lie's catalogue
  (:data:`EXPLICIT`); the Munthe-Kaas method with that tableau runs on the bodies' Lie
  groups.  With ``method=`` given as well, both must name the same tableau.  VelocityVerlet
  is the partitioned tableau of the same scheme (integrators/partitioned.py: Exudyn reuses the
  last stage's accelerations as the next step's first, this package evaluates them at the
  step's start; the same for forces of the configuration alone).
* GeneralizedAlpha (the default) is what the drop-in replaces by its explicit method, as
  without ``solverType``.
* TrapezoidalIndex2 names another implicit solver that the drop-in replaces just like
  generalized-alpha; a user who picked it chose specific properties (no numerical
  damping, index-2 constraints), so the run warns naming the method and groups that ran.
* the types without a counterpart (:data:`REFUSED`) raise :class:`BridgeError` before
  ``mbs`` is touched.
"""
from __future__ import annotations

import numpy as np

from ..integrators import tableau as T
from .reader import BridgeError

#: Exudyn's explicit solver types -> the catalogue tableau with the same coefficients
#: (tests/test_bridge_solvertype.py checks every coefficient against Exudyn's run)
EXPLICIT = {
    "ExplicitEuler": T.ExplicitEuler,
    "ExplicitMidpoint": T.ExplicitMidpoint,
    "RK33": T.RK33,
    "RK44": T.RK4,
    "RK67": T.RK67,
    "ODE23": T.BS3,
    "DOPRI5": T.DOPRI5,
    "VelocityVerlet": T.VelocityVerlet,
}

#: Exudyn's implicit solvers, replaced by the explicit Munthe-Kaas method
REPLACED = ("GeneralizedAlpha", "TrapezoidalIndex2")

#: types with no counterpart: why
REFUSED = {
    "DVERK6": "Exudyn 1.13.6's own SolveDynamic does not implement DVERK6 (NotImplementedFeatureError)",
}


def _type_name(solverType, where):
    import exudyn as exu
    if not isinstance(solverType, exu.DynamicSolverType):
        raise BridgeError(f"{where}={solverType!r} is not an exudyn.DynamicSolverType; pass e.g. "
                          f"exudyn.DynamicSolverType.RK44, or None")
    return solverType.name


def _same_tableau(a, b):
    return a.partitioned == b.partitioned and all(
        np.array_equal(x, y) for x, y in ((a.A, b.A), (a.b, b.b), (a.c, b.c),
                                          (getattr(a, "Aq", None), getattr(b, "Aq", None)),
                                          (getattr(a, "bq", None), getattr(b, "bq", None))))


def resolve_solver_type(solverType, settingsSolverType, method, check_method):
    """``(tableau or method name, name of the effective type, replaced)`` for SolveDynamic.

    ``method`` is the user's ``method=`` (None: not given; then the catalogue default RK4
    unless an explicit type selects the tableau); ``check_method`` turns a method into its
    tableau (raising BridgeError).  ``replaced`` is True when an implicit type other than
    the default is replaced (the caller warns).  Reads only."""
    if solverType is not None:
        name, where = _type_name(solverType, "solverType"), "solverType"
    else:
        name = _type_name(settingsSolverType, "simulationSettings.timeIntegration.solverType")
        where = "simulationSettings.timeIntegration.solverType"
    if name in REFUSED:
        raise BridgeError(f"{where}=DynamicSolverType.{name}: {REFUSED[name]}; pass an explicit type "
                          f"({', '.join(EXPLICIT)}) or method=... (one of {', '.join(T.method_names())}), or "
                          f"solve with exudyn.SolveDynamic")
    if name in EXPLICIT:
        tab = EXPLICIT[name]
        if method is not None and not _same_tableau(check_method(method), tab):
            given = check_method(method).name
            raise BridgeError(f"{where}=DynamicSolverType.{name} (the tableau {tab.name}) and method={given!r} "
                              f"name different integrators; pass one of them (or method={tab.name!r})")
        return (tab if method is None else method), name, False
    if name in REPLACED:
        return ("RK4" if method is None else method), name, name != "GeneralizedAlpha"
    raise BridgeError(f"{where}=DynamicSolverType.{name} is unknown to exudyn_lie; pass one of "
                      f"{', '.join([*EXPLICIT, *REPLACED])}")
