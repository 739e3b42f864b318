"""Explicit Runge-Kutta (Butcher) tableaus: a frozen, self-checking type and the catalogue.

A :class:`ButcherTableau` holds the coefficients ``a_jl, b_j, c_j`` of an explicit
``s``-stage method (the coefficients of eq. (MK1) in appendix B of the paper).  On
construction it checks

* ``A`` is square ``s x s`` and strictly lower triangular (explicit method),
* the row-sum condition ``c_j = sum_l a_jl``,
* consistency ``sum_j b_j = 1``,
* every order condition up to the claimed ``order``: for each rooted tree ``t`` with
  ``|t| <= order`` the elementary weight must equal ``1 / gamma(t)`` (Butcher's theory;
  1, 1, 2, 4, 9, 20 trees of order 1..6, see :func:`rooted_trees`),

and raises :class:`ValueError` naming the method and the first violated condition.  The
check is done in exact rational arithmetic when every coefficient is given exactly
(``int``, :class:`fractions.Fraction` or a string such as ``"-56/15"``), otherwise in
floating point with a tolerance.

The arrays ``A``, ``b``, ``c`` (and the optional embedded weights ``b_hat``) are
``float64``, C-contiguous and read-only.  :meth:`ButcherTableau.arrays` returns writable
copies for code that wants plain arrays (e.g. to pass into numba kernels without the
read-only type signature).

Adding a method touches one place: append it to :data:`METHODS`.
"""
from dataclasses import dataclass, field
from fractions import Fraction
from functools import lru_cache
from numbers import Rational
from typing import Optional, Tuple

import numpy as np

__all__ = [
    "ButcherTableau",
    "METHODS",
    "get_method",
    "method_names",
    "rooted_trees",
    "order_condition_residuals",
    "achieved_order",
    "quadrature_order",
    "ExplicitEuler",
    "ExplicitMidpoint",
    "Heun",
    "RK3",
    "RK4",
    "RK38",
    "DOPRI5",
    "RK6",
    "extrapolated_euler",
]

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


