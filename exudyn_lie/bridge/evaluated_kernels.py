"""Compiled pieces of the Exudyn-evaluated path (:mod:`.evaluated`, :mod:`.evaluated_problem`):
one numba call per stage before Exudyn evaluates the model, one after.

The Lie group nodes (``NodeRigidBodyRotVecLG``) are bodies with a group id of the
registry (SE3 / SO3xR3) of the one compiled stepper (:mod:`exudyn_lie.mbs.stepper`: eq. MK1,
``g_j = g exp(Psi_j)``, ``k_j = dexp^-1_{-Psi_j} V_j``), so both paths integrate the same ODE
with the same arithmetic.  Their state velocity is the kernel's: SE3 the body twist ``(omega, U)``,
``U = R^T rdot``; SO3xR3 ``(omega, rdot)``.  Exudyn's velocity coordinates of such a node are
``[rdot (global), omega (local)]`` (DESIGN.md, facts).

Every other ODE2 coordinate is a vector-space coordinate with ``qdot = v`` (mass points,
2D bodies, EP / Rxyz nodes, ANCF, GenericODE2, ...), integrated with the same tableau.
"""
import numpy as np
from numba import njit

from ..groups import so3
from ..mbs.codes import uses_body_twist
from ..mbs.stepper import copy_state
from .node_writers import rotvec_row


@njit(cache=True)
def _rotvec_continuous(R, prev, p, qnew):
    """Rotation vector ``p`` of R by the compiled path's rule for the same node type
    (bridge/node_writers.rotvec_row): the quaternion of R with the sign nearest ``prev``, the
    quaternion last written (kept, not the rotation vector: at the turnover near 2 pi that rule
    writes the short vector of the same rotation, whose quaternion has the other sign), so that it
    passes |p| = pi and turns over at 2 pi as Exudyn's Lie group update does; ``qnew`` receives the
    quaternion written."""
    z = np.zeros(3)
    for k in range(4):
        qnew[k] = prev[k]
    rotvec_row(R, z, z, qnew, False, p, z.copy(), z.copy(), np.empty(4))


@njit(cache=True)
def write_exudyn_state(gid, R, r, V, lgIdx, lgRef, prev, q, qt, vecIdx, qv, vv, rv, rq):
    """Exudyn's ODE2 coordinates ``q`` and velocities ``qt`` (mbs' Current views) of the
    state: a Lie group node writes ``log(R)`` minus the reference rotation vector (Exudyn:
    total = reference + current, componentwise), ``r`` minus the reference position,
    ``rdot = R U`` (SE3) or ``rdot`` (SO3xR3) and the local ``omega``; the vector-space
    coordinates are copied.  ``prev`` (nl, 4) the quaternions last written; ``rv`` (nl, 3),
    ``rq`` (nl, 4) receive the rotation vectors and quaternions written.  Returns ``max |qt|``
    (the velocity scale of eta's differentiation step)."""
    for i in range(gid.shape[0]):
        _rotvec_continuous(R[i], prev[i], rv[i], rq[i])
        Vi = V[i]
        body = uses_body_twist(gid[i])
        for k in range(3):
            q[lgIdx[i, k]] = r[i, k] - lgRef[i, k]
            q[lgIdx[i, 3 + k]] = rv[i, k] - lgRef[i, 3 + k]
            if body:
                qt[lgIdx[i, k]] = R[i, k, 0] * Vi[3] + R[i, k, 1] * Vi[4] + R[i, k, 2] * Vi[5]
            else:
                qt[lgIdx[i, k]] = Vi[3 + k]
            qt[lgIdx[i, 3 + k]] = Vi[k]
    for k in range(vecIdx.shape[0]):
        q[vecIdx[k]] = qv[k]
        qt[vecIdx[k]] = vv[k]
    vmax = 0.0
    for k in range(qt.shape[0]):
        vmax = max(vmax, abs(qt[k]))
    return vmax


@njit(cache=True)
def write_moved_positions(R, r, lgIdx, lgRef, prev, q, qt, vecIdx, qv, eps, ER, rv):
    """Exudyn's ODE2 coordinates of the configuration moved along the motion by ``eps``
    seconds at fixed velocities ``qt`` (for the acceleration term eta, :mod:`.evaluated`):
    a Lie group node ``R exp(eps omega)``, ``r + eps rdot`` (omega local, rdot global, read
    from ``qt``); vector coordinates ``q + eps v``.  ``prev`` (nl, 4): the quaternions last written."""
    w = np.empty(3)
    qnew = np.empty(4)
    for i in range(R.shape[0]):
        for k in range(3):
            w[k] = eps * qt[lgIdx[i, 3 + k]]
        so3.exp_into(w, ER)
        Rm = R[i] @ ER
        _rotvec_continuous(Rm, prev[i], rv[i], qnew)
        for k in range(3):
            q[lgIdx[i, k]] = r[i, k] + eps * qt[lgIdx[i, k]] - lgRef[i, k]
            q[lgIdx[i, 3 + k]] = rv[i, k] - lgRef[i, 3 + k]
    for k in range(vecIdx.shape[0]):
        q[vecIdx[k]] = qv[k] + eps * qt[vecIdx[k]]


