"""A weightless hose pulled over a cylinder (a drum): where it wraps, its curvature is 1/(R + r),
and the drum's push balances the mounts' reactions."""

from dataclasses import replace

import numpy as np
import pytest

from hoseline.mechanics.contact_newton import evaluate_contact, minimum_gap
from hoseline.mechanics.energy import joint_moments
from hoseline.mechanics.newton import node_positions
from hoseline.model.hose import Hose
from hoseline.model.mounts import Mount
from hoseline.model.obstacles import Cylinder
from hoseline.model.problem import Problem
from hoseline.procedures.contact.continuation import follow_contact
from hoseline.procedures.contact.model import bend_length, contact_model, reference_pressure
from hoseline.procedures.placement.sequence import place_only

LENGTH, EI, RADIUS, DRUM = 335.0, 1e5, 5.0, 40.0


@pytest.fixture(scope="module")
def over_the_drum():
    """Placed (no contact) with the end high, the hose passing above the drum; then the end carried down
    beside the drum with contact on, which pulls the hose taut over it: (props, clamps, state, model)."""
    hose = Hose(length=LENGTH, outer_diameter=2 * RADIUS, bending_stiffness=EI, torsional_stiffness=EI, segments=100)
    up = np.array([0.0, 0.0, 1.0])
    problem = Problem(hose, Mount(np.array([-100.0, 0.0, -80.0]), up), Mount(np.array([60.0, 0.0, 150.0]), up))
    props, high, state, _ = place_only(problem)
    drum = Cylinder(np.array([0.0, -200.0, 0.0]), np.array([0.0, 200.0, 0.0]), DRUM, "drum")
    pressure = reference_pressure(0.0, EI, bend_length(LENGTH, [drum], RADIUS))
    model = contact_model([drum], RADIUS, props.segment_length, pressure)
    assert minimum_gap(props, high, state, model) > 10.0
    end = np.array([100.0, 0.0, -80.0])

    def path(t):
        return replace(high, end_point=(1.0 - t) * high.end_point + t * end)

    state, _ = follow_contact("pull down", path, props, state, model)
    return props, path(1.0), state, model


def test_wrapped_part_has_the_drum_curvature(over_the_drum):
    props, clamps, state, model = over_the_drum
    gap = minimum_gap(props, clamps, state, model)
    assert 0.0 < gap < model.activation
    system = evaluate_contact(props, clamps, state, model)
    segments = np.unique(system.pairs[1])
    assert segments.size >= 15  # a wrap, not a touch
    h = props.segment_length
    _, darboux = joint_moments(state.frames, clamps.start_frame, clamps.end_frame, props.stiffness, h)
    curvature = np.linalg.norm(darboux[:, :2], axis=1)
    # joints inside the wrap, away from its ends: there the point reactions where the hose leaves the
    # drum bend the discrete hose over a few segments (curvature off by 1 % at the second joint in)
    inner = np.arange(segments.min() + 5, segments.max() - 3)
    expected = 1.0 / (DRUM + RADIUS)
    # a polygon of chord h on a circle of radius rho: discrete curvature 2 tan(angle / 2) / h is
    # 1/rho (1 + h^2 / 8 rho^2 + ...), 8e-4 % here; the gap (below d_hat) moves rho by less than 2e-4 %
    assert np.all(np.abs(curvature[inner] / expected - 1.0) < 2e-4), curvature[inner] / expected
    nodes = node_positions(props, clamps, state)
    radial = np.hypot(nodes[inner, 0], nodes[inner, 2]) - DRUM - RADIUS
    assert np.all(radial < model.activation + (h / 2) ** 2 / (2 * (DRUM + RADIUS)))


def test_drum_push_balances_the_mount_reactions(over_the_drum):
    props, clamps, state, model = over_the_drum
    system = evaluate_contact(props, clamps, state, model)
    push = system.forces.sum(axis=0)
    # weightless and symmetric: the start mount's force is the mirror image of the end mount's, so the
    # drum's push is minus their sum
    mirrored = state.end_force * np.array([-1.0, 1.0, 1.0])
    np.testing.assert_allclose(push, -(state.end_force + mirrored), rtol=1e-6, atol=1e-9 * np.abs(push).max())
    assert push[2] > 0.0  # the drum pushes the hose up
    # frictionless: every contact force points away from the drum's axis
    radial = system.on_hose[:, [0, 2]] / np.linalg.norm(system.on_hose[:, [0, 2]], axis=1)[:, None]
    along = np.sum(system.forces[:, [0, 2]] * radial, axis=1)
    np.testing.assert_allclose(along, np.linalg.norm(system.forces, axis=1), rtol=1e-9)
