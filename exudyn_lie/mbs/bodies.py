"""Per-body kinematics in the body's configuration group: the one place where the kernel
depends on the group of a body (``gid``, see :mod:`.codes` and :mod:`exudyn_lie.groups`).

* ``SE3`` (0): twist ``V = (omega, v)`` with ``v`` body-fixed, ``rdot = R v``;
* ``SO3xR3`` (1): mixed velocity, ``v = rdot`` spatial (eq. hybridvel);
* ``SE2`` / ``SO2xR2``: the planar subgroups, with the velocity representation of SE3 /
  SO3xR3 (``codes.uses_body_twist``, from each group's ``TWIST``).  A planar body keeps 6-vector
  velocities whose off-plane entries stay zero: its ``M^-1`` is zero off the plane
  (``compiled.planar_minv``), so off-plane forces do nothing, as for any planar body;
* ``R3`` (2): point masses (``groups/rn.py``): ``R = I`` and ``omega = 0`` for all time,
  ``v = rdot``; the rotation block of ``Minv`` is 0 and the translation block the (pseudo-)
  inverse of the mass on the free directions.  Every map that does not branch on ``R3``
  treats it as SO3xR3 with ``omega = 0``, which is exact.

The translation map ``T`` (``rdot = T v``) is ``R`` for SE3 and ``I`` for SO3xR3; with it
one formula serves both representations:  a body point ``s`` moves with
``pdot = T v + R (omega x s)`` and ``pddot = T vdot - R s^ omegadot + beta`` where the
velocity-product ("bias") term is ``beta = R (omega x (omega x s)) (+ R (omega x v) for SE3)``.

Every group-dependent operation of the kernel is a function here with one dispatch on
``gid``: the body point map, the generalised force of a point force, ``M^-1`` in the
body's velocity coordinates, the configuration update ``g exp(X)`` and the MK stage map
``dexp^-1``.  The last two are generated from the registry ``groups.GROUPS`` (below): a new
group needs no branch here; the velocity-representation maps branch on its ``TWIST``.
"""
import sys

from numba import njit

from ..groups import GROUPS
from ..groups.interface import algebra_axes
from .codegen import generate
from .codes import uses_body_twist, GID_R3, GID_SE3


# --------------------------------------------------------------------------- small vector helpers
@njit(cache=True, inline="always", _nrt=False)
def _cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@njit(cache=True, forceinline=True, _nrt=False)
def _matvec(M, x, out):
    for i in range(3):
        out[i] = M[i, 0] * x[0] + M[i, 1] * x[1] + M[i, 2] * x[2]


@njit(cache=True, forceinline=True, _nrt=False)
def _matTvec(M, x, out):
    for i in range(3):
        out[i] = M[0, i] * x[0] + M[1, i] * x[1] + M[2, i] * x[2]


@njit(cache=True, inline="always", _nrt=False)
def _side(gid, b, R, r, V, ident, zero3, zero6):
    """(gid, R, r, V) of a joint/connector side; ground has identity, zero velocity."""
    if b < 0:
        return GID_SE3, ident, zero3, zero6
    return gid[b], R[b], r[b], V[b]


# --------------------------------------------------------------------------- body kinematics
@njit(cache=True, inline="always", _nrt=False)
def connector_ends(gid, a, b, posA, posB, R, r, V, v3, ident, zero3, zero6):
    """The two ends of a point-to-point connector between bodies ``a`` and ``b`` (ground
    < 0): positions, velocities and velocity-product terms into ``v3[0..5]`` (pA, pB, vA,
    vB, bA, bB); returns the group and rotation of each side for the force that follows."""
    gA, RA, rA, VA = _side(gid, a, R, r, V, ident, zero3, zero6)
    gB, RB, rB, VB = _side(gid, b, R, r, V, ident, zero3, zero6)
    body_point(gA, RA, rA, VA, posA, v3[0], v3[2], v3[4])
    body_point(gB, RB, rB, VB, posB, v3[1], v3[3], v3[5])
    return gA, RA, gB, RB


