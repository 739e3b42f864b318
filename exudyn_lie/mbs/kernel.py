"""The compiled multibody kernel: the public names of its modules in one namespace.

Everything is numba-compiled and allocation-free; it works on the flat arrays of
:class:`exudyn_lie.mbs.compiled.SceneData` and ``Work``.  One module per job:

* :mod:`.codes` - group ids, row kinds, table columns, status codes, bounds;
* :mod:`.bodies` - per-body kinematics in the body's group (the only group dispatch, its
  group maps generated from the registry ``groups.GROUPS``);
* :mod:`.force_elements` - one registration per compiled force element, and
  ``compute_forces`` / ``spring_energy`` generated from them;
* :mod:`.forces` - applied and inertial generalised forces, one function per element;
* :mod:`.constraints` - joint rows ``h``, ``J`` and ``eta = -Jdot V``;
* :mod:`.index1` - the index-1 solve (Schur complement) and the stage right-hand side;
* :mod:`.projection` - position / velocity projection on the group;
* :mod:`.stepper` - the Munthe-Kaas stepper ``mk_steps`` with its seams
  (step controller: fixed, or :mod:`.adaptive`; right-hand side evaluated in Python);
* :mod:`.diagnostics` - energies and the rows of all joints at a state.

State per body ``i``: ``R[i]`` (3x3, body->world), ``r[i]`` (frame origin, world) and the
velocity ``V[i] = (omega, v)``; ``gid[i]`` selects the c-space group of the body:

* ``SE3`` (0): ``v`` body-fixed, ``rdot = R v``; Newton-Euler eq. (NE1),
  ``M Vdot - ad_V^T M V = W`` with the constant ``M = J_P``;
* ``SO3xR3`` (1): ``v = rdot`` spatial (mixed velocity, eq. hybridvel); the mixed
  Newton-Euler equations (section "Arbitrary Body-Fixed Reference Frame") with
  ``M^m = D M D^T``, ``D = diag(I, R)``.

Code layout (compile time): the entry points take the ``SceneData`` / ``Work``
namedtuples (``mk_steps`` - the time loop, also the accelerations at a state with
``nsteps = 0`` - and ``all_rows`` - constraint rows and energies for diagnostics); they
unpack them and call working functions that receive only the arrays they use.  Numba's
compile time grows steeply with the size of the tuples a function receives: the big
working functions (joint rows, spring forces, ...) are compiled and cached once with
short signatures; the light per-stage ones are inlined (``inline="always"``), which
keeps the stage free of call overhead.  Scratch vectors are rows of ``wk.v3`` (20, 3)
and ``wk.m3`` (4, 3, 3).
"""
from .bodies import add_point_force, add_world_torque, apply_minv, body_axis, body_point, exp_compose  # noqa: F401
from .codes import *  # noqa: F401,F403
from .constraints import joint_rows, joints_rows  # noqa: F401
from .diagnostics import all_rows, kinetic_and_gravity  # noqa: F401
from .force_elements import compute_forces, spring_energy  # noqa: F401
from . import implicit  # noqa: F401  (registers the implicit methods' overloads of the stepper's seam)
from .index1 import rhs, schur_correct, schur_solve  # noqa: F401
from .projection import project, project_state  # noqa: F401
from .step_observers import after_accepted_step, observe_initial_state, watch_rotation_entries  # noqa: F401
from .stepper import copy_state, mk_finish, mk_stage_k, mk_stage_state, mk_steps, state_is_finite  # noqa: F401
