"""The drop-in's method when the user names none (no ``method=``, an implicit Exudyn solver type):
the explicit default where it is stable at the script's own step, else the L-stable implicit
ESDIRK3 (mbs/implicit.py).  Both paths decide once at the start of a fixed-step run, from the
largest stable step of the explicit method at the initial state: the compiled path from the
spectral radius of its linearised equations (``Simulator.SpectralRadius``), the evaluated path
from the eigenvalues of Exudyn's own linearisation (``evaluated_stiffness.choice_step``: the largest
modes first where the damping is not proportional)."""
from ..integrators.control import P_H_MIN
from ..integrators.tableau import get_method
from .run_plan import adaptive_settings
from ..mbs.codes import STATUS_BLOWUP, STATUS_NONFINITE, STATUS_STAGE_ARG, STATUS_STIFF
from ..mbs.stiffness import watch_stages

#: the kernel statuses of an explicit method that a stiff mode makes unstable
UNSTABLE_STATUS = (STATUS_BLOWUP, STATUS_NONFINITE, STATUS_STAGE_ARG, STATUS_STIFF)

IMPLICIT_DEFAULT = "ESDIRK3"


def stiff_choice(explicit, h, hmax, rate, source):
    """``(tableau, line)``: ``explicit`` and None when ``h <= hmax`` (its largest stable step),
    else the implicit default and the one line that says why."""
    if not h > hmax:
        return explicit, None
    imp = get_method(IMPLICIT_DEFAULT)
    line = (f"exudyn_lie: {explicit.name} is not stable at the step h = {h:.4g} s for this model (fastest mode "
            f"|lambda| ~ {rate:.4g} 1/s, {source}; stable up to h = {hmax:.3g} s): integrating with the L-stable "
            f"implicit {imp.name} (order {imp.order}); method='{explicit.name}' keeps the explicit method")
    return imp, line


def unstable_choice(explicit, h, t, status, what=None):
    """``(implicit default, line)`` when ``explicit`` became unstable during a run (a contact that
    closed, a friction zone entered: a mode the check at the start could not see); ``status``: the
    kernel's, or None for the watch's estimate (mbs/stiffness.StageStiffnessWatch, which says
    ``what`` it saw)."""
    imp = get_method(IMPLICIT_DEFAULT)
    what = what or {STATUS_BLOWUP: "the state blew up", STATUS_NONFINITE: "the state became non-finite",
                    STATUS_STAGE_ARG: "a stage rotation exceeded 2 pi"}.get(
        status, "its stages show a mode beyond its stability region")     # (None, STATUS_STIFF)
    line = (f"exudyn_lie: {explicit.name} became unstable after t = {t:.6g} s at the step h = {h:.4g} s ({what}): "
            f"continuing from Exudyn's state at t = {t:.6g} s with the L-stable implicit {imp.name} (order "
            f"{imp.order}); method='{explicit.name}' keeps the explicit method")
    return imp, line


def auto_choice_text(tab):
    """The solution file's name of the method of a run whose choice is made at its start."""
    return f"{tab.name}, or {IMPLICIT_DEFAULT} if the model is too stiff for it at this step,"


# --------------------------------------------------------------------------- the compiled path's solver
def choose_at_start(solver, h):
    """A :class:`~.solver.LieGroupSolver`'s method for a fixed-step run of ``h``: its explicit one, or
    ESDIRK3 where that is not stable at ``h`` by the spectral radius of the linearised equations at the
    initial state."""
    from ..errors import SimulationError
    from ..integrators.stability import stability_radius
    explicit, sim = solver._explicit, solver.sim
    try:
        rho = sim.SpectralRadius()
    except SimulationError:           # the right-hand side fails at the start: the run says how
        rho = 0.0
    hmax = stability_radius(explicit) / rho if rho > 0 else float("inf")
    tab, line = stiff_choice(explicit, h, hmax, rho, "the spectral radius of the linearised equations at the "
                             "initial state")
    if tab is not sim.tableau:
        sim.SetMethod(tab)
    watch_stages(sim, True)             # a mode that becomes stiff later (off for ESDIRK3)
    solver.tableau, solver.method = tab, tab.name
    if line:
        print(line)


def replace_after_failure(solver, status, h, t, plan):
    """After a blow-up of the explicit method the user did not name: ESDIRK3 from now on (the caller
    restarts from Exudyn's state at ``t``); False when the failure stays an error.

    ESDIRK3 then takes the steps ``method='ESDIRK3'`` takes with the user's settings (adaptive by
    Exudyn's default ``adaptiveStep``), with one difference: a step at ``minimumStepSize`` is accepted
    beyond the tolerance (counted, a warning at the end), as Exudyn's explicit solvers continue.
    Why adaptive: the failure is an event that fixed steps do not resolve.  The penalty rolling
    coin's friction takes its direction from the last step's slip (Exudyn's data coordinates); at
    the script's step it chatters after the impact, 2.0 off a fine run where adaptive steps are
    4.7e-3 off (tests/test_rolling_disc_penalty.py).  Why accepted at the minimum: a contact force
    that jumps (a damped floor written as a load) has a local error O(h) that no step meets; the
    fixed steps this replaces have no error control at all."""
    sim = solver.sim
    if not (solver.autoImplicit and not sim.tableau.implicit and status in UNSTABLE_STATUS):
        return False
    tab, line = unstable_choice(sim.tableau, h, t, status)
    sim.SetMethod(tab)
    watch_stages(sim, False)
    solver.tableau, solver.method = tab, tab.name
    adaptive = adaptive_settings(tab, plan["ss"], h)
    if adaptive is not None:
        adaptive.update(minStep=adaptive["minStep"] or 1e-6 * h, acceptAtMinStep=True)
        plan["adaptive"] = adaptive
        line += (f"; with adaptive steps of at most {h:.4g} s (timeIntegration.adaptiveStep; relativeTolerance "
                 f"{adaptive['rtol']:g}, absoluteTolerance {adaptive['atol']:g})")
    solver._chunks = solver._new_chunks()          # (for the new method's stepper, fixed or adaptive)
    print(line)
    return True


def warn_steps_at_minimum(sim):
    """Exudyn's warning, once at the end: steps accepted at the minimum step beyond the tolerance."""
    ad = sim.adaptiveRun
    n = 0 if ad is None else ad.stepsAtMinStep
    if n:
        from ..userwarn import warn_user
        warn_user(f"exudyn_lie: {n} adaptive step(s) of {sim.tableau.name} reached timeIntegration.minimumStepSize "
                  f"= {ad.par[P_H_MIN]:g} s and were accepted beyond the tolerance (a force with a jump, an impact); "
                  f"the run continued, as Exudyn's explicit solvers do")
