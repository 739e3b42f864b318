"""MuJoCo as a peer in ``python -m exudyn_lie bench --sections mujoco``.

Since 4.0.0 MuJoCo's RK4 applies the Munthe-Kaas correction on ball and free joints: a ball
joint's quaternion is advanced by ``q exp(h k)`` with the stage slopes mapped by ``dexp^-1``
(eq. MK1 of the paper with the right-trivialised ``dexp``).  For one body on a ball joint to
the ground (the heavy top) MuJoCo's relative joint coordinate *is* the body's absolute
rotation, and a rotation about a fixed point is the SO(3) subgroup of SE(3) that MK-RK4 on
SE(3) integrates (corollary 1): the two codes compute the same discrete solution, to
round-off.  That makes MuJoCo the cleanest speed peer there is: the same algorithm in two
implementations.  On the spherical double pendulum MuJoCo's second ball joint is a relative
coordinate, so the discrete solutions differ (different formulations, same order 4); there
the models are checked to converge to the same solution.

What is built (:func:`mjcf_from_info`): the MJCF of a model of :mod:`models`, read from the
same :class:`models.ModelInfo` data the package integrates (masses, inertia about the COM,
COM offsets, initial poses and velocities, joint anchors, springs, gravity):

* every body a MuJoCo ``<body>`` whose frame is the Exudyn node frame (so ``xpos`` /
  ``xmat`` are the states the package reports), ``<inertial>`` with ``pos`` = the COM and
  ``fullinertia`` = the inertia about the COM; only trees of spherical joints rooted at the
  ground are accepted (MuJoCo closes loops with soft equality constraints: not the same
  model), anything else raises ``ValueError`` naming the joint;
* a ``type="ball"`` joint at the joint anchor on the child (``damping = armature = 0``);
  the initial ``qvel`` is the child's angular velocity relative to its parent, in the
  child frame (MuJoCo's ball-joint convention: ``q <- q exp(h qvel)``);
* a spring ``c (p0 - r)`` (the heavy top, eq. of the heavy-top section) as a ``spatial``
  tendon between a site at ``p0`` and a site at the body point, ``stiffness = c``,
  ``springlength = referenceLength`` (0): MuJoCo's tendon spring force is
  ``-c (L - L0) dL/dq`` evaluated with the rest of the passive forces in every stage
  (``mj_passive`` inside each ``mj_forward`` of the RK4 step), i.e. the generalised force
  of the same conservative force ``c (p0 - r)`` at every stage state, as the package
  evaluates it.  A Python callback (``mjcb_passive``) would put Python into every MuJoCo
  stage, and ``qfrc_applied`` is frozen over a step (not the same algorithm);
* ``integrator="RK4"``, ``timestep = h``, gravity of the model, contacts disabled (the
  models have no geoms; ball joints are coordinates, so MuJoCo has no constraint rows).

Timing (:func:`time_interleaved`; CPU time of the process, ``time.process_time``): the package's compiled time loop
``Simulator.Advance(n, h)`` (the same part of the work the other bench sections time)
against ``mujoco.mj_step(m, d, nstep=n)`` (MuJoCo's own C loop: no Python per step);
also a Python loop of ``mj_step(m, d)`` (its per-call overhead is reported separately)
and ``mujoco.rollout.rollout`` (C loop that also records the state of every step).
The competitors alternate inside every repetition (the machine is shared and noisy), the
median is reported.  Everything here is optional: without MuJoCo the section prints one
line and is skipped (``pip install .[bench]``).
"""
from __future__ import annotations

import time
import warnings

import numpy as np

MIN_VERSION = (4, 0, 0)
MODELS = {"heavytop": "heavy_top", "doublependulum": "spherical_double_pendulum"}
# exudyn_lie's MK-RK4 step at least this many times cheaper than MuJoCo's RK4 step
TARGET_RATIO = {"heavytop": 3.0, "doublependulum": 2.0}
PERSTEP_H = (1e-3, 1e-4)
TITLES = {"heavytop": "heavy top: 1 body, ball joint + spring", "doublependulum": "spherical double pendulum: 2 ball joints"}
# heavy top, 8 s (the paper's span) at h = 1e-3: the two codes must agree to round-off.  The
# discretisation error of either run is ~1e-7 there (printed beside), so any other algorithm
# misses this bound by orders of magnitude; the observed difference is ~1e-13.
AGREE_T, AGREE_H, AGREE_TOL = 8.0, 1e-3, 1e-12
EPS_LEVELS = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8)
WP_H0 = 1e-2
# CPU time of this process, not wall time: the machine is shared (2 cores, several jobs), and a
# run shorter than the scheduler's time slice would otherwise look faster per step than a
# longer one of the same work (measured: 2.9 -> 7.8 us per heavy-top step between 400 and 800
# steps at a load of 2.8).  Both codes run single-threaded in this process.
_clock = time.process_time


