"""The constrained rigid multibody kernel (paper eqs. BH2, index1, ODE2).

* :mod:`.scene`     - bodies, joints, forces in plain Python (:class:`Scene`);
* :mod:`.compiled`  - the scene flattened into arrays for numba;
* :mod:`.kernel`    - compiled stage right-hand side and Munthe-Kaas time loop;
* :mod:`.linalg`    - band / pivoted Cholesky for the index-1 solve;
* :mod:`.simulator` - compile once, run many (:class:`Simulator`).
"""
from .scene import GROUND, JOINT_TYPES, Scene, SceneError, frame_with_axis
from .simulator import (ConstraintError, Result, SimulationError, Simulator, StepSizeError)

__all__ = ["GROUND", "JOINT_TYPES", "Scene", "SceneError", "frame_with_axis", "Simulator",
           "Result", "SimulationError", "ConstraintError", "StepSizeError"]
