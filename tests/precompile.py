"""Compile the kernel's kinds once, shared out among the test workers, before any test runs.

numba compiles the time loop once per kind of model (method, step controller, lean or full
scene, solve; docs/ARCHITECTURE.md) and a first compile takes a minute or more.  Left to the
tests, each worker compiles a kind when its first test needs it, and the two workers of
``pytest -n 2`` often need the same kind at the same time: both compile it, and the cache
keeps one.  Here each worker, in ``pytest_sessionstart`` (``tests/conftest.py``), claims the
kinds one at a time (a file created exclusively in a directory of the test run) and compiles
those it claimed; xdist starts the tests once both workers have collected, so every test runs
on a compiled kind and no kind is compiled twice.  Nothing is asserted here: a kind that fails
to build is left to the tests that need it, which report it.

``KINDS`` lists one small model per kind of ``mk_steps`` the suite compiles, in the order the
workers take them.
"""
import os
import time
import warnings

import numpy as np


def _kernel_chain(method="RK4", **kw):
    from exudyn_lie.apps import bench_topology as BT
    from exudyn_lie.mbs import Simulator
    return Simulator(BT.build_scene("chain", 3), method, "SE3", **kw)


def _lean_fixed(method):
    def build():
        _kernel_chain(method).Advance(2, 1e-3)
    return build


def _lean_adaptive():
    sim = _kernel_chain("DOPRI5")
    sim.SetAdaptive(rtol=1e-6, atol=1e-6)
    sim.AdvanceTo(1e-3)


def _tree(stabilization):
    def build():
        from exudyn_lie.apps import bench_topology as BT
        from exudyn_lie.mbs import Simulator
        Simulator(BT.build_scene("star", 24), "RK4", "SE3", stabilization=stabilization).Advance(2, 1e-3)
    return build


def _oblique():
    from exudyn_lie.groups import so3
    from exudyn_lie.mbs import GROUND, RotationParameterCoordinate, Scene, Simulator
    sc = Scene()
    sc.AddBody(mass=2.0, inertia=np.diag([0.1, 0.2, 0.3]), R0=so3.exp(np.array([0.3, -0.5, 0.7])), r0=[0, 0, 0],
               omega0=[0.2, 0.9, -0.4], vel0=[0.1, 0, 0])
    sc.AddCoordinateConstraint(GROUND, 0, 0, RotationParameterCoordinate("rotationVector", 1),
                               constant=0.0)
    Simulator(sc, "RK4", "SE3", projectInitial=True).Advance(2, 1e-3)


def _drop_in(build, solverType=None, **kw):
    def run():
        import exudyn as exu
        import exudyn_lie as exl
        from exudyn_lie.apps import warmup as W
        SC, mbs = getattr(W, build)()
        ss = W._settings(solverType=None if solverType is None else getattr(exu.DynamicSolverType, solverType))
        exl.SolveDynamic(mbs, ss, showProgress=False, **kw)
    return run


#: (name, build): one model per kind of the time loop that the suite compiles.  Every drop-in run also
#: compiles the drop-in's RK4 kind (the accelerations at the start) and every kernel run the lean RK4
#: kind, so those two come first (one per worker) and the runs that need them after a long one; the
#: lean kinds, the shortest, last.
KINDS = [
    ("drop-in, RK4", _drop_in("_pendulum")),
    ("kernel, RK4 (lean scene)", _lean_fixed("RK4")),
    ("rotation-vector coordinate rows (oblique solve)", _oblique),
    ("tree solve, stabilised (full scene)", _tree("velocity")),
    ("drop-in, adaptive steps (DOPRI5)", _drop_in("_pendulum", "DOPRI5")),
    ("drop-in, ESDIRK3 (stiff, chosen by itself)", _drop_in("_stiff_springs")),
    ("drop-in, velocity Verlet", _drop_in("_pendulum", "VelocityVerlet")),
    ("drop-in, ESDIRK3 on adaptive steps", _drop_in("_pendulum", method="ESDIRK3")),
    ("kernel, adaptive steps (lean scene)", _lean_adaptive),
    ("kernel, ESDIRK3 (lean scene)", _lean_fixed("ESDIRK3")),
    ("tree solve (lean scene)", _tree(None)),
]


def _claim(directory, k):
    try:
        os.close(os.open(os.path.join(directory, f"kind{k}"), os.O_CREAT | os.O_EXCL | os.O_WRONLY))
        return True
    except FileExistsError:
        return False


def precompile(directory, log=None):
    """Compile every kind of ``KINDS`` that no other process of this test run has claimed in
    ``directory``; returns ``[(name, seconds, error or None)]`` of those compiled here."""
    os.makedirs(directory, exist_ok=True)
    done = []
    for k, (name, build) in enumerate(KINDS):
        if not _claim(directory, k):
            continue
        tic = time.perf_counter()
        err = None
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                build()
        except Exception as e:  # noqa: BLE001 - the tests that need the kind report it
            err = f"{type(e).__name__}: {e}"
        done.append((name, time.perf_counter() - tic, err))
        if log is not None:
            log(f"precompiled {name}: {done[-1][1]:.1f} s" + (f" ({err})" if err else ""))
    return done
