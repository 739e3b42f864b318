"""The figures of the paper's comparison: one figure per model, every solver on the same axes.

``<model>.png``: one row per measure (the position and rotation rows of every joint, or
for a free body the COM drift and the orientation error eps_r, then the energy drift),
one column per step size; each panel shows MK-RK4 on SE(3), MK-RK4 on SO(3)xR3 and
Exudyn's own solvers for that model.  The panels of a row share their y axis, so the
columns compare at a glance.

Reading aids (log axes cannot show zero):

* the sample at t = 0 is left out (the initial state is exact for every solver);
* a curve that is exactly 0 over the whole run is not drawn; the panel says
  "exactly 0: ..." for it;
* samples exactly 0 inside a curve are ticks on the lower edge of the panel, in the
  curve's colour;
* a run that stopped (Exudyn's Newton iteration failed) ends with an x, and the panel
  says where it stopped; a run without any data has no legend entry.

Saved at 150 dpi.
"""
from __future__ import annotations

import os

import numpy as np

DPI = 150
MAXPOINTS = 1500
STYLE = {        # label, colour, line style, width
    "SE3": ("MK-RK4 on $SE(3)$", "tab:blue", "-", 1.4),
    "SO3xR3": (r"MK-RK4 on $SO(3)\times\mathbb{R}^3$", "tab:orange", "--", 1.4),
    "GeneralizedAlpha": ("Exudyn generalized-alpha", "black", "-", 0.8),
    "TrapezoidalIndex2": ("Exudyn trapezoidal index 2", "tab:green", ":", 1.6),
    "RK44": ("Exudyn RK44", "tab:purple", "-.", 1.1),
    "DOPRI5": ("Exudyn DOPRI5", "tab:brown", ":", 1.6),
}
SHORT = {"SE3": "$SE(3)$", "SO3xR3": r"$SO(3)\times\mathbb{R}^3$", "GeneralizedAlpha": "gen.-alpha",
         "TrapezoidalIndex2": "trapezoidal", "RK44": "RK44", "DOPRI5": "DOPRI5"}


def _mpl():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def envelope(t, y, n=MAXPOINTS):
    """Block maxima (keeps the peaks a log plot should show) down to about n points."""
    t = np.asarray(t)
    y = np.asarray(y, float)
    if len(t) <= n:
        return t, y
    k = int(np.ceil(len(t) / n))
    m = len(t) // k
    tt = t[: m * k].reshape(m, k)[:, -1]
    yy = np.nanmax(y[: m * k].reshape(m, k), axis=1)
    return tt, yy


def _rows(info):
    """(label of the y axis, panel title, getter) of every measure of a model."""
    rows = []
    for j in info.joints:
        rows.append(("position violation [m]", f"{j.name} ({j.kind}), position rows",
                     (lambda rd, j=j: rd.position.get(j.name))))
        if any(j.lockedAxes[3:]):
            rows.append(("rotation violation [-]", f"{j.name} ({j.kind}), rotation rows",
                         (lambda rd, j=j: rd.rotation.get(j.name))))
    if info.exact is not None:
        rows.append((r"$|x_c - x_{c,\mathrm{exact}}|$ [m]", "COM drift from the exact solution",
                     lambda rd: rd.comDrift))
        rows.append((r"$\varepsilon_r = \|\log(R_\mathrm{exact}^T R)\|$ [rad]", "orientation error",
                     lambda rd: rd.orientation))
    rows.append((r"$|E(t) - E(0)|$ [J]", "energy drift", lambda rd: np.abs(rd.energy_drift())))
    return rows


def _series(rd, y):
    """(t, y) for a log plot: t > 0 only, finite values (None if there is no sample)."""
    if y is None or rd is None or len(rd.times) == 0:
        return None
    t = np.asarray(rd.times, float)
    y = np.asarray(y, float)
    n = min(len(t), len(y))
    t, y = t[:n], y[:n]
    keep = (t > 0) & np.isfinite(y)
    if not keep.any():
        return None
    return t[keep], y[keep]


def _names(rows):
    """'rotation rows of joint1, joint2; ...' for rows given by their panel titles."""
    groups = {}
    for _, title, _ in rows:
        what, _, rest = title.rpartition(", ")
        groups.setdefault(rest, []).append(what.split(" (")[0] if what else title)
    return "; ".join(f"{rest} of {', '.join(names)}" if names != [rest] else rest for rest, names in groups.items())


def _all_zero(runs, solvers, dts, get):
    """True if every solver's curve of this measure is exactly 0 (or absent) at every step."""
    for s in solvers:
        for dt in dts:
            ser = _series(runs.get((s, dt)), get(runs[(s, dt)]) if (s, dt) in runs else None)
            if ser is not None and np.any(ser[1] != 0.0):
                return False
    return True


def _stopped(runs, solvers, dt):
    out = []
    for s in solvers:
        rd = runs.get((s, dt))
        if rd is not None and not rd.ok:
            t_end = float(rd.times[-1]) if len(rd.times) else 0.0
            out.append(f"{SHORT[s]} at t = {t_end:.3g} s" if t_end > 0 else f"{SHORT[s]} in its first step")
    return out


