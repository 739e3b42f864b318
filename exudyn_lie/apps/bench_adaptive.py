"""Bench section ``adaptive``: adaptive Munthe-Kaas steps with error control on the group.

* **Tolerance proportionality**: the achieved error against tol = 1e-3 ... 1e-10 (atol =
  rtol = tol) of adaptive MK-DOPRI5 on the paper's models (max over the outputs every 0.1 s,
  in the solver's norm with atol = rtol = 1: :func:`state_error`, against MK-RK6 at
  h = 1e-4).
  Targets: fitted slope 1 +- 0.15, achieved/tol within [0.1, 10].
* **Work-precision**: CPU time of the integration against the achieved error, adaptive
  MK-DOPRI5 beside fixed-step MK-DOPRI5 and MK-RK4 (h halved from 1e-2).  The *best
  fixed-step run in hindsight* at the adaptive run's error is the fixed DOPRI5 curve
  interpolated (log-log) at that error.  Target: adaptive within 1.5x of it on every
  model, and faster on a model whose speed varies strongly in time: a ball falling onto a
  stiff one-sided spring (``bounce``: 0.45 s of free flight, 10 ms of contact).
* **Exudyn's adaptive solvers in the same run**: Exudyn's DOPRI5 and ODE23 (its error
  control, its defaults otherwise) on a free body, and exudyn_lie's DOPRI5 / ODE23 through
  ``SolveDynamic`` with the same settings; error at the end time.

Every number comes from :func:`run_section`; :func:`report_lines` writes them as they are,
targets met or not.
"""
import time
import warnings

import numpy as np

from .. import models
from ..mbs import Scene, Simulator

MODELS = ("heavy_top", "spherical_double_pendulum", "planar_four_bar", "free_body_offset_screw")
T_END = 1.0
OUT_DT = 0.1
REF_H = 1e-4
TOLS = tuple(10.0 ** -k for k in range(3, 11))
FIXED_H = tuple(1e-2 / 2 ** k for k in range(8))


# ------------------------------------------------------------------ models
BOUNCE = dict(m=1.0, k=1e5, g=9.81, z0=1.0, vx=0.3, wz=2.0)


def bounce_scene():
    """A ball (1 kg) dropped from 1 m onto a stiff one-sided spring (1e5 N/m) at z = 0:
    free flight 0.45 s, contact about pi sqrt(m/k) = 10 ms, then up again (no damping)."""
    B = BOUNCE
    sc = Scene(gravity=[0.0, 0.0, -B["g"]])
    sc.AddBody(B["m"], np.diag([0.004, 0.004, 0.004]), r0=[0.0, 0.0, B["z0"]], omega0=[0.0, 0.0, B["wz"]],
               vel0=[B["vx"], 0.0, 0.0], name="ball")
    k = B["k"]

    def contact(t, st):
        z = st.r[0, 2]
        F = np.zeros((1, 3))
        if z < 0.0:
            F[0, 2] = -k * z
        return F, np.zeros((1, 3))
    sc.AddPythonForce(contact, name="ground contact")
    return sc


