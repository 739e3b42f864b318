"""SE(3) maps: exp/log, dexp/dexpinv (closed, Park, Selig, series), FD, ad/Ad."""
from fractions import Fraction
import math

import numpy as np
import pytest

from exudyn_lie.groups import _taylor, se3, so3

EPS = np.finfo(float).eps
POINTS = ["zero", "tiny", "random", "near_pi"]
TOL = 2 * _taylor.AMP_MAX * EPS


def expm(M, terms=24):
    """Independent matrix exponential: Taylor series with scaling and squaring."""
    nrm = np.abs(M).sum(axis=0).max()
    s = max(0, int(math.ceil(math.log2(nrm))) + 1) if nrm > 0 else 0
    A = M / 2.0 ** s
    E = np.eye(M.shape[0])
    T = np.eye(M.shape[0])
    for k in range(1, terms):
        T = T @ A / k
        E = E + T
    for _ in range(s):
        E = E @ E
    return E


def unit(rng):
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def point(kind, rng):
    n = unit(rng)
    xi = {"zero": 0.0 * n, "tiny": 1e-8 * n, "random": rng.uniform(1.0, 2.0) * n,
          "near_pi": (math.pi - 1e-6) * n}[kind]
    return np.concatenate([xi, rng.normal(size=3)])


def screw_at(t, rng):
    return np.concatenate([t * unit(rng), rng.normal(size=3)])


def C4(R, r):
    return se3.to_matrix(R, r)


def exact_series_value(name, u, nterms=60):
    s = Fraction(0)
    for ck in reversed(_taylor.series(name, nterms)):
        s = s * Fraction(u) + ck
    return float(s)


# ------------------------------------------------------------------ exp / log
@pytest.mark.parametrize("kind", POINTS)
def test_exp_matches_matrix_exponential(kind, rng):
    X = point(kind, rng)
    R, r = se3.exp(X)
    np.testing.assert_allclose(C4(R, r), expm(se3.hat(X)), atol=1e-14)
    Rb, rb = np.empty((3, 3)), np.empty(3)
    se3.exp_into(X, Rb, rb)
    np.testing.assert_array_equal(R, Rb)
    np.testing.assert_array_equal(r, rb)


@pytest.mark.parametrize("kind", POINTS)
def test_log_exp_identity(kind, rng):
    X = point(kind, rng)
    np.testing.assert_allclose(se3.log(*se3.exp(X)), X, atol=1e-13)


@pytest.mark.parametrize("kind", POINTS)
def test_exp_log_identity(kind, rng):
    R, r = se3.compose(*se3.exp(point(kind, rng)), *se3.exp(point("random", rng)))
    X = se3.log(R, r)
    assert np.linalg.norm(X[0:3]) <= math.pi + 1e-14
    R2, r2 = se3.exp(X)
    np.testing.assert_allclose(R2, R, atol=1e-14)
    np.testing.assert_allclose(r2, r, atol=1e-13)


@pytest.mark.parametrize("kind", POINTS + ["exactly_pi"])
def test_exp_log_identity_at_the_points(kind, rng):
    """exp(log(g)) = g directly at g = exp(X) for the four points and |xi| = pi."""
    X = np.r_[math.pi * unit(rng), rng.normal(size=3)] if kind == "exactly_pi" else point(kind, rng)
    R, r = se3.exp(X)
    Xl = se3.log(R, r)
    assert np.linalg.norm(Xl[0:3]) <= math.pi + 1e-15
    R2, r2 = se3.exp(Xl)
    np.testing.assert_allclose(R2, R, atol=4e-15, rtol=0)
    np.testing.assert_allclose(r2, r, atol=4e-15 * (1 + np.linalg.norm(r)), rtol=0)


def test_log_at_exactly_pi(rng):
    for _ in range(10):
        n = unit(rng)
        R = 2.0 * np.outer(n, n) - np.eye(3)
        r = rng.normal(size=3)
        X = se3.log(R, r)
        assert abs(np.linalg.norm(X[0:3]) - math.pi) < 1e-14
        R2, r2 = se3.exp(X)
        np.testing.assert_allclose(R2, R, atol=1e-14)
        np.testing.assert_allclose(r2, r, atol=1e-13)


