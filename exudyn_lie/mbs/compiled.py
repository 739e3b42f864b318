"""Turn a :class:`~exudyn_lie.mbs.scene.Scene` into the flat arrays of the kernel.

``compile_scene`` is done once per scene and group choice; the result
(:class:`SceneData`, a namedtuple of arrays numba specialises on) is reused for every
run.  Features a scene lacks are zero-length arrays, so their loops cost nothing, and
the constraint solve is skipped entirely without joints.
"""
from collections import namedtuple

import numpy as np

from .force_elements import compile_elements, lean_elements_only, scene_fields
from .codes import (EXTERNAL_FORCES, EXTERNAL_NONE, EXTERNAL_RATES, GROUP_NAMES, J_NROW, J_ROW0, ROW_COORD,
                    ROW_COORD_VEL, ROW_DIST, ROW_KIND, ROW_ROLL, ROW_ROT, ROW_TRANS_LOCAL, ROW_TRANS_WORLD,
                    STAB_NONE, STAB_POSITION, STAB_VELOCITY)
from .rotation_parameters import TRACK_ANGLE, TRACK_NONE
from .external_probes import N_PROBE, probe_table
from .linalg import REL_PIVOT_TOL, rcm_order
from .rolling_disc_penalty_forces import N_DISC, rolling_disc_penalty_row
from .oblique_solve import oblique_plan
from .scene import GROUND, Scene, SceneError
from ..groups import canonical_name
from .tree_solve import tree_plan, work_size

GROUP_IDS = {name: gid for gid, name in enumerate(GROUP_NAMES)}
GROUP_NAMES = {v: k for k, v in GROUP_IDS.items()}

# Per feature: an integer table (body indices, flags) and float tables; zero rows when the
# scene lacks the feature.  Few, packed fields keep numba's compile time down (it grows
# steeply with the number of arrays a compiled function receives).
SceneData = namedtuple("SceneData", [
    "nb", "gid", "mass", "com", "M", "Minv", "gravity", "hasGravity",
    "hasQext",                        # codes.EXTERNAL_*: none, Python forces, or the whole right-hand side
    "loadIndex", "loadVectors",       # loads: [body, 0 force / 1 torque, bodyFixed]; [vector, point]
    # the compiled force elements' fields, from their registrations (mbs/force_elements.py), in this order:
    # * springs: springBodies [A, B], springPoints [posA, posB], springLaw [k, d, L0, f0];
    # * Cartesian springs: cartesianBodies, cartesianPoints, cartesianLaw [k(3), d(3), offset(3)];
    # * torsional springs: torsionBodies, torsionFrames [rotA, rotB], torsionLaw [k, d, offset, torque];
    # * coordinate springs: coordSpringEnds [A, B, end code A, end code B], coordSpringLaw [k, d, offset,
    #   direction A (3), direction B (3), force], coordSpringFrames [frame A, frame B], nCoordAngles (the
    #   rotation coordinates of the coordinate items, tracked in PathState: coordinate_angles);
    # * linear springs: linearBodies, linearPoints, linearAxis (axis on A), linearLaw [k, d, offset, force];
    # * rigid-body springs: rigidSpringBodies [A, B, intrinsic], rigidSpringPoints, rigidSpringFrames,
    #   rigidSpringLaw (rows K (6), D (6), offset)
    *scene_fields(),
    "jointIndex",                     # joints: [A, B, first row, rows]
    "jointPoints", "jointFrames",     # [posA, posB]; [rotA, rotB]
    "jointParams",                    # the rows' parameters (N_JOINT_PARAMS per joint, joint_parameters)
    "rowIndex",                       # constraint rows: [kind, axis of A, axis of B, body A, body B]
    "nrows", "bandwidth", "redundant", "pivotTol",
    "stabilization",                  # kernel.STAB_*: projection after every step; None: none (no projection
                                      #   compiled into the step loop, projection.project_state_if)
    "rowsAll",                        # None in a lean scene (scene_is_lean): the coordinate and rolling-disc
                                      #   row kinds are not compiled (mbs/presence.py); True otherwise
])

