"""Butcher tableau catalogue: self-checks, corrupted tableaus, name lookup."""
from fractions import Fraction

import numpy as np
import pytest

from exudyn_lie.integrators import tableau as T
from exudyn_lie.integrators.tableau import ButcherTableau, METHODS, get_method, method_names


@pytest.mark.parametrize("m", METHODS, ids=lambda m: m.name)
def test_catalogue_method_self_consistent(m):
    s = m.stages
    assert m.A.shape == (s, s) and m.b.shape == (s,) and m.c.shape == (s,)
    for arr in (m.A, m.b, m.c):
        assert arr.dtype == np.float64 and arr.flags.c_contiguous
        assert not arr.flags.writeable
        with pytest.raises(ValueError):
            arr[0] = 1.0
    assert np.all(np.triu(m.A) == 0.0)                    # explicit
    np.testing.assert_allclose(m.A.sum(axis=1), m.c, atol=1e-15)
    assert m.b.sum() == pytest.approx(1.0, abs=1e-15)
    # the claimed order is exactly the order (the conditions of order+1 fail; they are
    # generated up to MAX_CHECK_ORDER, see test_achieved_order_up_to_max_check_order)
    assert m.order < T.MAX_CHECK_ORDER
    assert m.achieved_order() == m.order
    # the catalogue is given in rationals, except Exudyn's RK67 (Lobatto nodes: sqrt(5))
    assert m.exact or m.name == "RK67"
    A, b, c = m.arrays()
    assert A.flags.writeable and np.array_equal(A, m.A) and np.array_equal(c, m.c)
    with pytest.raises(Exception):
        m.order = 7                                         # frozen
    # the order conditions also hold in floating point (float re-construction passes)
    ButcherTableau(name=m.name + "_float", A=m.A.tolist(), b=m.b.tolist(), c=m.c.tolist(),
                   order=m.order)


def test_tree_counts():
    # number of rooted trees of order 1..8 (OEIS A000081)
    counts = [sum(1 for n, _ in T.rooted_trees(8) if n == k) for k in range(1, 9)]
    assert counts == [1, 1, 2, 4, 9, 20, 48, 115]


def test_achieved_order_checks_up_to_max_check_order():
    """achieved_order() and the construction check use every generated order
    (MAX_CHECK_ORDER), not one less."""
    import inspect
    assert inspect.signature(T.achieved_order).parameters["max_order"].default == T.MAX_CHECK_ORDER
    assert (inspect.signature(ButcherTableau.achieved_order).parameters["max_order"].default
            == T.MAX_CHECK_ORDER)
    with pytest.raises(ValueError, match="up to order"):
        T.achieved_order(T.RK4.A.tolist(), T.RK4.b.tolist(), T.MAX_CHECK_ORDER + 1)


@pytest.mark.parametrize("k", range(1, T.MAX_CHECK_ORDER + 1))
def test_achieved_order_up_to_max_check_order(k):
    """Explicit Euler extrapolated on n = 1..k has order exactly k: the order is found for
    every k up to MAX_CHECK_ORDER, and claiming k + 1 fails (by the order-(k+1) conditions,
    or because k + 1 is beyond what can be checked)."""
    m = T.extrapolated_euler(k)
    assert m.stages == 1 + k * (k - 1) // 2 and m.exact
    assert m.achieved_order() == k
    A, b, c = m._exact_coeffs                     # the exact rationals of the tableau
    if k < T.MAX_CHECK_ORDER:
        with pytest.raises(ValueError, match=rf"order condition of order {k + 1}"):
            ButcherTableau(name="overclaimed", A=A, b=b, c=c, order=k + 1)
    else:
        with pytest.raises(ValueError, match="exceeds the checkable maximum"):
            ButcherTableau(name="overclaimed", A=A, b=b, c=c, order=k + 1)


def test_dopri5_embedded_and_active_stages():
    m = get_method("DOPRI5")
    assert m.b_hat is not None and m.order_hat == 4
    assert T.achieved_order(m.A.tolist(), m.b_hat.tolist()) == 4
    assert m.active_stages == (0, 1, 2, 3, 4, 5)              # FSAL stage unused (b_7 = 0)
    assert get_method("ExplicitMidpoint").active_stages == (0, 1)   # b_1 = 0 but used by stage 2


def test_quadrature_orders():
    q = {m.name: m.quadrature_order for m in METHODS}
    assert q["RK3"] == 4          # Kutta's RK3 uses Simpson's rule
    assert all(q[m.name] >= m.order for m in METHODS)


