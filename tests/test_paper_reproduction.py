"""The README's reproduction tables are written by ``python -m exudyn_lie paper --readme
README.md`` (the full run) and not edited by hand.

* the block names the command and holds the SHA-256 of its text (checked);
* its verdict counts (overall and per result of the paper, with the models each is
  checked on, and the heavy top's E(0)) equal those of a fresh evaluation of the quick
  command's runs (``_paper_support.lie_runs``, judged by ``exudyn_lie.apps.paper.evaluate``);
* its Table 1 (MK-RK4 maxima) equals the runs of the quick command (the same runs) at
  dt = 1e-2 and 1e-3;
* (slow) the command itself, ``--quick --out <tmp>``, writes REPRODUCTION.md with a valid
  header, the same verdict counts, and reproduces the README's Tables 1-3 at the common
  step sizes.

Cells are compared exactly when both are above 1e-10 and agree to the printed digits
on this machine; to stay valid on another CPU (different rounding in compiled code,
and chaotic pendulums at dt = 1e-2) the assertion allows one decade, and round-off
cells (<= 1e-10) only need to be round-off in both.
"""
import functools
import os
import subprocess
import sys

import numpy as np
import pytest

from _paper_support import DTS, README, ROOT, lie_runs
from exudyn_lie.apps.generated import check_hash, read_block, replace_block, with_header
from exudyn_lie.apps.report import (cell, measure_rows, parse_cell, parse_tables, parse_verdict_summary,
                                        verdict_summary)
from exudyn_lie.apps import versions
from exudyn_lie.apps.paper import README_BLOCK, Context, evaluate


def same(a, b):
    (x, fx, _), (y, fy, _) = parse_cell(a), parse_cell(b)
    if fx != fy:
        return False
    if np.isnan(x) or np.isnan(y):
        return np.isnan(x) and np.isnan(y)
    if x <= 1e-10 or y <= 1e-10:
        return x <= 1e-10 and y <= 1e-10
    return abs(np.log10(x / y)) <= 1.0


def readme_tables():
    """The body of the README's generated block (checked for edits)."""
    with open(README, encoding="utf-8") as f:
        block = read_block(f.read(), README_BLOCK)
    assert block is not None, "README.md has no generated paper block: run `python -m exudyn_lie paper --readme README.md`"
    cmd, ok, body = block
    assert cmd.startswith("python -m exudyn_lie paper") and "--readme README.md" in cmd, cmd
    assert "--quick" not in cmd, "the README's tables must come from the full run (dt down to 1e-4)"
    assert ok, "the README's paper block was edited after generation (hash mismatch): regenerate it"
    return body


def test_readme_block_is_unedited_output_of_the_command():
    assert "T1:heavy_top" in readme_tables()


def test_hash_detects_edits():
    text = with_header("python -m exudyn_lie paper", "# title\n| a | b |\n")
    assert check_hash(text) == (True, "python -m exudyn_lie paper")
    assert not check_hash(text.replace("| a |", "| x |"))[0]
    readme = replace_block("intro\n", "paper", "python -m exudyn_lie paper", "| a | b |\n")
    assert read_block(readme, "paper")[1]
    assert not read_block(readme.replace("| a |", "| x |"), "paper")[1]
    assert read_block(replace_block(readme, "paper", "cmd", "new\n"), "paper") == ("cmd", True, "new\n")


@functools.lru_cache(maxsize=None)
def fresh_quick_verdicts():
    """The verdict summary of a fresh quick evaluation (dt = 1e-2, 1e-3) of the runs of
    ``python -m exudyn_lie paper --quick``, judged by the command's own code."""
    ctx = Context(command="python -m exudyn_lie paper --quick", dts=DTS, jobs=1, versions=versions())
    runs = lie_runs()
    ctx.infos = [runs[n][0] for n in runs]
    ctx.results = {n: dict(runs[n][1]) for n in runs}
    evaluate(ctx)
    text = "\n".join(verdict_summary(ctx.infos, ctx.verdicts, ctx.heavyTop, ctx.versions))
    return parse_verdict_summary(text), ctx


