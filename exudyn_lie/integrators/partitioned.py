"""Partitioned explicit methods: the configurations and the velocities advanced with their own
coefficients (velocity Verlet), frozen and self-checking like :class:`~.butcher.ButcherTableau`.

A :class:`PartitionedTableau` is a :class:`ButcherTableau` whose ``(A, b)`` advance the velocities
(and the first-order coordinates), ``V_j = V + h sum_l a_jl Vdot_l``, ``V+ = V + h sum_j b_j Vdot_j``,
while the configurations have coefficients of their own::

    Psi_j = h (sum_{l<j} aq_jl k_l + aq_jj V_j),   g+ = g exp(h sum_j bq_j k_j)

A diagonal ``aq_jj`` lets a stage's configuration follow that stage's own velocity; it is allowed
only in a row with no other entry, where ``Psi_j = h aq_jj V_j`` is parallel to ``V_j`` and
``k_j = dexp^-1_{-Psi_j} V_j = V_j`` exactly (so the stage is explicit).  ``c`` (the base
tableau's) holds the row sums of ``A``, as Butcher's conditions of the first-order part need;
``cq``, the row sums of ``Aq``, are the times at which the stages are evaluated.

Checked on construction (the conditions below to 1e-14, in rational arithmetic for exact
coefficients): the triangular forms above, a first stage at the step's start, ``sum b = sum bq = 1``,
and the order-2 conditions of second-order equations ``Vdot = F(t, g)``:
``sum_j b_j cq_j = 1/2`` (the velocity) and ``sum_j bq_j c_j = 1/2`` (the configuration, through
the stage velocities).  The first-order part ``(A, b)`` carries Butcher's conditions of its own
``order`` (of the velocity-dependent forces and the first-order coordinates).

Exudyn's velocity Verlet (``CSolverExplicit.cpp``; Swope et al. 1982) as such a method: the half
kick ``V_2 = V + h/2 Vdot_1``, the drift ``g exp(h V_2)`` and the second half kick with
``Vdot_2 = F(t + h, g exp(h V_2), V_2)``.  It is symplectic where ``Vdot`` depends on the
configuration alone, of order 2 there and of order 1 where it depends on the velocity (the second
stage reads the half-step velocity).  Velocity-dependent are dampers, but also a rigid body's
gyroscopic term unless its inertia is isotropic (and, on SE(3), the coupling of the body-frame
twist).  Exudyn reuses the last stage's ``Vdot`` as the next step's first (one evaluation per
step); here each step evaluates its first stage at its own start (two per step): the same scheme
where ``Vdot`` depends on the configuration alone.
"""
import functools
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Tuple

import numpy as np

from .butcher import ButcherTableau, _readonly, _to_exact


