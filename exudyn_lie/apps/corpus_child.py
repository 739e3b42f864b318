"""The child process of ``python -m exudyn_lie corpus``: run ONE Exudyn script, unedited.

    python corpus_child.py MODE SCRIPT EVENTS [FACTOR]    (MODE: native | exl | fine | exlfine)

Started by :mod:`exudyn_lie.apps.corpus` (by its file path, so that a native run imports
nothing of exudyn_lie), in a fresh interpreter per run.  Before the script runs:

* graphics off: ``exudynTestGlobals.useGraphics = False`` (the TestModels read it from
  ``modelUnitTests``, imported from the script's folder when it has one, else a stand-in
  module), and the calls that open or wait for a window are no-ops: ``Renderer.Start /
  Stop / DoIdleTasks`` (``SC.renderer``), ``exu.StartRenderer / StopRenderer /
  DoRendererIdleTasks``, ``mbs.WaitForUserToContinue``, ``mbs.SolutionViewer`` and
  ``exudyn.interactive.SolutionViewer``, ``matplotlib.pyplot.show`` (the parent also sets
  ``MPLBACKEND=Agg`` and Exudyn's ``EXUDYN_SUPPRESS_UI_WINDOW_OPEN=1``);
* every ``SolveDynamic`` a script can reach - ``exudyn.SolveDynamic``,
  ``exudyn.solver.SolveDynamic`` (so also ``from exudyn.solver import *``) and the method
  ``exudyn.MainSystem.SolveDynamic`` - is replaced by a wrapper that logs the call and
  passes the same arguments to Exudyn's own function (native) or to
  :func:`exudyn_lie.SolveDynamic` (exl); mode fine: Exudyn's own function with
  ``timeIntegration.numberOfSteps`` multiplied by FACTOR during the call (a native
  reference at a finer step); mode exlfine: :func:`exudyn_lie.SolveDynamic` with the steps
  multiplied so (does exudyn_lie converge to the native reference?).  Static and
  eigenvalue solves stay Exudyn's.

The script runs with ``runpy.run_path(SCRIPT, run_name='__main__')``, ``sys.argv = [SCRIPT]``
and its folder first on ``sys.path``, as ``python SCRIPT`` would.  Events go to EVENTS as
JSON lines (``start``, ``solve``, ``solve_end`` / ``solve_error``, ``direct_solver``,
``exit``), written and flushed at once, so a run that is killed at its time limit still
tells how far it got.
"""
import json
import os
import runpy
import sys
import time
import traceback
import types

T0 = time.perf_counter()
TB_FRAMES = 5           # innermost traceback frames kept per error
TB_MESSAGE_LINES = 4    # and lines of its message


def _open_events(path):
    f = open(path, "a", buffering=1, encoding="utf-8")

    def emit(ev, **data):
        data["ev"] = ev
        data["t"] = round(time.perf_counter() - T0, 4)
        f.write(json.dumps(data, default=repr) + "\n")
        f.flush()
    return f, emit


def describe(exc):
    """Class, first line of the message, the innermost frame (file:line function) overall
    and inside exudyn_lie, and the traceback's tail."""
    msg = str(exc).strip()
    frames = traceback.extract_tb(exc.__traceback__)
    where = f"{frames[-1].filename}:{frames[-1].lineno} {frames[-1].name}" if frames else ""
    ours = [f for f in frames if f"{os.sep}exudyn_lie{os.sep}" in f.filename]
    # the innermost frames, then the message (Exudyn's can span many lines: its first few)
    tail = "".join(traceback.format_list(frames[-TB_FRAMES:])).rstrip().splitlines()
    tail += f"{type(exc).__name__}: {msg}".splitlines()[:TB_MESSAGE_LINES]
    return dict(cls=type(exc).__name__, module=type(exc).__module__,
                msg=msg.splitlines()[0] if msg else "", where=where,
                whereExl=f"{ours[-1].filename}:{ours[-1].lineno} {ours[-1].name}" if ours else "",
                tb="\n".join(tail))


def exl_kind(exc):
    """exudyn_lie's own errors: 'refusal' (SceneError / BridgeError: bad or unsupported
    input, raised before mbs is touched), 'stop' (SimulationError: StepSizeError,
    ConstraintError during the run), 'internal' (a BridgeError that says 'internal': a bug);
    None for any other exception."""
    exl = sys.modules.get("exudyn_lie")
    if exl is None:
        return None
    if isinstance(exc, exl.SimulationError):
        return "stop"
    if isinstance(exc, exl.SceneError):
        return "internal" if str(exc).strip().lower().startswith("internal") else "refusal"
    return None


def encode_result(value):
    """exudynTestGlobals.testResult as JSON: a float, a short list, or its repr."""
    if value is None:
        return None
    try:
        return float(value)
    except (TypeError, ValueError):
        pass
    try:
        import numpy as np
        a = np.asarray(value, dtype=float)
        return a.tolist() if a.size <= 20 else f"array of shape {a.shape}"
    except (TypeError, ValueError):
        return repr(value)[:200]


