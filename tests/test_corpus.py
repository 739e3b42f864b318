"""``python -m exudyn_lie corpus``: ordinary Exudyn scripts, unedited, run natively and through
``exudyn_lie.SolveDynamic`` in child processes, and classified.

Three small scripts in the style of Exudyn's TestModels (``exudynTestGlobals`` from
``modelUnitTests``, ``useGraphics``, ``testResult``): a rigid pendulum on a revolute joint
(supported; written at three step sizes), a slider with a velocity-level coordinate constraint (refused by both paths) and a
script with an error of its own (a name Exudyn 1.13.6 no longer exports)."""
import json
import math

import pytest

from exudyn_lie.apps import corpus

HEADER = '''import exudyn as exu
from exudyn.utilities import *
import numpy as np

useGraphics = True
try:
    from modelUnitTests import exudynTestGlobals
    useGraphics = exudynTestGlobals.useGraphics
except:
    class ExudynTestGlobals:
        pass
    exudynTestGlobals = ExudynTestGlobals()

SC = exu.SystemContainer()
mbs = SC.AddSystem()
'''

# a 1 m bar (1000 kg/m^3, 0.1 x 0.1 m) on a revolute joint at its end, released horizontally;
# testResult: x + y of the free end after 1 s
PENDULUM = HEADER + '''
L = 1
oGround = mbs.CreateGround(referencePosition=[0, 0, 0])
oBar = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [L, 0.1, 0.1]), referencePosition=[L/2, 0, 0],
                           gravity=[0, -9.81, 0])
mbs.CreateRevoluteJoint(itemNumbers=[oGround, oBar], position=[0, 0, 0], axis=[0, 0, 1])
mbs.Assemble()

simulationSettings = exu.SimulationSettings()
simulationSettings.timeIntegration.endTime = 1
simulationSettings.timeIntegration.numberOfSteps = {steps}
simulationSettings.timeIntegration.verboseMode = 0
if useGraphics:
    SC.renderer.Start()
    SC.renderer.DoIdleTasks()
mbs.SolveDynamic(simulationSettings)
if useGraphics:
    SC.renderer.Stop()

p = mbs.GetObjectOutputBody(oBar, exu.OutputVariableType.Position, localPosition=[L/2, 0, 0])
exudynTestGlobals.testResult = p[0] + p[1]
'''

DISC = HEADER + '''
# a block on a slider whose velocity is prescribed by a velocity-level ObjectConnectorCoordinateVector: Exudyn
# evaluates the model (the compiled kernel has no ObjectConnectorCoordinateVector), and that path refuses
# velocity-level constraints other than ObjectConnectorCoordinate's
oGround = mbs.CreateGround(referencePosition=[0, 0, 0])
oBlock = mbs.CreateRigidBody(inertia=InertiaCuboid(1000, [0.1, 0.1, 0.1]), referencePosition=[0, 0, 0],
                             initialVelocity=[1, 0, 0], gravity=[0, -9.81, 0])
nBlock = mbs.GetObject(oBlock)['nodeNumber']
nG = mbs.AddNode(NodePointGround())
mG = mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=nG))
mX = mbs.AddMarker(MarkerNodeCoordinates(nodeNumber=nBlock))
mbs.AddObject(ObjectConnectorCoordinateVector(markerNumbers=[mG, mX], scalingMarker0=np.zeros((1, 0)),
              scalingMarker1=np.array([[1, 0, 0, 0, 0, 0, 0]]), offset=[1], velocityLevel=True))
mbs.Assemble()
simulationSettings = exu.SimulationSettings()
simulationSettings.timeIntegration.endTime = 0.1
simulationSettings.timeIntegration.numberOfSteps = 10
exu.SolveDynamic(mbs, simulationSettings)
exudynTestGlobals.testResult = mbs.GetObjectOutputBody(oBlock, exu.OutputVariableType.Position,
                                                       localPosition=[0, 0, 0])[0]
'''

BROKEN = HEADER + '''
background = GraphicsDataRectangle(-1, -1, 1, 1, color4blue)   # dropped after Exudyn 1.11
mbs.SolveDynamic(exu.SimulationSettings())
'''

STEPS = (100, 200, 400)          # h = 10, 5, 2.5 ms


