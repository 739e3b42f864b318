"""exudyn_lie/_inline_overloads.py: this package's always-inlined overloads (the feature guards of
mbs/presence.py, the seams of stepper.mk_steps) are typed for inlining and never compiled as
functions of their own; numba's and other packages' overloads are left as numba makes them."""
import numpy as np
import pytest
from numba import literally, njit, types
from numba.core import event
from numba.extending import overload

from exudyn_lie import _inline_overloads
from exudyn_lie.mbs.presence import guarded


def _installed():
    t = _inline_overloads._Template
    return t is not None and getattr(t._get_jit_decorator, "_exudyn_lie", False)


needs_patch = pytest.mark.skipif(not _installed(), reason="numba version not in _inline_overloads.TESTED_NUMBA")


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


@needs_patch
def test_a_guarded_call_is_inlined_and_not_compiled_on_its_own():
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
    # numba compiled the caller for its two argument types and nothing else: not the guard's
    # implementations ("present_rows", "absent"; without the patch numba compiles both first)
    assert names == ["two_sites", "two_sites"]


def _overload_in(module, typing):
    """A fresh stub with the always-inlined overload ``typing``, which then lives in ``module``."""
    def stub(x):
        raise NotImplementedError

    typing.__module__ = module
    overload(stub, inline="always")(typing)
    return stub


def test_an_overload_of_another_module_is_compiled_as_numba_does():
    def typing(x):
        if isinstance(x, types.Float):
            return lambda x: x + 1.0
    stub = _overload_in(__name__, typing)

    @njit
    def caller(x):
        return stub(x)

    names = _compiled_while(lambda: caller(1.0))
    assert caller(1.0) == 2.0
    # numba's own rule (templates._build_impl): the implementation compiled in full first
    assert "<lambda>" in names and "caller" in names


@needs_patch
def test_a_literal_request_of_an_inlined_overload_is_honoured():
    """``literally`` in the implementation: numba's compile of it, skipped here, bound the
    request to the argument folding; the patch binds it itself (else numba's typing fails)."""
    def typing(n):
        if isinstance(n, types.IntegerLiteral):
            k = n.literal_value
            return lambda n: k * 10
        return lambda n: literally(n)
    stub = _overload_in(_inline_overloads.__name__.rpartition(".")[0] + ".test_literal", typing)

    @njit
    def caller(n):
        return stub(n)

    names = _compiled_while(lambda: caller(3))
    assert caller(3) == 30
    assert "<lambda>" not in names
