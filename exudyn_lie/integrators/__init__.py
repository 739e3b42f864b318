"""Explicit Runge-Kutta-Munthe-Kaas integrators (appendix B of the paper, eq. MK1).

* :mod:`.tableau` -- frozen, self-checking Butcher tableaus and the method catalogue.
* :mod:`.mk` -- the reference MK stepper on products of c-space groups (SE3 / SO3xR3).
* :mod:`.vector_space` -- the vector-space formulations (ODEvec1, ODEvec2) for comparison.
"""
from .tableau import (METHODS, ButcherTableau, achieved_order, get_method, method_names,
                      order_condition_residuals, quadrature_order, rooted_trees)
from .mk import (Trajectory, integrate, integrate_kinematic, mk_increment,
                 mk_increment_kinematic, mk_step, mk_step_kinematic, resolve_groups)
from . import vector_space

__all__ = [
    "METHODS", "ButcherTableau", "achieved_order", "get_method", "method_names",
    "order_condition_residuals", "quadrature_order", "rooted_trees",
    "Trajectory", "integrate", "integrate_kinematic", "mk_increment",
    "mk_increment_kinematic", "mk_step", "mk_step_kinematic", "resolve_groups",
    "vector_space",
]
