"""Leaf lists (mechanics/leaf_lists.py): the leaves near a moving hose answered from a list, to the bit as a walk."""

import pickle

import numpy as np
import pytest

from hoseline.mechanics.bounding_volumes import LEAF_SIZE, box_gap, build_tree, leaf_bounds, leaf_within
from hoseline.mechanics import contact_mesh
from hoseline.mechanics.contact_mesh import _leaves_in_order, pack_meshes
from hoseline.mechanics.leaf_lists import LeafLists


def _random_tree(rng, count=3000):
    """A tree over `count` random small triangles in a 100 mm cube (lower, upper, children, ranges)."""
    corners = rng.uniform(-50.0, 50.0, (count, 1, 3)) + rng.normal(scale=2.0, size=(count, 3, 3))
    return build_tree(corners.min(axis=1), corners.max(axis=1), corners.mean(axis=1), LEAF_SIZE)[1:]


def _segment_box_distance(p, q, lower, upper, samples=20001):
    """The distance (mm) from segment pq to a box, from below: the smallest over samples of the segment less the
    largest the true minimum can lie below it (half a sample spacing)."""
    t = np.linspace(0.0, 1.0, samples)[:, None]
    points = p + t * (q - p)
    outside = np.maximum(np.maximum(lower - points, points - upper), 0.0)
    return float(np.min(np.linalg.norm(outside, axis=1))) - 0.5 * float(np.linalg.norm(q - p)) / (samples - 1)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_the_leaf_test_never_rejects_a_leaf_within_reach(seed):
    """leaf_within's bound (the smallest box_gap of the segment's pieces) is a lower bound of the distance: a box it
    rejects lies at least the reach from the segment; and it rejects more than box_gap of the whole segment does."""
    rng = np.random.default_rng(seed)
    sharper = 0
    for _ in range(1500):
        p = rng.normal(scale=5.0, size=3)
        q = p + rng.normal(scale=6.0, size=3) * (rng.random() > 0.1)  # some points
        lower = rng.normal(scale=5.0, size=3)
        upper = lower + rng.uniform(0.0, 3.0, 3)
        reach = rng.uniform(0.0, 6.0)
        if not leaf_within(tuple(p), tuple(q), lower, upper, reach):
            assert _segment_box_distance(p, q, lower, upper) >= reach - 1e-9
            sharper += box_gap(tuple(p), tuple(q), lower, upper) < reach
    assert sharper > 10


def test_the_leaf_bound_is_below_the_reach_exactly_where_the_leaf_test_holds():
    rng = np.random.default_rng(5)
    lower, upper, children, ranges = _random_tree(rng, 500)
    starts = rng.uniform(-50.0, 50.0, (200, 3))
    ends = np.where(rng.random((200, 1)) < 0.2, starts, starts + rng.normal(scale=6.0, size=(200, 3)))
    segments = np.repeat(np.arange(200), 20)
    leaves = rng.choice(np.flatnonzero(children[:, 0] < 0), segments.size)
    bounds = leaf_bounds(starts, ends, segments, leaves, lower, upper)
    for reach in (1.0, 5.0, 20.0):
        within = [leaf_within(tuple(starts[i]), tuple(ends[i]), lower[leaf], upper[leaf], reach)
                  for i, leaf in zip(segments, leaves)]
        assert np.array_equal(bounds < reach, within) and 0 < sum(within) < len(within)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_moving_chain_gets_from_its_lists_exactly_what_a_walk_finds(seed):
    """A chain of stations (seed 0) or segments moved on by steps of every size, some within half the margin and
    some beyond, turned about their midpoints and stretched, with reaches that change: each search through one
    LeafLists returns the walk's (segments, leaves), the same arrays in the same order."""
    rng = np.random.default_rng(seed)
    lower, upper, children, ranges = tree = _random_tree(rng)
    roots = np.zeros(1, np.int64)
    lists, margin = LeafLists(), 1.0
    count = 40
    starts = np.cumsum(rng.normal(scale=4.0, size=(count, 3)), axis=0)
    ends = starts + rng.normal(scale=3.0, size=(count, 3)) * (seed != 0)
    answered, base = 0, rng.uniform(2.0, 3.0, count)
    out = rng.random(count) > 0.05  # some elements out of every search (no reach)
    for search in range(300):
        scale = rng.choice([0.0, 0.01, 0.03, 0.1, 0.2, 0.3, 0.6, 2.0], p=[0.1, 0.2, 0.2, 0.2, 0.1, 0.1, 0.05, 0.05])
        move = rng.normal(scale=scale, size=(count, 3))
        middle, half = 0.5 * (starts + ends), 0.5 * (ends - starts)
        turn = 1.0 + rng.normal(scale=scale / 10.0, size=(count, 1))  # stretched, shrunk
        starts, ends = middle + move - turn * half, middle + move + turn * half
        if seed != 0:
            ends = ends + rng.normal(scale=0.5 * scale, size=(count, 3))  # turned
        else:
            ends = starts
        reaches = (base + rng.uniform(0.0, 0.2, count)) * out - 0.5 * (search % 7 == 0)
        expected = _leaves_in_order(starts, ends, reaches, *tree, roots)
        listed = lists.leaves("segments", starts, ends, reaches, tree, roots, margin, _leaves_in_order, 10.0)
        if listed is None:
            continue
        answered += 1
        assert np.array_equal(listed[0], expected[0]) and np.array_equal(listed[1], expected[1]), search
    assert answered > 100