# --------------------------------------------------------------------------- the tableau type
@dataclass(frozen=True, eq=False)
class ButcherTableau:
    """Explicit Runge-Kutta method ``(A, b, c)`` of claimed ``order`` (self-checking).

    Parameters
    ----------
    name : str
        Unique (case-insensitive) method name used by :func:`get_method`.
    A, b, c : array-like
        Butcher coefficients; exact entries (int, Fraction, "p/q") enable an exact check.
    order : int
        Classical order claimed for the method; every order condition up to it is checked.
    b_hat, order_hat : optional
        Embedded weights and their order (for error estimation / step control).
    aliases : tuple of str
        Alternative names accepted by :func:`get_method`.
    description : str
        Reference / remark.
    """

    name: str
    A: np.ndarray
    b: np.ndarray
    c: np.ndarray
    order: int
    b_hat: Optional[np.ndarray] = None
    order_hat: Optional[int] = None
    aliases: Tuple[str, ...] = ()
    description: str = ""
    exact: bool = field(default=False, init=False)

    def __post_init__(self):
        name = self.name

        def fail(msg):
            raise ValueError(f"Butcher tableau '{name}': {msg}")

        if not isinstance(name, str) or not name:
            raise ValueError("Butcher tableau: name must be a non-empty string")
        try:
            A_raw = [[_to_exact(x) for x in row] for row in self.A]
            b_raw = [_to_exact(x) for x in self.b]
            c_raw = [_to_exact(x) for x in self.c]
        except (TypeError, ValueError, ZeroDivisionError) as exc:
            fail(f"coefficients are not numbers ({exc})")
        s = len(b_raw)
        if s == 0:
            fail("no stages")
        if len(A_raw) != s or any(len(row) != s for row in A_raw):
            fail(f"A must be {s}x{s} (s = len(b) = {s})")
        if len(c_raw) != s:
            fail(f"c must have {s} entries, got {len(c_raw)}")
        if not isinstance(self.order, (int, np.integer)) or self.order < 1:
            fail(f"order must be a positive integer, got {self.order!r}")
        if self.order > MAX_CHECK_ORDER:
            fail(f"claimed order {self.order} exceeds the checkable maximum {MAX_CHECK_ORDER}")
        if any(not np.isfinite(float(x)) for x in [*b_raw, *c_raw, *(y for r in A_raw for y in r)]):
            fail("non-finite coefficient")

        exact = _is_exact(A_raw) and _is_exact(b_raw) and _is_exact(c_raw)
        scale = _coef_scale(A_raw, b_raw)

        # explicit: strictly lower triangular A
        for j in range(s):
            for l in range(j, s):
                if A_raw[j][l] != 0:
                    fail(f"A is not strictly lower triangular (explicit method required): "
                         f"a[{j + 1},{l + 1}] = {float(A_raw[j][l])!r} != 0")
        # row-sum condition c_j = sum_l a_jl
        for j in range(s):
            rs = sum(A_raw[j], 0 * A_raw[j][0]) if s else 0
            if not _residual_ok(rs - c_raw[j], exact, scale):
                fail(f"row-sum condition violated: c[{j + 1}] = {float(c_raw[j])!r} but "
                     f"sum_l a[{j + 1},l] = {float(rs)!r}")
        # consistency
        sb = sum(b_raw, 0 * b_raw[0])
        if not _residual_ok(sb - 1, exact, scale):
            fail(f"consistency condition sum(b) = 1 violated: sum(b) = {float(sb)!r}")
        # order conditions (rooted trees) up to the claimed order
        self._check_order_conditions(A_raw, b_raw, int(self.order), exact, scale, "b", fail)

        b_hat_arr = None
        if self.b_hat is not None:
            bh_raw = [_to_exact(x) for x in self.b_hat]
            if len(bh_raw) != s:
                fail(f"b_hat must have {s} entries")
            if self.order_hat is None:
                fail("b_hat given without order_hat")
            ex_h = exact and _is_exact(bh_raw)
            self._check_order_conditions(A_raw, bh_raw, int(self.order_hat), ex_h, scale,
                                         "b_hat", fail)
            b_hat_arr = _readonly([float(x) for x in bh_raw])
        elif self.order_hat is not None:
            fail("order_hat given without b_hat")

        set_ = object.__setattr__
        set_(self, "A", _readonly([[float(x) for x in row] for row in A_raw]))
        set_(self, "b", _readonly([float(x) for x in b_raw]))
        set_(self, "c", _readonly([float(x) for x in c_raw]))
        set_(self, "b_hat", b_hat_arr)
        set_(self, "order", int(self.order))
        set_(self, "aliases", tuple(self.aliases))
        set_(self, "exact", bool(exact))
        set_(self, "_exact_coeffs", (A_raw, b_raw, c_raw) if exact else None)

    @staticmethod
    def _check_order_conditions(A_raw, b_raw, order, exact, scale, wname, fail):
        for n, tstr, res in _residuals(A_raw, b_raw, order):
            if not _residual_ok(res, exact, scale):
                fail(f"order condition of order {n} violated for weights {wname}, tree {tstr}: "
                     f"Phi(t) - 1/gamma(t) = {float(res):.3e}"
                     + (" (i.e. sum_j b_j c_j^%d = 1/%d)" % (n - 1, n) if tstr.count("o") == n - 1
                        and tstr.startswith("[") and "[" not in tstr[1:] else ""))

    # ----------------------------------------------------------------- derived quantities
    @property
    def stages(self):
        """Number of stages ``s``."""
        return len(self.b)

    @property
    def active_stages(self):
        """Stage indices whose evaluation can influence the step result.

        A stage is needed if its weight ``b_j`` is non-zero or a needed later stage uses it
        (``a_lj != 0``).  E.g. the 7th (FSAL) stage of DOPRI5 has ``b_7 = 0`` and is unused
        by the fixed-step 5th-order update.
        """
        s = self.stages
        need = [self.b[j] != 0.0 for j in range(s)]
        for j in range(s - 1, -1, -1):
            if not need[j]:
                need[j] = any(need[l] and self.A[l, j] != 0.0 for l in range(j + 1, s))
        return tuple(j for j in range(s) if need[j])

    @property
    def quadrature_order(self):
        """Order of the quadrature (b, c) — the error order for ``ydot = f(t)``."""
        if self._exact_coeffs is not None:
            _, b_raw, c_raw = self._exact_coeffs
            return quadrature_order(b_raw, c_raw)
        return quadrature_order(self.b, self.c)

    def achieved_order(self, max_order=MAX_CHECK_ORDER):
        """Highest order <= ``max_order`` whose conditions are all satisfied (>= ``order``
        by construction; a method of order ``MAX_CHECK_ORDER`` reports exactly that)."""
        if self._exact_coeffs is not None:
            A_raw, b_raw, _ = self._exact_coeffs
            return achieved_order(A_raw, b_raw, max_order)
        return achieved_order(self.A, self.b, max_order)

    def arrays(self):
        """Writable float64 copies ``(A, b, c)`` (plain arrays, e.g. for numba kernels)."""
        return (np.array(self.A, dtype=np.float64), np.array(self.b, dtype=np.float64),
                np.array(self.c, dtype=np.float64))

    def matches(self, name):
        key = name.strip().lower()
        return key == self.name.lower() or key in (a.lower() for a in self.aliases)

    def __repr__(self):
        return f"ButcherTableau(name={self.name!r}, stages={self.stages}, order={self.order})"


