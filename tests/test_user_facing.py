"""What a new user meets first: the command line, method names, exported errors,
warnings that point at the user's line, the cold-compile notice and the solution-file
header / log of a drop-in solve."""
import importlib.util
import io
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

import exudyn_lie as exl

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _cli(*args):
    r = subprocess.run([sys.executable, "-m", "exudyn_lie", *args], capture_output=True, text=True, cwd=ROOT,
                       timeout=300)
    return r.returncode, r.stdout + r.stderr


def test_cli_version_and_help():
    rc, out = _cli("--version")
    assert rc == 0 and out.startswith(f"exudyn_lie {exl.__version__}, exudyn ")
    rc, out = _cli("--help")
    assert rc == 0 and "COMMAND --help" in out and "--version" in out
    for cmd in ("paper", "bench", "stress"):
        rc, out = _cli(cmd, "--help")
        assert rc == 0 and f"python -m exudyn_lie {cmd}" in out
        assert "``" not in out, f"raw RST markup in '{cmd} --help'"
    rc, out = _cli("nonsense")
    assert rc == 2 and "unknown command 'nonsense'" in out


def test_error_classes_are_exported():
    from exudyn_lie.bridge.reader import BridgeError
    from exudyn_lie.mbs import ConstraintError, SceneError, SimulationError, StepSizeError
    assert exl.BridgeError is BridgeError and issubclass(exl.BridgeError, exl.SceneError)
    assert (exl.SceneError, exl.SimulationError, exl.ConstraintError, exl.StepSizeError) == \
        (SceneError, SimulationError, ConstraintError, StepSizeError)
    for name in ("BridgeError", "SceneError", "SimulationError", "ConstraintError", "StepSizeError",
                 "SolveDynamic", "LieGroupSolver"):
        assert name in exl.__all__ and name in dir(exl)


@pytest.mark.parametrize("name,expected", [("rk4", "RK4"), ("RK44", "RK4"), ("Rk-4", "RK4"), ("RK45", "DOPRI5"),
                                           ("dopri5", "DOPRI5"), ("dormand_prince", "DOPRI5"),
                                           ("explicit euler", "ExplicitEuler"), ("rk6", "RK6")])
def test_method_names_case_insensitive_with_aliases(name, expected):
    assert exl.get_method(name).name == expected


def test_unknown_method_still_refused():
    with pytest.raises(ValueError, match=r"unknown integration method 'RK5'; available: .*RK4"):
        exl.get_method("RK5")


def _heavy_top_settings(endTime, numberOfSteps, verboseMode=0):
    """The paper's heavy top (assembled) and quiet settings."""
    import exudyn as exu
    from exudyn_lie.models import heavy_top
    mbs, info = heavy_top.build()
    mbs.Assemble()
    ss = exu.SimulationSettings()
    ss.timeIntegration.endTime = endTime
    ss.timeIntegration.numberOfSteps = numberOfSteps
    ss.timeIntegration.verboseMode = verboseMode
    ss.solution.file.write = False
    return mbs, ss


def test_solve_dynamic_accepts_lower_case_method_and_logs_it(tmp_path, capsys):
    """Method names as users type them; the solution-file header and the log say what ran:
    method, group, step and the number of steps (not Exudyn's output steps)."""
    mbs, ss = _heavy_top_settings(0.2, 200, verboseMode=1)
    ss.solution.file.write = True
    ss.solution.file.writePeriod = 0.01
    ss.solution.file.name = str(tmp_path / "solution.txt")
    ss.timeIntegration.adaptiveStep = False          # fixed steps (DOPRI5 is adaptive under Exudyn's default)
    assert exl.SolveDynamic(mbs, ss, method="dopri5", liegroup="se3")
    out = capsys.readouterr().out
    assert "Nit/step" not in out                     # Exudyn's Newton count means nothing here
    expected = ("explicit Munthe-Kaas DOPRI5 (order 5, 7 stages), Lie group SE3 (1 body), step size h = 0.001 s, "
                "200 steps from t = 0 to 0.2 s; Exudyn's time loop made 20 steps of 10 integration step(s) each")
    assert expected in out and "200 steps in " in out and "set-up" in out
    header = [line for line in open(ss.solution.file.name) if line.startswith("#")]
    info_lines = [line for line in header if line.startswith("#solution information = ")]
    assert len(info_lines) == 1 and expected in info_lines[0]
    assert "#number of time steps (planned) = 20\n" in header          # Exudyn's own count: its steps


def test_warning_points_at_the_users_line():
    """A warning raised deep inside the package (the simulator's step-size check) names
    the caller's file and line."""
    from exudyn_lie.mbs import GROUND, Scene, Simulator
    sc = Scene()
    b = sc.AddBody(1.0, np.eye(3), r0=[1, 0, 0])
    sc.AddSphericalJoint(GROUND, b, [0, 0, 0])
    sim = Simulator(sc, "RK4", "SE3")
    with pytest.warns(RuntimeWarning, match="is not a multiple of stepSize") as rec:
        line = sys._getframe().f_lineno + 1
        sim.Run(0.01, 0.003)
    assert (rec[0].filename, rec[0].lineno) == (__file__, line)


def _fresh_cached_function(tmp_path, name):
    src = tmp_path / f"{name}.py"
    src.write_text("from numba import njit\n\n@njit(cache=True)\ndef f(x):\n    return 2.0 * x\n")
    spec = importlib.util.spec_from_file_location(name, src)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.f


