"""Constraint stabilisation on the group: position (Gauss-Newton) and velocity projection."""
from collections import namedtuple

from numba import njit, types
from numba.extending import overload

from .bodies import exp_compose
from .codes import PROJ_FAIL, PROJ_MAX_ITER, PROJ_TOL, STAB_NONE, STAB_POSITION, STAB_VELOCITY, STATUS_OK, STATUS_PROJECTION
from .constraints import joints_rows
from .index1 import apply_correction, rows_times, schur_correct, solve_multipliers, tree_of
from .presence import guarded


# the arguments of project, by what they are (built by project_state from SceneData / Work)
Joints = namedtuple("Joints",
                    ["gid", "jointIndex", "jointPoints", "jointFrames", "jointParams", "rowIndex", "rowsAll", "bodyParameters", "jointAngles"])  # the joint tables
Schur = namedtuple("Schur", ["Minv", "bw", "redundant", "pivotTol",              # J M^-1 J^T: data...
                             "W", "lam", "Sb", "Sd", "perm", "ytmp", "failInfo", "tmp12",    # ... and work
                             "tree"])                                            # index1.TreeSolve
Rows = namedtuple("Rows", ["h", "Jr", "eta", "rdrive"])    # the rows at a state; row drives (mbs.row_drives)
Scratch = namedtuple("Scratch", ["Psi", "v3", "m3", "ident", "zero3", "zero6"])


@njit(cache=True, _nrt=False)
def project(level, joints, schur, rows, scratch, R, r, V):
    """Constraint stabilisation (Simulator(stabilization=...)), both on the group:

    * positions (``level`` 2): Gauss-Newton ``g_i <- g_i exp(delta_i)``,
      ``delta = -M^-1 J^T (J M^-1 J^T)^-1 h(g)`` (the mass-weighted least-change
      correction; J is the derivative of h along g exp(delta) in each body's group);
    * velocities (``level`` >= 1): ``V <- V - M^-1 J^T (J M^-1 J^T)^-1 (J V - w)``, ``w`` the
      velocity targets ``rdrive[1]`` (0 but for rows with a moving offset or a velocity-level
      row's offset, :mod:`.row_drives`; a velocity-level row has ``h = 0``, so the position
      step leaves it alone).

    The row drives ``rdrive`` must hold their values at the state's time (the caller).
    Returns a status code (STATUS_PROJECTION if max |h| stays above the tolerance)."""
    gid, jointIndex, jointPoints, jointFrames, jointParams, rowIndex, rowsAll, bodyParameters, jointAngles = joints
    Minv, bw, redundant, pivotTol, W, lam, Sb, Sd, perm, ytmp, failInfo, tmp12, tree = schur
    h, Jr, eta, rdrive = rows
    Psi, v3, m3, ident, zero3, zero6 = scratch
    nb = gid.shape[0]
    if level >= STAB_POSITION:
        scale = 1.0
        for i in range(nb):
            for k in range(3):
                if abs(r[i, k]) > scale:
                    scale = abs(r[i, k])
        tol = PROJ_TOL * scale
        hmax = 0.0
        for it in range(PROJ_MAX_ITER + 1):
            joints_rows(gid, jointIndex, jointPoints, jointFrames, jointParams, rowIndex, rowsAll, bodyParameters,
                        jointAngles, R, r, V, h, Jr, eta, rdrive, v3, ident, zero3, zero6)
            hmax = 0.0
            for q in range(rowIndex.shape[0]):
                if abs(h[q]) > hmax:
                    hmax = abs(h[q])
            if hmax <= tol or it == PROJ_MAX_ITER:
                break
            for q in range(rowIndex.shape[0]):
                lam[q] = h[q]
            st = solve_multipliers(gid, Minv, rowIndex, bw, redundant, pivotTol, R, Jr, W, lam, Sb, Sd, perm, ytmp,
                                   failInfo, tmp12, tree)
            if st != STATUS_OK:
                return st
            for i in range(nb):
                for k in range(6):
                    Psi[i, k] = 0.0
            apply_correction(rowIndex, W, lam, Psi, tree)
            for i in range(nb):
                exp_compose(gid[i], R[i], r[i], Psi[i], m3[1], v3[1], m3[0], v3[0])
                for a in range(3):
                    r[i, a] = v3[1, a]
                    for c in range(3):
                        R[i, a, c] = m3[1, a, c]
        if hmax > PROJ_FAIL * tol:
            return STATUS_PROJECTION
    else:
        joints_rows(gid, jointIndex, jointPoints, jointFrames, jointParams, rowIndex, rowsAll, bodyParameters,
                    jointAngles, R, r, V, h, Jr, eta, rdrive, v3, ident, zero3, zero6)
    return schur_correct(gid, Minv, rowIndex, bw, redundant, pivotTol, R, V, -1.0, rdrive[1], Jr, W, lam, Sb, Sd,
                         perm, ytmp, failInfo, tmp12, tree)


