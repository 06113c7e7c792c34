"""Sweeps with contact: the end mount lowered toward a floor ([contact] plane), the hose comes to rest on it."""

import csv
import json

import numpy as np
import pytest

from hoseline.io.sweep_file import sweep_from_dict
from hoseline.io.sweep_results import write_sweep_data
from hoseline.procedures.sweep.quasi_static import run_sweep

LENGTH, MASS, RADIUS, HEIGHT, DROP = 400.0, 0.5, 5.0, 150.0, 100.0
FLOOR = {"obstacles": [{"kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0], "name": "floor"}]}


def lowered_end(contact: dict | None) -> dict:
    """A heavy hose between two horizontal mounts 150 mm above z = 0; the end mount goes down 100 mm in 5 steps."""
    data = {"hose": {"length": LENGTH, "outer_diameter": 2 * RADIUS, "bending_stiffness": 500.0,
                     "torsional_stiffness": 500.0, "mass_per_length": MASS, "segments": 30},
            "start": {"point": [-150.0, 0.0, HEIGHT], "direction": [1.0, 0.0, 0.0]},
            "end": {"point": [150.0, 0.0, HEIGHT], "direction": [-1.0, 0.0, 0.0], "body": "arm"},
            "environment": {"gravity": [0.0, 0.0, -9.81]},
            "bodies": [{"name": "arm", "stages": [{"name": "lower", "translate": [0.0, DROP], "axis": [0, 0, -1],
                                                   "steps": 5}]}],
            "sweep": {"compare_free_roll": False}}
    if contact is not None:
        data["contact"] = contact
    return data


@pytest.fixture(scope="module")
def on_and_through_the_floor():
    """(the sweep with the floor in [contact], the same sweep without)."""
    return run_sweep(sweep_from_dict(lowered_end(FLOOR))), run_sweep(sweep_from_dict(lowered_end(None)))


def test_without_contact_the_hose_passes_through_the_floor(on_and_through_the_floor):
    free = on_and_through_the_floor[1]
    assert free.centerlines[-1, :, 2].min() < -10.0  # the check below can fail
    assert free.contacts == []


def test_the_hose_comes_to_rest_on_the_floor(on_and_through_the_floor):
    result = on_and_through_the_floor[0]
    [floor] = result.contacts
    assert floor.name == "floor" and floor.kind == "plane"
    assert np.all(floor.min_gap >= 0.0)
    assert np.all(result.centerlines[:, :, 2] >= RADIUS)  # the surface, not only the stations' gap report
    force = np.linalg.norm(floor.total_force, axis=1)
    assert force[0] == 0.0 and force[-1] > 0.2
    touching = np.flatnonzero(force > 0.0)
    assert np.all(np.diff(force[touching[0] - 1:]) > 0.0)  # grows as the end goes down
    np.testing.assert_allclose(floor.total_force[:, :2], 0.0, atol=1e-9)  # frictionless: along the normal
    # the sag's bottom touches first at a point (still curved there: it lies on no length), then lies on more and more
    assert floor.length_in_contact[touching[0]] == 0.0 < floor.length_in_contact[touching[1]] < floor.length_in_contact[-1]


def test_the_mounts_and_the_floor_carry_the_weight(on_and_through_the_floor):
    """Force balance per pose: start and end reactions plus the floor's push equal the weight (an independent check
    of the contact loads folded into the start reaction)."""
    result = on_and_through_the_floor[0]
    weight = MASS * 9.81e-3 * LENGTH  # kg/m * m/s^2 -> N/mm, times mm
    total = result.start_force + result.end_force + result.contacts[0].total_force
    np.testing.assert_allclose(total, np.tile([0.0, 0.0, weight], (result.pose_count, 1)), atol=1e-6 * weight)


def test_contact_columns_in_poses_csv_and_sweep_json(on_and_through_the_floor, tmp_path):
    result = on_and_through_the_floor[0]
    write_sweep_data(result, tmp_path)
    with open(tmp_path / "poses.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    force = [float(row["contact_floor_force_N"]) for row in rows]
    np.testing.assert_allclose(force, np.linalg.norm(result.contacts[0].total_force, axis=1), rtol=1e-7)
    assert all(float(row["contact_floor_gap_mm"]) >= 0.0 for row in rows)
    assert float(rows[-1]["contact_floor_length_mm"]) > 0.0
    document = json.loads((tmp_path / "sweep.json").read_text())
    [floor] = document["contact"]
    assert floor["name"] == "floor" and len(floor["min_gap_mm"]) == result.pose_count
    worst = {row["quantity"]: row for row in document["worst_cases"]}
    assert worst["contact force from floor"]["pose"] == result.pose_count - 1  # the end lowest
    assert worst["smallest contact gap to floor"]["value"] >= 0.0


def test_the_report_draws_the_floor_and_colours_the_contact_points_by_their_push(on_and_through_the_floor):
    from hoseline.report.sweep_figures import plots_figure, view_figure
    from hoseline.report.sweep_html import sweep_report_html

    result = on_and_through_the_floor[0]
    view = view_figure(result)
    assert "floor (contact)" in [trace.name for trace in view.data]
    [points] = [trace for trace in view.data if trace.name and trace.name.startswith("contact with floor")]
    last = view.frames[-1]
    [shown] = [change for change, index in zip(last.data, last.traces) if view.data[index] is points]
    floor = result.contacts[0]
    np.testing.assert_allclose(np.column_stack([shown.x, shown.y, shown.z]), floor.points[-1], atol=1e-3)
    np.testing.assert_allclose(shown.marker.color, floor.forces[-1], rtol=1e-6)
    assert np.isclose(np.sum(floor.forces[-1]), np.linalg.norm(floor.total_force[-1]))  # all along the normal
    assert len(view.frames[0].data[view.frames[0].traces.index(view.data.index(points))].x) == 0  # not yet touching
    titles = [annotation.text for annotation in plots_figure(result).layout.annotations]
    assert "contact push [N]" in titles and "length in contact [mm]" in titles
    assert "contact with floor" in sweep_report_html(result)