def test_cold_compile_is_announced_once_and_timed(tmp_path, monkeypatch):
    """A function without numba cache index is cold: one line; once compiled (and cached)
    it is not; the compile timer sees the compilation."""
    from exudyn_lie import compiling
    monkeypatch.setattr(compiling, "_announced", False)
    measured = tmp_path / "cold_compile_seconds.txt"
    monkeypatch.setattr(compiling, "MEASURED_FILE", str(measured))
    monkeypatch.setattr(compiling, "MIN_STORED_SECONDS", 0.0)
    f = _fresh_cached_function(tmp_path, "cold_probe_a")
    assert compiling.cache_is_cold(f)
    buf = io.StringIO()
    assert compiling.announce_cold_compile(f, stream=buf)
    assert buf.getvalue() == (f"exudyn_lie: compiling the solver for this machine, first run only, "
                              f"{compiling.duration_text(compiling.estimated_seconds())}\n")
    assert not compiling.announce_cold_compile(f, stream=buf)          # once per process
    with compiling.compile_timer() as ct:
        assert f(2.0) == 4.0
    assert ct.seconds > 0
    # the compile time up to f's compilation is stored, and later compilations in the
    # process (other scenes, a test session) do not change it
    stored = measured.read_text()
    assert 0.0 < float(stored) <= ct.seconds + 0.05
    (tmp_path / "other").mkdir()
    h = _fresh_cached_function(tmp_path / "other", "cold_probe_b")
    assert h(3.0) == 6.0
    assert measured.read_text() == stored
    assert not compiling.cache_is_cold(f)
    g = _fresh_cached_function(tmp_path, "cold_probe_a")               # same source, new process-like import
    assert not compiling.cache_is_cold(g)                              # the index file exists now
    with compiling.compile_timer() as ct:
        g(1.0)
    assert ct.seconds == 0.0                                           # loaded from the cache


def test_cold_compile_estimate_is_the_last_measured_one(tmp_path, monkeypatch):
    """The notice's "about N s": the default before any cold start on the machine, then the
    compile seconds measured at the last one."""
    from exudyn_lie import compiling
    monkeypatch.setattr(compiling, "MEASURED_FILE", str(tmp_path / "cold_compile_seconds.txt"))
    assert compiling.estimated_seconds() == compiling.COLD_COMPILE_SECONDS
    (tmp_path / "cold_compile_seconds.txt").write_text("41.6\n")
    assert compiling.estimated_seconds() == 42
    (tmp_path / "cold_compile_seconds.txt").write_text("garbage\n")
    assert compiling.estimated_seconds() == compiling.COLD_COMPILE_SECONDS
    assert compiling.duration_text(42) == "about 42 s" and compiling.duration_text(185) == "about 3 min"


def test_kernel_warm_in_the_test_session():
    """After the first solve the kernel is not cold: no notice."""
    from exudyn_lie import compiling
    from exudyn_lie.mbs import GROUND, Scene, Simulator, kernel
    sc = Scene()
    b = sc.AddBody(1.0, np.eye(3), r0=[1, 0, 0])
    sc.AddSphericalJoint(GROUND, b, [0, 0, 0])
    Simulator(sc, "RK4", "SE3").Run(0.01, 0.001)
    assert not compiling.cache_is_cold(kernel.mk_steps)


def test_no_warnings_from_a_plain_solve():
    mbs, ss = _heavy_top_settings(0.1, 100)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert exl.SolveDynamic(mbs, ss, showProgress=False)


def test_every_long_compile_announces_itself_with_its_measured_time(tmp_path, monkeypatch):
    """A compile of a package function that is still running after NOTICE_AFTER says so
    (a variant never compiled here: no estimate yet); its duration is kept per variant, and
    the next compile of the same variant announces itself at once with that time.  Compiles
    of other packages' functions say nothing."""
    import time
    from types import SimpleNamespace

    from exudyn_lie import compiling
    monkeypatch.setattr(compiling, "HISTORY_FILE", str(tmp_path / "compile_seconds.json"))
    monkeypatch.setattr(compiling, "NOTICE_AFTER", 0.05)
    monkeypatch.setattr(compiling, "_coldInProgress", False)

    def kernel_like():
        pass
    kernel_like.__module__ = "exudyn_lie.mbs.probe"
    disp = SimpleNamespace(py_func=kernel_like)
    buf = io.StringIO()
    notices = compiling.CompileNotices(stream=buf)
    notices.on_start({"dispatcher": disp, "args": ("float64",)})
    time.sleep(0.3)                                    # the compile runs longer than NOTICE_AFTER
    notices.on_end({})
    first = buf.getvalue().splitlines()
    assert len(first) == 2 and "kernel_like" in first[0] and "no estimate yet" in first[0], first
    assert first[1].startswith("exudyn_lie: compiled in ")
    key = compiling.variant_key(disp, ("float64",))
    assert 0.3 <= compiling.load_history()[key] < 5
    buf.truncate(0)
    buf.seek(0)
    notices.on_start({"dispatcher": disp, "args": ("float64",)})
    assert "about 0 s (measured here before)" in buf.getvalue()        # at once, before the compile
    notices.on_end({})
    other = SimpleNamespace(py_func=len)                               # builtins: not the package's
    buf.truncate(0)
    buf.seek(0)
    notices.on_start({"dispatcher": other, "args": ()})
    time.sleep(0.2)
    notices.on_end({})
    assert buf.getvalue() == ""
