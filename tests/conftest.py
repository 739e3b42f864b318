"""Shared pytest configuration: the `slow` marker and a `--quick` flag.

The quick subset is ``pytest tests -m "not slow"``; the full suite is ``pytest tests``.
"""
import numpy as np
import pytest


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: long-running case, excluded from the quick subset")


@pytest.fixture
def rng():
    """A seeded generator so that every 'random' test point is reproducible."""
    return np.random.default_rng(20131122)


def pytest_sessionstart(session):
    """Under ``pytest -n N`` (xdist), each worker compiles its share of the kernel's kinds before
    the tests start, so that no kind is compiled by two workers at once (``tests/precompile.py``)."""
    import os
    import tempfile
    workerinput = getattr(session.config, "workerinput", None)
    if workerinput is None or int(workerinput.get("workercount", 1)) < 2:
        return
    from precompile import precompile
    precompile(os.path.join(tempfile.gettempdir(), f"exudyn_lie_precompile_{workerinput['testrunuid']}"))
