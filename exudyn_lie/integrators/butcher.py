"""The frozen, self-checking Butcher tableau (:class:`ButcherTableau`) and its continuous
extension (:class:`ContinuousExtension`); the checks are Butcher's order conditions
(:mod:`.order_conditions`).  The catalogue of methods is :mod:`.tableau`."""
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Optional, Tuple

import numpy as np

from .._memo import DiskMemo, arg_key
from . import order_conditions
from .order_conditions import (MAX_CHECK_ORDER, _coef_scale, _extended_stage_matrix, _is_exact, _readonly,
                               _residual_ok, _residuals, _to_exact, achieved_order, continuous_order_residuals,
                               quadrature_order)

# --------------------------------------------------------------------------- continuous extensions
# (dense output).  A continuous extension ("dense output") of an explicit RK
# method replaces the weights b_j by polynomials b_j(theta), 0 <= theta <= 1, so that
# y(t + theta h) ~ y + h sum_j b_j(theta) k_j  (Hairer-Norsett-Wanner I, sec. II.6).  It
# has order q when every tree t with |t| <= q satisfies the continuous order condition
#     sum_j b_j(theta) g_j(t) = theta^|t| / gamma(t)        (HNW I, Theorem II.6.1)
# i.e. coefficient-wise in theta.  Some extensions need stages beyond the s stages of the
# step ("extra stages", e.g. Verner's); they are appended to A as rows s, s+1, ... that
# may use every earlier stage, and are evaluated only when output is requested.

@dataclass(frozen=True, eq=False)
class ContinuousExtension:
    """Dense-output weights ``b_j(theta) = sum_k P[j, k] theta^(k+1)`` of order ``order``.

    Parameters
    ----------
    order : int
        Order of the interpolant (every continuous order condition up to it is checked
        by the :class:`ButcherTableau` that owns it).
    P : array-like, shape (s + m, degree)
        Polynomial coefficients per stage, lowest power (theta^1) first; ``s`` stages of
        the step plus ``m`` extra stages.  ``b_j(1) = b_j`` (and 0 for extra stages).
    A_extra : array-like, shape (m, s + m), optional
        Coupling rows of the extra stages (strictly lower triangular in the extended
        ``(s + m) x (s + m)`` matrix); ``c_extra`` their nodes (row sums).
    source : str
        Reference.
    """

    order: int
    P: np.ndarray
    A_extra: Optional[np.ndarray] = None
    c_extra: Optional[np.ndarray] = None
    source: str = ""

    @property
    def extra_stages(self):
        """Number ``m`` of stages evaluated only for dense output."""
        return 0 if self.A_extra is None else len(self.A_extra)

    @property
    def degree(self):
        """Degree of the polynomials ``b_j(theta)``."""
        return int(np.asarray(self.P).shape[1])

    def weights(self, theta):
        """``b_j(theta)`` for all ``s + m`` stages (float64 array)."""
        P = np.asarray(self.P, dtype=np.float64)
        th = float(theta)
        powers = th ** np.arange(1, P.shape[1] + 1)
        return P @ powers


_MEMO = DiskMemo("tableau", __file__, order_conditions.__file__)     # both compute what it keeps


def _checked(args, check):
    """Run ``check()`` (raises on a violated condition) unless the same check of the same
    exact coefficients passed before (kept on disk, :mod:`exudyn_lie._memo`)."""
    _MEMO.get(arg_key(*args), lambda: check() or True)


