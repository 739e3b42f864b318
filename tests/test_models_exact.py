"""The exact free-body solutions (models._torque_free): elliptic functions, Euler's
equations, the kinematic relation R^T Rdot = omega^, conservation of the angular
momentum, and 4th-order convergence of MK-RK4 towards it."""

import numpy as np
import pytest

from exudyn_lie import models
from exudyn_lie.models._torque_free import TorqueFreeRotation, agm_K, carlson_rf, ellipf, ellipj


def test_jacobi_elliptic_functions():
    u = np.linspace(-20, 60, 4001)
    for m in (0.0, 1e-6, 0.3, 0.7, 0.99):
        sn, cn, dn = ellipj(u, m)
        np.testing.assert_allclose(sn ** 2 + cn ** 2, 1, atol=2e-15)
        np.testing.assert_allclose(dn ** 2 + m * sn ** 2, 1, atol=2e-15)
        h = 1e-6
        s1, c1, d1 = ellipj(u + h, m)
        s0, c0, d0 = ellipj(u - h, m)
        np.testing.assert_allclose((s1 - s0) / (2 * h), cn * dn, atol=1e-8)
        np.testing.assert_allclose((c1 - c0) / (2 * h), -sn * dn, atol=1e-8)
        np.testing.assert_allclose((d1 - d0) / (2 * h), -m * sn * cn, atol=1e-8)
        K = agm_K(m)
        np.testing.assert_allclose(ellipj(np.array([K]), m)[0], 1.0, atol=1e-14)
        assert ellipf(np.pi / 2, m) == pytest.approx(K, rel=1e-14)
    assert agm_K(0.0) == pytest.approx(np.pi / 2)
    assert carlson_rf(1.0, 1.0, 1.0) == pytest.approx(1.0)
    # F(am(u)) = u
    m = 0.6
    u = np.array([0.3, 1.1, 2.5])
    sn, cn, _ = ellipj(u, m)
    np.testing.assert_allclose([ellipf(np.arctan2(s, c), m) for s, c in zip(sn, cn)], u, rtol=1e-13)


CASES = [
    ([1.224, 4.68, 5.76], [10 * np.pi, 2 * np.pi, 0.0]),      # the paper's free body
    ([1.224, 4.68, 5.76], [1.0, -2.0, 3.0]),
    ([5.76, 1.224, 4.68], [0.3, -2.0, 5.0]),                   # other axis orders
    ([4.68, 1.224, 5.76], [-3.0, 0.5, -0.2]),
    ([2.0, 3.0, 1.0], [0.1, 4.0, 0.2]),                        # near the intermediate axis
]


@pytest.mark.parametrize("inertia,omega0", CASES)
def test_torque_free_rotation_solves_euler_and_kinematics(inertia, omega0):
    R0 = models._common.rot_x(0.4) @ models._common.rot_z(-1.1)
    tf = TorqueFreeRotation(inertia, R0, omega0)
    t = np.linspace(0.0, 10.0, 801)[1:]
    w = tf.omega(t)
    np.testing.assert_allclose(tf.omega([0.0])[0], omega0, atol=1e-13)
    h = 1e-6
    wd = (tf.omega(t + h) - tf.omega(t - h)) / (2 * h)
    np.testing.assert_allclose(wd, tf.omega_dot(w), atol=2e-6 * max(1, np.abs(w).max() ** 2))
    R = tf.R(t)
    np.testing.assert_allclose(tf.R([0.0])[0], R0, atol=1e-14)
    np.testing.assert_allclose(np.einsum("nji,njk->nik", R, R), np.broadcast_to(np.eye(3), R.shape), atol=1e-13)
    Rd = (tf.R(t + h) - tf.R(t - h)) / (2 * h)
    W = np.einsum("nji,njk->nik", R, Rd)
    wfd = np.stack([W[:, 2, 1], W[:, 0, 2], W[:, 1, 0]], axis=1)
    np.testing.assert_allclose(wfd, w, atol=1e-6 * max(1, np.abs(w).max()))
    L = np.einsum("nij,nj->ni", R, np.asarray(inertia) * w)
    np.testing.assert_allclose(L, np.broadcast_to(L[0], L.shape), atol=1e-12 * np.linalg.norm(L[0]))
    T = 0.5 * np.einsum("ni,i,ni->n", w, np.asarray(inertia), w)
    np.testing.assert_allclose(T, T[0], rtol=1e-13)


def test_steady_spin_about_a_principal_axis():
    tf = TorqueFreeRotation([1.224, 4.68, 5.76], np.eye(3), [0, 0, 2 * np.pi])
    R = tf.R(np.array([0.25, 1.0]))
    np.testing.assert_allclose(R[0], models._common.rot_z(np.pi / 2), atol=1e-15)
    np.testing.assert_allclose(R[1], np.eye(3), atol=1e-14)


@pytest.mark.parametrize("name", ["free_body_com_rotation", "free_body_offset_rotation",
                                  "free_body_offset_screw", "free_body_com_translation"])
def test_exact_solution_of_the_models(name):
    """x_c(t) uniform, frame origin r = x_c - R c, and the model's initial state."""
    info = models.build(name)[1]
    ex = info.exact(np.array([0.0, 3.0]))
    b = info.bodies[0]
    np.testing.assert_allclose(ex["R"][0, 0], b.R0, atol=1e-15)
    np.testing.assert_allclose(ex["r"][0, 0], b.r0, atol=1e-15)
    np.testing.assert_allclose(ex["omega"][0, 0], b.omega0, atol=1e-12)
    np.testing.assert_allclose(ex["r"][1, 0], ex["com"][1, 0] - ex["R"][1, 0] @ b.com, atol=1e-14)


def test_mk_rk4_converges_to_the_exact_rotation_with_order_4():
    """An independent check of the exact solution (and of the kernel): the orientation
    error eps_r of MK-RK4 against it falls by ~1e4 per decade of step size."""
    from exudyn_lie.apps.runs import LieRunner
    mbs, info = models.build("free_body_com_rotation", endTime=2.0)
    lr = LieRunner(info, "SE3")
    e = [lr.run(dt).orientation.max() for dt in (4e-3, 2e-3, 1e-3)]
    p = np.log2(e[0] / e[1]), np.log2(e[1] / e[2])
    assert 3.7 < p[0] < 4.3 and 3.7 < p[1] < 4.3, (e, p)
