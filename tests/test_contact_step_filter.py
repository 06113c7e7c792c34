"""The bounds the contact step filter (mechanics/contact_newton.py, StepFilter) rests on, on random steps of a
helix whose turns nearly touch (self-contact) beside a floor and a capsule:

- a rotation step alpha delta moves segment j relative to segment i (i < j) by at most
  h sum_(k=i..j) alpha |delta_k|, so a self pair's gap changes by no more than that;
- two segments' surfaces are at least their midpoints' distance less a segment length and a diameter apart;
- `admits`, which takes exact gaps only where that second bound does not clear, decides as the exact gaps of
  every watched pair do.
"""

import numpy as np
import pytest

from hoseline.mechanics.contact import SEGMENT_CAPSULE, SEGMENT_SEGMENT, STATION_PLANE, listed_gaps
from hoseline.mechanics.contact_newton import SAFE_FRACTION, ContactModel, step_filter
from hoseline.mechanics.newton import RodProperties, apply_step
from hoseline.mechanics.rod import Clamps, RodState, centerline
from hoseline.mechanics.rotations import frame_from_tangent
from hoseline.mechanics.step_pairs import watched_pairs

RADIUS, H = 1.0, 1.0  # mm


def _helix_beside_obstacles(rng):
    """props, clamps, state, model: a helix of two close turns (gap about 1 mm) over a floor, a capsule beside it."""
    n_seg, turn = 48, 24
    angles = 2 * np.pi * (np.arange(n_seg) + 0.5) / turn
    radius = turn * H / (2 * np.pi)
    tangents = np.stack([-radius * np.sin(angles), radius * np.cos(angles), np.full(n_seg, (2 * RADIUS + 1.0) / (2 * np.pi))], 1)
    tangents += 0.02 * rng.standard_normal(tangents.shape)
    frames = np.array([frame_from_tangent(t / np.linalg.norm(t)) for t in tangents])
    nodes = centerline(frames, np.zeros(3), H)
    props = RodProperties(np.array([3e3, 3e3, 2e3]), H, n_seg)
    clamps = Clamps(np.zeros(3), frames[0].copy(), nodes[-1].copy(), frames[-1].copy(), False, np.zeros(3))
    model = ContactModel(RADIUS, 0.5, 1.0,
                         planes=np.array([[0.0, 0.0, -RADIUS - 0.8, 0.0, 0.0, 1.0]]),
                         capsules=np.array([[2 * radius + 2.0, -5.0, 0.0, 2 * radius + 2.0, 5.0, 0.0, 1.5]]),
                         owners_planes=np.array([0]), owners_capsules=np.array([1]), names=("floor", "post"),
                         self_exclusion=4)
    return props, clamps, RodState(frames, np.zeros(3)), model


def _self_gaps(nodes, model, first, second):
    kinds = np.full(first.size, SEGMENT_SEGMENT)
    return listed_gaps(nodes, model.hose_radius, model.planes, model.balls, model.capsules, model.mesh.triangles,
                       model.mesh.edges, kinds, first, second)


def test_self_pairs_move_apart_by_no_more_than_the_turns_between_them():
    rng = np.random.default_rng(7)
    props, clamps, state, model = _helix_beside_obstacles(rng)
    nodes = centerline(state.frames, clamps.start_point, H)
    first, second = np.triu_indices(props.segments, model.self_exclusion + 1)
    before = _self_gaps(nodes, model, first, second)
    for size in (1e-3, 1e-2, 0.1, 0.5):
        step = size * rng.standard_normal(3 * props.segments)
        reach = np.concatenate([[0.0], H * np.cumsum(np.linalg.norm(step.reshape(-1, 3), axis=1))])
        moved = centerline(apply_step(props, clamps, state, step, np.zeros(3)).frames, clamps.start_point, H)
        change = np.abs(_self_gaps(moved, model, first, second) - before)
        bound = reach[second + 1] - reach[first]
        assert np.all(change <= bound * (1 + 1e-12) + 1e-12), np.max(change - bound)
        assert np.max(change / bound) > 0.1  # the bound is not idle: some pairs come near it


def test_two_segments_are_at_least_their_midpoints_distance_less_a_segment_and_a_diameter_apart():
    rng = np.random.default_rng(8)
    props, clamps, state, model = _helix_beside_obstacles(rng)
    first, second = np.triu_indices(props.segments, model.self_exclusion + 1)
    for size in (0.0, 0.05, 0.3):
        step = size * rng.standard_normal(3 * props.segments)
        nodes = centerline(apply_step(props, clamps, state, step, np.zeros(3)).frames, clamps.start_point, H)
        midpoints = 0.5 * (nodes[:-1] + nodes[1:])
        lower = np.linalg.norm(midpoints[first] - midpoints[second], axis=1) - H - 2 * RADIUS
        assert np.all(_self_gaps(nodes, model, first, second) >= lower - 1e-12)


