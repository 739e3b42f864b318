"""The stepper's form of a tableau: the method tuples :func:`~.stepper.mk_steps` is compiled for (one
specialisation per tuple type), built from the integrators' tableaus, and the configurations' own
coefficients (:func:`config_coefficients`: a partitioned method's, else ``A, b`` themselves)."""
from collections import namedtuple

import numpy as np
from numba import types
from numba.extending import overload

# An explicit tableau as the stepper uses it: A, b, c, the indices of the evaluated stages, the
# embedded weights (no rows without a pair), and Aq, bq, the coefficients that advance the
# configurations: A, b themselves (the same arrays) but for a partitioned tableau
# (integrators/partitioned.py: velocity Verlet, whose c are the configurations' cq).  One tuple type
# for both, so that velocity Verlet runs on the explicit methods' compiled time loop (a kind of its
# own cost 33-39 s of compilation) with the same arithmetic: a stage reads Aq[j, j] either way.
Method = namedtuple("Method", ["A", "b", "c", "stages", "bhat", "Aq", "bq"])

# A diagonally implicit tableau (ESDIRK) with its Newton iteration's arrays and state (mbs/implicit.py,
# which registers the implicit overloads of is_implicit and implicit_stage)
ImplicitMethod = namedtuple("ImplicitMethod", ["A", "b", "c", "stages", "bhat", "gamma", "newton"])


def needed_stages(A, b):
    """Indices of the stages that can influence a step: ``b_j != 0`` or used by a needed
    later stage (``a_lj != 0``).  Stage 0 is always evaluated (it is also the
    accelerations at the step's initial state, recorded at outputs)."""
    A = np.asarray(A, float)
    b = np.asarray(b, float)
    s = len(b)
    need = [bool(b[j] != 0.0) for j in range(s)]
    for j in range(s - 1, -1, -1):
        if not need[j]:
            need[j] = any(need[l] and A[l, j] != 0.0 for l in range(j + 1, s))
    need[0] = True
    return np.array([j for j in range(s) if need[j]], dtype=np.int64)


def method_arrays(tableau):
    """The :class:`Method` of an explicit :class:`~exudyn_lie.integrators.tableau.ButcherTableau`,
    partitioned or not."""
    A, b, c = tableau.arrays()
    bh = np.zeros(0) if tableau.b_hat is None else np.array(tableau.b_hat, dtype=np.float64)
    if tableau.partitioned:
        Aq, bq = np.array(tableau.Aq, dtype=np.float64), np.array(tableau.bq, dtype=np.float64)
        return Method(A=A, b=b, c=np.array(tableau.cq, dtype=np.float64),
                      stages=np.array(tableau.active_stages, dtype=np.int64), bhat=bh, Aq=Aq, bq=bq)
    return Method(A=A, b=b, c=c, stages=needed_stages(A, b), bhat=bh, Aq=A, bq=b)


def config_coefficients(tab):
    """``(Aq, bq)``: the coefficients that advance the configurations: a :class:`Method`'s fields, an
    implicit or adaptive method's own ``(A, b)`` (chosen at compile time by the tuple's fields)."""


@overload(config_coefficients, inline="always")
def _config_coefficients(tab):
    if isinstance(tab, types.BaseNamedTuple) and "Aq" in tab.instance_class._fields:
        return lambda tab: (tab.Aq, tab.bq)
    return lambda tab: (tab.A, tab.b)
