"""What the outputs say about clips and reactions: a fixed clip's locked roll and axial torque in the
placement Result (summary.clips, the summary table), the reactions as world vectors in a sweep's poses.csv."""

import csv
import json
import math
from dataclasses import replace

import numpy as np
import pytest

from hoseline.io.problem_file import problem_to_toml
from hoseline.io.sweep_file import sweep_from_dict
from hoseline.io.sweep_results import write_sweep_data
from hoseline.mechanics.rotations import frame_from_tangent, rotation_matrix
from hoseline.model.clips import Clip
from hoseline.model.mounts import Mount
from hoseline.model.problem import Problem
from hoseline.procedures.placement.sequence import solve
from hoseline.procedures.sweep.quasi_static import run_sweep
from tests.test_clips import CLIP_DIRECTION, _clipped_problem, _hose

CLIP_NODE = 20  # the clip of _clipped_problem: 200 mm along a hose of 400 mm in 40 segments


@pytest.fixture(scope="module")
def fixed_clip():
    """The hose of test_clips held by a fixed clip, placed without and with 90 degrees of end twist."""
    return {twist: solve(_clipped_problem("fixed", twist=twist), estimate_error=False) for twist in (0.0, 90.0)}


def _minimal_turn(frame: np.ndarray, tangent: np.ndarray) -> np.ndarray:
    """`frame` (rows d1, d2, d3) turned about d3 x tangent until its d3 is `tangent` (unit): no roll about d3."""
    axis = np.cross(frame[2], tangent)
    angle = math.atan2(float(np.linalg.norm(axis)), float(frame[2] @ tangent))
    if np.linalg.norm(axis) == 0.0:
        return frame
    return frame @ rotation_matrix(axis / np.linalg.norm(axis) * angle).T


def _roll_deg(frame: np.ndarray, reference: np.ndarray) -> float:
    """Roll of `frame` from `reference` about their common d3, right-handed, degrees."""
    return math.degrees(math.atan2(float(frame[0] @ reference[1]), float(frame[0] @ reference[0])))


def test_a_fixed_clip_locks_at_the_roll_the_hose_reaches_without_twist(fixed_clip):
    """Roll free at the clip and at the end, an isotropic hose carries no twisting moment (m.t is constant along
    each span and zero at a free roll), so its material frame is the start fitting's frame carried along the
    hose without twist (parallel transport).  The placement locks the clip there: the locked roll is the roll
    of the transported frame at the clip from the reference (the start fitting's frame turned directly into
    the clip direction).  Here a 3D layout: -13.55 deg, the same whatever the end twist applied afterwards."""
    result = fixed_clip[0.0]
    problem = result.problem
    start = frame_from_tangent(problem.start.direction)
    transported = start
    for tangent in [*result.frames[:CLIP_NODE, 2], result.clips[0].frame[2]]:  # segment by segment up to the clip
        transported = _minimal_turn(transported, tangent)
    direction = CLIP_DIRECTION / np.linalg.norm(CLIP_DIRECTION)
    expected = _roll_deg(transported, _minimal_turn(start, direction))
    assert abs(expected) > 5.0  # a layout where the roll is not zero by symmetry
    for twist, placed in fixed_clip.items():
        clip = placed.clips[0]
        assert clip.locked_roll_deg == pytest.approx(expected, abs=1e-6)  # measured 4.5e-10 deg
        np.testing.assert_allclose(clip.frame[2], direction, atol=1e-12)
        np.testing.assert_allclose(clip.frame @ clip.frame.T, np.eye(3), atol=1e-12)


def test_a_fixed_clip_in_the_plane_of_a_planar_hose_locks_at_zero_roll():
    """Mounts, clip and weight in one plane: the hose stays in it, and the mirror image in that plane is the same
    placement, so the torque-free roll, which the mirror reverses, is zero."""
    hose = replace(_hose(400.0, 40), mass_per_length=0.3)
    clip = Clip("fixed", [-60.0, 120.0, 0.0], 200.0, [-1.0, 0.3, 0.0])
    problem = Problem(hose, Mount([0, 0, 0], [0, 1, 0]), Mount([-200, 0, 0], [1, 0, 0]),
                      gravity=np.array([0.0, -9.81, 0.0]), clips=(clip,))
    result = solve(problem, estimate_error=False)
    assert np.max(np.abs(result.centerline[:, 2])) < 1e-9 * 400.0
    assert result.clips[0].locked_roll_deg == pytest.approx(0.0, abs=1e-9)


