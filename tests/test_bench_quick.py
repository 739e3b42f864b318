"""The bench machinery on a tiny --quick configuration (functional checks only: no
timing is asserted).

The runs on worker processes go through a child process of their own: Exudyn's
ParameterVariation forks, and a fork of a pytest-xdist worker (which has execnet's
thread) can deadlock on a lock that thread held."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from exudyn_lie.apps import bench
from exudyn_lie.apps import bench_runs as BR
from exudyn_lie.apps import bench_wp as WP

# not in the quick subset (pytest -m "not slow"): runs the bench command's sections
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    argv = ["--quick", "--models", "heavytop", "--sections", "wp,perstep,scaling", "--chain", "1,3",
            "--methods", "RK4,RK6", "--groups", "SE3,SO3xR3", "--rounds", "2", "--jobs", "2",
            "--out", str(out), "--no-progress"]
    run = subprocess.run([sys.executable, "-m", "exudyn_lie", "bench", *argv],
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    return out, argv


def test_writes_table_with_command_header(quick_run):
    out, argv = quick_run
    text = (out / "BENCHMARKS.md").read_text()
    assert text.startswith("# exudyn_lie benchmarks")
    assert "`python -m exudyn_lie bench " + " ".join(argv) + "`" in text
    for section in ("## Targets", "## 1. Work-precision", "## 2. Cost per step", "## 3. Scaling",
                    "## 7. Profile and optimisation record", "_nrt=False"):
        assert section in text
    assert "ParameterVariation" in text


def test_plots_exist(quick_run):
    out, _ = quick_run
    for name in ("wp_heavytop.png", "scaling.png"):
        p = out / "bench_figures" / name
        assert p.exists() and p.stat().st_size > 5000
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_error_decreases_with_step(quick_run):
    out, _ = quick_run
    data = json.loads((out / "bench_results.json").read_text())
    comps = data["models"]["heavytop"]["comps"]
    labels = {c["label"] for c in comps}
    assert {"RK4 SE3", "RK6 SO3xR3", "GeneralizedAlpha", "TrapezoidalIndex2"} <= labels
    for c in comps:
        runs = [r for r in c["runs"] if r["ok"]]
        assert len(runs) >= 3, c["label"]
        runs.sort(key=lambda r: r["steps"])
        errs = [r["error"] for r in runs]
        # refining the step reduces the error (until the reference floor)
        assert errs[-1] < 1e-2 * errs[0], (c["label"], errs)
        for a, b in zip(errs[:-1], errs[1:]):
            assert b < a or b < 1e-11, (c["label"], errs)
        for r in runs:
            assert len(r["times"]) >= 3 and r["time"] > 0


def test_per_step_and_scaling_recorded(quick_run):
    out, _ = quick_run
    data = json.loads((out / "bench_results.json").read_text())
    for h in ("0.001", "0.0001"):
        ps = data["perstepSummary"]["heavytop"][h]
        for k in ("RK4 SE3", "RK4 SO3xR3", "GeneralizedAlpha", "TrapezoidalIndex2"):
            assert ps[k]["ok"] and ps[k]["us"] > 0
    rows = data["scaling"]["rows"]
    assert set(rows) == {"1", "3"}
    for row in rows.values():
        assert row["exl"]["ok"] and row["GA"]["ok"]


def test_sweep_uses_worker_processes_and_keeps_order():
    cases = [dict(kind="exl", model="heavytop", solver="RK4", group=g, T=0.01, nsteps=n, repeat=1, tag=i)
             for i, (g, n) in enumerate([("SE3", 5), ("SO3xR3", 10), ("SE3", 20), ("SO3xR3", 40)])]
    code = ("import json, os, sys; from exudyn_lie.apps import bench_runs as BR; "
            "res = BR.sweep(json.loads(sys.argv[1]), jobs=2); "
            "print(json.dumps(dict(pid=os.getpid(), res=res), default=lambda a: a.tolist()))")
    run = subprocess.run([sys.executable, "-c", code, json.dumps(cases)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    out = json.loads(run.stdout.strip().splitlines()[-1])
    res = out["res"]
    assert [r["case"]["tag"] for r in res] == [0, 1, 2, 3]
    assert all(r["ok"] for r in res)
    assert all(r["pid"] != out["pid"] for r in res)
    serial = BR.sweep(cases[:2], jobs=1)
    np.testing.assert_allclose(serial[1]["r"], res[1]["r"], rtol=0, atol=0)


def test_failed_run_is_a_data_point():
    r = BR.run_case(dict(kind="native", model="heavytop", solver="RK44", T=0.01, nsteps=2, repeat=1))
    assert not r["ok"] and "Error" in r["message"]       # Exudyn's explicit solvers refuse joints


def test_time_to_accuracy_interpolates_on_the_pareto_front():
    pts = [(1e-2, 1.0), (1e-4, 10.0), (1e-6, 100.0), (1e-3, 50.0)]     # (1e-3, 50) is dominated
    assert WP.pareto(pts) == [(1e-2, 1.0), (1e-4, 10.0), (1e-6, 100.0)]
    t, flag = WP.time_to_accuracy(pts, 1e-3)
    assert flag == "interp" and t == pytest.approx(10 ** 0.5)
    assert WP.time_to_accuracy(pts, 1e-1) == (1.0, "upper")
    t, flag = WP.time_to_accuracy(pts, 1e-8)
    assert np.isnan(t) and flag == "not reached"
    assert WP.observed_order([(1e-2, 1e-4), (1e-3, 1e-8)]) == pytest.approx(4.0)
    # second-order curve: time x 10 per 2 decades of error -> extrapolate along it
    curve = [(1e-2, 1.0), (1e-4, 10.0)]
    assert WP.extrapolate_time(curve, 1e-6) == pytest.approx(100.0)
    assert np.isnan(WP.extrapolate_time(curve, 1e-3))         # already reached: no extrapolation
    assert np.isnan(WP.extrapolate_time(curve, 1e-9))         # more than 3 decades away
    assert WP.fit_exponent([1, 10, 100], [2, 20, 200]) == pytest.approx(1.0)


def test_rotation_angle_is_accurate_for_tiny_angles():
    from exudyn_lie.groups import so3
    R = so3.exp(np.array([0.3, -0.2, 0.5]))
    dR = so3.exp(np.array([1e-10, 0, 0]))
    assert WP.rotation_angle(R, R @ dR) == pytest.approx(1e-10, rel=1e-5)


def test_model_names_resolve():
    assert BR.resolve_model("heavy_top") == "heavytop"
    assert BR.resolve_model("spherical_double_pendulum") == "doublependulum"
    assert BR.resolve_model("chain12") == "chain12"
    with pytest.raises(KeyError):
        BR.resolve_model("nosuchmodel")


def test_overhead_and_group_sections(tmp_path):
    """The bridge-overhead and group-map sections run and report (no timing asserted)."""
    readme = tmp_path / "README.md"
    readme.write_text("intro\n")
    argv = ["--quick", "--sections", "overhead,groups", "--out", str(tmp_path), "--no-progress",
            "--readme", str(readme)]
    assert bench.main(argv) == 0
    data = json.loads((tmp_path / "bench_results.json").read_text())
    ov = data["overhead"]
    assert 0 < ov["kernel"] < ov["none"]
    for d in ov["periods"].values():
        for key in ("sensor", "sensor+file"):
            # shares, not timings: with ~1 us per output the order of 'none' and 'bridge'
            # is left to the machine's noise in a short run
            row = d[key]
            assert row["bridge"] > 0 and row["exudyn"] > 0
            assert row["outputs"] == pytest.approx((row["bridge"] - ov["none"]) / row["bridge"])
    assert set(data["groups"]) == {"0.05", "1.0", "3.0"} and all(v > 0 for v in data["groups"].values())
    text = (tmp_path / "BENCHMARKS.md").read_text()
    assert "## 5. Bridge overhead" in text and "## 6. Group maps" in text
    from exudyn_lie.apps.generated import read_block
    cmd, ok, body = read_block(readme.read_text(), "bench")
    assert ok and cmd.startswith("python -m exudyn_lie bench --quick") and "SolveDynamic bridge: sensor machinery" in body


def _comp(kind, solver, runs, group=None):
    """A bench competitor with given (h, error, time) runs."""
    c = bench.Competitor("m", kind, solver, group)
    for k, (h, e, t) in enumerate(runs):
        c.results[k] = dict(ok=True, h=h, time=t)
        c.errors[k] = e
    return c


def test_not_reached_ratio_is_a_lower_bound_from_the_shortest_native_run():
    # exudyn_lie reaches 1e-8 in 0.01 s; native A stops at 1e-3 after 1 s, native B at 1e-5
    # after 10 s: the fastest native needs > 1 s (A needs > 1 s, B > 10 s), so the ratio is > 100
    exl = _comp("exl", "RK4", [(1e-2, 1e-3, 1e-4), (1e-3, 1e-9, 1e-2)], "SE3")
    na = _comp("native", "GeneralizedAlpha", [(1e-3, 1e-2, 0.1), (1e-4, 1e-3, 1.0)])
    nb = _comp("native", "TrapezoidalIndex2", [(1e-4, 1e-4, 1.0), (1e-5, 1e-5, 10.0)])
    summ = bench.summarize_wp(None, {"m": dict(comps=[exl, na, nb])})["m"]
    row = next(r for r in summ if r["eps"] == 1e-8)
    assert row["ratioBound"] == ">"
    t_exl = WP.time_to_accuracy(exl.points(), 1e-8)[0]
    assert row["ratio"] == pytest.approx(1.0 / t_exl)


def test_native_reference_check_detects_a_floor():
    # errors falling at order 2: Exudyn converges to the reference
    conv = WP.native_reference_check({"GeneralizedAlpha": [(1e-3, 4e-4), (5e-4, 1e-4), (2.5e-4, 2.5e-5)]})
    assert conv["converges"] and conv["order"] == pytest.approx(2.0) and conv["err"] == 2.5e-5
    # a model difference of 1e-4 puts a floor under the native errors: detected
    floor = WP.native_reference_check({"GeneralizedAlpha": [(1e-3, 5e-4), (5e-4, 2.0e-4), (2.5e-4, 1.3e-4)]})
    assert not floor["converges"]
    # the solver with the smallest error is the one reported
    two = WP.native_reference_check({"GeneralizedAlpha": [(1e-3, 4e-4), (5e-4, 1e-4)],
                                     "RK44": [(1e-3, 1e-8), (5e-4, 6.25e-10)]})
    assert two["solver"] == "RK44" and two["nominal"] == 4
    assert WP.native_reference_check({"GeneralizedAlpha": [(1e-3, 4e-4)]}) is None


def test_heavy_top_reference_agrees_with_exudyn(quick_run):
    """The reference (exudyn_lie RK6) is checked by Exudyn's own solvers: their errors
    against it still fall at their order, so the package and Exudyn integrate the same model."""
    out, _ = quick_run
    data = json.loads((out / "bench_results.json").read_text())
    rn = data["models"]["heavytop"]["refNative"]
    assert rn["converges"], rn
    assert rn["order"] > 1.5 and rn["err"] < 1e-4, rn


def test_items_section(tmp_path):
    """The point-mass-against-rigid-body section runs and reports (no timing asserted)."""
    readme = tmp_path / "README.md"
    readme.write_text("intro\n")
    argv = ["--quick", "--sections", "items", "--out", str(tmp_path), "--no-progress", "--readme", str(readme)]
    assert bench.main(argv) == 0
    data = json.loads((tmp_path / "bench_results.json").read_text())
    ps = data["items"]["perstep"]
    assert set(ps) == {f"{k}/{v}" for k in ("point", "SE3", "SO3xR3") for v in ("springs", "distance")}
    assert all(np.isfinite(x) for x in ps.values())
    assert "## 9. Point masses against rigid bodies" in (tmp_path / "BENCHMARKS.md").read_text()
