"""Sweeps with clips: clips carried by their bodies like the fittings, their loads per pose."""

import numpy as np
import pytest

from hoseline.io.sweep_file import SweepFileError, load_sweep
from hoseline.io.sweep_results import poses_csv, shapes_csv
from hoseline.procedures.sweep.quasi_static import run_sweep
from tests.test_sweep import SWEEP_TOML, sweep_folder

NO_FREE_ROLL = "\n[sweep]\ncompare_free_roll = false\n"


def _clip(kind, body=None, arc_length=165.3, direction="[-1.0, -0.3, 0.0]"):
    table = f'\n[[clips]]\ntype = "{kind}"\narc_length = {arc_length}\npoint = [-80.0, 40.0, -11.25]\n'
    if kind != "ball":
        table += f"direction = {direction}\n"
    return table + (f'body = "{body}"\n' if body else "")


def _balance(result, k):
    """Largest force (N) and moment (N*mm, about the origin) left over at pose k (no gravity here)."""
    points = (result.start_points[k], result.end_points[k])
    clip_points = result.centerlines[k][[int(np.argmin(np.abs(result.s - s))) for s in result.clip_arc_lengths[k]]]
    if result.station_arc_lengths is not None:
        stations = result.station_arc_lengths[k]
        clip_points = result.centerlines[k][[int(np.argmin(np.abs(stations - s))) for s in result.clip_arc_lengths[k]]]
    force = result.start_force[k] + result.end_force[k] + result.clip_forces[k].sum(axis=0)
    moment = (result.start_moment[k] + np.cross(points[0], result.start_force[k]) + result.end_moment[k]
              + np.cross(points[1], result.end_force[k])
              + sum(m + np.cross(p, f) for m, p, f in zip(result.clip_moments[k], clip_points, result.clip_forces[k])))
    return float(np.linalg.norm(force)), float(np.linalg.norm(moment))


def test_a_clip_on_the_knuckle_moves_with_it_and_its_loads_balance(tmp_path):
    """A rotating clip on the knuckle (the end's body, lifted 0, 10, 20 mm): the hose passes through
    the moved clip point at every pose, and mounts and clip balance (forces and moments)."""
    sweep = load_sweep(sweep_folder(tmp_path, SWEEP_TOML + _clip("rotating", "knuckle") + NO_FREE_ROLL))
    assert sweep.clip_bodies == ("knuckle",)
    result = run_sweep(sweep)
    for k in range(result.pose_count):
        lifted = np.array([-80.0, 40.0, -11.25 + 10.0 * k])
        assert np.linalg.norm(result.centerlines[k, 5] - lifted) < 1e-9 * 330.6
        force, moment = _balance(result, k)
        scale = np.linalg.norm(result.clip_forces[k, 0])
        assert force < 1e-8 * scale and moment < 1e-8 * scale * 330.6
    assert np.ptp(result.clip_forces[:, 0, 2]) > 1e-3 * np.max(np.abs(result.clip_forces))  # the load changes
    header = poses_csv(result).splitlines()[0]
    assert "clip_1_force_N" in header and "clip_1_moment_Nmm" in header


def test_a_sliding_clip_in_a_sweep_reports_where_it_holds_the_hose(tmp_path):
    """A fixed guide ring while the knuckle lifts: the hose slides through it, its arc length and
    the stations' arc lengths per pose in the result, poses.csv and shapes.csv."""
    sweep = load_sweep(sweep_folder(tmp_path, SWEEP_TOML + _clip("sliding") + NO_FREE_ROLL))
    result = run_sweep(sweep)
    arcs = result.clip_arc_lengths[:, 0]
    assert np.ptp(arcs) > 1e-3  # it slides
    assert abs(arcs[0] - result.assembly.clips[0].arc_length) < 1e-6  # pose 0 is the design position
    for k in range(result.pose_count):
        node = int(np.argmin(np.abs(result.station_arc_lengths[k] - arcs[k])))
        assert abs(result.station_arc_lengths[k, node] - arcs[k]) < 1e-9
        assert np.linalg.norm(result.centerlines[k, node] - [-80.0, 40.0, -11.25]) < 1e-9 * 330.6
        force, moment = _balance(result, k)
        assert force < 1e-8 * np.linalg.norm(result.clip_forces[k, 0])
    assert "clip_1_arc_length_mm" in poses_csv(result).splitlines()[0]
    rows = [line.split(",") for line in shapes_csv(result).splitlines()[1:]]
    assert abs(float(rows[-1][1]) - 330.6) < 1e-6 and any(abs(float(r[1]) - arcs[-1]) < 1e-4 for r in rows)


def test_a_clip_body_must_be_a_moving_body(tmp_path):
    with pytest.raises(SweepFileError, match="clips\\[0\\].body = 'wheel': no such body"):
        load_sweep(sweep_folder(tmp_path, SWEEP_TOML + _clip("ball", "wheel")))
