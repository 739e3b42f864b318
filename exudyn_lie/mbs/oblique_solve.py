"""The index-1 solve for rows whose force direction differs from their gradient.

A coordinate constraint on a rotation parameter of a body parametrised by a rotation vector
('rotationVector', whose velocity coordinates are the local omega) constrains the
rotation-vector component ``theta_k`` (its gradient on the body omega is the row ``G`` = row k
of ``dexpinv_{-theta}``, node_coordinates.py), while its Jacobian on the velocity coordinates,
which carries the reaction force, is ``e_k`` on the local omega (``C``).  The model is

    M Vdot = Q - C^T lambda,    G Vdot = eta    (eta = -Gdot V; the index-1 form of eq. index1)

so ``lambda`` solves the non-symmetric Schur complement ``(G M^-1 C^T) lambda = G M^-1 Q - eta``
and ``Vdot = M^-1 (Q - C^T lambda)``.  ``C`` is ``G`` with the rotation columns of the
'rotationVector' ends replaced by ``s e_k`` (``s = -1`` on side A, the factor on side B): the patches
of :class:`ObliquePlan`, fixed when the scene is compiled.

A scene with such a row is given this plan as ``Work.tplan`` (compiled.solve_plan); numba
then compiles ``index1.solve_multipliers`` to the dense LU below (partial pivoting), chosen
by the plan's type: scenes without such rows keep the band / tree solve unchanged.  The
projections use the same pair (oblique Gauss-Newton steps ``-M^-1 C^T (G M^-1 C^T)^-1 h``,
which reach ``h = 0`` with the true gradient ``G``).
"""
from collections import namedtuple

import numpy as np
from numba import njit

from .codes import J_NROW, J_ROW0, ROW_AX, ROW_BX, ROW_COORD, ROW_KIND
from .node_coordinates import PARAM_BASE, is_oblique

#: patches of the force-direction rows: row ``pq[p]``, first column ``pcol[p]`` (0: side A's
#: omega, 6: side B's), values ``pval[p]`` (3); work: ``Cr`` (m, 12) the rows C, ``S`` (m, m)
#: the Schur complement, ``piv`` (m,) its row permutation
ObliquePlan = namedtuple("ObliquePlan", ["pq", "pcol", "pval", "Cr", "S", "piv"])


def oblique_plan(sd):
    """The :class:`ObliquePlan` of ``sd``, or None if every row's force direction is its
    gradient."""
    pq, pcol, pval = [], [], []
    for j in range(sd.jointIndex.shape[0]):
        for q in range(sd.jointIndex[j, J_ROW0], sd.jointIndex[j, J_ROW0] + sd.jointIndex[j, J_NROW]):
            if sd.rowIndex[q, ROW_KIND] != ROW_COORD:
                continue
            for col, code, s in ((0, sd.rowIndex[q, ROW_AX], -1.0),
                                 (6, sd.rowIndex[q, ROW_BX], sd.jointParams[j, 0])):
                if code >= PARAM_BASE and is_oblique(code):
                    v = np.zeros(3)
                    v[code % PARAM_BASE] = s
                    pq.append(q)
                    pcol.append(col)
                    pval.append(v)
    if not pq:
        return None
    m = sd.nrows
    return ObliquePlan(np.array(pq, np.int64), np.array(pcol, np.int64), np.array(pval, float).reshape(-1, 3),
                       np.zeros((m, 12)), np.zeros((m, m)), np.zeros(m, np.int64))


@njit(cache=True, _nrt=False)
def force_direction_rows(plan, Jr):
    """``plan.Cr = C``: the rows ``Jr`` (G) with the plan's patches."""
    Cr = plan.Cr
    for q in range(Jr.shape[0]):
        for k in range(12):
            Cr[q, k] = Jr[q, k]
    for p in range(plan.pq.shape[0]):
        q = plan.pq[p]
        c = plan.pcol[p]
        for i in range(3):
            Cr[q, c + i] = plan.pval[p, i]