@njit(cache=True)
def unpack_state(gid, R, r, V, nvb, lgIdx, lgRef, prev, q, qt, vecIdx, qv, vv, y, rv, rq):
    """Exudyn's ``q``, ``qt`` (and the ODE1 coordinates ``y``) of a state of the problem's
    bodies (:mod:`.evaluated_problem`): the first ``nl = gid.size`` bodies are the Lie group
    nodes (:func:`write_exudyn_state`), the next ``nvb`` hold the vector-space ODE2
    coordinates three by three (position ``r``, velocity ``V[3:6]``), the rest the ODE1
    coordinates three by three (``V[3:6]``).  ``qv``, ``vv`` receive the vector coordinates,
    ``rv``, ``rq`` the rotation vectors and quaternions written.  Returns ``max |qt|``."""
    nl = gid.shape[0]
    nv = qv.shape[0]
    for k in range(nv):
        b = nl + k // 3
        qv[k] = r[b, k % 3]
        vv[k] = V[b, 3 + k % 3]
    for k in range(y.shape[0]):
        y[k] = V[nl + nvb + k // 3, 3 + k % 3]
    return write_exudyn_state(gid, R[:nl], r[:nl], V[:nl], lgIdx, lgRef, prev, q, qt, vecIdx, qv, vv, rv, rq)


@njit(cache=True)
def pack_rates(gid, R, V, acc, lgIdx, vecIdx, ydot, nvb, Vdot):
    """``Vdot`` of the problem's bodies from Exudyn's accelerations ``acc`` (nODE2) and ODE1
    rates ``ydot``: per Lie group node the group velocity rates (SO3xR3: ``(omegadot,
    rddot)``; SE3: ``(omegadot, R^T rddot - omega x U)``, from ``rdot = R U``), per vector
    body ``(0, vdot)``, per ODE1 body ``(0, ydot)``; padding rows 0."""
    nl = gid.shape[0]
    for i in range(Vdot.shape[0]):
        for k in range(6):
            Vdot[i, k] = 0.0
    for i in range(nl):
        Vdi = Vdot[i]
        for k in range(3):
            Vdi[k] = acc[lgIdx[i, 3 + k]]
        if uses_body_twist(gid[i]):
            w = V[i]
            Ri = R[i]
            for k in range(3):
                Vdi[3 + k] = (Ri[0, k] * acc[lgIdx[i, 0]] + Ri[1, k] * acc[lgIdx[i, 1]] + Ri[2, k] * acc[lgIdx[i, 2]])
            Vdi[3] -= w[1] * w[5] - w[2] * w[4]
            Vdi[4] -= w[2] * w[3] - w[0] * w[5]
            Vdi[5] -= w[0] * w[4] - w[1] * w[3]
        else:
            for k in range(3):
                Vdi[3 + k] = acc[lgIdx[i, k]]
    for k in range(vecIdx.shape[0]):
        Vdot[nl + k // 3, 3 + k % 3] = acc[vecIdx[k]]
    for k in range(ydot.shape[0]):
        Vdot[nl + nvb + k // 3, 3 + k % 3] = ydot[k]


@njit(cache=True)
def pack_state(gid, Rl, rl, Vl, qv, vv, y, nvb, R, r, V):
    """The problem's body state from the Lie group nodes' ``Rl, rl, Vl``, the vector
    coordinates ``qv, vv`` and the ODE1 coordinates ``y`` (the layout of
    :func:`unpack_state`; padding and the ODE1 bodies' positions 0, the packed bodies'
    rotations I)."""
    nl = gid.shape[0]
    for i in range(nl, R.shape[0]):
        for a in range(3):
            r[i, a] = 0.0
            for c in range(3):
                R[i, a, c] = 1.0 if a == c else 0.0
        for k in range(6):
            V[i, k] = 0.0
    copy_state(Rl, rl, Vl, R[:nl], r[:nl], V[:nl])
    for k in range(qv.shape[0]):
        r[nl + k // 3, k % 3] = qv[k]
        V[nl + k // 3, 3 + k % 3] = vv[k]
    for k in range(y.shape[0]):
        V[nl + nvb + k // 3, 3 + k % 3] = y[k]


@njit(cache=True)
def euler_parameter_eta(qt, coords, rows, out):
    """``out[rows[i]] = -2 |p_t|^2`` of the Euler parameters at ``coords[i]`` (evaluated.py, ``eta``)."""
    for i in range(rows.shape[0]):
        s = 0.0
        for k in range(4):
            v = qt[coords[i, k]]
            s += v * v
        out[rows[i]] = -2.0 * s
