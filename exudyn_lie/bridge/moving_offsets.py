"""Joint offsets moved by a user function during the run, on both paths.

Exudyn's reeving-system crane moves a winch by setting an ``ObjectConnectorCoordinate``'s
``offset`` in its pre-step function.  Exudyn calls the pre-step function with the step's
end time ``t1`` (``CSolverBase::InitializeStep``), and its index-3 solve holds the new offset
at ``t1``; its velocity level never learns that the offset moves.  The index-1 rows of both
paths need the offset's rate and acceleration (mbs/row_drives.py: a moving row
``h(q) - c(t)`` has ``J V = cdot`` and ``J Vdot = eta + cddot``).

A moved offset makes its row a moving row whose offset function on the step ``[t0, t1]``
is the cubic (:class:`OffsetCurve`) that starts at the constrained coordinate's actual value
and rate at ``t0`` and ends at the new offset at ``t1`` with the rate of the quadratic
through the last three offsets.  Starting from the actual state, the row has no residual
for the index-1 solve to keep: a curve from the old offset instead left the rate's jumps
from step to step in the velocity, and the coordinate drifted by first order in h (2.7 cm
of the reeving crane's 13.5 m carriage travel at its step of 1 ms).

:class:`ParameterOffsets` reads the offsets once per step and gives the curves;
each path says what the coordinate's actual value and rate are (the evaluated path from
Exudyn's residuals, the compiled path from its own rows), and where the curve goes.
"""
from __future__ import annotations


class OffsetCurve:
    """The cubic through ``(t0, x0)`` and ``(t1, x1)`` with the rates ``v0`` and ``v1``: a
    row's offset over one step, with its exact derivatives (mbs/row_drives.py asks for
    ``value_rate_acceleration`` before it takes differences of a function)."""

    __slots__ = ("t0", "hh", "x0", "v0", "x1", "v1")

    def __init__(self, t0, x0, v0, t1, x1, v1):
        self.t0, self.hh = float(t0), float(t1) - float(t0)
        self.x0, self.v0, self.x1, self.v1 = float(x0), float(v0), float(x1), float(v1)

    def value_rate_acceleration(self, t):
        hh = self.hh
        s = (t - self.t0) / hh
        a, b, c, d = self.x0, hh * self.v0, self.x1, hh * self.v1     # Hermite data on s in [0, 1]
        # x(s) = h00 a + h10 b + h01 c + h11 d, the Hermite basis in powers of s
        k2 = -3 * a - 2 * b + 3 * c - d
        k3 = 2 * a + b - 2 * c + d
        x = a + s * (b + s * (k2 + s * k3))
        xs = b + s * (2 * k2 + 3 * s * k3)
        xss = 2 * k2 + 6 * s * k3
        return x, xs / hh, xss / (hh * hh)

    def __call__(self, t):
        return self.value_rate_acceleration(t)[0]


class ConstantOffset:
    """An offset that has not moved (yet): a row's constant, as a drive of mbs/row_drives.py."""

    __slots__ = ("value",)

    def __init__(self, value):
        self.value = float(value)

    def value_rate_acceleration(self, t):
        return self.value, 0.0, 0.0

    def __call__(self, t):
        return self.value


class MovableOffset:
    """The offset function of a compiled row whose ``offset`` a step function may move: the
    constant offset until it moves, then the step's :class:`OffsetCurve` (set by the solver
    at the start of every step)."""

    __slots__ = ("curve", "label")

    def __init__(self, value, label):
        self.curve = ConstantOffset(value)
        self.label = label

    def value_rate_acceleration(self, t):
        return self.curve.value_rate_acceleration(t)

    def __call__(self, t):
        return self.curve(t)


def rate_at(points, t):
    """The derivative at ``t`` of the polynomial of degree <= 2 through ``[(t, value)]``."""
    if len(points) < 2:
        return 0.0
    if len(points) == 2:
        (ta, va), (tb, vb) = points
        return (vb - va) / (tb - ta)
    (ta, va), (tb, vb), (tc, vc) = points
    return (va * (2 * t - tb - tc) / ((ta - tb) * (ta - tc)) + vb * (2 * t - ta - tc) / ((tb - ta) * (tb - tc))
            + vc * (2 * t - ta - tb) / ((tc - ta) * (tc - tb)))


def offset_objects(mbs, describe):
    """``[(object, label)]`` of the active position-level ObjectConnectorCoordinates whose
    ``offset`` parameter a user function may move (those without an ``offsetUserFunction``,
    which replaces the offset; a velocity-level row's offset is a velocity target, which a
    step may change at once)."""
    from .reader import _userfunction
    out = []
    for o in range(mbs.systemData.NumberOfObjects()):
        d = mbs.GetObject(o)
        if d["objectType"] != "ConnectorCoordinate" or not d.get("activeConnector", True) \
                or d.get("velocityLevel", False):
            continue
        what = describe(o, d)
        if _userfunction(d, "offsetUserFunction", what) is None:
            out.append((o, f"the offset of {what}"))
    return out


class ParameterOffsets:
    """The offsets of ``objects`` (``[(object, rows, tag)]``; ``rows`` the object's rows in
    the path's own numbering; ``tag`` the caller's: a label on the evaluated path, the row's
    :class:`MovableOffset` on the compiled one), read once per step: :meth:`record` gives the
    curves of those that have moved so far."""

    def __init__(self, mbs, t0, objects):
        self.mbs = mbs
        self.objects = objects
        self.hist = {o: [(t0, float(mbs.GetObjectParameter(o, "offset")))] for o, _, _ in objects}
        self.moved = set()

    def __bool__(self):
        return bool(self.objects)

    def record(self, tStart, tEnd, actual):
        """Read the offsets set for the step from ``tStart`` to ``tEnd``; returns
        ``[(row, OffsetCurve, tag)]`` of the offsets that have moved so far.  ``actual()``
        (called only when one has moved) gives a function ``(row, new offset) -> (value,
        rate)`` of the constrained coordinate combination at the step's start."""
        moving = []
        at = None
        for o, rows, tag in self.objects:
            h = self.hist[o]
            v = float(self.mbs.GetObjectParameter(o, "offset"))
            if tEnd > h[-1][0]:
                h.append((tEnd, v))
                del h[:-3]
            else:
                h[-1] = (h[-1][0], v)      # the same step again (discontinuous iteration)
            if o not in self.moved and any(x[1] != h[0][1] for x in h):
                self.moved.add(o)
            if o in self.moved:
                if at is None:
                    at = actual()
                slope = rate_at(h, tEnd)
                for r in rows:
                    x0, v0 = at(r, v)
                    moving.append((r, OffsetCurve(tStart, x0, v0, tEnd, v, slope), tag))
        return moving
