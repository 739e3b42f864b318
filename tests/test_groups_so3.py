"""SO(3) maps: exp/log, dexp/dexpinv (right-trivialised), Taylor switches, ad/Ad."""
from fractions import Fraction
import math

import numpy as np
import pytest

from exudyn_lie.groups import _taylor, so3

EPS = np.finfo(float).eps
POINTS = ["zero", "tiny", "random", "near_pi"]


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


def unit(rng, n=3):
    v = rng.normal(size=n)
    return v / np.linalg.norm(v)


def point(kind, rng):
    n = unit(rng)
    return {"zero": 0.0 * n, "tiny": 1e-8 * n, "random": rng.uniform(1.0, 2.0) * n,
            "near_pi": (math.pi - 1e-6) * n}[kind]


def exact_series_value(name, u, nterms=70):
    """Reference value of a coefficient: its exact Taylor series at the rational u."""
    c = _taylor.series(name, nterms)
    uf = Fraction(u)
    s = Fraction(0)
    for ck in reversed(c):
        s = s * uf + ck
    return float(s)


# ------------------------------------------------------------------ exp / log
@pytest.mark.parametrize("kind", POINTS)
def test_exp_matches_matrix_exponential(kind, rng):
    x = point(kind, rng)
    R = so3.exp(x)
    np.testing.assert_allclose(R, expm(so3.hat(x)), atol=4e-15, rtol=0)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=4e-15)
    Rb = np.empty((3, 3))
    so3.exp_into(x, Rb)
    np.testing.assert_array_equal(R, Rb)


@pytest.mark.parametrize("kind", POINTS)
def test_log_exp_identity(kind, rng):
    x = point(kind, rng)
    np.testing.assert_allclose(so3.log(so3.exp(x)), x, atol=2e-15 * max(1, np.linalg.norm(x) ** 2) + 1e-15)


@pytest.mark.parametrize("kind", POINTS)
def test_exp_log_identity(kind, rng):
    R = so3.exp(point(kind, rng)) @ so3.exp(point("random", rng))   # arbitrary rotations
    x = so3.log(R)
    assert np.linalg.norm(x) <= math.pi + 1e-14
    np.testing.assert_allclose(so3.exp(x), R, atol=4e-15)


@pytest.mark.parametrize("kind", POINTS + ["exactly_pi"])
def test_exp_log_identity_at_the_points(kind, rng):
    """exp(log(g)) = g directly at g = exp(x) for the four points and |x| = pi (in
    floating point: the double nearest to pi); log lands on |xi| <= pi."""
    x = math.pi * unit(rng) if kind == "exactly_pi" else point(kind, rng)
    R = so3.exp(x)
    xl = so3.log(R)
    assert np.linalg.norm(xl) <= math.pi + 1e-15
    np.testing.assert_allclose(so3.exp(xl), R, atol=4e-15, rtol=0)
    if kind == "exactly_pi":          # log is defined up to the sign of the axis
        assert min(np.abs(xl - x).max(), np.abs(xl + x).max()) < 1e-7


def test_log_at_exactly_pi(rng):
    # exactly symmetric rotations by pi: R = 2 n n^T - I
    for _ in range(20):
        n = unit(rng)
        R = 2.0 * np.outer(n, n) - np.eye(3)
        x = so3.log(R)
        assert abs(np.linalg.norm(x) - math.pi) < 1e-14
        np.testing.assert_allclose(so3.exp(x), R, atol=4e-15)
        # consistent sign: the largest axis component is positive
        assert x[np.argmax(np.abs(x))] > 0
    np.testing.assert_allclose(so3.log(np.diag([1.0, -1.0, -1.0])), [math.pi, 0, 0], atol=1e-15)
    np.testing.assert_allclose(so3.log(np.diag([-1.0, -1.0, 1.0])), [0, 0, math.pi], atol=1e-15)
    # exp(pi n) computed numerically (R not exactly symmetric)
    for _ in range(20):
        n = unit(rng)
        R = so3.exp(math.pi * n)
        x = so3.log(R)
        assert abs(np.linalg.norm(x) - math.pi) < 1e-14
        np.testing.assert_allclose(so3.exp(x), R, atol=4e-15)