def bounce_exact(times):
    """The bounce's exact solution at ``times`` (t <= the second impact): free fall from z0
    until t1 = sqrt(2 z0 / g) with speed v1 = g t1; in contact ``m z'' = -k z - m g``, i.e.
    ``z = -a + a cos(w s) - (v1 / w) sin(w s)`` (a = m g / k, w = sqrt(k / m), s = t - t1)
    until its next root s2 (bracketed and bisected to round-off), leaving with v1 upwards
    (energy); x = vx t, and the spin about z is constant (isotropic inertia): R = Rz(wz t).
    V is the SE3 body twist (omega, R^T rdot).  The reference of the bounce: a numerical one
    loses its order at the contact's kink (RK6 at h = 2.5e-5 vs 1.25e-5 differ by 1.3e-7)."""
    from types import SimpleNamespace
    B = BOUNCE
    g, m, k = B["g"], B["m"], B["k"]
    t1 = np.sqrt(2.0 * B["z0"] / g)
    v1 = g * t1
    a, w = m * g / k, np.sqrt(k / m)

    def zc(s):
        return -a + a * np.cos(w * s) - v1 / w * np.sin(w * s), -a * w * np.sin(w * s) - v1 * np.cos(w * s)
    lo, hi = 0.5 * np.pi / w, 1.5 * np.pi / w     # z < 0 at lo, z > 0 at hi (a << v1 / w)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if zc(mid)[0] < 0.0:
            lo = mid
        else:
            hi = mid
    t2 = t1 + 0.5 * (lo + hi)
    n = len(times)
    R, r, V = np.zeros((n, 1, 3, 3)), np.zeros((n, 1, 3)), np.zeros((n, 1, 6))
    for q, t in enumerate(times):
        if t <= t1:
            z, vz = B["z0"] - 0.5 * g * t * t, -g * t
        elif t <= t2:
            z, vz = zc(t - t1)
        else:
            s = t - t2
            z, vz = v1 * s - 0.5 * g * s * s, v1 - g * s
        if t > t2 + 2.0 * v1 / g:
            raise ValueError("bounce_exact: past the second impact")
        c, sn = np.cos(B["wz"] * t), np.sin(B["wz"] * t)
        R[q, 0] = [[c, -sn, 0.0], [sn, c, 0.0], [0.0, 0.0, 1.0]]
        r[q, 0] = [B["vx"] * t, 0.0, z]
        V[q, 0, :3] = [0.0, 0.0, B["wz"]]
        V[q, 0, 3:] = R[q, 0].T @ np.array([B["vx"], 0.0, vz])
    return SimpleNamespace(times=np.asarray(times, float), R=R, r=r, V=V)


def model_scene(name):
    """(scene, groups) of a paper model, read from its Exudyn model by the bridge."""
    from ..bridge import LieGroupSolver
    if name == "bounce":
        return bounce_scene(), "SE3"
    mbs, info = models.build(name, endTime=T_END)
    mbs.Assemble()
    sol = LieGroupSolver(mbs, method="DOPRI5", liegroup="SE3")
    return sol.scene, list(sol.groups)


def run(scene, groups, method, **kw):
    sim = Simulator(scene, method=method, liegroup=groups, projectInitial=True)
    return sim.Run(T_END, **kw)


def median_run(scene, groups, method, repeat, **kw):
    """The run with its CPU time the least of ``repeat`` runs: on a shared machine the
    other jobs only add time, so the minimum estimates the run's own cost (a median of 3
    still moved by 3x between sessions)."""
    best = None
    times = []
    for _ in range(repeat):
        res = run(scene, groups, method, **kw)
        times.append(res.cpuTime)
        best = res
    best.cpuTime = float(np.min(times))
    return best


def state_error(res, ref):
    """The largest of :func:`state_errors`."""
    return float(np.max(state_errors(res, ref)))


def state_errors(res, ref):
    """Error at each output time in the solver's own norm with
    atol = rtol = 1 (``integrators/control.py``: per body the rotation difference by the
    logarithm, the translation, omega and v, each divided by 1 + its size; RMS over the 12
    components): the error that tol is a bound for, comparable across models."""
    from ..groups import so3
    from ..integrators import control as C
    idx = [int(np.argmin(np.abs(ref.times - t))) for t in res.times]
    if np.max(np.abs(ref.times[idx] - res.times)) > 1e-9:
        raise ValueError("output times differ")
    tol1 = C.tolerances(1.0, 1.0)
    nb = res.R.shape[1]
    errs = np.zeros(len(idx))
    for k, j in enumerate(idx):
        dPhi = np.zeros((nb, 6))
        for i in range(nb):
            dPhi[i, :3] = so3.log(np.ascontiguousarray(ref.R[j, i].T @ res.R[k, i]))
            dPhi[i, 3:] = res.r[k, i] - ref.r[j, i]
        errs[k] = C.weighted_rms(dPhi, res.V[k] - ref.V[j], ref.r[j], res.r[k], ref.V[j], res.V[k], tol1)
    return errs