@pytest.fixture(scope="module")
def corpus_run(tmp_path_factory):
    src = tmp_path_factory.mktemp("scripts")
    for n in STEPS:
        (src / f"pendulumRevolute{n}.py").write_text(PENDULUM.format(steps=n))
    (src / "velocityLevelSlider.py").write_text(DISC)
    # an Example: no testResult (the corpus compares the final states)
    (src / "pendulumExample.py").write_text(PENDULUM.format(steps=STEPS[0]).split("p = mbs.GetObjectOutputBody")[0])
    (src / "brokenScript.py").write_text(BROKEN)
    out = src / "results"
    lines = []
    records = corpus.run_corpus(corpus.collect_scripts([str(src)]), out, timeout=120, jobs=1, log=lines.append)
    assert corpus.main([str(src), "--out", str(out), "--match", "brokenScript.py"]) == 0  # the command line
    return {r["name"]: r for r in records}, lines, out


def test_every_script_reports_one_progress_line(corpus_run):
    records, lines, _ = corpus_run
    assert len(lines) == len(records) == len(STEPS) + 3
    assert all(any(name in line for line in lines) for name in records)


def test_script_error_is_a_native_failure_and_no_exl_run(corpus_run):
    r = corpus_run[0]["brokenScript.py"]
    assert r["native"]["status"] == "error"
    assert r["native"]["error"]["cls"] == "NameError"
    assert "GraphicsDataRectangle" in r["native"]["error"]["msg"]
    assert r["dynamic"] == "not reached"
    assert r["exl"] is None and r["exlStatus"] is None


def test_unsupported_item_is_refused_and_named(corpus_run):
    r = corpus_run[0]["velocityLevelSlider.py"]
    assert r["native"]["status"] == "ok" and r["dynamic"] == "yes"
    assert isinstance(r["testResult"][0], float)            # the native run set it
    assert r["exlStatus"] == "refused"
    assert r["exl"]["solves"][0]["exl"] == "refusal"
    assert r["exlReason"].startswith("BridgeError: ")
    assert r["firstRefusal"] == "ObjectConnectorCoordinateVector: velocityLevel=True"
    assert r["testResult"][1] is None                        # the script stopped at the solve
    assert "ObjectConnectorCoordinateVector" in r["inventory"] and "ObjectRigidBody" in r["inventory"]


def test_supported_pendulum_agrees_with_native_to_the_native_step_error(corpus_run):
    """exl (MK-RK4) and native (generalized-alpha, 2nd order) at the script's step h differ by
    both global errors.  The native one is estimated by Richardson extrapolation from the
    same script at h/2, h/4: e_n(h) = (4/3) |n(h) - n(h/2)|, valid when the observed ratio
    |n(h) - n(h/2)| / |n(h/2) - n(h/4)| is near 2^2 (checked); exl's likewise with the
    4th-order factor 16/15.  The factor 2 covers the O(h^3) remainder of the estimates."""
    records = corpus_run[0]
    n, x = {}, {}
    for steps in STEPS:
        r = records[f"pendulumRevolute{steps}.py"]
        assert r["native"]["status"] == "ok" and r["exlStatus"] == "ok", r
        n[steps], x[steps] = r["testResult"]
        assert r["relDiff"] == pytest.approx(abs(x[steps] - n[steps]) / max(abs(x[steps]), abs(n[steps])), rel=1e-12)
    h, h2, h4 = STEPS
    ratio = abs(n[h] - n[h2]) / abs(n[h2] - n[h4])
    assert 3.5 < ratio < 4.5, f"native not in its 2nd-order regime: ratio {ratio}"
    e_native = 4 / 3 * abs(n[h] - n[h2])
    e_exl = 16 / 15 * abs(x[h] - x[h2])
    assert abs(x[h] - n[h]) <= 2 * (e_native + e_exl)
    # and exl at the coarse step is the converged answer as far as native can tell: it matches
    # the extrapolated native value far better than native's own error at that step
    n_extrapolated = n[h4] + (n[h4] - n[h2]) / 3
    assert abs(x[h] - n_extrapolated) <= 1e-2 * e_native
    assert math.isfinite(e_native) and e_native > 0


