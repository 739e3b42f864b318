"""Constraint rows of every joint type, in both velocity representations.

* J equals finite differences of h along each (left-trivialised) twist direction;
* eta = -Jdot V equals minus the finite difference of J V along the motion g exp(t V).

Checked for the named joint types and for the generic joint with every one of the 63
non-empty subsets of the six relative axes locked.
"""
import itertools

import numpy as np
import pytest

from exudyn_lie.groups import se3, so3, so3xr3
from exudyn_lie.mbs import GROUND, JOINT_TYPES, Scene
from exudyn_lie.mbs.compiled import compile_carried, compile_scene, make_work
from exudyn_lie.mbs.diagnostics import constraint_jacobian


def random_rotation(rng):
    return so3.exp(rng.normal(size=3) * 1.5)


def group_exp_right(group, R, r, X):
    """(R, r) exp(X) in the given group."""
    if group == "SE3":
        ER, Er = se3.exp(X)
        return R @ ER, r + R @ Er
    ER, Er = so3xr3.exp(X)
    return R @ ER, r + Er


def two_body_scene(rng, kind, ground_side, axes=None, worldTranslation=False):
    """Two random bodies and one joint of type ``kind`` (``axes``: the constrained axes
    of a generic joint) between them, or between one of them and the ground."""
    sc = Scene()
    for _ in range(2):
        m = rng.uniform(0.5, 3.0)
        c = rng.normal(size=3) * 0.1
        Jc = np.diag(rng.uniform(0.01, 0.1, 3))
        J0 = Jc + m * (np.dot(c, c) * np.eye(3) - np.outer(c, c))
        sc.AddBody(m, J0, com=c, R0=random_rotation(rng), r0=rng.normal(size=3))
    A, B = (GROUND, 1) if ground_side == "A" else ((0, GROUND) if ground_side == "B" else (0, 1))
    sc.AddJoint(A, B, JOINT_TYPES[kind] if axes is None else axes, posA=rng.normal(size=3) * 0.3, rotA=random_rotation(rng),
                posB=rng.normal(size=3) * 0.3, rotB=random_rotation(rng), kind=kind,
                worldTranslation=worldTranslation)
    return sc


CASES = [(k, g, s) for k in JOINT_TYPES for g in ("SE3", "SO3xR3") for s in ("none", "A", "B")]
AXIS_SUBSETS = [ax for ax in itertools.product((0, 1), repeat=6) if any(ax)]


def finite_differences(sc, group, rng, eps=1e-6):
    """(J, eta, J_fd, (J V)'_fd) of a two-body scene at its initial poses and a random V:
    J_fd the central differences of h along each twist
    direction g exp(+-eps e_k) of each body, eta against the central difference of J V
    along the motion g exp(tau V)."""
    sd, _ = compile_scene(sc, [group, group])
    wk = make_work(sd, 4, carried=compile_carried(sc))
    R = np.array([b.R0 for b in sc.bodies])
    r = np.array([b.r0 for b in sc.bodies])
    V = rng.normal(size=(2, 6))
    h0, J, eta = constraint_jacobian(sd, wk, R, r, V)
    Jfd = np.zeros_like(J)
    for i in range(2):
        for k in range(6):
            X = np.zeros(6)
            X[k] = eps
            Rp, rp, Rm, rm = R.copy(), r.copy(), R.copy(), r.copy()
            Rp[i], rp[i] = group_exp_right(group, R[i], r[i], X)
            Rm[i], rm[i] = group_exp_right(group, R[i], r[i], -X)
            Jfd[:, 6 * i + k] = (constraint_jacobian(sd, wk, Rp, rp, V)[0]
                                 - constraint_jacobian(sd, wk, Rm, rm, V)[0]) / (2 * eps)

    def JV_at(tau):
        Rt, rt = R.copy(), r.copy()
        for i in range(2):
            Rt[i], rt[i] = group_exp_right(group, R[i], r[i], tau * V[i])
        return constraint_jacobian(sd, wk, Rt, rt, V)[1] @ V.reshape(-1)

    Jdot_V = (JV_at(eps) - JV_at(-eps)) / (2 * eps)
    return J, eta, Jfd, Jdot_V


