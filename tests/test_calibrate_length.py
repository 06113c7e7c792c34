"""Calibration of the free length: scans of a hose 3 mm longer than its drawing says."""

from dataclasses import replace

import pytest
from validation_cases import EI, FACTOR, ONE_SIDED, RADIUS, brake_hose

from hoseline.procedures.placement.sequence import solve
from hoseline.procedures.scans.calibration import ScanCase, calibrate
from hoseline.procedures.scans.centerline_fit import fit_centerline
from hoseline.procedures.scans.synthetic_scan import synthetic_scan

NOMINAL = 330.6  # mm, the problem file's length
TRUE_LENGTH = NOMINAL + 3.0


@pytest.fixture(scope="module")
def longer_hose_scans():
    """One-sided noisy scans at 0 and 180 deg of the hose 3 mm longer (truth at 80 segments)."""
    cases = []
    for seed, twist in enumerate((0.0, 180.0)):
        problem = brake_hose(segments=80, twist=twist)
        truth = solve(replace(problem, hose=replace(problem.hose, length=TRUE_LENGTH)), estimate_error=False)
        points = synthetic_scan(truth.s, truth.centerline, RADIUS, ONE_SIDED, seed=seed)
        cases.append(ScanCase(twist, fit_centerline(points, RADIUS, start_hint=problem.start.point).points))
    return cases


def test_length_alone_is_recovered(longer_hose_scans):
    calibration = calibrate(brake_hose(segments=40), longer_hose_scans, ["length"])
    (length,) = calibration.parameters
    assert length.identifiable
    assert length.value == pytest.approx(TRUE_LENGTH, abs=0.16)  # measured: 0.054 mm long
    assert all(after.mean < 0.3 for after in calibration.after)  # measured: 0.09, 0.11 mm


def test_length_with_stiffness_and_torsion_factor(longer_hose_scans):
    calibration = calibrate(brake_hose(segments=40), longer_hose_scans, ["bending_stiffness", "torsion_factor", "length"])
    fitted = {p.name: p for p in calibration.parameters}
    assert all(p.identifiable for p in fitted.values())
    assert fitted["length"].value == pytest.approx(TRUE_LENGTH, abs=0.5)  # measured: 0.17 mm long
    assert fitted["bending_stiffness"].value == pytest.approx(EI, rel=0.045)  # measured: +1.4 %
    assert fitted["torsion_factor"].value == pytest.approx(FACTOR, rel=0.055)  # measured: -1.7 %