# The path-dependent state (mbs/step_observers.py): what depends on the path, not only on the
# current configuration, moved on after every accepted step, left as it was by a rejected one.
# One tuple per simulator, shared by every Work it makes (a new Work keeps it).
PathState = namedtuple("PathState", [
    "torsionAngles",                  # (ns,) torsional springs' angles, turns included
    "bodyAngles",                     # (nb,) angle of each 2D body / rotor about angleFrames[i] e_z, turns included
    "bodyParameters",                 # (nb, 4) rotation parameters of each tracked body (rotation_parameters)
    "rollingDiscs",                   # penalty rolling discs (rolling_disc_penalty_forces.D_*): bodies, flags and
                                      #   law packed with their data coordinates, which change after every step
                                      #   (one array: three separate ones made the heavy top's step 3.0 -> 3.6 us,
                                      #   measured); None in a lean scene
    "watchMax",                       # largest |R[body][i, j]| of each watched entry over the accepted steps
    "jointAngles",                    # (nj, 2) the rotation coordinates of the coordinate constraints' ends
    "springAngles",                   # (ns, 2) those of the coordinate springs (coordinate_angles)
])

# What is tracked and watched per body: constants of a run, kept with the path state they
# describe.  In Work, not SceneData: in SceneData these fields made the heavy top's step 0.6 us
# slower although it tracks nothing (measured interleaved).
TrackPlan = namedtuple("TrackPlan", [
    "trackCodes",                     # (nb,) rotation_parameters.TRACK_*: what is tracked of each body
    "angleFrames",                    # (nb, 3, 3) the frame whose e_z a body's angle turns about
    "nTracked",                       # number of tracked bodies
    "watchBody", "watchEntry",        # watched rotation entries R[body][i, j] (Simulator.WatchRotationEntries)
])

# The workspace: scratch of a step (its content between calls means nothing), the constants of
# the solve, and the path state (``path``, shared).
Work = namedtuple("Work", [
    "Rs", "rs", "Vs",                 # the stage state (g_j, V_j of eq. MK1)
    "Rb", "rb", "Vb",                 # the step's start, restored when a step fails
    "Psi", "K", "Vd",                 # Psi_j, k_j and Vdot_j of the stages (eq. MK1)
    "Ve",                             # Vdot at a step's end and near it (the fixed steps' watch: stepper.fixed_step_watch)
    "Q", "Qext",                      # generalised forces of a stage: compiled, and evaluated in Python
    "Jr", "W", "eta", "h", "lam",     # constraint rows (eq. index1): Jacobian, M^-1 J^T, eta, h, multipliers
    "Sb", "Sd", "perm", "ytmp",       # the Schur complement: band, dense (redundant rows), pivots, scratch
    "failInfo",                       # what a failed status refers to (codes.INFO_*)
    "tmp6", "tmp12", "v3", "m3",      # scratch vectors and matrices
    "ident", "zero3", "zero6",        # constants: the ground's rotation, position and velocity
    "ext",                            # [token of the external rhs evaluator (mbs.external), 0: none;
                                      #  1 if the forces it returned were not finite; codes.EXT_RHS]
    "rdrive",                         # (3, m): the time-dependent part of each row (mbs.row_drives): value,
                                      #   rate (the velocity target of J V) and acceleration (added to eta)
    "drive",                          # [token of the row-drive evaluator (mbs.row_drives)], None without
                                      #   offset functions (then the time loop has no drive code: tplan's rule)
    "Vw",                             # (nb, 6) (omega body, world rdot) at the stage, for Python forces
    "tplan", "Tw",                    # the tree solve's plan (mbs.tree_solve.tree_plan) and flat work; None
                                      # for the band solve (index1._is_tree: then no tree code is compiled).
                                      # In Work, not SceneData: one more SceneData field made the heavy
                                      # top's step 0.5 us slower (2.85 -> 3.35 us, measured), one more
                                      # Work field did not
    "track",                          # the TrackPlan
    "path",                           # the PathState
    "probe",                          # kinematics of the Python forces' items, computed before the external
                                      #   call of each stage (mbs/external_probes.py); None without them
])

N_SCRATCH3 = 20


def body_mass_matrix(mass, inertia, com):
    """The 6x6 body-fixed inertia matrix ``J_P`` about the frame origin (eq. NE1 with
    the COM offset): ``[[Theta_P, m c^], [-m c^, m I]]`` for twists ``(omega, v)``."""
    c = np.asarray(com, float)
    ch = np.array([[0, -c[2], c[1]], [c[2], 0, -c[0]], [-c[1], c[0], 0]])
    M = np.zeros((6, 6))
    M[:3, :3] = inertia
    M[:3, 3:] = mass * ch
    M[3:, :3] = -mass * ch
    M[3:, 3:] = mass * np.eye(3)
    return M