@pytest.mark.parametrize("worldTranslation", [False, True])
@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
@pytest.mark.parametrize("ground_side", ["none", "A", "B"])
def test_generic_joint_every_axis_subset_against_finite_differences(group, ground_side, worldTranslation, rng):
    """The generic joint with each of the 63 non-empty subsets of (tx, ty, tz, rx, ry, rz)
    locked, random masses, COM offsets, poses, joint frames and twists: J and eta against
    finite differences (worst error measured 1.5e-9 over all subsets, sides and groups).
    ``worldTranslation``: the locked translations as world components (Exudyn's spherical
    joint with some axes free)."""
    assert len(AXIS_SUBSETS) == 63
    worst = {}
    for ax in AXIS_SUBSETS:
        sc = two_body_scene(rng, "generic", ground_side, axes=ax, worldTranslation=worldTranslation)
        J, eta, Jfd, Jdot_V = finite_differences(sc, group, rng)
        assert J.shape == (sum(ax), 12)
        # a joint row is never all zero on a moving side
        assert np.all(np.max(np.abs(J), axis=1) > 1e-3), ax
        worst[ax] = max(np.max(np.abs(J - Jfd)), np.max(np.abs(-eta - Jdot_V)))
    bad = {ax: e for ax, e in worst.items() if e > 1e-8}
    assert not bad, bad


@pytest.mark.parametrize("kind,group,ground_side", CASES)
def test_jacobian_and_eta_against_finite_differences(kind, group, ground_side, rng):
    sc = two_body_scene(rng, kind, ground_side)
    J, eta, Jfd, Jdot_V = finite_differences(sc, group, rng)
    assert J.shape == (sum(JOINT_TYPES[kind]), 12)
    # a body welded to the ground side has no columns of its own in the rows
    np.testing.assert_allclose(J, Jfd, atol=1e-8, rtol=1e-6)
    # eta: d/dt (J(g exp(tV)) V) = Jdot V = -eta
    np.testing.assert_allclose(-eta, Jdot_V, atol=1e-7, rtol=1e-6)


@pytest.mark.parametrize("group", ["SE3", "SO3xR3"])
def test_joint_frames_of_helpers_satisfy_constraints_initially(group, rng):
    """Joints created at a world position/axis hold in the initial configuration."""
    sc = Scene()
    b0 = sc.AddBody(1.0, np.eye(3) * 0.1, R0=random_rotation(rng), r0=[0.3, 0.1, 0])
    b1 = sc.AddBody(1.0, np.eye(3) * 0.1, R0=random_rotation(rng), r0=[0.6, -0.2, 0.1])
    p = np.array([0.45, 0.0, 0.05])
    sc.AddRevoluteJoint(GROUND, b0, [0, 0, 0], axis=[0, 1, 1])
    sc.AddPrismaticJoint(b0, b1, p, axis=[1, 2, 0])
    sc.AddCylindricalJoint(b0, b1, p, axis=[0, 0, 1])
    sc.AddUniversalJoint(b0, b1, p, axisA=[1, 0, 0], axisB=[0, 1, 0])
    sc.AddPlanarJoint(b0, b1, p, normal=[0, 1, 0])
    sc.AddFixedJoint(b0, b1, p)
    sc.AddSphericalJoint(b0, b1, p)
    sd, _ = compile_scene(sc, [group, group])
    wk = make_work(sd, 4, carried=compile_carried(sc))
    R = np.array([b.R0 for b in sc.bodies])
    r = np.array([b.r0 for b in sc.bodies])
    h, J, eta = constraint_jacobian(sd, wk, R, r, np.zeros((2, 6)))
    assert np.max(np.abs(h)) < 1e-14


def test_same_body_joint_is_rejected():
    sc = Scene()
    b = sc.AddBody(1.0, np.eye(3))
    with pytest.raises(ValueError, match="same"):
        sc.AddJoint(b, b, JOINT_TYPES["spherical"])
