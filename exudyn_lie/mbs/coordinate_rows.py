"""The coordinate-constraint row (``ROW_COORD``): Exudyn's ``ObjectConnectorCoordinate``,

    h = f q_B - q_A - offset,

on two node coordinates ``q_A``, ``q_B`` (``MarkerNodeCoordinate``: the *current* coordinate,
total minus reference; a ground node's coordinate is 0).  Here the coordinates are position
coordinates of the nodes along fixed world directions ``d`` (``e_k`` for coordinate k of a
point or rigid node, the axis ``referenceRotation e_x`` of a Mass1D's Node1D):
``q_X = d_X . p_X - ref_X``, with ``p_X`` the node position (the body point ``s = 0``), so
``h = f d_B . p_B - d_A . p_A - c`` with ``c = offset + f ref_B - ref_A`` (folded by the scene
compiler; ``jpar[j] = (f, c, d_A, d_B)``).

Rows (eq. index1): ``J V = f d_B . pdot_B - d_A . pdot_A``, ``pdot = T v`` at s = 0, hence
``J = (0, -T_A^T d_A | 0, f T_B^T d_B)``, and ``eta = -(f d_B . beta_B - d_A . beta_A)`` with
``beta`` the velocity-product acceleration of the node (``R (omega x v)`` for SE3, 0 else;
:func:`~.bodies.body_point`): ``d`` is constant.
"""
from numba import njit

from .bodies import translation_dual


@njit(cache=True, inline="always", _nrt=False)
def coordinate_row(q, a, b, gA, gB, RA, RB, par, pA, pB, bA, bB, e, RTe, h, Jr, eta):
    """Row ``q`` of a coordinate constraint from the node points ``pA, pB`` and their bias
    accelerations ``bA, bB`` (body_point at s = 0); ``par = (f, c, d_A, d_B)``."""
    f = par[0]
    hv = -par[1]
    et = 0.0
    for k in range(3):
        hv += f * par[5 + k] * pB[k] - par[2 + k] * pA[k]
        et += f * par[5 + k] * bB[k] - par[2 + k] * bA[k]
    h[q] = hv
    eta[q] = -et
    if a >= 0:
        _translation_column(gA, RA, par, 2, -1.0, e, RTe, Jr, q, 3)
    if b >= 0:
        _translation_column(gB, RB, par, 5, f, e, RTe, Jr, q, 9)


@njit(cache=True, inline="always", _nrt=False)
def _translation_column(g, R, par, i0, s, e, RTe, Jr, q, col):
    """``Jr[q, col:col+3] = s T^T d`` with ``d = par[i0:i0+3]`` (``rdot = T v``; bodies.translation_dual)."""
    for i in range(3):
        e[i] = par[i0 + i]
    for i in range(3):
        RTe[i] = R[0, i] * e[0] + R[1, i] * e[1] + R[2, i] * e[2]
    Te = translation_dual(g, e, RTe)
    for i in range(3):
        Jr[q, col + i] = s * Te[i]