@dataclass(frozen=True, eq=False)
class PartitionedTableau(ButcherTableau):
    """A partitioned explicit method (module docstring): ``A, b, c, order`` of the velocities'
    (first-order) part, ``Aq, bq`` of the configurations, ``order2`` for second-order equations
    whose forces depend on the configuration alone."""

    Aq: np.ndarray = None
    bq: np.ndarray = None
    order2: int = 2
    cq: np.ndarray = field(default=None, init=False)

    def __post_init__(self):
        super().__post_init__()
        name = self.name

        def fail(msg):
            raise ValueError(f"partitioned tableau '{name}': {msg}")

        s = len(self.b)
        if self.Aq is None or self.bq is None:
            fail("Aq and bq (the configurations' coefficients) are required")
        try:
            Aq = [[_to_exact(x) for x in row] for row in self.Aq]
            bq = [_to_exact(x) for x in self.bq]
        except (TypeError, ValueError, ZeroDivisionError) as exc:
            fail(f"configuration coefficients are not numbers ({exc})")
        if len(Aq) != s or any(len(row) != s for row in Aq) or len(bq) != s:
            fail(f"Aq must be {s}x{s} and bq have {s} entries")
        if any(x != 0 for x in Aq[0]):       # (row 1 of A: zero for any explicit tableau)
            fail("the first stage must be the step's start (row 1 of Aq zero)")
        for j in range(s):
            if any(Aq[j][l] != 0 for l in range(j + 1, s)):
                fail(f"Aq row {j + 1} is not lower triangular")
            if Aq[j][j] != 0 and any(Aq[j][l] != 0 for l in range(j)):
                fail(f"Aq row {j + 1}: a diagonal entry needs the rest of the row zero (the stage's "
                     f"configuration then follows its own velocity, explicitly)")
        ex = self._exact_coeffs
        A = ex[0] if ex is not None else [[Fraction(float(x)) for x in row] for row in self.A]
        b = ex[1] if ex is not None else [Fraction(float(x)) for x in self.b]
        c = [sum(row, Fraction(0)) for row in A]
        cq = [sum(row, Fraction(0)) for row in Aq]

        def close(x, y):
            return abs(float(x) - float(y)) <= 1e-14 * max(1.0, abs(float(y)))

        if not close(sum(bq, Fraction(0)), 1):
            fail(f"consistency sum(bq) = 1 violated: {float(sum(bq, Fraction(0)))!r}")
        if self.order2 >= 2:
            conds = (("sum_j b_j cq_j", sum((b[j] * cq[j] for j in range(s)), Fraction(0))),
                     ("sum_j bq_j c_j", sum((bq[j] * c[j] for j in range(s)), Fraction(0))))
            for what, val in conds:
                if not close(val, Fraction(1, 2)):
                    fail(f"order-2 condition of second-order equations violated: {what} = {float(val)!r}, "
                         f"not 1/2")
        if self.order2 > 2:
            fail("order conditions of partitioned methods are checked up to order 2 only")
        set_ = object.__setattr__
        set_(self, "Aq", _readonly([[float(x) for x in row] for row in Aq]))
        set_(self, "bq", _readonly([float(x) for x in bq]))
        set_(self, "cq", _readonly([float(x) for x in cq]))
        set_(self, "order2", int(self.order2))

    @property
    def partitioned(self):
        return True

    def _stage_coupling(self):
        """A stage feeds the velocities and the configurations (``active_stages``; the first stage,
        the step's start, is always used: Aq has a zero first row and bq or Aq reads it)."""
        return np.abs(self.A) + np.abs(self.Aq), np.abs(self.b) + np.abs(self.bq)

    @property
    def fsal(self):
        return False

    @property
    def order_label(self):
        return f"{self.order2}; {self.order} where the forces depend on the velocity"

    @functools.lru_cache(maxsize=None)
    def first_order_part(self):
        """The plain tableau ``(A, b, c)`` that advances the first-order coordinates."""
        return ButcherTableau(name=f"{self.name} (first-order part)", A=self.A, b=self.b, c=self.c,
                              order=self.order)

    def __repr__(self):
        return f"PartitionedTableau(name={self.name!r}, stages={self.stages}, order2={self.order2})"


def first_order_part(tableau):
    """The tableau that advances first-order coordinates: a partitioned method's ``(A, b)``, else the
    tableau itself."""
    return tableau.first_order_part() if tableau.partitioned else tableau


VelocityVerlet = PartitionedTableau(
    name="VelocityVerlet", order=1, order2=2,
    A=[[0, 0],
       ["1/2", 0]],
    b=["1/2", "1/2"], c=[0, "1/2"],
    Aq=[[0, 0],
        [0, 1]],
    bq=[0, 1],
    aliases=("Verlet", "StormerVerlet"),
    description="Velocity Verlet (kick-drift-kick) as Exudyn's VelocityVerlet defines it: V_2 = V + h/2 "
                "Vdot_1, g+ = g exp(h V_2), V+ = V_2 + h/2 F(t + h, g+, V_2); symplectic and of order 2 "
                "where F depends on the configuration alone, order 1 otherwise.",
)

PARTITIONED_METHODS: Tuple[PartitionedTableau, ...] = (VelocityVerlet,)