def test_readme_verdicts_match_a_fresh_quick_run():
    """The README's verdict table (counts overall and per result of the paper, the models
    each result is checked on, the heavy top's E(0)) equals a fresh evaluation."""
    old = parse_verdict_summary(readme_tables())
    assert old is not None, "the README block has no verdict summary"
    new, ctx = fresh_quick_verdicts()
    assert new["claims"] == len(ctx.verdicts) > 30
    assert old["claims"] == new["claims"], (old["claims"], new["claims"])
    assert old["counts"] == new["counts"], (old["counts"], new["counts"])
    assert old["rows"] == new["rows"], {k: (old["rows"].get(k), new["rows"].get(k))
                                        for k in set(old["rows"]) | set(new["rows"])
                                        if old["rows"].get(k) != new["rows"].get(k)}


def test_failed_runs_cannot_be_read_as_values():
    """A run that stopped early shows 'failed' first, and no number at all when not one
    step succeeded."""
    from exudyn_lie.apps.runs import RunData
    rd = RunData("m", "GeneralizedAlpha", 1e-2, False, "Newton", 0.0, np.array([0.0]), native=True)
    assert cell(rd, 0.0) == "failed at t=0"
    rd = RunData("m", "GeneralizedAlpha", 1e-2, False, "Newton", 0.0, np.zeros(0), native=True)
    assert cell(rd, float("nan")) == "failed at t=0"
    rd = RunData("m", "GeneralizedAlpha", 1e-2, False, "Newton", 0.0, np.array([0.0, 0.01, 0.02]), native=True)
    c = cell(rd, 2.5e-9)
    assert c.startswith("failed at t=0.02") and "2.50e-09" in c
    assert parse_cell(c)[1:] == (True, 0.02) and parse_cell("failed at t=0")[1:] == (True, 0.0)
    rd.ok = True
    assert cell(rd, 0.0) == "0" and parse_cell("0") == (0.0, False, None)


def test_readme_table1_matches_the_runs():
    cells = parse_tables(readme_tables())
    n = exact = 0
    for name, (info, runs) in lie_runs().items():
        for label, meas, get in measure_rows(info):
            for g in ("SE3", "SO3xR3"):
                for dt in DTS:
                    key = ("T1", name, label, meas, f"{g} dt={dt:g}")
                    assert key in cells, f"{key} missing from the README's Table 1"
                    mine = cell(runs[(g, dt)], get(runs[(g, dt)]))
                    assert same(cells[key], mine), (key, cells[key], mine)
                    n += 1
                    exact += cells[key] == mine
    assert n > 100
    print(f"{exact}/{n} cells identical")


@pytest.mark.slow
def test_quick_command_regenerates_the_tables(tmp_path):
    out = tmp_path / "paper"
    env = dict(os.environ)
    env["PYTHONPATH"] = ROOT + os.pathsep + env.get("PYTHONPATH", "")
    proc = subprocess.run([sys.executable, "-m", "exudyn_lie", "paper", "--quick", "--out", str(out)],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "[22/22]" in proc.stdout                       # progress was shown
    text = (out / "REPRODUCTION.md").read_text(encoding="utf-8")
    ok, cmd = check_hash(text)
    assert ok and cmd == f"python -m exudyn_lie paper --quick --out {out}"
    assert len(list(out.glob("*.png"))) >= 30
    assert "## Cross-check through exl.SolveDynamic" in text
    assert parse_verdict_summary(text) == parse_verdict_summary(readme_tables()) == fresh_quick_verdicts()[0]
    new, old = parse_tables(text), parse_tables(readme_tables())
    assert {k[0] for k in new} == {"T1", "T2", "T3"}
    common = [k for k in new if k in old]
    assert len(common) == len(new), "the quick run has cells the README lacks"
    bad = [(k, old[k], new[k]) for k in common if not same(old[k], new[k])]
    assert not bad, bad[:10]
    print(f"{sum(old[k] == new[k] for k in common)}/{len(common)} cells identical")
