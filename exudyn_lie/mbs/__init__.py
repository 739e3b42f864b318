"""The constrained rigid multibody kernel (paper eqs. BH2, index1, ODE2).

* :mod:`.scene`     - bodies, joints, forces in plain Python (:class:`Scene`);
* :mod:`.compiled`  - the scene flattened into arrays for numba;
* compiled, one job per module: :mod:`.codes`, :mod:`.bodies` (group dispatch),
  :mod:`.forces`, :mod:`.constraints`, :mod:`.index1` (solve and stage rhs),
  :mod:`.projection`, :mod:`.stepper` (the Munthe-Kaas stepper), :mod:`.diagnostics`;
  :mod:`.kernel` re-exports their public names;
* :mod:`.linalg`    - band / pivoted Cholesky for the index-1 solve;
* :mod:`.external`  - right-hand sides evaluated in Python, called from the stepper;
* :mod:`.simulator` - compile once, run many (:class:`Simulator`).

See ``docs/ARCHITECTURE.md``.
"""
from .. import _numba_cache  # noqa: F401  (first: the cache key of every compiled function)
from .scene import GROUND, JOINT_TYPES, AngleCoordinate, RotationParameterCoordinate, Scene, SceneError, frame_with_axis
from .simulator import (ConstraintError, Result, SimulationError, Simulator, StepSizeError)

__all__ = ["GROUND", "JOINT_TYPES", "AngleCoordinate", "RotationParameterCoordinate", "Scene", "SceneError", "frame_with_axis", "Simulator",
           "Result", "SimulationError", "ConstraintError", "StepSizeError"]
