"""Contact from the problem file to the result: [contact] tables, placement with contact, the report per obstacle."""

import tomllib

import numpy as np
import pytest

from hoseline.io.problem_file import ProblemFileError, problem_from_dict, problem_to_dict, problem_to_toml
from hoseline.procedures.contact.model import DEFAULT_ACTIVATION
from hoseline.procedures.placement.continuation import PlacementError
from hoseline.procedures.placement.sequence import solve

DRUM_RADIUS, HOSE_RADIUS = 30.0, 5.0
BASE = {"hose": {"length": 335.0, "outer_diameter": 2 * HOSE_RADIUS, "bending_stiffness": 1e5, "segments": 50},
        "start": {"point": [-100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]},
        "end": {"point": [100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]}}
DRUM = {"kind": "cylinder", "start": [0.0, -200.0, 0.0], "end": [0.0, 200.0, 0.0], "radius": DRUM_RADIUS, "name": "drum"}


def with_contact(contact: dict) -> dict:
    return dict(BASE, contact=contact)


def test_contact_tables_round_trip_through_toml():
    contact = {"self": True, "obstacles": [
        {"kind": "plane", "point": [0.0, 0.0, -300.0], "normal": [0.0, 0.0, 2.0], "name": "floor"},
        {"kind": "sphere", "center": [0.0, 50.0, 0.0], "radius": 5.0},
        {"kind": "sphere", "center": [0.0, 90.0, 0.0], "radius": 6.0},
        DRUM]}
    problem = problem_from_dict(with_contact(contact))
    assert problem.self_contact and len(problem.contact) == 4
    assert [o.name for o in problem.contact] == ["floor", "sphere 1", "sphere 2", "drum"]
    np.testing.assert_allclose(problem.contact[0].normal, [0.0, 0.0, 1.0])
    again = problem_from_dict(tomllib.loads(problem_to_toml(problem)))
    assert problem_to_dict(again) == problem_to_dict(problem)
    assert "contact" not in problem_to_dict(problem_from_dict(BASE))  # no [contact]: the file is as before


@pytest.mark.parametrize("contact, expected", [
    ({"self": 1}, "contact.self = 1: must be true or false"),
    ({"slf": True}, "did you mean 'contact.self'"),
    ({"obstacles": [{"kind": "cone"}]}, "contact.obstacles[0].kind = \"cone\": must be one of"),
    ({"obstacles": [{"kind": "plane", "point": [0, 0, 0]}]}, "contact.obstacles[0]: a plane takes point and normal: missing normal"),
    ({"obstacles": [{"kind": "sphere", "center": [0.0, 0, 0], "radius": 1.0, "normal": [0, 0, 1]}]}, "normal given"),
    ({"obstacles": [{"kind": "sphere", "center": [0.0, 0, 0], "radius": -2.0}]}, "contact.obstacles[0].radius = -2.0: must be positive"),
    ({"obstacles": [DRUM, DRUM]}, "contact.obstacles[1].name = 'drum' is used by an earlier obstacle"),
    ({"obstacles": [dict(DRUM, name="self")]}, "is reserved for self-contact"),
    ({"obstacles": [dict(DRUM, end=DRUM["start"])]}, "contact.obstacles[0]: obstacle 'drum': start and end coincide"),
])
def test_bad_contact_tables_are_refused_naming_the_field(contact, expected):
    with pytest.raises(ProblemFileError) as error:
        problem_from_dict(with_contact(contact))
    assert expected in str(error.value)


@pytest.fixture(scope="module")
def over_the_drum():
    """(placed without contact, placed with the drum): the free arch passes through the drum."""
    return solve(problem_from_dict(BASE), estimate_error=False), solve(problem_from_dict(with_contact({"obstacles": [DRUM]})))