# ------------------------------------------------------------------ the section
def run_section(cfg, log):
    quick = getattr(cfg, "quick", False)
    repeat = 2 if quick else 3
    tols = TOLS[::2] if quick else TOLS
    out = dict(T=T_END, tols=list(tols), models={}, native={})
    names = MODELS[:2] if quick else MODELS
    for name in tuple(names) + ("bounce",):
        log(f"adaptive: {name}")
        scene, groups = model_scene(name)
        if name == "bounce":                             # exact: RK6 loses its order at the kink
            ref = bounce_exact(OUT_DT * np.arange(int(round(T_END / OUT_DT)) + 1))
        else:
            ref = run(scene, groups, "RK6", stepSize=REF_H, outputEvery=int(round(OUT_DT / REF_H)))
        m = dict(adaptive=[], fixed={"DOPRI5": [], "RK4": []})
        run(scene, groups, "DOPRI5", stepSize=OUT_DT, rtol=1e-3, atol=1e-3)     # warm-up (compilation)
        for tol in tols:
            try:
                res = median_run(scene, groups, "DOPRI5", repeat, stepSize=OUT_DT, rtol=tol, atol=tol)
                errs = state_errors(res, ref)
                m["adaptive"].append(dict(tol=tol, err=float(errs.max()), errFirst=float(errs[1]), cpu=res.cpuTime,
                                          steps=res.steps, rejected=res.rejectedSteps, rhs=res.rhsEvaluations))
            except Exception as e:                       # noqa: BLE001 - reported as it is
                m["adaptive"].append(dict(tol=tol, err=np.nan, cpu=np.nan, steps=0, rejected=0, rhs=0,
                                          message=str(e).splitlines()[0]))
        for method in ("DOPRI5", "RK4"):
            for h in FIXED_H:
                try:
                    res = median_run(scene, groups, method, repeat, stepSize=h, outputEvery=int(round(OUT_DT / h)))
                    m["fixed"][method].append(dict(h=h, err=state_error(res, ref), cpu=res.cpuTime,
                                                   steps=res.steps))
                except Exception as e:                   # noqa: BLE001
                    m["fixed"][method].append(dict(h=h, err=np.nan, cpu=np.nan, message=str(e).splitlines()[0]))
        summarize(m, tols)
        out["models"][name] = m
    log("adaptive: Exudyn's DOPRI5 / ODE23 against exudyn_lie's, free body")
    out["native"] = native_comparison(tols[1::2] if not quick else tols[:2])
    log("adaptive: Exudyn's adaptive generalized-alpha against exudyn_lie's DOPRI5, constrained models")
    out["ga"] = ga_comparison(GA_MODELS[:1] if quick else GA_MODELS, tols[::2] if not quick else tols[:2],
                              GA_STEPS[::2] if quick else GA_STEPS)
    return out


def summarize(m, tols):
    a = [r for r in m["adaptive"] if np.isfinite(r["err"]) and r["err"] > 0]
    if len(a) >= 2:
        lt, le = np.log([r["tol"] for r in a]), np.log([r["err"] for r in a])
        m["slope"] = float(np.polyfit(lt, le, 1)[0])
        ratios = [r["err"] / r["tol"] for r in a]
        m["ratioMin"], m["ratioMax"] = float(min(ratios)), float(max(ratios))
        first = [r["errFirst"] / r["tol"] for r in a]     # after the first output period only
        m["firstMin"], m["firstMax"] = float(min(first)), float(max(first))
    fx = sorted([r for r in m["fixed"]["DOPRI5"] if np.isfinite(r["err"]) and r["err"] > 0], key=lambda r: r["err"])
    worst = None
    for r in a:
        t_fix = interp_cost(fx, r["err"])
        r["fixedCpu"] = t_fix
        r["ratio"] = r["cpu"] / t_fix if t_fix and np.isfinite(t_fix) else np.nan
        if np.isfinite(r["ratio"]):
            worst = r["ratio"] if worst is None else max(worst, r["ratio"])
    m["worstRatio"] = worst
    inside = [r["ratio"] for r in a if np.isfinite(r.get("ratio", np.nan))]
    m["medianRatio"] = float(np.median(inside)) if inside else None


