"""The studio's "Place again" with contact (issue 28): every state a drag or the weight slider reaches that is an
equilibrium clear of the obstacles is placed afresh, and the saved problem file, solved by `hoseline solve`, gives
the shape shown within 0.1 mm; before that, the badge says how far the fresh placement is from the shape shown.

The hose of tests/test_studio_contact.py (400 mm, EI 500 N mm^2, 30 segments, mounts 300 mm apart): a floor
just below it, met by dragging the end mount down, by turning the start fitting towards the floor (the straight
hose the published sequence starts from then runs through the floor), or by raising the weight slider with the
floor 1 mm below the weightless shape (the issue's case); and a bar the free hose passes through, with the side the
hose ends on named by hose_side, which a drag must keep.
"""

import json
import math
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from test_studio_contact import RADIUS, dragged, resting_hose
from hoseline.io.problem_file import problem_from_dict, problem_to_dict
from hoseline.model.motion import matrix_quaternion, quaternion_matrix
from hoseline.procedures.placement.continuation import PlacementError
from hoseline.procedures.placement.sequence import solve
from hoseline.studio.messages import Target
from hoseline.studio.session import Session
from hoseline.studio.view import state_message

SAVED_TO_SHOWN_MM = 0.1  # the bound between the shape shown and the saved file solved


