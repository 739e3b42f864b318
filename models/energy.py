"""Mechanical energy of a model's state, from the model description alone.

``T = 1/2 m |v_c|^2 + 1/2 omega . Theta_c omega`` per body, gravity potential
``-m g . x_c``, springs ``1/2 k (L - L0)^2`` with ``L`` the distance of the attachment
points (the paper's heavy-top spring has ``L0 = 0``).  Used for Exudyn's native runs
and to check the kernel's energy bookkeeping.
"""
import numpy as np

GROUND = -1


def _point(R, r, b, p):
    if b == GROUND:
        return np.broadcast_to(np.asarray(p, float), (R.shape[0], 3))
    return r[:, b] + np.einsum("nij,j->ni", R[:, b], p)


def energies(info, R, r, omega, vel):
    """(nt, 3) array: kinetic, gravity potential, spring energy.

    ``omega``: body-fixed angular velocities (nt, nb, 3); ``vel``: world velocities of
    the body frame origins (nt, nb, 3)."""
    R = np.asarray(R, float)
    nt = R.shape[0]
    out = np.zeros((nt, 3))
    g = np.asarray(info.gravity, float)
    for i, b in enumerate(info.bodies):
        w = omega[:, i]
        Rc = np.einsum("nij,j->ni", R[:, i], b.com)
        vc = vel[:, i] + np.cross(np.einsum("nij,nj->ni", R[:, i], w), Rc)
        out[:, 0] += 0.5 * b.mass * np.einsum("ni,ni->n", vc, vc) + \
            0.5 * np.einsum("ni,ij,nj->n", w, b.inertiaCOM, w)
        out[:, 1] -= b.mass * ((r[:, i] + Rc) @ g)
    for s in info.springs:
        L = np.linalg.norm(_point(R, r, s.bodyB, s.posB) - _point(R, r, s.bodyA, s.posA), axis=1)
        out[:, 2] += 0.5 * s.stiffness * (L - s.referenceLength) ** 2
    return out