# --------------------------------------------------------------------------- availability
def mujoco_status():
    """``(module or None, message)``: MuJoCo if a version >= 4.0.0 is importable, else a
    one-line reason for skipping the section."""
    try:
        import mujoco
    except ImportError:
        return None, ("MuJoCo peer skipped: mujoco is not installed (optional bench dependency: "
                      "pip install '.[bench]' or pip install 'mujoco>=4.0.0')")
    ver = tuple(int(x) for x in mujoco.__version__.split(".")[:3] if x.isdigit())
    if ver < MIN_VERSION:
        return None, (f"MuJoCo peer skipped: mujoco {mujoco.__version__} is installed; the peer needs >= 4.0.0 "
                      f"(its RK4 applies the Munthe-Kaas correction on ball joints only since 4.0.0)")
    return mujoco, f"mujoco {mujoco.__version__}"


# --------------------------------------------------------------------------- the model
def _f(x):
    return " ".join(repr(float(v)) for v in np.ravel(x))


def _tree(info):
    """Parent of every body (``GROUND = -1``) and the joint to it; refuses what MuJoCo
    cannot represent as the same model (non-spherical joints, loops, free bodies)."""
    parent = {}
    for j in info.joints:
        if j.kind != "spherical":
            raise ValueError(f"{info.name}: joint {j.name!r} is {j.kind}; the MuJoCo peer builds trees of "
                             f"spherical joints only")
        if j.bodyB < 0 or j.bodyB in parent:
            raise ValueError(f"{info.name}: joint {j.name!r} closes a loop (body {info.bodies[j.bodyB].name!r} "
                             f"has two joints to its parents); MuJoCo would need a soft equality constraint, "
                             f"not the same model")
        parent[j.bodyB] = j
    for i, b in enumerate(info.bodies):
        if i not in parent:
            raise ValueError(f"{info.name}: body {b.name!r} has no joint to a parent; the MuJoCo peer builds "
                             f"trees of ball joints rooted at the ground")
    for i, b in enumerate(info.bodies):      # every body reaches the ground (no cycle among bodies)
        k, seen = i, 0
        while k >= 0 and seen <= len(info.bodies):
            k, seen = parent[k].bodyA, seen + 1
        if k >= 0:
            raise ValueError(f"{info.name}: the joints of body {b.name!r} form a loop that does not reach the "
                             f"ground; the MuJoCo peer builds trees of ball joints rooted at the ground")
    return parent


def _frame(info, i):
    if i < 0:
        return np.eye(3), np.zeros(3), np.zeros(3)
    b = info.bodies[i]
    return b.R0, b.r0, b.omega0


# MuJoCo pipeline stages these models do not use (no contacts, constraint rows, equality
# constraints, limits, friction loss, damping, sensors, actuators): disabled so that MuJoCo
# is timed at its fastest for the same dynamics (the agreement check runs with them off).
LEAN_FLAGS = ("contact", "constraint", "equality", "limit", "frictionloss", "damper", "sensor", "actuation",
              "island")