# ---------------------------------------------------------------- dexp family
@pytest.mark.parametrize("kind", POINTS)
def test_dexp_times_dexpinv_is_identity(kind, rng):
    X = point(kind, rng)
    np.testing.assert_allclose(se3.dexp(X) @ se3.dexpinv(X), np.eye(6), atol=1e-13)
    np.testing.assert_allclose(se3.dexpinv(X) @ se3.dexp(X), np.eye(6), atol=1e-13)


@pytest.mark.parametrize("kind", POINTS)
def test_dexp_right_and_left_finite_difference(kind, rng):
    """d/de exp(X+eY) exp(X)^-1 = hat(dexp_X Y); exp(X)^-1 d/de exp(X+eY) = hat(dexp_{-X} Y)."""
    X = point(kind, rng)
    Y = rng.normal(size=6)
    h = 1e-6
    dE = (C4(*se3.exp(X + h * Y)) - C4(*se3.exp(X - h * Y))) / (2 * h)
    E = C4(*se3.exp(X))
    Einv = C4(*se3.inverse(*se3.exp(X)))
    np.testing.assert_allclose(Einv @ E, np.eye(4), atol=1e-14)
    np.testing.assert_allclose(se3.vee(dE @ Einv), se3.dexp(X) @ Y, atol=1e-8)
    V = se3.vee(Einv @ dE)                       # body-fixed twist of exp(X(t)), Xdot = Y
    np.testing.assert_allclose(V, se3.dexp(-X) @ Y, atol=1e-8)
    # the MK stage relation: Xdot = dexpinv_{-X} V
    np.testing.assert_allclose(se3.dexpinv(-X) @ V, Y, atol=1e-8)


@pytest.mark.parametrize("kind", POINTS)
def test_closed_forms_equal_series_and_selig(kind, rng):
    X = point(kind, rng)
    np.testing.assert_allclose(se3.dexp(X), se3.dexp_series(X, 40), atol=1e-14)
    np.testing.assert_allclose(se3.dexpinv(X), se3.dexpinv_series(X, 64), atol=1e-13)
    np.testing.assert_allclose(se3.dexpinv_selig(X), se3.dexpinv(X), atol=1e-13)


SWITCHES = {
    "exp": lambda: so3.T_SWITCH_EXP,
    "dexp": lambda: se3.T_SWITCH_DEXP,
    "dexpinv": lambda: se3.T_SWITCH_DEXPINV,
    "selig": lambda: se3.T_SWITCH_SELIG,
}


@pytest.mark.parametrize("which", list(SWITCHES))
@pytest.mark.parametrize("f", [0.99, 1.01])
def test_both_sides_of_switch_matrices(which, f, rng):
    t = SWITCHES[which]() * f
    for _ in range(3):
        X = screw_at(t, rng)
        R, r = se3.exp(X)
        np.testing.assert_allclose(C4(R, r), expm(se3.hat(X)), atol=1e-14)
        np.testing.assert_allclose(se3.dexp(X), se3.dexp_series(X, 40), atol=2e-15)
        np.testing.assert_allclose(se3.dexpinv(X), se3.dexpinv_series(X, 64), atol=2e-15)
        np.testing.assert_allclose(se3.dexpinv_selig(X), se3.dexpinv_series(X, 64), atol=4e-15)