def _F(*xs):
    return [Fraction(x) for x in xs]


# --------------------------------------------------------------------------- the catalogue
ExplicitEuler = ButcherTableau(
    name="ExplicitEuler", order=1,
    A=[[0]], b=[1], c=[0],
    aliases=("Euler", "RK1"),
    description="Forward Euler.",
)

ExplicitMidpoint = ButcherTableau(
    name="ExplicitMidpoint", order=2,
    A=[[0, 0],
       ["1/2", 0]],
    b=[0, 1], c=[0, "1/2"],
    aliases=("Midpoint", "RK2"),
    description="Explicit midpoint rule; the paper's two-stage illustration in section "
                "'significance of the configuration space' (called 'explicit trapezoidal' "
                "there): k1 = f(t, x), k2 = f(t + h/2, x + h/2 k1), x+ = x + h k2.",
)

Heun = ButcherTableau(
    name="Heun", order=2,
    A=[[0, 0],
       [1, 0]],
    b=["1/2", "1/2"], c=[0, 1],
    aliases=("ExplicitTrapezoidal",),
    description="Heun's method (explicit trapezoidal rule).",
)

RK3 = ButcherTableau(
    name="RK3", order=3,
    A=[[0, 0, 0],
       ["1/2", 0, 0],
       [-1, 2, 0]],
    b=["1/6", "2/3", "1/6"], c=[0, "1/2", 1],
    aliases=("Kutta3",),
    description="Kutta's third-order method (1901).",
)

RK4 = ButcherTableau(
    name="RK4", order=4,
    A=[[0, 0, 0, 0],
       ["1/2", 0, 0, 0],
       [0, "1/2", 0, 0],
       [0, 0, 1, 0]],
    b=["1/6", "1/3", "1/3", "1/6"], c=[0, "1/2", "1/2", 1],
    aliases=("RK44", "ClassicalRK4"),
    description="The classical fourth-order Runge-Kutta method (used in the paper's examples).",
)

RK38 = ButcherTableau(
    name="RK38", order=4,
    A=[[0, 0, 0, 0],
       ["1/3", 0, 0, 0],
       ["-1/3", 1, 0, 0],
       [1, -1, 1, 0]],
    b=["1/8", "3/8", "3/8", "1/8"], c=[0, "1/3", "2/3", 1],
    aliases=("ThreeEighths",),
    description="Kutta's 3/8 rule.",
)

DOPRI5 = ButcherTableau(
    name="DOPRI5", order=5,
    A=[[0, 0, 0, 0, 0, 0, 0],
       ["1/5", 0, 0, 0, 0, 0, 0],
       ["3/40", "9/40", 0, 0, 0, 0, 0],
       ["44/45", "-56/15", "32/9", 0, 0, 0, 0],
       ["19372/6561", "-25360/2187", "64448/6561", "-212/729", 0, 0, 0],
       ["9017/3168", "-355/33", "46732/5247", "49/176", "-5103/18656", 0, 0],
       ["35/384", 0, "500/1113", "125/192", "-2187/6784", "11/84", 0]],
    b=["35/384", 0, "500/1113", "125/192", "-2187/6784", "11/84", 0],
    c=[0, "1/5", "3/10", "4/5", "8/9", 1, 1],
    b_hat=["5179/57600", 0, "7571/16695", "393/640", "-92097/339200", "187/2100", "1/40"],
    order_hat=4,
    aliases=("DormandPrince", "DP5", "RK45"),
    description="Dormand-Prince 5(4), used as a fixed-step method with the 5th-order "
                "weights (b_7 = 0, so the FSAL stage is not evaluated); the embedded "
                "4th-order weights are kept in b_hat.",
)