def interp_cost(fixed, err):
    """CPU time of the fixed-step curve at ``err`` (log-log interpolation between the two
    runs around it); NaN outside the curve's range."""
    if len(fixed) < 2:
        return np.nan
    e = np.log([r["err"] for r in fixed])
    c = np.log([r["cpu"] for r in fixed])
    x = np.log(err)
    if x < e.min() or x > e.max():
        return np.nan
    order = np.argsort(e)
    return float(np.exp(np.interp(x, e[order], c[order])))


# ------------------------------------------------------------------ Exudyn's adaptive solvers
def native_comparison(tols):
    """Exudyn's DOPRI5 and ODE23 (RotVecLG node; error control always on, as its source
    reads) against exudyn_lie's through SolveDynamic with the same settings, on the paper's
    free body with offset screw motion; error at the end time against MK-RK6 h = 1e-4."""
    import exudyn as exu

    import exudyn_lie as exl
    from ..models._common import _ensure_sensors, body_states_from_sensors
    name = "free_body_offset_screw"
    scene, groups = model_scene(name)
    ref = run(scene, groups, "RK6", stepSize=REF_H, outputEvery=int(round(OUT_DT / REF_H)))
    out = []
    for solver in ("DOPRI5", "ODE23"):
        for who in ("Exudyn", "exudyn_lie"):
            for tol in tols:
                mbs, info = models.build(name, endTime=T_END)
                sens = _ensure_sensors(info)
                mbs.Assemble()
                ss = exu.SimulationSettings()
                ti = ss.timeIntegration
                ti.endTime, ti.numberOfSteps = T_END, 10           # h_max = 0.1 s
                ti.absoluteTolerance = ti.relativeTolerance = tol
                ti.verboseMode = 0
                ss.solution.file.write = False
                ss.solution.sensors.writePeriod = OUT_DT
                tic = time.perf_counter()
                msg = ""
                try:
                    if who == "Exudyn":
                        mbs.SolveDynamic(ss, solverType=getattr(exu.DynamicSolverType, solver))
                        steps = mbs.sys["dynamicSolver"].it.currentStepIndex
                    else:
                        exl.SolveDynamic(mbs, ss, method=solver, liegroup="SE3", showProgress=False,
                                         stabilization=None)
                        steps = mbs.sys["lieGroupSolver"].timing["accepted"]
                except Exception as e:                      # noqa: BLE001
                    steps, msg = 0, str(e).splitlines()[0]
                wall = time.perf_counter() - tic
                data = [[mbs.GetSensorStoredData(x) for x in s4] for s4 in sens]
                nt = min(len(d[0]) for d in data)
                R, r, om, ve = body_states_from_sensors(data, nt)
                tEnd = data[0][0][nt - 1, 0]
                err = np.nan
                if abs(tEnd - T_END) < 1e-9:
                    err = max(float(np.max(np.abs(R[-1] - ref.R[-1]))), float(np.max(np.abs(r[-1] - ref.r[-1]))),
                              float(np.max(np.abs(om[-1] - ref.omega[-1]))),
                              float(np.max(np.abs(ve[-1] - ref.vel[-1]))))
                out.append(dict(solver=solver, who=who, tol=tol, err=err, steps=int(steps), wall=wall,
                                message=msg))
    return out


GA_MODELS = ("heavy_top", "spherical_double_pendulum", "planar_four_bar")
GA_STEPS = (100, 200, 400, 800, 1600, 3200)


def _sensor_end_error(mbs, sens, ref):
    """Largest absolute difference of R, r, omega (body), v (world) at the end time between
    the node sensors and the reference run (NaN if the run did not reach the end)."""
    from ..models._common import body_states_from_sensors
    data = [[mbs.GetSensorStoredData(x) for x in s4] for s4 in sens]
    nt = min(len(d[0]) for d in data)
    R, r, om, ve = body_states_from_sensors(data, nt)
    if abs(data[0][0][nt - 1, 0] - T_END) > 1e-9:
        return np.nan
    return max(float(np.max(np.abs(R[-1] - ref.R[-1]))), float(np.max(np.abs(r[-1] - ref.r[-1]))),
               float(np.max(np.abs(om[-1] - ref.omega[-1]))), float(np.max(np.abs(ve[-1] - ref.vel[-1]))))