@pytest.mark.parametrize("f", [0.99, 1.01])
def test_both_sides_of_switch_coefficients(f):
    for names, fn, t_sw in ((("B", "C", "Q3", "Q4"), se3.coef_dexp, se3.T_SWITCH_DEXP),
                            (("D", "E2"), se3.coef_dexpinv, se3.T_SWITCH_DEXPINV),
                            (("S2", "S4"), se3.coef_selig, se3.T_SWITCH_SELIG)):
        u = (t_sw * f) ** 2
        for name, val in zip(names, fn(u)):
            ref = exact_series_value(name, u)
            assert abs(val - ref) <= TOL * abs(ref), (name, f, val, ref)
    for ser, clo, u in ((se3.series_dexp, se3.closed_dexp, se3.U_SWITCH_DEXP),
                        (se3.series_dexpinv, se3.closed_dexpinv, se3.U_SWITCH_DEXPINV),
                        (se3.series_selig, se3.closed_selig, se3.U_SWITCH_SELIG)):
        np.testing.assert_allclose(ser(u), clo(u), rtol=TOL)


def test_taylor_coefficients_and_switch_rule():
    assert _taylor.series("Q3", 3) == [Fraction(-1, 12), Fraction(1, 180), Fraction(-1, 6720)]
    assert _taylor.series("Q4", 3) == [Fraction(-1, 60), Fraction(1, 1260), Fraction(-1, 60480)]
    assert _taylor.series("E2", 2) == [Fraction(1, 360), Fraction(1, 7560)]
    # Selig's ad^2 / ad^4 coefficients tend to B_2/2! and B_4/4!
    assert _taylor.series("S2", 1) == [Fraction(1, 12)]
    assert _taylor.series("S4", 1) == [Fraction(-1, 720)]
    for names, t_sw in ((("B", "C", "Q3", "Q4"), se3.T_SWITCH_DEXP),
                        (("D", "E2"), se3.T_SWITCH_DEXPINV), (("S2", "S4"), se3.T_SWITCH_SELIG)):
        assert t_sw == max(_taylor.t_min(n) for n in names)
        for name in names:
            n = _taylor.nterms_for(name, t_sw)
            c = [float(v) for v in _taylor.series(name, n + 1)]
            assert abs(c[n]) * t_sw ** (2 * n) <= EPS * abs(c[0])


# ------------------------------------------------------------- paper formulas
def _paper_P_U(X, printed):
    """P (eq. P1) and U (below eq. dexpInvSE3Park) in the paper's notation."""
    xi, eta = X[0:3], X[3:6]
    t = np.linalg.norm(xi)
    W, N = so3.hat(xi), so3.hat(eta)
    alpha = 2 / t * math.sin(t / 2) * math.cos(t / 2)
    beta = 4 / t ** 2 * math.sin(t / 2) ** 2
    h = xi @ eta / t ** 2
    S = N @ W + W @ N
    if printed:
        gamma = 2 / t / math.tan(t / 2)
        P = (beta / 2 * N + (1 - alpha) / t ** 2 * S + h * (alpha - beta) / t * W
             + h / t ** 2 * (beta / 2 - 3 * (1 - alpha) / t) * W @ W)
        U = (1 - gamma) / t ** 2 * S + h / t ** 3 * (1 / beta + gamma - 2) * W @ W - N / 2
    else:
        gamma = t / 2 / math.tan(t / 2)
        P = (beta / 2 * N + (1 - alpha) / t ** 2 * S + h * (alpha - beta) * W
             + h * (beta / 2 - 3 * (1 - alpha) / t ** 2) * W @ W)
        U = (1 - gamma) / t ** 2 * S + h / t ** 2 * (1 / beta + gamma - 2) * W @ W - N / 2
    return P, U


def test_paper_P1_and_U_corrected_forms(rng):
    """The printed P1 / U do not reproduce the series; the corrected ones do (see se3 doc)."""
    X = point("random", rng)
    P_ser = se3.dexp_series(X, 40)[3:6, 0:3]
    U_ser = se3.dexpinv_series(X, 64)[3:6, 0:3]
    P, U = _paper_P_U(X, printed=False)
    np.testing.assert_allclose(P, P_ser, atol=1e-13)
    np.testing.assert_allclose(U, U_ser, atol=1e-13)
    np.testing.assert_allclose(se3.dexp_P(X), P_ser, atol=1e-14)
    np.testing.assert_allclose(se3.dexpinv_U(X), U_ser, atol=1e-14)
    Pp, Up = _paper_P_U(X, printed=True)
    assert np.abs(Pp - P_ser).max() > 1e-2
    assert np.abs(Up - U_ser).max() > 1e-2