@pytest.mark.parametrize("delta", [1e-12, 1e-9, 1e-6, 1e-3])
def test_log_near_pi(delta, rng):
    for _ in range(10):
        x = (math.pi - delta) * unit(rng)
        np.testing.assert_allclose(so3.log(so3.exp(x)), x, atol=2e-14)


def test_log_small_angle_switch(rng):
    # both sides of the atan(x)/x switch in rotvec_from_quat (x = |q|/q0 ~ t/2)
    for f in (0.99, 1.01):
        x = 2.0 * so3.T_SWITCH_LOG * f * unit(rng)
        np.testing.assert_allclose(so3.log(so3.exp(x)), x, rtol=1e-14, atol=0)


# ---------------------------------------------------------------- dexp family
@pytest.mark.parametrize("kind", POINTS)
def test_dexp_times_dexpinv_is_identity(kind, rng):
    x = point(kind, rng)
    np.testing.assert_allclose(so3.dexp(x) @ so3.dexpinv(x), np.eye(3), atol=1e-14)
    np.testing.assert_allclose(so3.dexpinv(x) @ so3.dexp(x), np.eye(3), atol=1e-14)


@pytest.mark.parametrize("kind", POINTS)
def test_dexp_right_trivialised_finite_difference(kind, rng):
    """d/de exp(x + e y) exp(x)^-1 = hat(dexp_x y), and the left version with dexp_{-x}."""
    x = point(kind, rng)
    y = rng.normal(size=3)
    h = 1e-6
    dE = (so3.exp(x + h * y) - so3.exp(x - h * y)) / (2 * h)
    R = so3.exp(x)
    right = so3.vee(dE @ R.T)
    left = so3.vee(R.T @ dE)
    np.testing.assert_allclose(right, so3.dexp(x) @ y, atol=1e-9)
    np.testing.assert_allclose(left, so3.dexp(-x) @ y, atol=1e-9)
    # body angular velocity of R = exp(xi(t)): omega = dexp_{-xi} xidot
    np.testing.assert_allclose(so3.dexpinv(-x) @ left, y, atol=1e-8)


@pytest.mark.parametrize("kind", POINTS)
def test_closed_forms_equal_series(kind, rng):
    x = point(kind, rng)
    np.testing.assert_allclose(so3.dexp(x), so3.dexp_series(x, 40), atol=2e-15)
    np.testing.assert_allclose(so3.dexpinv(x), so3.dexpinv_series(x, 60), atol=2e-14)


@pytest.mark.parametrize("which", ["exp", "dexpinv"])
@pytest.mark.parametrize("f", [0.99, 1.01])
def test_both_sides_of_switch_matrices(which, f, rng):
    t = (so3.T_SWITCH_EXP if which == "exp" else so3.T_SWITCH_DEXPINV) * f
    for _ in range(5):
        x = t * unit(rng)
        np.testing.assert_allclose(so3.exp(x), expm(so3.hat(x)), atol=4e-16 * 4)
        np.testing.assert_allclose(so3.dexp(x), so3.dexp_series(x, 40), atol=4e-16)
        np.testing.assert_allclose(so3.dexpinv(x), so3.dexpinv_series(x, 40), atol=4e-16)


@pytest.mark.parametrize("f", [0.99, 1.01])
def test_both_sides_of_switch_coefficients(f):
    """Coefficient level: series below, closed form above the switch, vs the exact series.

    The switch rule bounds the closed form's error by ~AMP_MAX eps at the switch
    (observed: < 10 eps) and the series' truncation by eps."""
    TOL = 2 * _taylor.AMP_MAX * EPS
    u = (so3.T_SWITCH_EXP * f) ** 2
    for name, val in zip("ABC", so3.coef_ABC(u)):
        ref = exact_series_value(name, u)
        assert abs(val - ref) <= TOL * abs(ref), (name, f, val, ref)
    u = (so3.T_SWITCH_DEXPINV * f) ** 2
    ref = exact_series_value("D", u)
    assert abs(so3.coef_D(u) - ref) <= TOL * abs(ref)
    # and both branches agree with each other at the switch itself
    u = so3.U_SWITCH_EXP
    np.testing.assert_allclose(so3.series_ABC(u), so3.closed_ABC(u), rtol=TOL)
    u = so3.U_SWITCH_DEXPINV
    np.testing.assert_allclose(so3.series_D(u), so3.closed_D(u), rtol=TOL)