def test_admits_decides_as_the_exact_gaps_of_every_pair():
    """A trial is admitted exactly when every pair, watched or not, keeps above SAFE_FRACTION of its gap now:
    the step filter leaves out only pairs that cannot come so near, and admits' midpoint bound only pairs
    that did not."""
    rng = np.random.default_rng(9)
    props, clamps, state, model = _helix_beside_obstacles(rng)
    kinds, first, second, now = model.pairs(centerline(state.frames, clamps.start_point, H), np.inf)
    decisions, mixed = set(), False
    steps = [size * rng.standard_normal(3 * props.segments) for size in (2e-3, 1e-2, 3e-2, 0.1, 0.3) for _ in range(4)]
    for size in (0.1, 0.15):  # the first six segments turned: the hose beyond them swings near the floor
        for _ in range(3):
            steps.append(np.zeros(3 * props.segments))
            steps[-1][:18] = size * rng.standard_normal(18)
    for hinge in (6, 12, 30):  # one segment turned by 1.2 rad: the hose beyond it moves as a body, by 1.13 h
        for axis in np.vstack([np.eye(3), -np.eye(3)]):
            steps.append(np.zeros(3 * props.segments))
            steps[-1][3 * hinge:3 * hinge + 3] = 1.2 * axis
    for step in steps:
        watch = step_filter(props, clamps, state, step, model)
        watched = watch.pairs[0]
        mixed |= bool(np.any(watched == SEGMENT_SEGMENT) and np.any(watched != SEGMENT_SEGMENT))
        for alpha in (watch.limit, 0.25 * watch.limit):  # no trial goes beyond the limit
            trial = apply_step(props, clamps, state, alpha * step, np.zeros(3))
            nodes = centerline(trial.frames, clamps.start_point, H)
            exact = listed_gaps(nodes, model.hose_radius, model.planes, model.balls, model.capsules,
                                model.mesh.triangles, model.mesh.edges, kinds, first, second)
            expected = bool(np.all(exact > SAFE_FRACTION * now))
            assert watch.admits(props, clamps, trial, model, alpha) == expected
            decisions.add(expected)
    assert decisions == {True, False} and mixed  # both answers were met, with self and obstacle pairs watched


def test_the_smallest_self_gap_is_that_of_every_pair():
    """ContactModel.smallest_gaps finds the smallest self-contact gap by a growing cutoff, not over every pair: the
    same as the exact gaps of every pair, for the helix (passes nearly touching) and for it stretched straight."""
    rng = np.random.default_rng(10)
    props, clamps, state, model = _helix_beside_obstacles(rng)
    first, second = np.triu_indices(props.segments, model.self_exclusion + 1)
    straight = np.zeros_like(state.frames[:, 0, :])
    straight[:, 2] = 1.0
    for nodes in (centerline(state.frames, clamps.start_point, H), np.cumsum(np.vstack([np.zeros(3), straight]), axis=0)):
        every = _self_gaps(nodes, model, first, second)
        assert model.smallest_gaps(nodes)["self"] == pytest.approx(float(np.min(every)), abs=1e-12)
        assert model.smallest_gap(nodes) <= float(np.min(every))


def test_the_watched_pairs_are_those_of_every_pair_listed_and_filtered():
    """step_pairs.watched_pairs skips the exact distance of self pairs its midpoint bound clears: the same limit
    as every pair below the cutoff (contact.pair_gaps) gives, and the same pairs and gaps as filtering them by
    the move cut to that limit, on steps from tiny to a hinge that swings half the helix."""
    rng = np.random.default_rng(11)
    props, clamps, state, model = _helix_beside_obstacles(rng)
    nodes = centerline(state.frames, clamps.start_point, H)
    shrink = 1.0 - SAFE_FRACTION
    steps = [size * rng.standard_normal(3 * props.segments) for size in (0.0, 1e-3, 1e-2, 0.1, 0.5) for _ in range(3)]
    steps.append(np.zeros(3 * props.segments))
    steps[-1][3 * 20:3 * 20 + 3] = (0.0, 1.2, 0.0)
    counts = set()
    for step in steps:
        reach = np.concatenate([[0.0], H * np.cumsum(np.linalg.norm(step.reshape(-1, 3), axis=1))])
        cutoff = float(reach[-1]) + model.activation
        kinds, first, second, gaps = model.pairs(nodes, cutoff)
        bound = np.where(kinds == STATION_PLANE, reach[first], reach[np.minimum(first + 1, props.segments)])
        bound = np.where(kinds == SEGMENT_SEGMENT, reach[np.minimum(second + 1, props.segments)] - reach[first], bound)
        thickness = np.where(kinds == SEGMENT_SEGMENT, 2 * RADIUS, np.inf)
        thickness[kinds == SEGMENT_CAPSULE] = 2 * model.capsules[second[kinds == SEGMENT_CAPSULE], 6]
        with np.errstate(divide="ignore", invalid="ignore"):
            limit = min(1.0, float(np.min(np.where(bound > 0, (gaps + thickness) / bound, np.inf), initial=np.inf)))
        keep = shrink * gaps < limit * bound
        found = watched_pairs(nodes, RADIUS, model.planes, model.balls, model.capsules, model.self_exclusion, reach,
                              cutoff, shrink)
        mine = np.lexsort(found[2::-1])  # in any order (a long step's self pairs are not found by the sort and sweep)
        theirs = np.lexsort((second[keep], first[keep], kinds[keep]))
        for got, expected in zip(found[:4], (kinds[keep], first[keep], second[keep], gaps[keep])):
            np.testing.assert_array_equal(got[mine], expected[theirs])
        assert found[4] == limit
        counts.add(int(np.count_nonzero(keep)))
    assert min(counts) == 0 and max(counts) > 50  # from nothing watched to many pairs
