"""Exact import-time computations kept on disk, like numba's cache (start-up).

Importing the package derives exact (``Fraction``) Taylor coefficients of the group maps
(:mod:`exudyn_lie.groups._taylor`) and checks every catalogue tableau's order conditions
(:mod:`exudyn_lie.integrators.butcher`, :mod:`exudyn_lie.integrators.order_conditions`): about 0.2 s of every import, always with the
same result.  A :class:`DiskMemo` keeps such results in the package's ``__pycache__``
(numba's user-wide cache directory when that is not writable is not needed: a memo that
cannot be written is simply recomputed next time), keyed by a hash of the arguments and
of the source files that compute them: editing one of them starts a new memo.  A result is
stored only after it was computed successfully (a failing check raises and stores
nothing), and is written once per process (``atexit``).
"""
import atexit
import hashlib
import os
import pickle

_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "__pycache__")


def arg_key(*args):
    """A key of exact arguments (Fractions, floats, arrays, tuples): the hash of their pickle."""
    return hashlib.sha1(pickle.dumps(args, protocol=4)).hexdigest()


class DiskMemo:
    """``memo.get(key, compute)``: the stored result for ``key`` or ``compute()`` (stored)."""

    def __init__(self, name, *source_files):
        sha = hashlib.sha1()
        for source in source_files:
            with open(source, "rb") as f:
                sha.update(f.read())
        h = sha.hexdigest()[:16]
        self.path = os.path.join(_DIR, f"memo_{name}_{h}.pkl")
        self.data = None
        self.dirty = False

    def _load(self):
        self.data = {}
        try:
            with open(self.path, "rb") as f:
                d = pickle.load(f)
            if isinstance(d, dict):
                self.data = d
        except (OSError, EOFError, pickle.UnpicklingError, AttributeError, ValueError):
            pass

    def get(self, key, compute):
        if self.data is None:
            self._load()
        try:
            return self.data[key]
        except KeyError:
            pass
        v = compute()
        self.data[key] = v
        if not self.dirty:
            self.dirty = True
            atexit.register(self.save)
        return v

    def save(self):
        """Write the memo (atomically; silently skipped where the directory is read-only)."""
        if not self.dirty:
            return
        try:
            os.makedirs(_DIR, exist_ok=True)
            tmp = f"{self.path}.{os.getpid()}.tmp"
            with open(tmp, "wb") as f:
                pickle.dump(self.data, f, protocol=4)
            os.replace(tmp, self.path)
            self.dirty = False
        except OSError:
            pass
