"""Constants shared by the compiled kernel modules: group ids, constraint-row kinds, the
columns of the integer tables of ``SceneData``, status codes, the stage-argument bound and
the stabilisation levels."""
import numpy as np
from numba import njit

from ..groups import GROUPS, so3

# group id of a body = position of its group in the one registry, exudyn_lie.groups.GROUPS
GROUP_NAMES = tuple(GROUPS)
GID_SE3 = GROUP_NAMES.index("SE3")
GID_SO3xR3 = GROUP_NAMES.index("SO3xR3")
GID_R3 = GROUP_NAMES.index("R3")         # point masses (groups/rn.py): R = I, omega = 0
GID_SE2 = GROUP_NAMES.index("SE2")
GID_SO2xR2 = GROUP_NAMES.index("SO2xR2")
# velocity representation per group id (groups.interface.TWISTS): True = body-fixed v
# (rdot = R v, as SE3), False = mixed (rdot = v, as SO3xR3); a frozen constant in numba
BODY_TWIST = np.array([GROUPS[g].TWIST == "body" for g in GROUP_NAMES])
# the same as one integer (bit gid set: a body twist), for compiled code: a test of a frozen
# integer constant folds into the branch, where indexing the global array costs a load in
# every body map of every stage (measured: heavy top 3.3 -> 2.6 us per step)
BODY_TWIST_BITS = int(sum(1 << i for i, g in enumerate(GROUP_NAMES) if GROUPS[g].TWIST == "body"))


@njit(cache=True, inline="always", _nrt=False)
def uses_body_twist(gid):
    """True if bodies of group ``gid`` use body-fixed twists (``rdot = R v``, as SE3)."""
    return (BODY_TWIST_BITS >> gid) & 1 == 1

ROW_TRANS_LOCAL = 0   # a = (R_A rotA)[:, ax] ; h = a . (pB - pA)
ROW_TRANS_WORLD = 1   # a = e_ax (world)       ; h = a . (pB - pA)
ROW_ROT = 2           # h = (R_A rotA)[:, ax] . (R_B rotB)[:, bx]
ROW_DIST = 4          # h = |p_B - p_A| - L0 (distance constraint, mbs/distance_rows.py)
ROW_COORD = 3         # h = f p_B[bx] - p_A[ax] - c (coordinate constraint, mbs/coordinate_rows.py)
ROW_ROLL = 5          # velocity level: e_ax . (contact point velocity B - A) (rolling disc, mbs/rolling_disc_rows.py)
ROW_COORD_VEL = 6     # velocity level: f qdot_B - qdot_A = w(t) (coordinate constraint on rates; h = 0)

# columns of the integer tables of SceneData
ROW_KIND, ROW_AX, ROW_BX, ROW_BODY_A, ROW_BODY_B = 0, 1, 2, 3, 4      # rowIndex (m, 5)
J_BODY_A, J_BODY_B, J_ROW0, J_NROW = 0, 1, 2, 3                        # jointIndex (nj, 4)
L_BODY, L_KIND, L_FIXED = 0, 1, 2                                      # loadIndex (nl, 3)

# the right-hand side outside the compiled code (mbs/external.py), SceneData.hasQext
EXTERNAL_NONE = 0
EXTERNAL_FORCES = 1        # Python forces added to the compiled ones (Scene.AddPythonForce)
EXTERNAL_RATES = 2         # the whole Vdot (Scene.SetRightHandSide)

STATUS_OK = 0
STATUS_SINGULAR = 1
STATUS_NONFINITE = 2
STATUS_BLOWUP = 3
STATUS_PROJECTION = 4      # the position projection did not converge
STATUS_STAGE_ARG = 5       # a stage argument Psi_j left the domain of dexpinv (wk.failInfo[INFO_BODY] = body)
STATUS_EXTERNAL = 6        # the right-hand side evaluated in Python raised (mbs.external)
STATUS_STEP_MIN = 7        # adaptive steps: the error control asks for a step below the minimum (mbs.adaptive)
STATUS_NEWTON = 8          # an implicit stage's Newton iteration did not converge (mbs.implicit)
STATUS_STIFF = 9           # fixed steps watched: the stages show a mode beyond the stability radius (mbs.stiffness)
STATUS_NO_RHS = 10         # a Work without the address of the stage right-hand side (mbs.rhs_address)
EXT_RHS = 2                # Work.ext[EXT_RHS]: that address
# what a failed status refers to (Work.failInfo): the failing constraint row, the numerical rank of
# redundant rows, the body whose stage argument left the domain of dexpinv
INFO_ROW, INFO_RANK, INFO_BODY = 0, 1, 2

# Domain of the MK stage equation k_j = dexpinv_{-Psi_j} V_j (eq. MK1): dexpinv of SO(3)
# (and of SE(3), whose blocks share the coefficient) is singular at |rotation part| = 2 pi,
# where D(t) = (1 - (t/2) cot(t/2)) / t^2 has a pole.  Near it, with t = 2 pi - delta, the
# condition number of dexpinv (ratio of its singular values, 1 along the axis and
# (t/2) / |sin(t/2)| across it) is about 2 pi / delta, and so is the relative condition
# number of D(t) itself.  The time loop stops a step whose stage argument exceeds
# STAGE_ARG_MAX = so3.DEXP_ANGLE_MAX = 2 pi (1 - sqrt(eps)) (condition number <= 1/sqrt(eps):
# at most half the digits of the stage velocity lost), before evaluating that stage - the
# same rule as the Python reference stepper (tests/reference_mk.py), so SE3's exactness for
# motions in a subgroup holds on the same domain in both.  The test is one squared-norm
# compare per body and stage.
STAGE_ARG_MAX = so3.DEXP_ANGLE_MAX
STAGE_ARG_MAX2 = STAGE_ARG_MAX * STAGE_ARG_MAX

# stabilisation after each step (SceneData.stabilization)
STAB_NONE = 0
STAB_VELOCITY = 1          # V <- V - M^-1 J^T (J M^-1 J^T)^-1 J V
STAB_POSITION = 2          # Gauss-Newton on the group for h(g) = 0, then the velocity projection
PROJ_MAX_ITER = 20
PROJ_TOL = 1e-13           # converged: max |h| <= PROJ_TOL max(1, max |r|)
PROJ_FAIL = 1e3            # failure: max |h| > PROJ_FAIL * tolerance after PROJ_MAX_ITER iterations
