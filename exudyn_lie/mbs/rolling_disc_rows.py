"""The rolling-disc rows (``ROW_ROLL``): a disc rolling without slip on a plane, constrained in
local directions (lateral, forward, normal), nonholonomic rows at velocity level.

Geometry (all world vectors; frame 0 on the plane body A or ground, frame 1 on the disc B):

    n  = R_A rotA planeNormal              (plane normal, used unnormalised)
    w1 = R_B rotB discAxis                 (disc axis)
    wF = (w1 x n) / |w1 x n|               (forward, rolling direction)
    w3 = w1 x wF                           (from the disc centre to the contact point)
    wL = n x wF                            (lateral)
    p_C = p_1 + r w3                       (contact point; p_1 the disc centre)

The row ``k`` (``constrainedAxes`` lateral / forward / normal, in this order) is

    g_k = e_k . c,   c = u_B(p_C) - u_A(p_C),   e = (wL, wF, n)

with ``u_X(p_C)`` the velocity of body X's material point at ``p_C``.  It is linear in V:
``g_k = J_k V`` (eq. index1 with a velocity-level row: there is no position residual, ``h = 0``;
the kernel's J V check / velocity projection see ``g_k``).  ``J_k`` is the world-direction row of
``e_k`` with both points at ``p_C`` (``s_X = R_X^T (p_C - r_X)`` in X's coordinates): the
velocity Jacobian of body X's material point at ``p_C``, projected on ``e_k``.

Acceleration level: ``J V' = eta = -Jdot V`` with ``Jdot V = d/dt (J(g(t)) V)`` at frozen V:

    Jdot V = edot . c + e . (beta_B - beta_A)
             + e . (omega_B x (p_C' - u_B)) - e . (omega_A x (p_C' - u_A)),

``beta_X`` the velocity-product acceleration of the material point ``s_X`` (body_point), the
last two terms from the motion of the material point under the contact point
(``R_X (omega x s_X') = omega_X x (p_C' - u_X)``, world omega), and the rates

    w1' = omega_B x w1,  n' = omega_A x n,  f = w1 x n,  f' = w1' x n + w1 x n',
    wF' = (f' - wF (wF . f')) / |f|,  w3' = w1' x wF + w1 x wF',  wL' = n' x wF + n x wF',
    p_C' = p_1' + r w3'.

Checked against finite differences of J V along g exp(tau V) (tests/test_rolling_disc.py).
"""
import numpy as np
from numba import njit

from .bodies import _cross, _matTvec, _matvec, body_point, translation_dual


@njit(cache=True, inline="always", _nrt=False)
def _dot(a0, a1, a2, b0, b1, b2):
    return a0 * b0 + a1 * b1 + a2 * b2


