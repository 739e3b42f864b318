"""The linear spring-damper along an axis fixed in the frame of side 0 (body A):

    a = A_0 axis0 (world),  u = a . (p_1 - p_0),  v = a . (pdot_1 - pdot_0),
    f = k (u - offset) + d (v - velocityOffset) + force,

the force ``f a`` acts through the *position* Jacobians of the two points only (``-f a``
applied at point 1, ``+f a`` at point 0): the rotation of the axis ``a`` itself
contributes no generalised force.  ``SceneData``: ``linearBodies`` = [A, B], ``linearPoints`` =
[posA, posB], ``linearAxis`` = the axis in A's body frame (world if A is ground), ``linearLaw`` =
[k, d, offset, force - d velocityOffset].
"""
from numba import njit

from .bodies import add_pair_force, connector_ends


@njit(cache=True, _nrt=False)
def linear_spring_forces(gid, linearBodies, linearPoints, linearAxis, linearLaw, R, r, V, Q, v3, ident, zero3, zero6):
    pA, pB, vA, vB, F, a = v3[0], v3[1], v3[2], v3[3], v3[6], v3[7]
    for s in range(linearBodies.shape[0]):
        ia = linearBodies[s, 0]
        ib = linearBodies[s, 1]
        gA, RA, gB, RB = connector_ends(gid, ia, ib, linearPoints[s, 0], linearPoints[s, 1], R, r, V, v3, ident,
                                        zero3, zero6)
        u = 0.0
        v = 0.0
        for k in range(3):
            a[k] = RA[k, 0] * linearAxis[s, 0] + RA[k, 1] * linearAxis[s, 1] + RA[k, 2] * linearAxis[s, 2]
        for k in range(3):
            u += a[k] * (pB[k] - pA[k])
            v += a[k] * (vB[k] - vA[k])
        f = linearLaw[s, 0] * (u - linearLaw[s, 2]) + linearLaw[s, 1] * v + linearLaw[s, 3]
        for k in range(3):
            F[k] = f * a[k]
        add_pair_force(gA, RA, linearPoints[s, 0], ia, gB, RB, linearPoints[s, 1], ib, F, Q)


# the element's entry (registered in mbs/force_elements.py)
@njit(cache=True, inline="always", _nrt=False)
def linear_spring_element(sd, wk, R, r, V, Q):
    linear_spring_forces(sd.gid, sd.linearBodies, sd.linearPoints, sd.linearAxis, sd.linearLaw, R, r, V, Q, wk.v3,
                         wk.ident, wk.zero3, wk.zero6)