def ga_comparison(names, tols, steps=GA_STEPS):
    """Exudyn's generalized-alpha with its adaptive step (``adaptiveStep = True``, Exudyn's
    default: the step is reduced after a failed Newton iteration and recovers; there is no
    error estimate) at numberOfSteps = ``steps``, against exudyn_lie's adaptive DOPRI5
    through ``SolveDynamic`` at ``tols`` (numberOfSteps = 10: h_max = 0.1 s), on the
    constrained paper models.  Error: the largest absolute difference of R, r, omega, v at
    the end time against MK-RK6 at h = 1e-4 (node sensors, the same for both); CPU: the
    wall time of the SolveDynamic call (least of 3; both through Exudyn's time loop)."""
    import exudyn as exu

    import exudyn_lie as exl
    from ..models._common import _ensure_sensors
    out = {}
    for name in names:
        scene, groups = model_scene(name)
        ref = run(scene, groups, "RK6", stepSize=REF_H, outputEvery=int(round(OUT_DT / REF_H)))
        rows = []
        # the first of each kind is a warm-up (the bridge's first solve of a model resolves
        # its compiled entry points), not reported
        for who, values in (("Exudyn GA", (steps[-1],) + tuple(steps)), ("exudyn_lie DOPRI5", (tols[0],) + tuple(tols))):
            for q, v in enumerate(values):
                walls, err, msg, nst = [], np.nan, "", 0
                for _ in range(3):
                    mbs, info = models.build(name, endTime=T_END)
                    sens = _ensure_sensors(info)
                    mbs.Assemble()
                    ss = exu.SimulationSettings()
                    ti = ss.timeIntegration
                    ti.endTime = T_END
                    ti.verboseMode = 0
                    ss.solution.file.write = False
                    ss.solution.sensors.writePeriod = OUT_DT
                    ss.displayComputationTime = False
                    if info.redundantConstraints:
                        ss.linearSolverType = exu.LinearSolverType.EigenDense
                        ss.linearSolverSettings.ignoreSingularJacobian = True
                    tic = time.perf_counter()
                    try:
                        if who == "Exudyn GA":
                            ti.numberOfSteps = int(v)
                            ti.adaptiveStep = True
                            mbs.SolveDynamic(ss, solverType=exu.DynamicSolverType.GeneralizedAlpha)
                            nst = int(mbs.sys["dynamicSolver"].it.currentStepIndex)
                        else:
                            ti.numberOfSteps = 10
                            ti.absoluteTolerance = ti.relativeTolerance = v
                            with warnings.catch_warnings():
                                warnings.simplefilter("ignore")      # the redundant loop, announced above
                                exl.SolveDynamic(mbs, ss, method="DOPRI5", liegroup="SE3", showProgress=False,
                                                 stabilization=None)
                            nst = int(mbs.sys["lieGroupSolver"].timing["accepted"])
                    except Exception as e:                   # noqa: BLE001 - reported as it is
                        msg = str(e).splitlines()[0] if str(e) else type(e).__name__
                    walls.append(time.perf_counter() - tic)
                    err = _sensor_end_error(mbs, sens, ref)
                    if msg:
                        break
                if q > 0:
                    rows.append(dict(who=who, value=v, err=err, cpu=float(np.min(walls)), steps=nst, message=msg))
        out[name] = rows
    return out


# ------------------------------------------------------------------ report and plots
def _f(x, fmt=".2g"):
    return "-" if x is None or not np.isfinite(x) else format(x, fmt)