def test_taylor_coefficients_and_switch_rule():
    # hand-derived leading terms
    assert _taylor.series("A", 4) == [1, Fraction(-1, 6), Fraction(1, 120), Fraction(-1, 5040)]
    assert _taylor.series("B", 3) == [Fraction(1, 2), Fraction(-1, 24), Fraction(1, 720)]
    assert _taylor.series("C", 3) == [Fraction(1, 6), Fraction(-1, 120), Fraction(1, 5040)]
    assert _taylor.series("D", 4) == [Fraction(1, 12), Fraction(1, 720), Fraction(1, 30240),
                                      Fraction(1, 1209600)]
    B = _taylor.bernoulli(9)
    assert B[:5] == [1, Fraction(-1, 2), Fraction(1, 6), 0, Fraction(-1, 30)] and B[8] == Fraction(-1, 30)
    # rule: first dropped term <= eps at the switch; closed form amplification <= AMP_MAX
    for names, t_sw in ((("A", "B", "C"), so3.T_SWITCH_EXP), (("D",), so3.T_SWITCH_DEXPINV)):
        for name in names:
            n = _taylor.nterms_for(name, t_sw)
            c = [float(v) for v in _taylor.series(name, n + 1)]
            assert abs(c[n]) * t_sw ** (2 * n) <= EPS * abs(c[0])
            if _taylor.CANCELLATION[name] is not None:
                K, p = _taylor.CANCELLATION[name]
                assert K / t_sw ** p <= _taylor.AMP_MAX * (1 + 1e-12)


def test_dexp_singular_at_two_pi(rng):
    x = 2 * math.pi * unit(rng)
    assert abs(np.linalg.det(so3.dexp(x))) < 1e-12


# ------------------------------------------------------------ apply variants
@pytest.mark.parametrize("kind", POINTS + ["switch"])
def test_apply_into_equals_matrix(kind, rng):
    x = point(kind, rng) if kind != "switch" else so3.T_SWITCH_EXP * 1.01 * unit(rng)
    y = rng.normal(size=3)
    out = np.empty(3)
    so3.dexp_apply_into(x, y, out)
    np.testing.assert_allclose(out, so3.dexp(x) @ y, atol=1e-15 * 8)
    so3.dexpinv_apply_into(x, y, out)
    np.testing.assert_allclose(out, so3.dexpinv(x) @ y, atol=1e-15 * 8)
    # aliasing out = y
    z = y.copy()
    so3.dexpinv_apply_into(x, z, z)
    np.testing.assert_allclose(z, so3.dexpinv(x) @ y, atol=1e-15 * 8)


# ---------------------------------------------------------------- ad, Ad, group
def test_hat_vee_ad_Ad_group(rng):
    x, y = rng.normal(size=3), rng.normal(size=3)
    np.testing.assert_array_equal(so3.vee(so3.hat(x)), x)
    np.testing.assert_allclose(so3.hat(x) @ y, np.cross(x, y), atol=1e-15)
    bracket = so3.hat(x) @ so3.hat(y) - so3.hat(y) @ so3.hat(x)
    np.testing.assert_allclose(so3.ad(x) @ y, so3.vee(bracket), atol=1e-15)
    R = so3.exp(rng.normal(size=3))
    np.testing.assert_allclose(so3.hat(so3.Ad(R) @ x), R @ so3.hat(x) @ R.T, atol=1e-14)
    R2 = so3.exp(rng.normal(size=3))
    np.testing.assert_allclose(so3.compose(R, R2), R @ R2, atol=1e-15)
    np.testing.assert_allclose(so3.compose(R, so3.inverse(R)), np.eye(3), atol=1e-15)