def mjcf_from_info(info, h, lean=True):
    """MJCF text of the model ``info`` (see the module docstring) with time step ``h``;
    ``lean``: every pipeline stage of :data:`LEAN_FLAGS` disabled (else contacts only)."""
    import mujoco
    parent = _tree(info)
    children = {}
    for i in range(len(info.bodies)):
        children.setdefault(parent[i].bodyA, []).append(i)
    L = [f'<mujoco model="{info.name}">',
         f' <option timestep="{float(h)!r}" integrator="RK4" gravity="{_f(info.gravity)}">',
         "  <flag " + " ".join(f'{x}="disable"' for x in (LEAN_FLAGS if lean else ("contact",))) + "/>",
         ' </option>', ' <worldbody>']
    for s in info.springs:
        if s.bodyA < 0:
            L.append(f'  <site name="{s.name}_A" pos="{_f(s.posA)}"/>')
        if s.bodyB < 0:
            L.append(f'  <site name="{s.name}_B" pos="{_f(s.posB)}"/>')

    def body(i, ind):
        b, j = info.bodies[i], parent[i]
        Rp, rp, _ = _frame(info, j.bodyA)
        pos = Rp.T @ (b.r0 - rp)                   # body frame in the parent frame at t = 0
        Rrel = Rp.T @ b.R0
        q = np.zeros(4)
        mujoco.mju_mat2Quat(q, Rrel.ravel())
        # the joint anchors of both sides must be the same point at t = 0
        anchorA = rp + Rp @ j.posA if j.bodyA >= 0 else np.asarray(j.posA, float)
        anchorB = b.r0 + b.R0 @ j.posB
        if np.linalg.norm(anchorA - anchorB) > 1e-12 * max(1.0, np.linalg.norm(anchorA)):
            raise ValueError(f"{info.name}: joint {j.name!r} is not assembled at t = 0 (anchors "
                             f"{anchorA} and {anchorB})")
        Ic = b.inertiaCOM
        L.append(f'{ind}<body name="{b.name}" pos="{_f(pos)}" quat="{_f(q)}">')
        L.append(f'{ind} <inertial pos="{_f(b.com)}" mass="{b.mass!r}" '
                 f'fullinertia="{_f([Ic[0, 0], Ic[1, 1], Ic[2, 2], Ic[0, 1], Ic[0, 2], Ic[1, 2]])}"/>')
        L.append(f'{ind} <joint name="{j.name}" type="ball" pos="{_f(j.posB)}" damping="0" armature="0"/>')
        for s in info.springs:
            for side, bi, p in (("A", s.bodyA, s.posA), ("B", s.bodyB, s.posB)):
                if bi == i:
                    L.append(f'{ind} <site name="{s.name}_{side}" pos="{_f(p)}"/>')
        for c in children.get(i, []):
            body(c, ind + " ")
        L.append(f"{ind}</body>")

    for c in children.get(-1, []):
        body(c, "  ")
    L.append(" </worldbody>")
    if info.springs:
        L.append(" <tendon>")
        for s in info.springs:
            L.append(f'  <spatial name="{s.name}" stiffness="{float(s.stiffness)!r}" '
                     f'springlength="{float(s.referenceLength)!r}" damping="0">'
                     f'<site site="{s.name}_A"/><site site="{s.name}_B"/></spatial>')
        L.append(" </tendon>")
    L.append("</mujoco>")
    return "\n".join(L)


def initial_qvel(info):
    """Ball-joint velocities: the child's body-fixed angular velocity minus its parent's,
    both in the child frame (``omega_i - R_i^T R_p omega_p``)."""
    parent = _tree(info)
    qv = np.zeros(3 * len(info.bodies))
    for i, b in enumerate(info.bodies):
        Rp, _, wp = _frame(info, parent[i].bodyA)
        qv[3 * i:3 * i + 3] = b.omega0 - b.R0.T @ Rp @ wp
    return qv


class MujocoRun:
    """A MuJoCo model and data of one bench model, reset to its initial state."""

    def __init__(self, info, h, lean=True):
        import mujoco
        self.mj = mujoco
        self.info = info
        self.xml = mjcf_from_info(info, h, lean)
        self.m = mujoco.MjModel.from_xml_string(self.xml)
        self.d = mujoco.MjData(self.m)
        self.qvel0 = initial_qvel(info)
        self.nb = len(info.bodies)
        self.set_step(h)

    def set_step(self, h):
        self.m.opt.timestep = float(h)
        self.h = float(h)

    def reset(self):
        self.mj.mj_resetData(self.m, self.d)
        self.d.qvel[:] = self.qvel0

    def step(self, n):
        self.mj.mj_step(self.m, self.d, nstep=int(n))

    def step_python_loop(self, n):
        step, m, d = self.mj.mj_step, self.m, self.d
        for _ in range(int(n)):
            step(m, d)

    def ok(self):
        W = self.mj.mjtWarning
        bad = sum(self.d.warning[int(w)].number for w in (W.mjWARN_BADQPOS, W.mjWARN_BADQVEL, W.mjWARN_BADQACC))
        return bad == 0 and bool(np.all(np.isfinite(self.d.qpos)) and np.all(np.isfinite(self.d.qvel)))

    def state(self):
        """(R, r) of every body: the body frames (= Exudyn node frames) at ``d.time``."""
        self.mj.mj_kinematics(self.m, self.d)     # mj_step leaves xpos at the start of its last step
        R = np.array([self.d.xmat[i + 1].reshape(3, 3) for i in range(self.nb)])
        r = np.array([self.d.xpos[i + 1] for i in range(self.nb)])
        return R, r


def build_info(name):
    from exudyn_lie import models
    mbs, info = models.build(MODELS[name])
    mbs.Assemble()
    return mbs, info


def exl_simulator(mbs, method="RK4", group="SE3"):
    from ..bridge import SceneFromExudyn
    from ..mbs import Simulator
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Simulator(SceneFromExudyn(mbs), method, group)