def test_hybrid_twist_map(rng):
    """eq. hybridtwist: A(X) = blockdiag(I, R) dexp_{-X} = [[dexp_{-xi}, 0], [R P(-X), dexp_xi]]."""
    X = point("random", rng)
    R, _ = se3.exp(X)
    A = np.block([[np.eye(3), np.zeros((3, 3))], [np.zeros((3, 3)), R]]) @ se3.dexp(-X)
    np.testing.assert_allclose(A[3:6, 3:6], so3.dexp(X[0:3]), atol=1e-14)
    np.testing.assert_allclose(A[3:6, 0:3], R @ se3.dexp_P(-X), atol=1e-14)


# ------------------------------------------------------------ apply variants
@pytest.mark.parametrize("kind", POINTS + ["dexp_switch", "dexpinv_switch"])
def test_apply_into_equals_matrix(kind, rng):
    if kind == "dexp_switch":
        X = screw_at(se3.T_SWITCH_DEXP * 1.01, rng)
    elif kind == "dexpinv_switch":
        X = screw_at(se3.T_SWITCH_DEXPINV * 1.01, rng)
    else:
        X = point(kind, rng)
    Y = rng.normal(size=6)
    out = np.empty(6)
    se3.dexp_apply_into(X, Y, out)
    np.testing.assert_allclose(out, se3.dexp(X) @ Y, atol=1e-14)
    se3.dexpinv_apply_into(X, Y, out)
    np.testing.assert_allclose(out, se3.dexpinv(X) @ Y, atol=1e-14)
    Z = Y.copy()
    se3.dexpinv_apply_into(X, Z, Z)
    np.testing.assert_allclose(Z, se3.dexpinv(X) @ Y, atol=1e-14)
    Z = Y.copy()
    se3.dexp_apply_into(X, Z, Z)
    np.testing.assert_allclose(Z, se3.dexp(X) @ Y, atol=1e-14)
    # strided views (as used by the integrator: rows of 2-D work arrays)
    W = np.zeros((3, 6))
    W[1] = Y
    se3.dexpinv_apply_into(X, W[1], W[2])
    np.testing.assert_allclose(W[2], se3.dexpinv(X) @ Y, atol=1e-14)


# ---------------------------------------------------------------- ad, Ad, group
def test_hat_vee_ad_Ad_group(rng):
    X, Y = rng.normal(size=6), rng.normal(size=6)
    np.testing.assert_array_equal(se3.vee(se3.hat(X)), X)
    bracket = se3.hat(X) @ se3.hat(Y) - se3.hat(Y) @ se3.hat(X)
    np.testing.assert_allclose(se3.ad(X) @ Y, se3.vee(bracket), atol=1e-14)
    # eq. se3bracket
    expl = np.concatenate([np.cross(X[:3], Y[:3]), np.cross(X[:3], Y[3:]) - np.cross(Y[:3], X[3:])])
    np.testing.assert_allclose(se3.ad(X) @ Y, expl, atol=1e-14)
    R, r = se3.exp(rng.normal(size=6))
    C = C4(R, r)
    Cinv = C4(*se3.inverse(R, r))
    np.testing.assert_allclose(C @ Cinv, np.eye(4), atol=1e-14)
    np.testing.assert_allclose(se3.hat(se3.Ad(R, r) @ X), C @ se3.hat(X) @ Cinv, atol=1e-13)
    # Ad_exp(X) = exp(ad_X)
    np.testing.assert_allclose(se3.Ad(*se3.exp(X)), expm(se3.ad(X)), atol=1e-12)
    R2, r2 = se3.exp(rng.normal(size=6))
    np.testing.assert_allclose(C4(*se3.compose(R, r, R2, r2)), C @ C4(R2, r2), atol=1e-14)
    np.testing.assert_array_equal(se3.from_matrix(C)[1], r)
