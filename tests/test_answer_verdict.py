"""What a result says about itself: the uniqueness verdict on the final shape, the forks met on
the way, and the a-posteriori estimate of the discretisation error."""

from dataclasses import replace

import numpy as np
import pytest
from cases import THESIS_TOML, write
from scipy.interpolate import CubicSpline
from typer.testing import CliRunner

from hoseline import cli
from hoseline.commands import common
from hoseline.demos.thesis_hose import demo_problem
from hoseline.procedures.placement.refinement import solve_to_accuracy
from hoseline.procedures.placement.sequence import solve


def with_segments(problem, segments):
    return replace(problem, hose=replace(problem.hose, segments=segments))


def test_a_fork_on_the_path_whose_branches_meet_again_leaves_the_answer_unique():
    """The thesis hose at 0 deg: with its end free to spin it leaves its plane at about 0.77 of
    the place phase (a symmetric fork) and comes back.  The fork is reported as met on the
    path; the branch not taken, followed to the end, lands on the same shape: the answer is unique."""
    result = solve(with_segments(demo_problem(0.0), 40), estimate_error=False)
    assert len(result.path_forks) == 1 and result.path_forks[0].startswith("place at fraction 0.7")
    assert "symmetric fork" in result.path_forks[0]
    assert any("ends on this shape again" in event for event in result.events), result.events
    assert result.unique and result.other_equilibria == []


def test_the_mirror_image_at_180_degrees_is_the_other_way_of_turning_the_same_fitting():
    """At 180 deg the mirror image in the mounts' plane is another shape of the same assembly:
    twisting by -180 deg clamps the fitting exactly as +180 deg does, and gives that image.
    Checked against an independent solve at -180 deg."""
    plus = solve(with_segments(demo_problem(180.0), 40), alternatives=True, estimate_error=False)
    minus = solve(with_segments(demo_problem(-180.0), 40), estimate_error=False)
    assert not plus.unique and len(plus.other_equilibria) == 1 and len(plus.alternatives) == 1
    other = plus.other_equilibria[0]
    assert other.same_clamps and other.energy_gap == 0.0
    assert "-180 deg instead of 180 deg" in other.origin and "same physical assembly" in other.origin
    # the fitting is clamped identically at +-180 deg (measured: 2.4e-16) ...
    assert np.max(np.abs(minus.end_frame - plus.end_frame)) < 1e-12
    # ... and the shape turned the other way is the reported image (measured: 1.1e-13 mm), not the answer itself
    assert np.max(np.abs(minus.centerline - plus.alternatives[0].centerline)) < 1e-8
    assert np.max(np.abs(minus.centerline - plus.centerline)) == pytest.approx(other.max_distance, rel=1e-6)
    assert other.max_distance > 100.0


@pytest.mark.parametrize("twist", [0.0, 180.0])
def test_the_error_estimate_matches_the_error_against_a_fine_solve(twist):
    """Richardson from one solve at half the segments against the true error (an 800-segment
    solve, itself about 1e-3 mm off): measured ratios 0.987 and 1.009 at 50 segments."""
    problem = demo_problem(twist)
    reference = solve(with_segments(problem, 800), estimate_error=False)
    exact = CubicSpline(reference.s, reference.centerline, axis=0)
    result = solve(with_segments(problem, 50))
    true_error = np.max(np.linalg.norm(result.centerline - exact(result.s), axis=1))
    assert result.discretisation_error == pytest.approx(true_error, rel=0.04)
    assert result.summary()["discretisation_error_mm"] == result.discretisation_error


def test_solving_to_an_accuracy_meets_it():
    """Asked for 0.02 mm from 25 segments (error about 0.86 mm), the segment count is raised
    until the estimate meets it, and the true error does too."""
    problem = with_segments(demo_problem(180.0), 25)
    result = solve_to_accuracy(problem, 0.02)
    reference = solve(with_segments(problem, 800), estimate_error=False)
    true_error = np.max(np.linalg.norm(result.centerline - CubicSpline(reference.s, reference.centerline, axis=0)(result.s), axis=1))
    assert result.discretisation_error <= 0.02 and true_error <= 0.02
    assert result.problem.hose.segments > 100  # measured: 197 segments, estimate 0.0138 mm
    assert any(event.startswith("accuracy:") for event in result.events)


def test_cli_accuracy_option(tmp_path):
    problem = write(tmp_path / "p.toml", THESIS_TOML)
    runner = CliRunner()
    bad = runner.invoke(cli.app, ["solve", str(problem), "-o", str(tmp_path / "bad"), "--accuracy", "-1mm"])
    assert bad.exit_code == common.BAD_INPUT and "--accuracy" in bad.output
    assert not (tmp_path / "bad").exists()
    good = runner.invoke(cli.app, ["solve", str(problem), "-o", str(tmp_path / "out"), "-q", "--accuracy", "0.5mm"])
    assert good.exit_code == 0, good.output
    import json

    summary = json.loads((tmp_path / "out" / "result.json").read_text())["summary"]
    assert summary["discretisation_error_mm"] <= 0.5 and summary["segments"] > 10


def test_the_estimate_compares_through_an_interpolation_of_fourth_order():
    """The coarse shape is read at the fine stations through the cubic of the four coarse stations around each
    (accuracy.local_cubic): on a helix its error falls 16-fold per halving of the spacing, far below the O(h^2)
    it estimates (linear interpolation, 4-fold, would leave the estimate its own error), at uneven spacing too
    (the stations of sliding clips)."""
    from hoseline.procedures.placement.accuracy import local_cubic

    def helix(s):
        return np.column_stack([40.0 * np.cos(s / 50.0), 40.0 * np.sin(s / 50.0), 0.3 * s])

    errors = []
    for segments in (16, 32, 64):
        known = np.linspace(0.0, 300.0, segments + 1)
        known[1:-1] += 0.2 * np.sin(np.arange(1, segments)) * (300.0 / segments)  # uneven
        wanted = np.linspace(0.0, 300.0, 2 * segments + 1)
        errors.append(np.max(np.abs(local_cubic(known, helix(known), wanted) - helix(wanted))))
    assert 12.0 < errors[0] / errors[1] < 20.0 and 12.0 < errors[1] / errors[2] < 20.0
    np.testing.assert_allclose(local_cubic(known, helix(known), known), helix(known), atol=1e-12)


def test_a_solve_asked_not_to_check_uniqueness_says_not_checked():
    """check_uniqueness=False (a study's sweep samples): the same shape, the forks on the path still listed, and the
    verdict "not checked" with the reason, never "yes"; alternatives need the search."""
    problem = with_segments(demo_problem(0.0), 40)
    checked = solve(problem, estimate_error=False)
    unchecked = solve(problem, estimate_error=False, check_uniqueness=False)
    assert checked.unique is True and unchecked.unique is None
    assert unchecked.summary()["uniqueness"] == "not checked"
    assert unchecked.unchecked == "the search for other equilibria was not asked for"
    assert unchecked.path_forks == checked.path_forks and unchecked.other_equilibria == []
    np.testing.assert_array_equal(unchecked.centerline, checked.centerline)
    with pytest.raises(ValueError, match="alternatives need check_uniqueness"):
        solve(problem, alternatives=True, check_uniqueness=False)