@njit(cache=True, _nrt=False)
def rolling_disc_row(q, axis, a, b, gA, gB, RA, RB, rA, rB, VA, VB, rotA, rotB, par, pB, vB, s, t, uA, uB, bA, bB,
                     w, h, Jr, eta):
    """Row ``q`` (``axis``: 0 lateral, 1 forward, 2 normal) of a rolling disc; ``par = jointParams[j]``
    = (radius, planeNormal, discAxis); ``pB, vB`` the disc centre and its velocity;
    ``s, t, uA, uB, bA, bB, w`` 3-vector scratch."""
    rad = par[0]
    # plane normal and disc axis in world coordinates, world angular velocities
    for k in range(3):
        t[k] = rotA[k, 0] * par[1] + rotA[k, 1] * par[2] + rotA[k, 2] * par[3]
    _matvec(RA, t, w)
    n0, n1, n2 = w[0], w[1], w[2]
    for k in range(3):
        t[k] = rotB[k, 0] * par[4] + rotB[k, 1] * par[5] + rotB[k, 2] * par[6]
    _matvec(RB, t, w)
    a0, a1, a2 = w[0], w[1], w[2]
    _matvec(RA, VA[:3], w)
    oA0, oA1, oA2 = w[0], w[1], w[2]
    _matvec(RB, VB[:3], w)
    oB0, oB1, oB2 = w[0], w[1], w[2]
    # forward, contact and lateral directions
    f0, f1, f2 = _cross(a0, a1, a2, n0, n1, n2)
    gn = np.sqrt(f0 * f0 + f1 * f1 + f2 * f2)
    F0, F1, F2 = f0 / gn, f1 / gn, f2 / gn
    c30, c31, c32 = _cross(a0, a1, a2, F0, F1, F2)
    L0, L1, L2 = _cross(n0, n1, n2, F0, F1, F2)
    # their rates
    ad0, ad1, ad2 = _cross(oB0, oB1, oB2, a0, a1, a2)
    nd0, nd1, nd2 = _cross(oA0, oA1, oA2, n0, n1, n2)
    x0, x1, x2 = _cross(ad0, ad1, ad2, n0, n1, n2)
    y0, y1, y2 = _cross(a0, a1, a2, nd0, nd1, nd2)
    fd0, fd1, fd2 = x0 + y0, x1 + y1, x2 + y2
    pr = _dot(F0, F1, F2, fd0, fd1, fd2)
    Fd0, Fd1, Fd2 = (fd0 - F0 * pr) / gn, (fd1 - F1 * pr) / gn, (fd2 - F2 * pr) / gn
    x0, x1, x2 = _cross(ad0, ad1, ad2, F0, F1, F2)
    y0, y1, y2 = _cross(a0, a1, a2, Fd0, Fd1, Fd2)
    w3d0, w3d1, w3d2 = x0 + y0, x1 + y1, x2 + y2
    # the row's direction e and its rate
    if axis == 0:
        x0, x1, x2 = _cross(nd0, nd1, nd2, F0, F1, F2)
        y0, y1, y2 = _cross(n0, n1, n2, Fd0, Fd1, Fd2)
        e0, e1, e2 = L0, L1, L2
        ed0, ed1, ed2 = x0 + y0, x1 + y1, x2 + y2
    elif axis == 1:
        e0, e1, e2 = F0, F1, F2
        ed0, ed1, ed2 = Fd0, Fd1, Fd2
    else:
        e0, e1, e2 = n0, n1, n2
        ed0, ed1, ed2 = nd0, nd1, nd2
    # contact point, its rate, and the material points of A and B under it
    pC0, pC1, pC2 = pB[0] + rad * c30, pB[1] + rad * c31, pB[2] + rad * c32
    pCd0, pCd1, pCd2 = vB[0] + rad * w3d0, vB[1] + rad * w3d1, vB[2] + rad * w3d2
    t[0], t[1], t[2] = pC0 - rA[0], pC1 - rA[1], pC2 - rA[2]
    _matTvec(RA, t, s)
    body_point(gA, RA, rA, VA, s, w, uA, bA)
    sA0, sA1, sA2 = s[0], s[1], s[2]
    t[0], t[1], t[2] = pC0 - rB[0], pC1 - rB[1], pC2 - rB[2]
    _matTvec(RB, t, s)
    body_point(gB, RB, rB, VB, s, w, uB, bB)
    c0, c1, c2 = uB[0] - uA[0], uB[1] - uA[1], uB[2] - uA[2]
    mB0, mB1, mB2 = _cross(oB0, oB1, oB2, pCd0 - uB[0], pCd1 - uB[1], pCd2 - uB[2])
    mA0, mA1, mA2 = _cross(oA0, oA1, oA2, pCd0 - uA[0], pCd1 - uA[1], pCd2 - uA[2])
    jdv = (_dot(ed0, ed1, ed2, c0, c1, c2)
           + _dot(e0, e1, e2, bB[0] - bA[0] + mB0 - mA0, bB[1] - bA[1] + mB1 - mA1, bB[2] - bA[2] + mB2 - mA2))
    h[q] = 0.0             # velocity-level row: no position residual
    eta[q] = -jdv
    # J: the world-direction row of e with both points at p_C (columns as constraints.joint_rows)
    w[0], w[1], w[2] = e0, e1, e2
    if a >= 0:
        _matTvec(RA, w, t)                           # RA^T e
        c0, c1, c2 = _cross(t[0], t[1], t[2], sA0, sA1, sA2)
        Jr[q, 0] = c0
        Jr[q, 1] = c1
        Jr[q, 2] = c2
        Te = translation_dual(gA, w, t)
        Jr[q, 3] = -Te[0]
        Jr[q, 4] = -Te[1]
        Jr[q, 5] = -Te[2]
    if b >= 0:
        _matTvec(RB, w, t)                           # RB^T e
        c0, c1, c2 = _cross(s[0], s[1], s[2], t[0], t[1], t[2])
        Jr[q, 6] = c0
        Jr[q, 7] = c1
        Jr[q, 8] = c2
        Te = translation_dual(gB, w, t)
        Jr[q, 9] = Te[0]
        Jr[q, 10] = Te[1]
        Jr[q, 11] = Te[2]
