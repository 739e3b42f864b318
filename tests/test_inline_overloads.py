"""exudyn_lie/_inline_overloads.py: this package's always-inlined overloads (the feature guards of
mbs/presence.py, the seams of stepper.mk_steps) are typed for inlining and never compiled as
functions of their own; numba's and other packages' overloads are left as numba makes them."""
import numpy as np
from numba import njit, types
from numba.core import event
from numba.extending import overload

from exudyn_lie import _inline_overloads
from exudyn_lie.mbs.presence import guarded


class _Compiled(event.Listener):
    """The names of the functions numba compiles while it is active."""

    def __init__(self):
        self.names = []

    def on_start(self, ev):
        if ev.kind == "numba:compile":
            disp = ev.data["dispatcher"]
            self.names.append(getattr(disp, "py_func", disp).__name__)

    def on_end(self, ev):
        pass


def _compiled_while(fn):
    listener = _Compiled()
    with event.install_listener("numba:compile", listener):
        fn()
    return listener.names


@njit(inline="always")
def _twice_plus(x, y):
    return 2.0 * x + y


def test_a_guarded_call_is_inlined_and_not_compiled_on_its_own():
    assert getattr(_inline_overloads._Template._get_jit_decorator, "_exudyn_lie", False)   # installed
    g = guarded(_twice_plus, rows=True, default=-1)

    @njit
    def two_sites(table, x):
        return g(table, x, 1.0) + g(table, x, 0.5)

    out = {}

    def run():
        out["present"] = two_sites(np.zeros(2), 3.0)
        out["no rows"] = two_sites(np.zeros(0), 3.0)
        out["absent"] = two_sites(None, 3.0)

    names = _compiled_while(run)
    assert out == {"present": 7.0 + 6.5, "no rows": -2, "absent": -2}
    # numba compiled the caller for its two argument types, and nothing else: neither the
    # guard's implementations ("present_rows", "absent") nor the entry they inline
    assert names == ["two_sites", "two_sites"]


def _other_stub(x):
    raise NotImplementedError


@overload(_other_stub, inline="always")
def _other_impl(x):
    if isinstance(x, types.Float):
        return lambda x: x + 1.0


def test_an_overload_of_another_module_is_compiled_as_numba_does():
    @njit
    def caller(x):
        return _other_stub(x)

    names = _compiled_while(lambda: caller(1.0))
    assert caller(1.0) == 2.0
    # numba's own rule (templates._build_impl): the implementation compiled in full first
    assert "<lambda>" in names and "caller" in names
