"""Stiffness estimates of a :class:`~.simulator.Simulator` ``sim`` (free functions; the
simulator's ``StageStiffness``, ``suggest_step`` and ``SpectralRadius`` call them), and the
rules that turn them into a stable step size:

* the eigenvalues ``lambda`` of the linearised equations (a problem's own linearisation, e.g.
  the Jacobians of the modelling system the bridge reads, on the evaluated path) and the
  method's stability polynomial ``R``: the largest ``h`` with ``|R(h lambda)| <= 1``
  (:func:`largest_stable_step`), the check before a run (:func:`check_linear_stability`);
* the spectral radius ``rho`` of the linearised equations (power iteration on
  Jacobian-vector products of the stepper's own vector field, :func:`spectral_radius`) and
  the radius of the method's stability half-disk: the step suggested after a blow-up
  (:func:`suggest_step`);
* Shampine's estimate from a step's stages: a mode that became stiff during a run
  (:class:`StageStiffnessWatch`).
"""
from __future__ import annotations

import numpy as np

from ..errors import SimulationError, step_size_error
from ..integrators.stability import is_a_stable, pair_growth, stability_coefficients, stability_radius
from . import kernel
from .bodies import body_dexpinv_stage, exp_compose
from .diagnostics import stage_rates

SAFETY = 0.9                 # a suggested step: this fraction of the largest stable one
GROWTH_TOL = 1e-9            # |R(z)| <= 1 + GROWTH_TOL counts as stable (R(0) = 1 exactly)
RUN_GROWTH = 1.1             # ... or |R(z)|^n <= RUN_GROWTH over a run of n steps (check_linear_stability)
STIFF_STEPS = 3              # h rho beyond the stability radius in this many consecutive steps ...
STIFF_FACTOR = 10.0          # ... or beyond this multiple of it in one step (a stiff contact lasts a step or two)


def _grows(coeffs, z, tol=GROWTH_TOL):
    return np.abs(np.polyval(coeffs[::-1], z)) > 1.0 + tol


def largest_stable_step(tableau, ev, nsteps=None):
    """The largest h with ``|R(h lambda)| <= 1`` for every eigenvalue (inf if every mode is
    stable for all h, e.g. no stiffness); bisection between stable and unstable h.  Modes
    that grow physically count with their imaginary part only.

    ``nsteps`` (a run's number of steps): ``|R(h lambda)|^nsteps <= RUN_GROWTH`` instead.  Most
    explicit methods of order 5 and above (DOPRI5, RK67) leave the imaginary axis at the origin:
    ``|R(i y)| = 1 + O(y^(p+2))`` grows for every step of an undamped oscillation, RK67 by 5.3e-4 per
    step at h omega = 1: 1 % over a run of 20 such steps, an error of the size of the method's own
    at that step; over 1000 steps at h omega = 0.91, 1.3 times (docs/EVALUATED.md, Stiffness,
    names the two scripts these figures come from)."""
    # a mode that grows physically (Re lambda > 0: an inverted pendulum, gyroscopic
    # coupling) grows for every h; only its oscillation must be resolved: Re lambda -> 0
    ev = np.asarray(ev, complex)
    ev = np.minimum(ev.real, 0.0) + 1j * ev.imag
    ev = ev[np.abs(ev) > 0]
    if ev.size == 0 or (tableau.implicit and is_a_stable(tableau)):
        return float("inf")
    if tableau.partitioned:          # every mode as a second-order one (the configurations' own coefficients)
        def grows(z, tol):
            return pair_growth(tableau, z) > 1.0 + tol
    else:
        c = np.array([float(x) for x in stability_coefficients(tableau)])

        def grows(z, tol):
            return _grows(c, z, tol)
    tol = GROWTH_TOL if not nsteps else max(GROWTH_TOL, RUN_GROWTH ** (1.0 / nsteps) - 1.0)
    rho = float(np.max(np.abs(ev)))
    hi = 1.0 / rho
    while not np.any(grows(hi * ev, tol)):
        hi *= 2.0
        if hi * rho > 1e6:
            return float("inf")
    lo = 0.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if np.any(grows(mid * ev, tol)):
            hi = mid
        else:
            lo = mid
    return lo


