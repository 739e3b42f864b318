"""The simulator's time as an origin plus whole steps of one size.

A fixed step's stage time is ``t0 + (k0 + n) h + c_j h`` (:func:`~.stepper.mk_steps`, its ``t0,
k0``): one product from the origin, never a sum of steps.  Restarting each call of the stepper
at the time the previous call reached would round differently with the number of steps per
call, so a time-dependent model's last bits would follow how the outputs were chunked (the
bridge sizes its chunks by the wall time).  Setting the time (a start, the host's time after a
user function, an adaptive run's end) or stepping with another size starts a new origin.
"""


class StepClock:
    """``t = origin + steps * h``; :meth:`start` gives the ``(t0, k0)`` of the next steps of ``h``."""

    __slots__ = ("origin", "steps", "h")

    def __init__(self, t):
        self.origin, self.steps, self.h = float(t), 0, 0.0

    @property
    def t(self):
        return self.origin + self.steps * self.h if self.steps else self.origin

    def start(self, h):
        """``(origin, steps)`` for steps of ``h`` from the current time: a new origin there if the
        clock counted steps of another size."""
        if h != self.h:
            self.origin, self.steps, self.h = self.t, 0, float(h)
        return self.origin, self.steps

    def advance(self, n):
        """``n`` more steps of the size of the last :meth:`start`."""
        self.steps += int(n)
