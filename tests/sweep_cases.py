"""Sweeps shared by the sweep tests: a coarse version of the built-in demo, solved once per test module."""

import pytest

from hoseline.procedures.sweep.quasi_static import run_sweep
from hoseline.report.sweep_report import write_sweep_report
from hoseline.demos.sweep import demo_sweep

SEGMENTS = 20


def coarse_demo():
    """The demo sweep with 20 segments and a pose every 5 degrees / 5 mm."""
    return demo_sweep(steps_per_degree=0.2, segments=SEGMENTS)


@pytest.fixture(scope="module")
def small_sweep_result():
    return run_sweep(coarse_demo())


@pytest.fixture(scope="module")
def small_sweep_report(small_sweep_result, tmp_path_factory):
    """The report folder of the coarse demo sweep."""
    return write_sweep_report(small_sweep_result, tmp_path_factory.mktemp("sweep") / "out", "# input echo test\n")

