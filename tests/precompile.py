"""Compile the kernel's kinds once, shared out among the test workers, before any test runs.

numba compiles the time loop once per kind of model (method, step controller, lean or full
scene, solve; docs/ARCHITECTURE.md) and a first compile takes a minute or more.  Left to the
tests, each worker compiles a kind when its first test needs it, and the two workers of
``pytest -n 2`` often need the same kind at the same time: both compile it, and the cache
keeps one.  Here each worker, once it has collected (``tests/conftest.py``), claims the kinds one
at a time (a file created exclusively in a directory the controller made for the run) and
compiles those it claimed, a kind only after the kinds it needs; xdist starts the tests once
every worker has collected, so the tests run on compiled kinds and no kind of ``KINDS`` is
compiled twice.  Nothing is asserted here: a kind that fails to build is left to the tests that
need it, which report it.
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


#: (name, build, prerequisites): one model per kind of the time loop that the suite compiles.  Every
#: drop-in run also compiles the drop-in's RK4 kind (the accelerations at the start) and every kernel
#: run the lean RK4 kind: a kind is taken only once the kinds it needs are compiled (else the two
#: workers would compile those at once).  ESDIRK3 on adaptive steps waits for ESDIRK3 and DOPRI5: the
#: Newton iteration (mbs/implicit.py) is compiled once per kind of scene for fixed and adaptive steps,
#: the dense output (mbs/adaptive.py) once for explicit and implicit pairs (compiled at once by both
#: workers, they cost about 100 s twice; by hand, numba's compile events).  While one worker compiles the drop-in's RK4, the other takes the lean kinds and
#: the oblique solve; the full tree solve waits for the drop-in's RK4 (the callees with the same
#: array arguments, the joint rows among them, are compiled once) and comes last, after the longest
#: chain (RK4, ESDIRK3, its adaptive steps).  Velocity Verlet runs on the explicit methods' kind
#: (mbs/methods.py).
DROP_IN_RK4, LEAN_RK4, DROP_IN_ESDIRK3, DROP_IN_DOPRI5 = 0, 1, 4, 5
KINDS = [
    ("drop-in, RK4", _drop_in("_pendulum"), ()),
    ("kernel, RK4 (lean scene)", _lean_fixed("RK4"), ()),
    ("tree solve (lean scene)", _tree(None), (LEAN_RK4,)),
    ("rotation-vector coordinate rows (oblique solve)", _oblique, ()),
    ("drop-in, ESDIRK3 (stiff, chosen by itself)", _drop_in("_stiff_springs"), (DROP_IN_RK4,)),
    ("drop-in, adaptive steps (DOPRI5)", _drop_in("_pendulum", "DOPRI5"), (DROP_IN_RK4,)),
    ("drop-in, ESDIRK3 on adaptive steps", _drop_in("_pendulum", method="ESDIRK3"),
     (DROP_IN_ESDIRK3, DROP_IN_DOPRI5)),
    ("tree solve, stabilised (full scene)", _tree("velocity"), (DROP_IN_RK4,)),
]
#: a run that selects fewer tests (``-k``, one file) is not made to wait for every kind
MIN_TESTS = 200
#: seconds a worker waits at most for another's kind before it builds its own (a worker that died)
WAIT_LIMIT = 1800.0


def _create(path):
    """True if this process created ``path`` (atomic: the claim of a kind)."""
    try:
        os.close(os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY))
        return True
    except FileExistsError:
        return False


def _next_kind(directory, waited):
    """The first unclaimed kind whose prerequisites are compiled, claimed; None when every kind is
    claimed; -1 when the unclaimed ones still wait for a prerequisite."""
    pending = False
    for k, (_, _, needs) in enumerate(KINDS):
        if os.path.exists(os.path.join(directory, f"kind{k}")):
            continue
        if waited < WAIT_LIMIT and not all(os.path.exists(os.path.join(directory, f"done{j}")) for j in needs):
            pending = True
            continue
        if _create(os.path.join(directory, f"kind{k}")):
            return k
        pending = True
    return -1 if pending else None


def precompile(directory, log=print):
    """Compile the kinds of ``KINDS`` that no other process sharing ``directory`` has claimed, each
    once its prerequisites are compiled; ``log`` gets a line for each kind that failed to build
    (its tests then compile and report it).  Returns ``[(name, seconds, error or None)]``."""
    done = []
    waited = 0.0
    try:
        while True:
            k = _next_kind(directory, waited)
            if k is None:
                return done
            if k < 0:
                time.sleep(0.5)
                waited += 0.5
                continue
            name, build, _ = KINDS[k]
            tic = time.perf_counter()
            err = None
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    build()
            except Exception as e:  # noqa: BLE001 - the tests that need the kind report it
                err = f"{type(e).__name__}: {e}"
                log(f"tests/precompile.py: {name} failed to build ({err}); its tests compile it")
            done.append((name, time.perf_counter() - tic, err))
            _create(os.path.join(directory, f"done{k}"))
    except OSError as e:                     # the directory went away or cannot be written
        log(f"tests/precompile.py: stopped ({e})")
        return done
