"""Start-up (issue 19, 3): what a warm first solve loads.

The bench (``python -m exudyn_lie bench --sections startup``) measures the times; this test
checks the mechanism behind them, in fresh interpreters: with numba's cache filled, the first
``SolveDynamic`` loads the compiled kernel without numba's full context refresh (which
imports numba's ``arraymath`` and, through its BLAS probe, ``scipy.linalg``: 0.2 s), and the
kernel's cached code references no function of ``numba.np.arraymath`` (``np.round`` did)."""
import os
import subprocess
import sys

import pytest

pytestmark = pytest.mark.slow

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

SCRIPT = r"""
import sys
import exudyn as exu
import exudyn_lie as exl
from exudyn_lie import models
mbs, info = models.build("heavy_top")
mbs.Assemble()
ss = exu.SimulationSettings()
ss.timeIntegration.numberOfSteps = 10
ss.timeIntegration.endTime = 0.01
ss.solution.file.write = False
ss.solution.sensors.active = False
exl.SolveDynamic(mbs, ss, method="RK4", liegroup="SE3", showProgress=False)
print("LOADED", "scipy.linalg" in sys.modules, "numba.np.arraymath" in sys.modules)
"""


def _run():
    env = dict(os.environ)
    env["PYTHONPATH"] = ROOT + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    p = subprocess.run([sys.executable, "-c", SCRIPT], env=env, cwd=ROOT, capture_output=True, text=True,
                       timeout=1800)
    assert p.returncode == 0, p.stderr[-2000:]
    return [x for x in p.stdout.splitlines() if x.startswith("LOADED")][-1]


def test_warm_first_solve_loads_no_scipy_linalg_nor_numba_arraymath():
    _run()                          # fills numba's cache if it is cold (compiling refreshes the contexts)
    line = _run()
    assert line == "LOADED False False", line


def test_bench_startup_section_reports_the_issue_targets():
    """The bench's start-up harness runs a fresh interpreter and states the issue's targets
    (no timing asserted)."""
    from exudyn_lie.apps import bench_startup as B
    d = B.startup_once("bridge", steps=10)
    assert d["ok"], d.get("message")
    assert d["secondSolve"] > 0 and d["imports"] > 0 and abs(d["firstFixed"] - (d["firstSolve"] - d["secondSolve"])) < 1e-12
    assert 0 < d["numbaImport"] < d["imports"]      # numba's own import, part of exudyn_lie's
    keys = ("wall", "imports", "numbaImport", "importsCpu", "firstSolve", "secondSolve", "firstFixed",
            "firstFixedCpu")
    res = {"bridge": {"cold": dict(d, loadEnd=d["load"]),
                      "warm": dict({k: d[k] for k in keys}, min={k: d[k] for k in keys}, load=d["load"][0])},
           "cores": 2}
    rows = B.target_lines(res)
    assert any(r.startswith("| start-up, warm cache: `import exudyn_lie`") and "<= 0.1 s" in r for r in rows)
    assert any("first solve's fixed cost (bridge path" in r and "<= 0.05 s" in r for r in rows)
    assert any("first run ever" in r and ("<= 20 s" in r or "<= 30 s" in r) for r in rows)
    assert all(r.endswith("| yes |") or r.endswith("| no |") for r in rows)
    assert B.report_lines(res)[0] == "## 4. Start-up"