@njit(cache=True, inline="always", _nrt=False)
def add_pair_force(gA, RA, posA, a, gB, RB, posB, b, F, Q):
    """World force ``F`` on body ``a`` at ``posA`` and ``-F`` on body ``b`` at ``posB``
    (ground < 0 takes none); ``F`` is left negated if ``b`` is a body."""
    if a >= 0:
        add_point_force(gA, RA, posA, F, Q[a])
    if b >= 0:
        for k in range(3):
            F[k] = -F[k]
        add_point_force(gB, RB, posB, F, Q[b])


@njit(cache=True, forceinline=True, _nrt=False)
def body_point(gid, R, r, V, s, p, pd, beta):
    """World position ``p``, velocity ``pd`` and velocity-product acceleration ``beta``
    of the body point ``s`` (body coordinates)."""
    w0, w1, w2 = V[0], V[1], V[2]
    ws0, ws1, ws2 = _cross(w0, w1, w2, s[0], s[1], s[2])            # omega x s
    wws0, wws1, wws2 = _cross(w0, w1, w2, ws0, ws1, ws2)            # omega x (omega x s)
    if uses_body_twist(gid):
        # rdot = R v : pd = R (v + omega x s); beta = R (omega x (omega x s) + omega x v)
        wv0, wv1, wv2 = _cross(w0, w1, w2, V[3], V[4], V[5])
        l0 = V[3] + ws0
        l1 = V[4] + ws1
        l2 = V[5] + ws2
        b0 = wws0 + wv0
        b1 = wws1 + wv1
        b2 = wws2 + wv2
        for i in range(3):
            p[i] = r[i] + R[i, 0] * s[0] + R[i, 1] * s[1] + R[i, 2] * s[2]
            pd[i] = R[i, 0] * l0 + R[i, 1] * l1 + R[i, 2] * l2
            beta[i] = R[i, 0] * b0 + R[i, 1] * b1 + R[i, 2] * b2
    else:
        for i in range(3):
            p[i] = r[i] + R[i, 0] * s[0] + R[i, 1] * s[1] + R[i, 2] * s[2]
            pd[i] = V[3 + i] + R[i, 0] * ws0 + R[i, 1] * ws1 + R[i, 2] * ws2
            beta[i] = R[i, 0] * wws0 + R[i, 1] * wws1 + R[i, 2] * wws2


@njit(cache=True, forceinline=True, _nrt=False)
def body_axis(R, V, u, a, ad, beta):
    """World direction ``a = R u`` of the body-fixed unit vector ``u``, its rate
    ``ad = R (omega x u)`` and bias acceleration ``beta = R (omega x (omega x u))``."""
    wu0, wu1, wu2 = _cross(V[0], V[1], V[2], u[0], u[1], u[2])
    wwu0, wwu1, wwu2 = _cross(V[0], V[1], V[2], wu0, wu1, wu2)
    for i in range(3):
        a[i] = R[i, 0] * u[0] + R[i, 1] * u[1] + R[i, 2] * u[2]
        ad[i] = R[i, 0] * wu0 + R[i, 1] * wu1 + R[i, 2] * wu2
        beta[i] = R[i, 0] * wwu0 + R[i, 1] * wwu1 + R[i, 2] * wwu2


@njit(cache=True, forceinline=True, _nrt=False)
def add_point_force(gid, R, s, F, Q):
    """Generalised force of a world force ``F`` at body point ``s``:
    ``Q = (s x R^T F, T^T F)`` so that ``Q . V`` is the power (R3: ``(0, F)``, omega = 0)."""
    if gid == GID_R3:
        Q[3] += F[0]
        Q[4] += F[1]
        Q[5] += F[2]
        return
    f0 = R[0, 0] * F[0] + R[1, 0] * F[1] + R[2, 0] * F[2]
    f1 = R[0, 1] * F[0] + R[1, 1] * F[1] + R[2, 1] * F[2]
    f2 = R[0, 2] * F[0] + R[1, 2] * F[1] + R[2, 2] * F[2]
    m0, m1, m2 = _cross(s[0], s[1], s[2], f0, f1, f2)
    Q[0] += m0
    Q[1] += m1
    Q[2] += m2
    if uses_body_twist(gid):
        Q[3] += f0
        Q[4] += f1
        Q[5] += f2
    else:
        Q[3] += F[0]
        Q[4] += F[1]
        Q[5] += F[2]


