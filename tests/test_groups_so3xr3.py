"""SO(3) x R^3 maps (7x7 matrix representation as oracle), and SE3 vs SO3xR3."""
import math

import numpy as np
import pytest

from exudyn_lie.groups import GROUPS, se3, so3, so3xr3

POINTS = ["zero", "tiny", "random", "near_pi"]


def expm(M, terms=24):
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


C7 = so3xr3.to_matrix


def test_registry():
    assert GROUPS["SE3"] is se3 and GROUPS["SO3xR3"] is so3xr3
    assert list(GROUPS)[:2] == ["SE3", "SO3xR3"]        # group ids 0, 1 (codes.GID_*)


@pytest.mark.parametrize("kind", POINTS)
def test_exp_matches_matrix_exponential(kind, rng):
    X = point(kind, rng)
    R, r = so3xr3.exp(X)
    np.testing.assert_allclose(C7(R, r), expm(so3xr3.hat(X)), atol=1e-14)
    Rb, rb = np.empty((3, 3)), np.empty(3)
    so3xr3.exp_into(X, Rb, rb)
    np.testing.assert_array_equal(R, Rb)
    np.testing.assert_array_equal(r, rb)


@pytest.mark.parametrize("kind", POINTS)
def test_log_exp_and_exp_log(kind, rng):
    X = point(kind, rng)
    np.testing.assert_allclose(so3xr3.log(*so3xr3.exp(X)), X, atol=1e-14)
    R, r = so3xr3.compose(*so3xr3.exp(X), *so3xr3.exp(point("random", rng)))
    R2, r2 = so3xr3.exp(so3xr3.log(R, r))
    np.testing.assert_allclose(R2, R, atol=1e-14)
    np.testing.assert_allclose(r2, r, atol=1e-14)


@pytest.mark.parametrize("kind", POINTS + ["exactly_pi"])
def test_exp_log_identity_at_the_points(kind, rng):
    """exp(log(g)) = g directly at g = exp(X) for the four points and |xi| = pi."""
    X = np.r_[math.pi * unit(rng), rng.normal(size=3)] if kind == "exactly_pi" else point(kind, rng)
    R, r = so3xr3.exp(X)
    Xl = so3xr3.log(R, r)
    assert np.linalg.norm(Xl[0:3]) <= math.pi + 1e-15
    R2, r2 = so3xr3.exp(Xl)
    np.testing.assert_allclose(R2, R, atol=4e-15, rtol=0)
    np.testing.assert_array_equal(r2, r)
    # the 7x7 matrix representation agrees (eq. MatrixSO3xR3)
    np.testing.assert_allclose(C7(R2, r2), C7(R, r), atol=4e-15, rtol=0)


def test_log_at_exactly_pi(rng):
    n = unit(rng)
    R = 2.0 * np.outer(n, n) - np.eye(3)
    X = so3xr3.log(R, np.ones(3))
    assert abs(np.linalg.norm(X[:3]) - math.pi) < 1e-14
    np.testing.assert_allclose(so3xr3.exp(X)[0], R, atol=1e-14)
    np.testing.assert_array_equal(so3xr3.exp(X)[1], np.ones(3))


@pytest.mark.parametrize("kind", POINTS)
def test_dexp_family(kind, rng):
    X = point(kind, rng)
    np.testing.assert_allclose(so3xr3.dexp(X) @ so3xr3.dexpinv(X), np.eye(6), atol=1e-14)
    np.testing.assert_allclose(so3xr3.dexp(X), so3xr3.dexp_series(X, 40), atol=1e-14)
    np.testing.assert_allclose(so3xr3.dexpinv(X), so3xr3.dexpinv_series(X, 64), atol=1e-13)
    # finite differences in the 7x7 representation, right and left trivialised
    Y = rng.normal(size=6)
    h = 1e-6
    dE = (C7(*so3xr3.exp(X + h * Y)) - C7(*so3xr3.exp(X - h * Y))) / (2 * h)
    E = C7(*so3xr3.exp(X))
    Einv = C7(*so3xr3.inverse(*so3xr3.exp(X)))
    np.testing.assert_allclose(E @ Einv, np.eye(7), atol=1e-14)
    np.testing.assert_allclose(so3xr3.vee(dE @ Einv), so3xr3.dexp(X) @ Y, atol=1e-8)
    Vm = so3xr3.vee(Einv @ dE)                   # mixed velocity (omega body, rdot)
    np.testing.assert_allclose(Vm, so3xr3.dexp(-X) @ Y, atol=1e-8)
    np.testing.assert_allclose(Vm[3:], Y[3:], atol=1e-8)


