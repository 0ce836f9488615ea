"""Shared pytest configuration: registers the markers used by the tests."""

from __future__ import annotations


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "slow: a test that takes more than ~10 s (deselect with -m 'not slow')")
    config.addinivalue_line(
        "markers", "openfoam: a test that runs OpenFOAM (the quick subset deselects them: "
                   "./Alltest -m 'not openfoam and not slow')")
