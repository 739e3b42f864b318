"""The kernel's group maps are generated from the registry groups.GROUPS (mbs/bodies.py): for
every registered group, ``exp_compose`` is the group's ``(R, r) exp(X)`` in its velocity
representation and ``body_dexpinv_stage`` its ``dexpinv_apply_into``."""
import numpy as np
import pytest

from exudyn_lie.groups import GROUPS
from exudyn_lie.groups.interface import algebra_axes
from exudyn_lie.mbs import bodies
from exudyn_lie.mbs.codes import GROUP_NAMES


def _rotation(rng):
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


@pytest.mark.parametrize("name", list(GROUPS))
def test_generated_dispatch_is_the_registered_groups_maps(name):
    G = GROUPS[name]
    gid = GROUP_NAMES.index(name)
    rng = np.random.default_rng(gid)
    axes = list(algebra_axes(G))
    for _ in range(5):
        X = np.zeros(6)
        X[axes] = rng.normal(size=len(axes)) * 0.7
        Y = np.zeros(6)
        Y[axes] = rng.normal(size=len(axes))
        R = np.eye(3) if not any(a < 3 for a in axes) else _rotation(rng)
        r = rng.normal(size=3)
        Rout, rout, ER, Er = np.zeros((3, 3)), np.zeros(3), np.zeros((3, 3)), np.zeros(3)
        bodies.exp_compose(gid, R, r, X, Rout, rout, ER, Er)
        E, e = G.exp(X)
        # body twists compose as SE3, mixed velocities as SO3xR3 (the group's TWIST)
        want_r = r + (R @ e if G.TWIST == "body" else e)
        np.testing.assert_allclose(Rout, R @ E, rtol=0, atol=1e-14)
        np.testing.assert_allclose(rout, want_r, rtol=0, atol=1e-14)
        out = np.zeros(6)
        bodies.body_dexpinv_stage(gid, X, Y, out)
        want = np.zeros(6)
        G.dexpinv_apply_into(X, Y, want)
        np.testing.assert_array_equal(out, want)
    # an unregistered id does nothing (no branch)
    out = np.full(6, 7.0)
    bodies.body_dexpinv_stage(len(GROUPS), X, Y, out)
    assert np.all(out == 7.0)
