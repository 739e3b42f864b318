"""The interface every body configuration group implements (the registry
:data:`exudyn_lie.groups.GROUPS`), in the spirit of jaxlie's ``MatrixLieGroup`` and manif's
``LieGroupBase``: the same operations with the same signatures for every group, all
``numba.njit`` functions callable from Python and from compiled code.

An element is a pair ``(R, r)`` (3x3 rotation body -> world, 3-vector); an algebra /
tangent vector is a 6-vector ``X = (rotation, translation)``.  ``dexp`` is right-
trivialised (see the package docstring).  The ``_into`` variants write into arrays the
caller provides and do not allocate (the compiled kernel uses them).

A group whose algebra is a subspace of the 6-vectors (R^3 of the point masses, the planar
groups) names the axes that are its coordinates with a module constant ``ALGEBRA_AXES``;
the others are ignored by ``exp`` and 0 in ``log``.  Without it, all six are.

``so3`` is the rotation factor shared by both groups, not a body group: its elements are
``R`` alone and its algebra 3-vectors, so its signatures lack the translation arguments.

The velocity representation of a body in its group (``rdot = T v``, the body point map,
``M^-1``, the inertial terms) is the compiled kernel's business: :mod:`exudyn_lie.mbs.bodies`.
"""
import inspect

#: operation -> parameter names (the signature every registered group shares)
OPERATIONS = {
    "hat": ("X",),
    "vee": ("M",),
    "exp": ("X",),
    "log": ("R", "r"),
    "dexp": ("X",),
    "dexpinv": ("X",),
    "ad": ("X",),
    "Ad": ("R", "r"),
    "compose": ("R1", "r1", "R2", "r2"),
    "inverse": ("R", "r"),
    "to_matrix": ("R", "r"),
    "from_matrix": ("C",),
    # allocation-free
    "exp_into": ("X", "R", "r"),
    "log_into": ("R", "r", "X"),
    "dexp_apply_into": ("X", "Y", "out"),
    "dexpinv_apply_into": ("X", "Y", "out"),
    "compose_into": ("R1", "r1", "R2", "r2", "R", "r"),
    "inverse_into": ("R", "r", "Ri", "ri"),
    "Ad_into": ("R", "r", "M"),
}


#: module constants every registered group declares: ``TWIST``, the velocity representation
#: of a body on it (``"body"``: ``rdot = R v`` as SE3; ``"mixed"``: ``rdot = v`` as SO3xR3);
#: optional ``ALGEBRA_AXES``, the axes of the 6-vector its algebra spans (default all six;
#: the planar groups (2, 3, 4)) -- the kernel and the tests read both from here.
TWISTS = ("body", "mixed")


def algebra_axes(module):
    """Axes of the 6-vector spanned by the group's algebra (a subalgebra for the planar groups)."""
    return tuple(getattr(module, "ALGEBRA_AXES", range(6)))


def missing_operations(module):
    """``[(operation, problem)]`` where ``module`` departs from :data:`OPERATIONS`
    (empty for a conforming group)."""
    out = []
    if getattr(module, "TWIST", None) not in TWISTS:
        out.append(("TWIST", f"module constant TWIST must be one of {TWISTS}"))
    for name, params in OPERATIONS.items():
        f = getattr(module, name, None)
        if f is None:
            out.append((name, "missing"))
            continue
        py = getattr(f, "py_func", None)
        if py is None:
            out.append((name, "not a numba function"))
            continue
        got = tuple(inspect.signature(py).parameters)
        if got != params:
            out.append((name, f"parameters {got}, expected {params}"))
    return out