def test_fine_native_reference_has_k_times_the_steps(corpus_run):
    """Where exl ran, the corpus also runs the script natively with numberOfSteps x 10: its
    error (2nd order) is that of the script's step / 10^2, measured against the native value
    extrapolated from h/2 and h/4; exl at the script's step is closer to it than native."""
    records = corpus_run[0]
    n = {k: records[f"pendulumRevolute{k}.py"]["testResult"][0] for k in STEPS}
    h, h2, h4 = STEPS
    n_extrapolated = n[h4] + (n[h4] - n[h2]) / 3
    e_native = 4 / 3 * abs(n[h] - n[h2])
    r = records[f"pendulumRevolute{h}.py"]
    assert r["fineFactor"] == 10 and r["fine"]["status"] == "ok"
    assert abs(r["testResultFine"] - n_extrapolated) <= 2 * e_native / 10**2
    for k in STEPS:
        r = records[f"pendulumRevolute{k}.py"]
        assert r["relDiffFine"] < r["relDiffNativeFine"]
    assert records["velocityLevelSlider.py"]["fine"] is None and records["brokenScript.py"]["fine"] is None


def test_report_files(corpus_run):
    records, _, out = corpus_run
    data = json.loads((out / "corpus.json").read_text())       # written by main (one script)
    assert [r["name"] for r in data["scripts"]] == ["brokenScript.py"]
    assert data["summary"]["native"]["error"] == 1
    s = corpus.summarize(list(records.values()))
    assert s["scripts"] == len(STEPS) + 3 and s["base"] == len(STEPS) + 2
    assert s["exl"]["ok"] == len(STEPS) + 1 and s["exl"]["refused"] == 1 and s["exl"]["crashed"] == 0
    assert s["firstRefusal"] == {"ObjectConnectorCoordinateVector: velocityLevel=True": 1}
    assert s["fineReferences"] == len(STEPS) and s["exlCloserToFine"] == len(STEPS)
    text = corpus.render(list(records.values()), s, "test", 0.0, 120)
    assert "| `ObjectConnectorCoordinateVector: velocityLevel=True` | 1 |" in text
    assert "`brokenScript.py`" in (out / "corpus.md").read_text()


def test_scripts_without_test_result_are_compared_by_their_final_states(corpus_run):
    """Exudyn's Examples set no testResult: the corpus compares the final ODE2 coordinates of
    every solve (relative to the state's largest entry) against the fine native run.  The
    pendulum example: exudyn_lie at the script's step is closer to native at 10x the steps
    than native at the script's step (RK4 against generalized-alpha's 2nd order), and it is
    not a run to look at."""
    r = corpus_run[0]["pendulumExample.py"]
    assert r["testResult"] == [None, None] and r["relDiff"] is None
    assert r["exlStatus"] == "ok" and r["fine"]["status"] == "ok"
    assert 0 < r["stateDiffFine"] < r["stateDiffNativeFine"] < 1e-2
    assert r["stateDiff"] == pytest.approx(r["stateDiffNativeFine"], rel=0.5)
    assert not corpus.suspect(r)
    s = corpus.summarize(list(corpus_run[0].values()))
    assert s["statePairs"] == len(STEPS) + 1 and s["suspects"] == []


def test_state_difference_and_suspects():
    """The state comparison pairs solves by number, skips failed ones and states of another
    size, and takes the worst pair; a run is one to look at only when it is off by more than
    1e-3 and by more than 10x native's own difference."""
    a = _run(solves=[dict(n=1, status="ok", state=[1.0, 2.0]), dict(n=2, status="ok", state=[0.0, 4.0])])
    b = _run(solves=[dict(n=1, status="ok", state=[1.0, 2.2]), dict(n=2, status="ok", state=[0.0, 4.0, 1.0])])
    assert corpus.state_difference(a, b) == pytest.approx(0.2 / 2.2)
    b["solves"][0]["status"] = "error"
    assert corpus.state_difference(a, b) is None
    assert corpus.suspect(dict(stateDiffFine=2e-3, stateDiffNativeFine=1e-4))
    assert not corpus.suspect(dict(stateDiffFine=2e-3, stateDiffNativeFine=3e-4))
    assert not corpus.suspect(dict(stateDiffFine=5e-4, stateDiffNativeFine=1e-9))
    assert not corpus.suspect(dict(stateDiffFine=None, stateDiffNativeFine=None))


