"""The step observers: state that depends on the path, moved on after every accepted step.

Some quantities are not functions of the current configuration alone: the angle of a torsional
spring continued over turns, the rotation coordinates of the coordinate items, the rotation
parameters of a body continued on one branch (what a write-back of node coordinates needs),
the slip and gap of a penalty contact at the last step, the largest watched rotation entry.
Each is an *observer*: one registration (:func:`register_observer`) with its update
``(sd, wk, R, r, V)``, which does nothing when the scene lacks it.  The time loop calls every
observer after each accepted step (:func:`after_accepted_step`, generated from the
registrations, inlined into the stepper); a rejected step calls none, so the observers keep
their values at the step's start.  An observer registered with ``atStart`` is also set at an
initial state (:func:`observe_initial_state`): the tracked angles are, the contact data and
the watch are not (the contact data keep their given initial values).

Adding an observer: its update (``inline="always"``, guarded so that it compiles to nothing
or costs one test when the scene lacks it) and one :func:`register_observer` line below.
"""
import sys
from collections import namedtuple

from numba import njit

from .codegen import generate
from .coordinate_angles import update_coordinate_angles
from .forces import torsion_angles
from .presence import guarded
from .rolling_disc_penalty_forces import update_rolling_disc_penalty_data
from .rotation_parameters import update_tracked_bodies

StepObserver = namedtuple("StepObserver", ["name", "update", "atStart", "present"])

#: every step observer, in registration order
OBSERVERS = []
_SEALED = False         # True once after_accepted_step is generated: a later registration would not be in it


def register_observer(name, update, atStart, present):
    """Register one step observer (module docstring).  ``present(sd, wk)``: on the Python
    side, whether the scene has it (a scene without any ``atStart`` observer does not load
    :func:`observe_initial_state` at all)."""
    if any(o.name == name for o in OBSERVERS):
        raise ValueError(f"step observer {name!r} is registered twice")
    if _SEALED:
        # the stepper's code is generated from the registrations when this module is imported
        raise ValueError(f"step observer {name!r}: observers are registered in mbs/step_observers.py, before the "
                         f"stepper's code is generated from them")
    OBSERVERS.append(StepObserver(name, update, bool(atStart), present))


# none of these in a lean scene (their tables None, mbs/presence.py); in a full one only with rows
_torsion_angles_if = guarded(torsion_angles, rows=True)
_disc_data_if = guarded(update_rolling_disc_penalty_data, rows=True)


@njit(cache=True, inline="always", _nrt=False)
def observe_torsion_turns(sd, wk, R, r, V):
    """The torsional springs' angles, continued over turns (their force reads the branch)."""
    _torsion_angles_if(sd.torsionBodies, sd.gid, sd.torsionBodies, sd.torsionFrames, wk.path.torsionAngles, R, r, V,
                       wk.m3, wk.ident, wk.zero3, wk.zero6)


@njit(cache=True, inline="always", _nrt=False)
def _coordinate_angles(nCoordAngles, jointIndex, jointFrames, jointAngles, rowIndex, coordSpringEnds,
                       coordSpringFrames, springAngles, R):
    if nCoordAngles > 0:                 # a count, not a table: the guard's rows check does not apply
        update_coordinate_angles(jointIndex, jointFrames, jointAngles, rowIndex, coordSpringEnds,
                                 coordSpringFrames, springAngles, R)


_coordinate_angles_if = guarded(_coordinate_angles)


@njit(cache=True, inline="always", _nrt=False)
def observe_coordinate_angles(sd, wk, R, r, V):
    """The rotation coordinates of the coordinate items (springs and constraints)."""
    _coordinate_angles_if(sd.nCoordAngles, sd.nCoordAngles, sd.jointIndex, sd.jointFrames, wk.path.jointAngles,
                          sd.rowIndex, sd.coordSpringEnds, sd.coordSpringFrames, wk.path.springAngles, R)


@njit(cache=True, inline="always", _nrt=False)
def observe_tracked_bodies(sd, wk, R, r, V):
    """The angle of each 2D body / rotor and the rotation parameters of each tracked body."""
    if wk.track.nTracked > 0:
        update_tracked_bodies(wk.track.trackCodes, wk.track.angleFrames, wk.path.bodyAngles, wk.path.bodyParameters,
                              R)


@njit(cache=True, inline="always", _nrt=False)
def observe_contact_data(sd, wk, R, r, V):
    """The penalty rolling discs' data coordinates: slip velocity and gap of the new state."""
    _disc_data_if(wk.path.rollingDiscs, sd.gid, wk.path.rollingDiscs, R, r, V, wk.v3, wk.ident, wk.zero3, wk.zero6)


@njit(cache=True, _nrt=False)
def watch_rotation_entries(watchBody, watchEntry, watchMax, R):
    """Largest |R[body][i, j]| of the watched entries over the accepted steps (cheap
    monitoring between outputs, e.g. of a coordinate singularity; none by default)."""
    for w in range(watchBody.shape[0]):
        a = abs(R[watchBody[w], watchEntry[w, 0], watchEntry[w, 1]])
        if a > watchMax[w]:
            watchMax[w] = a


@njit(cache=True, inline="always", _nrt=False)
def observe_watched_entries(sd, wk, R, r, V):
    if wk.track.watchBody.shape[0] > 0:
        watch_rotation_entries(wk.track.watchBody, wk.track.watchEntry, wk.path.watchMax, R)


def _has_rows(table):
    return table is not None and table.shape[0] > 0


# ---------------------------------------------------------------- the registrations
register_observer("torsionTurns", observe_torsion_turns, True, lambda sd, wk: _has_rows(sd.torsionBodies))
register_observer("coordinateAngles", observe_coordinate_angles, True, lambda sd, wk: (sd.nCoordAngles or 0) > 0)
register_observer("trackedBodies", observe_tracked_bodies, True, lambda sd, wk: wk.track.nTracked > 0)
register_observer("contactData", observe_contact_data, False, lambda sd, wk: _has_rows(wk.path.rollingDiscs))
register_observer("watchedEntries", observe_watched_entries, False, lambda sd, wk: wk.track.watchBody.shape[0] > 0)


# ---------------------------------------------------------------- generated from the registrations
def _calls(observers):
    return [f"observer{OBSERVERS.index(o)}(sd, wk, R, r, V)" for o in observers]


_ENV = {f"observer{k}": o.update for k, o in enumerate(OBSERVERS)}

after_accepted_step = njit(cache=True, inline="always", _nrt=False)(generate(
    "after_accepted_step", "def after_accepted_step(sd, wk, R, r, V):", _calls(OBSERVERS), [], dict(_ENV),
    "Every step observer after an accepted step, in registration order.", sys.modules[__name__]))

observe_initial_state = njit(cache=True, _nrt=False)(generate(
    "observe_initial_state", "def observe_initial_state(sd, wk, R, r, V):",
    _calls([o for o in OBSERVERS if o.atStart]), [], dict(_ENV),
    "The observers registered with ``atStart`` at an initial state.", sys.modules[__name__]))


_SEALED = True


def observed_at_start(sd, wk):
    """The names of the ``atStart`` observers the scene has (Python side)."""
    return [o.name for o in OBSERVERS if o.atStart and o.present(sd, wk)]