def _panel(ax, runs, solvers, dt, get, handles):
    """Draw one panel; returns the note for its title (curves exactly 0 over the run)."""
    from matplotlib.transforms import blended_transform_factory
    zero_all = []
    edge = blended_transform_factory(ax.transData, ax.transAxes)
    for s in solvers:
        rd = runs.get((s, dt))
        if rd is None:
            continue
        label, color, ls, lw = STYLE[s]
        ser = _series(rd, get(rd))
        if ser is None:
            continue
        t, y = ser
        if np.all(y == 0.0):
            zero_all.append(SHORT[s])
            continue
        tt, yy = envelope(t, y)
        pos = yy > 0
        (line,) = ax.semilogy(tt, np.where(pos, yy, np.nan), color=color, ls=ls, lw=lw, label=label)
        handles.setdefault(s, line)
        if not pos.all():                               # exact zeros inside the curve: ticks on the edge
            ax.plot(tt[~pos], np.full((~pos).sum(), 0.0), "|", color=color, ms=6, transform=edge, clip_on=False)
        if not rd.ok:
            ax.semilogy([tt[-1]], [yy[-1] if yy[-1] > 0 else np.nan], "x", color=color, ms=7, mew=1.5)
    return ["exactly 0: " + ", ".join(zero_all)] if zero_all else []


def plot_model(info, runs, dts, outdir, solvers=("SE3", "SO3xR3"), natives=()):
    """The figure of one model (``<name>.png``); ``runs``: {(solver, dt): RunData}.
    Returns the list of paths written."""
    plt = _mpl()
    from matplotlib.ticker import LogLocator, NullFormatter
    order = [s for s in tuple(solvers) + tuple(natives) if s in STYLE]
    rows, zero_rows = [], []
    for row in _rows(info):                     # rows exactly 0 everywhere: named, not drawn
        (zero_rows if _all_zero(runs, order, dts, row[2]) else rows).append(row)
    nr, nc = len(rows), len(dts)
    h = 2.4 * nr + 1.7 + 0.2 * bool(zero_rows)
    fig, axes = plt.subplots(nr, nc, figsize=(4.6 * nc + 0.9, h), squeeze=False, sharex=True, sharey="row")
    handles = {}
    for ri, (ylabel, title, get) in enumerate(rows):
        for ci, dt in enumerate(dts):
            ax = axes[ri, ci]
            notes = _panel(ax, runs, order, dt, get, handles)
            if ri == 0:                         # where runs stopped: once per column
                stop = _stopped(runs, order, dt)
                notes += ["stopped: " + ", ".join(stop)] if stop else []
            ax.set_title(f"{title}, $\\Delta t$ = {dt:g} s" + "".join("\n" + n for n in notes), fontsize=10)
            ax.grid(True, which="major", alpha=0.3)
            ax.tick_params(labelsize=9)
            if ci == 0:
                ax.set_ylabel(ylabel, fontsize=10)
            if ri == nr - 1:
                ax.set_xlabel("$t$ [s]", fontsize=10)
        row = axes[ri, 0]
        if any(a.get_lines() for a in axes[ri]):
            row.yaxis.set_major_locator(LogLocator(base=10, numticks=7))
            row.yaxis.set_minor_formatter(NullFormatter())
        else:                                           # nothing to draw on a log axis: every curve is 0
            for a in axes[ri]:
                a.set_yscale("linear")
                a.set_ylim(-1, 1)
                a.set_yticks([0])
    title = f"{info.title}: MK-RK4 on $SE(3)$ and $SO(3)\\times\\mathbb{{R}}^3$ and Exudyn's own solvers"
    if zero_rows:
        title += "\nexactly 0 for every solver and step size (not drawn): " + _names(zero_rows)
    fig.suptitle(title, fontsize=12, y=1 - 0.1 / h)
    ticks = any(line.get_marker() == "|" for a in axes.flat for line in a.get_lines())
    crosses = any(line.get_marker() == "x" for a in axes.flat for line in a.get_lines())
    if ticks or crosses:          # the reading aids, explained in the figure itself
        fig.text(0.5, 0.08 / h, "   ".join(
            (["|  on a panel's lower edge: a sample exactly 0 (a log axis cannot show 0)"] if ticks else [])
            + (["x: the run stopped there"] if crosses else [])), ha="center", va="bottom", fontsize=9,
            color="0.25")
    legend = [handles[s] for s in order if s in handles]
    fig.legend(legend, [STYLE[s][0] for s in order if s in handles], loc="upper center", ncol=len(legend),
               fontsize=10, frameon=False, bbox_to_anchor=(0.5, 1 - (0.45 + 0.2 * bool(zero_rows)) / h))
    fig.subplots_adjust(left=0.9 / (4.6 * nc + 0.9), right=0.985, bottom=0.75 / h, top=1 - (1.55 + 0.2 * bool(zero_rows)) / h,
                        hspace=0.42 + 0.12 * (nr > 4), wspace=0.08)
    path = os.path.join(outdir, f"{info.name}.png")
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return [path]
