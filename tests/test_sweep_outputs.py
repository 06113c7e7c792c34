"""What a sweep writes: the fitting tips per pose, full precision without round-off noise, the demo's
strut, the envelope's grid, no empty panels, a title from the file name, slider frames without repeats."""

import csv
import json
from dataclasses import replace

import numpy as np
import pytest
import trimesh
from sweep_cases import small_sweep_report, small_sweep_result  # noqa: F401 (fixtures)
from test_sweep import SWEEP_TOML, run, sweep_folder

from hoseline.io.csv_numbers import without_round_off
from hoseline.io.sweep_results import shapes_csv
from hoseline.procedures.geometry.clearance import TriangleIndex
from hoseline.report.sweep_figures import view_figure
from hoseline.report.sweep_html import sweep_report_html


def read_poses(folder):
    with open(folder / "poses.csv", newline="") as stream:
        return list(csv.DictReader(stream))


def test_poses_csv_gives_the_fitting_tips_and_directions_of_every_pose(small_sweep_report, small_sweep_result):
    sweep = small_sweep_result.sweep
    problem = sweep.problem
    rows = read_poses(small_sweep_report)
    assert len(rows) == small_sweep_result.pose_count
    for k, row in enumerate(rows):  # where the knuckle's pose puts the end fitting (the start one is fixed)
        for end, body, mount in (("start", sweep.start_body, problem.start), ("end", sweep.end_body, problem.end)):
            pose = sweep.pose(body, k)
            tip = [float(row[f"{end}_{axis}_mm"]) for axis in "xyz"]
            direction = [float(row[f"{end}_direction_{axis}"]) for axis in "xyz"]
            np.testing.assert_allclose(tip, pose.point(mount.point), atol=1e-5)  # 8 digits of 200 mm
            np.testing.assert_allclose(direction, pose.rotation @ (mount.direction / np.linalg.norm(mount.direction)),
                                       atol=1e-7)
    assert {float(row["end_z_mm"]) for row in rows} != {float(rows[0]["end_z_mm"])}  # the end fitting moves


def test_round_off_is_written_as_zero(small_sweep_report):
    # at design position both fittings lie in the plane z = -11.25: the single-plane offset is exactly 0
    # (computed, it came out as -3.4e-41)
    design = [row for row in read_poses(small_sweep_report) if float(row["travel"]) == 0.0]
    assert len(design) >= 2 and all(row["single_plane_offset_mm"] == "0" for row in design)
    values = np.array([1e-45, -3e-13, 2e-11, -5.0, np.nan, -0.0])
    cleaned = without_round_off(values)
    np.testing.assert_array_equal(cleaned[[0, 1, 2, 3, 5]], [0.0, 0.0, 2e-11, -5.0, 0.0])
    assert np.isnan(cleaned[4]) and not np.signbit(cleaned[5])


def test_shapes_csv_writes_s_as_precisely_as_the_coordinates(small_sweep_result):
    stations = np.sqrt(np.arange(small_sweep_result.s.size)) * 105.123456789  # arc lengths with many digits
    text = shapes_csv(replace(small_sweep_result, s=stations))
    table = np.loadtxt(text.splitlines()[1:], delimiter=",")
    # 8 significant digits: within half a unit of the 8th, 5e-8 relative at most (6 digits: 5e-6)
    np.testing.assert_allclose(table[:, 1], np.tile(stations, small_sweep_result.pose_count), rtol=6e-8, atol=0.0)
    lines = small_sweep_result.centerlines
    np.testing.assert_allclose(table[:, 2:].reshape(lines.shape), lines, rtol=6e-8, atol=1e-10)


def test_demo_strut_is_written_and_the_clearance_can_be_checked_against_it(small_sweep_report, small_sweep_result):
    document = json.loads((small_sweep_report / "sweep.json").read_text())
    assert document["obstacles"][0]["file"] == "obstacle_strut.stl"
    strut = trimesh.load(small_sweep_report / "obstacle_strut.stl")
    assert strut.is_watertight and len(strut.faces) == len(small_sweep_result.sweep.obstacles[0].faces)
    clearance = small_sweep_result.clearances[0]
    radius = small_sweep_result.sweep.problem.hose.outer_radius
    index = TriangleIndex(strut.vertices, strut.faces)
    for k in (0, clearance.worst, small_sweep_result.pose_count - 1):  # the STL holds coordinates in float32
        assert index.nearest(small_sweep_result.centerlines[k], radius).distance == pytest.approx(clearance.distance[k],
                                                                                                 abs=1e-4)


def test_sweep_json_and_the_report_give_the_envelope_grid(small_sweep_report, small_sweep_result):
    envelope = json.loads((small_sweep_report / "sweep.json").read_text())["envelope"]
    assert envelope["file"] == "envelope.stl"
    radius = small_sweep_result.sweep.problem.hose.outer_radius
    assert envelope["cell_mm"] == envelope["requested_cell_mm"] == 0.5 * radius and envelope["radius_mm"] == radius
    assert envelope["triangles"] == len(trimesh.load(small_sweep_report / "envelope.stl", process=False).faces)
    html = (small_sweep_report / "report.html").read_text(encoding="utf-8")
    assert f"{envelope['triangles']} triangles on a grid of {envelope['cell_mm']:.3g} mm" in html


def test_report_without_the_free_roll_comparison_has_no_free_roll_panel(small_sweep_result):
    panel = "end free to spin: separation"
    assert panel in sweep_report_html(small_sweep_result)
    html = sweep_report_html(replace(small_sweep_result, free_centerlines=None, separation=None))
    assert panel not in html and "free to spin" not in html


def test_sweep_file_without_a_name_is_titled_by_its_file_stem(tmp_path):
    toml = SWEEP_TOML.replace('name = "brake hose"\n', "")
    assert toml != SWEEP_TOML
    code, output = run("sweep", sweep_folder(tmp_path, toml), "-o", tmp_path / "out", "--quiet")
    assert code == 0, output
    html = (tmp_path / "out" / "report.html").read_text(encoding="utf-8")
    assert "<h1>sweep</h1>" in html and "Sweep of" not in html


def test_slider_frames_send_only_what_changes(small_sweep_result):
    figure = view_figure(small_sweep_result)
    changing = {"x", "y", "z", "line", "hovertemplate", "type"}
    for frame in figure.frames:
        for trace in frame.data:
            sent = {key for key, value in trace.to_plotly_json().items() if value is not None}
            assert sent <= changing, sent - changing
            assert all(np.asarray(trace[axis]).dtype == np.float32 for axis in "xyz")
