"""Unit quaternions (Euler parameters) and unit dual quaternions."""
import math

import numpy as np
import pytest

import dualquat_oracle as dq
from exudyn_lie.groups import quaternion as qt
from exudyn_lie.groups import se3, so3

POINTS = ["zero", "tiny", "random", "near_pi"]


def unit(rng, n=3):
    v = rng.normal(size=n)
    return v / np.linalg.norm(v)


def rotvec(kind, rng):
    n = unit(rng)
    return {"zero": 0.0 * n, "tiny": 1e-8 * n, "random": rng.uniform(1.0, 2.0) * n,
            "near_pi": (math.pi - 1e-6) * n}[kind]


# ------------------------------------------------------------------ quaternions
def test_hamilton_matrices_equal_product(rng):
    Q, P = rng.normal(size=4), rng.normal(size=4)
    QP = qt.multiply(Q, P)
    np.testing.assert_allclose(qt.hamilton_plus(Q) @ P, QP, atol=1e-14)
    np.testing.assert_allclose(qt.hamilton_minus(P) @ Q, QP, atol=1e-14)
    # scalar/vector form of the Hamilton product
    ref = np.r_[Q[0] * P[0] - Q[1:] @ P[1:], Q[0] * P[1:] + P[0] * Q[1:] + np.cross(Q[1:], P[1:])]
    np.testing.assert_allclose(QP, ref, atol=1e-14)
    np.testing.assert_allclose(qt.multiply(Q, qt.conjugate(Q)), [Q @ Q, 0, 0, 0], atol=1e-14)
    # eq. DE, and D(Q) P = vec(P Q*), E(Q) P = vec(Q* P), D Q = E Q = 0
    q0, q = Q[0], Q[1:]
    np.testing.assert_array_equal(qt.D(Q), np.c_[-q, q0 * np.eye(3) + so3.hat(q)])
    np.testing.assert_array_equal(qt.E(Q), np.c_[-q, q0 * np.eye(3) - so3.hat(q)])
    np.testing.assert_allclose(qt.D(Q) @ P, qt.multiply(P, qt.conjugate(Q))[1:], atol=1e-14)
    np.testing.assert_allclose(qt.E(Q) @ P, qt.multiply(qt.conjugate(Q), P)[1:], atol=1e-14)
    np.testing.assert_allclose(qt.D(Q) @ Q, 0, atol=1e-14)
    np.testing.assert_allclose(qt.E(Q) @ Q, 0, atol=1e-14)


@pytest.mark.parametrize("kind", POINTS)
def test_rotvec_matrix_round_trips(kind, rng):
    xi = rotvec(kind, rng)
    Q = qt.from_rotvec(xi)
    assert abs(Q @ Q - 1) < 1e-15 and Q[0] >= 0
    R = so3.exp(xi)
    np.testing.assert_allclose(qt.to_matrix(Q), R, atol=4e-15)
    np.testing.assert_allclose(qt.D(Q) @ qt.E(Q).T, R, atol=4e-15)        # R = D E^T
    np.testing.assert_allclose(qt.from_matrix(R), Q, atol=4e-15)
    np.testing.assert_allclose(qt.to_rotvec(Q), xi, atol=4e-15)
    np.testing.assert_allclose(qt.to_rotvec(-Q), xi, atol=4e-15)          # double cover
    np.testing.assert_allclose(qt.to_matrix(-Q), R, atol=4e-15)


@pytest.mark.parametrize("kind", POINTS + ["exactly_pi"])
def test_quaternion_exp_log_identity(kind, rng):
    """from_rotvec (exp) after to_rotvec (log) returns the quaternion, directly at
    Q = from_rotvec(x) for the four points, and at Q = (0, n) (a rotation by exactly pi)."""
    if kind == "exactly_pi":
        Q = np.r_[0.0, unit(rng)]
    else:
        Q = qt.from_rotvec(rotvec(kind, rng))
    xi = qt.to_rotvec(Q)
    assert np.linalg.norm(xi) <= math.pi + 1e-15
    np.testing.assert_allclose(qt.from_rotvec(xi), Q, atol=4e-16 * 4, rtol=0)
    np.testing.assert_allclose(so3.exp(xi), qt.to_matrix(Q), atol=4e-15, rtol=0)