def point_mass_matrix(body):
    """``M`` of a point mass (group R3): ``m P`` on the free directions ``P``, no rotation block."""
    out = np.zeros((6, 6))
    out[3:, 3:] = body.mass * body.freeDirections
    return out


def point_minv(body):
    """``M^-1`` of a point mass (group R3): zero rotation block (omega stays 0), the
    pseudo-inverse ``P / m`` of ``m P`` on the free directions ``P``."""
    out = np.zeros((6, 6))
    out[3:, 3:] = body.freeDirections / body.mass
    return out


N_JOINT_PARAMS = 8      # float parameters per joint (ROW_COORD: factor, constant, directions d_A, d_B;
                        # ROW_DIST: distance; ROW_ROLL: disc radius, plane normal (3), disc axis (3))


def body_track(body):
    """What is tracked of a body after every accepted step (rotation_parameters.TRACK_*): the
    angle of a 2D body / rotor, else its node's rotation parameters (``Body.track``)."""
    if body.planar or body.angleFrame is not None:
        return TRACK_ANGLE
    return TRACK_NONE if body.track is None else int(body.track[0])


def joint_rows_of(joint):
    """(kind, ax, bx) of the rows of a scene joint."""
    if joint.coordinate is not None:
        # end codes: 0 position, 1 an angle (coordinate_angles), >= 10 a node rotation parameter (node_coordinates)
        kind = ROW_COORD_VEL if joint.velocityLevel else ROW_COORD
        return [(kind, int(joint.coordinate[4]), int(joint.coordinate[5]))]
    if joint.distance is not None:
        return [(ROW_DIST, 0, 0)]
    if joint.rollingDisc is not None:
        return [(ROW_ROLL, i, 0) for i in range(3) if joint.constrainedAxes[i]]
    return joint_row_descriptors(joint.constrainedAxes, joint.worldTranslation)


def joint_parameters(joint):
    """The float parameters of the joint's rows (``SceneData.jointParams``)."""
    if joint.coordinate is not None:
        dA, dB, f, c = joint.coordinate[:4]
        return [f, c, *dA, *dB]
    if joint.distance is not None:
        return [joint.distance] + [0.0] * (N_JOINT_PARAMS - 1)
    if joint.rollingDisc is not None:
        radius, normal, axis = joint.rollingDisc
        return [radius, *normal, *axis] + [0.0] * (N_JOINT_PARAMS - 7)
    return [0.0] * N_JOINT_PARAMS


#: the planar subgroup of each c-space: a 2D body (Scene.AddBody2D) on c-space 'SE3' is
#: integrated on SE2, on 'SO3xR3' on SO2xR2
PLANAR_GROUP = {"SE3": "SE2", "SO3xR3": "SO2xR2"}
_SPACE_OF = {v: k for k, v in PLANAR_GROUP.items()}
PLANAR_AXES = [2, 3, 4]          # (omega_z, v_x, v_y) in the 6-vector velocity


def axes_minv(M, axes):
    """``M^-1`` of a body that moves along the velocity axes ``axes`` only: the inverse of
    that block, zero elsewhere, so forces along the other axes produce no acceleration and
    the velocity stays on those axes (a 2D body: ``PLANAR_AXES``; a rotor: omega_z)."""
    Minv = np.zeros((6, 6))
    ix = np.ix_(list(axes), list(axes))
    Minv[ix] = np.linalg.inv(M[ix])
    return Minv


def planar_minv(M):
    """``M^-1`` of a 2D body in its 6-vector velocity (a 2D body has exactly the 3
    coordinates ``PLANAR_AXES``)."""
    return axes_minv(M, PLANAR_AXES)