def test_the_axial_torque_is_what_the_clip_does_to_the_twisting_moment(fixed_clip):
    """The axial torque is the clip moment about the clip direction; the clip moment itself equals what the
    hose's internal moments and forces on both sides of the clip leave over (moments about the station after
    the clip of the piece between stations 19 and 21: the internal moments, the internal force at 19, the
    clip force and the piece's weight).  Without end twist the clip is locked torque-free: no axial torque."""
    direction = CLIP_DIRECTION / np.linalg.norm(CLIP_DIRECTION)
    for twist, result in fixed_clip.items():
        clip = result.clips[0]
        before, after = CLIP_NODE - 1, CLIP_NODE + 1
        x_before, x_after = result.centerline[before], result.centerline[after]
        weight = (result.problem.hose.mass_per_length * 1e-3 * result.problem.gravity
                  * result.problem.hose.segment_length)
        middles = 0.5 * (result.centerline[before + 1:after + 1] + result.centerline[before:after])
        moment = -(result.internal_moment[after] - result.internal_moment[before]
                   - np.cross(x_before - x_after, result.internal_force[before])
                   + np.cross(clip.point - x_after, clip.force)
                   + sum(np.cross(middle - x_after, weight) for middle in middles))
        np.testing.assert_allclose(clip.moment, moment, atol=1e-9 * np.linalg.norm(clip.moment))  # measured 1e-16
        assert clip.axial_torque == pytest.approx(moment @ direction, abs=1e-9 * np.linalg.norm(moment))
        summary = clip.summary()
        assert summary["axial_torque_Nmm"] == clip.axial_torque and summary["locked_roll_deg"] == clip.locked_roll_deg
        np.testing.assert_array_equal(summary["frame"], clip.frame)
        if twist == 0.0:
            assert abs(clip.axial_torque) < 1e-9 * np.linalg.norm(clip.moment)  # measured 2e-14
        else:  # 90 degrees at the end: the span after the clip is twisted, the one before is not
            assert abs(clip.axial_torque) > 0.05 * np.linalg.norm(clip.moment)
            assert clip.axial_torque == pytest.approx(-result.twisting_moment[after], rel=0.02)  # measured 0.8 %


def test_other_clips_report_no_locked_roll_and_the_table_shows_both():
    from rich.console import Console

    from hoseline.report.table import summary_table

    fixed, rotating = (solve(_clipped_problem(kind), estimate_error=False) for kind in ("fixed", "rotating"))
    assert rotating.clips[0].locked_roll_deg is None
    assert abs(rotating.clips[0].axial_torque) < 1e-9 * np.linalg.norm(rotating.clips[0].moment)
    console = Console(width=200, record=True)
    console.print(summary_table([fixed, rotating], ["fixed", "rotating"]))
    text = console.export_text()
    assert f"{fixed.clips[0].locked_roll_deg:.2f}" in text and "clip 1 locked roll" in text
    assert f"{fixed.clips[0].axial_torque:.4g}" in text and "clip 1 axial torque" in text


# --- reactions as vectors in poses.csv ---

LENGTH, MASS, HEIGHT, DROP = 400.0, 0.5, 150.0, 100.0
GRAVITY = [0.0, 0.0, -9.81]
LOADS = (("start_force", "N"), ("start_moment", "Nmm"), ("end_force", "N"), ("end_moment", "Nmm"),
         ("clip_1_force", "N"), ("clip_1_moment", "Nmm"))


def _lowered_with_a_clip() -> dict:
    """A heavy hose between two horizontal mounts, held at its middle by a fixed clip; the end mount goes down
    100 mm in 4 steps (all in the plane y = 0)."""
    return {"hose": {"length": LENGTH, "outer_diameter": 10.0, "bending_stiffness": 500.0,
                     "torsional_stiffness": 500.0, "mass_per_length": MASS, "segments": 30},
            "start": {"point": [-150.0, 0.0, HEIGHT], "direction": [1.0, 0.0, 0.0]},
            "end": {"point": [150.0, 0.0, HEIGHT], "direction": [-1.0, 0.0, 0.0], "body": "arm"},
            "clips": [{"type": "fixed", "arc_length": 200.0, "point": [0.0, 0.0, 100.0], "direction": [1.0, 0.0, 0.2],
                       "name": "bracket"}],
            "environment": {"gravity": GRAVITY},
            "bodies": [{"name": "arm", "stages": [{"name": "lower", "translate": [0.0, DROP], "axis": [0, 0, -1],
                                                   "steps": 4}]}],
            "sweep": {"compare_free_roll": False}}


@pytest.fixture(scope="module")
def lowered(tmp_path_factory):
    """(the sweep result, the rows of its poses.csv)."""
    result = run_sweep(sweep_from_dict(_lowered_with_a_clip()))
    folder = tmp_path_factory.mktemp("lowered")
    write_sweep_data(result, folder)
    with open(folder / "poses.csv", newline="") as stream:
        return result, list(csv.DictReader(stream))


def _vector(row: dict, name: str, unit: str) -> np.ndarray:
    return np.array([float(row[f"{name}_{axis}_{unit}"]) for axis in "xyz"])


