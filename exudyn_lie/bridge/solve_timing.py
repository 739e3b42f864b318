"""Where the time of a ``SolveDynamic`` call goes: the set-up before the time loop (reading
the model, the simulator, Exudyn's InitializeSolver: the fixed cost), numba's compilation
(a kind of model run for the first time on a machine), and the time loop.

:func:`GetSolveTiming` gives them for the last ``SolveDynamic`` of the process, so that a
script (or ``python -m exudyn_lie corpus``) can set them against the native solve.
Compilation is measured with numba's own compile events: only real compilations count, not
the loading of cached machine code, and a compilation inside the time loop (the first
call of the stepper) is taken out of the loop's time.
"""
from __future__ import annotations

import contextlib
import functools
import time
from dataclasses import asdict, dataclass

from numba.core import event


@dataclass
class SolveTiming:
    """Seconds of one ``SolveDynamic`` call: ``total`` = ``setup`` + ``compile`` + ``loop``."""
    total: float = 0.0
    setup: float = 0.0          # the fixed cost: everything outside the loop, compilation aside
    compile: float = 0.0        # numba's compilation, wherever it happened
    loop: float = 0.0           # Exudyn's time loop with exudyn_lie's steps, compilation aside
    path: str = ""              # 'compiled' or 'evaluated'


_last = None            # the SolveTiming of the last call
_clock = None           # the numba TimingListener of the call under way
_current = None         # its SolveTiming


def GetSolveTiming():
    """A dict of the last ``exudyn_lie.SolveDynamic`` call's seconds: ``total``, ``setup``
    (reading the model, building the solver, Exudyn's InitializeSolver and FinalizeSolver: the
    fixed cost), ``compile`` (numba compiling a new kind of model), ``loop`` (the time loop),
    and its ``path`` ('compiled' or 'evaluated'); None before the first call."""
    return None if _last is None else asdict(_last)


@contextlib.contextmanager
def timed_solve():
    """Around a whole ``SolveDynamic`` call: yields its :class:`SolveTiming`, filled in on exit
    (also when the call raises)."""
    global _last, _clock, _current
    timing, clock = SolveTiming(), event.TimingListener()    # outermost compilations, summed
    outer = _clock, _current
    _clock, _current = clock, timing
    tic = time.perf_counter()
    try:
        with event.install_listener("numba:compile", clock):
            yield timing
    finally:
        _clock, _current = outer
        timing.total = time.perf_counter() - tic
        timing.compile = _seconds(clock)
        timing.setup = max(0.0, timing.total - timing.compile - timing.loop)
        _last = timing


def timed_call(fn):
    """``fn`` (SolveDynamic) inside :func:`timed_solve`; its name, signature and text kept."""
    @functools.wraps(fn)
    def call(*args, **kwargs):
        with timed_solve():
            return fn(*args, **kwargs)
    return call


def _seconds(clock):
    return clock.duration if clock.done else 0.0


def compile_seconds():
    """numba's compilation so far in the call under way (0 outside a call)."""
    return 0.0 if _clock is None else _seconds(_clock)


def record_loop(seconds, path):
    """The time loop of the call under way took ``seconds``, compilation aside, on ``path``."""
    if _current is not None:
        _current.loop += seconds
        _current.path = path