def joint_row_descriptors(constrainedAxes, worldTranslation=False):
    """Rows of a joint with the given locks, as (kind, ax, bx):

    * translations: in the A joint frame (``ROW_TRANS_LOCAL``), or in world
      coordinates (``ROW_TRANS_WORLD``) when all three translations are locked or
      ``worldTranslation`` (world components of the locked axes);
    * rotations: 3 locked -> z0.y1, z0.x1, x0.y1; 2 locked (free axis f) -> f0 . l1 for
      both locked axes l; 1 locked (universal, free axes f1 < f2) -> f1_0 . f2_1.
    """
    ax = constrainedAxes
    rows = []
    world = bool(worldTranslation) or (ax[0] and ax[1] and ax[2])
    for i in range(3):
        if ax[i]:
            rows.append((ROW_TRANS_WORLD if world else ROW_TRANS_LOCAL, i, 0))
    nrot = ax[3] + ax[4] + ax[5]
    if nrot == 3:
        rows += [(ROW_ROT, 2, 1), (ROW_ROT, 2, 0), (ROW_ROT, 0, 1)]
    elif nrot == 2:
        free = [i for i in range(3) if not ax[3 + i]][0]
        for lk in range(3):
            if ax[3 + lk]:
                rows.append((ROW_ROT, free, lk))
    elif nrot == 1:
        f1, f2 = [i for i in range(3) if not ax[3 + i]]
        rows.append((ROW_ROT, f1, f2))
    return rows


def resolve_groups(scene: Scene, liegroup):
    """Per-body group names from ``'SE3'``, ``'SO3xR3'``, ``'auto'`` or a mapping/sequence;
    point masses are on ``R3`` whatever is asked (their only group)."""
    out = []
    for i, (b, g) in enumerate(zip(scene.bodies, _rigid_groups(scene, liegroup))):
        if g == "R3" and not b.isPoint:
            raise SceneError(f"liegroup for {scene.describe_body(i)}: R3 is the group of point masses; use 'SE3', "
                             f"'SO3xR3' or 'auto' for a rigid body")
        out.append("R3" if b.isPoint else g)
    return out


def _rigid_groups(scene: Scene, liegroup):
    nb = scene.nBodies
    if isinstance(liegroup, str):
        key = _group_key(liegroup, "liegroup")
        if key == "auto":
            return _planar_subgroups(scene, auto_groups(scene))
        return _planar_subgroups(scene, [key] * nb)
    if isinstance(liegroup, dict):
        out = []
        for i in range(nb):
            if i not in liegroup and scene.bodies[i].isPoint:
                out.append("R3")
                continue
            if i not in liegroup:
                raise SceneError(f"liegroup mapping has no entry for {scene.describe_body(i)}; "
                                 f"give one of 'SE3', 'SO3xR3' for every body")
            out.append(_group_key(liegroup[i], f"liegroup[{i}]"))
        extra = set(liegroup) - set(range(nb))
        if extra:
            raise SceneError(f"liegroup mapping names unknown bodies {sorted(extra)}")
    else:
        seq = list(liegroup)
        if len(seq) != nb:
            raise SceneError(f"liegroup sequence has {len(seq)} entries for {nb} bodies")
        out = [_group_key(g, f"liegroup[{i}]") for i, g in enumerate(seq)]
    return _planar_subgroups(scene, out)


def _planar_subgroups(scene, names):
    """A c-space name per body -> the group of each body: a 2D body on the planar subgroup
    of its c-space (``PLANAR_GROUP``).  The user names c-spaces only ('SE3', 'SO3xR3',
    ``_group_key``); a planar name reaches here from ``compile_scene`` (idempotent) and is
    refused for a 3D body."""
    out = []
    for i, (b, g) in enumerate(zip(scene.bodies, names)):
        space = _SPACE_OF.get(g, g)
        if b.planar:
            out.append(PLANAR_GROUP[space])
        elif g in _SPACE_OF:
            raise SceneError(f"liegroup[{i}] = {g!r} is a planar group but {scene.describe_body(i)} is a 3D body; "
                             f"use {space!r}")
        else:
            out.append(g)
    return out


def _group_key(name, what):
    g = canonical_name(name)
    if g in ("SE3", "SO3xR3", "R3", "auto"):
        return g
    raise SceneError(f"{what}: unknown Lie group {name!r}; use 'SE3', 'SO3xR3' or 'auto' "
                     f"(2D bodies then run on SE2 / SO2xR2)")


def auto_groups(scene: Scene):
    """The automatic per-body choice (paper, section "significance of the c-space"):
    SO3xR3 only for an unconstrained body whose frame sits at its COM (its force-free
    motion is a subgroup of SO3xR3, section secFreeBody), SE3 for every other body
    (lower-pair motions are SE3 subgroups, corollary 1 / lemma 1)."""
    constrained = set()
    for j in scene.joints:
        constrained.update([j.bodyA, j.bodyB])
    for s in scene.connectors():
        constrained.update([s.bodyA, s.bodyB])
    out = []
    for i, b in enumerate(scene.bodies):
        free = i not in constrained
        at_com = np.linalg.norm(b.com) == 0.0
        out.append("SO3xR3" if (free and at_com) else "SE3")
    return out


