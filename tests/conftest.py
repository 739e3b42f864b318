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