def report_lines(a, figures=()):
    if not a:
        return []
    L = ["## Adaptive steps (error control on the group)", ""]
    L.append(f"Adaptive MK-DOPRI5 (atol = rtol = tol, PI controller, HINIT, FSAL, dense output at the outputs "
             f"every {OUT_DT:g} s), T = {a['T']:g} s, SE3.  Error: the largest over the outputs, in the solver's norm "
             f"with atol = rtol = 1 (each quantity divided by 1 + its size, RMS per body), against MK-RK6 at h = {REF_H:g} (bounce: its exact solution).  CPU: the integration "
             f"(least of 3 runs).  'vs best fixed': adaptive CPU / fixed-step MK-DOPRI5's CPU interpolated at the "
             f"same error (the best fixed step in hindsight); '-' where the fixed curve does not reach that error.")
    L.append("")
    L.append("| model | slope (target 1 +- 0.15) | error/tol (target [0.1, 10]) | error/tol at t = "
             f"{OUT_DT:g} s | vs best fixed: worst / median (target <= 1.5) |")
    L.append("|---|---|---|---|---|")
    for name, m in a["models"].items():
        L.append(f"| {name} | {_f(m.get('slope'), '.3f')} | {_f(m.get('ratioMin'))} - {_f(m.get('ratioMax'))} | "
                 f"{_f(m.get('firstMin'))} - {_f(m.get('firstMax'))} | "
                 f"{_f(m.get('worstRatio'), '.2f')} / {_f(m.get('medianRatio'), '.2f')} |")
    L.append("")
    for name, m in a["models"].items():
        L.append(f"**{name}**: tol, error, accepted / rejected steps, rhs evaluations, CPU [ms], vs best fixed")
        L.append("")
        L.append("| tol | error | steps | rejected | rhs | CPU ms | vs best fixed |")
        L.append("|---|---|---|---|---|---|---|")
        for r in m["adaptive"]:
            L.append(f"| {r['tol']:.0e} | {_f(r['err'])} | {r['steps']} | {r['rejected']} | {r['rhs']} | "
                     f"{_f(1e3 * r['cpu'], '.3g')} | {_f(r.get('ratio', np.nan), '.2f')} |")
        L.append("")
    if a.get("native"):
        L.append("Exudyn's adaptive explicit solvers against exudyn_lie's through `SolveDynamic` with the same "
                 "settings (free_body_offset_screw, numberOfSteps = 10, i.e. h_max = 0.1 s; error: the largest absolute "
                 "difference of R, r, omega, v at the end time):")
        L.append("")
        L.append("| solver | tol | Exudyn error | Exudyn steps | exudyn_lie error | exudyn_lie steps |")
        L.append("|---|---|---|---|---|---|")
        rows = {}
        for r in a["native"]:
            rows.setdefault((r["solver"], r["tol"]), {})[r["who"]] = r
        for (s, tol), d in rows.items():
            e, x = d.get("Exudyn", {}), d.get("exudyn_lie", {})
            L.append(f"| {s} | {tol:.0e} | {_f(e.get('err', np.nan))}{' (' + e['message'] + ')' if e.get('message') else ''} "
                     f"| {e.get('steps', '-')} | {_f(x.get('err', np.nan))} | {x.get('steps', '-')} |")
        L.append("")
    if a.get("ga"):
        L.append("Exudyn's generalized-alpha with its adaptive step (`adaptiveStep = True`, its default: the step is "
                 "reduced after a failed Newton iteration, no error estimate) at numberOfSteps = N, against exudyn_lie's "
                 "adaptive DOPRI5 through `SolveDynamic` at tol (numberOfSteps = 10); the same sensors, error: the "
                 "largest absolute difference of R, r, omega, v at the end time against MK-RK6 at h = 1e-4; CPU: wall "
                 "time of the SolveDynamic call (least of 3):")
        L.append("")
        L.append("| model | solver | N or tol | steps | error | CPU ms |")
        L.append("|---|---|---|---|---|---|")
        for name, rows in a["ga"].items():
            for r in rows:
                v = f"N = {r['value']}" if r["who"].startswith("Exudyn") else f"tol = {r['value']:.0e}"
                L.append(f"| {name} | {r['who']} | {v} | {r['steps']} | {_f(r['err'])}"
                         f"{' (' + r['message'] + ')' if r.get('message') else ''} | {_f(1e3 * r['cpu'], '.3g')} |")
        L.append("")
    for f in figures:
        L.append(f"![adaptive]({f})")
        L.append("")
    return L