def distance(Ra, ra, Rb, rb):
    """(largest |ra - rb| [m], largest rotation angle between Ra and Rb [rad]) over the bodies."""
    from .bench_wp import rotation_angle
    dr = max(float(np.linalg.norm(a - b)) for a, b in zip(ra, rb))
    dR = max(rotation_angle(a, b) for a, b in zip(Ra, Rb))
    return dr, dR


# --------------------------------------------------------------------------- checks
def agreement(T=AGREE_T, h=AGREE_H, model="heavytop"):
    """MuJoCo RK4 against exudyn_lie MK-RK4 SE3 on the same model and step: the final
    distance, and for scale the distance of both to a fine RK6 run (the discretisation
    error) and the round-off floor (``roundoff``: the largest distance of the package's own
    run to itself with each initial angular velocity component moved by one ulp, up or down:
    two round-off-exact implementations of one algorithm can differ by about that much)."""
    mbs, info = build_info(model)
    n = int(round(T / h))
    sim = exl_simulator(mbs)
    sim.SetInitialState()
    sim.Advance(n, h)
    run = MujocoRun(info, h)
    run.reset()
    run.step(n)
    R, r = run.state()
    dr, dR = distance(R, r, sim.R, sim.r)
    ref = exl_simulator(mbs, "RK6", "SE3")
    ref.SetInitialState()
    nref = 10 * n
    ref.Advance(nref, T / nref)
    er, eR = distance(R, r, ref.R, ref.r)
    floor = 0.0
    for direction in (np.inf, -np.inf):
        ulp = exl_simulator(mbs)
        ulp.SetInitialState()
        ulp.V[:, :3] = np.nextafter(ulp.V[:, :3], direction)
        ulp.Advance(n, h)
        floor = max(floor, *distance(ulp.R, ulp.r, sim.R, sim.r))
    return dict(model=model, T=T, h=h, steps=n, dr=dr, dR=dR, tol=AGREE_TOL, ok=bool(max(dr, dR) <= AGREE_TOL),
                mujocoTime=float(run.d.time), discretisation=max(er, eR), roundoff=floor)


# --------------------------------------------------------------------------- timing
def time_interleaved(name, h, n, repeat):
    """Per-step cost [us] on model ``name`` at step ``h`` over ``n`` steps from the initial
    state, medians over ``repeat`` repetitions with the competitors alternating inside each
    repetition: ``exl`` (MK-RK4 SE3, ``Simulator.Advance``), ``mujoco`` (``mj_step(nstep=n)``,
    unused stages off), ``mujocoDefault`` (the same with only contacts off),
    ``mujocoLoop`` (a Python loop of ``mj_step(m, d)``), ``mujocoRollout``
    (``rollout.rollout``, which also stores every state); ``pythonPerCall``: a Python loop of
    ``mj_step(m, d, nstep=0)`` (the loop, the binding's argument handling, no step) per call."""
    from mujoco import rollout as mjrollout
    mbs, info = build_info(name)
    sim = exl_simulator(mbs)
    run = MujocoRun(info, h)
    rdef = MujocoRun(info, h, lean=False)
    spec = run.mj.mjtState.mjSTATE_FULLPHYSICS
    s0 = np.zeros(run.mj.mj_stateSize(run.m, spec))
    run.reset()
    run.mj.mj_getState(run.m, run.d, s0, spec)
    states = np.zeros((1, n, s0.size))

    def t_exl():
        sim.SetInitialState()
        tic = _clock()
        sim.Advance(n, h)
        return _clock() - tic

    def t_mj(r):
        r.reset()
        tic = _clock()
        r.step(n)
        return _clock() - tic

    def t_loop():
        run.reset()
        tic = _clock()
        run.step_python_loop(n)
        return _clock() - tic

    def t_roll():
        tic = _clock()
        mjrollout.rollout([run.m], [run.d], s0[None], nstep=n, state=states, skip_checks=True)
        return _clock() - tic

    def t_call():
        step, m, d = run.mj.mj_step, run.m, run.d
        tic = _clock()
        for _ in range(n):
            step(m, d, nstep=0)
        return _clock() - tic

    timers = dict(exl=t_exl, mujoco=lambda: t_mj(run), mujocoDefault=lambda: t_mj(rdef), mujocoLoop=t_loop,
                  mujocoRollout=t_roll, pythonPerCall=t_call)
    for t in timers.values():        # warm-up (numba cache, MuJoCo's first call)
        t()
    times = {k: [] for k in timers}
    for _ in range(int(repeat)):
        for k, t in timers.items():
            times[k].append(t())
    out = {k: float(np.median(v)) / n * 1e6 for k, v in times.items()}
    out["times"] = times
    out["ratio"] = out["mujoco"] / out["exl"]
    out["ratioDefault"] = out["mujocoDefault"] / out["exl"]
    # the rollout recorded every state: its last row is the state after n steps, as mj_step's
    run.reset()
    run.step(n)
    out["rolloutSame"] = bool(np.array_equal(states[0, -1, 1:], np.r_[run.d.qpos, run.d.qvel]))
    return out


