"""Butcher's order conditions of explicit Runge-Kutta methods: rooted trees, elementary
weights, the residuals of every condition up to an order (exact in rational arithmetic when
the coefficients are exact), the achieved order, and the conditions of a continuous
extension (dense output).  :class:`~.butcher.ButcherTableau` checks itself with them."""
from fractions import Fraction
from functools import lru_cache
from numbers import Rational

import numpy as np

#: Highest order for which order conditions are generated on demand (trees are cheap:
#: 115 trees up to order 7, 286 up to order 8).
MAX_CHECK_ORDER = 8

_FLOAT_TOL = 1e-12


# --------------------------------------------------------------------------- rooted trees
# A rooted tree is represented canonically as a sorted tuple of its children's subtrees;
# the single-node tree is ().  Order |t| = 1 + sum |child|; density
# gamma(t) = |t| * prod gamma(child).

def _tree_order(t):
    return 1 + sum(_tree_order(ch) for ch in t)


def _tree_density(t):
    g = _tree_order(t)
    for ch in t:
        g *= _tree_density(ch)
    return g


@lru_cache(maxsize=None)
def _trees_of_order(n):
    """All rooted trees with exactly ``n`` nodes (canonical, no duplicates)."""
    if n == 1:
        return ((),)
    # children form a multiset of trees whose orders sum to n - 1
    result = set()

    def build(remaining, min_key, acc):
        if remaining == 0:
            result.add(tuple(sorted(acc)))
            return
        for m in range(1, remaining + 1):
            for sub in _trees_of_order(m):
                key = (m, sub)
                if min_key is not None and key < min_key:
                    continue
                build(remaining - m, key, acc + [sub])

    build(n - 1, None, [])
    return tuple(sorted(result))


def rooted_trees(max_order):
    """All rooted trees up to ``max_order`` as ``(order, tree)`` pairs, grouped by order."""
    if max_order > MAX_CHECK_ORDER:
        raise ValueError(f"order conditions are generated up to order {MAX_CHECK_ORDER}")
    return [(n, t) for n in range(1, max_order + 1) for t in _trees_of_order(n)]


def _tree_str(t):
    """Bracket notation: the single node is 'o', [t1 t2] a root with children t1, t2."""
    if t == ():
        return "o"
    return "[" + " ".join(_tree_str(ch) for ch in t) + "]"


def _stage_weights(A, one):
    """``g(t)`` of :func:`_elementary_weight` with a memo shared by all trees (subtrees
    recur: this makes the 286 trees up to order 8 cheap even for many stages)."""
    s = len(A)
    memo = {}

    def g(tree):
        v = memo.get(tree)
        if v is None:
            v = [one] * s
            for ch in tree:
                gc = g(ch)
                Agc = [sum((A[i][l] * gc[l] for l in range(s)), 0 * one) for i in range(s)]
                v = [v[i] * Agc[i] for i in range(s)]
            memo[tree] = v
        return v

    return g


def _elementary_weight(t, g, b, one):
    """Phi(t) = b . g(t), g(o) = 1, g([t1..tm]) = prod_k (A g(t_k)) (componentwise)."""
    gv = g(t)
    return sum((b[i] * gv[i] for i in range(len(b))), 0 * one)


def _residuals(A, b, max_order):
    """Iterator over ``(order, tree_str, Phi(t) - 1/gamma(t))`` for all trees up to
    ``max_order``, generated lazily, order by order (so a check can stop early)."""
    if max_order > MAX_CHECK_ORDER:
        raise ValueError(f"order conditions are generated up to order {MAX_CHECK_ORDER}")
    exact = _is_exact(A) and _is_exact(b)
    one = Fraction(1) if exact else 1.0
    A_ = [[(Fraction(x) if exact else float(x)) for x in row] for row in A]
    b_ = [(Fraction(x) if exact else float(x)) for x in b]
    g = _stage_weights(A_, one)
    return ((n, _tree_str(t), _elementary_weight(t, g, b_, one) - one / _tree_density(t))
            for n in range(1, max_order + 1) for t in _trees_of_order(n))