@njit(cache=True, forceinline=True, _nrt=False)
def add_world_torque(R, T, Q):
    """Body-fixed generalised torque of a world torque ``T``."""
    for i in range(3):
        Q[i] += R[0, i] * T[0] + R[1, i] * T[1] + R[2, i] * T[2]


@njit(cache=True, inline="always", _nrt=False)
def add_point_force_origin(gid, R, FT, Q):
    """:func:`add_point_force` of the world force ``FT[0:3]`` at the frame origin
    (``s = 0``): ``Q += (0, T^T F)``."""
    if uses_body_twist(gid):
        for k in range(3):
            Q[3 + k] += R[0, k] * FT[0] + R[1, k] * FT[1] + R[2, k] * FT[2]
    else:
        for k in range(3):
            Q[3 + k] += FT[k]


@njit(cache=True, inline="always", _nrt=False)
def add_world_torque_row(R, FT, Q):
    """:func:`add_world_torque` of the world torque ``FT[3:6]``: ``Q[0:3] += R^T T``."""
    for i in range(3):
        Q[i] += R[0, i] * FT[3] + R[1, i] * FT[4] + R[2, i] * FT[5]


@njit(cache=True, forceinline=True, _nrt=False)
def apply_minv(gid, Minv, R, x, out, tmp):
    """``out = M_rep^-1 x`` for the body's velocity representation.

    SE3: ``M`` is the constant J_P, ``Minv`` its inverse.  SO3xR3: ``V^m = D V`` with
    ``D = diag(I, R)``, hence ``(M^m)^-1 = D M^-1 D^T``."""
    if uses_body_twist(gid):
        for i in range(6):
            s = 0.0
            for k in range(6):
                s += Minv[i, k] * x[k]
            out[i] = s
    else:
        tmp[0] = x[0]
        tmp[1] = x[1]
        tmp[2] = x[2]
        for i in range(3):
            tmp[3 + i] = R[0, i] * x[3] + R[1, i] * x[4] + R[2, i] * x[5]
        for i in range(6):
            s = 0.0
            for k in range(6):
                s += Minv[i, k] * tmp[k]
            tmp[6 + i] = s
        out[0] = tmp[6]
        out[1] = tmp[7]
        out[2] = tmp[8]
        for i in range(3):
            out[3 + i] = R[i, 0] * tmp[9] + R[i, 1] * tmp[10] + R[i, 2] * tmp[11]



# --------------------------------------------------------------------------- group maps
# ``exp_compose`` and ``body_dexpinv_stage`` dispatch on the group id with one branch per
# entry of the registry exudyn_lie.groups.GROUPS, generated below when this module is
# imported: numba needs static calls, and a new group then needs its module and its registry
# line only.  Each branch calls the group's own ``exp_into`` / ``dexpinv_apply_into`` (the
# interface of groups/interface.py) and composes by the group's declared constants: ``TWIST``
# (body: ``r + R Er``, mixed: ``r + Er``) and ``ALGEBRA_AXES`` (no rotation axis, as R3:
# ``R`` is kept, exactly).  The generated source is compiled with this file's name, so numba
# caches it like the rest of the module; its cache key (exudyn_lie._numba_cache) hashes every
# solver module, groups/__init__.py (the registry) and this template included.

@njit(cache=True, inline="always", _nrt=False)
def compose_body_twist(R, r, ER, Er, Rout, rout):
    """``(Rout, rout) = (R, r)(ER, Er) = (R ER, r + R Er)`` (eq. MultSE3: body twists)."""
    for i in range(3):
        rout[i] = r[i] + R[i, 0] * Er[0] + R[i, 1] * Er[1] + R[i, 2] * Er[2]
    for i in range(3):
        for j in range(3):
            Rout[i, j] = R[i, 0] * ER[0, j] + R[i, 1] * ER[1, j] + R[i, 2] * ER[2, j]


@njit(cache=True, inline="always", _nrt=False)
def compose_mixed(R, r, ER, Er, Rout, rout):
    """``(Rout, rout) = (R ER, r + Er)`` (eq. MultDirectProduct: mixed velocities)."""
    for i in range(3):
        rout[i] = r[i] + Er[i]
    for i in range(3):
        for j in range(3):
            Rout[i, j] = R[i, 0] * ER[0, j] + R[i, 1] * ER[1, j] + R[i, 2] * ER[2, j]


