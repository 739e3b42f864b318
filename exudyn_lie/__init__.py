"""exudyn_lie: Munthe-Kaas Lie group integrators, explicit and implicit, for Exudyn multibody models.

Each rigid body is integrated on its own configuration-space Lie group, SE(3) (screw
update) or SO(3)xR3 (decoupled update), as analysed by Müller & Terze, *The
significance of the configuration space Lie group for the constraint satisfaction in
numerical time integration of multibody systems*.

Entry points
------------
* :func:`SolveDynamic` - drop-in solver for an Exudyn ``mbs`` (``exudyn_lie.bridge``);
* :class:`Scene` / :class:`Simulator` - the multibody kernel without Exudyn;
* :mod:`exudyn_lie.groups` - SO3, SE3, SO3xR3, quaternions, dual quaternions;
* :mod:`exudyn_lie.integrators` - Butcher tableaus and the MK stepper;
* :mod:`exudyn_lie.models` - the paper's mechanisms as Exudyn models;
* ``python -m exudyn_lie paper | bench | stress`` (:mod:`exudyn_lie.apps`, not loaded here).

Errors: :class:`SceneError` (bad input; :class:`BridgeError` for an Exudyn model, a
subclass), :class:`SimulationError` (a run failed) with :class:`ConstraintError` and
:class:`StepSizeError`.
"""
__version__ = "0.1.0"

# Nothing is imported here: ``import exudyn_lie`` costs no numpy, numba or Exudyn (a
# short start-up).  The names below load their module on first use; every subpackage with
# compiled code imports ``_numba_cache`` first (the cache key of every compiled function).
_LAZY = {
    "get_method": "integrators.tableau", "method_names": "integrators.tableau",
    **{n: "mbs" for n in ("GROUND", "ConstraintError", "Scene", "SceneError", "SimulationError", "Simulator",
                          "StepSizeError")},
    **{n: "bridge" for n in ("SolveDynamic", "GetSolveTiming", "LieGroupSolver", "SceneFromExudyn", "ExudynScene", "BridgeError")},
}

__all__ = ["__version__", *_LAZY]


def __getattr__(name):
    mod = _LAZY.get(name)
    if mod is None:
        raise AttributeError(f"module 'exudyn_lie' has no attribute {name!r}")
    from importlib import import_module
    value = getattr(import_module(f"{__name__}.{mod}"), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
