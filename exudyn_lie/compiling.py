"""Numba's one-off compilation of the solver: a notice when it starts, and its duration.

The compiled kernel is cached in ``__pycache__`` beside its sources (``cache=True``), so
only the first run on a machine (or after the sources changed) compiles.  A cold start is
recognised by numba's own cache index of the kernel's time loop: missing or stale (numba
compares the source file's time stamp and size) and not compiled in this process yet.
"""
import contextlib
import sys

#: Seconds a cold start compiles: 17 s (paper, kernel path) to 36 s (SolveDynamic on a busy machine) on a
#: 2-core Intel Xeon, measured with
#: an empty cache (README, set-up).
COLD_COMPILE_SECONDS = 30

_announced = False


def cache_is_cold(disp):
    """True if the numba dispatcher ``disp`` (cache=True) will be compiled, not loaded
    from numba's cache."""
    if disp.signatures:                      # compiled or loaded in this process already
        return False
    try:
        return not disp._cache._cache_file._load_index()
    except Exception:                        # noqa: BLE001 - numba internals changed: say nothing
        return False


def announce_cold_compile(disp, stream=None):
    """Print one line (once per process) if the solver is about to be compiled; ``disp``:
    the kernel's time loop (its cache stands for the whole kernel's)."""
    global _announced
    if _announced or not cache_is_cold(disp):
        return False
    _announced = True
    print(f"exudyn_lie: compiling the solver for this machine, first run only, about {COLD_COMPILE_SECONDS} s",
          file=sys.stderr if stream is None else stream, flush=True)
    return True


@contextlib.contextmanager
def compile_timer():
    """Measure the seconds numba spends compiling inside the block (nested compilations
    counted once); ``.seconds`` of the yielded object (0 if nothing was compiled)."""
    from numba.core import event

    class _Timer(event.TimingListener):
        @property
        def seconds(self):
            return self.duration if self.done else 0.0

    tl = _Timer()
    with event.install_listener("numba:compile", tl):
        yield tl