@njit(cache=True, inline="always", _nrt=False)
def compose_translation(R, r, ER, Er, Rout, rout):
    """``(Rout, rout) = (R, r + Er)``: a group without rotation axes (R3) keeps ``R``."""
    for i in range(3):
        rout[i] = r[i] + Er[i]
        for j in range(3):
            Rout[i, j] = R[i, j]


def composition_of(module):
    """The composition of ``(R, r)`` with an element of the group ``module``, by its
    declared constants (see above)."""
    if not any(a < 3 for a in algebra_axes(module)):
        return "compose_translation"
    return "compose_body_twist" if module.TWIST == "body" else "compose_mixed"


def _generated_dispatch(name, params, branch, doc):
    """An njit function ``name(gid, params)`` with one ``if gid == k:`` branch per registered
    group (``branch(k, module)``: its source lines), compiled as part of this file."""
    lines = []
    env = {"compose_body_twist": compose_body_twist, "compose_mixed": compose_mixed,
           "compose_translation": compose_translation}
    for k, module in enumerate(GROUPS.values()):
        env[f"group{k}_exp_into"] = module.exp_into
        env[f"group{k}_dexpinv_apply_into"] = module.dexpinv_apply_into
        lines.append(f"if gid == {k}:")
        lines += ["    " + x for x in branch(k, module)]
        lines.append("    return")
    return generate(name, f"def {name}(gid, {params}):", lines, [], env, doc, sys.modules[__name__])


_EXP_COMPOSE_DOC = """``(Rout, rout) = (R, r) exp(X)`` in the body's group (eqs. expX / expSO3xR3, and
their planar restrictions); ``ER, Er`` are scratch for ``exp(X)``."""
_DEXPINV_DOC = """``out = dexp^-1_X Y`` in the body's group (the MK stage map, eq. MK1, with
``X = -Psi_j``): the group's ``dexpinv_apply_into`` (SE3 the full 6x6 map; SO3xR3 SO3's on
the rotation part, the identity on the translation; SE2 the planar closed form; the abelian
R3 and SO2xR2 the identity)."""


exp_compose = njit(cache=True, forceinline=True, _nrt=False)(_generated_dispatch(
    "exp_compose", "R, r, X, Rout, rout, ER, Er",
    lambda k, G: [f"group{k}_exp_into(X, ER, Er)", f"{composition_of(G)}(R, r, ER, Er, Rout, rout)"],
    _EXP_COMPOSE_DOC))

body_dexpinv_stage = njit(cache=True, inline="always", _nrt=False)(_generated_dispatch(
    "body_dexpinv_stage", "X, Y, out", lambda k, G: [f"group{k}_dexpinv_apply_into(X, Y, out)"], _DEXPINV_DOC))


