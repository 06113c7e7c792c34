"""Shared fixtures: one solved hose for the export tests."""

import pytest

from hoseline.demos.thesis_hose import demo_problem
from hoseline.procedures.placement.sequence import solve


@pytest.fixture(scope="session")
def twisted_hose():
    """The thesis brake hose of the demo at 180 degrees of twist (100 segments): bent in space and twisted."""
    return solve(demo_problem(180.0))
