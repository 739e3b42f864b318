"""One interface and one registry for the body configuration groups."""
import numpy as np
import pytest

from exudyn_lie.groups import GROUPS, interface
from exudyn_lie.mbs import codes
from exudyn_lie.mbs.compiled import GROUP_IDS


@pytest.mark.parametrize("name", list(GROUPS))
def test_registered_groups_implement_the_interface(name):
    assert interface.missing_operations(GROUPS[name]) == []


def test_kernel_group_ids_come_from_the_registry():
    assert codes.GROUP_NAMES == tuple(GROUPS)
    assert GROUP_IDS == {n: i for i, n in enumerate(GROUPS)}
    assert codes.GROUP_NAMES[codes.GID_SE3] == "SE3" and codes.GROUP_NAMES[codes.GID_SO3xR3] == "SO3xR3"
    assert codes.GROUP_NAMES[codes.GID_SE2] == "SE2" and codes.GROUP_NAMES[codes.GID_SO2xR2] == "SO2xR2"
    assert list(codes.BODY_TWIST) == [GROUPS[g].TWIST == "body" for g in GROUPS]
    # the compiled test (an integer constant) says the same for every group id, from Python
    # and from compiled code
    from numba import njit
    probe = njit(lambda g: codes.uses_body_twist(g))
    for gid, g in enumerate(GROUPS):
        assert codes.uses_body_twist(gid) == probe(gid) == (GROUPS[g].TWIST == "body")


@pytest.mark.parametrize("name", list(GROUPS))
def test_interface_laws(name):
    """exp/log, compose/inverse, dexp/dexpinv through the shared signatures."""
    G = GROUPS[name]
    rng = np.random.default_rng(3)
    X = np.zeros(6)
    ax = list(interface.algebra_axes(G))       # planar groups, R3: the algebra is a subspace
    X[ax] = rng.normal(size=len(ax)) * 0.7
    R, r = G.exp(X)
    np.testing.assert_allclose(G.log(R, r), X, atol=1e-13)
    Ri, ri = G.inverse(R, r)
    I, z = G.compose(R, r, Ri, ri)
    np.testing.assert_allclose(I, np.eye(3), atol=1e-14)
    np.testing.assert_allclose(z, 0, atol=1e-14)
    Y = np.zeros(6)
    Y[ax] = rng.normal(size=len(ax))
    out = np.zeros(6)
    G.dexp_apply_into(X, Y, out)
    back = np.zeros(6)
    G.dexpinv_apply_into(X, out, back)
    np.testing.assert_allclose(back, Y, atol=1e-13)
    R2, r2 = np.zeros((3, 3)), np.zeros(3)
    G.exp_into(X, R2, r2)
    assert np.array_equal(R2, R) and np.array_equal(r2, r)


def test_missing_operations_detects_a_departure():
    from exudyn_lie.groups import so3
    probs = dict(interface.missing_operations(so3))
    assert "exp_into" in probs and "parameters" in probs["exp_into"]
