"""Rotation parameters of the bodies tracked after every accepted step (a step observer, for
the coordinate items on rotation parameters and for a write-back of node coordinates,
bridge/node_writers.py): the parameters reached by integrating them continuously, i.e. for a
rotation ``R`` the branch nearest to the parameters at the last accepted step (one step turns a
body by far less than pi):

* ``TRACK_QUAT``: the unit quaternion of ``R`` with the sign nearest the previous one - Euler
  parameters integrated continuously, and the quaternion behind a rotation vector that is
  updated by composing quaternions: ``2 acos(q0) qv / |qv|`` (:func:`quat_rotvec`; |theta| <=
  2 pi, turning over at 2 pi, not at pi);
* ``TRACK_TAIT_BRYAN``: Tait-Bryan angles ``R = Rx(a0) Ry(a1) Rz(a2)``, the solution of the two
  (each modulo 2 pi) nearest the previous angles;
* ``TRACK_ANGLE``: the angle of a 2D body / rotor (coordinate_angles.frame_angle, kept in
  ``PathState.bodyAngles``).

:func:`update_tracked_bodies` moves them on after every accepted step; the node parameters
live in ``PathState.bodyParameters`` (``TrackPlan.trackCodes`` the code per body), and all are
recorded with every output row (stepper.mk_steps, adaptive.serve_outputs) by
:func:`record_tracked`.
"""
import math

import numpy as np
from numba import njit

from .coordinate_angles import frame_angle

TRACK_NONE = 0
TRACK_ANGLE = 1
TRACK_QUAT = 2
TRACK_TAIT_BRYAN = 3
TWO_PI = 2.0 * math.pi