def check_linear_stability(tableau, h, t, ev, source, refuse=True, nsteps=None):
    """Raise the StepSizeError (with ``refuse``) if ``h`` is beyond the largest stable step
    for the eigenvalues ``ev`` of the linearised equations at time ``t`` (``source`` says
    where they come from; ``nsteps``: over a run of that many steps, :func:`largest_stable_step`);
    returns (fastest rate |lambda|, largest stable step)."""
    ev = np.asarray(ev, complex)
    hmax = largest_stable_step(tableau, ev, nsteps)
    rate = float(np.max(np.abs(ev))) if ev.size else 0.0
    if refuse and h > hmax:
        raise step_size_error(tableau.name, h, t, "the step size is beyond the stability limit of the method for "
                              "this model", f"its fastest mode has |lambda| = {rate:.4g} 1/s ({source}), stable "
                              f"up to h = {hmax:.3g} s", SAFETY * hmax)
    return rate, hmax


class StageStiffnessWatch:
    """A mode that became stiff during a run of fixed steps (a contact that closes, a
    friction zone that is entered): Shampine's estimate from the last step's stages
    (:func:`stage_stiffness_of`) against the method's stability radius; the StepSizeError
    after ``STIFF_STEPS`` steps beyond it in a row, or one step ``STIFF_FACTOR`` beyond (a caller
    that repeats the step with an implicit method watches every step: :func:`watch_stages`)."""

    def __init__(self, tableau):
        self.tableau = tableau
        self.radius = stability_radius(tableau)
        self.count = 0

    def check(self, sim, h, nb=None, firstOrder=None, strict=False):
        """``firstOrder``: a function giving the rate of the first-order coordinates' own modes (from
        their eigenvalues; ``radius / largest stable step`` beyond the half-disk), which the
        second-order estimate of the stages does not see (a rate measured some steps before counts
        for each of them); ``strict``: fail at the first step beyond (a caller that repeats it with
        an implicit method)."""
        if self.radius == np.inf:       # an A-stable method: no mode is beyond its region
            return
        rho = stage_stiffness_of(sim, h, nb)
        source = ("Shampine's estimate from the stages; e.g. a contact or a friction zone that became "
                  "active")
        what = "its stages show a mode beyond its stability region"
        rho1 = firstOrder() if firstOrder is not None else 0.0
        if rho1 > rho:
            rho, source = rho1, ("the eigenvalues of d(ydot)/dy of the first-order coordinates at the state "
                                 "last evaluated; e.g. a regularised friction state that became stiff")
            what = "its first-order coordinates have a mode beyond its stability region, by d(ydot)/dy"
        if h * rho <= self.radius:
            self.count = 0
            return
        self.count += 1
        if strict or self.count >= STIFF_STEPS or h * rho > STIFF_FACTOR * self.radius:
            exc = step_size_error(
                self.tableau.name, h, sim.t, "the step size is beyond the stability limit of the method",
                f"the last step(s) show a mode of rate |lambda| ~ {rho:.4g} 1/s ({source}), h |lambda| = "
                f"{h * rho:.3g} > {self.radius:.3g} (the method's stability radius, or the rate at which the "
                f"mode leaves its stability region); the state is not reliable",
                SAFETY * self.radius / rho)
            exc.stiffStages = rho
            exc.stiffWhat = what
            raise exc


def watch_stages(sim, on, nb=None):
    """With ``on``, every fixed step of ``sim``'s explicit method whose stages show a mode beyond its
    stability radius (:func:`stage_stiffness_of`'s estimate, in the stepper) is undone and the run
    stops with STATUS_STIFF: for a caller that repeats the step with an implicit method.  The
    explicit method amplifies the stiff mode in every step beyond its radius (RK4 at h |lambda| =
    5.5: about 20 times per step): after a few such steps the state is far off, and a run that
    continued from there with the implicit method was wrong without a sign.  Off for an implicit
    method.  ``nb``: the first bodies watched (default all)."""
    radius = stability_radius(sim.tableau) if on and not sim.tableau.implicit else 0.0
    sim.control.par[0] = radius if np.isfinite(radius) else 0.0
    sim.control.par[1] = sim.sd.nb if nb is None else int(nb)