def plot(a, figdir):
    import os

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    os.makedirs(figdir, exist_ok=True)
    names = list(a["models"])
    paths = []
    fig, ax = plt.subplots(figsize=(6.5, 5))
    for name in names:
        m = a["models"][name]
        t = [r["tol"] for r in m["adaptive"] if np.isfinite(r["err"])]
        e = [r["err"] for r in m["adaptive"] if np.isfinite(r["err"])]
        ax.loglog(t, e, "o-", label=name)
    tt = np.array(a["tols"])
    ax.loglog(tt, tt, "k--", lw=1, label="error = tol")
    ax.fill_between(tt, 0.1 * tt, 10 * tt, color="0.9", label="[0.1, 10] tol")
    ax.set_xlabel("tol (atol = rtol)")
    ax.set_ylabel("achieved error")
    ax.set_title("adaptive MK-DOPRI5: tolerance proportionality")
    ax.legend(fontsize=7)
    ax.grid(True, which="both", alpha=0.3)
    p = os.path.join(figdir, "adaptive_tol.png")
    fig.tight_layout()
    fig.savefig(p, dpi=160)
    plt.close(fig)
    paths.append(p)
    n = len(names)
    cols = 3
    rows = (n + cols - 1) // cols
    fig, axs = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.6 * rows), squeeze=False)
    for k, name in enumerate(names):
        ax = axs[k // cols][k % cols]
        m = a["models"][name]
        for lab, rs, sty in (("adaptive DOPRI5", m["adaptive"], "o-"), ("fixed DOPRI5", m["fixed"]["DOPRI5"], "s--"),
                             ("fixed RK4", m["fixed"]["RK4"], "^:")):
            pts = [(r["err"], r["cpu"]) for r in rs if np.isfinite(r["err"]) and np.isfinite(r["cpu"])]
            if pts:
                e, c = zip(*sorted(pts))
                ax.loglog(e, c, sty, label=lab, ms=4)
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("error")
        ax.set_ylabel("CPU time [s]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6)
    for k in range(n, rows * cols):
        axs[k // cols][k % cols].axis("off")
    fig.tight_layout()
    p = os.path.join(figdir, "adaptive_wp.png")
    fig.savefig(p, dpi=160)
    plt.close(fig)
    paths.append(p)
    if a.get("ga"):
        ga = a["ga"]
        fig, axs = plt.subplots(1, len(ga), figsize=(4.2 * len(ga), 3.6), squeeze=False)
        for k, (name, rows) in enumerate(ga.items()):
            ax = axs[0][k]
            for who, sty in (("Exudyn GA", "s--"), ("exudyn_lie DOPRI5", "o-")):
                pts = sorted((r["err"], r["cpu"]) for r in rows if r["who"] == who and np.isfinite(r["err"]))
                if pts:
                    e, c = zip(*pts)
                    ax.loglog(e, c, sty, ms=4, label=("Exudyn adaptive gen.-alpha (N steps)" if who == "Exudyn GA"
                                                      else "exudyn_lie adaptive DOPRI5 (tol)"))
            ax.set_title(name, fontsize=9)
            ax.set_xlabel("error at the end time (max abs)")
            ax.set_ylabel("CPU time of SolveDynamic [s]")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=6)
        fig.tight_layout()
        p = os.path.join(figdir, "adaptive_ga.png")
        fig.savefig(p, dpi=160)
        plt.close(fig)
        paths.append(p)
    return paths


def main():
    """``python -m exudyn_lie.apps.bench_adaptive [--quick] [--out DIR]``: this section alone."""
    import argparse
    import json
    import os
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", default="bench_out")
    args = ap.parse_args()

    class Cfg:
        quick = args.quick
    a = run_section(Cfg, lambda s: print(s, flush=True))
    figs = plot(a, os.path.join(args.out, "bench_figures"))
    rel = [os.path.relpath(f, args.out) for f in figs]
    text = "\n".join(report_lines(a, rel))
    with open(os.path.join(args.out, "bench_adaptive.md"), "w") as f:
        f.write(text + "\n")
    with open(os.path.join(args.out, "bench_adaptive.json"), "w") as f:
        json.dump(a, f, indent=1, default=float)
    print(text)


if __name__ == "__main__":
    main()
