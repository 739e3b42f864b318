"""Forward differences of the stage right-hand side by groups of bodies (Curtis, Powell & Reid).

The Newton matrix of an implicit stage needs ``D_V = dF/dV`` and ``D_Theta = dF/dTheta``
(mbs/implicit.py): by plain forward differences, two evaluations of the right-hand side per
unknown, ``12 nb`` in all.  A body's velocity and configuration reach the accelerations of the
bodies its joints and forces couple it to, and no others.  Bodies whose couplings reach no body
in common can therefore be perturbed together: one evaluation per group and axis, each row
changed by at most one of the group's bodies.  The groups are a greedy distance-2 colouring of
the bodies' coupling (``coupled[r, c]``: some entry of the 6 x 6 block ``(r, c)`` of ``D_V`` or
``D_Theta`` is not zero, or ``r == c``), taken from the last Jacobian made column by column, or,
where there is none yet, found by :func:`probe_coupling` with one evaluation per body (``nb``
evaluations, then ``12`` per group, against ``12 nb``).

The pattern is that of exact zeros at one state; a coupling that appears later (a contact that
closes) would be attributed to the wrong column.  Each grouped evaluation therefore checks the
rows that no body of its group reaches: if one of them changed at all, the pattern is out of date
and the caller makes the Jacobian column by column instead (:data:`NEW_COUPLING`).  A coupling
that appears in a row some other body of the group reaches is not seen there (two bodies of one
group that come into contact); the Jacobian then only slows the simplified Newton iteration, whose
solution does not depend on it: ``implicit.solve_stage`` solves a stage that does not converge with
it again with a Jacobian made column by column (a new pattern), and after a stage that converged
slowly with a Jacobian by groups of its own step the next Jacobian probes the pattern anew.
"""
from numba import njit

from .bodies import exp_compose
from .codes import STATUS_OK
from .rhs_address import rhs_at
from .stepper import copy_state

#: grouped_differences' status when a row outside the group's pattern changed
NEW_COUPLING = -1
FD_STEP = 1.4901161193847656e-08     # sqrt(eps): forward differences of F


@njit(cache=True, inline="always", _nrt=False)
def restore_configuration(i, R, r, Rs, rs):
    """Body ``i``'s configuration in the stage arrays ``Rs, rs`` back to ``R, r`` after a difference."""
    for a in range(3):
        rs[i, a] = r[i, a]
        for c in range(3):
            Rs[i, a, c] = R[i, a, c]


@njit(cache=True, _nrt=False)
def body_coupling(Dv, Dth, nb, coupled):
    """``coupled[r, c] = 1`` where block ``(r, c)`` of ``Dv`` or ``Dth`` has an entry that is not zero,
    and on the diagonal."""
    for r in range(nb):
        for c in range(nb):
            v = 1 if r == c else 0
            for m in range(6):
                if v:
                    break
                for k in range(6):
                    if Dv[6 * r + m, 6 * c + k] != 0.0 or Dth[6 * r + m, 6 * c + k] != 0.0:
                        v = 1
                        break
            coupled[r, c] = v


@njit(cache=True, _nrt=False)
def probe_coupling(sd, wk, t, R, r, V, A0, Ap, axes, coupled, X):
    """``coupled`` at ``(t, g, V)`` where ``F = A0`` by one evaluation per body: its velocity and its
    configuration moved along all its axes at once (steps that differ per axis, so that no two
    axes cancel in a row), the rows that changed are coupled to it.  Returns a status."""
    gid = sd.gid
    nb = gid.shape[0]
    copy_state(R, r, V, wk.Rs, wk.rs, wk.Vs)
    for c in range(nb):
        for k in range(6):
            X[k] = FD_STEP * (1.0 + 0.125 * k) * axes[c, k]
            wk.Vs[c, k] = V[c, k] + X[k] * max(1.0, abs(V[c, k]))
        exp_compose(gid[c], R[c], r[c], X, wk.Rs[c], wk.rs[c], wk.m3[0], wk.v3[0])
        st = rhs_at(sd, wk, t, Ap)
        for k in range(6):
            wk.Vs[c, k] = V[c, k]
        restore_configuration(c, R, r, wk.Rs, wk.rs)
        if st != STATUS_OK:
            return st
        for row in range(nb):
            v = 1 if row == c else 0
            for m in range(6):
                if Ap[row, m] != A0[row, m]:
                    v = 1
            coupled[row, c] = v
    return STATUS_OK


