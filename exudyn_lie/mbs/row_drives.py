"""Time-dependent constraint rows (rheonomic rows): the moving offset of a row and the
velocity-level rows, e.g. a coordinate constraint with a prescribed offset ``c(t)`` or a
prescribed rate ``w(t)`` of the coordinates.

A row with a moving offset ``c(t)`` (the scene's ``Joint.offset``) is

    h(g, t) = h(g) - c(t),   J V = cdot(t),   J Vdot = eta + cddot(t)

(eq. index1 with the explicit time derivatives of the constraint: ``hddot = J Vdot + Jdot V
- cddot``).  A velocity-level row (``Joint.velocityLevel``, row kind ``ROW_COORD_VEL``)
constrains the rates only, ``J V = w(t)`` with ``w = constant + offset(t)``; its
acceleration level is the time derivative ``J Vdot = eta + wdot(t)`` (same ``J`` and
``eta = -Jdot V`` as the position-level row), and it has no position-level equation: its
``h`` is 0, so the position projection and the position drift leave it alone while the
velocity projection, the velocity drift and the initial velocity check use ``J V - w``.

The kernel holds the time-dependent part of every row in ``Work.rdrive`` (3, m): value,
rate (the velocity target) and acceleration (:func:`~.constraints.joints_rows` subtracts the
value from ``h`` and adds the acceleration to ``eta``).  Constant parts are set once
(``compiled.constant_drives``: a velocity-level row's constant offset); a row with an offset
function is evaluated at every time the rows are evaluated at: once per stage
(``stepper.stage_rhs``) and before a projection at a step's end, through the right-hand-side
seam of :mod:`.external` (one call to the registered evaluator, its handle in
``Work.drive``, None without offset functions; no Python stage loop): :func:`update_row_drives`.

**Derivatives of an offset function** (a Python function, e.g. a user function the bridge
reads, which gives the value only): fourth-order central differences on time with the step
``DRIVE_STEP = 2^-10 s`` (about 1e-3 s),

    cdot  = (c(t-2d) - 8 c(t-d) + 8 c(t+d) - c(t+2d)) / (12 d)
    cddot = (-c(t-2d) + 16 c(t-d) - 30 c(t) + 16 c(t+d) - c(t+2d)) / (12 d^2),

five evaluations for value, rate and acceleration together.  Why this step and not the
``eps^(1/3)`` / ``eps^(1/4)`` of second-order differences: the second derivative enters the
accelerations of every stage, so its error bounds the accuracy of the whole solve.  With
the three-point formula at ``d = eps^(1/4)`` the relative error of ``cddot`` for a 1 Hz motion
is ``d^2 w^2 / 12 ~ 5e-8`` (truncation), which would hide RK4's errors below 1e-7.  The
five-point formula costs the same five evaluations; its error
``d^4 |c^(6)| / 90 + 16 eps |c| / (3 d^2)`` is smallest at ``d^6 = 240 eps |c| / |c^(6)|``,
i.e. ``d = (240 eps)^(1/6) / w`` = 9.8e-4 s for a 1 Hz harmonic (``w = 2 pi``): ``DRIVE_STEP``,
a power of two so that ``t +- d`` are exact for the times of a solve.  Relative error of
``cddot`` at 1 Hz: about 3e-11 (of ``cdot``: 5e-11); it grows as ``w^4`` for faster drives
(1e-7 at 10 Hz).  The offset function is evaluated up to ``2 d`` before ``t0`` and after the
end time.  A kink in the offset (a ramp) is smoothed over ``+-2 d``.
"""
import numpy as np
from numba import njit, types
from numba.extending import overload

from . import external
from .codes import J_ROW0, STATUS_EXTERNAL, STATUS_OK

DRIVE_STEP = 2.0 ** -10
_W1 = np.array([1.0, -8.0, 0.0, 8.0, -1.0]) / 12.0          # cdot * d
_W2 = np.array([-1.0, 16.0, -30.0, 16.0, -1.0]) / 12.0      # cddot * d^2