def model_inventory(mbs):
    """Item types of mbs with Exudyn's prefixes (NodeRigidBodyEP, ObjectRigidBody, ...),
    and 'GeneralContact' if the system has one (it is not an item)."""
    kinds = set()
    sd = mbs.systemData
    for count, get, key, prefix in ((sd.NumberOfNodes, mbs.GetNode, "nodeType", "Node"),
                                    (sd.NumberOfObjects, mbs.GetObject, "objectType", "Object"),
                                    (sd.NumberOfMarkers, mbs.GetMarker, "markerType", "Marker"),
                                    (sd.NumberOfLoads, mbs.GetLoad, "loadType", "Load")):
        for i in range(count()):
            kinds.add(prefix + str(get(i)[key]))
    try:
        if mbs.NumberOfGeneralContacts() > 0:
            kinds.add("GeneralContact")
    except AttributeError:
        pass
    return sorted(kinds)


def _noop(*args, **kwargs):
    return None


def _true(*args, **kwargs):
    return True


def replace_everywhere(original, replacement, name):
    """Rebind ``name`` in every loaded module that holds ``original`` (re-exports included)."""
    for mod in list(sys.modules.values()):
        if getattr(mod, name, None) is original:
            setattr(mod, name, replacement)


def install_graphics_stubs(exu):
    """No window opens and nothing waits for a user."""
    renderer = getattr(exu, "Renderer", None)
    if renderer is not None:
        renderer.Start = _true
        renderer.Stop = _noop
        renderer.DoIdleTasks = _noop
    exu.StartRenderer = _true
    exu.StopRenderer = _noop
    exu.DoRendererIdleTasks = _noop
    exu.MainSystem.WaitForUserToContinue = _noop
    import exudyn.interactive
    import exudyn.utilities  # noqa: F401 - loaded before patching, as a script would
    replace_everywhere(exudyn.interactive.SolutionViewer, _noop, "SolutionViewer")
    exu.MainSystem.SolutionViewer = _noop
    sys.meta_path.insert(0, _PyplotShowStub())


class _PyplotShowStub:
    """Makes ``matplotlib.pyplot.show`` a no-op when the script imports pyplot (importing
    matplotlib up front would cost every run the import)."""

    def find_spec(self, name, path=None, target=None):
        if name != "matplotlib.pyplot":
            return None
        sys.meta_path.remove(self)
        import importlib.util
        spec = importlib.util.find_spec(name)
        if spec is None or spec.loader is None:
            return spec
        spec.loader = _ShowStubLoader(spec.loader)
        return spec


class _ShowStubLoader:
    """pyplot's own loader, with ``show`` replaced once the module has run."""

    def __init__(self, inner):
        self.inner = inner

    def create_module(self, spec):
        return self.inner.create_module(spec)

    def exec_module(self, module):
        self.inner.exec_module(module)
        module.show = _noop

    def __getattr__(self, name):
        return getattr(self.inner, name)


def test_globals(script_dir):
    """exudynTestGlobals with useGraphics = False and testResult = None: from the script's
    own ``modelUnitTests.py`` (the TestModels folder) or a stand-in module of that name."""
    standin = not os.path.isfile(os.path.join(script_dir, "modelUnitTests.py"))
    if standin:
        mod = types.ModuleType("modelUnitTests")

        class ExudynTestStructure:
            def __init__(self, useGraphics=False, performTests=False, testError=0, testResult=0,
                         testTolFact=1, isPerformanceTest=False):
                self.useGraphics = useGraphics
                self.performTests = performTests
                self.testError = testError
                self.testResult = testResult
                self.testTolFact = testTolFact
                self.isPerformanceTest = isPerformanceTest
        mod.ExudynTestStructure = ExudynTestStructure
        mod.exudynTestGlobals = ExudynTestStructure()
        sys.modules["modelUnitTests"] = mod
    else:
        import modelUnitTests as mod
    g = mod.exudynTestGlobals
    g.useGraphics = False
    g.testResult = None          # None afterwards: the script did not set it
    return g, standin


def _solver_type(args, kwargs):
    """The solver type a SolveDynamic call asks for: its argument, else the settings' own."""
    st = kwargs.get("solverType", args[1] if len(args) > 1 else None)
    if st is not None:
        return str(st)
    ss = kwargs.get("simulationSettings", args[0] if args else None)
    return "settings: " + str(getattr(getattr(ss, "timeIntegration", None), "solverType", None))


def _finer(original, factor):
    """Exudyn's SolveDynamic with numberOfSteps * factor for the call (settings restored)."""
    def solve(mbs, *args, **kwargs):
        ss = kwargs.get("simulationSettings", args[0] if args else None)
        if ss is None:
            import exudyn
            ss = exudyn.SimulationSettings()
            if args:
                args = (ss,) + args[1:]
            else:
                kwargs["simulationSettings"] = ss
        ti = ss.timeIntegration
        steps = ti.numberOfSteps
        ti.numberOfSteps = steps * factor
        try:
            return original(mbs, *args, **kwargs)
        finally:
            ti.numberOfSteps = steps
    return solve


STATE_ENTRIES = 2000


