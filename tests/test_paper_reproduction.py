"""The reproduction tables of docs/PAPER.md are written by ``python -m exudyn_lie paper --readme
docs/PAPER.md`` (the full run) and not edited by hand.

* the block names the command and holds the SHA-256 of its text (checked);
* its verdict counts (overall and per result of the paper, with the models each is
  checked on, and the heavy top's E(0)) equal those of a fresh evaluation of the quick
  command's runs (``_paper_support.lie_runs``, judged by ``exudyn_lie.apps.paper.evaluate``);
* its Table 1 (MK-RK4 maxima) equals the runs of the quick command (the same runs) at
  dt = 1e-2 and 1e-3, cell by cell as printed above round-off (``cells_agree``);
* (slow) the command itself, ``--out <tmp> --readme <copy of docs/PAPER.md>``, writes
  REPRODUCTION.md with a valid header and one figure per model, and the block it writes
  equals the README's block exactly: the verdicts and Tables 1-3 at every step size,
  dt = 1e-4 included.

The comparisons are exact up to round-off: the runs are deterministic (compiled code,
fixed steps, one process per model), but the sum of roundings in a value differs between
CPUs and compiled code, so two cells agree when their text is the same or their values
differ by at most the round-off bound (``_paper_support.roundoff_bound``: 1e-12 at dt >=
1e-3, 1e-15 per step below, the bound of the paper's exactness verdicts).
"""
import functools
import os
import subprocess
import sys

import numpy as np
import pytest

from _paper_support import DTS, README, ROOT, cells_agree, lie_runs, roundoff_bound
from exudyn_lie.apps.generated import check_hash, read_block, replace_block, with_header
from exudyn_lie.apps.report import (cell, measure_rows, parse_cell, parse_tables, parse_verdict_summary,
                                        verdict_summary)
from exudyn_lie.apps import versions
from exudyn_lie.apps.paper import README_BLOCK, Context, evaluate


def readme_tables():
    """The body of the README's generated block (checked for edits)."""
    with open(README, encoding="utf-8") as f:
        block = read_block(f.read(), README_BLOCK)
    assert block is not None, "docs/PAPER.md has no generated paper block: run `python -m exudyn_lie paper --readme docs/PAPER.md`"
    cmd, ok, body = block
    assert cmd.startswith("python -m exudyn_lie paper") and "--readme docs/PAPER.md" in cmd, cmd
    assert "--quick" not in cmd, "the README's tables must come from the full run (dt down to 1e-4)"
    assert ok, "the README's paper block was edited after generation (hash mismatch): regenerate it"
    return body


def test_readme_block_is_unedited_output_of_the_command():
    cells = parse_tables(readme_tables())
    assert {k[0] for k in cells} == {"T1", "T2", "T3"}
    assert any(k[:2] == ("T1", "heavy_top") for k in cells)


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


def test_cells_agree_above_roundoff_only():
    assert cells_agree("1.23e-03", "1.23e-03", 1e-12)
    assert not cells_agree("1.23e-03", "1.24e-03", 1e-12)           # above round-off: every digit
    assert cells_agree("2.83e-15", "6.94e-15", 1e-12)               # both round-off
    assert not cells_agree("2.83e-15", "6.94e-12", 1e-12)           # one side above the bound
    assert cells_agree("8.01e-11", "8.00e-11", 1e-11)               # apart by less than the round-off
    assert not cells_agree("8.10e-09", "8.00e-09", 1e-11)
    assert not cells_agree("failed at t=0.02 (max 2.50e-15 before)", "2.50e-15", 1e-12)  # a failed run
    assert not cells_agree("x", "x", 1e-12)                         # not a cell at all


def test_readme_table1_matches_the_runs():
    cells = parse_tables(readme_tables())
    n = above = 0
    for name, (info, runs) in lie_runs().items():
        for label, meas, get in measure_rows(info):
            for g in ("SE3", "SO3xR3"):
                for dt in DTS:
                    key = ("T1", name, label, meas, f"{g} dt={dt:g}")
                    assert key in cells, f"{key} missing from the README's Table 1"
                    mine = cell(runs[(g, dt)], get(runs[(g, dt)]))
                    bound = roundoff_bound(info, dt)
                    assert cells_agree(cells[key], mine, bound), (key, cells[key], mine)
                    n += 1
                    above += parse_cell(mine)[0] > bound
    # most cells are above round-off, and those were compared digit by digit
    assert n > 100 and above > n // 2, (n, above)


@pytest.mark.slow
def test_full_command_regenerates_the_readme_block_exactly(tmp_path):
    """The README's block is what the full command writes: run it into a copy of the
    README and compare the two blocks text for text (verdicts, Tables 1-3, dt = 1e-4 too)."""
    out = tmp_path / "paper"
    copy = tmp_path / "PAPER.md"
    with open(README, encoding="utf-8") as f:
        copy.write_text(f.read(), encoding="utf-8")
    env = dict(os.environ)
    env["PYTHONPATH"] = ROOT + os.pathsep + env.get("PYTHONPATH", "")
    proc = subprocess.run([sys.executable, "-m", "exudyn_lie", "paper", "--out", str(out), "--readme", str(copy)],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=1800)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "[22/22]" in proc.stdout                       # progress was shown
    text = (out / "REPRODUCTION.md").read_text(encoding="utf-8")
    ok, cmd = check_hash(text)
    assert ok and cmd == f"python -m exudyn_lie paper --out {out} --readme {copy}"
    from exudyn_lie import models
    assert sorted(p.name for p in out.glob("*.png")) == sorted(f"{m}.png" for m in models.MODELS)
    assert "## Cross-check through exl.SolveDynamic" in text
    new = read_block(copy.read_text(encoding="utf-8"), README_BLOCK)
    assert new is not None and new[1]
    old_body, new_body = readme_tables(), new[2]
    if old_body != new_body:
        old_cells, new_cells = parse_tables(old_body), parse_tables(new_body)
        infos = {name: models.build(name)[1] for name in models.MODELS}
        diff = [(k, old_cells.get(k), new_cells.get(k)) for k in sorted(set(old_cells) | set(new_cells))
                if k not in old_cells or k not in new_cells
                or not cells_agree(old_cells[k], new_cells[k],
                                   roundoff_bound(infos[k[1]], float(k[4].rsplit("dt=", 1)[1])))]
        assert not diff, f"the README block differs from a fresh run above round-off; first differences: {diff[:10]}"
    assert parse_verdict_summary(text) == parse_verdict_summary(old_body)
