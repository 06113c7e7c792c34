"""Where a contact carries its force (procedures/contact/extent.py): the arc the hose lies on, its touch-down
points and their point forces, against free-boundary solutions of the elastica that are not hoseline's rod:
the heavy hose on a floor (tests/elastica_floor_shooting.py), the weightless hose pulled over a drum
(tests/elastica_drum_shooting.py), and the issue's heavy hose placed onto the floor its fittings point at
(tests/floor_free_boundary.py, symmetric and not)."""

import math

import numpy as np
import pytest

from elastica_drum_shooting import solve_drum_elastica
from elastica_floor_shooting import solve_floor_elastica
from hoseline.model.hose import Hose
from hoseline.model.mounts import Mount
from hoseline.model.obstacles import Cylinder, Plane
from hoseline.model.problem import Problem
from hoseline.io.problem_file import problem_from_dict
from hoseline.procedures.contact.placement import contact_reports
from hoseline.procedures.placement.sequence import solve
from test_contact_bring_in import shooting_reference
from hoseline.demos.floor import ASYMMETRIC, SYMMETRIC, floor_data
from test_contact_bring_in import LENGTH as HEAVY_LENGTH
from test_contact_bring_in import WEIGHT as HEAVY_WEIGHT
from test_contact_cylinder import DRUM, over_the_drum  # noqa: F401 (a fixture)
from test_contact_cylinder import EI as DRUM_EI
from test_contact_floor import EI, HALF_SPAN, HEIGHT, LENGTH, RADIUS, WEIGHT, on_the_floor  # noqa: F401 (a fixture)


def _report(props, clamps, state, model, obstacle, gravity):
    """The ObstacleContact of `obstacle` at the state (the problem only names the obstacle for the report)."""
    hose = Hose(length=props.length, outer_diameter=2 * RADIUS, bending_stiffness=props.stiffness[0],
                torsional_stiffness=props.stiffness[2], segments=props.segments)
    start, end = Mount(clamps.start_point, clamps.start_frame[2]), Mount(clamps.end_point, -clamps.end_frame[2])
    problem = Problem(hose, start, end, gravity=gravity, contact=[obstacle])
    (report,), _ = contact_reports(problem, props, clamps, state, model)
    return report


@pytest.fixture(scope="module")
def floor(on_the_floor):
    props, clamps, state, model = on_the_floor
    report = _report(props, clamps, state, model, Plane(np.zeros(3), np.array([0.0, 0.0, 1.0]), "floor"),
                     np.array([0.0, 0.0, -9.81]))
    return props, report, solve_floor_elastica(LENGTH, EI, WEIGHT, HALF_SPAN, HEIGHT, RADIUS)


def test_the_floor_carries_the_hose_where_the_free_boundary_solution_lies_on_it(floor):
    props, report, exact = floor
    h = props.segment_length
    lying = LENGTH - 2.0 * exact.lifted  # 434.6 mm
    arc, = report.carried
    assert report.length_in_contact == pytest.approx(arc.length)
    assert arc.length == pytest.approx(lying, rel=0.01), (arc.length, lying)
    # the barrier's reach is longer: its pairs span the stations next to the touch-downs too
    assert report.arc_length[-1] - report.arc_length[0] > 1.01 * lying
    # the touch-downs to a tenth of a segment, in arc length and on the floor
    left, right = report.touchdowns
    assert left.arc_length == pytest.approx(exact.lifted, abs=0.1 * h)
    assert right.arc_length == pytest.approx(LENGTH - exact.lifted, abs=0.1 * h)
    np.testing.assert_allclose(left.point, [-exact.touchdown, 0.0, RADIUS], atol=0.1 * h)
    np.testing.assert_allclose(right.point, [exact.touchdown, 0.0, RADIUS], atol=0.1 * h)
    assert (arc.start, arc.end) == (left.arc_length, right.arc_length)


def test_the_floor_pushes_the_weight_per_length_where_the_hose_lies_and_the_shear_jump_at_touch_down(floor):
    props, report, exact = floor
    arc = report.carried[0]
    # a point force at each touch-down, straight up, of the free-boundary solution's shear jump
    for touchdown in report.touchdowns:
        np.testing.assert_allclose(touchdown.force[:2], 0.0, atol=1e-9)
        assert touchdown.force[2] == pytest.approx(exact.reaction, rel=0.01), (touchdown.force, exact.reaction)
    # between them the floor carries the weight of the hose lying on it: the weight per length
    np.testing.assert_allclose(arc.distributed_force[:2], 0.0, atol=1e-9)
    assert arc.distributed_force[2] / arc.length == pytest.approx(WEIGHT, rel=0.01)
    # and the parts make up the floor's whole push
    parts = arc.distributed_force + sum(touchdown.force for touchdown in report.touchdowns)
    np.testing.assert_allclose(parts, report.total_force, rtol=1e-12)


