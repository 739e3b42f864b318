"""A :class:`~.simulator.Simulator`'s side of the implicit methods (free functions of ``sim``; the
simulator's ``Advance``, ``newtonCounters`` and the output rows call them): fixed steps whose
Newton iteration did not converge, done again in parts (:func:`substeps`), and the Newton work
counted (:func:`newton_counters_of`).  The iteration itself is compiled: :mod:`.implicit`."""
from __future__ import annotations

from . import kernel
from .implicit import NEWTON_MAXIT_FULL, NEWTON_TOL, NP_FOLLOW, NP_MAXIT_FULL, NP_TOL, implicit_method, newton_counters
from .methods import method_arrays

#: the parts an implicit step whose Newton iteration does not converge is tried in, in turn
SUBSTEPS = (2, 4, 8, 16, 32, 64)


def method_arrays_of(tableau, gid):
    """The stepper's form of ``tableau`` (mbs/methods.py): an explicit ``Method`` (partitioned or not),
    or an ``ImplicitMethod`` with its Newton arrays for the bodies of
    group ids ``gid``."""
    return implicit_method(tableau, gid) if tableau.implicit else method_arrays(tableau)


def apply_fallbacks(sim):
    """Newton's own iteration after a failed simplified one for ``sim``'s implicit method, where
    ``sim.newtonSubsteps`` divides failed steps too (:meth:`~.simulator.Simulator.SetNewtonFallbacks`)."""
    nw = getattr(sim.method, "newton", None)
    if nw is not None:
        nw.par[NP_MAXIT_FULL] = NEWTON_MAXIT_FULL if sim.newtonSubsteps else 0.0


def set_newton_tolerance(sim, tol):
    """The Newton tolerance of ``sim``'s implicit method with fixed steps: ``None`` (default) makes it
    follow each step's local error (:func:`~.implicit.follow_local_error`), a number holds it (relative
    to the step's velocity scale).  Adaptive steps derive it from ``rtol`` (:func:`~.implicit.newton_tolerance`)."""
    nw = getattr(sim.method, "newton", None)
    if nw is None:
        raise ValueError(f"{sim.tableau.name} is explicit: no Newton iteration")
    nw.par[NP_FOLLOW] = 1.0 if tol is None else 0.0
    nw.par[NP_TOL] = NEWTON_TOL if tol is None else float(tol)


def newton_counters_of(sim):
    """The Newton work of ``sim``'s implicit method so far, fixed and adaptive steps together (None
    for an explicit method)."""
    if not sim.tableau.implicit:
        return None
    out = newton_counters(sim.method.newton)
    ad = getattr(sim, "_ad", None)
    if ad is not None and hasattr(ad.method, "newton"):
        for key, v in newton_counters(ad.method.newton).items():
            out[key] += v
    return out


def advance(sim, n, h):
    """``n`` fixed steps of ``h`` from ``sim``'s state, a step whose Newton iteration fails done in
    parts (:func:`substeps`, unless ``sim.newtonSubsteps`` is empty: a caller that reduces the step
    itself); returns the kernel status (``sim.t`` at the last accepted step)."""
    done = 0
    while True:
        st, d = sim._mk_steps(n - done, h)
        done += d
        sim._clock.advance(d)
        if st != kernel.STATUS_NEWTON or not sim.tableau.implicit or not sim.newtonSubsteps:
            return st
        st = substeps(sim, h, sim.t)
        if st != kernel.STATUS_OK:
            return st
        done += 1
        sim._clock.advance(1)
        if done == n:
            return st


def substeps(sim, h, t):
    """One step of size ``h`` from ``sim``'s state at ``t`` in ``sim.newtonSubsteps`` equal parts, the first
    division whose every part converges (its Newton iteration); a failed division leaves the state and
    the path state as they were.  Returns the kernel status (``STATUS_NEWTON`` when every division
    failed).  A force that switches on inside a step (a contact that closes) can stall the iteration at
    the user's step."""
    start = (sim.R.copy(), sim.r.copy(), sim.V.copy())
    path = [None if a is None else a.copy() for a in sim.wk.path]
    for m in sim.newtonSubsteps:
        st, _ = sim._mk_steps(m, h / m, t)
        if st == kernel.STATUS_OK:
            sim.dividedSteps += 1
            return st
        sim.R[:], sim.r[:], sim.V[:] = start
        for a, saved in zip(sim.wk.path, path):
            if a is not None:
                a[...] = saved
        if st != kernel.STATUS_NEWTON:
            return st
    return kernel.STATUS_NEWTON
