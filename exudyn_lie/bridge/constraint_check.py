"""The run-time check of the constraints, independent of the integrator: at the outputs,
Exudyn's own position-level residuals of the algebraic equations
(``ComputeAlgebraicEquations``) at the state written into mbs.

A constraint that does not hold is the most visible symptom of integrating another model
than the user's, and Exudyn computes it from its own item definitions, whatever exudyn_lie
made of them.  Explicit index-1 integration without stabilisation lets the constraints
drift, though (the paper's subject: on SO3xR3 a revolute joint drifts, on SE3 it holds), so a
residual above the tolerance is judged by whether the integrator's own account explains it:

* the compiled path: the kernel's residuals of the same joint at the same state
  (``Simulator.RowResiduals``).  If the kernel sees its rows of the joint drift as much (at
  least :data:`EXPLAINED` of Exudyn's residual), the drift is the method's: a warning names
  the item and the size, once per item.  If the kernel holds its rows while Exudyn's residual
  of the item is large, the kernel integrates another constraint than Exudyn's: a
  :class:`~exudyn_lie.errors.ConstraintError` stops the run.
* the Exudyn-evaluated path (the integrator's rows are Exudyn's own, so they cannot be
  compared with themselves): the residual must change as the velocity-level equations the
  integrator uses say, ``g(t1) - g(t0) = (t1 - t0) (g_v(t0) + g_v(t1)) / 2`` up to the
  trapezoid's error and the method's local position error, summed over the run per item.  A
  velocity level that leaves out a moving offset (Exudyn's GenericJoint with
  ``offsetUserFunction``, a ``ConnectorCoordinate`` offset moved by a pre-step function) lets
  the residual grow by steps the velocity level does not see, at the offset's rate.  The
  run stops when more than half of the growth is unexplained *and* the unexplained part grows
  at more than :data:`UNEXPLAINED_RATE` of the model's velocity scale (the largest velocity
  coordinate so far times the model's size, at least 1 m) *and*, in a model where no Python
  function runs between Exudyn's steps, it is more than :data:`METHOD_ERROR_RATIO` times the
  velocity level's own drift over the same steps (the sum of ``(t1 - t0) |g_v(t1) - g_v(t0)|``).
  The method's local position errors also escape the velocity level, at a rate of about
  ``(omega h)^4 / 120`` of the velocities for RK4, which the rate rule alone excuses only up to
  ``omega h ~ 1`` (RK4 at h = 0.1 s on a swinging double pendulum broke it:
  tests/test_evaluated_projection.py).  They come with local velocity errors: a step's position
  error ``e_q`` and velocity error ``e_v`` of a mode of frequency omega keep ``h |e_v| ~ omega h
  |e_q|``, so the unexplained part is about ``1 / (omega h)`` times the velocity level's drift,
  within the ratio from ``omega h ~ 0.1`` on (that run: 0.1 to 8 times where an item was judged;
  docs/EVALUATED.md).  A moving offset that the velocity level leaves out moves the position level
  only (the velocity level stays where the integrator keeps it): 2.4e10 times the drift in
  tests/test_trust.py's defect.  A marker that a pre-step function moves on a moving body,
  though, moves both levels at each step (the position level by the marker's move ``dp``, the
  velocity level by about ``omega x dp``): the same signature as the method's error at
  ``omega h``, so where a pre-step, post-step or PostNewton user function runs, the drift excuses
  nothing (tests/test_trust.py, a marker moved on a swinging pendulum at RK4's coarse step).
* with the rank-revealing solve (redundant constraints), every row that the solve drops must
  be implied by the rows it keeps: among the items taking part in the dependency, one item's
  residual above the tolerance and :data:`NOT_IMPLIED` times larger than every other's stops
  the run (its rows were not redundant).

Cost.  The check reads Exudyn's residuals once per output (about 2 us) and judges an item
only when its residual first exceeds the tolerance and again whenever it has doubled since
(a drifting run judges each item a few times, not at every output).  On the cheapest runs
(the heavy top, about 27 us per output period of ten steps) even that would be 10 % of the
run, so the check keeps to a time budget of :data:`BUDGET` of the solve's wall time, its own
set-up (about 0.2 ms: the items, the model's size, two residual evaluations) included: an
output is skipped while the check has used more (the outputs to skip are counted from the
run's rate so far, so a skipped output costs a decrement), so cheap runs are checked at every
few outputs, and the first and the last output always.  One judgement can cost more than a read,
so the budget is set below the 5 % a user would notice.  The Exudyn-evaluated path, whose steps cost
far more than a read, is checked at every output with no budget: its verdict weighs the growth
between judgements, and outputs skipped by the wall time made it follow the machine's load (a coarse
RK4 run of tests/test_evaluated_projection.py stopped under load only).

The tolerance is ``constraintCheck`` of ``exl.SolveDynamic``: ``True`` (the default)
``DEFAULT_RELATIVE`` times the model's size (the diagonal of the box around its nodes and
markers, at least 1 mm, read at the first output whose residual exceeds the smallest such
tolerance, 1e-8: most runs that hold their constraints never need it), a float in the rows' own units (m for positions), or
``False`` for no check.  1e-5 of the model's size is far above round-off and invisible in a
plot, so a residual below it needs no judgement.
"""
from __future__ import annotations

