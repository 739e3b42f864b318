"""Compile only what the scene has: calls guarded by the *type* of a table.

A *lean* scene (``compiled.scene_is_lean``: bodies, gravity, loads, point-to-point springs,
joints of the lower-pair and distance row kinds) gets ``None`` for the tables of every other
feature.  Its SceneData type then differs from that of a full scene, so numba compiles the
kernel once per kind (each cached), and the calls below compile to nothing on ``None``: a
first run ever of such a scene types and lowers none of the other features' code.  A full scene has arrays, zero rows where it lacks a feature, as before, and
runs the same machine code as before.

``guarded(entry)`` makes ``g(table, *args)``: nothing when ``table`` is None, else
``entry(*args)``.  ``guarded(entry, rows=True)`` also skips the call when ``table`` has no
rows; ``guarded(entry, result=k)`` returns argument ``k`` unchanged on ``None`` (the energy
sums, ``e = g(table, ..., e)``), ``guarded(entry, default=c)`` the constant ``c`` (a status).  The guard is a numba overload, inlined: the selection by
type happens at compile time (numba prunes no ``if x is None`` on a tuple's field, only on a
function's argument, and an overload's implementation is chosen from the argument types).
"""
import inspect

from numba import types
from numba.extending import overload


def guarded(entry, rows=False, result=None, default=None):
    """``g(table, *args)``: ``entry(*args)`` unless ``table`` is None (module docstring);
    ``default``: the integer returned instead (a status code) when ``result`` is not given."""
    params = list(inspect.signature(getattr(entry, "py_func", entry)).parameters)
    args = ", ".join(params)
    absent = params[result] if result is not None else ("None" if default is None else repr(int(default)))
    # explicit arguments: numba's inliner takes no *args
    src = f"""
def g(table, {args}):
    raise NotImplementedError("compiled only")


def absent(table, {args}):
    return {absent}


def present(table, {args}):
    return entry({args})


def present_rows(table, {args}):
    if table.shape[0] > 0:
        return entry({args})
    return {absent}


def select(table, {args}):
    if isinstance(table, types.NoneType):
        return absent
    return present_rows if rows else present
"""
    env = {"entry": entry, "types": types, "rows": rows, "__name__": __name__}
    exec(compile(src, f"<guarded {entry.__name__}>", "exec"), env)
    g = env["g"]
    g.__name__ = g.__qualname__ = f"guarded_{entry.__name__}"

    overload(g, inline="always")(env["select"])
    return g


def is_present(table):
    """Python side: whether a table is there (not None) and has rows."""
    return table is not None and (not hasattr(table, "shape") or table.shape[0] > 0)