def solved_by_the_cli(problem_toml: str, folder: Path) -> tuple[np.ndarray, dict]:
    """(stations mm, result.json) of `hoseline solve` on the problem file text, run as a user runs it."""
    path = folder / "saved.toml"
    path.write_text(problem_toml)
    cli = Path(sys.executable).with_name("hoseline")
    run = subprocess.run([str(cli), "solve", str(path), "-o", str(folder / "out"), "--quiet"], capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    stations = np.loadtxt(folder / "out" / "centerline.csv", delimiter=",", skiprows=1)[:, 1:]
    return stations, json.loads((folder / "out" / "result.json").read_text())


def place_again_and_save(session: Session, folder: Path) -> dict:
    """From a state shown clear of every obstacle: the badge's comparison, "Place again", then the saved file solved
    by the CLI; checks each step and returns the CLI's result.json."""
    shown = session.result()
    assert all(contact.min_gap >= 0.0 for contact in shown.contacts)
    assert shown.stability_margin > 0.0  # a stable equilibrium
    badge = session.compare_with_placement()  # what the page shows before the user presses "Place again"
    assert "failed" not in badge, badge.get("failed")
    session.place_again()
    placed = session.result()
    moved = float(np.max(np.linalg.norm(placed.centerline - shown.centerline, axis=1)))
    # the badge named the distance to the shape that "Place again" then shows, and "same" only where it is the same
    assert badge["distance"] == pytest.approx(moved, rel=1e-9, abs=1e-9)
    assert badge["same"] == (moved <= 1e-6 * session.problem.hose.length)
    assert all(contact.min_gap >= 0.0 for contact in placed.contacts)
    stations, document = solved_by_the_cli(session.problem_toml(), folder)
    assert np.max(np.linalg.norm(stations - placed.centerline, axis=1)) <= SAVED_TO_SHOWN_MM
    assert document["summary"]["contact"]["min_gap_mm"] >= 0.0
    return document


def lying_on(result, floor_height: float) -> int:
    """How many stations lie on the floor (the hose's surface within the barrier's reach of it)."""
    return int(np.sum(result.centerline[:, 2] - RADIUS - floor_height < 0.01))


def floor_problem(data: dict, height: float, placement: str = "bring_in"):
    """The problem of `data` with a floor (plane z = height, mm) in [contact]."""
    data = dict(data, contact={"placement": placement, "obstacles": [
        {"kind": "plane", "point": [0.0, 0.0, height], "normal": [0.0, 0.0, 1.0], "name": "floor"}]})
    return problem_from_dict(data)


def test_an_end_dragged_down_onto_the_floor_is_placed_again_and_saved_as_shown(tmp_path):
    data = problem_to_dict(resting_hose(contact=False))
    data["end"]["point"][2] = 150.0  # level mounts: the hose hangs clear of the floor 5 mm below its lowest point
    hanging = solve(problem_from_dict(data), estimate_error=False)
    floor = float(np.min(hanging.centerline[:, 2])) - RADIUS - 5.0
    session = Session(floor_problem(data, floor))
    assert lying_on(session.result(), floor) == 0
    dragged(session, [0.0, 0.0, -40.0])
    assert lying_on(session.result(), floor) >= 3  # the drag laid it on the floor
    document = place_again_and_save(session, tmp_path)
    assert lying_on(session.result(), floor) >= 3
    [brought] = document["summary"]["contact"]["placement"]
    assert brought["name"] == "floor" and brought["free_gap_mm"] < 0.0  # the free hose hangs through it


def turned(session: Session, degrees: float) -> None:
    """Turn the start fitting about the world y axis by `degrees` (its direction towards -z), in 2-degree steps as a
    drag of the rotation gizmo sends them."""
    start = state_message(session)["fittings"]["start"]
    frame = quaternion_matrix(start["quaternion"])
    steps = math.ceil(abs(degrees) / 2.0)
    for k in range(1, steps + 1):
        angle = math.radians(degrees * k / steps)
        c, s = math.cos(angle), math.sin(angle)
        about_y = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
        session.apply(Target(type="set", seq=k, start={"point": start["point"],
                                                       "quaternion": list(matrix_quaternion(about_y @ frame))}))


def test_a_start_fitting_turned_towards_the_floor_is_placed_again_though_its_straight_start_runs_through_it(tmp_path):
    session = Session(resting_hose())
    turned(session, 30.0)
    problem = session.problem
    np.testing.assert_allclose(problem.start.direction, [math.cos(math.pi / 6), 0.0, -0.5], atol=1e-12)
    straight_end = problem.start.point + problem.hose.length * problem.start.direction
    assert straight_end[2] < -RADIUS  # the straight hose the sequence starts from runs 50 mm into the floor
    with pytest.raises(PlacementError, match="straight hose .* 'floor'"):  # the old way refuses it
        solve(replace(problem, contact_placement="along_path"), estimate_error=False)
    place_again_and_save(session, tmp_path)
    assert lying_on(session.result(), 0.0) >= 3


@pytest.mark.parametrize("mass", [0.5, 2.0])
def test_a_heavier_hose_on_a_floor_1_mm_below_its_weightless_shape_is_placed_again_and_saved_as_shown(mass, tmp_path):
    """The issue's case: the floor 1 mm below the weightless hose's lowest surface; the weight slider raised from 0 to
    `mass` kg/m lays the hose on it (w L^3 / EI = 630 and 2500)."""
    data = problem_to_dict(resting_hose(contact=False))
    data["hose"]["mass_per_length"] = 0.0
    weightless = solve(problem_from_dict(data), estimate_error=False)
    floor = float(np.min(weightless.centerline[:, 2])) - RADIUS - 1.0
    session = Session(floor_problem(data, floor))
    assert lying_on(session.result(), floor) == 0
    for k, step in enumerate(np.linspace(0.0, mass, 5)[1:], start=1):
        session.apply(Target(type="set", seq=k, hose={"mass_per_length": float(step)}))
    assert lying_on(session.result(), floor) >= 3
    place_again_and_save(session, tmp_path)
    assert lying_on(session.result(), floor) >= 3


def barred_hose(hose_side, radius: float = 5.0, above: float = 3.0):
    """The hose of tests/test_studio_contact.py without the floor, self-contact on, and a bar (cylinder of `radius`
    mm, across the hose's plane) through the middle station of its free shape, its axis `above` mm above it;
    hose_side for the bar, or None."""
    data = problem_to_dict(resting_hose(contact=False))
    middle = solve(problem_from_dict(data), estimate_error=False).centerline[15]
    bar = {"kind": "cylinder", "start": (middle + [0.0, -60.0, above]).tolist(),
           "end": (middle + [0.0, 60.0, above]).tolist(), "radius": radius, "name": "bar"}
    if hose_side is not None:
        bar["hose_side"] = hose_side
    data["contact"] = {"self": True, "obstacles": [bar]}
    return problem_from_dict(data), middle


def test_a_drag_keeps_the_hose_side_so_place_again_and_the_saved_file_keep_the_hose_over_the_bar(tmp_path):
    """Unhinted the free hose is pushed under the bar (the side of least penetration: the bar's axis is above it);
    hose_side = +z lays it over the bar.  A drag, "Place again" and the saved file keep that choice."""
    unhinted, middle = barred_hose(None)
    assert solve(unhinted, estimate_error=False).centerline[15, 2] < middle[2]
    problem, _ = barred_hose([0.0, 0.0, 1.0])
    session = Session(problem)
    assert session.result().centerline[15, 2] > middle[2]
    dragged(session, [0.0, 10.0, -10.0])
    np.testing.assert_allclose(session.problem.contact_sides[0], [0.0, 0.0, 1.0])
    document = place_again_and_save(session, tmp_path)
    assert session.result().centerline[15, 2] > middle[2]
    [brought] = document["summary"]["contact"]["placement"]
    assert brought["rule"] == "hose_side" and brought["hose_side"][2] > 0.7
    assert "hose_side" in session.problem_toml()


def test_where_a_drag_leaves_the_hose_on_the_other_side_of_the_bar_the_badge_says_so_and_place_again_goes_there(
        tmp_path):
    """Another stable equilibrium shown: placed over a bar (radius 8 mm, its axis 2 mm below the free hose), the hose
    dragged 14 mm stays over it, while a fresh placement there pushes it under the bar.  The badge gives the
    distance to that shape; "Place again" shows it, and the saved file gives it."""
    problem, middle = barred_hose(None, radius=8.0, above=-2.0)
    session = Session(problem)
    dragged(session, [0.0, 10.0, -10.0])
    assert session.result().centerline[15, 2] > middle[2]  # over the bar
    badge = session.compare_with_placement()
    assert not badge["same"] and badge["distance"] > 10.0
    place_again_and_save(session, tmp_path)
    assert session.result().centerline[15, 2] < middle[2]  # under it


def test_a_hose_over_a_bar_through_its_free_shape_dragged_down_is_placed_again_and_saved_as_shown(tmp_path):
    """A bar of radius 10 mm through the free hose's middle: placed, the hose lies over it; its end dragged 6 mm down,
    it still does, clear of the bar and stable.  "Place again" must place that state too."""
    problem, middle = barred_hose(None, radius=10.0, above=0.0)
    session = Session(problem)
    dragged(session, [0.0, 0.0, -6.0])
    assert session.result().centerline[15, 2] > middle[2]
    place_again_and_save(session, tmp_path)
