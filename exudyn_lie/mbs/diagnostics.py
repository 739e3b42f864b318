"""Diagnostics at a state: energies and the constraint rows of every joint."""
import numpy as np
from numba import njit

from .bodies import body_twist
from .constraints import joints_rows
from .force_elements import spring_energy


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
def all_rows(sd, wk, R, r, V, h, Jr, eta, e):
    """Diagnostics at the state (R, r, V): residuals ``h``, Jacobian rows ``Jr`` and
    ``eta`` of every joint, and ``e`` = (kinetic, gravity potential, spring potential)."""
    joints_rows(sd.gid, sd.jint, sd.jpos, sd.jrot, sd.jpar, sd.rint, sd.rowsAll, wk.bparam, R, r, V, h, Jr, eta, wk.rdrive, wk.v3, wk.ident,
                wk.zero3, wk.zero6)
    ekin, egrav = kinetic_and_gravity(sd.gid, sd.M, sd.mass, sd.com, sd.gravity, R, r, V, wk.tmp6)
    e[0] = ekin
    e[1] = egrav
    e[2] = spring_energy(sd, wk, R, r, V)       # the registered force elements' (mbs/force_elements.py)
