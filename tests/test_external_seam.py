"""The call of the external seam from compiled code (mbs/external.py: ``call``, ``handle``)."""
import gc

import pytest
from numba import njit

from exudyn_lie.mbs import external


class Owner:
    def __init__(self):
        self.seen = []

    def record(self, t):
        self.seen.append(t)

    def fail(self, t):
        raise ValueError(f"failed at {t}")


@njit
def call_from_compiled(h, t):
    return external.call(h, t)


def test_call_reaches_the_evaluator_and_keeps_its_exception():
    o = Owner()
    ok, bad = external.register(o, "record"), external.register(o, "fail")
    assert call_from_compiled(external.handle(ok), 0.25) == 0
    assert o.seen == [0.25]
    assert call_from_compiled(external.handle(bad), 0.5) == 1
    with pytest.raises(ValueError, match="failed at 0.5"):
        external.reraise(bad)
    external.reraise(bad)                 # raised once only
    assert call_from_compiled(0, 0.1) == 1   # no evaluator: a failure, not a crash


def test_the_registry_does_not_keep_the_owner():
    o = Owner()
    token = external.register(o, "record")
    del o
    gc.collect()
    with pytest.raises(KeyError):
        external.handle(token)
