"""Rotation parameters of 3D rigid bodies as coordinates of the coordinate items
(:class:`~.scene_items.RotationParameterCoordinate`: parameter k of a body whose orientation is
parametrised by a rotation vector ('rotationVector'), Euler parameters ('eulerParameters') or
Tait-Bryan angles R = Rx Ry Rz ('taitBryanXYZ')).  The coordinate's value is the parameter
``q_k``, its rate is the parametrisation's *velocity coordinate* k, and its Jacobian is ``e_k``
on the parametrisation's velocity coordinates.  In the kernel's body velocity (local omega)
that is, per parametrisation, with ``p`` the rotation parameters of the body's ``R``:

* value ``q_k = p_k(R)`` on the branch a continuous integration of the parameters reaches,
  taken nearest to the parameters tracked at the last accepted step (``Work.bodyParameters``,
  :mod:`.rotation_parameters`);
* ``G``, the gradient of ``q_k`` on omega: ``qdot_k = G . omega`` (the chain rule through the
  parametrisation, ``pdot = P(p) omega``, ``G`` = row k of ``P``), and the bias
  ``Gdot . omega`` (``qddot_k = G . omegadot + Gdot . omega``);
* ``C``, the direction on omega of the Jacobian ``e_k`` (the generalised force ``f e_k``
  is the local torque ``C f``, the coordinate's rate is ``C . omega``).

For **'eulerParameters'** (velocity coordinates ``pdot``) and **'taitBryanXYZ'** (angle rates)
the velocity coordinate *is* the parameter's rate, so ``C = G``: the Jacobian is the chain-rule
row.  For **'rotationVector'** the velocity coordinates are the local omega itself: ``C = e_k``
(a local torque about body axis k; rate ``omega_k``), while the position-level value is the
rotation vector component with ``G`` = row k of ``dexpinv_{-theta}`` (``thetadot =
dexpinv_{-theta} omega``, groups/so3.py).  A coordinate constraint on it is then the index-3
model ``M Vdot = Q - C^T lambda``, ``theta_k = const``: force direction ``C`` != gradient ``G``
(a non-symmetric index-1 solve, :mod:`.oblique_solve`).

The item's end code (``rowIndex`` ROW_AX / ROW_BX of a coordinate row, ``coordSpringEnds`` columns 2 / 3 of
a coordinate spring) is ``10 * kind + k`` (:func:`param_code`); 0 is a position coordinate,
1 an angle about a fixed axis (:mod:`.coordinate_angles`).
"""
import math

from numba import njit

from ..groups import _taylor, so3
from .rotation_parameters import nearest_tait_bryan, quat_scalars

PARAM_ROTATION_VECTOR = 1    # rotation vector (3); velocity coordinates: the local omega
PARAM_EULER_PARAMETERS = 2   # Euler parameters (4); velocity coordinates: their rates
PARAM_TAIT_BRYAN = 3         # Tait-Bryan angles R = Rx Ry Rz (3); velocity coordinates: the angle rates
PARAM_BASE = 10              # end codes >= PARAM_BASE are rotation parameters of a body
#: the parametrisations by name (RotationParameterCoordinate.kind)
PARAM_KINDS = {"rotationVector": PARAM_ROTATION_VECTOR, "eulerParameters": PARAM_EULER_PARAMETERS,
               "taitBryanXYZ": PARAM_TAIT_BRYAN}

# D = (1 - (t/2) cot(t/2)) / t^2 of dexpinv (so3.coef_D) and dD/du (u = t^2): series below
# so3's switch point (12 terms: the derivative's truncation error there is below 1e-16 of
# 1/720), closed form above (its cancellation error there is ~60 eps / u < 4e-14 relative)
_CD = _taylor.coeffs("D", 12)
_CDD = tuple((i + 1) * c for i, c in enumerate(_CD[1:]))
U_SWITCH = so3.U_SWITCH_DEXPINV


def param_code(kind, k):
    """End code of coordinate k (0-based within the rotation parameters) of a node kind."""
    return PARAM_BASE * int(kind) + int(k)