@njit(cache=True, inline="always", _nrt=False)
def quat_scalars(R):
    """Unit quaternion (scalar first, >= 0) of R, Shepperd's method, as four scalars."""
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr >= R[0, 0] and tr >= R[1, 1] and tr >= R[2, 2]:
        s = 2.0 * math.sqrt(max(1.0 + tr, 0.0))
        a, b, c, d = 0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s
    elif R[0, 0] >= R[1, 1] and R[0, 0] >= R[2, 2]:
        s = 2.0 * math.sqrt(max(1.0 + R[0, 0] - R[1, 1] - R[2, 2], 0.0))
        a, b, c, d = (R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s
    elif R[1, 1] >= R[2, 2]:
        s = 2.0 * math.sqrt(max(1.0 - R[0, 0] + R[1, 1] - R[2, 2], 0.0))
        a, b, c, d = (R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s
    else:
        s = 2.0 * math.sqrt(max(1.0 - R[0, 0] - R[1, 1] + R[2, 2], 0.0))
        a, b, c, d = (R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s
    n = math.sqrt(a * a + b * b + c * c + d * d)
    if a < 0.0:
        n = -n
    return a / n, b / n, c / n, d / n


@njit(cache=True, _nrt=False)
def quat_of(R, out):
    """Unit quaternion (scalar first, >= 0) of R, Shepperd's method."""
    out[0], out[1], out[2], out[3] = quat_scalars(R)


@njit(cache=True, _nrt=False)
def nearest_quat(R, ref, out):
    """The quaternion of R (``out``, may be ``ref`` itself) with the sign nearest ``ref``."""
    f0, f1, f2, f3 = ref[0], ref[1], ref[2], ref[3]
    quat_of(R, out)
    if out[0] * f0 + out[1] * f1 + out[2] * f2 + out[3] * f3 < 0.0:
        for k in range(4):
            out[k] = -out[k]


@njit(cache=True, _nrt=False)
def quat_rotvec(q, out):
    """The rotation vector of the quaternion q (either sign): ``2 acos(q0) qv / |qv|``,
    |theta| in [0, 2 pi] (what a composition of quaternions returns)."""
    s = math.sqrt(q[1] ** 2 + q[2] ** 2 + q[3] ** 2)
    w = 2.0 * math.atan2(s, q[0])
    if s > 1e-12:
        fac = w / s
    elif q[0] > 0.0:
        fac = 2.0 / q[0]                 # small angle: w / s -> 2 / q0
    else:
        fac = w / s if s > 0.0 else 0.0
    for k in range(3):
        out[k] = q[1 + k] * fac


@njit(cache=True, _nrt=False)
def rotvec_quat(p, out):
    """The quaternion ``(cos(t/2), sin(t/2) p / t)``, ``t = |p|``, of the rotation vector p (the inverse
    of :func:`quat_rotvec` for |p| <= 2 pi); below t = 1e-4 the series of sin(t/2) / t to t^4, whose
    next term, t^6 / 645120, is below the rounding of 1/2."""
    t2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2]
    t = math.sqrt(t2)
    if t < 1e-4:
        s = 0.5 - t2 / 48.0 + t2 * t2 / 3840.0
    else:
        s = math.sin(0.5 * t) / t
    out[0] = math.cos(0.5 * t)
    for k in range(3):
        out[1 + k] = s * p[k]


@njit(cache=True, inline="always", _nrt=False)
def wrap_near(x, ref):
    # np.rint, not np.round: the same value (round half to even), but np.round's numba
    # implementation lives in numba.np.arraymath, which imports scipy.linalg when a
    # cached kernel is loaded (0.12 s of a warm start)
    return x + TWO_PI * np.rint((ref - x) / TWO_PI)


@njit(cache=True, _nrt=False)
def nearest_tait_bryan(R, ref, out):
    """Tait-Bryan angles of ``R = Rx Ry Rz`` (``out`` may be ``ref`` itself): of the two solutions (a0, a1, a2) and
    (a0 + pi, pi - a1, a2 + pi), each shifted by 2 pi turns, the one nearest ``ref``; at the
    gimbal lock (a1 = +-pi/2) only a0 +- a2 is defined: a0 is kept."""
    c1 = math.sqrt(R[1, 2] ** 2 + R[2, 2] ** 2)
    a1 = math.atan2(R[0, 2], c1)
    if c1 > 1e-14:
        a0 = math.atan2(-R[1, 2], R[2, 2])
        a2 = math.atan2(-R[0, 1], R[0, 0])
    else:
        a0 = 0.0
        a2 = math.atan2(R[1, 0], R[1, 1])
    if c1 < 1e-7:
        sg = 1.0 if a1 > 0 else -1.0
        comb = a0 + sg * a2
        out[0] = ref[0]
        out[1] = wrap_near(a1, ref[1])
        out[2] = wrap_near(sg * (comb - ref[0]), ref[2])
        return
    b0 = wrap_near(a0, ref[0])
    b1 = wrap_near(a1, ref[1])
    b2 = wrap_near(a2, ref[2])
    e0 = wrap_near(a0 + math.pi, ref[0])
    e1 = wrap_near(math.pi - a1, ref[1])
    e2 = wrap_near(a2 + math.pi, ref[2])
    d0 = (b0 - ref[0]) ** 2 + (b1 - ref[1]) ** 2 + (b2 - ref[2]) ** 2
    d1 = (e0 - ref[0]) ** 2 + (e1 - ref[1]) ** 2 + (e2 - ref[2]) ** 2
    if d0 <= d1:
        out[0], out[1], out[2] = b0, b1, b2
    else:
        out[0], out[1], out[2] = e0, e1, e2


@njit(cache=True, _nrt=False)
def nearest_parameters(code, R, ref, out):
    """The parameters of kind ``code`` of R nearest ``ref`` (TRACK_QUAT / TRACK_TAIT_BRYAN)."""
    if code == TRACK_QUAT:
        nearest_quat(R, ref, out)
    elif code == TRACK_TAIT_BRYAN:
        nearest_tait_bryan(R, ref, out)


@njit(cache=True, _nrt=False)
def update_tracked_bodies(trackCodes, angleFrames, bodyAngles, bodyParameters, R):
    """Move what is tracked of every body to its rotation after an accepted step: the angle of
    a 2D body / rotor (continued over turns, coordinate_angles.frame_angle) and the node
    rotation parameters (the quaternion case, every tracked body of most models, with
    scalars only: it runs every step).  One call, not inlined into the stepper."""
    for i in range(trackCodes.shape[0]):
        c = trackCodes[i]
        if c == TRACK_ANGLE:
            bodyAngles[i] = frame_angle(angleFrames[i], R[i], bodyAngles[i])
        elif c == TRACK_QUAT:
            q0, q1, q2, q3 = quat_scalars(R[i])
            if q0 * bodyParameters[i, 0] + q1 * bodyParameters[i, 1] + q2 * bodyParameters[i, 2] + q3 * bodyParameters[i, 3] < 0.0:
                q0, q1, q2, q3 = -q0, -q1, -q2, -q3
            bodyParameters[i, 0], bodyParameters[i, 1], bodyParameters[i, 2], bodyParameters[i, 3] = q0, q1, q2, q3
        elif c == TRACK_TAIT_BRYAN:
            nearest_tait_bryan(R[i], bodyParameters[i], bodyParameters[i])


@njit(cache=True, _nrt=False)
def record_tracked(trackCodes, bodyAngles, bodyParameters, out):
    """The tracked values at the current state into an output row ``out`` (nb, 4): the
    angle (TRACK_ANGLE) in column 0, node parameters otherwise."""
    for i in range(trackCodes.shape[0]):
        c = trackCodes[i]
        if c == TRACK_ANGLE:
            out[i, 0] = bodyAngles[i]
        elif c != TRACK_NONE:
            for k in range(4):
                out[i, k] = bodyParameters[i, k]


@njit(cache=True, _nrt=False)
def tracked_at(trackCodes, angleFrames, bodyAngles, bodyParameters, R, out):
    """The tracked values at a state ``R`` near the tracked one (a dense output inside the
    last accepted step) into ``out`` (nb, 4): each nearest its value at the step's end."""
    for i in range(trackCodes.shape[0]):
        c = trackCodes[i]
        if c == TRACK_ANGLE:
            out[i, 0] = frame_angle(angleFrames[i], R[i], bodyAngles[i])
        elif c != TRACK_NONE:
            nearest_parameters(c, R[i], bodyParameters[i], out[i])