def test_placement_with_contact_rests_on_the_drum_without_entering_it(over_the_drum):
    free, touching = over_the_drum
    axis_distance = np.hypot(free.centerline[:, 0], free.centerline[:, 2])
    assert axis_distance.min() < DRUM_RADIUS + HOSE_RADIUS - 1.0  # without contact the hose passes through the drum
    gap = touching.summary()["contact"]["min_gap_mm"]
    assert 0.0 < gap < DEFAULT_ACTIVATION
    assert np.hypot(touching.centerline[:, 0], touching.centerline[:, 2]).min() > DRUM_RADIUS + HOSE_RADIUS
    drum, = touching.contacts
    assert drum.name == "drum" and drum.kind == "cylinder"
    # the arch is flatter than the drum at its top (curvature 0.014 against 1/(R + r) = 0.029 1/mm): it rests on
    # a point there, which takes the whole push, and lies on no length
    touch, = drum.touchdowns
    assert drum.length_in_contact == 0.0 and touch.arc_length == pytest.approx(335.0 / 2)
    np.testing.assert_allclose(touch.force, drum.total_force, rtol=1e-12)
    assert np.all((drum.gap > 0.0) & (drum.gap < DEFAULT_ACTIVATION))
    # frictionless: every push points away from the drum's axis (the y axis), through the hose point
    radial = drum.point[:, [0, 2]] / np.linalg.norm(drum.point[:, [0, 2]], axis=1)[:, None]
    np.testing.assert_allclose(np.sum(drum.force[:, [0, 2]] * radial, axis=1), np.linalg.norm(drum.force, axis=1),
                               rtol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(drum.surface_point[:, [0, 2]], axis=1), DRUM_RADIUS, rtol=1e-12)
    assert np.all((drum.arc_length > 0.0) & (drum.arc_length < 335.0))
    assert touching.stable and touching.residual < 1e-8


def test_mounts_and_drum_balance_and_the_internal_force_carries_the_push(over_the_drum):
    _, touching = over_the_drum
    drum = touching.contacts[0]
    # weightless: the mounts' reactions and the drum's push sum to zero
    np.testing.assert_allclose(touching.start_force + touching.end_force + drum.total_force, 0.0,
                               atol=1e-9 * np.linalg.norm(drum.total_force))
    assert drum.total_force[2] > 0.0
    # the internal force steps by the push: beyond the contact it is the end reaction alone
    np.testing.assert_allclose(touching.internal_force[-1], touching.end_force, atol=1e-12)
    np.testing.assert_allclose(touching.internal_force[0], -touching.start_force, atol=1e-12)
    summary = touching.summary()["contact"]["obstacles"][0]
    assert summary["name"] == "drum" and len(summary["points"]) == drum.gap.size


def test_along_the_path_a_start_inside_an_obstacle_is_refused_naming_it():
    ball = {"kind": "sphere", "center": [-100.0, 0.0, 50.0], "radius": 10.0, "name": "ball"}  # on the straight start
    with pytest.raises(PlacementError) as error:
        solve(problem_from_dict(with_contact({"placement": "along_path", "obstacles": [ball]})), estimate_error=False)
    assert "'ball'" in str(error.value) and "straight hose" in str(error.value)


def test_brought_in_an_obstacle_on_the_straight_start_only_is_no_obstacle_and_is_reported_clear():
    ball = {"kind": "sphere", "center": [-100.0, 0.0, 50.0], "radius": 10.0, "name": "ball"}  # on the straight start
    result = solve(problem_from_dict(with_contact({"obstacles": [ball]})), estimate_error=False)
    free = solve(problem_from_dict(BASE), estimate_error=False)
    np.testing.assert_allclose(result.centerline, free.centerline, atol=1e-9)  # the free shape clears it
    placement, = result.summary()["contact"]["placement"]
    assert placement["name"] == "ball" and placement["rule"] == "clear" and placement["hose_side"] is None
    assert placement["free_gap_mm"] == pytest.approx(result.contacts[0].min_gap)


def test_a_sweep_file_takes_contact():  # the sweep itself: tests/test_sweep_contact.py
    from hoseline.io.sweep_file import sweep_from_dict

    data = with_contact({"obstacles": [DRUM]}) | {
        "end": dict(BASE["end"], body="arm"),
        "bodies": [{"name": "arm", "stages": [{"name": "lift", "translate": [0.0, 5.0], "axis": [0, 0, 1], "steps": 2}]}]}
    assert [obstacle.name for obstacle in sweep_from_dict(data).problem.contact] == ["drum"]