@pytest.mark.parametrize("f", [0.99, 1.01])
def test_both_sides_of_switch(f, rng):
    for t in (so3.T_SWITCH_EXP * f, so3.T_SWITCH_DEXPINV * f):
        X = np.concatenate([t * unit(rng), rng.normal(size=3)])
        np.testing.assert_allclose(C7(*so3xr3.exp(X)), expm(so3xr3.hat(X)), atol=2e-15)
        np.testing.assert_allclose(so3xr3.dexp(X), so3xr3.dexp_series(X, 40), atol=2e-15)
        np.testing.assert_allclose(so3xr3.dexpinv(X), so3xr3.dexpinv_series(X, 40), atol=2e-15)


@pytest.mark.parametrize("kind", POINTS)
def test_apply_into_equals_matrix(kind, rng):
    X = point(kind, rng)
    Y = rng.normal(size=6)
    out = np.empty(6)
    so3xr3.dexp_apply_into(X, Y, out)
    np.testing.assert_allclose(out, so3xr3.dexp(X) @ Y, atol=1e-14)
    so3xr3.dexpinv_apply_into(X, Y, out)
    np.testing.assert_allclose(out, so3xr3.dexpinv(X) @ Y, atol=1e-14)
    Z = Y.copy()
    so3xr3.dexpinv_apply_into(X, Z, Z)
    np.testing.assert_allclose(Z, so3xr3.dexpinv(X) @ Y, atol=1e-14)


def test_hat_vee_ad_Ad_group(rng):
    X, Y = rng.normal(size=6), rng.normal(size=6)
    np.testing.assert_array_equal(so3xr3.vee(so3xr3.hat(X)), X)
    bracket = so3xr3.hat(X) @ so3xr3.hat(Y) - so3xr3.hat(Y) @ so3xr3.hat(X)
    np.testing.assert_allclose(so3xr3.ad(X) @ Y, so3xr3.vee(bracket), atol=1e-14)
    np.testing.assert_allclose(so3xr3.ad(X) @ Y, np.r_[np.cross(X[:3], Y[:3]), 0, 0, 0], atol=1e-14)
    R, r = so3xr3.exp(rng.normal(size=6))
    C, Cinv = C7(R, r), C7(*so3xr3.inverse(R, r))
    np.testing.assert_allclose(so3xr3.hat(so3xr3.Ad(R, r) @ X), C @ so3xr3.hat(X) @ Cinv, atol=1e-13)
    R2, r2 = so3xr3.exp(rng.normal(size=6))
    np.testing.assert_allclose(C7(*so3xr3.compose(R, r, R2, r2)), C @ C7(R2, r2), atol=1e-14)
    np.testing.assert_array_equal(so3xr3.from_matrix(C)[1], r)


def test_se3_and_so3xr3_differ_only_in_coupling(rng):
    """Same rotation; SE3 translation is dexp_xi eta, SO3xR3 translation is eta; same for
    a pure translation (xi = 0) or a screw along its axis (eta || xi)."""
    X = point("random", rng)
    Rs, rs = se3.exp(X)
    Rd, rd = so3xr3.exp(X)
    np.testing.assert_allclose(Rs, Rd, atol=1e-15)
    np.testing.assert_allclose(rs, so3.dexp(X[:3]) @ rd, atol=1e-14)
    Xa = np.r_[X[:3], 0.7 * X[:3]]
    np.testing.assert_allclose(se3.exp(Xa)[1], so3xr3.exp(Xa)[1], atol=1e-14)
