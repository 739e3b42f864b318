"""Embedded pairs and continuous extensions of the catalogue (issue 18): the orders of
b, b_hat and of the dense weights (exact order conditions and measured convergence),
b(1) = b, FSAL from the coefficients, and corrupted extensions refused."""
from fractions import Fraction

import numpy as np
import pytest

from exudyn_lie.integrators import tableau as T
from exudyn_lie.integrators.tableau import ButcherTableau, ContinuousExtension, METHODS, PAIRS

ALL = tuple(METHODS) + tuple(m for m in PAIRS if m not in METHODS)
DENSE = [m for m in ALL if m.dense is not None]


def test_pairs_are_exactly_the_tableaus_with_embedded_weights():
    assert {m.name for m in ALL if m.b_hat is not None} == {m.name for m in PAIRS}


def test_the_catalogue_has_the_three_pairs():
    names = {m.name for m in PAIRS if m.b_hat is not None}
    assert {"DOPRI5", "BS3", "Vern6"} <= names
    assert any(m.order >= 6 for m in PAIRS)
    assert {m.name for m in DENSE} >= {"DOPRI5", "BS3", "Vern6"}


@pytest.mark.parametrize("m", PAIRS, ids=lambda m: m.name)
def test_embedded_weights_have_exactly_their_order(m):
    """b has order m.order (exact rationals) and b_hat exactly m.order_hat = order - 1 (the
    construction checked b_hat up to order_hat exactly; here the conditions of order_hat + 1
    must fail, otherwise the error estimate would be of higher order than claimed)."""
    A, b, c = m._exact_coeffs
    assert m.exact and T.achieved_order(A, b) == m.order
    assert T.achieved_order(m.A.tolist(), m.b_hat.tolist()) == m.order_hat == m.order - 1
    assert not np.array_equal(m.b, m.b_hat)


def test_embedded_order_claim_is_checked():
    A, b, c = T.BS3._exact_coeffs
    with pytest.raises(ValueError, match=r"order condition of order 3 violated for weights b_hat"):
        ButcherTableau(name="bs3_overclaimed", A=A, b=b, c=c, order=3,
                       b_hat=["7/24", "1/4", "1/3", "1/8"], order_hat=3)


def test_fsal_is_derived_from_the_coefficients():
    assert T.DOPRI5.fsal and T.BS3.fsal and T.Vern6.fsal
    assert not any(m.fsal for m in (T.RK4, T.RK38, T.RK6, T.Heun, T.ExplicitEuler))
    # a user's FSAL tableau under any name, and the same tableau with the last row changed
    A, b, c = T.BS3._exact_coeffs
    assert ButcherTableau(name="mine", A=A, b=b, c=c, order=3).fsal
    A2 = [list(r) for r in A]
    A2[3] = [Fraction(1, 9), Fraction(4, 9), Fraction(4, 9), 0]
    assert not ButcherTableau(name="mine2", A=A2, b=b, c=c, order=3).fsal


# ------------------------------------------------------------------------ dense output
def _extended(m):
    """(A_ext, c_ext) of the s stages plus the dense extra stages (floats)."""
    d = m.dense
    s, k = m.stages, m.stages + m.dense.extra_stages
    A = np.zeros((k, k))
    A[:s, :s] = m.A
    c = np.zeros(k)
    c[:s] = m.c
    if d.extra_stages:
        A[s:, :] = d.A_extra
        c[s:] = d.c_extra
    return A, c


@pytest.mark.parametrize("m", DENSE, ids=lambda m: m.name)
def test_dense_weights_order_and_end_value(m):
    """b(1) = b (extra stages: 0) and b(0) = 0 to round-off of the polynomial coefficients;
    the continuous order conditions (exact at construction) hold up to the claimed order
    and fail at the next: the order is exactly dense.order."""
    d, s = m.dense, m.stages
    eps = np.finfo(float).eps
    scale = np.abs(d.P).sum(axis=1)
    w1 = d.weights(1.0)
    assert np.all(np.abs(w1[:s] - m.b) <= 4 * eps * scale[:s])
    assert np.all(np.abs(w1[s:]) <= 4 * eps * scale[s:])
    assert np.all(d.weights(0.0) == 0.0)
    A, _ = _extended(m)
    res = T.continuous_order_residuals(A.tolist(), d.P.tolist(), d.order + 1)
    big = np.abs(A).max() ** 2 * np.abs(d.P).max() * 1e-13
    assert max(abs(r) for n, _, _, r in res if n <= d.order) < big
    assert max(abs(r) for n, _, _, r in res if n == d.order + 1) > 1e-6