import time

import numpy as np
from numba import njit

from ..errors import ConstraintError, SimulationError
from ..mbs.linalg import max_abs
from ..userwarn import warn_user

#: default tolerance as a fraction of the model's size
DEFAULT_RELATIVE = 1e-5
#: the integrator's own residual of an item must be at least this fraction of Exudyn's to explain it
EXPLAINED = 0.1
#: a dropped row whose residual exceeds every other dependent item's this many times is not implied
NOT_IMPLIED = 100.0
#: the check's share of the run's wall time (module docstring, "Cost")
BUDGET = 0.02
#: an item is judged again when its residual has grown by this factor since it was last judged
REJUDGE = 2.0
#: on the evaluated path: the share of the residual's growth the velocity level must explain
UNEXPLAINED_SHARE = 0.5
#: ... and the rate of the unexplained growth, relative to the model's velocity scale, that stops
UNEXPLAINED_RATE = 1e-2
#: ... and its size against the velocity level's drift over the same steps (the method's own error)
METHOD_ERROR_RATIO = 10.0

VELOCITY_LEVEL_TYPES = ("JointRollingDisc", "JointRollingDisc2D")


def check_tolerance(constraintCheck):
    """Validate the keyword; returns None (off), True (default) or a positive float."""
    if constraintCheck is None or constraintCheck is False:
        return None
    if constraintCheck is True:
        return True
    from .settings import positive_float
    return positive_float(constraintCheck, ValueError(f"constraintCheck must be True, False or a positive "
                                                      f"tolerance, got {constraintCheck!r}"))


_NO_POSITION = set()    # marker types whose Position output Exudyn refuses


def model_size(mbs):
    """The diagonal of the box around the nodes' and markers' positions at the current state
    (at least 1 mm)."""
    import exudyn as exu
    pts = []
    sd = mbs.systemData
    P, C = exu.OutputVariableType.Position, exu.ConfigurationType.Current
    for kind, output, count in (("node", mbs.GetNodeOutput, sd.NumberOfNodes()),
                                ("marker", mbs.GetMarkerOutput, sd.NumberOfMarkers())):
        for i in range(count):
            # Exudyn raises for an item type without a position (a BodyMass marker), which
            # costs ten times a position: each type is asked once per process
            itemType = None
            if kind == "marker":
                itemType = mbs.GetMarker(i)["markerType"]
                if itemType in _NO_POSITION:
                    continue
            try:
                pts.append(np.asarray(output(i, P, configuration=C), float)[:3])
            except Exception:            # noqa: BLE001 - an item without a position
                if itemType is not None:
                    _NO_POSITION.add(itemType)
    P = np.array([p for p in pts if p.shape == (3,)]).reshape(-1, 3)
    P = P[np.isfinite(P).all(axis=1)]
    if not len(P):
        return 1.0
    return max(float(np.linalg.norm(P.max(axis=0) - P.min(axis=0))), 1e-3)