@njit(cache=True, _nrt=False)
def color_bodies(coupled, nb, color, stamp):
    """Greedy distance-2 colouring: bodies ``c`` and ``c2`` get different colours if some row
    body ``r`` is coupled to both.  Writes ``color``; returns the number of colours.  ``stamp``:
    scratch of ``nb`` entries."""
    for c in range(nb):
        color[c] = -1
        stamp[c] = -1
    ncol = 0
    for c in range(nb):
        for r in range(nb):
            if coupled[r, c]:
                for c2 in range(nb):
                    if coupled[r, c2] and color[c2] >= 0:
                        stamp[color[c2]] = c
        q = 0
        while stamp[q] == c:
            q += 1
        color[c] = q
        ncol = max(ncol, q + 1)
    return ncol


@njit(cache=True, _nrt=False)
def _scatter(coupled, axes, color, q, k, eps, Ap, A0, D, claim):
    """The columns ``(i, k)`` of the group ``q`` into ``D`` (zero outside each body's pattern);
    returns False if a row that no body of the group reaches changed."""
    nb = color.shape[0]
    for r in range(nb):
        claim[r] = -1
    for i in range(nb):
        if color[i] != q or axes[i, k] == 0.0:
            continue
        col = 6 * i + k
        for r in range(nb):
            if coupled[r, i]:
                claim[r] = i
                for m in range(6):
                    D[6 * r + m, col] = (Ap[r, m] - A0[r, m]) / eps[i]
            else:
                for m in range(6):
                    D[6 * r + m, col] = 0.0
    for r in range(nb):
        if claim[r] < 0:
            for m in range(6):
                if Ap[r, m] != A0[r, m]:
                    return False
    return True


@njit(cache=True, _nrt=False)
def grouped_differences(sd, wk, t, R, r, V, A0, Ap, axes, coupled, color, ncol, eps, claim, X, Dv, Dth):
    """``Dv``, ``Dth`` at ``(t, g, V)`` where ``F = A0`` by one evaluation per colour and axis (module
    docstring), each into ``Ap``; the columns of axes a body does not have are zero.  Returns a status, or
    :data:`NEW_COUPLING`."""
    gid = sd.gid
    nb = gid.shape[0]
    n = 6 * nb
    copy_state(R, r, V, wk.Rs, wk.rs, wk.Vs)
    for i in range(nb):            # the columns of absent axes
        for k in range(6):
            if axes[i, k] == 0.0:
                for row in range(n):
                    Dv[row, 6 * i + k] = 0.0
                    Dth[row, 6 * i + k] = 0.0
    for q in range(ncol):
        for k in range(6):
            some = False
            for i in range(nb):
                if color[i] == q and axes[i, k] != 0.0:
                    some = True
                    eps[i] = FD_STEP * max(1.0, abs(V[i, k]))
                    wk.Vs[i, k] = V[i, k] + eps[i]
            if not some:
                continue
            st = rhs_at(sd, wk, t, Ap)
            for i in range(nb):
                if color[i] == q:
                    wk.Vs[i, k] = V[i, k]
            if st != STATUS_OK:
                return st
            if not _scatter(coupled, axes, color, q, k, eps, Ap, A0, Dv, claim):
                return NEW_COUPLING
            for m in range(6):
                X[m] = 0.0
            X[k] = FD_STEP
            for i in range(nb):
                if color[i] == q and axes[i, k] != 0.0:
                    eps[i] = X[k]
                    exp_compose(gid[i], R[i], r[i], X, wk.Rs[i], wk.rs[i], wk.m3[0], wk.v3[0])
            st = rhs_at(sd, wk, t, Ap)
            for i in range(nb):
                if color[i] == q:
                    restore_configuration(i, R, r, wk.Rs, wk.rs)
            if st != STATUS_OK:
                return st
            if not _scatter(coupled, axes, color, q, k, eps, Ap, A0, Dth, claim):
                return NEW_COUPLING
    return STATUS_OK
