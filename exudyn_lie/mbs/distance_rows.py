"""The distance-constraint row (``ROW_DIST``): a distance constraint at position level,

    h = |p_B - p_A| - L0,

with ``p_A, p_B`` the two body points.  With ``d = p_B - p_A``, ``L = |d|`` and ``e = d / L``:
``hdot = e . ddot`` and ``hddot = e . dddot + (|ddot|^2 - (e . ddot)^2) / L``, so the row's
Jacobian is that of a world-direction row along ``e`` (the columns of ``ROW_TRANS_WORLD``
with the axis ``e``, :mod:`.constraints`) and (eq. index1)

    eta = -(e . beta_d + (|ddot|^2 - (e . ddot)^2) / L),

``beta_d = beta_B - beta_A`` the velocity-product accelerations of the two points.
"""
import numpy as np
from numba import njit


@njit(cache=True, inline="always", _nrt=False)
def distance_row(q, L0, d, dd, bd, e, h, eta):
    """``h[q]``, ``eta[q]`` and the row's world direction ``e`` from ``d = p_B - p_A``, its
    rate ``dd`` and bias acceleration ``bd``; ``L0 = jointParams[j, 0]``."""
    L = np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    if L == 0.0:
        L = 1.0          # direction undefined (the model is singular there); keep finite
    for k in range(3):
        e[k] = d[k] / L
    ed = e[0] * dd[0] + e[1] * dd[1] + e[2] * dd[2]
    dd2 = dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2]
    eb = e[0] * bd[0] + e[1] * bd[1] + e[2] * bd[2]
    h[q] = L - L0
    eta[q] = -(eb + (dd2 - ed * ed) / L)
