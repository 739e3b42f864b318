"""``exudyn_lie.SolveDynamic``: the drop-in for ``exudyn.SolveDynamic`` (the arguments
checked, the path chosen, a :class:`~.solver.LieGroupSolver` or the Exudyn-evaluated solver
run inside Exudyn's time loop)."""
from __future__ import annotations

from ..errors import SimulationError, raised_at_boundary
from ..mbs.scene import SceneError
from ..userwarn import warn_user
from .constraint_check import check_tolerance
from .solvertype import REPLACED, resolve_solver_type
from .reader import BridgeError
from .blas_threads import one_blas_thread
from .solve_timing import timed_call
from .solver import LieGroupSolver, _check_method


def _check_index2_rotvec_constraints(mbs, typeName, settings):
    """Exudyn's index-2 solves (TrapezoidalIndex2, generalizedAlpha.useIndex2Constraints) hold a
    ConnectorCoordinate at velocity level, Exudyn's e_k: on a RotVecLG rotation coordinate that
    is omega_k = 0, another model than the position-level theta_k = const (index 3, Exudyn's
    default) that exudyn_lie integrates (mbs/node_coordinates.py).  Refused (reads only)."""
    from .evaluated_items import _describe_object, _rotvec_coordinate_marker
    if not (typeName == "TrapezoidalIndex2" or settings.timeIntegration.generalizedAlpha.useIndex2Constraints):
        return
    for o in range(mbs.systemData.NumberOfObjects()):
        d = mbs.GetObject(o)
        if d["objectType"] == "ConnectorCoordinate" and d.get("activeConnector", True) \
                and _rotvec_coordinate_marker(mbs, d):
            raise BridgeError(f"{_describe_object(mbs, o, d)}: on a rotation coordinate of a NodeRigidBodyRotVecLG, "
                              f"Exudyn's index-2 solve ({'TrapezoidalIndex2' if typeName == 'TrapezoidalIndex2' else 'generalizedAlpha.useIndex2Constraints=True'}) "
                              f"holds omega_k = 0, not the coordinate; exudyn_lie integrates the position-level "
                              f"(index-3) model: use Exudyn's default index-3 setting, or solve with exudyn.SolveDynamic")


def _before_solve(mbs, replacedType, methodName, where, assemble):
    """What both paths say and do before their solve: the implicit solver type the explicit
    method replaces (``replacedType``, or False), and the assembly of an unassembled ``mbs``."""
    if replacedType:
        warn_user(f"exudyn_lie.SolveDynamic: DynamicSolverType.{replacedType} (Exudyn's implicit solver) is replaced, "
                  f"like GeneralizedAlpha, by the Munthe-Kaas method {methodName}{where}; method= or an "
                  f"explicit solverType chooses the method, liegroup= the groups")
    if assemble:
        warn_user("exudyn_lie.SolveDynamic: mbs is not assembled; calling mbs.Assemble()")
        mbs.Assemble()


