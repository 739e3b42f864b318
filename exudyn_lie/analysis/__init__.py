"""Measures, runs, claims, figures and the report of ``python -m exudyn_lie paper``.

* :mod:`.geometry` - joint violations (Exudyn's joint rows re-implemented on stored
  states), orientation error eps_r = ||log(R^T R_num)||, COM positions;
* :mod:`.energy`   - kinetic / gravity / spring energy from states;
* :mod:`.runs`     - MK-RK4 runs through the Exudyn bridge and Exudyn's native runs,
  reduced to :class:`.runs.RunData`;
* :mod:`.claims`   - the paper's claims judged on the runs (:func:`.claims.judge`);
* :mod:`.plots`    - the figures (SE3 beside SO3xR3);
* :mod:`.report`   - REPRODUCTION.md with its content hash.
"""
from .energy import energies
from .geometry import (com_positions, joint_rows, joint_velocity_violations, joint_violations,
                       orientation_error, so3_log_angle)

__all__ = ["energies", "com_positions", "joint_rows", "joint_violations", "joint_velocity_violations",
           "orientation_error", "so3_log_angle"]