def final_state(mbs):
    """The ODE2 and ODE1 coordinates at the end of a solve, for comparing runs of scripts
    that set no testResult (at most ``STATE_ENTRIES`` of them, evenly spaced); None if
    Exudyn cannot give them."""
    try:
        import exudyn as exu
        sd = mbs.systemData
        cur = exu.ConfigurationType.Current
        x = list(sd.GetODE2Coordinates(configuration=cur)) + list(sd.GetODE1Coordinates(configuration=cur))
    except Exception:                            # noqa: BLE001 - information only
        return None
    if len(x) > STATE_ENTRIES:
        step = len(x) / STATE_ENTRIES
        x = [x[int(k * step)] for k in range(STATE_ENTRIES)]
    return [float(v) for v in x]


def install_solve_wrappers(exu, mode, emit, factor=1):
    """Replace every reachable SolveDynamic by a logging wrapper (see the module doc)."""
    import exudyn.solver
    original = exudyn.solver.SolveDynamic
    if mode in ("exl", "exlfine"):
        import exudyn_lie
        target = exudyn_lie.SolveDynamic if mode == "exl" else _finer(exudyn_lie.SolveDynamic, factor)
    elif mode == "fine":
        target = _finer(original, factor)
    else:
        target = original
    state = dict(depth=0, count=0)

    def timing():
        """exudyn_lie's split of the call (set-up, compilation, time loop), in an exl run."""
        if mode not in ("exl", "exlfine"):
            return None
        import exudyn_lie
        return exudyn_lie.GetSolveTiming()

    def SolveDynamic(mbs, *args, **kwargs):
        if state["depth"]:                       # a solve inside a solve: Exudyn's own
            return original(mbs, *args, **kwargs)
        n = state["count"] = state["count"] + 1
        info = dict(n=n, solverType=_solver_type(args, kwargs))
        if mode == "native":
            try:
                info["inventory"] = model_inventory(mbs)
            except Exception as e:               # noqa: BLE001 - the inventory is information only
                info["inventory"] = None
                info["inventoryError"] = f"{type(e).__name__}: {e}"
        emit("solve", **info)
        tic = time.perf_counter()
        state["depth"] += 1
        try:
            result = target(mbs, *args, **kwargs)
        except BaseException as e:
            emit("solve_error", n=n, seconds=time.perf_counter() - tic, timing=timing(),
                 exl=exl_kind(e) if mode in ("exl", "exlfine") else None,
                 **describe(e))
            raise
        finally:
            state["depth"] -= 1
        emit("solve_end", n=n, seconds=time.perf_counter() - tic, timing=timing(), returned=repr(result)[:40],
             state=final_state(mbs))
        return result

    SolveDynamic.__doc__ = original.__doc__
    replace_everywhere(original, SolveDynamic, "SolveDynamic")
    exu.MainSystem.SolveDynamic = SolveDynamic
    if mode == "native":
        _log_direct_solvers(exu, state, emit)


def _log_direct_solvers(exu, state, emit):
    """Native runs: note dynamic solves that bypass SolveDynamic (MainSolver*.SolveSystem /
    SolveSteps called by the script); they are not swapped in the exl run."""
    seen = set()
    for cls in (exu.MainSolverImplicitSecondOrder, exu.MainSolverExplicit):
        for name in ("SolveSystem", "SolveSteps"):
            method = getattr(cls, name, None)
            if method is None:
                continue

            def wrapper(self, *args, _method=method, _key=f"{cls.__name__}.{name}", **kwargs):
                if not state["depth"] and _key not in seen:
                    seen.add(_key)
                    emit("direct_solver", call=_key)
                return _method(self, *args, **kwargs)
            setattr(cls, name, wrapper)


def main(argv):
    mode, script, events = argv[:3]
    factor = int(argv[3]) if len(argv) > 3 else 1
    script = os.path.abspath(script)
    f, emit = _open_events(events)
    script_dir = os.path.dirname(script)
    sys.path[0] = script_dir
    sys.argv = [script]
    status, error = "ok", None
    g = None
    try:
        import exudyn as exu
        install_graphics_stubs(exu)
        g, standin = test_globals(script_dir)
        install_solve_wrappers(exu, mode, emit, factor)
        emit("start", mode=mode, factor=factor, exudyn=getattr(exu, "__version__", "?"), standinTestGlobals=standin)
    except BaseException as e:                   # noqa: BLE001 - the bootstrap itself failed
        emit("exit", status="bootstrap error", error=describe(e), testResult=None)
        f.close()
        os._exit(3)
    try:
        runpy.run_path(script, run_name="__main__")
    except SystemExit as e:
        if e.code not in (None, 0):
            status, error = "error", dict(cls="SystemExit", module="builtins", msg=f"exit code {e.code}",
                                          where="", whereExl="", tb="")
    except BaseException as e:                   # noqa: BLE001 - the script's error is the result
        status, error = "error", describe(e)
    emit("exit", status=status, error=error, testResult=encode_result(getattr(g, "testResult", None)))
    f.close()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)                                  # no interpreter shutdown: threads, renderers


if __name__ == "__main__":
    main(sys.argv[1:])