def _rk4_exact():
    return dict(A=[[0, 0, 0, 0], ["1/2", 0, 0, 0], [0, "1/2", 0, 0], [0, 0, 1, 0]],
                b=["1/6", "1/3", "1/3", "1/6"], c=[0, "1/2", "1/2", 1])


def test_corrupted_b_raises():
    d = _rk4_exact()
    d["b"] = ["1/6", "1/3", "1/3", "1/5"]
    with pytest.raises(ValueError, match=r"'broken'.*sum\(b\) = 1"):
        ButcherTableau(name="broken", order=4, **d)


def test_corrupted_c_raises():
    d = _rk4_exact()
    d["c"] = [0, "1/2", "1/3", 1]
    with pytest.raises(ValueError, match=r"'broken'.*row-sum.*c\[3\]"):
        ButcherTableau(name="broken", order=4, **d)


def test_non_explicit_raises():
    """Explicit or ESDIRK (explicit first stage, one diagonal gamma) only: neither an entry above the
    diagonal nor a diagonal of several values."""
    d = _rk4_exact()
    d["A"] = [[0, 0, 0, 0], ["1/4", "1/4", 0, 0], [0, "1/2", 0, 0], [0, 0, 1, 0]]
    with pytest.raises(ValueError, match=r"'broken'.*diagonally implicit.*a\[j,j\] = gamma.*0, 0.25, 0, 0"):
        ButcherTableau(name="broken", order=4, **d)
    d["A"] = [[0, 0, 0, 0], ["1/2", 0, "1/4", 0], [0, "1/2", 0, 0], [0, 0, 1, 0]]
    with pytest.raises(ValueError, match=r"'broken'.*not lower triangular.*a\[2,3\]"):
        ButcherTableau(name="broken", order=4, **d)


def test_wrong_order_claim_raises():
    d = _rk4_exact()
    with pytest.raises(ValueError, match=r"'overclaimed'.*order 5.*sum_j b_j c_j\^4 = 1/5"):
        ButcherTableau(name="overclaimed", order=5, **d)


def test_subtly_wrong_high_order_tableau_caught():
    """Perturb RK6 keeping row sums, sum(b) and the quadrature conditions: still caught."""
    A = [[Fraction(x).limit_denominator(10**6) for x in row] for row in T.RK6.A]
    b = [Fraction(x).limit_denominator(10**6) for x in T.RK6.b]
    c = [Fraction(x).limit_denominator(10**6) for x in T.RK6.c]
    ButcherTableau(name="rk6_copy", A=A, b=b, c=c, order=6)         # exact copy passes
    eps = Fraction(1, 1000)
    A[6][1] += eps                                                   # keep row sum:
    A[6][0] -= eps
    with pytest.raises(ValueError, match=r"'rk6_bad'.*order condition of order \d"):
        ButcherTableau(name="rk6_bad", A=A, b=b, c=c, order=6)


def test_float_tableau_small_error_caught():
    A, b, c = T.RK4.arrays()
    A[3, 2] += 1e-7
    A[3, 0] -= 1e-7
    with pytest.raises(ValueError, match="order condition"):
        ButcherTableau(name="rk4_float_bad", A=A, b=b, c=c, order=4)


def test_shape_errors():
    with pytest.raises(ValueError, match="'x'"):
        ButcherTableau(name="x", A=[[0, 0]], b=[1], c=[0], order=1)
    with pytest.raises(ValueError, match="c must have"):
        ButcherTableau(name="x", A=[[0]], b=[1], c=[0, 0], order=1)


def test_get_method_case_insensitive_and_aliases():
    for m in METHODS:
        assert get_method(m.name) is m
        assert get_method(m.name.upper()) is m
        assert get_method(m.name.lower()) is m
        for a in m.aliases:
            assert get_method(a) is m
    assert get_method(T.RK4) is T.RK4


def test_get_method_unknown_lists_names():
    with pytest.raises(ValueError) as exc:
        get_method("RK99")
    msg = str(exc.value)
    assert "RK99" in msg
    for name in method_names():
        assert name in msg


def test_names_unique():
    keys = [k.lower() for m in METHODS for k in (m.name, *m.aliases)]
    assert len(keys) == len(set(keys))
    assert method_names() == tuple(m.name for m in METHODS)
    assert any(m.order >= 5 for m in METHODS)
    with pytest.raises(ValueError, match="clashes"):
        T._check_catalogue((T.RK4, ButcherTableau(name="rk44", A=[[0]], b=[1], c=[0], order=1)))