def _label(mbs, kind, i):
    if kind == "node":
        d = mbs.GetNode(i)
        return f"node {i} ('{d.get('name', '')}') Node{d['nodeType']}"
    d = mbs.GetObject(i)
    return f"object {i} ('{d.get('name', '')}') Object{d['objectType']}"


class ConstraintCheck:
    """Exudyn's position-level residuals at the outputs (module docstring).

    ``solver`` is the run's initialised ``MainSolverImplicitSecondOrder``.  ``items`` come out
    as ``(kind, index, AE rows)`` for every active position-level constraint with coordinates
    (an item's rows that constrain no coordinate, Exudyn's equations ``lambda = 0`` of free
    axes, are left out).  ``dependent``: the items of a redundant set (rank-revealing solve),
    None without one.  ``aeCoordinates``: AE unknowns that are coordinates (a sliding joint's
    sliding coordinate, bridge/evaluated_sliding.py), which the test for multipliers leaves
    alone: its rows are equations of them."""

    #: what holds a drift, said in its warning (both paths have the keyword)
    remedy = "stabilization='position' or a smaller step holds it"

    def __init__(self, mbs, solver, tolerance, dependent=None, aeCoordinates=()):
        self.mbs, self.solver = mbs, solver
        sd = mbs.systemData
        self.n, self.n1, self.m = int(sd.ODE2Size()), int(sd.ODE1Size()), int(sd.AEsize())
        self._size = None
        self._tol = None if tolerance is True else float(tolerance)
        # no residual below the smallest tolerance (the model's size at least 1 mm) is judged,
        # so the size is read only when a residual first exceeds it
        self._floor = DEFAULT_RELATIVE * 1e-3 if tolerance is True else self._tol
        active = self._rows_with_coordinates(np.asarray(aeCoordinates, np.int64))
        items, nodeRows = [], set()
        for n in range(sd.NumberOfNodes()):
            rows = [int(r) for r in sd.GetNodeLTGAE(n) if active[int(r)]]
            nodeRows.update(int(r) for r in sd.GetNodeLTGAE(n))
            if rows:
                items.append(("node", n, np.array(rows, np.int64)))
        self._switchable = set()          # objects with an activeConnector flag
        for o in range(sd.NumberOfObjects()):
            d = mbs.GetObject(o)
            if not d.get("activeConnector", True) or d.get("velocityLevel", False) is True \
                    or d["objectType"] in VELOCITY_LEVEL_TYPES:
                continue
            # a body's LTG AE lists its node's equations (an EP node's |p| = 1): the node's item
            rows = [int(r) for r in sd.GetObjectLTGAE(o) if active[int(r)] and int(r) not in nodeRows]
            if rows:
                items.append(("object", o, np.array(rows, np.int64)))
                if "activeConnector" in d:
                    self._switchable.add(o)
        self.items = items
        self.rows = np.concatenate([it[2] for it in items]) if items else np.zeros(0, np.int64)
        # item of each checked row, for the per-item maxima
        self._itemOfRow = np.concatenate([np.full(len(it[2]), k) for k, it in enumerate(items)]) \
            if items else np.zeros(0, np.int64)
        self.dependent = None if dependent is None else set(dependent)
        # the residual above which each item is judged (again): the tolerance, then REJUDGE x
        # the residual at its last judgement
        self._level = None
        self._starts = np.cumsum([0] + [len(it[2]) for it in items[:-1]]).astype(np.int64)
        self._t0 = None
        self.everyOutput = False
        self.spent = 0.0
        self.skipped = 0
        self._allRows = len(self.rows) == self.m and np.array_equal(self.rows, np.arange(self.m))
        self.warned = set()
        self.checks = 0
        self._o = self.n + self.n1

    @property
    def size(self):
        """The model's size (:func:`model_size`), read when first asked for."""
        if self._size is None:
            self._size = model_size(self.mbs)
        return self._size

    @property
    def tol(self):
        """The tolerance in the rows' units (module docstring)."""
        if self._tol is None:
            self._tol = DEFAULT_RELATIVE * self.size
        return self._tol

    def _rows_with_coordinates(self, aeCoordinates):
        """Which AE rows are equations of the coordinates: those whose residual does not move
        when every multiplier moves by 1 (Exudyn writes the equation ``lambda = 0`` of a free
        axis or an inactive connector as the multiplier itself).  Two residual evaluations,
        no Jacobian (a dense one would grow with the square of the coordinates)."""
        s, mbs = self.solver, self.mbs
        if self.m == 0:
            return np.zeros(0, bool)
        import exudyn as exu
        sd, cur, o = mbs.systemData, exu.ConfigurationType.Current, self.n + self.n1
        lam = np.array(sd.GetAECoordinates(configuration=cur), float)
        s.ComputeAlgebraicEquations(mbs, False)
        g0 = np.array(s.GetSystemResidual()[o:], float)
        bump = np.ones(self.m)
        bump[aeCoordinates] = 0.0
        sd.SetAECoordinates(lam + bump, configuration=cur)
        try:
            s.ComputeAlgebraicEquations(mbs, False)
            g1 = np.array(s.GetSystemResidual()[o:], float)
        finally:
            sd.SetAECoordinates(lam, configuration=cur)
        return g1 == g0

    def row_residuals(self, t):
        """g of the checked rows (a new array) at the state in mbs at time ``t``."""
        sd = self.mbs.systemData
        t0 = sd.GetTime()
        if t0 != t:
            sd.SetTime(t)
        self.solver.ComputeAlgebraicEquations(self.mbs, False)
        if t0 != t:
            sd.SetTime(t0)
        g = self.solver.GetSystemResidual()[self._o:]
        return g if self._allRows else g[self.rows]

    def residuals(self, t, g=None):
        """Per checked item, the largest |g| of its rows at the state in mbs at time ``t``."""
        if g is None:
            g = np.abs(self.row_residuals(t))
        return np.maximum.reduceat(g, self._starts)       # each item's rows are contiguous

    def start(self, since, setupFrom, everyOutput=False):
        """The run's time loop starts.  The budget is a share of the time since ``since`` (the
        solve's start), and the check's own set-up since ``setupFrom`` counts against it.
        ``everyOutput``: no budget, every output is checked (the evaluated path, whose verdicts
        weigh the growth since the last judgement: outputs skipped by the wall time would make a
        verdict depend on the machine's speed)."""
        self.everyOutput = everyOutput
        self._t0 = since
        self._loop = time.perf_counter()
        self.spent = self._loop - setupFrom
        self._seen = 0                    # outputs so far
        self._wait = 0                    # outputs to skip before the budget is asked again

    def due(self, last=False):
        """Whether an output is checked within the time budget (module docstring, "Cost");
        ``last``: the run's last output, always checked."""
        self._seen += 1
        if last or self._seen == 1 or self.everyOutput:   # a model made wrong shows at once: the first output always
            return True
        if self._wait:
            self._wait -= 1
            self.skipped += 1
            return False
        now = time.perf_counter()
        if self.spent <= BUDGET * (now - self._t0):
            return True
        # skip the outputs the run takes until its time reaches spent / BUDGET, at its rate so far
        perOutput = (now - self._loop) / self._seen
        self._wait = int((self.spent / BUDGET - (now - self._t0)) / perOutput) if perOutput > 0 else 0
        self.skipped += 1
        return False

    def timed_check(self, t, explain, prepare=None, projected=None):
        """:meth:`check` (after ``prepare()``, if given), its time counted in the budget."""
        now = time.perf_counter()
        if prepare is not None:
            prepare()
        self.check(t, explain, projected)
        self.spent += time.perf_counter() - now

    def at_output(self, t, explain, last=False, projected=None):
        """:meth:`timed_check` if it is :meth:`due`."""
        if self.due(last):
            self.timed_check(t, explain, projected=projected)

    def check(self, t, explain, projected=None):
        """Check the state in mbs at time ``t``.  ``explain(k, g)``: None if the integrator's
        own account explains item k's residual ``g``, else the sentence that says why not.
        ``projected``: per item, the sum of the projections' corrections that the integrator's
        account does not explain (a run projected after every step, bridge/evaluated_projection.py,
        whose residual stays at round-off); judged as a residual, without a drift warning (the
        projection holds the drift)."""
        if not self.items or not self.mbs.systemIsConsistent:
            return                        # items modified by a user function, until Exudyn assembles again
        self.checks += 1
        g = self.row_residuals(t)
        gmax = max_abs(g)
        if self.dependent is not None:
            self._velocity_redundancy(t)
        pmax = 0.0 if projected is None else max_abs(projected)       # (sums of |.|)
        if (gmax <= self._floor or gmax <= self.tol) and (pmax <= self._floor or pmax <= self.tol):
            return
        g = np.abs(g)
        if self._level is None:
            self._level = np.full(len(self.items), self.tol)
        G = self.residuals(t, g)
        if pmax > 0.0:
            byProjection = projected > G
            G = np.maximum(G, projected)
        for k in np.nonzero(G > self._level)[0]:
            self._level[k] = REJUDGE * G[k]
            kind, i, _ = self.items[k]
            if kind == "object" and i in self._switchable and not self.mbs.GetObjectParameter(i, "activeConnector"):
                continue                  # switched off during the run: its rows are lambda = 0
            why = explain(int(k), float(G[k]))
            projection = pmax > 0.0 and byProjection[k]
            if why is not None:
                what = (f"the projections onto them after each step add up to {G[k]:.3g}" if projection else
                        f"Exudyn's residual is {G[k]:.3g}")
                raise ConstraintError(
                    f"the constraints of {_label(self.mbs, kind, i)} do not hold at t = {t:.6g} s: {what} "
                    f"(tolerance {self.tol:.3g}), and {why}: exudyn_lie integrates another model than Exudyn "
                    f"defines. Please report this with the script; constraintCheck=False runs it anyway")
            if projection:
                continue
            self._redundancy(t, G, k)
            if (kind, i) not in self.warned:
                self.warned.add((kind, i))
                warn_user(f"exudyn_lie: the constraints of {_label(self.mbs, kind, i)} drift: Exudyn's residual is "
                          f"{G[k]:.3g} at t = {t:.6g} s (tolerance {self.tol:.3g}), and exudyn_lie's own account "
                          f"of the constraints explains it: the drift of index-1 integration without "
                          f"constraint stabilisation (reported once per item); {self.remedy}")

    def _velocity_redundancy(self, t):
        """The rule of :meth:`_redundancy` on Exudyn's velocity-level residuals (tolerance:
        the position tolerance per second)."""
        sd = self.mbs.systemData
        t0 = sd.GetTime()
        sd.SetTime(t)
        try:
            self.solver.ComputeAlgebraicEquations(self.mbs, True)
        except Exception:                  # noqa: BLE001 - an item without a velocity level
            return
        finally:
            sd.SetTime(t0)
        gv = np.abs(np.asarray(self.solver.GetSystemResidual())[self._o:][self.rows])
        if gv.max() <= self.tol:
            return
        Gv = np.zeros(len(self.items))
        np.maximum.at(Gv, self._itemOfRow, gv)
        for k in np.nonzero(Gv > self.tol)[0]:
            self._redundancy(t, Gv, k, "velocity-level ")

    def _redundancy(self, t, G, k, level=""):
        dep = self.dependent
        if dep is None or self.items[k][1] not in dep:
            return
        others = [G[j] for j in range(len(self.items)) if j != k and self.items[j][1] in dep]
        if others and G[k] > NOT_IMPLIED * max(max(others), 1e-300):
            kind, i, _ = self.items[k]
            raise ConstraintError(
                f"the constraints of {_label(self.mbs, kind, i)} were taken for redundant, but they do not hold at "
                f"t = {t:.6g} s: Exudyn's {level}residual is {G[k]:.3g}, the other constraints of the dependency at most "
                f"{max(others):.3g}, so they are not implied by them. The rank-revealing solve dropped rows that "
                f"were not redundant; please report this with the script")