def work_precision(name, T, href, repeat, kmax, budget, log=None):
    """Final configuration error at ``T`` against exudyn_lie RK6 SE3 at ``href`` and median
    CPU time, for MuJoCo RK4 and exudyn_lie MK-RK4 / MK-RK6 SE3 at ``h = 1e-2 / 2^k``
    (interleaved per level).  A curve stops below 5e-9 (past the last accuracy level) or
    when one run exceeds ``budget`` seconds."""
    mbs, info = build_info(name)
    ref = exl_simulator(mbs, "RK6", "SE3")
    nref = int(round(T / href))
    ref.SetInitialState()
    ref.Advance(nref, T / nref)
    Rref, rref = ref.R.copy(), ref.r.copy()
    sims = {"RK4 SE3": exl_simulator(mbs, "RK4"), "RK6 SE3": exl_simulator(mbs, "RK6")}
    run = MujocoRun(info, WP_H0)
    curves = {"MuJoCo RK4": [], "RK4 SE3": [], "RK6 SE3": []}
    active = set(curves)
    for k in range(kmax + 1):
        n = int(round(T / WP_H0 * 2 ** k))
        h = T / n
        run.set_step(h)
        res = {c: dict(times=[], ok=True, err=np.nan, message="") for c in active}

        def one(c):
            if c == "MuJoCo RK4":
                run.reset()
                tic = _clock()
                run.step(n)
                t = _clock() - tic
                ok = run.ok()
                R, r = run.state() if ok else (None, None)
                return t, ok, R, r, "" if ok else "MuJoCo warned (bad qpos / qvel / qacc)"
            sim = sims[c]
            sim.SetInitialState()
            tic = _clock()
            try:
                sim.Advance(n, h)
            except Exception as e:   # StepSizeError beyond the stability limit: a failed point
                return _clock() - tic, False, None, None, f"{type(e).__name__}"
            t = _clock() - tic
            return t, bool(np.all(np.isfinite(sim.r))), sim.R.copy(), sim.r.copy(), ""

        nrep = int(repeat)
        rep = 0
        while rep < nrep:
            if rep == 1:
                # short runs are repeated more (>= ~0.25 s per curve and level, at most 51 times):
                # a median of a few millisecond runs on a shared machine is at the mercy of the scheduler
                tmax = max((x["times"][0] for x in res.values() if x["times"]), default=1.0)
                nrep = int(np.clip(np.ceil(0.25 / max(tmax, 1e-6)), repeat, 51))
            for c in list(res):
                if not res[c]["ok"]:
                    continue
                t, ok, R, r, msg = one(c)
                res[c]["times"].append(t)
                if not ok:
                    res[c].update(ok=False, message=msg)
                elif rep == 0:
                    res[c]["err"] = max(distance(R, r, Rref, rref))
            rep += 1
        for c, x in res.items():
            tmed = float(np.median(x["times"])) if x["times"] else np.nan
            curves[c].append(dict(k=k, n=n, h=h, ok=x["ok"], err=x["err"] if x["ok"] else np.nan, time=tmed,
                                  repeat=len(x["times"]), message=x["message"]))
            if x["ok"] and (x["err"] < 5e-9 or tmed > budget):
                active.discard(c)
        if log:
            log("mujoco wp " + name + f" h = {h:.3g}: " + ", ".join(
                f"{c} {curves[c][-1]['err']:.2g} in {1e3 * curves[c][-1]['time']:.3g} ms" for c in res))
        if not active:
            break
    return dict(T=T, href=href, curves=curves, summary=wp_summary(curves))


