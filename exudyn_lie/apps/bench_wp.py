"""Work-precision analysis for the bench: final-state errors against a reference,
time-to-accuracy by log-log interpolation, competitor ratios, plots.

Error of a run (``final_error``): the largest over all bodies of

* ``|r - r_ref|`` (m), the position of the body frame (= Exudyn node) origin, and
* ``|log(R_ref^T R)|`` (rad), the angle of the rotation error,

at the end time.  Both are O(1)-scaled for the paper's mechanisms (links of 0.1-0.5 m),
so one number serves as the accuracy of the configuration.

Time to reach an accuracy ``eps`` (``time_to_accuracy``): on the Pareto front of a
competitor's runs (no other run is both faster and more accurate), ``log t`` is
interpolated linearly in ``log err`` between the two front points that bracket
``eps``.  Below the most accurate run the accuracy is *not reached* (NaN); above the
least accurate run the cheapest run's time is an upper bound (flagged).
"""
from __future__ import annotations

import math

import numpy as np


def rotation_angle(Ra, Rb):
    """Angle of ``Ra^T Rb`` (accurate for small angles: atan2 of the skew part)."""
    D = Ra.T @ Rb
    s = 0.5 * math.sqrt((D[2, 1] - D[1, 2]) ** 2 + (D[0, 2] - D[2, 0]) ** 2 + (D[1, 0] - D[0, 1]) ** 2)
    c = 0.5 * (D[0, 0] + D[1, 1] + D[2, 2] - 1.0)
    return math.atan2(s, c)


def final_error(res, ref):
    """Configuration error of a run against the reference (see module docstring)."""
    e = 0.0
    for i in range(len(ref["r"])):
        e = max(e, float(np.linalg.norm(np.asarray(res["r"][i]) - ref["r"][i])),
                rotation_angle(np.asarray(ref["R"][i]), np.asarray(res["R"][i])))
    return e


def velocity_error(res, ref):
    """Largest velocity error (body-fixed angular velocity in rad/s, frame origin
    velocity in m/s) - reported in the raw data, not used for the diagrams."""
    e = 0.0
    for i in range(len(ref["r"])):
        e = max(e, float(np.linalg.norm(np.asarray(res["omega"][i]) - ref["omega"][i])),
                float(np.linalg.norm(np.asarray(res["vel"][i]) - ref["vel"][i])))
    return e


def pareto(points):
    """Pareto front of (err, time) points: sorted by decreasing error, increasing time."""
    pts = sorted((float(e), float(t)) for e, t in points
                 if np.isfinite(e) and np.isfinite(t) and e > 0 and t > 0)
    front = []
    best_t = np.inf
    for e, t in pts:                  # increasing error: keep if faster than all more accurate
        if t < best_t:
            front.append((e, t))
            best_t = t
    return front[::-1]                # decreasing error, increasing time


def time_to_accuracy(points, eps):
    """(time, flag) to reach error ``eps``: flag ``'interp'`` (bracketed),
    ``'upper'`` (all runs are more accurate than eps: the cheapest run's time, an upper
    bound) or ``'not reached'`` (time NaN)."""
    front = pareto(points)
    if not front:
        return np.nan, "not reached"
    errs = [e for e, _ in front]
    if eps >= errs[0]:
        return front[0][1], "upper"
    if eps < errs[-1]:
        return np.nan, "not reached"
    for (e0, t0), (e1, t1) in zip(front[:-1], front[1:]):
        if e1 <= eps <= e0:
            if e0 == e1:
                return t1, "interp"
            w = (math.log(eps) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + w * (math.log(t1) - math.log(t0))), "interp"
    return np.nan, "not reached"


def extrapolate_time(points, eps, max_decades=3.0):
    """Time to reach ``eps`` below the most accurate run, extrapolated in log-log along
    the two most accurate Pareto points (NaN if not converging or too far)."""
    front = pareto(points)
    if len(front) < 2 or eps >= front[-1][0]:
        return np.nan
    (e1, t1), (e2, t2) = front[-2], front[-1]
    if not (e2 < e1 and t2 > t1):
        return np.nan
    slope = math.log(t2 / t1) / math.log(e1 / e2)     # 1/order for a fixed-step method
    if not (0.0 < slope <= 2.0) or math.log10(e2 / eps) > max_decades:
        return np.nan
    return t2 * (e2 / eps) ** slope


def observed_order(points_h):
    """Least-squares slope of log err against log h over (h, err) points."""
    pts = [(h, e) for h, e in points_h if np.isfinite(e) and e > 0 and np.isfinite(h) and h > 0]
    if len(pts) < 2:
        return np.nan
    x = np.log([p[0] for p in pts])
    y = np.log([p[1] for p in pts])
    return float(np.polyfit(x, y, 1)[0])