def test_poses_csv_gives_the_reactions_as_world_vectors(lowered):
    result, rows = lowered
    arrays = {"start_force": result.start_force, "start_moment": result.start_moment, "end_force": result.end_force,
              "end_moment": result.end_moment, "clip_1_force": result.clip_forces[:, 0],
              "clip_1_moment": result.clip_moments[:, 0]}
    for k, row in enumerate(rows):
        for name, unit in LOADS:
            scale = np.max(np.linalg.norm(arrays[name], axis=1))
            np.testing.assert_allclose(_vector(row, name, unit), arrays[name][k], atol=1e-7 * scale)  # 8 digits
            assert float(row[f"{name}_{unit}"]) == pytest.approx(np.linalg.norm(arrays[name][k]), rel=1e-7)
    assert np.ptp([float(row["clip_1_force_z_N"]) for row in rows]) > 0.03  # the clip's load changes (0.06 N)


def test_the_vector_columns_balance_the_weight(lowered):
    """From poses.csv alone: the mounts and the clip carry the weight (forces), and their moments about the origin
    with the weight's (at the centroid of the stations of shapes.csv's pose) sum to zero."""
    result, rows = lowered
    weight = MASS * 1e-3 * np.array(GRAVITY) * LENGTH
    for k, row in enumerate(rows):
        start = np.array([float(row[f"start_{axis}_mm"]) for axis in "xyz"])
        end = np.array([float(row[f"end_{axis}_mm"]) for axis in "xyz"])
        clip = np.array([0.0, 0.0, 100.0])
        forces = [_vector(row, f"{name}_force", "N") for name in ("start", "end", "clip_1")]
        assert np.linalg.norm(sum(forces) + weight) < 1e-6 * np.linalg.norm(weight)
        centroid = 0.5 * (result.centerlines[k, 1:] + result.centerlines[k, :-1]).mean(axis=0)
        moment = (sum(_vector(row, f"{name}_moment", "Nmm") for name in ("start", "end", "clip_1"))
                  + sum(np.cross(point, force) for point, force in zip((start, end, clip), forces))
                  + np.cross(centroid, weight))
        assert np.linalg.norm(moment) < 1e-6 * np.linalg.norm(weight) * LENGTH


def test_the_vectors_at_a_pose_are_what_hoseline_solve_gives_there(lowered, tmp_path):
    """The last pose (end mount 100 mm down) placed afresh by `hoseline solve`: in this plane the lock angle and
    the clip's locked roll are zero both ways, so the equilibrium is the same and so are the reactions."""
    from typer.testing import CliRunner

    from hoseline import cli

    result, rows = lowered
    problem = result.sweep.problem
    there = replace(problem, end=Mount(result.end_points[-1], result.end_directions[-1]))
    problem_file = tmp_path / "last_pose.toml"
    problem_file.write_text(problem_to_toml(there))
    done = CliRunner().invoke(cli.app, ["solve", str(problem_file), "-o", str(tmp_path / "out"), "--quiet"])
    assert done.exit_code == 0, done.output
    summary = json.loads((tmp_path / "out" / "result.json").read_text())["summary"]
    [clip] = summary["clips"]
    assert clip["locked_roll_deg"] == pytest.approx(0.0, abs=1e-9) and summary["lock_angle_deg"] == pytest.approx(0.0, abs=1e-9)
    solved = {"start_force": summary["start_force_N"], "start_moment": summary["start_moment_Nmm"],
              "end_force": summary["end_force_N"], "end_moment": summary["end_moment_Nmm"],
              "clip_1_force": clip["force_N"], "clip_1_moment": clip["moment_Nmm"]}
    for name, unit in LOADS:
        scale = np.linalg.norm(solved["clip_1_moment" if unit == "Nmm" else "clip_1_force"])
        np.testing.assert_allclose(_vector(rows[-1], name, unit), solved[name], atol=1e-6 * scale)


def test_the_twisting_moment_at_a_fixed_clip_s_station_is_that_of_the_hose_beyond_it(fixed_clip):
    """At the clip station the moment is the half joint's from the clip frame to the segment beyond, and its
    twisting part is along that joint's tangent (the clip's and the segment's mean): zero without end twist, and
    the twist of the span beyond with it (projected on the two segments' mean tangent instead, it read -31.6 N*mm
    without twist and -784 N*mm at 90 deg, 8 % above the span's -724)."""
    untwisted, twisted = fixed_clip[0.0], fixed_clip[90.0]
    assert abs(untwisted.twisting_moment[CLIP_NODE]) <= 1e-9 * untwisted.bending_moment[CLIP_NODE]
    beyond = twisted.twisting_moment[CLIP_NODE + 1]
    assert twisted.twisting_moment[CLIP_NODE] == pytest.approx(beyond, rel=1e-2)
    assert np.max(np.abs(twisted.twisting_moment)) == pytest.approx(abs(beyond), rel=1e-2)