@njit(cache=True, inline="always", _nrt=False)
def project_state(sd, wk, level, R, r, V):
    if sd.nrows == 0:
        return STATUS_OK
    return project(level,
                   Joints(sd.gid, sd.jointIndex, sd.jointPoints, sd.jointFrames, sd.jointParams, sd.rowIndex,
                          sd.rowsAll, wk.path.bodyParameters, wk.path.jointAngles),
                   Schur(sd.Minv, sd.bandwidth, sd.redundant, sd.pivotTol, wk.W, wk.lam, wk.Sb, wk.Sd, wk.perm,
                         wk.ytmp, wk.failInfo, wk.tmp12, tree_of(sd, wk)),
                   Rows(wk.h, wk.Jr, wk.eta, wk.rdrive), Scratch(wk.Psi, wk.v3, wk.m3, wk.ident, wk.zero3, wk.zero6),
                   R, r, V)


def is_stabilized(level):
    """At compile time if possible: whether the steps are projected (``SceneData.stabilization``
    None: never, so nothing of the projection is compiled into the step loop)."""
    raise NotImplementedError("compiled only")


@overload(is_stabilized, inline="always")
def _is_stabilized(level):
    if isinstance(level, types.NoneType):
        return lambda level: False
    return lambda level: level != STAB_NONE


#: ``project_state(sd, wk, level, R, r, V)`` unless ``level`` (``sd.stabilization``) is None:
#: without stabilisation the step loop compiles no projection (mbs/presence.py)
project_state_if = guarded(project_state, default=STATUS_OK)


# ---------------------------------------------------------------- constraint tolerance (adaptive steps)
# The array ``ctol`` of the adaptive loop: position tolerance (<= 0: off), velocity tolerance,
# and the count of projections it triggered.
CT_POS, CT_VEL, CT_N_PROJ = range(3)


@njit(cache=True, _nrt=False)
def constraint_rows_at(sd, wk, R, r, V):
    """Rows h(g), J and eta at (R, r, V) into ``wk.h``, ``wk.Jr``, ``wk.eta``; returns
    (max |h|, max |J V - w|), J V - w computed into ``wk.lam`` (scratch; ``w`` the velocity
    targets of the row drives, at the state's time)."""
    joints_rows(sd.gid, sd.jointIndex, sd.jointPoints, sd.jointFrames, sd.jointParams, sd.rowIndex, sd.rowsAll,
                wk.path.bodyParameters, wk.path.jointAngles, R, r, V, wk.h, wk.Jr, wk.eta, wk.rdrive, wk.v3,
                wk.ident, wk.zero3, wk.zero6)
    rows_times(sd.rowIndex, wk.Jr, V, -1.0, wk.rdrive[1], wk.lam)
    hmax = 0.0
    vmax = 0.0
    for q in range(sd.nrows):
        if abs(wk.h[q]) > hmax:
            hmax = abs(wk.h[q])
        if abs(wk.lam[q]) > vmax:
            vmax = abs(wk.lam[q])
    return hmax, vmax


@njit(cache=True, _nrt=False)
def project_tangent(sd, wk, R, X):
    """``X <- X - M^-1 J^T (J M^-1 J^T)^-1 J X``: the mass-orthogonal projection of a
    per-body algebra vector (nb, 6) onto the tangent space ``J X = 0`` of the constraint
    manifold, with J from the last :func:`constraint_rows_at` (same coordinates as V and as
    the increments Phi: the derivative of h along g exp(delta))."""
    return schur_correct(sd.gid, sd.Minv, sd.rowIndex, sd.bandwidth, sd.redundant, sd.pivotTol, R, X, 0.0, wk.eta,
                         wk.Jr, wk.W, wk.lam, wk.Sb, wk.Sd, wk.perm, wk.ytmp, wk.failInfo, wk.tmp12, tree_of(sd, wk))


@njit(cache=True, _nrt=False)
def project_error_estimate(sd, wk, R, r, V, dPhi, dV):
    """The error estimate (dPhi, dV) of an adaptive step, both projected onto the tangent
    space of the constraint manifold at the step's end (R, r, V) (docs/ADAPTIVE.md,
    "Constraint tolerance"): the normal parts are drift, which the constraint tolerance
    controls, not the accuracy tolerance (as in Simbody)."""
    if sd.nrows == 0:
        return STATUS_OK
    constraint_rows_at(sd, wk, R, r, V)
    st = project_tangent(sd, wk, R, dPhi)
    if st != STATUS_OK:
        return st
    return project_tangent(sd, wk, R, dV)


@njit(cache=True, _nrt=False)
def enforce_constraint_tolerance(sd, wk, ctol, R, r, V):
    """Project the state on the group when its drift exceeds the constraint tolerance:
    max |h(g)| > ctol[CT_POS] -> positions (Gauss-Newton on the group) and velocities;
    else max |J V| > ctol[CT_VEL] -> velocities only.  Returns (status, projected)."""
    if sd.nrows == 0:
        return STATUS_OK, False
    hmax, vmax = constraint_rows_at(sd, wk, R, r, V)
    if hmax > ctol[CT_POS]:
        level = STAB_POSITION
    elif vmax > ctol[CT_VEL]:
        level = STAB_VELOCITY
    else:
        return STATUS_OK, False
    return project_state(sd, wk, level, R, r, V), True