def order_condition_residuals(A, b, max_order):
    """``[(order, tree_str, Phi(t) - 1/gamma(t)), ...]`` for all trees up to max_order.

    ``A``, ``b`` may be nested lists of Fractions (exact) or floats.
    """
    return list(_residuals(A, b, max_order))


def _is_exact(x):
    if isinstance(x, (list, tuple, np.ndarray)):
        return all(_is_exact(y) for y in x)
    return isinstance(x, Rational) and not isinstance(x, bool)


def _to_exact(x):
    """int / Fraction / 'p/q' string -> Fraction; anything else -> float (inexact)."""
    if isinstance(x, str):
        return Fraction(x)
    if isinstance(x, Rational) and not isinstance(x, bool):
        return Fraction(x)
    return float(x)


def _residual_ok(res, exact, scale=1.0):
    if exact:
        return res == 0
    return abs(float(res)) <= _FLOAT_TOL * max(1.0, scale)


def achieved_order(A, b, max_order=MAX_CHECK_ORDER):
    """Largest p <= max_order (default: every order whose conditions are generated,
    ``MAX_CHECK_ORDER``) such that all order conditions up to p hold.

    Orders are checked one after the other and the check stops at the first order with
    a violated condition.
    """
    A_ = [[_to_exact(x) for x in row] for row in A]
    b_ = [_to_exact(x) for x in b]
    exact = _is_exact(A_) and _is_exact(b_)
    scale = _coef_scale(A_, b_)
    for n, _, r in _residuals(A_, b_, max_order):
        if not _residual_ok(r, exact, scale):
            return n - 1
    return max_order


def quadrature_order(b, c, max_order=12):
    """Order of the quadrature rule (b, c): largest q with sum b c^(k-1) = 1/k, k <= q."""
    b_ = [_to_exact(x) for x in b]
    c_ = [_to_exact(x) for x in c]
    exact = _is_exact(b_) and _is_exact(c_)
    q = 0
    for k in range(1, max_order + 1):
        val = sum(bj * cj ** (k - 1) for bj, cj in zip(b_, c_))
        target = Fraction(1, k) if exact else 1.0 / k
        if not _residual_ok(val - target, exact, _coef_scale([c_], b_)):
            break
        q = k
    return q


def _coef_scale(A, b):
    vals = [abs(float(x)) for row in A for x in row] + [abs(float(x)) for x in b]
    return max(vals) if vals else 1.0


def _readonly(x):
    arr = np.array(x, dtype=np.float64, order="C", copy=True)
    arr.setflags(write=False)
    return arr


def _extended_stage_matrix(A_raw, dense_A_extra, zero):
    """The ``(s + m) x (s + m)`` stage matrix: A padded with the extra-stage rows."""
    s = len(A_raw)
    m = 0 if dense_A_extra is None else len(dense_A_extra)
    A_ext = [list(row) + [zero] * m for row in A_raw]
    for row in (dense_A_extra or []):
        A_ext.append(list(row))
    return A_ext, s + m


def continuous_order_residuals(A_ext, P, max_order):
    """``[(order, tree_str, power k, residual), ...]``: for every tree with
    ``|t| <= max_order`` and every power theta^k of the dense weights,
    ``sum_j P[j, k-1] g_j(t) - [k == |t|] / gamma(t)`` (zero for an extension of order
    ``max_order``).  Exact for rational input, float otherwise."""
    exact = _is_exact(A_ext) and _is_exact(P)
    one = Fraction(1) if exact else 1.0
    A_ = [[(Fraction(x) if exact else float(x)) for x in row] for row in A_ext]
    P_ = [[(Fraction(x) if exact else float(x)) for x in row] for row in P]
    g = _stage_weights(A_, one)
    out = []
    for n in range(1, max_order + 1):
        for t in _trees_of_order(n):
            gv = g(t)
            gam = _tree_density(t)
            for k in range(1, len(P_[0]) + 1):
                val = sum((P_[j][k - 1] * gv[j] for j in range(len(P_))), 0 * one)
                out.append((n, _tree_str(t), k, val - (one / gam if k == n else 0 * one)))
    return out