@njit(cache=True, inline="always", _nrt=False)
def _coef_D_dD(u):
    """(D, dD/du) at u = t^2."""
    if u < U_SWITCH:
        return _taylor.horner(_CD, u), _taylor.horner(_CDD, u)
    h = 0.5 * math.sqrt(u)
    ct = math.cos(h) / math.sin(h)
    D = (1.0 - h * ct) / u
    sh = math.sin(h)
    return D, -(ct - h / (sh * sh)) / (8.0 * h * u) - D / u      # dh/du = 1 / (8 h)


@njit(cache=True, inline="always", _nrt=False)
def _nearest_quat(R, prev):
    """The unit quaternion of R with the sign nearest ``prev`` (four scalars)."""
    q0, q1, q2, q3 = quat_scalars(R)
    if q0 * prev[0] + q1 * prev[1] + q2 * prev[2] + q3 * prev[3] < 0.0:
        return -q0, -q1, -q2, -q3
    return q0, q1, q2, q3


@njit(cache=True, inline="always", _nrt=False)
def rotvec_of_quat(q0, q1, q2, q3):
    """The rotation vector of a quaternion of either sign, ``2 acos(q0) qv / |qv|`` (the branch
    that composing quaternions step by step reaches, |theta| <= 2 pi; as
    rotation_parameters.quat_rotvec)."""
    s = math.sqrt(q1 * q1 + q2 * q2 + q3 * q3)
    if s > 1e-12:
        fac = 2.0 * math.atan2(s, q0) / s
    elif q0 > 0.0:
        fac = 2.0 / q0
    else:
        fac = 2.0 * math.atan2(s, q0) / s if s > 0.0 else 0.0
    return q1 * fac, q2 * fac, q3 * fac