def wp_summary(curves):
    """Per accuracy: time to reach it per curve and the ratios MuJoCo / exudyn_lie."""
    from .bench_wp import observed_order, time_to_accuracy
    rows = []
    for eps in EPS_LEVELS:
        tt = {c: time_to_accuracy([(p["err"], p["time"]) for p in pts if p["ok"]], eps) for c, pts in curves.items()}
        tm = tt["MuJoCo RK4"][0]
        rows.append(dict(eps=eps, times=tt, ratioRK4=tm / tt["RK4 SE3"][0],
                         ratioBest=tm / min(tt["RK4 SE3"][0], tt["RK6 SE3"][0])))
    # observed order over the runs inside the accuracy band of the ratios (1e-4 ... 1e-8): past the
    # pre-asymptotic coarse steps, before the round-off floor of runs of 10^5 steps (~1e-9 on
    # the double pendulum's fast spin).  The same model: MuJoCo's error against the package's
    # reference falls at RK4's order through the band (a model difference would level it off)
    lo, hi = min(EPS_LEVELS), max(EPS_LEVELS)
    order = {}
    for c, pts in curves.items():
        hs = [(p["h"], p["err"]) for p in pts if p["ok"] and lo <= p["err"] <= hi]
        order[c] = observed_order(hs)
    ok = [p for p in curves["MuJoCo RK4"] if p["ok"] and lo <= p["err"] <= hi]
    finest = ok[-1] if ok else dict(h=np.nan, err=np.nan)
    conv = bool(np.isfinite(order["MuJoCo RK4"]) and 3.5 <= order["MuJoCo RK4"] <= 5.0)
    return dict(rows=rows, order=order, finestH=finest["h"], finestErr=finest["err"], converges=conv)


# --------------------------------------------------------------------------- the section
def run_section(cfg, log):
    """The bench section ``mujoco``; returns its results (``skipped`` = the reason if MuJoCo
    is missing)."""
    mujoco, msg = mujoco_status()
    if mujoco is None:
        log(msg)
        return dict(skipped=msg)
    names = [m for m in MODELS if m in getattr(cfg, "models", MODELS)]
    if not names:
        msg = f"MuJoCo peer skipped: none of its models ({', '.join(MODELS)}) is selected by --models"
        log(msg)
        return dict(skipped=msg)
    res = dict(version=mujoco.__version__, xml={}, models=names)
    log(f"MuJoCo peer ({msg}): agreement on the heavy top, {AGREE_T:g} s at h = {AGREE_H:g}")
    ag = agreement()
    res["agreement"] = ag
    log(f"MuJoCo RK4 vs MK-RK4 SE3: |dr| = {ag['dr']:.2g} m, |dR| = {ag['dR']:.2g} rad (tolerance {AGREE_TOL:g}; "
        f"discretisation error {ag['discretisation']:.2g}; round-off floor {ag['roundoff']:.2g})")
    for name in names:
        res["xml"][name] = mjcf_from_info(build_info(name)[1], PERSTEP_H[0])
    if not ag["ok"]:
        res["failed"] = (f"MuJoCo's RK4 and MK-RK4 SE3 differ by {max(ag['dr'], ag['dR']):.2g} > {AGREE_TOL:g} "
                         f"on the heavy top: the models are not the same; no timing reported")
        log(res["failed"])
        return res
    n = 200 if cfg.quick else 2000
    rep = 5 if cfg.quick else 15
    res["perstep"] = {}
    for name in names:
        for h in PERSTEP_H:
            d = time_interleaved(name, h, n, rep)
            res["perstep"].setdefault(name, {})[h] = d
            log(f"MuJoCo per step {name} h = {h:g}: exudyn_lie {d['exl']:.3g} us, MuJoCo mj_step(nstep) "
                f"{d['mujoco']:.3g} us ({d['ratio']:.2f}x; only contacts off {d['mujocoDefault']:.3g} us), "
                f"Python loop {d['mujocoLoop']:.3g} us (a bare call {d['pythonPerCall']:.2g} us), "
                f"rollout {d['mujocoRollout']:.3g} us")
    res["nsteps"], res["repeat"] = n, rep
    res["wp"] = {}
    for name in names:
        res["wp"][name] = work_precision(name, cfg.T, cfg.href, 3 if cfg.quick else 5, kmax=5 if cfg.quick else 11,
                                         budget=0.3 if cfg.quick else 2.5, log=log)
    return res


def _r(x):
    return f"{x:.3g}x" if np.isfinite(x) else "n/a"


