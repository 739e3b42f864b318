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


# ---------------------------------------------------------------- kinds compiled before the tests (tests/precompile.py)
@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node):
    """Controller of ``pytest -n N``: one directory for the workers' claims of the kernel's kinds."""
    import tempfile
    config = node.config
    if not hasattr(config, "_exudyn_lie_precompile"):
        config._exudyn_lie_precompile = tempfile.mkdtemp(prefix="exudyn_lie_precompile_")
    node.workerinput["exudyn_lie_precompile"] = config._exudyn_lie_precompile


def pytest_unconfigure(config):
    import shutil
    d = getattr(config, "_exudyn_lie_precompile", None)
    if d is not None:
        shutil.rmtree(d, ignore_errors=True)


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(session, config, items):
    """A worker of ``pytest -n N`` (N >= 2) compiles its share of the kernel's kinds once its tests
    are selected, so that no kind is compiled by two workers at once: only for runs of at least
    ``precompile.MIN_TESTS`` tests, not with ``--collect-only``, not with
    ``EXUDYN_LIE_TEST_PRECOMPILE=0``."""
    import os
    import sys
    from precompile import MIN_TESTS, precompile
    d = getattr(config, "workerinput", {}).get("exudyn_lie_precompile")
    if (d is None or int(config.workerinput.get("workercount", 1)) < 2 or len(items) < MIN_TESTS
            or config.option.collectonly or os.environ.get("EXUDYN_LIE_TEST_PRECOMPILE") == "0"):
        return
    precompile(d, log=lambda line: print(line, file=sys.stderr, flush=True))