@njit(cache=True, _nrt=False)
def node_parameter(code, R, prev, w, G, C, tmp):
    """Value ``q_k`` of the node rotation parameter with end ``code`` at ``R`` (branch nearest
    the tracked ``prev``), its gradient ``G`` and the force direction ``C`` on the local omega
    (written), and the bias ``Gdot . w`` at the body's local omega ``w``.  ``tmp``: 3 scratch."""
    kind = code // PARAM_BASE
    k = code - PARAM_BASE * kind
    for i in range(3):
        C[i] = 0.0
    if kind == PARAM_ROTATION_VECTOR:
        q0, q1, q2, q3 = _nearest_quat(R, prev)
        t0, t1, t2 = rotvec_of_quat(q0, q1, q2, q3)
        th = (t0, t1, t2)
        u = t0 * t0 + t1 * t1 + t2 * t2
        D, dD = _coef_D_dD(u)
        # thetadot = dexpinv_{-theta} w = w + theta x w / 2 + D theta x (theta x w)
        c0, c1, c2 = t1 * w[2] - t2 * w[1], t2 * w[0] - t0 * w[2], t0 * w[1] - t1 * w[0]
        tw = t0 * w[0] + t1 * w[1] + t2 * w[2]
        d0, d1, d2 = t0 * tw - u * w[0], t1 * tw - u * w[1], t2 * tw - u * w[2]
        tmp[0] = w[0] + 0.5 * c0 + D * d0
        tmp[1] = w[1] + 0.5 * c1 + D * d1
        tmp[2] = w[2] + 0.5 * c2 + D * d2
        # G = e_k + (e_k x theta) / 2 + D (theta_k theta - u e_k)
        for i in range(3):
            G[i] = D * th[k] * th[i]
        G[k] += 1.0 - D * u
        G[(k + 2) % 3] += 0.5 * th[(k + 1) % 3]
        G[(k + 1) % 3] -= 0.5 * th[(k + 2) % 3]
        C[k] = 1.0
        # Gdot . w = (thetadot x w)_k / 2 + dD udot (theta_k (theta.w) - u w_k)
        #            + D (thetadot_k (theta.w) + theta_k (thetadot.w) - udot w_k),  udot = 2 theta.thetadot
        tdw = tmp[0] * w[0] + tmp[1] * w[1] + tmp[2] * w[2]
        udot = 2.0 * (t0 * tmp[0] + t1 * tmp[1] + t2 * tmp[2])
        k1 = (k + 1) % 3
        k2 = (k + 2) % 3
        cross_k = tmp[k1] * w[k2] - tmp[k2] * w[k1]
        bias = (0.5 * cross_k + dD * udot * (th[k] * tw - u * w[k])
                + D * (tmp[k] * tw + th[k] * tdw - udot * w[k]))
        return th[k], bias
    if kind == PARAM_EULER_PARAMETERS:
        p0, p1, p2, p3 = _nearest_quat(R, prev)
        p = (p0, p1, p2, p3)
        # pdot = P(p) w: pdot_0 = -pv . w / 2, pdot_v = (p0 w + pv x w) / 2 (= GL^T w / 4, GL the local G of p)
        pd0 = -0.5 * (p1 * w[0] + p2 * w[1] + p3 * w[2])
        pd1 = 0.5 * (p0 * w[0] + p2 * w[2] - p3 * w[1])
        pd2 = 0.5 * (p0 * w[1] + p3 * w[0] - p1 * w[2])
        pd3 = 0.5 * (p0 * w[2] + p1 * w[1] - p2 * w[0])
        if k == 0:
            G[0], G[1], G[2] = -0.5 * p1, -0.5 * p2, -0.5 * p3
            bias = -0.5 * (pd1 * w[0] + pd2 * w[1] + pd3 * w[2])
        else:
            i = k - 1
            i1 = (i + 1) % 3
            i2 = (i + 2) % 3
            # G = (p0 e_i + e_i x pv) / 2; P linear in p: Gdot . w = row k of P(pdot) w
            G[i] = 0.5 * p0
            G[i2] = 0.5 * p[1 + i1]
            G[i1] = -0.5 * p[1 + i2]
            pd = (pd0, pd1, pd2, pd3)
            bias = 0.5 * (pd0 * w[i] + pd[1 + i1] * w[i2] - pd[1 + i2] * w[i1])
        for i in range(3):
            C[i] = G[i]
        return p[k], bias
    # PARAM_TAIT_BRYAN: R = Rx(a0) Ry(a1) Rz(a2), w = GR(a) adot (bridge/rotations.rxyz_glocal)
    nearest_tait_bryan(R, prev, tmp)
    a1 = tmp[1]
    a2 = tmp[2]
    val = tmp[k]
    c1, s1 = math.cos(a1), math.sin(a1)
    c2, s2 = math.cos(a2), math.sin(a2)
    uu = c2 * w[0] - s2 * w[1]
    ww = s2 * w[0] + c2 * w[1]
    ad0 = uu / c1
    ad1 = ww
    ad2 = w[2] - s1 * ad0
    # adot = GR^-1 w; its rows and their derivatives at frozen w (d uu = -ad2 ww, d ww = ad2 uu)
    if k == 0:
        G[0], G[1], G[2] = c2 / c1, -s2 / c1, 0.0
        bias = -ad2 * ww / c1 + uu * s1 * ad1 / (c1 * c1)
    elif k == 1:
        G[0], G[1], G[2] = s2, c2, 0.0
        bias = ad2 * uu
    else:
        G[0], G[1], G[2] = -s1 * c2 / c1, s1 * s2 / c1, 1.0
        bias = -ad1 * uu / (c1 * c1) + s1 / c1 * ad2 * ww
    for i in range(3):
        C[i] = G[i]
    return val, bias


@njit(cache=True, _nrt=False)
def node_parameter_terms(q, a, b, codeA, codeB, RA, RB, VA, VB, bodyParameters, f, h, Jr, eta, G, C, tmp):
    """Add the node-parameter ends of coordinate row ``q`` (``h = f q_B - q_A - c``; the
    position terms of such an end are zero, coordinate_rows): ``h``, ``J`` on the rotation
    columns (the gradient ``G``) and ``eta = -Gdot omega``.  The force direction ``C`` of the
    row is :func:`force_direction_patch`'s business (oblique_solve)."""
    if a >= 0 and codeA >= PARAM_BASE:
        v, bias = node_parameter(codeA, RA, bodyParameters[a], VA, G, C, tmp)
        h[q] -= v
        eta[q] += bias
        for i in range(3):
            Jr[q, i] = -G[i]
    if b >= 0 and codeB >= PARAM_BASE:
        v, bias = node_parameter(codeB, RB, bodyParameters[b], VB, G, C, tmp)
        h[q] += f * v
        eta[q] -= f * bias
        for i in range(3):
            Jr[q, 6 + i] = f * G[i]


def is_oblique(code):
    """True if the force direction C of an end differs from its gradient G ('rotationVector')."""
    return int(code) // PARAM_BASE == PARAM_ROTATION_VECTOR