def test_from_matrix_at_pi_and_composition(rng):
    n = unit(rng)
    R = 2.0 * np.outer(n, n) - np.eye(3)
    Q = qt.from_matrix(R)
    assert Q[0] == 0.0
    np.testing.assert_allclose(qt.to_matrix(Q), R, atol=4e-15)
    # homomorphism: R(Q P) = R(Q) R(P)
    Q, P = qt.from_rotvec(rng.normal(size=3)), qt.from_rotvec(rng.normal(size=3))
    np.testing.assert_allclose(qt.to_matrix(qt.multiply(Q, P)), qt.to_matrix(Q) @ qt.to_matrix(P),
                               atol=1e-14)
    # both sides of the half-angle switch in from_rotvec
    for f in (0.99, 1.01):
        xi = 2 * so3.T_SWITCH_EXP * f * unit(rng)
        np.testing.assert_allclose(qt.to_matrix(qt.from_rotvec(xi)), so3.exp(xi), atol=2e-15)


@pytest.mark.parametrize("kind", POINTS)
def test_angular_velocity_is_2E_Qdot(kind, rng):
    """Finite differences: with R = D E^T the BODY-fixed omega (R^T Rdot) is 2 E Qdot, and
    2 D Qdot is the spatial one (the paper's eq. Hh uses D)."""
    xi = rotvec(kind, rng)
    xidot = rng.normal(size=3)
    h = 1e-6
    Q = qt.from_rotvec(xi)
    Qdot = (qt.from_rotvec(xi + h * xidot) - qt.from_rotvec(xi - h * xidot)) / (2 * h)
    Rdot = (so3.exp(xi + h * xidot) - so3.exp(xi - h * xidot)) / (2 * h)
    R = so3.exp(xi)
    omega = so3.vee(R.T @ Rdot)
    np.testing.assert_allclose(2 * qt.E(Q) @ Qdot, omega, atol=1e-8)
    np.testing.assert_allclose(qt.omega_from_qdot(Q, Qdot), omega, atol=1e-8)
    np.testing.assert_allclose(2 * qt.D(Q) @ Qdot, R @ omega, atol=1e-8)
    np.testing.assert_allclose(omega, so3.dexp(-xi) @ xidot, atol=1e-8)
    # rate map: Qdot = 1/2 E^T omega, tangent to |Q| = 1
    qd = qt.qdot_from_omega(Q, omega)
    np.testing.assert_allclose(qd, Qdot, atol=1e-8)
    np.testing.assert_allclose(qd, 0.5 * qt.multiply(Q, np.r_[0.0, omega]), atol=1e-15)
    assert abs(Q @ qd) < 1e-15
    # mixed velocity map (eq. Hh, corrected)
    rdot = rng.normal(size=3)
    Vm = np.r_[omega, rdot]
    rate = qt.rate_from_mixed(Q, Vm)
    np.testing.assert_allclose(qt.Hm(Q) @ rate, Vm, atol=1e-14)
    np.testing.assert_allclose(qt.Hm(Q) @ np.r_[Qdot, rdot], Vm, atol=1e-8)


# ------------------------------------------------------------- dual quaternions
def pose(kind, rng):
    return se3.exp(np.r_[rotvec(kind, rng), rng.normal(size=3)])


def test_dual_hamilton_matrices(rng):
    Qh, Ph = rng.normal(size=8), rng.normal(size=8)
    QP = dq.multiply(Qh, Ph)
    np.testing.assert_allclose(dq.plus(Qh) @ Ph, QP, atol=1e-14)
    np.testing.assert_allclose(dq.minus(Ph) @ Qh, QP, atol=1e-14)


@pytest.mark.parametrize("kind", POINTS)
def test_pose_and_screw_round_trips(kind, rng):
    R, r = pose(kind, rng)
    Qh = dq.from_pose(R, r)
    assert abs(Qh[:4] @ Qh[:4] - 1) < 1e-15
    assert abs(Qh[:4] @ Qh[4:]) < 1e-15                                   # Pluecker condition
    # eq. Qpos: (0, r) = 2 (Q^-)^T Qe
    np.testing.assert_allclose(2 * qt.hamilton_minus(Qh[:4]).T @ Qh[4:], np.r_[0, r], atol=1e-14)
    R2, r2 = dq.to_pose(Qh)
    np.testing.assert_allclose(R2, R, atol=1e-14)
    np.testing.assert_allclose(r2, r, atol=1e-14)
    np.testing.assert_allclose(dq.to_pose(-Qh)[1], r, atol=1e-14)          # double cover
    X = se3.log(R, r)
    np.testing.assert_allclose(dq.from_screw(X), Qh, atol=1e-14)
    np.testing.assert_allclose(dq.to_screw(Qh), X, atol=1e-13)


