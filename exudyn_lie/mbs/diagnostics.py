"""Diagnostics at a state: energies and the constraint rows of every joint."""
import numpy as np
from numba import njit

from .bodies import _side, body_point, body_twist
from .constraints import joints_rows
from .coordinate_forces import coordinate_spring_energy
from .forces import torsion_angle


# --------------------------------------------------------------------------- diagnostics
@njit(cache=True, _nrt=False)
def kinetic_and_gravity(gid, M, mass, com, gravity, R, r, V, Vb):
    """(kinetic energy, gravity potential) of all bodies."""
    ekin = 0.0
    egrav = 0.0
    for i in range(gid.shape[0]):
        body_twist(gid[i], R[i], V[i], Vb)
        for a in range(6):
            for c in range(6):
                ekin += 0.5 * Vb[a] * M[i, a, c] * Vb[c]
        for k in range(3):
            xc = r[i, k] + R[i, k, 0] * com[i, 0] + R[i, k, 1] * com[i, 1] + R[i, k, 2] * com[i, 2]
            egrav -= mass[i] * gravity[k] * xc
    return ekin, egrav


@njit(cache=True, _nrt=False)
def spring_energy(gid, sint, spos, spar, cint, cpos, cpar, tint, trot, tpar, tphi, R, r, V, v3, m3, ident, zero3,
                  zero6):
    """Potential energy of the point-to-point, Cartesian and torsional springs."""
    pA, pB, vA, vB, bA, bB = v3[0], v3[1], v3[2], v3[3], v3[4], v3[5]
    espr = 0.0
    for s in range(sint.shape[0]):
        gA, RA, rA, VA = _side(gid, sint[s, 0], R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, sint[s, 1], R, r, V, ident, zero3, zero6)
        body_point(gA, RA, rA, VA, spos[s, 0], pA, vA, bA)
        body_point(gB, RB, rB, VB, spos[s, 1], pB, vB, bB)
        L = np.sqrt((pB[0] - pA[0]) ** 2 + (pB[1] - pA[1]) ** 2 + (pB[2] - pA[2]) ** 2)
        espr += 0.5 * spar[s, 0] * (L - spar[s, 2]) ** 2 + spar[s, 3] * L
    for s in range(cint.shape[0]):
        gA, RA, rA, VA = _side(gid, cint[s, 0], R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, cint[s, 1], R, r, V, ident, zero3, zero6)
        body_point(gA, RA, rA, VA, cpos[s, 0], pA, vA, bA)
        body_point(gB, RB, rB, VB, cpos[s, 1], pB, vB, bB)
        for k in range(3):
            espr += 0.5 * cpar[s, 0, k] * (pB[k] - pA[k] - cpar[s, 2, k]) ** 2
    for s in range(tint.shape[0]):
        gA, RA, rA, VA = _side(gid, tint[s, 0], R, r, V, ident, zero3, zero6)
        gB, RB, rB, VB = _side(gid, tint[s, 1], R, r, V, ident, zero3, zero6)
        phi, phid = torsion_angle(trot[s, 0], trot[s, 1], tphi[s], RA, VA, RB, VB, m3[0], m3[1])
        espr += 0.5 * tpar[s, 0] * (phi - tpar[s, 2]) ** 2 + tpar[s, 3] * phi
    return espr


@njit(cache=True, _nrt=False)
def all_rows(sd, wk, R, r, V, h, Jr, eta, e):
    """Diagnostics at the state (R, r, V): residuals ``h``, Jacobian rows ``Jr`` and
    ``eta`` of every joint, and ``e`` = (kinetic, gravity potential, spring potential)."""
    joints_rows(sd.gid, sd.jint, sd.jpos, sd.jrot, sd.jpar, sd.rint, wk.bparam, R, r, V, h, Jr, eta, wk.v3, wk.ident, wk.zero3,
                wk.zero6)
    ekin, egrav = kinetic_and_gravity(sd.gid, sd.M, sd.mass, sd.com, sd.gravity, R, r, V, wk.tmp6)
    e[0] = ekin
    e[1] = egrav
    e[2] = spring_energy(sd.gid, sd.sint, sd.spos, sd.spar, sd.cint, sd.cpos, sd.cpar, sd.tint, sd.trot, sd.tpar,
                         wk.tphi, R, r, V, wk.v3, wk.m3, wk.ident, wk.zero3, wk.zero6)
    if sd.kint.shape[0] > 0:
        e[2] += coordinate_spring_energy(sd.gid, sd.kint, sd.kpar, sd.krot, wk.bparam, R, r, V, wk.v3, wk.ident, wk.zero3, wk.zero6)