def stage_stiffness_of(sim, h, nb=None):
    """Shampine's estimate of the fastest rate the last fixed step of size ``h`` met, from
    its stages (the largest of :func:`~.diagnostics.stage_rates`; the first ``nb`` bodies, default all):
    a mode that became stiff during the run (a contact that closed) shows here before it
    blows up."""
    tab = sim.method
    return float(stage_rates(tab.A, getattr(tab, "Aq", tab.A), float(h), tab.stages, sim.wk.K, sim.wk.Vd,
                             sim.sd.nb if nb is None else int(nb))[0])


def suggest_step(sim, h):
    """A step size that should be stable: ``0.8 r / rho``, where ``rho`` is the spectral
    radius of the linearised equations of motion at the state the failed :meth:`Advance`
    (or chunk of output rows, :mod:`.outputs`) started from (:meth:`SpectralRadius`) and ``r``
    the radius of the method's stability half-disk (:func:`~exudyn_lie.integrators.stability.stability_radius`).
    Never more than ``h / 2``; ``h / 10`` if the estimate is not available."""
    start = getattr(sim, "_segmentStart", None)
    try:
        if start is None:
            raise ValueError("no reference state")
        t0, R, r, V = start[:4]
        rho = spectral_radius(sim, R, r, V, t0)
    except Exception:           # noqa: BLE001 - a suggestion must never mask the error
        return h / 10.0
    if not np.isfinite(rho) or rho <= 0:
        return h / 10.0
    return float(min(0.5 * h, 0.8 * stability_radius(sim.tableau) / rho))


def spectral_radius(sim, R=None, r=None, V=None, t=None, iterations=40, seed=0):
    """Estimate of the spectral radius ``rho`` of the Jacobian of the first-order
    equations of motion ``(xi, V)' = (dexp^-1_{-xi} V, F(g exp(xi), V))`` in local
    coordinates ``xi`` around ``g`` (eqs. ODE2 with MK1): power iteration on
    central-difference Jacobian-vector products.  ``h rho`` is what the step size
    must keep inside the method's stability region."""
    R = sim.R if R is None else np.asarray(R, float)
    r = sim.r if r is None else np.asarray(r, float)
    V = sim.V if V is None else np.asarray(V, float)
    t = sim.t if t is None else float(t)
    nb = sim.sd.nb
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(2, nb, 6))
    d /= np.linalg.norm(d)
    scale = 1.0 + float(np.max(np.abs(V))) + float(np.max(np.abs(r)))
    logs = []
    for it in range(int(iterations)):
        eps = 1e-7 * scale
        fp = _local_field(sim, R, r, V, t, eps * d)
        fm = _local_field(sim, R, r, V, t, -eps * d)
        w = (fp - fm) / (2 * eps)
        nw = float(np.linalg.norm(w))
        if not np.isfinite(nw):
            return float("nan")
        if nw == 0.0:
            return 0.0
        logs.append(np.log(nw))
        d = w / nw
    # the dominant modes of a mechanical system come in complex pairs, for which the
    # norm ratio oscillates: average the logarithms of the second half
    return float(np.exp(np.mean(logs[len(logs) // 2:])))


def _local_field(sim, R, r, V, t, dx):
    """The vector field of :meth:`SpectralRadius` at ``(xi, V + dV) = dx``."""
    sd, wk = sim.sd, sim.wk
    nb = sd.nb
    Rp = np.empty((nb, 3, 3))
    rp = np.empty((nb, 3))
    Vp = np.ascontiguousarray(V + dx[1])
    out = np.empty((2, nb, 6))
    ER, Er = np.empty((3, 3)), np.empty(3)
    for i in range(nb):
        X = np.ascontiguousarray(dx[0, i])
        exp_compose(int(sim.gid[i]), R[i], r[i], X, Rp[i], rp[i], ER, Er)
        body_dexpinv_stage(int(sim.gid[i]), -X, Vp[i], out[0, i])
    if sim._evaluate(t, Rp, rp, Vp) != kernel.STATUS_OK:
        raise SimulationError("right-hand side failed while estimating the spectral radius")
    out[1] = wk.Vd[0]
    return out