#: the row kinds of a lean scene (mbs/presence.py); the others (coordinate, rolling disc) make it full
LEAN_ROW_KINDS = (ROW_TRANS_LOCAL, ROW_TRANS_WORLD, ROW_ROT, ROW_DIST)


#: ``SceneData.stabilization`` of a full scene for ``Simulator(stabilization=...)``
STABILIZATION_CODES = {None: STAB_NONE, "velocity": STAB_VELOCITY, "position": STAB_POSITION}

#: False compiles every scene full (tests compare the two kinds on one scene)
LEAN_SCENES = True


def scene_is_lean(scene: Scene, stabilization=None):
    """A lean scene (mbs/presence.py): force elements registered ``lean`` only, joints whose rows
    are of ``LEAN_ROW_KINDS``, no stabilisation (``stabilization`` None), no row with an offset
    function, no probes and no right-hand side of its own (``Scene.SetRightHandSide``).  Its other
    features' tables are None, so the kernel compiled for it has none of their code: the paper's
    models, whose step time the specialisation serves.  Every other scene is compiled *full*, with
    stabilisation, row drives and probes as run-time switches: one kernel kind per method kind
    instead of one per combination of features, each a compile of tens of seconds on a first run
    (23 kinds in the test suite before, 10 after); a scene with a right-hand side shares them."""
    return (LEAN_SCENES and stabilization is None and scene.rightHandSide is None
            and probe_table(scene).shape[0] == 0
            and all(getattr(j, "offset", None) is None for j in scene.joints)
            and lean_elements_only(scene) and all(kind in LEAN_ROW_KINDS for j in scene.joints
                                                  for kind, _, _ in joint_rows_of(j)))


def compile_scene(scene: Scene, groups, stabilization=None, full=False):
    """Flat arrays for the kernel.  ``groups`` is the per-body list of group names;
    ``stabilization``: None, 'velocity' or 'position' (mbs/projection.py); ``full``: full even
    for a lean scene (:func:`scene_is_lean`)."""
    nb = scene.nBodies
    if nb == 0:
        raise SceneError("the scene has no bodies")
    groups = _planar_subgroups(scene, list(groups))     # 2D bodies: the planar subgroup of their c-space
    gid = np.array([GROUP_IDS[g] for g in groups], dtype=np.int64)
    mass = np.array([b.mass for b in scene.bodies], float)
    com = np.array([b.com for b in scene.bodies], float).reshape(nb, 3)
    M = np.array([point_mass_matrix(b) if b.isPoint else body_mass_matrix(b.mass, b.inertia, b.com)
                  for b in scene.bodies])
    Minv = np.array([point_minv(b) if b.isPoint else planar_minv(Mi) if b.planar else
                     axes_minv(Mi, b.freeAxes) if b.freeAxes is not None else np.linalg.inv(Mi)
                     for b, Mi in zip(scene.bodies, M)])

    def arr(x, shape, dtype=float):
        a = np.array(x, dtype=dtype)
        return a.reshape(shape) if a.size else np.zeros(shape if shape[0] != -1 else (0,) + shape[1:], dtype)

    L = scene.loads

    # the constraint rows, joint by joint, in the order of the solve that serves the scene
    # (choose_solve): reverse Cuthill-McKee for the band Cholesky, as given for the tree solve
    J = scene.joints
    nj = len(J)
    jrow0, jnrow, cols, bw = choose_solve(nb, J)
    rkind, rax, rbx, rA, rB, rjoint = cols
    m = len(rkind)
    lean = not full and scene_is_lean(scene, stabilization)
    sd = SceneData(
        nb=nb, gid=gid, mass=mass, com=com, M=M, Minv=Minv,
        gravity=scene.gravity.astype(float), hasGravity=bool(np.any(scene.gravity != 0)),
        hasQext=(EXTERNAL_RATES if scene.rightHandSide is not None else
                 EXTERNAL_FORCES if scene.pythonForces else EXTERNAL_NONE),
        loadIndex=arr([[l.body, 0 if l.kind == "force" else 1, int(l.bodyFixed)] for l in L], (-1, 3), np.int64),
        loadVectors=arr([[l.vector, l.pos] for l in L], (-1, 2, 3)),
        **compile_elements(scene, lean),
        jointIndex=arr([[j.bodyA, j.bodyB, jrow0[k], jnrow[k]] for k, j in enumerate(J)], (-1, 4), np.int64),
        jointPoints=arr([[j.posA, j.posB] for j in J], (-1, 2, 3)),
        jointFrames=arr([[j.rotA, j.rotB] for j in J], (-1, 2, 3, 3)),
        jointParams=arr([joint_parameters(j) for j in J], (-1, N_JOINT_PARAMS)),
        rowIndex=arr([list(x) for x in zip(rkind, rax, rbx, rA, rB)], (-1, 5), np.int64),
        nrows=m, bandwidth=bw, redundant=False, pivotTol=REL_PIVOT_TOL,
        stabilization=None if lean else STABILIZATION_CODES[stabilization],
        rowsAll=None if lean else True,
    )
    return sd, np.array(rjoint, dtype=np.int64)