RK6 = ButcherTableau(
    name="RK6", order=6,
    A=[[0, 0, 0, 0, 0, 0, 0],
       ["1/3", 0, 0, 0, 0, 0, 0],
       [0, "2/3", 0, 0, 0, 0, 0],
       ["1/12", "1/3", "-1/12", 0, 0, 0, 0],
       ["-1/16", "9/8", "-3/16", "-3/8", 0, 0, 0],
       [0, "9/8", "-3/8", "-3/4", "1/2", 0, 0],
       ["9/44", "-9/11", "63/44", "18/11", 0, "-16/11", 0]],
    b=["11/120", 0, "27/40", "27/40", "-4/15", "-4/15", "11/120"],
    c=[0, "1/3", "2/3", "1/3", "1/2", "1/2", 1],
    aliases=("Butcher6",),
    description="Butcher's sixth-order, seven-stage explicit method (1964).",
)

#: The catalogue.  Adding a method = appending a tableau here.
METHODS = (ExplicitEuler, ExplicitMidpoint, Heun, RK3, RK4, RK38, DOPRI5, RK6)


def extrapolated_euler(order, name=None):
    """Explicit Euler with polynomial (Aitken-Neville) extrapolation on the harmonic
    step sequence n_j = j, j = 1..order, written as one explicit RK tableau of the given
    order with 1 + order (order - 1)/2 stages, in exact rationals.

    Not part of the catalogue: a source of explicit methods of any order up to
    ``MAX_CHECK_ORDER``, e.g. to check that order-dependent code (order conditions,
    convergence tests) handles orders beyond the catalogue.  The result is
    ``sum_j gamma_j T_j`` with ``T_j`` the result of ``n_j`` Euler substeps of size
    ``h/n_j`` and the Lagrange weights at 0 of the nodes ``1/n_j``:
    ``gamma_j = prod_{i != j} n_j/(n_j - n_i)``.
    """
    k = int(order)
    if not 1 <= k <= MAX_CHECK_ORDER:
        raise ValueError(f"extrapolated_euler: order must be in 1..{MAX_CHECK_ORDER}")
    ns = list(range(1, k + 1))
    gam = []
    for j, nj in enumerate(ns):
        g = Fraction(1)
        for i, ni in enumerate(ns):
            if i != j:
                g *= Fraction(nj, nj - ni)
        gam.append(g)
    s = 1 + sum(n - 1 for n in ns)
    A = [[Fraction(0)] * s for _ in range(s)]
    b = [Fraction(0)] * s
    c = [Fraction(0)] * s
    row = 1
    for nj, gj in zip(ns, gam):
        w = Fraction(1, nj)
        b[0] += gj * w                     # the first Euler substep of every sequence
        first = row
        for m in range(1, nj):             # substeps 2..n_j: stage value after m substeps
            A[row][0] = w
            for l in range(first, row):
                A[row][l] = w
            c[row] = m * w
            b[row] = gj * w
            row += 1
    return ButcherTableau(name=name or f"ExtrapolatedEuler{k}", A=A, b=b, c=c, order=k,
                          description=f"explicit Euler extrapolated on n = 1..{k}")


def _check_catalogue(methods):
    seen = {}
    for m in methods:
        for key in (m.name, *m.aliases):
            k = key.lower()
            if k in seen:
                raise ValueError(f"method name '{key}' of '{m.name}' clashes with "
                                 f"'{seen[k]}'")
            seen[k] = m.name


_check_catalogue(METHODS)


def method_names():
    """Canonical names of the catalogue methods, in catalogue order."""
    return tuple(m.name for m in METHODS)


def _name_key(name):
    """A method name as compared: case, blanks, '-' and '_' ignored ('rk-4' = 'RK4')."""
    return "".join(ch for ch in name.lower() if ch not in " \t-_")


def get_method(name):
    """The catalogue tableau called ``name``: case-insensitive, ignoring blanks, '-' and
    '_', and accepting every tableau's aliases (``'rk4'``, ``'RK44'`` -> RK4, ``'RK45'``,
    ``'dopri5'`` -> DOPRI5).  An unknown name raises ValueError with the catalogue.

    A :class:`ButcherTableau` passed in is returned unchanged.
    """
    if isinstance(name, ButcherTableau):
        return name
    if not isinstance(name, str):
        raise TypeError(f"method name must be a string or ButcherTableau, got {type(name)}")
    key = _name_key(name)
    for m in METHODS:
        if key in (_name_key(n) for n in (m.name,) + tuple(m.aliases)):
            return m
    raise ValueError(f"unknown integration method '{name}'; available: "
                     + ", ".join(method_names()) + " (case-insensitive; aliases: "
                     + ", ".join(f"{a} = {m.name}" for m in METHODS for a in m.aliases) + ")")
