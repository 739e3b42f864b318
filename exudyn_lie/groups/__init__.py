"""Lie group maps for rigid body configurations: SO3, SE3, SO3xR3, quaternions.

Conventions (fixed for the whole package)
-----------------------------------------
* float64 numpy arrays; every public function is ``numba.njit(cache=True)`` and
  callable from Python and from other njit code (so3/se3 with fastmath={'contract'}:
  FMA fusion only).  No np.dot/@ inside njit code (numba needs scipy for it).
  numba's own cache key is the function's source file only; ``exudyn_lie._numba_cache``
  adds a hash of every compiled module of the package, so edits here recompile callers.
* Lie algebra vectors X = (xi, eta), ROTATION FIRST (X[0:3] rotation, X[3:6]
  translation); twists V = (omega, v).  SE3: body-fixed twist (omega, v = R^T rdot);
  SO3xR3: mixed velocity (omega body-fixed, rdot spatial).
* Group elements: SO3 -> R (3x3, body -> world); SE3 / SO3xR3 -> pair (R, r).
  SE3:    (R1, r1)(R2, r2) = (R1 R2, r1 + R1 r2)   (eq. MultSE3)
  SO3xR3: (R1, r1)(R2, r2) = (R1 R2, r1 + r2)      (eq. MultDirectProduct)
* exp: SO3 eq. expSO3; SE3 exp(xi, eta) = (exp xi^, dexp_xi eta) (eq. expX);
  SO3xR3 exp(xi, r) = (exp xi^, r) (eq. expSO3xR3).
* dexp is RIGHT-trivialised (paper): dexp_X Y = sum_i ad_X^i Y/(i+1)!, i.e.
  d/de exp(X + e Y) = hat(dexp_X Y) exp(X).  The left-trivialised derivative is
  exp(-X) d/de exp(X + e Y) = hat(dexp_{-X} Y).  Reconstruction V = dexp_{-X} Xdot;
  Munthe-Kaas stage k = dexpinv_{-Psi} V (eq. MK1).
* ad: SE3 [[xi^, 0], [eta^, xi^]]; SO3xR3 [[xi^, 0], [0, 0]]; SO3 x^.
  Ad: SE3 [[R, 0], [r^ R, R]] (hat(Ad_C X) = C hat(X) C^-1); SO3xR3 blockdiag(R, I).
* log: |xi| <= pi, robust at/near pi (via Shepperd's quaternion and atan2).
* hat: SO3 3x3; SE3 4x4; SO3xR3 the paper's 7x7 representation.

Module interface (so3 / se3 / so3xr3)
-------------------------------------
hat, vee, exp, log, dexp, dexpinv, ad, Ad, compose, inverse, and their
allocation-free variants for hot loops, which write into caller-provided arrays:

    exp_into(X, R[, r])          log_into(R[, r], X)
    dexp_apply_into(X, Y, out)   dexpinv_apply_into(X, Y, out)   (out may alias Y)
    compose_into(R1[, r1], R2[, r2], R[, r])   (outputs may alias the inputs)
    inverse_into(R[, r], Ri[, ri])             (outputs may alias the inputs)
    Ad_into(R[, r], M)

(so3 without the translation arguments), dexp_series, dexpinv_series; se3 also
dexpinv_selig, dexp_P, dexpinv_U; coefficient helpers (coef_*) and switch
constants (T_SWITCH_*).  Every public function of so3, se3, so3xr3 and quaternion
(and of the tests' dual quaternions) is called from inside an njit function in tests/test_groups_njit.py,
which also checks that the _into variants do not allocate.
"""
from .. import _numba_cache  # noqa: F401  (first: the cache key of every compiled function)
from . import so3, se3, so3xr3, rn, se2, so2xr2, quaternion

# The one registry of body configuration groups (name -> module).  Every entry implements
# the interface of :mod:`.interface` with the same signatures; its position is the group
# id the compiled kernel uses (exudyn_lie.mbs.codes).  A new group: its module, one line here.
GROUPS = {'SE3': se3, 'SO3xR3': so3xr3, 'R3': rn, 'SE2': se2, 'SO2xR2': so2xr2}

__all__ = ["so3", "se3", "so3xr3", "rn", "se2", "so2xr2", "quaternion", "GROUPS", "canonical_name",
           "switch_report"]


def canonical_name(name):
    """The registry name of a group as users write it (case, blanks, parentheses and underscores
    ignored, 'SO3R3' for SO3xR3), ``'auto'``, or None for anything else: the one parser of group
    names (the callers say which groups they accept)."""
    if not isinstance(name, str):
        return None
    key = name.strip().lower()
    for ch in "() _":
        key = key.replace(ch, "")
    if key == "auto":
        return "auto"
    key = {"so3r3": "so3xr3"}.get(key, key)
    return next((g for g in GROUPS if g.lower() == key), None)


def switch_report():
    """{map: (t_switch, {coefficient: number of Taylor terms})} for every Taylor branch.

    Rule (see ``_taylor``): closed forms only where their cancellation amplifies
    rounding by <= AMP_MAX = 32; below, enough terms that the first dropped ones
    are <= eps relative to the leading term.
    """
    return {
        "so3.exp/dexp (A,B,C)": (so3.T_SWITCH_EXP, {"A": so3.N_A, "B": so3.N_B, "C": so3.N_C}),
        "so3.dexpinv (D)": (so3.T_SWITCH_DEXPINV, {"D": so3.N_D}),
        "so3.log (atan(x)/x, x=|q|/q0)": (so3.T_SWITCH_LOG, {"ATAN": so3.N_ATAN}),
        "se3.dexp (B,C,Q3,Q4)": (se3.T_SWITCH_DEXP, se3.NTERMS["dexp"]),
        "se3.dexpinv (D,E2)": (se3.T_SWITCH_DEXPINV, se3.NTERMS["dexpinv"]),
        "se3.dexpinv_selig (S2,S4)": (se3.T_SWITCH_SELIG, se3.NTERMS["selig"]),
    }
