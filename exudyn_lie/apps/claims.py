"""Judge the paper's claims on measured runs.

Every :class:`exudyn_lie.models.Claim` names a target (joint or body), a measure (position /
rotation rows of a joint, COM drift, orientation error, energy drift) and a kind:

* ``exact_SE3`` / ``exact_SO3xR3``: that group keeps the measure at round-off level for
  every step size, and at dt = 1e-2 the other group is at least ``SEPARATION`` (1e3)
  times worse;
* ``exact_both``: both groups at round-off level;
* ``SE3_exact``: SE(3) at round-off level, nothing claimed for SO(3)xR3;
* ``same_order``: at the largest step neither group is exact, and their maxima stay
  within ``SAME_ORDER_DECADES`` (1.5 decades) at every step size where both are above
  round-off (at smaller steps both may reach round-off together); the exact cases are
  separated by >= 3 decades;
* ``SO3xR3_better`` / ``SE3_better``: that group's maximum is smaller at every step
  size; ``SE3_better_large_step``: at the largest step only;
* ``identical_rotation``: the SE3 and SO3xR3 runs rotate the body identically
  (``||log(R_SE3^T R_SO3xR3)||`` at round-off level);
* ``identical_drift``: the kinetic-energy drifts agree within 10 % (or both round-off).

Round-off level ("exact"), :func:`exact_tol`: ``1e-12 L`` at the step sizes the issue
names (dt >= 1e-3), with L the length scale of the measure (1 m, or the distance a free
body travels) - the paper's "computation precision", no allowance.  Below dt = 1e-3
(the full run's dt = 1e-4, up to N = 1e5 steps) ``max(1e-12, 1e-15 N) L``: the update
keeps a subgroup only in exact arithmetic; each step commits a few unit round-offs
(u = 2^-53 = 1.1e-16) of the positions, which nothing corrects (no stabilisation), so
they accumulate - at most linearly in N; 1e-15 per step is about 9 u.  The report states
this bound and the largest per-step growth actually observed under it
(:func:`roundoff_growth`).

Each claim is filed under the result of the paper it checks (:func:`category_of`):
corollary 1 for the motion constraints of a single body - in particular every lower
pair joint to the ground (lemma 1 then holds trivially with G1 = {I}, as the paper
notes) -, lemma 1 for an exact joint between two moving bodies, corollary 3 for the
'same order' claims, and the free-body, energy and orientation observations.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, Tuple

import numpy as np

from ..models.geometry import GROUND, so3_log_angle

EXACT_TOL = 1e-12            # the bound (per metre of L) at dt >= STRICT_DT, no allowance
EXACT_PER_STEP = 1e-15       # round-off allowance per step (per metre of L), only below STRICT_DT
STRICT_DT = 1e-3             # at this step size and above: EXACT_TOL, no allowance
UNIT_ROUNDOFF = 2.0 ** -53
SEPARATION = 1e3
SAME_ORDER_DECADES = 1.5
LARGE_STEP = 1e-2

CATEGORIES = {
    "corollary 1": "Corollary 1: a body whose motion is restricted to a subgroup of its c-space group keeps "
                   "its motion constraints exactly (lower pair joints to the ground; lemma 1 holds trivially "
                   "there, with G1 = {I})",
    "lemma 1": "Lemma 1: two moving bodies in subgroups whose relative motion is a subgroup keep the joint "
               "between them exactly",
    "corollary 3": "Corollary 3: otherwise SE(3) and SO(3)xR3 achieve the same order of accuracy",
    "free body": "Free bodies: with the frame at the COM the motion is a subgroup of SO(3)xR3 (the only "
                 "practical case favouring it); off the COM SO(3)xR3 is still the more accurate for a screw motion",
    "energy": "Energy observations",
    "orientation": "Orientation constraints of the planar four-bar / rotation updates of free bodies",
}
EXACT_KINDS = ("exact_SE3", "exact_SO3xR3", "exact_both", "SE3_exact")


def _results_named(ref):
    """The paper's results a claim's ``ref`` invokes (a result followed by 'fails' is
    not invoked)."""
    ref = ref.lower()
    out = set()
    for r in ("corollary 1", "lemma 1", "corollary 3"):
        k = ref.find(r)
        if k >= 0 and not ref[k + len(r):].lstrip().startswith("fails"):
            out.add(r)
    return out


def category_of(claim, info=None):
    """The result of the paper a claim checks (a key of :data:`CATEGORIES`).

    * energy measures -> 'energy'; 'same order' claims -> 'corollary 3';
    * free bodies (no joint): an exactness claim citing corollary 1 -> 'corollary 1'
      (the COM of the off-COM rotation, kept by SE(3)); identical rotation updates ->
      'orientation'; the rest -> 'free body';
    * joints: exactness claims citing neither corollary 1 nor lemma 1 (the planar
      four-bar's orientation rows) -> 'orientation'; a joint to the ground -> 'corollary
      1' (the joint is the body's motion constraint; lemma 1 with G1 = {I} is the same
      statement); a joint between two moving bodies -> 'lemma 1' if the claim cites it,
      else 'corollary 1' (the Cardan shaft's joint 2, exact because body 2 is confined
      to rotations about the cross centre).

    ``info`` (the model) tells ground joints apart; without it a joint claim citing
    lemma 1 is filed under lemma 1."""
    named = _results_named(claim.ref)
    if claim.measure == "energy":
        return "energy"
    if claim.kind == "same_order" or "corollary 3" in named:
        return "corollary 3"
    joint = None
    if info is not None and claim.measure in ("position", "rotation"):
        joint = next((j for j in info.joints if j.name == claim.target), None)
    if claim.measure in ("com", "orientation"):
        if claim.kind in ("exact_SE3", "SE3_exact") and "corollary 1" in named:
            return "corollary 1"
        if claim.kind == "identical_rotation":
            return "orientation"
        return "free body"
    if not named & {"corollary 1", "lemma 1"}:
        return "orientation"
    if joint is not None and GROUND in (joint.bodyA, joint.bodyB):
        return "corollary 1"
    return "lemma 1" if "lemma 1" in named else "corollary 1"


@dataclass
class Verdict:
    model: str
    claim: object
    verdict: str                  # 'confirmed', 'not confirmed', 'incomplete'
    evidence: str
    values: Dict[Tuple[str, float], float] = field(default_factory=dict)
    category: str = ""              # key of CATEGORIES (category_of)
    tols: Dict[float, float] = field(default_factory=dict)    # exactness bound per step size
    steps: Dict[float, int] = field(default_factory=dict)     # number of steps per step size
    length: float = 1.0             # L of the bound


def series(rd, claim):
    """The time series a claim is judged on (None if the run does not have it)."""
    m = claim.measure
    if m == "position":
        return rd.position.get(claim.target)
    if m == "rotation":
        return rd.rotation.get(claim.target)
    if m == "com":
        return rd.comDrift
    if m == "orientation":
        return rd.orientation
    if m == "energy":
        d = rd.energy_drift()
        return np.abs(d)
    raise ValueError(f"unknown measure {m!r}")


def run_max(rd, claim):
    s = series(rd, claim)
    if s is None or len(s) == 0:
        return float("nan")
    return float(np.nanmax(s))


def length_scale(info, claim):
    """L of the round-off tolerance: the largest COM distance from the origin along the
    exact path for free bodies (the travelled distance), else 1 m."""
    if claim.measure == "com" and info.exact is not None:
        t = np.linspace(0.0, info.endTime, 11)
        return max(1.0, float(np.max(np.linalg.norm(info.exact(t)["com"], axis=-1))))
    return 1.0


def n_steps(info, dt):
    return int(round(info.endTime / dt))


def exact_tol(info, claim, dt):
    """The round-off bound of an exactness claim at step size ``dt``: ``1e-12 L`` for
    dt >= 1e-3 (no allowance), ``max(1e-12, 1e-15 N) L`` below (round-off
    accumulated over N uncorrected steps, at most linearly; see the module docstring)."""
    L = length_scale(info, claim)
    if dt >= STRICT_DT * (1.0 - 1e-9):
        return EXACT_TOL * L
    return max(EXACT_TOL, EXACT_PER_STEP * n_steps(info, dt)) * L


def exact_bound_text(dts):
    """The bound of :func:`exact_tol` in words, for the step sizes of a run."""
    strict = [d for d in dts if d >= STRICT_DT * (1.0 - 1e-9)]
    loose = [d for d in dts if d < STRICT_DT * (1.0 - 1e-9)]
    t = []
    if strict:
        t.append(f"<= {EXACT_TOL:g} L at dt = {', '.join(f'{d:g}' for d in strict)} (no allowance)")
    if loose:
        t.append(f"<= max({EXACT_TOL:g}, {EXACT_PER_STEP:g} N) L at dt = {', '.join(f'{d:g}' for d in loose)} "
                 f"(N steps: round-off of about {EXACT_PER_STEP / UNIT_ROUNDOFF:.0f} u per step, u = 2^-53, "
                 f"accumulated linearly)")
    return "; ".join(t)


def exact_groups(kind):
    """The group(s) an exactness claim declares exact."""
    return {"exact_SE3": ("SE3",), "SE3_exact": ("SE3",), "exact_SO3xR3": ("SO3xR3",),
            "exact_both": ("SE3", "SO3xR3")}.get(kind, ())


def roundoff_growth(verdicts):
    """Per exactness claim, group and step size where the bound has the per-step
    allowance: (value / (N u L), verdict, group, dt, value, bound), largest first - the
    round-off growth per step actually observed, in units of u."""
    out = []
    for v in verdicts:
        for g in exact_groups(v.claim.kind):
            for dt, tol in v.tols.items():
                n = v.steps.get(dt, 0)
                if dt >= STRICT_DT * (1.0 - 1e-9) or not n:
                    continue
                x = v.values.get((g, dt), float("nan"))
                if np.isfinite(x):
                    out.append((x / (n * UNIT_ROUNDOFF * v.length), v, g, dt, x, tol))
    out.sort(key=lambda e: -e[0])
    return out


def fmt(x):
    if x is None or not np.isfinite(x):
        return "n/a"
    if x == 0:
        return "0"
    return f"{x:.2e}"


def judge(info, claim, runs, dts):
    """``runs``: {(group, dt): RunData} for 'SE3' and 'SO3xR3'."""
    vals = {}
    okall = True
    for g in ("SE3", "SO3xR3"):
        for dt in dts:
            rd = runs.get((g, dt))
            if rd is None or not rd.ok:
                okall = False
                vals[(g, dt)] = float("nan") if rd is None else run_max(rd, claim)
            else:
                vals[(g, dt)] = run_max(rd, claim)
    kind = claim.kind
    tols = {dt: exact_tol(info, claim, dt) for dt in dts}
    big = max(dts)
    line = "; ".join(f"dt={dt:g}: SE3 {fmt(vals[('SE3', dt)])}, SO3xR3 {fmt(vals[('SO3xR3', dt)])}" for dt in dts)
    ok = None
    note = ""

    def exact(g):
        return all(vals[(g, dt)] <= tols[dt] for dt in dts)

    def ratio(a, b):
        a, b = vals[(a, big)], vals[(b, big)]
        return a / max(b, 1e-300)

    if kind in ("exact_SE3", "exact_SO3xR3"):
        g = kind.split("_", 1)[1]
        other = "SO3xR3" if g == "SE3" else "SE3"
        r = ratio(other, g)
        ok = exact(g) and r >= SEPARATION
        note = (f"{g} at round-off (bound {', '.join(f'{fmt(tols[d])} at dt={d:g}' for d in dts)}): "
                f"{'yes' if exact(g) else 'NO'}; "
                f"{other}/{g} at dt={big:g}: {fmt(r)} (need >= {SEPARATION:g})")
        p = observed_orders(vals, dts, tols)
        if other in p:
            note += f"; observed order of {other}: {p[other]:.1f}"
    elif kind == "exact_both":
        ok = exact("SE3") and exact("SO3xR3")
        note = (f"both at round-off level (bound {', '.join(f'{fmt(tols[d])} at dt={d:g}' for d in dts)}): "
                f"{'yes' if ok else 'NO'}")
    elif kind == "SE3_exact":
        ok = exact("SE3")
        note = (f"SE3 at round-off level (bound {', '.join(f'{fmt(tols[d])} at dt={d:g}' for d in dts)}): "
                f"{'yes' if ok else 'NO'} (SO3xR3 not claimed)")
    elif kind == "same_order":
        # compare where both are above round-off; where one is at round-off, the other must be too
        resolved = [dt for dt in dts if vals[("SE3", dt)] > tols[dt] and vals[("SO3xR3", dt)] > tols[dt]]
        both_roundoff = [dt for dt in dts if vals[("SE3", dt)] <= tols[dt] and vals[("SO3xR3", dt)] <= tols[dt]]
        dec = [abs(np.log10(vals[("SE3", dt)] / vals[("SO3xR3", dt)])) for dt in resolved]
        consistent = len(resolved) + len(both_roundoff) == len(dts)
        ok = big in resolved and consistent and max(dec) <= SAME_ORDER_DECADES
        note = (f"max |log10(SE3/SO3xR3)| = {max(dec) if dec else float('nan'):.2f} decades over the step sizes where "
                f"both are above round-off ({', '.join(f'{d:g}' for d in resolved) or 'none'}; need <= "
                f"{SAME_ORDER_DECADES})")
        if both_roundoff:
            note += f"; both at round-off at dt = {', '.join(f'{d:g}' for d in both_roundoff)}"
        if not consistent:
            note += "; at some step size only one group is at round-off: NOT the same order"
        p = observed_orders(vals, dts, tols)
        if p:
            note += "; observed order " + ", ".join(f"{g} {x:.1f}" for g, x in p.items())
    elif kind in ("SO3xR3_better", "SE3_better"):
        g = kind.split("_")[0]
        other = "SO3xR3" if g == "SE3" else "SE3"
        ok = all(vals[(g, dt)] < vals[(other, dt)] for dt in dts)
        note = f"{g} smaller at every step size: {'yes' if ok else 'NO'}"
    elif kind == "SE3_better_large_step":
        ok = vals[("SE3", big)] < vals[("SO3xR3", big)]
        note = f"SE3 smaller at dt={big:g}: {'yes' if ok else 'NO'} (ratio SO3xR3/SE3 {fmt(ratio('SO3xR3', 'SE3'))})"
    elif kind == "identical_rotation":
        diffs = {}
        for dt in dts:
            a, b = runs.get(("SE3", dt)), runs.get(("SO3xR3", dt))
            if a is None or b is None or a.R is None or b.R is None or not (a.ok and b.ok):
                diffs[dt] = float("nan")
                continue
            diffs[dt] = float(np.max(so3_log_angle(np.einsum("nbji,nbjk->nbik", a.R, b.R))))
        ok = all(np.isfinite(d) and d <= 1e-9 for d in diffs.values())
        note = ("max ||log(R_SE3^T R_SO3xR3)|| = " + ", ".join(f"{fmt(d)} (dt={dt:g})" for dt, d in diffs.items())
                + " (need <= 1e-9 rad)")
        for dt, d in diffs.items():
            vals[("diff", dt)] = d
    elif kind == "identical_drift":
        res = []
        for dt in dts:
            a, b = vals[("SE3", dt)], vals[("SO3xR3", dt)]
            floor = 1e-12 * abs(info.computed.get("T0", info.computed.get("E0", 1.0)))
            same = (a <= floor and b <= floor) or abs(a - b) <= 0.1 * max(a, b)
            res.append(same)
        ok = all(res)
        note = "drifts within 10 % (or both round-off) at every step size: " + ("yes" if ok else "NO")
    else:
        raise ValueError(f"unknown claim kind {kind!r}")
    if not okall:
        verdict = "incomplete"
        note += "; some runs failed (maxima up to the failure)"
        if ok is False:
            verdict = "not confirmed"
    else:
        verdict = "confirmed" if ok else "not confirmed"
    return Verdict(info.name, claim, verdict, f"{line}. {note}", vals, category_of(claim, info), tols,
                   {dt: n_steps(info, dt) for dt in dts}, length_scale(info, claim))


def observed_orders(vals, dts, tols=None):
    """Convergence order between the two largest step sizes, where both errors are above
    round-off and decrease."""
    dts = sorted(dts, reverse=True)
    if len(dts) < 2:
        return {}
    out = {}
    for g in ("SE3", "SO3xR3"):
        a, b = vals.get((g, dts[0])), vals.get((g, dts[1]))
        floor = tols[dts[1]] if tols else 0.0
        if a and b and np.isfinite(a) and np.isfinite(b) and b > floor and a > b:
            out[g] = np.log10(a / b) / np.log10(dts[0] / dts[1])
    return out


def judge_model(info, runs, dts):
    return [judge(info, c, runs, dts) for c in info.claims]


def heavy_top_energy_verdict(info, rd):
    """The paper prints E(0) = 5000.69 J; the run starts at 2500.69 J with 1/2 c |p0-r|^2.

    ``rd``: a run of the heavy top (its energy at t = 0 is used)."""
    E0 = float(rd.energy[0])
    E0b = float(rd.energy[0] + rd.energyParts[0, 2])     # spring energy c |p0 - r|^2
    paper = info.paper["E0"]
    match_half = abs(E0 - paper) < 0.01
    match_nohalf = abs(E0b - paper) < 0.01
    return dict(computed=E0, computed_without_half=E0b, paper=paper,
                verdict=("confirmed" if match_half else
                         ("explained: paper's value = c|p0 - r|^2 (the 1/2 missing)" if match_nohalf
                          else "not confirmed")))