@pytest.fixture(scope="module")
def drum(over_the_drum):
    props, clamps, state, model = over_the_drum
    obstacle = Cylinder(np.array([0.0, -200.0, 0.0]), np.array([0.0, 200.0, 0.0]), DRUM, "drum")
    report = _report(props, clamps, state, model, obstacle, np.zeros(3))
    # the fixture's mounts: (-+100, -80) mm, the fittings pointing up; the drum's axis is the y axis
    return props, report, solve_drum_elastica(props.length, DRUM_EI, DRUM, RADIUS, 100.0, -80.0)


def test_the_drum_wrap_is_the_free_boundary_solution_s(drum):
    props, report, exact = drum
    h = props.segment_length
    arc, = report.carried
    assert exact.wrap == pytest.approx(62.24, abs=0.01)  # the elastica's wrap, not the tangent points of a string
    assert arc.length == pytest.approx(exact.wrap, rel=0.01), (arc.length, exact.wrap)
    assert report.length_in_contact == pytest.approx(arc.length)
    start, end = report.touchdowns
    assert start.arc_length == pytest.approx(exact.lift_off, abs=0.1 * h)
    assert end.arc_length == pytest.approx(props.length - exact.lift_off, abs=0.1 * h)
    rho = DRUM + RADIUS
    for touchdown, side in ((start, -1.0), (end, 1.0)):
        expected = rho * np.array([side * math.sin(exact.half_angle), 0.0, math.cos(exact.half_angle)])
        np.testing.assert_allclose(touchdown.point, expected, atol=0.1 * h)


def test_the_drum_pushes_the_tension_over_the_radius_and_a_point_force_at_each_lift_off(drum):
    props, report, exact = drum
    arc = report.carried[0]
    rho = DRUM + RADIUS
    for touchdown, side in zip(report.touchdowns, (-1.0, 1.0)):
        outward = np.array([side * math.sin(exact.half_angle), 0.0, math.cos(exact.half_angle)])
        assert np.linalg.norm(touchdown.force) == pytest.approx(exact.point_force, rel=0.01)
        # along the drum's normal at the lift-off point, to the angle of a tenth of a segment on the drum
        turned = math.acos(min(1.0, touchdown.force @ outward / np.linalg.norm(touchdown.force)))
        assert turned < 0.1 * props.segment_length / rho, turned
    # T / rho over the wrap: its resultant, 2 T sin(alpha), upward
    distributed = 2.0 * exact.tension * math.sin(exact.half_angle)
    assert arc.distributed_force[2] == pytest.approx(distributed, rel=0.01)
    assert abs(arc.distributed_force[0]) < 1e-6 * distributed
    parts = arc.distributed_force + sum(touchdown.force for touchdown in report.touchdowns)
    np.testing.assert_allclose(parts, report.total_force, rtol=1e-12)


def test_the_summary_lists_the_carried_arcs_and_the_touchdowns(floor):
    _, report, _ = floor
    summary = report.summary()
    carried, = summary["carried_arcs"]
    assert carried["length_mm"] == pytest.approx(summary["length_in_contact_mm"])
    assert [t["arc_length_mm"] for t in summary["touchdowns"]] == [carried["start_mm"], carried["end_mm"]]
    assert len(summary["points"]) == report.gap.size  # the barrier's pairs


@pytest.fixture(scope="module", params=[SYMMETRIC, ASYMMETRIC], ids=["symmetric", "asymmetric"])
def placed_on_the_floor(request):
    """The issue's heavy hose (w L^3 / EI = 80) placed by solve onto the floor its fittings point at, and the
    free-boundary shooting solution of its layout."""
    result = solve(problem_from_dict(floor_data(*request.param)), estimate_error=False)
    return result, shooting_reference(result, request.param)


def test_the_placed_heavy_hose_lies_on_the_floor_as_the_free_boundary_solution(placed_on_the_floor):
    result, exact = placed_on_the_floor
    h = HEAVY_LENGTH / (result.centerline.shape[0] - 1)
    s_l, s_r = exact.lifted
    floor, = result.contacts
    arc, = floor.carried
    assert floor.length_in_contact == pytest.approx(HEAVY_LENGTH - s_l - s_r, rel=0.01)  # measured 0.43 %, 0.45 %
    left, right = floor.touchdowns
    assert left.arc_length == pytest.approx(s_l, abs=0.1 * h)
    assert right.arc_length == pytest.approx(HEAVY_LENGTH - s_r, abs=0.1 * h)
    # the point forces are the shear jumps of the free boundary (measured 1.0 % and 0.6 % off: 20 mm segments)
    for touchdown, shear in zip(floor.touchdowns, exact.shears):
        assert touchdown.force[2] == pytest.approx(-shear, rel=0.015)
    assert arc.distributed_force[2] / arc.length == pytest.approx(HEAVY_WEIGHT, rel=0.005)
    np.testing.assert_allclose(arc.distributed_force + left.force + right.force, floor.total_force, rtol=1e-12)