@njit(cache=True, inline="always", _nrt=False)
def body_inertial_forces(gid, Mi, mass, com, R, Vi, Qi):
    """Subtract the velocity-dependent (gyroscopic / centrifugal) terms of one body from
    its generalised force ``Qi``, in the body's velocity coordinates.

    SE3, eq. (NE1): ``M Vdot = W + ad_V^T (M V)``, ``ad_V^T (L, p) = (-(w x L) - v x p, -(w x p))``.
    SO3xR3: ``M^m Vdot = W - (w x Theta_P w, m R (w x (w x c)))``."""
    w0, w1, w2 = Vi[0], Vi[1], Vi[2]
    if uses_body_twist(gid):
        Lx = Mi[0, 0] * w0 + Mi[0, 1] * w1 + Mi[0, 2] * w2 + Mi[0, 3] * Vi[3] + Mi[0, 4] * Vi[4] + Mi[0, 5] * Vi[5]
        Ly = Mi[1, 0] * w0 + Mi[1, 1] * w1 + Mi[1, 2] * w2 + Mi[1, 3] * Vi[3] + Mi[1, 4] * Vi[4] + Mi[1, 5] * Vi[5]
        Lz = Mi[2, 0] * w0 + Mi[2, 1] * w1 + Mi[2, 2] * w2 + Mi[2, 3] * Vi[3] + Mi[2, 4] * Vi[4] + Mi[2, 5] * Vi[5]
        px = Mi[3, 0] * w0 + Mi[3, 1] * w1 + Mi[3, 2] * w2 + Mi[3, 3] * Vi[3] + Mi[3, 4] * Vi[4] + Mi[3, 5] * Vi[5]
        py = Mi[4, 0] * w0 + Mi[4, 1] * w1 + Mi[4, 2] * w2 + Mi[4, 3] * Vi[3] + Mi[4, 4] * Vi[4] + Mi[4, 5] * Vi[5]
        pz = Mi[5, 0] * w0 + Mi[5, 1] * w1 + Mi[5, 2] * w2 + Mi[5, 3] * Vi[3] + Mi[5, 4] * Vi[4] + Mi[5, 5] * Vi[5]
        a0, a1, a2 = _cross(w0, w1, w2, Lx, Ly, Lz)
        b0, b1, b2 = _cross(Vi[3], Vi[4], Vi[5], px, py, pz)
        c0, c1, c2 = _cross(w0, w1, w2, px, py, pz)
        Qi[0] -= a0 + b0
        Qi[1] -= a1 + b1
        Qi[2] -= a2 + b2
        Qi[3] -= c0
        Qi[4] -= c1
        Qi[5] -= c2
    elif gid != GID_R3:             # mixed velocities (SO3xR3, SO2xR2); R3 (a point mass) has none
        Lx = Mi[0, 0] * w0 + Mi[0, 1] * w1 + Mi[0, 2] * w2
        Ly = Mi[1, 0] * w0 + Mi[1, 1] * w1 + Mi[1, 2] * w2
        Lz = Mi[2, 0] * w0 + Mi[2, 1] * w1 + Mi[2, 2] * w2
        a0, a1, a2 = _cross(w0, w1, w2, Lx, Ly, Lz)
        Qi[0] -= a0
        Qi[1] -= a1
        Qi[2] -= a2
        c = com
        if mass * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) > 0.0:
            wc0, wc1, wc2 = _cross(w0, w1, w2, c[0], c[1], c[2])
            e0, e1, e2 = _cross(w0, w1, w2, wc0, wc1, wc2)
            for k in range(3):
                Qi[3 + k] -= mass * (R[k, 0] * e0 + R[k, 1] * e1 + R[k, 2] * e2)


@njit(cache=True, inline="always", _nrt=False)
def body_twist(gid, R, V, Vb):
    """The body-fixed twist ``Vb = (omega, R^T rdot)`` of the body's group velocity ``V``
    (SE3: ``V`` itself; SO3xR3: ``v_b = R^T v``)."""
    for k in range(3):
        Vb[k] = V[k]
    if uses_body_twist(gid):
        for k in range(3):
            Vb[3 + k] = V[3 + k]
    else:
        for k in range(3):
            Vb[3 + k] = R[0, k] * V[3] + R[1, k] * V[4] + R[2, k] * V[5]


@njit(cache=True, inline="always", _nrt=False)
def body_world_velocity(gid, R, V, out):
    """``out = (omega, rdot)``: the body-fixed angular velocity and the world velocity of the
    frame origin, from the body's group velocity ``V`` (body twists, SE3 / SE2: ``rdot = R v``;
    mixed, SO3xR3 / SO2xR2 / R3: ``rdot = v``).  What :class:`~exudyn_lie.mbs.state.BodyStates` hands to Python forces."""
    for k in range(3):
        out[k] = V[k]
    if uses_body_twist(gid):
        for k in range(3):
            out[3 + k] = R[k, 0] * V[3] + R[k, 1] * V[4] + R[k, 2] * V[5]
    else:
        for k in range(3):
            out[3 + k] = V[3 + k]


@njit(cache=True, inline="always", _nrt=False)
def translation_dual(gid, a, RTa):
    """``T^T a`` for a world vector ``a``, given ``RTa = R^T a``: the translational
    velocity coordinates' share of ``a . rdot`` (``rdot = T v``: ``T = R`` for SE3,
    ``I`` for SO3xR3).  Returns one of the two arrays (no copy)."""
    if uses_body_twist(gid):
        return RTa
    return a