def target_lines(res):
    """Rows of the bench's targets table."""
    if not res:
        return []
    if "skipped" in res:
        return [f"| MuJoCo peer | {res['skipped']} | - |"]
    ag = res["agreement"]
    L = [f"| MuJoCo peer, heavytop: MuJoCo {res['version']} RK4 = exudyn_lie MK-RK4 SE3 to round-off ({ag['T']:g} s, "
         f"h = {ag['h']:g}, tolerance {ag['tol']:g}) | |dr| = {ag['dr']:.2g} m, |dR| = {ag['dR']:.2g} rad "
         f"(either run is {ag['discretisation']:.2g} from RK6 at h/10; one ulp in the initial angular velocity moves "
         f"the package's own run by {ag['roundoff']:.2g}) | {'yes' if ag['ok'] else 'no'} |"]
    if "failed" in res:
        return L + [f"| MuJoCo peer, per-step targets against MuJoCo | not measured: {res['failed']} | no |"]
    for name, dh in res["perstep"].items():
        target = TARGET_RATIO[name]
        cells = [f"h = {h:g}: {d['exl']:.3g} us vs {d['mujoco']:.3g} us ({d['ratio']:.2f}x)"
                 for h, d in sorted(dh.items(), reverse=True)]
        ok = all(d["ratio"] >= target for d in dh.values())
        L.append(f"| MuJoCo peer, {name}: MK-RK4 (SE3) step >= {target:g}x cheaper than MuJoCo's RK4 step (mj_step, same "
                 f"model and step) | {'; '.join(cells)} | {'yes' if ok else 'no'} |")
    for name, w in res["wp"].items():
        sm = w["summary"]
        L.append(f"| MuJoCo peer, {name}: MuJoCo's model converges to the package's solution (MuJoCo RK4 against exudyn_lie "
                 f"RK6 at h = {w['href']:g}, T = {w['T']:g} s: observed order 3.5 ... 5 over its runs with errors in "
                 f"1e-4 ... 1e-8) "
                 f"| order {sm['order']['MuJoCo RK4']:.2f} (its most accurate run in the band: {sm['finestErr']:.2g} at "
                 f"h = {sm['finestH']:.3g}) "
                 f"| {'yes' if sm['converges'] else 'no'} |")
    for name, w in res["wp"].items():
        cells = [f"{_r(r['ratioRK4'])} at {r['eps']:.0e}" for r in w["summary"]["rows"]]
        L.append(f"| MuJoCo peer, {name}: work-precision, MuJoCo RK4 time / MK-RK4 SE3 time to reach 1e-4 ... 1e-8 "
                 f"(informative) | {', '.join(cells)} | - |")
    return L


