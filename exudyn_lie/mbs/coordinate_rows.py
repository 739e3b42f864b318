"""The coordinate-constraint row (``ROW_COORD``): Exudyn's ``ObjectConnectorCoordinate``,

    h = f q_B - q_A - offset,

on two node coordinates ``q_A``, ``q_B`` (``MarkerNodeCoordinate``: the *current* coordinate,
total minus reference; a ground node's coordinate is 0).  Here the coordinates are position
coordinates of the nodes: ``q_X = p_X[k_X] - ref_X``, with ``p_X`` the node position (the
body point ``s = 0``), so ``h = f p_B[bx] - p_A[ax] - c`` with ``c = offset + f ref_B - ref_A``
(folded by the scene compiler; ``jpar[j] = (f, c)``).

Rows (eq. index1): ``J V = f e_bx . pdot_B - e_ax . pdot_A``, ``pdot = T v`` at s = 0, hence
``J = (0, -T_A^T e_ax | 0, f T_B^T e_bx)``, and ``eta = -(f beta_B[bx] - beta_A[ax])`` with
``beta`` the velocity-product acceleration of the node (``R (omega x v)`` for SE3, 0 else;
:func:`~.bodies.body_point`).
"""
from numba import njit

from .bodies import translation_dual


@njit(cache=True, inline="always", _nrt=False)
def coordinate_row(q, a, b, gA, gB, RA, RB, ax, bx, par, pA, pB, bA, bB, e, RTe, h, Jr, eta):
    """Row ``q`` of a coordinate constraint from the node points ``pA, pB`` and their bias
    accelerations ``bA, bB`` (body_point at s = 0); ``par = (f, c)``."""
    f = par[0]
    h[q] = f * pB[bx] - pA[ax] - par[1]
    eta[q] = -(f * bB[bx] - bA[ax])
    if a >= 0:
        _translation_column(gA, RA, ax, -1.0, e, RTe, Jr, q, 3)
    if b >= 0:
        _translation_column(gB, RB, bx, f, e, RTe, Jr, q, 9)


@njit(cache=True, inline="always", _nrt=False)
def _translation_column(g, R, k, s, e, RTe, Jr, q, col):
    """``Jr[q, col:col+3] = s T^T e_k`` (``rdot = T v``; bodies.translation_dual)."""
    for i in range(3):
        e[i] = 0.0
        RTe[i] = R[k, i]
    e[k] = 1.0
    Te = translation_dual(g, e, RTe)
    for i in range(3):
        Jr[q, col + i] = s * Te[i]