class ConsistencyAccount:
    """The evaluated path's explanation (module docstring): per item, the summed growth of
    Exudyn's residual, the part of it the velocity-level equations do not explain, and the
    velocity level's own drift over the same intervals."""

    def __init__(self, check: ConstraintCheck, weighMethodError=True):
        self.c = check
        self.weighMethodError = weighMethodError       # False: a Python function runs between steps
        ni = len(check.items)
        self.growth, self.unexplained, self.velocityDrift = np.zeros(ni), np.zeros(ni), np.zeros(ni)
        self.t = self.g = self.gv = self.t0 = None
        self.size = max(1.0, check.size)
        self.vscale = 0.0

    def step(self, t, gv, vmax):
        """Account the interval from the last call to ``t``; ``gv`` the velocity-level
        residuals (all AE rows) the integrator uses, at the state in mbs; ``vmax`` its
        largest velocity coordinate."""
        if not self.c.mbs.systemIsConsistent:
            return
        c = self.c
        g = c.row_residuals(t)
        v = gv if c._allRows else np.asarray(gv)[c.rows]
        if not len(g) == len(v) == len(c._itemOfRow):
            # (the compiled loop below reads and writes by index without checks)
            raise SimulationError(f"the model's algebraic equations changed during the run ({len(c._itemOfRow)} "
                                  f"checked rows at the start, {len(g)} now: was mbs assembled again by a user "
                                  f"function?); exudyn_lie cannot follow that; solve with exudyn.SolveDynamic")
        self.vscale = max(self.vscale, float(vmax))
        if self.t0 is None:
            self.t0 = t
        if self.t is not None and t > self.t:
            account_interval(t - self.t, g, v, self.g, self.gv, c._itemOfRow, self.growth, self.unexplained,
                             self.velocityDrift)
        self.t, self.g, self.gv = t, g, v

    def explain(self, k, g):
        """None if the velocity level explains item k's growth, else why not."""
        span = self.t - self.t0 if self.t is not None else 0.0
        u, drift = self.unexplained[k], self.velocityDrift[k]
        if span > 0.0 and u > UNEXPLAINED_SHARE * self.growth[k] \
                and u / span > UNEXPLAINED_RATE * self.vscale * self.size \
                and (u > METHOD_ERROR_RATIO * drift or not self.weighMethodError):
            method = (f"; nor the method's error at this step: they drifted by {drift:.3g} over the same steps"
                      if self.weighMethodError else "")
            return (f"of its growth over the run ({self.growth[k]:.3g}), {u:.3g} is not what the velocity-level "
                    f"equations that exudyn_lie integrates predict (a moving offset or another time-dependent term "
                    f"that they leave out{method})")
        return None


