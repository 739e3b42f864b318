"""Rotation parametrisations used by Exudyn's rigid-body nodes, in plain numpy.

All functions work on batches: a leading axis ``n`` (one row per node).  They are
derived here (not taken from Exudyn) and checked against ``exudyn.rigidBodyUtilities``
in ``tests/test_bridge_nodes.py``.

* rotation vector ``theta``: ``R = exp(hat(theta))`` (Rodrigues);
* Euler parameters ``ep = (e0, e1, e2, e3)`` (unit quaternion, scalar first):
  ``R = (e0^2 - |e|^2) I + 2 e e^T + 2 e0 hat(e)``,
  ``omega_local = GL(ep) ep_t`` with ``GL(ep) = 2 [-e, e0 I - hat(e)]`` (3x4);
* Tait-Bryan angles ``a = (a0, a1, a2)``: ``R = Rx(a0) Ry(a1) Rz(a2)``,
  ``omega_local = GR(a) a_t`` with
  ``GR = [[c1 c2, s2, 0], [-c1 s2, c2, 0], [s1, 0, 1]]`` (singular at ``c1 = 0``).
"""
import numpy as np

TWO_PI = 2.0 * np.pi


def skew(x):
    x = np.asarray(x, float)
    S = np.zeros(x.shape[:-1] + (3, 3))
    S[..., 0, 1] = -x[..., 2]
    S[..., 0, 2] = x[..., 1]
    S[..., 1, 0] = x[..., 2]
    S[..., 1, 2] = -x[..., 0]
    S[..., 2, 0] = -x[..., 1]
    S[..., 2, 1] = x[..., 0]
    return S


# ---------------------------------------------------------------- rotation vector
def rotvec_to_matrix(theta):
    """Rodrigues' formula for a batch (n, 3) -> (n, 3, 3); exact for any |theta|."""
    th = np.atleast_2d(np.asarray(theta, float))
    t = np.linalg.norm(th, axis=1)
    W = skew(th)
    small = t < 1e-4
    ts = np.where(small, 1.0, t)
    # sin(t)/t and (1 - cos t)/t^2 with half angles (no cancellation); Taylor below 1e-4
    a = np.where(small, 1.0 - t * t / 6.0, np.sin(ts) / ts)
    hs = np.sin(0.5 * ts)
    b = np.where(small, 0.5 - t * t / 24.0, 2.0 * hs * hs / (ts * ts))
    return np.eye(3) + a[:, None, None] * W + b[:, None, None] * (W @ W)


def matrix_to_quaternion(R):
    """Unit quaternions (n, 4), scalar first and >= 0, by Shepperd's method."""
    R = np.asarray(R, float).reshape(-1, 3, 3)
    n = R.shape[0]
    q = np.zeros((n, 4))
    tr = R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2]
    diag = np.stack([tr, R[:, 0, 0], R[:, 1, 1], R[:, 2, 2]], axis=1)
    k = np.argmax(diag, axis=1)
    for i in range(n):
        Ri = R[i]
        if k[i] == 0:
            s = 2.0 * np.sqrt(max(1.0 + tr[i], 0.0))
            q[i] = [0.25 * s, (Ri[2, 1] - Ri[1, 2]) / s, (Ri[0, 2] - Ri[2, 0]) / s, (Ri[1, 0] - Ri[0, 1]) / s]
        elif k[i] == 1:
            s = 2.0 * np.sqrt(max(1.0 + Ri[0, 0] - Ri[1, 1] - Ri[2, 2], 0.0))
            q[i] = [(Ri[2, 1] - Ri[1, 2]) / s, 0.25 * s, (Ri[0, 1] + Ri[1, 0]) / s, (Ri[0, 2] + Ri[2, 0]) / s]
        elif k[i] == 2:
            s = 2.0 * np.sqrt(max(1.0 - Ri[0, 0] + Ri[1, 1] - Ri[2, 2], 0.0))
            q[i] = [(Ri[0, 2] - Ri[2, 0]) / s, (Ri[0, 1] + Ri[1, 0]) / s, 0.25 * s, (Ri[1, 2] + Ri[2, 1]) / s]
        else:
            s = 2.0 * np.sqrt(max(1.0 - Ri[0, 0] - Ri[1, 1] + Ri[2, 2], 0.0))
            q[i] = [(Ri[1, 0] - Ri[0, 1]) / s, (Ri[0, 2] + Ri[2, 0]) / s, (Ri[1, 2] + Ri[2, 1]) / s, 0.25 * s]
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    q /= np.linalg.norm(q, axis=1)[:, None]
    return q


def matrix_to_rotvec(R):
    """Principal rotation vectors (n, 3), |theta| <= pi, robust near 0 and pi."""
    q = matrix_to_quaternion(R)
    v = q[:, 1:]
    s = np.linalg.norm(v, axis=1)
    t = 2.0 * np.arctan2(s, q[:, 0])
    small = s < 1e-12
    fac = np.where(small, 2.0 / np.where(q[:, 0] == 0, 1.0, q[:, 0]), t / np.where(small, 1.0, s))
    return v * fac[:, None]


