"""``GeneralContact`` on the Exudyn-evaluated path: the contact law of Exudyn's explicit solvers.

Exudyn's ``GeneralContact`` (``System/CContact.cpp``) evaluates one of two laws, chosen by the
system's ``SolverData.doPostNewtonIteration``:

* **active sets** (``true``, set by every solver's initialisation): ``ComputeODE2RHS`` applies the
  contacts found at the last ``PostNewtonStep`` only, *even where they have separated since*
  (``CContact.cpp``: "in active set strategy, we always compute the contact, even if there is
  separation"), with the friction regime (sticking or sliding) frozen there; the implicit solvers'
  discontinuous iteration then repeats a step whose active set changed.  This is the law of the
  interface the evaluated path drives (``MainSolverImplicitSecondOrder``).
* **full search** (``false``, set by ``CSolverExplicitTimeInt::PostInitializeSolverSpecific``):
  every ``ComputeODE2RHS`` searches the contacts at the state it is given and applies those with
  a negative gap; ``PostNewtonStep`` does nothing.

The Munthe-Kaas stages evaluate the right-hand side at states inside the step, so the active-set
law applied the contacts of the step's start to all of them: a ball leaving a sphere was pulled
back for the rest of the step, and the result differed from generalized-alpha at a fine step by
an amount that did not shrink with h (5.2e-4 for a ball on a sphere at h = 1e-4 and 2.5e-5, the
trial that kept GeneralContact refused until now); with the full search the bouncing ball of
``tests/test_general_contact.py`` is Exudyn's RK44 run at the same step.  Exudyn 1.13.6 has no
setter for the flag; an explicit solver's initialisation on the same system is the one way to
clear it, so :func:`use_full_search` runs one after the implicit solver's (which set it), with
settings that write, store and warn nothing.  It sets the current accelerations, ODE1 rates and multipliers to zero, which the
evaluated path computes and writes afterwards anyway.  The next solver that Exudyn initialises
on this system sets the flag again.
"""
from __future__ import annotations

import contextlib
import io


def general_contacts(mbs):
    """The number of ``GeneralContact`` objects of ``mbs``."""
    return int(mbs.NumberOfGeneralContacts())


def use_full_search(mbs, t0, tEnd):
    """Make ``mbs``'s GeneralContacts evaluate the full contact search at every ``ComputeODE2RHS``
    (module docstring); returns the explicit solver object (kept alive for the run).  Call after
    the implicit solver's ``InitializeSolver``, before the state and accelerations are written."""
    import exudyn as exu
    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.solverType = exu.DynamicSolverType.RK44
    ti.startTime = float(t0)
    ti.endTime = float(tEnd) if tEnd > t0 else float(t0) + 1.0
    ti.numberOfSteps = 1
    ti.verboseMode = 0
    ti.explicit.eliminateConstraints = False      # models with joints: no error, only the warning
    ti.explicit.useLieGroupIntegration = False    # below, which is swallowed
    ti.reuseConstantMassMatrix = False            # (no mass matrix computed for nothing)
    s.solution.file.write = False
    s.solution.file.writeInitialValues = False
    s.solution.sensors.active = False
    s.show.computationTime = False
    s.show.statistics = False
    explicit = exu.MainSolverExplicit()
    with contextlib.redirect_stdout(io.StringIO()):
        # Exudyn prints "explicit INTEGRATOR WILL IGNORE CONSTRAINTS" for a model with joints: about
        # a run that does not take place
        ok = explicit.InitializeSolver(mbs, s)
    if ok is False:
        from .reader import BridgeError
        raise BridgeError(f"GeneralContact: Exudyn's explicit solver could not be initialised to select the "
                          f"contact law of its explicit solvers: {explicit.GetErrorString()}")
    return explicit
