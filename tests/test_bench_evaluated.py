"""The bench section ``evaluated`` runs with --quick and reports (no timing asserted: speed
targets live in the bench report, not in tests)."""
import json

import numpy as np
import pytest

from exudyn_lie.apps import bench


@pytest.mark.slow
def test_evaluated_section_runs_and_reports(tmp_path):
    argv = ["--quick", "--sections", "evaluated", "--out", str(tmp_path), "--no-progress"]
    assert bench.main(argv) == 0
    data = json.loads((tmp_path / "bench_results.json").read_text())
    ev = data["evaluated"]
    assert set(ev["rows"]) == {"1", "10", "50"}
    for r in ev["rows"].values():
        assert not r["errors"], r["errors"]
        for key in ("evaluated", "compiled", "native", "calls"):
            assert np.isfinite(r[key]) and r[key] > 0
    assert np.isfinite(ev["exponent"])
    text = (tmp_path / "BENCHMARKS.md").read_text()
    assert "## Exudyn-evaluated path" in text and "Exudyn-evaluated path: overhead per stage" in text
