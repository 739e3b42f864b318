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
