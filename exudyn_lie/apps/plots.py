"""Figures like the paper's: SE(3) beside SO(3)xR3, one curve per step size.

* ``<model>_joints.png``   - position (and rotation) violation of every joint over time;
* ``<model>_com.png``      - COM drift from the exact solution (free bodies);
* ``<model>_orientation.png`` - eps_r = ||log(R^T R_num)|| against the exact rotation;
* ``<model>_energy.png``   - drift of the total energy |E(t) - E(0)|;
* ``<model>_native.png``   - the same violation / drift measures for Exudyn's solvers.

Log scales with a floor of 1e-17 (exact zeros are drawn on the floor).
"""
from __future__ import annotations

import os

import numpy as np

FLOOR = 1e-17
MAXPOINTS = 1500
COLORS = {1e-2: "tab:red", 1e-3: "tab:blue", 1e-4: "tab:green"}


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


def _curve(ax, rd, y, label):
    """One curve; a failed run is marked in the legend (and its last value with an x),
    also when it has no data to draw."""
    c = COLORS.get(rd.stepSize)
    if not rd.ok:
        t_end = float(rd.times[-1]) if len(rd.times) else 0.0
        label += " (failed at t=0, no data)" if t_end <= 0.0 else f" (failed at t={t_end:.3g} s)"
    if y is None or len(y) == 0 or len(rd.times) <= 1:
        if not rd.ok:
            ax.semilogy([], [], color=c, lw=1.0, ls="--", label=label)
        return
    t, yy = envelope(rd.times, y)
    ax.semilogy(t, np.maximum(yy, FLOOR), color=c, lw=1.0, label=label)
    if not rd.ok:
        ax.semilogy([t[-1]], [max(float(yy[-1]), FLOOR) if np.isfinite(yy[-1]) else FLOOR], "x", color=c, ms=6)


def _grid(plt, nrows, ncols, title):
    h = 2.4 * nrows + 1.0
    fig, axes = plt.subplots(nrows, ncols, figsize=(5.2 * ncols, h), squeeze=False, sharex=True)
    fig.suptitle(title, fontsize=10, y=1 - 0.12 / h)
    # fixed margins: tight_layout costs seconds per figure on log axes
    fig.subplots_adjust(left=0.09, right=0.98, bottom=0.6 / h, top=1 - 0.75 / h, hspace=0.4, wspace=0.2)
    return fig, axes


def _finish(fig, axes, path):
    from matplotlib.ticker import LogLocator, NullLocator
    for ax in axes.ravel():
        ax.grid(True, which="major", alpha=0.3)
        if ax.lines:
            ax.yaxis.set_major_locator(LogLocator(base=10, numticks=6))
            ax.yaxis.set_minor_locator(NullLocator())
            ax.legend(fontsize=7, loc="best")
        ax.tick_params(labelsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("t [s]", fontsize=8)
    fig.savefig(path, dpi=80)
    import matplotlib.pyplot as plt
    plt.close(fig)
    return path


def _rows(info):
    rows = []
    for j in info.joints:
        rows.append((j, "position"))
        if any(j.lockedAxes[3:]):
            rows.append((j, "rotation"))
    return rows


def plot_model(info, runs, dts, outdir, solvers=("SE3", "SO3xR3"), natives=()):
    """All figures of one model; ``runs``: {(solver, dt): RunData}. Returns the paths.
    ``solvers=()`` skips the MK-RK4 figures, ``natives=()`` the native one."""
    plt = _mpl()
    paths = []
    name = info.name

    def panel_set(cols, fname, title, measures):
        fig, axes = _grid(plt, len(measures), len(cols), title)
        for ci, sol in enumerate(cols):
            for ri, (ylabel, get) in enumerate(measures):
                ax = axes[ri, ci]
                for dt in dts:
                    rd = runs.get((sol, dt))
                    if rd is None:
                        continue
                    _curve(ax, rd, get(rd), f"dt={dt:g}")
                lab = f"MK-RK4 {sol}" if sol in ("SE3", "SO3xR3") else sol
                ax.set_title(f"{lab}: {ylabel}", fontsize=9)
        paths.append(_finish(fig, axes, os.path.join(outdir, fname)))

    if solvers and info.joints:
        meas = []
        for j, what in _rows(info):
            unit = "[m]" if what == "position" else "[-]"
            meas.append((f"{j.name} ({j.kind}) {what} violation {unit}",
                         (lambda rd, j=j, w=what: (rd.position if w == "position" else rd.rotation).get(j.name))))
        panel_set(solvers, f"{name}_joints.png", f"{info.title}: constraint violation per joint", meas)
    if solvers and info.exact is not None:
        panel_set(solvers, f"{name}_com.png", f"{info.title}: COM drift from the exact solution",
                  [("|x_c - x_c,exact| [m]", lambda rd: rd.comDrift)])
        panel_set(solvers, f"{name}_orientation.png", f"{info.title}: orientation error",
                  [("eps_r = ||log(R^T R_num)|| [rad]", lambda rd: rd.orientation)])
    if solvers:
        panel_set(solvers, f"{name}_energy.png", f"{info.title}: energy drift (E(0) = {_E0(runs):.6g} J)",
                  [("|E(t) - E(0)| [J]", lambda rd: np.abs(rd.energy_drift()))])
    if natives:
        if info.joints:
            meas = [(f"{j.name} ({j.kind}) position violation [m]",
                     (lambda rd, j=j: rd.position.get(j.name))) for j in info.joints]
        else:
            meas = [("|x_c - x_c,exact| [m]", lambda rd: rd.comDrift),
                    ("eps_r [rad]", lambda rd: rd.orientation)]
        meas.append(("|E(t) - E(0)| [J]", lambda rd: np.abs(rd.energy_drift())))
        panel_set(natives, f"{name}_native.png", f"{info.title}: Exudyn's native solvers", meas)
    return paths


def _E0(runs):
    for rd in runs.values():
        if rd.energy is not None and len(rd.energy):
            return float(rd.energy[0])
    return float("nan")