NATIVE_ORDER = {"GeneralizedAlpha": 2, "GeneralizedAlpha-mN": 2, "TrapezoidalIndex2": 2, "RK44": 4, "RK67": 6}


def native_reference_check(runs):
    """Independent check of the reference (an exudyn_lie run) by Exudyn's own solvers.

    ``runs``: ``{solver: [(h, err), ...]}``, the fixed-step native runs of one model with
    their final errors against the reference.  If the reference (or the model the
    package reads) differed from Exudyn's solution by ``delta``, the native errors would
    level off at ``delta`` and the observed order between the two finest runs would
    fall towards 0.  Returns, for the native solver with the smallest error, a dict
    ``solver, h, err, order`` (over its two finest runs) and ``nominal`` (its order),
    with ``converges`` = the errors still fall at >= half the nominal order; ``None``
    when no native solver has two finished runs."""
    best = None
    for solver, pts in runs.items():
        pts = sorted((h, e) for h, e in pts if np.isfinite(e) and e > 0 and np.isfinite(h) and h > 0)
        if len(pts) < 2 or solver not in NATIVE_ORDER:
            continue
        (h1, e1), (h2, e2) = pts[0], pts[1]          # finest, next finest
        order = math.log(e2 / e1) / math.log(h2 / h1) if h2 > h1 else np.nan
        cand = dict(solver=solver, h=h1, err=e1, order=order, nominal=NATIVE_ORDER[solver],
                    converges=bool(np.isfinite(order) and order >= 0.5 * NATIVE_ORDER[solver]))
        if best is None or e1 < best["err"]:
            best = cand
    return best


def fit_exponent(N, t):
    """Exponent p of ``t ~ N^p`` (least squares in log-log)."""
    N = np.asarray(N, float)
    t = np.asarray(t, float)
    ok = np.isfinite(t) & (t > 0)
    if ok.sum() < 2:
        return np.nan
    return float(np.polyfit(np.log(N[ok]), np.log(t[ok]), 1)[0])


# --------------------------------------------------------------------------- plots
_STYLE = {"SE3": "-", "SO3xR3": "--", "auto": ":"}
_MARK = {"RK4": "o", "DOPRI5": "s", "RK6": "^"}
_NATIVE_MARK = {"GeneralizedAlpha": "v", "GeneralizedAlpha-mN": "<", "TrapezoidalIndex2": ">",
                "RK44": "D", "RK67": "P", "DOPRI5": "X"}


def plot_work_precision(path, title, curves, eps_band=(1e-8, 1e-4)):
    """``curves``: list of (label, kind, solver, group, [(err, time)...]).  Log-log
    CPU time against final error; exudyn_lie solid/dashed, Exudyn native grey."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9.8, 5.4))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    ci = 0
    for label, kind, solver, group, pts in curves:
        pts = sorted((e, t) for e, t in pts if np.isfinite(e) and e > 0 and np.isfinite(t))
        if not pts:
            continue
        e, t = zip(*pts)
        if kind == "exl":
            ax.loglog(e, t, _STYLE.get(group, "-"), marker=_MARK.get(solver, "o"), color=colors[ci % len(colors)],
                      label=label, ms=4, lw=1.3)
            ci += 1
        else:
            ax.loglog(e, t, "-.", marker=_NATIVE_MARK.get(solver, "x"), color="0.25" if "Alpha" in solver
                      else ("0.55" if "Trap" in solver or solver == "RK67" else "0.75"),
                      label=f"Exudyn {label}", ms=5, lw=1.3)
    ax.axvspan(eps_band[0], eps_band[1], color="0.92", zorder=0, label="accuracy range of the speed targets")
    ax.set_xlabel("final configuration error (max over bodies of |dr| [m], |dR| [rad])")
    ax.set_ylabel("CPU time of the time loop [s] (median)")
    ax.set_title(title, fontsize=10)
    ax.invert_xaxis()
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=1, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)


def plot_scaling(path, series, title):
    """``series``: list of (label, N list, per-step time list, exponent)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 4.6))
    for label, N, t, p in series:
        N = np.asarray(N, float)
        t = np.asarray(t, float)
        ok = np.isfinite(t)
        if not ok.any():
            continue
        ax.loglog(N[ok], t[ok] * 1e6, "o-", label=f"{label} (fit N^{p:.2f})" if np.isfinite(p) else label, ms=4)
    ax.set_xlabel("number of bodies N")
    ax.set_ylabel("CPU time per step [us] (median)")
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