def test_self_contact_is_reported_with_the_obstacles():
    result = solve(problem_from_dict(with_contact({"self": True, "obstacles": [DRUM]})), estimate_error=False)
    drum, itself = result.contacts
    assert (drum.name, itself.name, itself.kind) == ("drum", "self", "self")
    assert 0.0 < drum.min_gap < DEFAULT_ACTIVATION and len(drum.touchdowns) == 1  # a point contact, as above
    # the arch does not come near itself: no self-contact pairs, and its smallest gap is that of passes
    # ceil(pi r / h) + 1 segments apart on a nearly straight stretch, about their spacing less 2 r
    assert itself.gap.size == 0 and itself.length_in_contact == 0.0 and itself.min_gap > 5.0
    assert result.summary()["contact"]["min_gap_mm"] == pytest.approx(drum.min_gap)


def test_accuracy_with_contact_refines_until_the_estimate_meets_it():
    from hoseline.procedures.placement.refinement import solve_to_accuracy

    problem = problem_from_dict(with_contact({"obstacles": [DRUM]}))  # 50 segments: estimated 0.28 mm
    result = solve_to_accuracy(problem, 0.05)
    assert result.problem.hose.segments > 50 and result.discretisation_error <= 0.05
    assert any(event.startswith("accuracy: with contact, estimated errors") for event in result.events)


@pytest.mark.parametrize("placement", ["bring_in", "along_path"])
def test_an_end_mount_inside_an_obstacle_is_refused_as_bad_input_naming_the_fitting(placement):
    sphere = {"kind": "sphere", "center": [100.0, 0.0, -82.0], "radius": 4.0, "name": "knob"}  # around the end point
    with pytest.raises(ProblemFileError) as failure:
        problem_from_dict(with_contact({"placement": placement, "obstacles": [sphere]}))
    message = str(failure.value)
    assert "[contact]: the hose at the end fitting is held inside obstacle 'knob'" in message
    assert "Move the obstacle" in message


def test_the_solver_refuses_a_mount_inside_an_obstacle_too_naming_the_fitting():
    from dataclasses import replace

    from hoseline.model.obstacles import Sphere

    problem = replace(problem_from_dict(BASE), contact=(Sphere([100.0, 0.0, -82.0], 4.0, "knob"),))  # not from a file
    with pytest.raises(PlacementError, match="the hose at the end fitting is held inside obstacle 'knob'"):
        solve(problem, estimate_error=False)


def test_a_drum_of_40_mm_across_the_end_fitting_s_path_is_brought_in_and_the_hose_rests_on_it():
    result = solve(problem_from_dict(with_contact({"obstacles": [DRUM | {"radius": 40.0}]})), estimate_error=False)
    drum, = result.contacts
    assert 0.0 < drum.min_gap < DEFAULT_ACTIVATION and result.stable
    assert np.hypot(result.centerline[:, 0], result.centerline[:, 2]).min() > 40.0 + HOSE_RADIUS
    placement, = result.summary()["contact"]["placement"]
    assert placement["rule"] == "least penetration" and placement["hose_side"][2] > 0.9  # the hose over the drum


def test_along_the_path_a_drum_of_40_mm_across_the_end_fitting_s_path_is_refused_before_any_solve():
    # docs/model.md: it once stopped at fraction 0.67 of the place phase; the end fitting's straight path from the
    # straight hose's end (-100, 0, 255) to its mount (100, 0, -80) passes within the hose radius of the drum there
    with pytest.raises(PlacementError) as failure:
        solve(problem_from_dict(with_contact({"placement": "along_path", "obstacles": [DRUM | {"radius": 40.0}]})),
              estimate_error=False)
    assert "carries the end fitting" in str(failure.value)
    assert "obstacle 'drum' between fractions 0.680 and 0.705" in str(failure.value)
