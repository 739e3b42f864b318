"""Explicit Runge-Kutta-Munthe-Kaas integrators (appendix B of the paper, eq. MK1).

* :mod:`.tableau` -- frozen, self-checking Butcher tableaus and the method catalogue.
* :mod:`.stability` -- stability polynomial and radius of any tableau (from its coefficients).
* :mod:`.control` -- step-size control (error norm in the algebra, PI controller, HINIT).
* the Python reference MK steppers (clear, slow), against which tests check the compiled
  stepper (:mod:`exudyn_lie.mbs.stepper`, the one every solver path runs), are test oracles
  (``tests/reference_mk.py``, ``tests/reference_mk_adaptive.py``).
* the vector-space formulations (ODEvec1, ODEvec2) the paper compares with are a test oracle
  (``tests/vector_space_oracle.py``).
"""
from .. import _numba_cache  # noqa: F401  (first: the cache key of every compiled function)
from .tableau import (METHODS, ButcherTableau, achieved_order, get_method, method_names,
                      order_condition_residuals, quadrature_order, rooted_trees)

__all__ = [
    "METHODS", "ButcherTableau", "achieved_order", "get_method", "method_names",
    "order_condition_residuals", "quadrature_order", "rooted_trees",
]
