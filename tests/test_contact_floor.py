"""A heavy hose hanging between two mounts onto a frictionless floor, against the shooting
solution of the planar elastica with a free boundary (tests/elastica_floor_shooting.py)."""

from dataclasses import replace

import numpy as np
import pytest

from elastica_floor_shooting import solve_floor_elastica
from hoseline.mechanics.contact_newton import evaluate_contact, minimum_gap, solve_with_contact
from hoseline.mechanics.energy import joint_moments
from hoseline.mechanics.newton import node_positions
from hoseline.model.hose import Hose
from hoseline.model.mounts import Mount
from hoseline.model.obstacles import Plane
from hoseline.model.problem import Problem
from hoseline.procedures.contact.continuation import follow_contact
from hoseline.procedures.contact.model import contact_model, reference_pressure
from hoseline.procedures.placement.sequence import place_only

LENGTH, EI, MASS, HALF_SPAN, HEIGHT, RADIUS = 1000.0, 2e4, 0.5, 420.0, 150.0, 5.0
WEIGHT = MASS * 9.81e-3  # N/mm
SEGMENTS = 100


@pytest.fixture(scope="module")
def on_the_floor():
    """The hose placed (no contact) with its end high, where it clears the floor, then the end carried to its
    mount with contact on: (props, clamps, state, model)."""
    hose = Hose(length=LENGTH, outer_diameter=2 * RADIUS, bending_stiffness=EI, torsional_stiffness=EI,
                mass_per_length=MASS, segments=SEGMENTS)
    down = np.array([0.0, 0.0, -1.0])
    problem = Problem(hose, Mount(np.array([-HALF_SPAN, 0.0, HEIGHT]), down), Mount(np.array([300.0, 0.0, 500.0]), down),
                      gravity=np.array([0.0, 0.0, -9.81]))
    props, high, state, _ = place_only(problem)
    floor = Plane(np.zeros(3), np.array([0.0, 0.0, 1.0]), "floor")
    model = contact_model([floor], RADIUS, props.segment_length, reference_pressure(WEIGHT, EI, LENGTH))
    assert minimum_gap(props, high, state, model) > 10.0  # the start clears the floor
    end = np.array([HALF_SPAN, 0.0, HEIGHT])

    def path(t):
        return replace(high, end_point=(1.0 - t) * high.end_point + t * end)

    state, _ = follow_contact("lower the end", path, props, state, model)
    return props, path(1.0), state, model


def test_lifted_length_and_touchdown_match_the_shooting_solution(on_the_floor):
    props, clamps, state, model = on_the_floor
    exact = solve_floor_elastica(LENGTH, EI, WEIGHT, HALF_SPAN, HEIGHT, RADIUS)
    h = props.segment_length
    nodes = node_positions(props, clamps, state)
    system = evaluate_contact(props, clamps, state, model)
    in_contact = np.unique(system.pairs[1])
    # touch-down on the right: the bending moment grows linearly from zero there (the shear is the point
    # reaction); extrapolate the curvature of the first two stations off the floor to zero
    _, darboux = joint_moments(state.frames, clamps.start_frame, clamps.end_frame, props.stiffness, h)
    curvature = np.linalg.norm(darboux[:, :2], axis=1)
    k = int(in_contact.max()) + 1
    s_touch = k * h - curvature[k] * h / (curvature[k + 1] - curvature[k])
    lifted = LENGTH - s_touch
    assert abs(lifted - exact.lifted) < 1e-3 * LENGTH, (lifted, exact.lifted)
    x_touch = np.interp(s_touch, np.arange(SEGMENTS + 1) * h, nodes[:, 0])
    assert abs(x_touch - exact.touchdown) < 1e-3 * LENGTH, (x_touch, exact.touchdown)
    # the left side is the mirror image
    j = int(in_contact.min()) - 1
    s_left = j * h + curvature[j] * h / (curvature[j - 1] - curvature[j])
    assert abs(s_left - exact.lifted) < 1e-3 * LENGTH
    # the suspended shape, station by station, against the shooting curve at the same distance from the mount
    for k in range(SEGMENTS + 1):
        sigma = k * h - (LENGTH - exact.lifted)
        if sigma > 0.0:
            x, z = exact.shape(sigma)[:2]
            assert np.hypot(nodes[k, 0] - x, nodes[k, 2] - z) < 1e-3 * LENGTH, k
    # the force along the floor is the end mount's horizontal force
    assert state.end_force[0] == pytest.approx(exact.horizontal, rel=0.03)


def test_resting_hose_never_penetrates_and_the_floor_carries_its_share(on_the_floor):
    props, clamps, state, model = on_the_floor
    gap = minimum_gap(props, clamps, state, model)
    assert 0.0 < gap < model.activation
    system = evaluate_contact(props, clamps, state, model)
    exact = solve_floor_elastica(LENGTH, EI, WEIGHT, HALF_SPAN, HEIGHT, RADIUS)
    floor_load = float(np.sum(system.forces[:, 2]))
    # the floor carries the weight of the hose lying on it plus the two touch-down reactions
    expected = WEIGHT * (LENGTH - 2 * exact.lifted) + 2 * exact.reaction
    assert floor_load == pytest.approx(expected, rel=0.02)
    # and the vertical balance of the whole hose closes: mounts + floor = weight
    start_force_z = WEIGHT * LENGTH - floor_load - state.end_force[2]
    assert start_force_z == pytest.approx(state.end_force[2], rel=1e-6, abs=1e-9)  # symmetric mounts


def test_a_state_inside_an_obstacle_is_refused_naming_it(on_the_floor):
    props, clamps, state, model = on_the_floor
    raised = replace(model, planes=model.planes + np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0]))
    _, report = solve_with_contact(props, clamps, state, raised)
    assert not report.converged
    assert "floor" in report.message and "station" in report.message