@njit(cache=True)
def account_interval(dt, g, gv, g0, gv0, itemOfRow, growth, unexplained, velocityDrift):
    """Per item (``itemOfRow``), the residual's growth |g - g0| over an interval of ``dt``, the part
    of it the trapezoid of the velocity level, ``dt (gv0 + gv) / 2``, does not explain, and the
    velocity level's drift ``dt |gv - gv0|``, added up (:class:`ConsistencyAccount`: on the
    Exudyn-evaluated path it runs after every step, one call where numpy took seven)."""
    for i in range(g.shape[0]):
        dg = g[i] - g0[i]
        k = itemOfRow[i]
        growth[k] += abs(dg)
        unexplained[k] += abs(dg - 0.5 * dt * (gv0[i] + gv[i]))
        velocityDrift[k] += dt * abs(gv[i] - gv0[i])


def kernel_explanation(sim, jointRows):
    """The compiled path's explanation (module docstring): ``explain(k, g)`` at the kernel
    state of output row ``o`` of the output chunk ``ch`` (its rows ``ch.out.Ro, ro, Vo``) at time ``t``,
    set by ``at(ch, o, t)``; ``jointRows[k]`` the kernel rows of checked item k (None: no
    compiled rows to compare, e.g. a node's own equation)."""
    state = {}

    def at(ch, o, t):
        state["s"] = (ch, o, t)
        state.pop("h", None)

    def explain(k, g):
        rows = jointRows[k]
        if rows is None or not len(rows):
            return None
        if "h" not in state:
            ch, o, t = state["s"]
            state["h"] = np.abs(sim.RowResiduals(ch.out.Ro[o], ch.out.ro[o], ch.out.Vo[o], t)[0])
        own = float(state["h"][rows].max())
        if own >= EXPLAINED * g:
            return None
        return f"exudyn_lie's own rows of it are at {own:.3g}"

    return at, explain