def _run(status="ok", solves=(), error=None, in_solve=False):
    return dict(status=status, solves=list(solves), error=error, inSolve=in_solve, testResult=None,
                inventory=[], directSolvers=[], wall=0.0)


def _err(cls, msg):
    return dict(cls=cls, module="", msg=msg, where="s.py:3 f", whereExl="", tb="")


@pytest.mark.parametrize("exl_run, expected", [
    (_run(solves=[dict(n=1, status="ok")]), "ok"),
    (_run("error", [dict(n=1, status="error", exl="refusal", error=_err("BridgeError", "object 0 of type X"))],
          _err("BridgeError", "object 0 of type X")), "refused"),
    (_run("error", [dict(n=1, status="error", exl="stop", error=_err("StepSizeError", "h too large"))],
          _err("StepSizeError", "h too large")), "stopped"),
    (_run("error", [dict(n=1, status="error", exl="internal", error=_err("BridgeError", "internal: x"))],
          _err("BridgeError", "internal: x")), "crashed"),
    (_run("error", [dict(n=1, status="error", exl=None, error=_err("KeyError", "3"))], _err("KeyError", "3")),
     "crashed"),
    (_run("error", [dict(n=1, status="ok")], _err("AttributeError", "no it")), "crashed"),     # after the solve
    (_run("error", [dict(n=1, status="ok")], _err("NameError", "name 'VSum' is not defined")), "native error"),
    (_run("error", [dict(n=1, status="error", exl=None, error=_err("ValueError", "user"))],
          _err("ValueError", "user")), "native error"),          # the script's user function, as natively
    (_run("timeout", [dict(n=1, status="running")], in_solve=True), "timeout"),
    (_run("died", [dict(n=1, status="running")], _err("died", "exit code -11"), in_solve=True), "crashed"),
    (_run("bootstrap error", [], _err("ImportError", "no exudyn_lie")), "crashed"),
])
def test_classification_rules(exl_run, expected):
    native = _run("error", [dict(n=1, status="error", error=_err("ValueError", "user"))],
                  _err("NameError", "name 'VSum' is not defined"))
    assert corpus.exl_outcome(native, exl_run)[0] == expected


def test_time_inside_solve_dynamic_is_split_and_summarised(corpus_run):
    """Every script both runs finish has its seconds inside SolveDynamic: native, and
    exudyn_lie's set-up, compilation and time loop, which add up to exudyn_lie's whole call."""
    from exudyn_lie.apps.corpus_timing import script_times
    records, _, _ = corpus_run
    for n in STEPS:
        t = script_times(records[f"pendulumRevolute{n}.py"])
        assert t is not None and t["path"] == "compiled"
        assert t["native"] > 0 and t["loop"] > 0 and t["setup"] > 0 and t["compile"] >= 0
        assert t["setup"] + t["compile"] + t["loop"] == pytest.approx(t["exl"], rel=0.05, abs=0.02)
    assert script_times(records["velocityLevelSlider.py"]) is None         # refused: no ratio
    s = corpus.summarize(list(records.values()))["time"]
    assert s["scripts"] == len(STEPS) + 1
    text = corpus.render(list(records.values()), corpus.summarize(list(records.values())), "test", 0.0, 120)
    assert "## Time inside `SolveDynamic`" in text and "| `pendulumRevolute100.py` | compiled |" in text


def test_scripts_running_at_once_do_not_write_into_each_others_files(tmp_path):
    """With two jobs each works in its own copy of the folder: two scripts that write the same
    relative file (as Exudyn's Examples share ``solution/sensorPos.txt``), wait, and read it back
    both read their own line (in one shared copy the second overwrote the first's file)."""
    src = tmp_path / "scripts"
    src.mkdir()
    body = ("import os, time\nos.makedirs('solution', exist_ok=True)\n"
            "open('solution/shared.txt', 'w').write('{name}')\ntime.sleep(2.0)\n"
            "assert open('solution/shared.txt').read() == '{name}', 'another script wrote here'\n")
    for name in ("writerA", "writerB"):
        (src / f"{name}.py").write_text(body.format(name=name))
    records = corpus.run_corpus(corpus.collect_scripts([str(src)]), tmp_path / "out", timeout=60, jobs=2,
                                log=lambda line: None)
    assert [r["native"]["status"] for r in records] == ["ok", "ok"]
