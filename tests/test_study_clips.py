"""Studies with clips: a clip's position and direction as tolerances (clips[k].point, clips[k].direction)."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from hoseline.cli import app
from hoseline.io.problem_file import load_problem, problem_to_toml
from hoseline.model import Hose, Mount, Problem
from hoseline.model.clips import Clip
from hoseline.procedures.placement.sequence import solve
from hoseline.procedures.variation.tolerances import (COORDINATES, Tolerance, Variation, coordinate_names, perturbed,
                                                      tilt_axes)

CLIP_POINT, CLIP_DIRECTION = np.array([-60.0, 120.0, 10.0]), np.array([-1.0, 0.3, 0.0])


def clipped(kind: str = "fixed") -> Problem:
    """The clipped hose of tests/test_clips.py (40 segments), the clip on station 20."""
    hose = Hose(length=400.0, outer_diameter=10.0, bending_stiffness=1.5e5, torsional_stiffness=1.0e5, segments=40,
                mass_per_length=0.3)
    clip = Clip(kind, CLIP_POINT, 200.0, None if kind == "ball" else CLIP_DIRECTION)
    return Problem(hose, Mount([0, 0, 0], [0, 1, 0]), Mount([-200, 0, 30], [1, 0, 0]), end_twist_deg=90.0,
                   gravity=np.array([0.0, 0.0, -9.81]), clips=(clip,))


def test_a_clip_deviation_moves_its_point_and_turns_its_direction_by_the_angle_given():
    problem = clipped()
    names = coordinate_names(1)
    assert names[len(COORDINATES):] == ("clips[0].x", "clips[0].y", "clips[0].z", "clips[0].tilt_a", "clips[0].tilt_b")
    deviation = np.zeros(len(names))
    deviation[names.index("clips[0].y")] = 0.7
    deviation[names.index("clips[0].tilt_b")] = 3.0
    [clip] = perturbed(problem, deviation).clips
    np.testing.assert_allclose(clip.point, CLIP_POINT + [0.0, 0.7, 0.0])
    original = problem.clips[0].direction
    assert math.degrees(math.acos(np.clip(clip.direction @ original, -1.0, 1.0))) == pytest.approx(3.0)
    b = tilt_axes(original)[1]
    assert abs(clip.direction @ b) < 1e-12  # turned about b: no component along it
    [unmoved] = perturbed(problem, deviation[:len(COORDINATES)]).clips  # without clip coordinates
    assert np.array_equal(unmoved.point, CLIP_POINT) and np.array_equal(unmoved.direction, original)
    length = np.zeros(len(COORDINATES))
    length[COORDINATES.index("hose.length")] = 4.0  # 1 % longer: the clip keeps its station, 1 % further along
    assert perturbed(problem, length).clips[0].arc_length == pytest.approx(202.0)


def test_a_clip_tolerance_is_sampled_like_a_mount_tolerance():
    variation = Variation((Tolerance("clips[0].point", "sphere", (0.5,)),), clips=1)
    rows = variation.coordinates(np.random.default_rng(1).random((200, variation.dimensions)))
    moved = rows[:, len(COORDINATES):len(COORDINATES) + 3]
    assert np.all(np.linalg.norm(moved, axis=1) <= 0.5) and np.max(np.linalg.norm(moved, axis=1)) > 0.4
    assert np.all(rows[:, :len(COORDINATES)] == 0.0)
    np.testing.assert_allclose(variation.covariance()[len(COORDINATES):len(COORDINATES) + 3, len(COORDINATES):][:, :3],
                               np.eye(3) * 0.5**2 / 5.0)
    with pytest.raises(ValueError, match="has 1 clip"):
        Variation((Tolerance("clips[1].point", "sphere", (0.5,)),), clips=1)


STUDY = """
base = "problem.toml"
[sampling]
method = "latin-hypercube"
samples = 6
seed = 2
[[vary]]
parameter = "clips[0].point"
distribution = "sphere"
radius = 2.0
[[vary]]
parameter = "clips[0].direction"
distribution = "cone"
angle = 3.0
[limits]
bend_radius = 30.0
"""


def test_a_study_varies_the_clip_and_every_sample_runs_through_its_moved_clip(tmp_path):
    """Each sample's hose passes through its own clip point: the station on the clip against the nominal point plus
    the sample's deviation (a check through the clip constraint, not through the tolerance code)."""
    (tmp_path / "problem.toml").write_text(problem_to_toml(clipped()), encoding="utf-8")
    (tmp_path / "study.toml").write_text(STUDY, encoding="utf-8")
    result = CliRunner().invoke(app, ["study", str(tmp_path / "study.toml"), "-o", str(tmp_path / "out"), "--workers",
                                      "0"])
    assert result.exit_code == 0, result.output
    rows = list(csv.DictReader((tmp_path / "out" / "samples.csv").open(encoding="utf-8")))
    assert len(rows) == 6 and all(row["status"] == "solved" for row in rows)
    moves = np.array([[float(row[f"clips[0].{axis} [mm]"]) for axis in "xyz"] for row in rows])
    assert np.all(np.linalg.norm(moves, axis=1) <= 2.0) and np.min(np.linalg.norm(moves, axis=1)) > 0.0
    with np.load(tmp_path / "out" / "samples.npz") as data:
        shapes = data["shapes"][:, 0]  # (samples, N+1, 3): the placed centreline of each sample
    np.testing.assert_allclose(shapes[:, 20], CLIP_POINT + moves, atol=1e-6)
    worst = next((tmp_path / "out" / "worst").glob("*/problem.toml"))  # a worst sample reproduces with its clip moved
    again = solve(load_problem(worst), estimate_error=False)
    assert np.linalg.norm(again.centerline[20] - again.problem.clips[0].point) < 1e-6
    assert np.linalg.norm(again.problem.clips[0].point - CLIP_POINT) > 0.0


