"""Numba's one-off compilation of the solver: a notice when it starts, and its duration.

The compiled kernel is cached in ``__pycache__`` beside its sources (``cache=True``), so
only the first run on a machine (or after the sources changed) compiles.  A cold start is
recognised by numba's own cache index of the kernel's time loop: missing or stale (numba
compares the source file's time stamp and size) and not compiled in this process yet.
"""
import contextlib
import hashlib
import json
import os
import sys
import threading
import time

#: Seconds a cold start compiles when this machine has not compiled the solver before, on an idle
#: 2-core AMD EPYC with an empty cache: 97 s for the paper's heavy top through the kernel (a lean
#: scene; ``python -m exudyn_lie bench --sections startup --quick --cold``) and 185 s for a pendulum
#: read from an Exudyn script through ``SolveDynamic`` (the full kernel; by hand, docs/BENCH.md).
#: The default is the drop-in's, which most first runs are.  After one cold start the notice
#: gives the compile time measured then on this machine (:data:`MEASURED_FILE`).
COLD_COMPILE_SECONDS = 190


def _state_dir():
    """Where the measured compile times live: beside the cache every copy of the package
    shares (``_numba_cache.shared_cache_dir``), else beside the sources."""
    try:
        from ._numba_cache import shared_cache_dir
        d = shared_cache_dir()
        os.makedirs(d, exist_ok=True)
        return d
    except OSError:
        return os.path.join(os.path.dirname(os.path.abspath(__file__)), "__pycache__")


_STATE_DIR = _state_dir()
#: numba's compile seconds of the last cold start on this machine (beside numba's cache)
MEASURED_FILE = os.path.join(_STATE_DIR, "cold_compile_seconds.txt")
#: the compile seconds of every variant compiled on this machine: ``{variant: seconds}``
HISTORY_FILE = os.path.join(_STATE_DIR, "compile_seconds.json")
#: a compile that takes longer than this announces itself
NOTICE_AFTER = 1.0

#: a cold start shorter than this is not stored (a probe, not the solver)
MIN_STORED_SECONDS = 1.0

_announced = False
_coldInProgress = False      # the cold start's line is out and its compile not finished


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


def duration_text(seconds):
    """``'about 40 s'`` (to the nearest second, halves up), from 90 s on in minutes: ``'about 3 min'``."""
    s = int(seconds + 0.5)
    return f"about {s} s" if s < 90 else f"about {int(s / 60 + 0.5)} min"


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
            global _coldInProgress
            _coldInProgress = False
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
    global _announced, _coldInProgress
    if _announced or not cache_is_cold(disp):
        return False
    _announced = _coldInProgress = True
    print(f"exudyn_lie: compiling the solver for this machine, first run only, {duration_text(estimated_seconds())}",
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


def variant_key(dispatcher, args):
    """A compiled variant: the function and the numba types of its arguments (hashed, the
    types of a model's work arrays spell out hundreds of fields)."""
    py = dispatcher.py_func
    sig = hashlib.sha1(repr(tuple(args or ())).encode()).hexdigest()[:12]
    return f"{py.__module__}.{py.__qualname__}[{sig}]"


def load_history():
    try:
        with open(HISTORY_FILE) as f:
            h = json.load(f)
        return h if isinstance(h, dict) else {}
    except (OSError, ValueError):
        return {}


def _store(key, seconds):
    h = load_history()
    h[key] = round(float(seconds), 3)
    try:
        tmp = f"{HISTORY_FILE}.{os.getpid()}"
        with open(tmp, "w") as f:
            json.dump(h, f, indent=0, sort_keys=True)
        os.replace(tmp, HISTORY_FILE)
    except OSError:
        pass


class CompileNotices:
    """Every compile of a package function that takes more than :data:`NOTICE_AFTER`
    announces itself on stderr: at once with the time this variant took on this machine
    before (:data:`HISTORY_FILE`), or, for a variant never compiled here, after one second,
    by a timer thread (numba's LLVM passes release the interpreter).  Its duration goes
    into the history for next time.  Installed once per process (:func:`install_notices`);
    the cold start's own line (:func:`announce_cold_compile`) stands for the compiles it
    covers."""

    def __init__(self, stream=None):
        self.stream = stream
        self.depth = 0
        self.key = None
        self.start = 0.0
        self.timer = None
        self.announced = False
        self.lock = threading.Lock()

    def _print(self, text):
        print(text, file=sys.stderr if self.stream is None else self.stream, flush=True)

    def _announce(self, estimate):
        with self.lock:
            if self.key is None or self.announced:
                return
            self.announced = True
            name = self.key.split("[")[0].rsplit(".", 1)[-1]
            if estimate is None:
                self._print(f"exudyn_lie: compiling for a new kind of model ({name}), first run on this machine; "
                            f"no estimate yet (its time is kept for the next compile of this kind)")
            else:
                self._print(f"exudyn_lie: compiling for a new kind of model ({name}), first run on this machine, "
                            f"{duration_text(estimate)} (measured here before)")

    def on_start(self, data):
        self.depth += 1
        if self.depth != 1:
            return
        disp = data.get("dispatcher")
        py = getattr(disp, "py_func", None)
        if py is None or not str(getattr(py, "__module__", "")).startswith("exudyn_lie"):
            self.key = None
            return
        self.key = variant_key(disp, data.get("args"))
        self.start = time.perf_counter()
        self.announced = False
        if _coldInProgress:
            self.announced = True            # the cold start's line covers it
            return
        estimate = load_history().get(self.key)
        if estimate is not None:
            if estimate >= NOTICE_AFTER:
                self._announce(estimate)
            return
        self.timer = threading.Timer(NOTICE_AFTER, self._announce, args=(None,))
        self.timer.daemon = True
        self.timer.start()

    def on_end(self, data):
        self.depth -= 1
        if self.depth or self.key is None:
            return
        if self.timer is not None:
            self.timer.cancel()
            self.timer = None
        seconds = time.perf_counter() - self.start
        _store(self.key, seconds)
        with self.lock:
            if self.announced and not _coldInProgress and seconds >= NOTICE_AFTER:
                self._print(f"exudyn_lie: compiled in {seconds:.1f} s (once per machine and kind of model)")
            self.key = None


_notices = None


def install_notices():
    """Register :class:`CompileNotices` with numba's compile events (once per process)."""
    global _notices
    if _notices is not None:
        return _notices
    from numba.core import event

    notices = CompileNotices()

    class _Listener(event.Listener):
        def on_start(self, ev):
            notices.on_start(ev.data or {})

        def on_end(self, ev):
            notices.on_end(ev.data or {})
    event.register("numba:compile", _Listener())
    _notices = notices
    return notices



install_notices()