def _check_continuous_extension(dense, A_raw, b_raw, exact, scale, fail):
    """Validate ``dense`` against the method; returns the float arrays to store."""
    if not isinstance(dense, ContinuousExtension):
        fail(f"dense must be a ContinuousExtension, got {type(dense).__name__}")
    s = len(b_raw)
    try:
        P_raw = [[_to_exact(x) for x in row] for row in dense.P]
        Ax_raw = (None if dense.A_extra is None else
                  [[_to_exact(x) for x in row] for row in dense.A_extra])
        cx_raw = None if dense.c_extra is None else [_to_exact(x) for x in dense.c_extra]
    except (TypeError, ValueError, ZeroDivisionError) as exc:
        fail(f"dense-output coefficients are not numbers ({exc})")
    m = 0 if Ax_raw is None else len(Ax_raw)
    if (cx_raw is None) != (Ax_raw is None) or (cx_raw is not None and len(cx_raw) != m):
        fail("dense output: A_extra and c_extra must be given together, one node per row")
    if len(P_raw) != s + m or len({len(row) for row in P_raw}) != 1:
        fail(f"dense output: P must have {s + m} rows (stages + extra stages) of equal length")
    if not isinstance(dense.order, (int, np.integer)) or not 1 <= dense.order <= MAX_CHECK_ORDER:
        fail(f"dense output: order must be in 1..{MAX_CHECK_ORDER}, got {dense.order!r}")
    ex = exact and _is_exact(P_raw) and (Ax_raw is None or (_is_exact(Ax_raw) and _is_exact(cx_raw)))
    zero = Fraction(0) if ex else 0.0
    for i, row in enumerate(Ax_raw or []):
        if len(row) != s + m or any(row[l] != 0 for l in range(s + i, s + m)):
            fail(f"dense output: extra stage {s + i + 1} must couple only to earlier stages "
                 f"({s + m} entries, zero from column {s + i + 1} on)")
        if not _residual_ok(sum(row, zero) - cx_raw[i], ex, scale):
            fail(f"dense output: row-sum condition violated for extra stage {s + i + 1}")
    # b_j(1) = b_j: the interpolant ends at the step's result (extra stages: 0)
    for j, row in enumerate(P_raw):
        target = b_raw[j] if j < s else zero
        if not _residual_ok(sum(row, zero) - target, ex, max(scale, _coef_scale([], row))):
            fail(f"dense output: b_{j + 1}(1) = {float(sum(row, zero))!r} differs from "
                 f"{'b' if j < s else 'zero (extra stage)'} {float(target)!r}")
    A_ext, _ = _extended_stage_matrix(A_raw, Ax_raw, zero)
    pscale = max(scale, _coef_scale(A_ext, [x for row in P_raw for x in row]))
    for n, tstr, k, res in continuous_order_residuals(A_ext, P_raw, int(dense.order)):
        if not _residual_ok(res, ex, pscale):
            fail(f"dense output: continuous order condition of order {n} violated, tree "
                 f"{tstr}, coefficient of theta^{k}: residual {float(res):.3e}")
    out = ContinuousExtension(
        order=int(dense.order), P=_readonly([[float(x) for x in row] for row in P_raw]),
        A_extra=None if Ax_raw is None else _readonly([[float(x) for x in row] for row in Ax_raw]),
        c_extra=None if cx_raw is None else _readonly([float(x) for x in cx_raw]),
        source=dense.source)
    # the exact rationals (P, A_extra, c_extra) when given exactly, as _exact_coeffs
    object.__setattr__(out, "_exact_coeffs", (P_raw, Ax_raw, cx_raw) if ex else None)
    return out


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
    dense : ContinuousExtension, optional
        Dense-output weights b_j(theta) (checked: continuous order conditions, b(1) = b).
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
    dense: Optional[ContinuousExtension] = None
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

        # explicit (strictly lower triangular A) or singly diagonally implicit with an explicit
        # first stage (ESDIRK: a_11 = 0, a_jj = gamma > 0 for j > 1): the stepper solves one stage
        # at a time, each with the same Newton matrix I - h gamma F' (mbs/implicit.py)
        for j in range(s):
            for l in range(j + 1, s):
                if A_raw[j][l] != 0:
                    fail(f"A is not lower triangular (explicit or diagonally implicit method required): "
                         f"a[{j + 1},{l + 1}] = {float(A_raw[j][l])!r} != 0")
        diag = [A_raw[j][j] for j in range(s)]
        if any(d != 0 for d in diag):
            if diag[0] != 0 or any(d != diag[1] for d in diag[1:]) or not float(diag[1]) > 0:
                fail("a diagonally implicit method needs an explicit first stage (a[1,1] = 0) and one "
                     "positive diagonal a[j,j] = gamma for j > 1 (ESDIRK); got diagonal "
                     + ", ".join(f"{float(d):.6g}" for d in diag))
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
        _checked(("b", A_raw, b_raw, int(self.order), exact, scale),
                 lambda: self._check_order_conditions(A_raw, b_raw, int(self.order), exact, scale, "b", fail))

        b_hat_arr = None
        if self.b_hat is not None:
            bh_raw = [_to_exact(x) for x in self.b_hat]
            if len(bh_raw) != s:
                fail(f"b_hat must have {s} entries")
            if self.order_hat is None:
                fail("b_hat given without order_hat")
            ex_h = exact and _is_exact(bh_raw)
            _checked(("b_hat", A_raw, bh_raw, int(self.order_hat), ex_h, scale),
                     lambda: self._check_order_conditions(A_raw, bh_raw, int(self.order_hat), ex_h, scale,
                                                          "b_hat", fail))
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
        # --- dense output: checked against A and b, stored as float arrays
        if self.dense is not None:
            dense = self.dense
            set_(self, "dense", _MEMO.get(arg_key("dense", dense, A_raw, b_raw, exact, scale),
                                          lambda: _check_continuous_extension(dense, A_raw, b_raw, exact, scale,
                                                                              fail)))

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
        A, b = self._stage_coupling()
        s = self.stages
        need = [b[j] != 0.0 for j in range(s)]
        for j in range(s - 1, -1, -1):
            if not need[j]:
                need[j] = any(need[l] and A[l, j] != 0.0 for l in range(j + 1, s))
        return tuple(j for j in range(s) if need[j])

    def _stage_coupling(self):
        """``(A, b)`` as :attr:`active_stages` reads them: which stage feeds which, and the result."""
        return self.A, self.b

    # --- embedded pairs ----------------------------------------------------
    @property
    def fsal(self):
        """First Same As Last, decided from the coefficients: the last stage row equals the
        weights (``a_sj = b_j`` for all j, hence ``b_s = 0`` and ``c_s = 1``), so the last
        stage is evaluated at the step's result and its right-hand side is the first
        stage of the next step.  In a Munthe-Kaas step the last stage argument is then
        ``Psi_s = h sum_j b_j k_j = Phi`` and ``V_s = V_+``: its evaluation
        ``Vdot_s = F(t + h, g exp(Phi), V_+)`` is the next step's ``Vdot_1`` (the stage
        value ``k_s = dexp^-1_(-Phi) V_+`` itself differs from the next ``k_1 = V_+``)."""
        s = self.stages        # (an implicit last stage is solved, not evaluated: not reused)
        return s > 1 and not self.implicit and bool(np.array_equal(self.A[s - 1], self.b))

    @property
    def order_label(self):
        """The order as reported in a solution file's header."""
        return str(self.order)

    @property
    def partitioned(self):
        """True for a :class:`~.partitioned.PartitionedTableau` (the configurations' own coefficients)."""
        return False

    @property
    def implicit(self):
        """True for a diagonally implicit method (``a_jj = gamma > 0`` for the stages after the first)."""
        return bool(self.A[-1, -1] != 0.0)

    @property
    def gamma(self):
        """The diagonal ``gamma`` of a diagonally implicit method (0 for an explicit one)."""
        return float(self.A[-1, -1])

    @property
    def embedded(self):
        """True if the tableau carries embedded weights (an error estimate)."""
        return self.b_hat is not None

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
