"""The uniqueness verdict at half a turn with a set, with the thesis' springs and with weight across the mounts'
plane, where no mirror image exists: the end fitting turned the other way round to the same clamp gives a second
shape (issue 32 item 1); and a verdict that could not be checked says so."""

from dataclasses import replace

import numpy as np
import pytest
from validation_cases import brake_hose

from hoseline import solve
from hoseline.model.preset import Preset
from hoseline.model.stiffeners import thesis_preset
from hoseline.procedures.placement.sequence import place_only
from hoseline.procedures.placement.uniqueness import Candidate, judge_uniqueness


def with_preset(twist):
    problem = brake_hose(segments=60, twist=twist)
    return replace(problem, hose=replace(problem.hose, preset=Preset(1.0 / 400.0, 30.0)))


def heavy(twist):
    return brake_hose(segments=60, twist=twist)  # its weight across the mounts' plane: no mirror image


def stiffened(twist):
    problem = brake_hose(twist=twist)
    springs = thesis_preset(problem.hose.length)
    return replace(problem, hose=replace(problem.hose, stiffeners=springs.stiffeners, segments=springs.segments))


@pytest.mark.parametrize("make, apart", [(with_preset, 172.6), (heavy, 176.6)], ids=["preset", "weight"])
def test_at_half_a_turn_the_other_way_round_is_a_second_shape_of_the_same_assembly(make, apart):
    up, down = solve(make(180.0)), solve(make(-180.0))
    assert np.max(np.abs(up.end_frame - down.end_frame)) < 1e-12  # the same clamp
    shapes_apart = float(np.max(np.linalg.norm(up.centerline - down.centerline, axis=1)))
    assert shapes_apart == pytest.approx(apart, abs=2.0)
    for result, other in ((up, down), (down, up)):
        assert result.unique is False and result.summary()["uniqueness"] == "no"
        (found,) = [o for o in result.other_equilibria if o.origin.startswith("the end fitting turned the other way")]
        assert found.same_clamps and found.max_distance == pytest.approx(shapes_apart, rel=1e-6)
        energy = result.elastic_energy + result.gravity_energy
        assert found.energy_gap == pytest.approx(other.elastic_energy + other.gravity_energy - energy, abs=1e-3)


def test_with_the_thesis_springs_at_half_a_turn():
    result = solve(stiffened(180.0), estimate_error=False)
    (found,) = result.other_equilibria
    assert result.unique is False and found.same_clamps and found.max_distance == pytest.approx(142.5, abs=2.0)


def test_a_twist_under_half_a_turn_does_not_try_the_longer_way():
    result = solve(with_preset(90.0))
    assert result.unique is True and not result.other_equilibria


def test_a_search_that_could_not_be_followed_leaves_the_verdict_not_checked():
    problem = with_preset(90.0)
    result = solve(problem, estimate_error=False)
    props, final, state, _ = place_only(problem)
    judge_uniqueness(result, props, final, state, [Candidate("a branch could not be followed to the end", None, None)], [])
    assert result.unique is None and result.summary()["uniqueness"] == "not checked"
    assert result.summary()["unique"] is None and "could not be followed" in result.summary()["uniqueness_not_checked"]
