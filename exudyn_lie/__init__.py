"""exudyn_lie: explicit Munthe-Kaas Lie group integrators for Exudyn multibody models.

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

from . import _numba_cache  # noqa: E402,F401  (first: the cache key of every compiled function)

from .integrators.tableau import get_method, method_names  # noqa: E402
from .mbs import (GROUND, ConstraintError, Scene, SceneError, SimulationError,  # noqa: E402
                  Simulator, StepSizeError)


# the Exudyn bridge imports exudyn; it is loaded on first use of one of these names
_BRIDGE_NAMES = ("SolveDynamic", "LieGroupSolver", "SceneFromExudyn", "ExudynScene", "BridgeError")

__all__ = ["__version__", "get_method", "method_names", "GROUND", "Scene", "Simulator", "SceneError",
           "SimulationError", "ConstraintError", "StepSizeError", *_BRIDGE_NAMES]


def __getattr__(name):
    if name in _BRIDGE_NAMES:
        from . import bridge
        return getattr(bridge, name)
    raise AttributeError(f"module 'exudyn_lie' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))