# ---------------------------------------------------------------- Euler parameters
def ep_to_matrix(ep):
    """Rotation matrices of (unit) Euler parameters (n, 4)."""
    ep = np.atleast_2d(np.asarray(ep, float))
    e0 = ep[:, 0]
    e = ep[:, 1:]
    R = (e0 * e0 - np.einsum("ni,ni->n", e, e))[:, None, None] * np.eye(3)
    R = R + 2.0 * np.einsum("ni,nj->nij", e, e) + 2.0 * e0[:, None, None] * skew(e)
    return R


def ep_glocal(ep):
    """GL(ep) (n, 3, 4): omega_local = GL ep_t; GL GL^T = 4 I and GL ep = 0 for unit ep."""
    ep = np.atleast_2d(np.asarray(ep, float))
    e0 = ep[:, 0]
    e = ep[:, 1:]
    G = np.zeros((ep.shape[0], 3, 4))
    G[:, :, 0] = -e
    G[:, :, 1:] = e0[:, None, None] * np.eye(3) - skew(e)
    return 2.0 * G


# ---------------------------------------------------------------- Tait-Bryan xyz
def rxyz_to_matrix(a):
    a = np.atleast_2d(np.asarray(a, float))
    c = np.cos(a)
    s = np.sin(a)
    n = a.shape[0]
    Rx = np.zeros((n, 3, 3))
    Ry = np.zeros((n, 3, 3))
    Rz = np.zeros((n, 3, 3))
    Rx[:, 0, 0] = 1
    Rx[:, 1, 1] = c[:, 0]
    Rx[:, 1, 2] = -s[:, 0]
    Rx[:, 2, 1] = s[:, 0]
    Rx[:, 2, 2] = c[:, 0]
    Ry[:, 1, 1] = 1
    Ry[:, 0, 0] = c[:, 1]
    Ry[:, 0, 2] = s[:, 1]
    Ry[:, 2, 0] = -s[:, 1]
    Ry[:, 2, 2] = c[:, 1]
    Rz[:, 2, 2] = 1
    Rz[:, 0, 0] = c[:, 2]
    Rz[:, 0, 1] = -s[:, 2]
    Rz[:, 1, 0] = s[:, 2]
    Rz[:, 1, 1] = c[:, 2]
    return Rx @ Ry @ Rz


def rxyz_glocal(a):
    """GR(a) (n, 3, 3): omega_local = GR a_t."""
    a = np.atleast_2d(np.asarray(a, float))
    c1, s1 = np.cos(a[:, 1]), np.sin(a[:, 1])
    c2, s2 = np.cos(a[:, 2]), np.sin(a[:, 2])
    G = np.zeros((a.shape[0], 3, 3))
    G[:, 0, 0] = c1 * c2
    G[:, 0, 1] = s2
    G[:, 1, 0] = -c1 * s2
    G[:, 1, 1] = c2
    G[:, 2, 0] = s1
    G[:, 2, 2] = 1.0
    return G


def rxyz_glocal_dot(a, a_t):
    """d/dt GR(a(t)) for the angle rates a_t."""
    a = np.atleast_2d(np.asarray(a, float))
    a_t = np.atleast_2d(np.asarray(a_t, float))
    c1, s1 = np.cos(a[:, 1]), np.sin(a[:, 1])
    c2, s2 = np.cos(a[:, 2]), np.sin(a[:, 2])
    d1, d2 = a_t[:, 1], a_t[:, 2]
    G = np.zeros((a.shape[0], 3, 3))
    G[:, 0, 0] = -s1 * c2 * d1 - c1 * s2 * d2
    G[:, 0, 1] = c2 * d2
    G[:, 1, 0] = s1 * s2 * d1 - c1 * c2 * d2
    G[:, 1, 1] = -s2 * d2
    G[:, 2, 0] = c1 * d1
    return G


def matrix_to_rxyz_candidates(R):
    """Both Tait-Bryan solutions (n, 2, 3) of R = Rx Ry Rz (principal ranges).

    Second solution: (a0 + pi, pi - a1, a2 + pi).  At the singularity (cos a1 = 0)
    only a0 + a2 (a1 = +pi/2) or a0 - a2 (a1 = -pi/2) is defined; a0 = 0 is returned."""
    R = np.asarray(R, float).reshape(-1, 3, 3)
    c1 = np.sqrt(R[:, 1, 2] ** 2 + R[:, 2, 2] ** 2)
    a1 = np.arctan2(R[:, 0, 2], c1)
    sing = c1 < 1e-14
    a0 = np.where(sing, 0.0, np.arctan2(-R[:, 1, 2], R[:, 2, 2]))
    a2 = np.where(sing, np.arctan2(R[:, 1, 0], R[:, 1, 1]), np.arctan2(-R[:, 0, 1], R[:, 0, 0]))
    A = np.stack([a0, a1, a2], axis=1)
    B = np.stack([a0 + np.pi, np.pi - a1, a2 + np.pi], axis=1)
    return np.stack([A, B], axis=1)


def wrap_near(x, ref):
    """x + 2 pi k (componentwise) closest to ref."""
    return x + TWO_PI * np.round((ref - x) / TWO_PI)
