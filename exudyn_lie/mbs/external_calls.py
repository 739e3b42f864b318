"""The compiled side of the stepper's seam to Python (:mod:`.external`): the Python forces of a
stage and a whole right-hand side from outside, each one call of the registered evaluator
(:func:`call_evaluator`), with the compiled work around the call.  :func:`~.stepper.stage_rhs`
calls them."""
import numpy as np
from numba import njit

from . import external
from .bodies import add_point_force_origin, add_world_torque_row, body_world_velocity
from .codes import STATUS_EXTERNAL, STATUS_OK
from .external_probes import probe_kinematics
from .presence import guarded


@njit(cache=True, _nrt=False)
def call_evaluator(token, t):
    """``external.call(token, t)``: the evaluator whose :func:`~.external.handle` is ``token``."""
    return external.call(token, t)


_probe_kinematics_if = guarded(probe_kinematics)


@njit(cache=True, _nrt=False)
def external_forces(token, gid, t, Rs, rs, Vs, Vw, Qext, ext, probe):
    """The right-hand side seam (:mod:`.external`), one Python call per stage.

    Before the call, compiled: the world velocities ``Vw = (omega, rdot)`` of the stage
    state, ``Qext = 0`` and the kinematics the Python items read (``probe``,
    :mod:`.external_probes`).  The call passes only ``(token, t)`` (no array is boxed: the
    evaluator holds views of ``wk.Rs, wk.rs, wk.Vw, wk.Qext``) and the evaluator adds the
    world forces at the frame origins and the world torques, ``Qext[i] = (F_i, T_i)``.
    After it, compiled: ``Qext[i]`` becomes the generalised force of ``(F_i, T_i)``
    (:func:`~.bodies.add_point_force`, :func:`~.bodies.add_world_torque`), after a check
    that they are finite (``ext[1] = 1`` otherwise).  Returns a status code."""
    for i in range(gid.shape[0]):
        body_world_velocity(gid[i], Rs[i], Vs[i], Vw[i])
        for k in range(6):
            Qext[i, k] = 0.0
    _probe_kinematics_if(probe, Rs, rs, Vw, probe)      # probe None: no item reads any (no code)
    if call_evaluator(token, t):
        return STATUS_EXTERNAL
    for i in range(gid.shape[0]):
        f0, f1, f2 = Qext[i, 0], Qext[i, 1], Qext[i, 2]
        m0, m1, m2 = Qext[i, 3], Qext[i, 4], Qext[i, 5]
        if not (np.isfinite(f0 + f1 + f2) and np.isfinite(m0 + m1 + m2)):
            ext[1] = 1
            return STATUS_EXTERNAL
        # the world force (at the frame origin) and torque in place of the row: Vw[i] is free now
        Vw[i, 0], Vw[i, 1], Vw[i, 2] = f0, f1, f2
        Vw[i, 3], Vw[i, 4], Vw[i, 5] = m0, m1, m2
        for k in range(6):
            Qext[i, k] = 0.0
        add_point_force_origin(gid[i], Rs[i], Vw[i], Qext[i])
        add_world_torque_row(Rs[i], Vw[i], Qext[i])
    return STATUS_OK


@njit(cache=True, _nrt=False)
def external_rates(token, t, Vout, Vdot, ext):
    """The whole right-hand side from outside (``EXTERNAL_RATES``): the evaluator writes the
    stage's ``Vdot`` into ``Vout`` (``wk.Qext``, which it holds a view of), copied here after a
    check that it is finite (``ext[1] = 1`` otherwise).  Returns a status code."""
    if call_evaluator(token, t):
        return STATUS_EXTERNAL
    for i in range(Vout.shape[0]):
        for k in range(6):
            x = Vout[i, k]
            if not np.isfinite(x):
                ext[1] = 1
                return STATUS_EXTERNAL
            Vdot[i, k] = x
    return STATUS_OK