def report_lines(res, figure=None):
    """The section of BENCHMARKS.md."""
    L = ["## 8. MuJoCo as a peer (same algorithm, other code)", ""]
    if "skipped" in res:
        return L + [res["skipped"] + ".", ""]
    ag = res["agreement"]
    L += [f"MuJoCo {res['version']} builds the heavy top and the spherical double pendulum from the same "
          "`models.ModelInfo` data the package integrates (`exudyn_lie.apps.bench_mujoco.mjcf_from_info`): "
          "ball joints, inertia about the COM (`<inertial pos fullinertia>`), contacts disabled, "
          "`integrator=\"RK4\"`, the heavy top's spring `c (p0 - r)` as a spatial tendon of zero rest length "
          "(evaluated in every RK4 stage like the package's spring). Since 4.0.0 its RK4 applies the "
          "Munthe-Kaas correction on ball joints, so on the heavy top it computes MK-RK4 on SE(3)'s discrete "
          "solution.", "",
          f"Agreement (checked before any timing): heavy top, {ag['T']:g} s at h = {ag['h']:g} s "
          f"({ag['steps']} steps): |r_MuJoCo - r_exl| = {ag['dr']:.2g} m, rotation {ag['dR']:.2g} rad "
          f"(tolerance {ag['tol']:g}); for scale, the distance of either run to RK6 at h/10 is "
          f"{ag['discretisation']:.2g}, and the round-off floor (the package's own run with each initial angular "
          f"velocity component moved by one ulp, up or down, against itself) is {ag['roundoff']:.2g}: the two "
          f"implementations agree to round-off when their distance is of that order. "
          + ("**Agreement failed.**" if not ag["ok"] else ""), ""]
    if "failed" in res:
        return L + [res["failed"], ""]
    L += [f"Cost per step: CPU time of the process (`time.process_time`: on a shared machine a run longer than "
          f"the scheduler's time slice would otherwise pay for other jobs), median over {res['repeat']} "
          f"repetitions of {res['nsteps']} steps from the initial state, "
          "exudyn_lie and the MuJoCo variants alternating in every repetition. exudyn_lie: "
          "`Simulator.Advance(n, h)` (MK-RK4, SE3, the compiled time loop); MuJoCo: `mj_step(m, d, nstep=n)` (its "
          "C loop, no Python per step) with the pipeline stages these models do not use disabled (`"
          + ", ".join(LEAN_FLAGS) + "`: MuJoCo at its fastest for the same dynamics; the number the targets "
          "use), the same with only contacts disabled, a Python loop of `mj_step(m, d)`, and "
          "`mujoco.rollout.rollout` (a C loop that also stores every state). 'Bare call': a Python loop of "
          "`mj_step(m, d, nstep=0)`, the loop and the binding's own cost per call without a step, i.e. what a "
          "Python loop adds to MuJoCo.", "",
          "| model | h | exudyn_lie us/step | MuJoCo mj_step(nstep) us/step | ratio | target | MuJoCo, only "
          "contacts off | MuJoCo Python loop | bare call | MuJoCo rollout |",
          "|---|---|---|---|---|---|---|---|---|---|"]
    for name, dh in res["perstep"].items():
        for h, d in sorted(dh.items(), reverse=True):
            L.append(f"| {name} | {h:g} | {d['exl']:.3g} | {d['mujoco']:.3g} | {d['ratio']:.2f}x | "
                     f">= {TARGET_RATIO[name]:g}x: {'yes' if d['ratio'] >= TARGET_RATIO[name] else 'no'} | "
                     f"{d['mujocoDefault']:.3g} ({d['ratioDefault']:.2f}x) | {d['mujocoLoop']:.3g} | "
                     f"{d['pythonPerCall']:.2g} | {d['mujocoRollout']:.3g} |")
    L += ["", "Work-precision: final configuration error at T (largest over the bodies of |r - r_ref| [m] and the "
          "rotation angle of R_ref^T R [rad]) against exudyn_lie RK6 SE3 at a small step, CPU time of the time loop "
          "(median, interleaved per step size h = 1e-2 / 2^k). Time to reach an accuracy by log-log "
          "interpolation; ratio = MuJoCo's time over exudyn_lie's.", ""]
    if figure:
        L += [f"![MuJoCo work-precision]({figure})", ""]
    L += ["| model | accuracy | MuJoCo RK4 | exudyn_lie MK-RK4 SE3 | exudyn_lie MK-RK6 SE3 | MuJoCo / MK-RK4 | "
          "MuJoCo / best exudyn_lie |", "|---|---|---|---|---|---|---|"]
    for name, w in res["wp"].items():
        for r in w["summary"]["rows"]:
            t = r["times"]
            L.append(f"| {name} | {r['eps']:.0e} | " + " | ".join(
                (f"{1e3 * t[c][0]:.3g} ms" if np.isfinite(t[c][0]) else "n/r") for c in
                ("MuJoCo RK4", "RK4 SE3", "RK6 SE3")) + f" | {_r(r['ratioRK4'])} | {_r(r['ratioBest'])} |")
    L.append("")
    L.append("Observed order over the runs with errors in 1e-4 ... 1e-8 (both codes converge to the same "
             "solution): " + "; ".join(
                 f"{name}: " + ", ".join(f"{c} {o:.2f}" for c, o in w["summary"]["order"].items())
                 for name, w in res["wp"].items()) + ".")
    L.append("")
    return L


def plot(res, path):
    """Work-precision figure of the section (one panel per model)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    wp = res.get("wp") or {}
    fig, axes = plt.subplots(1, len(wp), figsize=(5.2 * len(wp), 4.4), squeeze=False)
    style = {"MuJoCo RK4": dict(color="tab:red", marker="s", ls="--"),
             "RK4 SE3": dict(color="tab:blue", marker="o", ls="-"),
             "RK6 SE3": dict(color="tab:green", marker="^", ls="-")}
    for ax, (name, w) in zip(axes[0], wp.items()):
        for c, pts in w["curves"].items():
            p = [(x["err"], x["time"]) for x in pts if x["ok"] and np.isfinite(x["err"]) and x["err"] > 0]
            if p:
                e, t = zip(*p)
                lab = c if c.startswith("MuJoCo") else f"exudyn_lie MK-{c}"
                ax.loglog(e, np.array(t) * 1e3, label=lab, ms=5, lw=1.4, **style[c])
        ax.axvspan(min(EPS_LEVELS), max(EPS_LEVELS), color="0.93", zorder=0,
                   label=f"accuracies of the ratios ({max(EPS_LEVELS):.0e} ... {min(EPS_LEVELS):.0e})")
        ax.invert_xaxis()
        ax.set_xlabel("final configuration error [m, rad]")
        ax.set_ylabel("CPU time of the time loop [ms]")
        ax.set_title(f"{TITLES.get(name, name)}, T = {w['T']:g} s", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"MuJoCo {res.get('version', '')} RK4 against exudyn_lie: same model, same step sizes "
                 f"(CPU time, median)", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path