def test_lists_that_answer_nothing_are_made_ever_more_rarely_and_a_copy_starts_empty():
    """A chain that jumps farther than the margin at every search (a placement's Newton steps) makes fewer and fewer
    lists; one that creeps (a sweep's poses) makes one per half margin of travel.  A pickled copy has no lists."""
    rng = np.random.default_rng(7)
    tree, roots = _random_tree(rng), np.zeros(1, np.int64)
    made = []

    def walk(*arguments):
        made.append(1)
        return _leaves_in_order(*arguments)

    def searches(step):
        lists = LeafLists()
        made.clear()
        starts = rng.uniform(-20.0, 20.0, (30, 3))
        plain = 0
        for _ in range(100):
            starts = starts + step * rng.normal(size=starts.shape) / np.sqrt(3.0)
            found = lists.leaves("stations", starts, starts, np.full(30, 2.0), tree, roots, 1.0, walk, 10.0)
            plain += found is None
        return len(made), plain, lists

    lists_made, plain, _ = searches(5.0)
    assert lists_made <= 10 and plain >= 90
    lists_made, plain, lists = searches(0.01)
    assert 1 <= lists_made <= 5 and plain == 0
    assert pickle.loads(pickle.dumps(lists))._lists == {}


def test_station_gaps_are_those_of_the_search_from_the_root_to_the_bit(monkeypatch):
    """MeshArrays.station_gaps (the nearest triangle in the listed leaves, or the search from the root for long
    bounds) against np.min(segment_gaps(nodes, nodes)) for a hose of radius 5 mm creeping along a finely faceted
    drum (48 000 triangles, leaves far smaller than the hose), its stations a few tenths of a millimetre off it."""
    from test_contact_mesh import _faceted_drum

    monkeypatch.setattr(contact_mesh, "LISTED_TRIANGLES", 0)  # whatever the mesh's size
    rng = np.random.default_rng(11)
    vertices, faces = _faceted_drum(240, rows=100)
    mesh = pack_meshes([(vertices, faces)], [0])
    k = np.arange(31)
    radius = 40.0 + 5.0 + 0.15 + 0.1 * np.sin(k)  # the drum's, the hose's and a gap of 0.05-0.25 mm
    nodes = np.column_stack([radius * np.cos(0.05 * k), 3.0 * k, radius * np.sin(0.05 * k)])
    base = rng.uniform(0.0, 0.3, k.size)  # each station's bound, within a list's reach (1.5 hose radii)
    near = listed = 0
    for search in range(100):
        moved = nodes + rng.normal(scale=0.002 * (search % 4), size=nodes.shape) + [0.0, 0.02 * search, 0.0]
        bounds = base + rng.uniform(0.0, 0.05, k.size) if search % 5 else np.full(k.size, 40.0)
        expected = np.min(mesh.segment_gaps(moved, moved, 5.0, bounds)[0], axis=0)
        assert np.array_equal(mesh.station_gaps(moved, 5.0, bounds), expected)
        near += int(np.sum(expected < bounds))
        listed += bool(mesh.leaf_lists._lists)
    assert near > 300 and listed > 50


def test_mesh_pairs_from_the_lists_are_those_of_a_mesh_without_them(monkeypatch):
    """MeshArrays.pairs of a hose creeping over a faceted drum (its lists kept from search to search) against the
    same mesh copied afresh for each search (dataclasses.replace: no lists), the pairs and gaps to the bit."""
    from dataclasses import replace

    from test_contact_mesh import _faceted_drum

    monkeypatch.setattr(contact_mesh, "LISTED_TRIANGLES", 0)  # lists for this drum of 1152 triangles too
    rng = np.random.default_rng(13)
    vertices, faces = _faceted_drum(48, rows=12)
    mesh = pack_meshes([(vertices, faces)], [0])
    nodes = np.cumsum(np.vstack([[[-60.0, -30.0, 38.0]], 6.0 * rng.standard_normal((30, 3)) + [4.0, 2.0, 0.0]]), axis=0)
    found = 0
    for search in range(150):
        moved = nodes + rng.normal(scale=0.02, size=nodes.shape) + [0.0, 0.0, -0.02 * search]
        cutoffs = 0.3 if search % 3 else (np.full(31, 0.3), rng.uniform(0.0, 0.4, 30))
        listed = mesh.pairs(moved, 1.0, cutoffs, every_feature=search % 2 == 0)
        fresh = replace(mesh).pairs(moved, 1.0, cutoffs, every_feature=search % 2 == 0)
        assert all(np.array_equal(a, b) for a, b in zip(listed, fresh)), search
        found += listed[0].size
    assert found > 200 and mesh.leaf_lists._lists
