"""`calibrate --fit preset_curvature,preset_angle`: the set of a hose recovered from synthetic scans
(synthetic_scan + fit_centerline) of a finer model with a known preset, starting from no preset."""

import math
from dataclasses import replace

import pytest
from validation_cases import brake_hose, scan_cases

from hoseline.model.preset import Preset
from hoseline.procedures.scans.calibration import calibrate

TRUE_SET = Preset(1.0 / 300.0, 60.0)  # a radius of set of 300 mm, towards 60 deg from the start fitting's d1


def with_preset(problem, preset, segments):
    return replace(problem, hose=replace(problem.hose, preset=preset, segments=segments))


def test_recovers_the_preset_from_scans_at_two_twists():
    """Truth: 96 segments; scans all round, 0.05 mm noise; model: 32 segments from no set at all.
    Measured: radius 302.9 mm (+1.0 %, 1.3 sigma), angle 59.6 deg (0.6 deg sigma); mean deviation 33 mm before,
    0.15-0.17 mm after (the 32-segment model's discretisation)."""
    cases = scan_cases(lambda twist: with_preset(brake_hose(twist=twist), TRUE_SET, 96))
    calibration = calibrate(with_preset(brake_hose(), None, 32), cases, ["preset_curvature", "preset_angle"])
    fitted = {p.name: p for p in calibration.parameters}
    curvature, angle = fitted["preset_curvature"], fitted["preset_angle"]
    assert curvature.identifiable and angle.identifiable
    assert curvature.value == pytest.approx(TRUE_SET.curvature, rel=0.03)
    assert abs(math.remainder(angle.value - TRUE_SET.angle_deg, 360.0)) < 3.0
    assert abs(curvature.value - TRUE_SET.curvature) < 3.0 * curvature.std
    assert calibration.hose.preset == Preset(curvature.value, angle.value)
    for before, after in zip(calibration.before, calibration.after):
        assert before.mean > 10.0 and after.mean < 0.3  # mm