def test_corrupted_dense_output_is_refused():
    A, b, c = T.BS3._exact_coeffs
    good = [[1, "-4/3", "5/9"], [0, 1, "-2/3"], [0, "4/3", "-8/9"], [0, -1, 1]]
    ButcherTableau(name="ok", A=A, b=b, c=c, order=3, dense=ContinuousExtension(order=3, P=good))
    bad_end = [row[:] for row in good]
    bad_end[0][2] = "4/9"                                   # b_1(1) != b_1
    with pytest.raises(ValueError, match=r"b_1\(1\)"):
        ButcherTableau(name="bad", A=A, b=b, c=c, order=3,
                       dense=ContinuousExtension(order=3, P=bad_end))
    # keep b(1) = b but break an order-2 condition (move weight between theta^2, theta^3)
    bad = [row[:] for row in good]                          # move 1/10 of theta^2 weight
    bad[1][1], bad[1][2] = "11/10", "-23/30"                # from stage 3 to stage 2, and
    bad[2][1], bad[2][2] = "37/30", "-71/90"                # back in theta^3: b(1) and the
                                                            # order-1 sums stay, c differs
    with pytest.raises(ValueError, match=r"continuous order condition of order 2"):
        ButcherTableau(name="bad", A=A, b=b, c=c, order=3,
                       dense=ContinuousExtension(order=3, P=bad))
    with pytest.raises(ValueError, match=r"continuous order condition of order 4"):
        ButcherTableau(name="over", A=A, b=b, c=c, order=3,
                       dense=ContinuousExtension(order=4, P=good))


# ---------------------------------------------- measured order of the dense output (R^n)
def _bernoulli(t, y):
    """y' = -2 t y^2 + y: with u = 1/y, u' = 2 t - u, so y = 1/(2 t - 2 + 3 e^-t), y(0) = 1."""
    return -2.0 * t * y * y + y


def _bernoulli_exact(t):
    return 1.0 / (2.0 * t - 2.0 + 3.0 * np.exp(-t))


def _exact_extended(m):
    """A_ext, c_ext, P of the method and its dense output as long doubles, from the exact
    rationals (the double-rounded coefficients of Verner's pair, up to 2e4 in size, would
    add an O(eps |P| h) error that hides the h^7 behaviour)."""
    A, b, c = m._exact_coeffs
    P, Ax, cx = m.dense._exact_coeffs
    s, k = len(b), len(P)
    ld = np.longdouble

    def q(x):
        x = Fraction(x)
        return ld(x.numerator) / ld(x.denominator)

    A_ext = np.zeros((k, k), dtype=ld)
    c_ext = np.zeros(k, dtype=ld)
    for i in range(s):
        c_ext[i] = q(c[i])
        for j in range(s):
            A_ext[i, j] = q(A[i][j])
    for i in range(k - s):
        c_ext[s + i] = q(cx[i])
        for j in range(k):
            A_ext[s + i, j] = q(Ax[i][j])
    P_ = np.array([[q(x) for x in row] for row in P], dtype=ld)
    return A_ext, c_ext, P_


def _dense_step(m, f, t, y, h, thetas):
    """One RK step from (t, y) and its continuous extension at the given thetas (long
    double arithmetic, exact coefficients)."""
    A, c, P = _exact_extended(m)
    k = np.zeros(len(c), dtype=np.longdouble)
    for j in range(len(c)):
        k[j] = f(t + c[j] * h, y + h * (A[j, :j] @ k[:j]))
    out = []
    for th in thetas:
        w = P @ (th ** np.arange(1, P.shape[1] + 1, dtype=np.longdouble))
        out.append(y + h * (w @ k))
    return np.array(out)


@pytest.mark.parametrize("m", DENSE, ids=lambda m: m.name)
def test_dense_output_converges_at_its_order(m):
    """Local error of the interpolant started from the exact y(t0):
    max over theta in (0, 1) of |y0 + h sum_j b_j(theta) k_j - y(t0 + theta h)| = C h^(q+1)
    (long double arithmetic, round-off ~1e-19).  Fitted slope of log(error) over log(h)
    on the 4 smallest steps of a halving sequence whose errors stay above 1e-16: within
    [q + 1 - 0.3, q + 1 + 0.5]."""
    q = m.dense.order
    ld = np.longdouble
    t0 = ld(4) / 10
    y0 = _bernoulli_exact(t0)
    thetas = np.linspace(ld(0.05), ld(0.95), 19)
    hs, errs = [], []
    for h in ld(0.4) * ld(2) ** -np.arange(0, 14):
        y = _dense_step(m, _bernoulli, t0, y0, h, thetas)
        e = np.max(np.abs(y - _bernoulli_exact(t0 + thetas * h)))
        if e < 1e-16:
            break
        hs.append(float(h))
        errs.append(float(e))
    assert len(hs) >= 4, (m.name, hs, errs)
    slope = np.polyfit(np.log(hs[-4:]), np.log(errs[-4:]), 1)[0]
    assert q + 1 - 0.3 <= slope <= q + 1 + 0.5, (m.name, hs, errs, slope)