@njit(cache=True, _nrt=False)
def evaluate_row_drives(token, t):
    """One Python call through the seam of :mod:`.external`: the evaluator registered under
    ``token`` writes the row drives at ``t``.  Returns a status code (STATUS_EXTERNAL if an
    offset function raised)."""
    return STATUS_EXTERNAL if external.call(token, t) else STATUS_OK


def update_row_drives(drive, t):
    """The row drives ``wk.rdrive`` at time ``t``: ``drive = wk.drive`` is None in a lean scene
    (compiled to nothing, as the tree solve's ``index1._is_tree``: the call, then through numba's
    objmode, present but not taken cost the heavy top about 0.1 us of 2.9 us per step, measured),
    else ``[handle]`` of the evaluator (:func:`evaluate_row_drives`), 0 without offset functions."""
    raise NotImplementedError("compiled only")


@overload(update_row_drives)
def _update_row_drives(drive, t):
    if isinstance(drive, types.NoneType):
        def no_drives(drive, t):
            return STATUS_OK
        return no_drives

    def drives(drive, t):
        if drive[0] == 0:           # a full scene without offset functions
            return STATUS_OK
        return evaluate_row_drives(drive[0], t)
    return drives


def offset_and_derivatives(fn, t, label):
    """``(c(t), cdot(t), cddot(t))`` of an offset function: its own
    ``value_rate_acceleration(t)`` if it has one (a curve whose derivatives are known), else
    the central differences of the module text; raises for an exception or a non-finite
    value, naming ``label``."""
    exact = getattr(fn, "value_rate_acceleration", None)
    if exact is not None:
        return exact(t)
    d = DRIVE_STEP
    c = np.empty(5)
    for k in range(5):
        tk = t + (k - 2) * d
        try:
            c[k] = float(fn(tk))
        except Exception as e:           # noqa: BLE001 - re-raised with the item's name
            raise _named(e, f"{label} raised at t = {tk:.9g}: {type(e).__name__}: {e}") from e
        if not np.isfinite(c[k]):
            raise ValueError(f"{label} returned {c[k]} at t = {tk:.9g}; it must return a finite float")
    return float(c[2]), float(_W1 @ c) / d, float(_W2 @ c) / (d * d)


def _named(e, msg):
    """An exception of the type of ``e`` with the message ``msg`` (RuntimeError if that type
    cannot be built from a message)."""
    try:
        return type(e)(msg)
    except Exception:                    # noqa: BLE001
        return RuntimeError(msg)


class RowDrives:
    """The offset functions of a scene's rows and their evaluation at a time into
    ``rdrive`` (the evaluator the stepper calls through :mod:`.external`)."""

    def __init__(self, scene, sd):
        self.rows = []          # (row, function, velocity level, constant, label)
        for j, jt in enumerate(scene.joints):
            if getattr(jt, "offset", None) is None:
                continue
            label = getattr(jt.offset, "label", None) or f"{jt.name}: offset function"
            self.rows.append((int(sd.jointIndex[j, J_ROW0]), jt.offset, bool(jt.velocityLevel),
                              float(sd.jointParams[j, 1]), label))

    def __bool__(self):
        return bool(self.rows)

    def evaluate(self, t, rdrive):
        """Fill ``rdrive[:, q]`` of the rows with an offset function at time ``t``: a
        position-level row (value, rate, acceleration) of ``c(t)``; a velocity-level row
        (0, constant + w(t), wdot(t))."""
        for q, fn, vel, const, label in self.rows:
            c, cd, cdd = offset_and_derivatives(fn, t, label)
            if vel:
                rdrive[0, q], rdrive[1, q], rdrive[2, q] = 0.0, const + c, cd
            else:
                rdrive[0, q], rdrive[1, q], rdrive[2, q] = c, cd, cdd