def _same_dual_quaternion(Qh, Ph, atol):
    """Qh == Ph up to the double cover (Qh and -Qh are the same pose)."""
    sgn = 1.0 if Qh[:4] @ Ph[:4] >= 0 else -1.0
    np.testing.assert_allclose(sgn * Qh, Ph, atol=atol, rtol=0)


@pytest.mark.parametrize("kind", POINTS + ["exactly_pi"])
def test_dual_quaternion_screw_round_trip(kind, rng):
    """from_screw (exp) after to_screw (log) returns the dual quaternion, directly at
    Qh = from_screw(X) for the four points and |xi| = pi."""
    X = np.r_[math.pi * unit(rng) if kind == "exactly_pi" else rotvec(kind, rng),
              rng.normal(size=3)]
    Qh = dq.from_screw(X)
    Xl = dq.to_screw(Qh)
    assert np.linalg.norm(Xl[:3]) <= math.pi + 1e-15
    _same_dual_quaternion(dq.from_screw(Xl), Qh, 1e-14)
    R, r = dq.to_pose(Qh)
    R2, r2 = se3.exp(Xl)
    np.testing.assert_allclose(R2, R, atol=4e-15, rtol=0)
    np.testing.assert_allclose(r2, r, atol=1e-14, rtol=0)


def test_dual_quaternion_to_screw_at_exactly_pi(rng):
    """to_screw of a pose rotated by exactly pi (q0 == 0 exactly: R = 2 n n^T - I)."""
    for _ in range(10):
        n = unit(rng)
        R = 2.0 * np.outer(n, n) - np.eye(3)
        r = rng.normal(size=3)
        Qh = dq.from_pose(R, r)
        assert Qh[0] == 0.0
        X = dq.to_screw(Qh)
        assert abs(np.linalg.norm(X[:3]) - math.pi) < 1e-14
        R2, r2 = se3.exp(X)
        np.testing.assert_allclose(R2, R, atol=4e-15, rtol=0)
        np.testing.assert_allclose(r2, r, atol=1e-14, rtol=0)
        _same_dual_quaternion(dq.from_screw(X), Qh, 1e-14)


def test_dual_product_is_se3_product(rng):
    C1, C2 = pose("random", rng), pose("random", rng)
    Qh = dq.multiply(dq.from_pose(*C1), dq.from_pose(*C2))
    R, r = se3.compose(*C1, *C2)
    R2, r2 = dq.to_pose(Qh)
    np.testing.assert_allclose(R2, R, atol=1e-14)
    np.testing.assert_allclose(r2, r, atol=1e-14)


@pytest.mark.parametrize("kind", POINTS)
def test_twist_maps(kind, rng):
    """H(Qh) Qhdot = V (body), Hm(Qh) Qhdot = V^m (mixed), checked against finite
    differences of Qh(t) = from_pose(C exp(t V))."""
    R, r = pose(kind, rng)
    Qh = dq.from_pose(R, r)
    V = rng.normal(size=6)
    Vm = np.r_[V[:3], R @ V[3:]]
    qhd = dq.qhdot_from_twist(Qh, V)
    np.testing.assert_allclose(dq.H(Qh) @ qhd, V, atol=1e-14)
    np.testing.assert_allclose(dq.Hm(Qh) @ qhd, Vm, atol=1e-14)
    np.testing.assert_allclose(dq.qhdot_from_mixed(Qh, Vm), qhd, atol=1e-14)
    # tangent to |Q| = 1 and Q.Qe = 0
    assert abs(Qh[:4] @ qhd[:4]) < 1e-15
    assert abs(qhd[:4] @ Qh[4:] + Qh[:4] @ qhd[4:]) < 1e-14
    h = 1e-6
    Qp = dq.from_pose(*se3.compose(R, r, *se3.exp(h * V)))
    Qm = dq.from_pose(*se3.compose(R, r, *se3.exp(-h * V)))
    # from_pose picks q0 >= 0; near pi that may flip the double cover: follow Qh
    Qp = Qp if Qp[:4] @ Qh[:4] > 0 else -Qp
    Qm = Qm if Qm[:4] @ Qh[:4] > 0 else -Qm
    fd = (Qp - Qm) / (2 * h)
    np.testing.assert_allclose(fd, qhd, atol=1e-8)
    np.testing.assert_allclose(dq.H(Qh) @ fd, V, atol=1e-8)
    np.testing.assert_allclose(dq.Hm(Qh) @ fd, Vm, atol=1e-8)
    # the paper's upper-left block 2 D(Q) gives the spatial angular velocity R omega
    np.testing.assert_allclose(2 * qt.D(Qh[:4]) @ qhd[:4], R @ V[:3], atol=1e-14)
