"""A band ordering of a sparse Newton matrix: reverse Cuthill-McKee on the pattern of its
Jacobians (the implicit stages' matrix, mbs/implicit.py).

The Newton matrix ``I - hg D_V - hg^2 D_Theta`` couples only the bodies that an item connects:
over the 288 bodies of a model of modular robots (a real script, run through the bridge) 1.2 % of
the entries of ``D_V`` are not zero.  Factored densely it costs ``n^3 / 3`` operations (1.4 s for n = 1,728 here) and every
Newton iteration ``n^2``.  Numbered so that coupled unknowns are near each other (reverse
Cuthill-McKee: breadth first from an unknown of least degree, neighbours by increasing degree,
the numbering reversed), the matrix is a band of half-widths ``kl``, ``ku``, factored in ``n kl
(kl + ku)`` operations (linalg.band_lu_factor_inplace).

The pattern is the exact one of the forward differences (an entry is zero where the difference
is, so bodies of separate mechanisms are never coupled); whatever it is, the factors are those
of the whole matrix, so the band changes the cost and the round-off, not the Newton iteration's
result.
"""
from numba import njit

# a band factorisation only where it saves this much of the dense one (the ordering's own O(n^2)
# scans are then small against it), and only from this size on
BAND_GAIN = 4.0
BAND_MIN_N = 48


@njit(cache=True, inline="always", _nrt=False)
def _coupled(Dv, Dth, a, c):
    return Dv[a, c] != 0.0 or Dth[a, c] != 0.0 or Dv[c, a] != 0.0 or Dth[c, a] != 0.0


@njit(cache=True, _nrt=False)
def _degrees(Dv, Dth, n, deg):
    for a in range(n):
        deg[a] = 0
    for a in range(n):
        for c in range(a + 1, n):
            if _coupled(Dv, Dth, a, c):
                deg[a] += 1
                deg[c] += 1


@njit(cache=True, _nrt=False)
def rcm_numbering(Dv, Dth, n, perm, iperm, deg, nbr):
    """Reverse Cuthill-McKee numbering of the symmetric pattern of ``Dv`` and ``Dth``: the
    unknown ``perm[a]`` gets the number ``a`` (``iperm`` the inverse); ``deg`` and ``nbr``
    scratch of length ``n``.  Every connected part starts at an unknown of least degree.  The
    compiled twin of ``linalg.rcm_order`` (Python lists, for orders made once at set-up): this
    one runs inside the compiled Newton iteration after each Jacobian, on the dense pattern."""
    _degrees(Dv, Dth, n, deg)
    for a in range(n):
        iperm[a] = -1
    count = 0
    while count < n:
        s = -1
        for a in range(n):
            if iperm[a] < 0 and (s < 0 or deg[a] < deg[s]):
                s = a
        perm[count] = s
        iperm[s] = count
        head = count
        count += 1
        while head < count:
            a = perm[head]
            head += 1
            m = 0
            for c in range(n):
                if iperm[c] < 0 and c != a and _coupled(Dv, Dth, a, c):
                    # insertion by increasing degree (stable: equal degrees keep their order)
                    q = m
                    while q > 0 and deg[nbr[q - 1]] > deg[c]:
                        nbr[q] = nbr[q - 1]
                        q -= 1
                    nbr[q] = c
                    m += 1
            for q in range(m):
                perm[count] = nbr[q]
                iperm[nbr[q]] = count
                count += 1
    for a in range(n // 2):
        perm[a], perm[n - 1 - a] = perm[n - 1 - a], perm[a]
    for a in range(n):
        iperm[perm[a]] = a


@njit(cache=True, _nrt=False)
def bandwidths(Dv, Dth, n, iperm):
    """(kl, ku): the half-widths of the pattern of ``Dv`` and ``Dth`` (and the diagonal) in the
    numbering ``iperm``."""
    kl = 0
    ku = 0
    for a in range(n):
        ia = iperm[a]
        for c in range(n):
            if Dv[a, c] != 0.0 or Dth[a, c] != 0.0:
                d = ia - iperm[c]
                if d > kl:
                    kl = d
                elif -d > ku:
                    ku = -d
    return kl, ku


@njit(cache=True, _nrt=False)
def band_worthwhile(n, kl, ku):
    """True where the band factorisation saves :data:`BAND_GAIN` of the dense one and the band's
    rows (``kl + ku + 1`` entries, stored in the Newton matrix's ``Db``) are shorter than the
    matrix's (a lopsided pattern, one body that every other depends on, has ``ku`` near ``n``)."""
    return n >= BAND_MIN_N and kl + ku < n and BAND_GAIN * n * kl * (kl + ku + 1.0) < n * n * n / 3.0
