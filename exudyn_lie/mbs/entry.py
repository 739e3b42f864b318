"""Compiled entry points of numba dispatchers, resolved once per argument structure.

A Python call of a numba function re-derives the types of its arguments every time; for the
kernel's namedtuples of ~60 arrays that costs microseconds per call and about a millisecond
for the first resolution.  :func:`entry_point` caches the compiled entry point by a cheap
structural key, so repeated solves (and every new :class:`~exudyn_lie.mbs.Simulator` with
the same scene structure) skip it.  :func:`call` is how the simulator and the bridge's output
chunks call the kernel.
"""
import numpy as np
from numba._dispatcher import compute_fingerprint

_ENTRY_CACHE = {}


def _type_key(x):
    """A cheap key that determines numba's type of an argument: numba's own C-level
    fingerprint (arrays: dtype, ndim, layout, writeability; tuples: their items), with the
    class of a namedtuple (which the fingerprint does not see).  About 2 us for a scene
    tuple of 40 arrays, against 27 us for the Python walk below (the fallback)."""
    try:
        return (type(x), compute_fingerprint(x))
    except Exception:
        return _type_key_walk(x)


def _type_key_walk(x):
    if isinstance(x, np.ndarray):
        return (x.dtype.str, x.ndim, x.flags.c_contiguous, x.flags.writeable)
    if isinstance(x, tuple):
        return (type(x),) + tuple(_type_key_walk(v) for v in x)
    return type(x)


def entry_point(dispatcher, args):
    """The compiled entry point of a numba ``dispatcher`` for exactly these argument
    types (the dispatcher must have been called with them once); None if unavailable.
    Resolved signatures are cached by a cheap structural key of the arguments, so a
    repeated solve does not pay numba's type resolution (~1 ms per namedtuple) again."""
    try:
        key = (id(dispatcher),) + tuple(_type_key(a) for a in args)
        ep = _ENTRY_CACHE.get(key)
        if ep is None:
            sig = tuple(dispatcher.typeof_pyval(a) for a in args)
            ov = dispatcher.overloads.get(sig)
            if ov is None:
                return None
            ep = _ENTRY_CACHE[key] = ov.entry_point
        return ep
    except Exception:
        return None


def call(cache, name, dispatcher, args):
    """``dispatcher(*args)`` through its compiled entry point, resolved once and kept in
    ``cache[name]`` (the one place that resolves them; drop the cache when the argument types
    may change)."""
    ep = cache.get(name)
    if ep is None:
        ep = entry_point(dispatcher, args)
        if ep is None:
            out = dispatcher(*args)              # the first call compiles or loads it
            cache[name] = entry_point(dispatcher, args) or dispatcher
            return out
        cache[name] = ep
    return ep(*args)
