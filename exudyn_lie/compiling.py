"""Numba's one-off compilation of the solver: a notice when it starts, and its duration.

The compiled kernel is cached in ``__pycache__`` beside its sources (``cache=True``), so
only the first run on a machine (or after the sources changed) compiles.  A cold start is
recognised by numba's own cache index of the kernel's time loop: missing or stale (numba
compares the source file's time stamp and size) and not compiled in this process yet.
"""
import contextlib
import os
import sys

#: Seconds a cold start compiles when this machine has not compiled the solver before: 16 s
#: (kernel path) to 19 s (SolveDynamic) on an idle 2-core AMD EPYC, measured with an empty
#: cache (``python -m exudyn_lie bench --sections startup --quick --cold``, README).  After one
#: cold start the notice gives the compile time measured then on this machine (:data:`MEASURED_FILE`).
COLD_COMPILE_SECONDS = 20
#: numba's compile seconds of the last cold start on this machine (beside numba's cache)
MEASURED_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "__pycache__", "cold_compile_seconds.txt")

#: a cold start shorter than this is not stored (a probe, not the solver)
MIN_STORED_SECONDS = 1.0

_announced = False


def estimated_seconds():
    """The compile time the notice announces: the last cold start's, measured on this
    machine, else :data:`COLD_COMPILE_SECONDS`."""
    try:
        with open(MEASURED_FILE) as f:
            v = float(f.read().split()[0])
        if 0.0 < v < 3600.0:
            return int(round(v))
    except (OSError, ValueError, IndexError):
        pass
    return COLD_COMPILE_SECONDS


def _measure_this_cold_start(disp):
    """Sum numba's compile time from now until the kernel's time loop ``disp`` is compiled,
    and store it (the next cold start on this machine, e.g. after an update, announces it).
    Only up to that point: a process that goes on compiling other scenes (a test session)
    would otherwise store its own total.  (The listener stays registered, inert: numba's
    broadcast iterates over the listeners' list, so removing one during it skips another.)"""
    import time
    from numba.core import event

    class _UntilKernel(event.Listener):
        depth, start, seconds, finished = 0, 0.0, 0.0, False

        def on_start(self, ev):
            if not self.finished:
                if self.depth == 0:
                    self.start = time.perf_counter()
                self.depth += 1

        def on_end(self, ev):
            if self.finished:
                return
            self.depth -= 1
            if self.depth == 0:
                self.seconds += time.perf_counter() - self.start
            if (ev.data or {}).get("dispatcher") is not disp:
                return
            self.finished = True
            if self.seconds < MIN_STORED_SECONDS:
                return
            try:
                os.makedirs(os.path.dirname(MEASURED_FILE), exist_ok=True)
                with open(MEASURED_FILE, "w") as f:
                    f.write(f"{self.seconds:.3f}\n")
            except OSError:
                pass
    listener = _UntilKernel()
    event.register("numba:compile", listener)
    return listener


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
    print(f"exudyn_lie: compiling the solver for this machine, first run only, about {estimated_seconds()} s",
          file=sys.stderr if stream is None else stream, flush=True)
    _measure_this_cold_start(disp)
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