#: the index-1 solve is the tree solve (mbs.tree_solve) when the rows form a forest and the
#: band of S in reverse Cuthill-McKee order is at least this wide: the band Cholesky costs
#: ~bandwidth^2 per row, the tree solve a constant per body.  Measured crossover (topology
#: bench scenes, MK-RK4): a star of 5 bars on spherical joints (bandwidth 14) costs the same
#: either way (27.7 vs 27.2 us per step), 4 bars (11) 15 % more on the tree, 7 (20) 17 % less.
TREE_MIN_BANDWIDTH = 14


def choose_solve(nb, J):
    """``(jrow0, jnrow, cols, bandwidth)``: the rows of the joints ``J`` (see
    ``_joint_rows_in_order``) in the order of their solve and the bandwidth of ``S`` in that
    order (``solve_plan`` then takes the tree solve for a forest with a band of at least
    ``TREE_MIN_BANDWIDTH``).  A body carrying more than ``TREE_MIN_BANDWIDTH`` rows makes
    them mutually coupled in ``S`` (bandwidth at least that of the clique), so a forest with
    such a body skips the reverse Cuthill-McKee ordering (quadratic in its rows)."""
    nj = len(J)
    if nj == 0:
        jrow0, jnrow, cols = _joint_rows_in_order(J, [])
        return jrow0, jnrow, cols, 0
    jrow0, jnrow, cols = _joint_rows_in_order(J, range(nj))
    forest = tree_plan(nb, _rint_of(cols)) is not None
    per_body = np.bincount([b for b in cols[3] + cols[4] if b != GROUND], minlength=nb)
    if not (forest and per_body.max() > TREE_MIN_BANDWIDTH):
        jrow0, jnrow, cols = _joint_rows_in_order(J, rcm_order(nj, _joint_graph(J)))
    return jrow0, jnrow, cols, _bandwidth(cols[3], cols[4])


def _rint_of(cols):
    return np.array(cols[:5], np.int64).T.reshape(-1, 5)


def _bandwidth(rA, rB):
    """Bandwidth of S: rows q > l couple iff they share a body; the farthest coupled earlier
    row of q is the first row that touched one of q's bodies."""
    bw = 0
    first_row_of_body = {}
    for q in range(len(rA)):
        for b in (rA[q], rB[q]):
            if b == GROUND:
                continue
            if b not in first_row_of_body:
                first_row_of_body[b] = q
            bw = max(bw, q - first_row_of_body[b])
    return bw


def _joint_graph(J):
    """Edges between joints that share a body (the graph of S's rows, joint by joint)."""
    edges = []
    by_body = {}
    for k, jt in enumerate(J):
        for b in (jt.bodyA, jt.bodyB):
            if b != GROUND:
                by_body.setdefault(b, []).append(k)
    for lst in by_body.values():
        for x in range(len(lst)):
            for y in range(x + 1, len(lst)):
                edges.append((lst[x], lst[y]))
    return edges


def _joint_rows_in_order(J, order):
    """First row and row count per joint, and the row columns (kind, ax, bx, A, B, joint)
    with the joints' rows in ``order``."""
    jrow0 = np.zeros(len(J), np.int64)
    jnrow = np.zeros(len(J), np.int64)
    cols = ([], [], [], [], [], [])
    for k in order:
        jt = J[k]
        rows = joint_rows_of(jt)
        jrow0[k] = len(cols[0])
        jnrow[k] = len(rows)
        for kind, a, b in rows:
            for col, v in zip(cols, (kind, a, b, jt.bodyA, jt.bodyB, k)):
                col.append(v)
    return jrow0, jnrow, cols