@pytest.mark.parametrize("kind, text, message", [
    ("fixed", STUDY.replace("clips[0].point", "clips[2].point"), "the base has 1 clip(s), numbered from 0"),
    ("ball", STUDY, "clip 0 is a ball clip: it holds the position only"),
    ("sliding", STUDY.replace("seed = 2", 'seed = 2\nstart = "nominal"'), 'start = "nominal" with a sliding clip'),
    ("sliding", STUDY + "\n[reliability]\n",
     "[reliability]: the base has a sliding clip, whose sensitivities FORM needs are not covered"),
])
def test_bad_clip_tolerances_are_refused_naming_the_fix(tmp_path, kind, text, message):
    (tmp_path / "problem.toml").write_text(problem_to_toml(clipped(kind)), encoding="utf-8")
    (tmp_path / "study.toml").write_text(text, encoding="utf-8")
    result = CliRunner().invoke(app, ["study", str(tmp_path / "study.toml"), "-o", str(tmp_path / "out"), "--workers",
                                      "0"])
    assert result.exit_code == 2
    assert message in " ".join(result.output.split())
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("kind", ["fixed", "rotating", "ball"])
def test_sensitivities_with_a_clip_match_finite_differences_of_full_placements(kind):
    """As tests/test_study_sensitivity.py without clips: d(quantity)/d(parameter) and d(station)/d(parameter) for the
    mounts, the length (the clip keeps its station: its arc length stretches with the hose) and the clip's point and
    direction, against central differences of whole placements from the straight hose (Richardson-extrapolated),
    which find the end's and a fixed clip's lock angles afresh each time."""
    from hoseline.procedures.placement.sequence import place_only
    from hoseline.procedures.variation.samples import placement_readings
    from hoseline.procedures.variation.sensitivity import placement_sensitivities, step_sizes

    problem = clipped(kind)
    names = coordinate_names(1)
    wanted = ["end.x", "start.tilt_b", "hose.length", "hose.bending", "clips[0].y", "clips[0].z"]
    wanted += [] if kind == "ball" else ["clips[0].tilt_a", "clips[0].tilt_b"]
    varied = tuple(names.index(name) for name in wanted)
    sensitivities = placement_sensitivities(problem, varied)
    # 3e-5 of the scale (0.012 mm), Richardson-extrapolated: ten times the larger steps of the unclipped test moves
    # the smallest bend radius of the fixed clip's hose to another station (a kink the reference would straddle)
    steps = 300.0 * step_sizes(problem)

    def readings(deviation: np.ndarray) -> np.ndarray:
        hose = perturbed(problem, deviation)
        props, clamps, state, _ = place_only(hose)
        read = placement_readings(hose, props, clamps, state)
        return np.concatenate([read.smooth_values(), read.centerlines[0].ravel()])

    def central(j: int, step: float) -> np.ndarray:
        e = np.zeros(len(names))
        e[j] = step
        return (readings(e) - readings(-e)) / (2.0 * step)

    worst = 0.0
    for j in varied:
        reference = (4.0 * central(j, steps[j] / 2.0) - central(j, steps[j])) / 3.0
        quantities, stations = np.split(reference, [sensitivities.values.size])
        scale = np.abs(quantities) + np.abs(sensitivities.values) / (step_sizes(problem)[j] / 1e-7)
        worst = max(worst, float(np.max(np.abs(sensitivities.derivatives[:, j] - quantities) / scale)))
        station_error = np.max(np.abs(sensitivities.station_derivatives[:, :, j].ravel() - stations))
        worst = max(worst, float(station_error / np.max(np.abs(stations))))
    assert worst <= 1e-6  # the issue asks 1e-5; measured at most 2e-7 (the stations' derivatives along EI)


@pytest.mark.parametrize("kind", ["fixed", "rotating", "ball"])
def test_the_warm_start_with_a_clip_reaches_the_published_placement(kind):
    """Newton from the nominal equilibria (start = "nominal") against the published sequence from the straight hose,
    for mounts, length and clip moved (measured: within 1e-8 mm)."""
    from hoseline.procedures.placement.sequence import place_only
    from hoseline.procedures.variation.nominal import nominal_placement, warm_start
    from hoseline.procedures.variation.samples import placement_readings

    problem = clipped(kind)
    nominal = nominal_placement(problem)
    names = coordinate_names(1)
    rng = np.random.default_rng(3)
    for _ in range(4):
        deviation = np.zeros(len(names))
        deviation[[5, 6, 7, 15, 16, 17]] = rng.normal(0.0, 0.5, 6)  # end.x .. z and clips[0].x .. z, mm
        deviation[names.index("hose.length")] = rng.normal(0.0, 1.0)
        if kind != "ball":
            deviation[18:20] = rng.normal(0.0, 1.0, 2)  # the clip's direction, degrees
        warm = placement_readings(*warm_start(nominal, deviation)).centerlines[0]
        hose = perturbed(problem, deviation)
        published = placement_readings(hose, *place_only(hose)[:3]).centerlines[0]
        assert np.max(np.linalg.norm(warm - published, axis=1)) < 1e-6