@raised_at_boundary((SceneError, SimulationError))
@timed_call
@one_blas_thread
def SolveDynamic(mbs, simulationSettings=None, solverType=None, updateInitialValues=False, storeSolver=True,
                 showHints=False, showCausingItems=True, autoAssemble=True, *, method=None, liegroup="auto",
                 stabilization="auto", projectInitial=True, verbose=False, showProgress=True, substeps=None,
                 accelerations=None, constraintTolerance=None, evaluation="auto", constraintCheck=True):
    """Drop-in for ``exudyn.SolveDynamic``: integrate ``mbs`` with a Munthe-Kaas Lie group method
    inside Exudyn's time loop; returns True.

    The positional arguments are Exudyn's.  ``solverType`` (else
    ``timeIntegration.solverType``, as Exudyn reads them): an explicit type selects its
    tableau (RK44 -> RK4, ODE23 -> BS3, ...), GeneralizedAlpha is replaced by ``method``,
    TrapezoidalIndex2 too but with a warning, VelocityVerlet selects the partitioned velocity Verlet,
    DVERK6 is refused
    (:mod:`exudyn_lie.bridge.solvertype`); ``showHints`` / ``showCausingItems`` are accepted for
    compatibility.  Keyword-only extras: ``method`` (default: the explicit solverType's tableau,
    else RK4, or the L-stable implicit ESDIRK3 where RK4 is not stable at the step, at the start or
    after a blow-up during the run, said in one line: :mod:`.method_choice`;
    :func:`exudyn_lie.method_names`, ``'ESDIRK3'`` or a
    :class:`~exudyn_lie.integrators.ButcherTableau` of the user's own; it must agree with an
    explicit solverType),
    ``liegroup`` ('SE3', 'SO3xR3', 'auto' or {rigid-body object index: group}),
    ``stabilization`` (default 'auto': 'position', so that joints hold to round-off as Exudyn's
    generalized-alpha holds them to its Newton tolerance; on the Exudyn-evaluated path onto
    Exudyn's own constraints, once their residual exceeds 1e-10 of the scale,
    bridge/evaluated_projection.py; its cost: ``bench --sections stabilization``; None with
    ``constraintTolerance``, which projects by its own rule; None: the paper's unstabilised
    methods; 'velocity'), ``projectInitial`` (default True: an inconsistent initial state is
    projected onto the constraints with a warning; False: ConstraintError), ``verbose``
    (print the group per body, the plan and the time spent), ``showProgress`` (a progress line every 2 s on runs longer than about 4 s, with
    the time to go),
    ``substeps`` (internal steps per Exudyn step; default: one Exudyn step per output
    period), ``accelerations`` (write q_tt / multipliers; default: when something reads
    them), ``constraintTolerance`` (adaptive steps only; default None: off): project on the
    group when the constraint drift exceeds it, the error estimate projected onto the
    constraint manifold's tangent space (Simbody's scheme; docs/ADAPTIVE.md),
    ``evaluation`` ('auto': the compiled kernel when it has every item of the model,
    else Exudyn evaluates the whole model, :mod:`.evaluated_solve`, with one warning naming
    the items; 'compiled' / 'exudyn' force a path), ``constraintCheck`` (default True:
    Exudyn's own position-level residuals of the constraints at the outputs, within 2 % of
    the run's time (its set-up included) and always at the first and the last, with a tolerance of 1e-5 times the model's size; a residual above it that the integrator's own
    account does not explain stops the run with a ConstraintError naming the item, one it
    explains, the drift of an unstabilised method, is reported once per item as a warning;
    a float sets the tolerance in the rows' units, False switches the check off;
    :mod:`.constraint_check`).

    Honours ``timeIntegration.startTime / endTime / numberOfSteps``, sensors (stored and
    files), the solution and restart files, pre/post-step user functions,
    ``updateInitialValues`` and ``storeSolver`` (``mbs.sys['dynamicSolver']``,
    ``mbs.sys['lieGroupSolver']``).  ``simulationSettings`` is not changed, not even
    during the run (see :meth:`LieGroupSolver.Solve`).

    Bad input raises before ``mbs`` is touched: the arguments, the settings and the whole
    model (items, initial state, and with ``projectInitial=False`` the initial constraint
    consistency) are checked first; with
    ``autoAssemble`` and an mbs that is not assembled, the model is checked from its item
    dictionaries (what ``mbs.Assemble()`` will set) and only then assembled.

    Where the call's time went (set-up, numba's compilation, the time loop):
    ``exudyn_lie.GetSolveTiming()`` (:mod:`.solve_timing`)."""
    import exudyn as exu
    check_tolerance(constraintCheck)
    auto = stabilization == "auto"
    settings = exu.SimulationSettings() if simulationSettings is None else simulationSettings
    # solverType (argument, else the setting, as Exudyn reads them) -> the tableau (bridge/solvertype.py)
    named = method is not None
    method, typeName, replaced = resolve_solver_type(solverType, settings.timeIntegration.solverType, method,
                                                     _check_method)
    autoImplicit = not named and typeName in REPLACED      # no method named: RK4, or ESDIRK3 where RK4 is unstable
    assemble = not mbs.systemIsConsistent and autoAssemble
    if evaluation not in ("auto", "compiled", "exudyn"):
        raise BridgeError(f"evaluation must be 'auto', 'compiled' or 'exudyn', got {evaluation!r}")
    scene = None                         # the model as the compiled reader read it (read once)
    if evaluation != "compiled":
        from .evaluated_dispatch import evaluated_path
        path, scene = evaluated_path(mbs, evaluation, assemble, method=method, liegroup=liegroup,
                                     stabilization="position" if auto else stabilization, projectInitial=projectInitial,
                                     verbose=verbose, settings=settings, substeps=substeps, autoImplicit=autoImplicit)
        if path is not None:
            if constraintTolerance is not None:
                raise BridgeError("exudyn_lie.SolveDynamic: constraintTolerance is available on the compiled path only "
                                  "(adaptive steps); this model is evaluated by Exudyn: leave constraintTolerance=None")
            _before_solve(mbs, replaced and typeName, path.tableau.name, "", assemble)
            return path.Solve(simulationSettings, updateInitialValues=updateInitialValues, storeSolver=storeSolver,
                              showProgress=showProgress, substeps=substeps, accelerations=accelerations,
                              constraintCheck=constraintCheck)
    if auto:      # the drop-in holds joints as native does (README, "Options that matter")
        stabilization = None if constraintTolerance is not None else "position"
    solver = LieGroupSolver(mbs, method=method, liegroup=liegroup, stabilization=stabilization,
                            projectInitial=projectInitial, verbose=verbose, constraintTolerance=constraintTolerance,
                            autoImplicit=autoImplicit, handOver=evaluation == "auto" and auto and constraintTolerance is None,
                            _configuration="items" if assemble else "initial", _scene=scene)
    solver._check_run(settings, substeps)
    _check_index2_rotvec_constraints(mbs, typeName, settings)
    groups = ", ".join(f"{g} ({solver.groups.count(g)})" for g in dict.fromkeys(solver.groups)) or "none"
    _before_solve(mbs, replaced and typeName, solver.tableau.name, f" on the Lie groups {groups} (bodies per group)",
                  assemble)
    return solver.Solve(simulationSettings, updateInitialValues=updateInitialValues, storeSolver=storeSolver,
                        showProgress=showProgress, substeps=substeps, accelerations=accelerations, refresh=assemble,
                        constraintCheck=constraintCheck)