def solve_plan(sd, solve="auto"):
    """The tree solve's plan for ``sd`` (``tree_plan``), or ``None`` for the band (or, with
    redundant rows, the pivoted) solve, or an ``oblique_solve.ObliquePlan`` when a row's force
    direction differs from its gradient (then always: that solve is the only one for it).  ``solve``: ``'auto'`` (a forest whose band is at
    least ``TREE_MIN_BANDWIDTH`` wide), or ``'tree'`` / ``'band'`` to compare the two on one
    scene (tests, measurements); a scene whose rows close a loop has no tree solve."""
    if sd.nrows == 0:
        return None
    oblique = oblique_plan(sd)
    if oblique is not None:
        # rows whose force direction differs from their gradient (oblique_solve): the LU
        # of J M^-1 C^T; neither the symmetric band / pivoted Cholesky nor the tree solve applies
        if sd.redundant or solve == "tree":
            raise SceneError("the scene has coordinate constraints on rotation-vector coordinates (force direction "
                             "e_k on the local angular velocity, != gradient) together with "
                             + ("redundant constraints" if sd.redundant else "solve='tree'")
                             + ": exudyn_lie's non-symmetric solve has no rank-revealing / tree variant; remove the "
                             "redundant constraint axes")
        return oblique
    if sd.redundant or solve == "band":
        return None
    plan = tree_plan(sd.nb, sd.rowIndex)
    if solve == "tree":
        if plan is None:
            raise SceneError("the constraint rows close a loop (between bodies or through the ground): no tree solve")
        return plan
    return plan if sd.bandwidth >= TREE_MIN_BANDWIDTH else None


# what every Work of a simulator carries over from the one before (compile_carried)
Carried = namedtuple("Carried", ["track", "path", "probe"])


def _rows(rows, shape, dtype=float):
    a = np.array(rows, dtype)
    return a.reshape(shape) if a.size else np.zeros(tuple(0 if d == -1 else d for d in shape), dtype)


def compile_carried(scene: Scene, sd=None):
    """The :class:`TrackPlan`, the initial :class:`PathState` and the probes of the Python
    forces' items of a scene, carried by every Work of its simulator (:func:`make_work`); lean or
    full as its SceneData ``sd`` (default: as :func:`compile_scene` without stabilisation)."""
    lean = scene_is_lean(scene) if sd is None else sd.rowsAll is None
    track = TrackPlan(
        trackCodes=_rows([body_track(b) for b in scene.bodies], (-1,), np.int64),
        angleFrames=_rows([np.eye(3) if b.angleFrame is None else b.angleFrame for b in scene.bodies], (-1, 3, 3)),
        nTracked=int(sum(body_track(b) > 0 for b in scene.bodies)),
        watchBody=np.zeros(0, np.int64), watchEntry=np.zeros((0, 2), np.int64))
    path = PathState(
        torsionAngles=np.zeros(0 if lean else len(scene.torsionalSprings)),
        bodyAngles=np.array([b.angle0 if (b.planar or b.angleFrame is not None) else 0.0 for b in scene.bodies],
                            float),
        bodyParameters=_rows([np.zeros(4) if b.track is None else b.track[1] for b in scene.bodies], (-1, 4)),
        rollingDiscs=None if lean else _rows([rolling_disc_penalty_row(e) + list(e.data0)
                                              for e in scene.rollingDiscPenalties], (-1, N_DISC)),
        watchMax=np.zeros(0),
        jointAngles=_rows([j.coordinate[6:8] if j.coordinate is not None else (0.0, 0.0) for j in scene.joints],
                          (-1, 2)),
        springAngles=_rows([(s.angleA[2], s.angleB[2]) for s in scene.coordinateSprings], (-1, 2)))
    return Carried(track, path, probe_table(scene))


def full_carried(carried):
    """A lean scene's :class:`Carried` for its full SceneData, with the same path state arrays."""
    return carried._replace(path=carried.path._replace(rollingDiscs=np.zeros((0, N_DISC))))


def nothing_carried(sd):
    """Nothing tracked (bodies whose scene did not go through :func:`compile_carried`); for a
    lean scene's SceneData no penalty discs (``rollingDiscs`` None, mbs/presence.py)."""
    nb, lean = sd.nb, sd.rowsAll is None
    track = TrackPlan(trackCodes=np.zeros(nb, np.int64), angleFrames=np.zeros((nb, 3, 3)), nTracked=0,
                      watchBody=np.zeros(0, np.int64), watchEntry=np.zeros((0, 2), np.int64))
    nt = 0 if sd.torsionBodies is None else sd.torsionBodies.shape[0]
    path = PathState(torsionAngles=np.zeros(nt), bodyAngles=np.zeros(nb), bodyParameters=np.zeros((nb, 4)),
                     rollingDiscs=None if lean else np.zeros((0, N_DISC)), watchMax=np.zeros(0),
                     jointAngles=np.zeros((sd.jointIndex.shape[0], 2)),
                     springAngles=np.zeros((0 if sd.coordSpringEnds is None else sd.coordSpringEnds.shape[0], 2)))
    return Carried(track, path, np.zeros((0, N_PROBE)))


def with_redundant(sd, flag):
    return sd._replace(redundant=bool(flag), bandwidth=(sd.nrows - 1 if flag else sd.bandwidth))


def constant_drives(sd):
    """The row drives ``Work.rdrive`` (3, m) of the constant parts: a velocity-level row's
    constant ``c`` (``jointParams[j, 1]``) is its velocity target; rows with a moving offset are
    filled at every evaluation time (mbs/row_drives.py)."""
    rd = np.zeros((3, sd.nrows))
    for j in range(sd.jointIndex.shape[0]):
        q = sd.jointIndex[j, J_ROW0]
        if sd.jointIndex[j, J_NROW] > 0 and sd.rowIndex[q, ROW_KIND] == ROW_COORD_VEL:
            rd[1, q] = sd.jointParams[j, 1]
    return rd


def make_work(sd, nstages, solve="auto", carried=None):
    """The workspace of a simulator; ``carried`` (:func:`compile_carried`): its track plan, path
    state and probes, shared (not copied) so that a new Work keeps their state."""
    nb, lean = sd.nb, sd.rowsAll is None
    carried = nothing_carried(sd) if carried is None else carried
    m = sd.nrows
    plan = solve_plan(sd, solve)
    tree = isinstance(plan, np.ndarray)        # tree_solve's plan (an ObliquePlan is no tree)
    return Work(
        Rs=np.zeros((nb, 3, 3)), rs=np.zeros((nb, 3)), Vs=np.zeros((nb, 6)),
        Rb=np.zeros((nb, 3, 3)), rb=np.zeros((nb, 3)), Vb=np.zeros((nb, 6)), Psi=np.zeros((nb, 6)),
        K=np.zeros((nstages, nb, 6)), Vd=np.zeros((nstages, nb, 6)), Ve=np.zeros((2, nb, 6)), Q=np.zeros((nb, 6)), Qext=np.zeros((nb, 6)),
        Jr=np.zeros((m, 12)), W=np.zeros((m, 12)), eta=np.zeros(m), h=np.zeros(m), lam=np.zeros(m),
        Sb=np.zeros((0 if tree and not sd.redundant else m, sd.bandwidth + 1)),
        Sd=np.zeros((m, m)) if sd.redundant else np.zeros((0, 0)),
        perm=np.zeros(m, np.int64), ytmp=np.zeros(m), failInfo=np.zeros(4, np.int64),
        tmp6=np.zeros(6), tmp12=np.zeros(12), v3=np.zeros((N_SCRATCH3, 3)), m3=np.zeros((4, 3, 3)),
        ident=np.eye(3), zero3=np.zeros(3), zero6=np.zeros(6),
        ext=np.zeros(3, np.int64), rdrive=constant_drives(sd),
        # a full scene's [handle] of the row drives' evaluator (0: none; Simulator._make_work)
        drive=None if lean else np.zeros(1, np.int64), Vw=np.zeros((nb, 6) if sd.hasQext else (0, 6)),
        tplan=plan, Tw=np.zeros(work_size(nb, m, plan)) if tree else None,
        track=carried.track, path=carried.path,
        # None in a lean scene (no probes): external_forces then compiles without probe_kinematics
        # (the call of external_forces itself stays, see stepper.stage_rhs)
        probe=None if lean else carried.probe,
    )
