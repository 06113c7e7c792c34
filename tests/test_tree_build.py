"""The bounding-volume tree's build (mechanics/bounding_volumes.build_tree): a median split by selection, not a sort."""

import numpy as np
import pytest

from hoseline.mechanics.bounding_volumes import LEAF_SIZE, _select, build_tree


@pytest.mark.parametrize("seed", range(4))
def test_the_selection_puts_each_item_where_a_sort_by_key_then_item_would(seed):
    rng = np.random.default_rng(seed)
    count = int(rng.integers(2, 400))
    keys = rng.integers(0, 6, count).astype(float) if seed % 2 else rng.standard_normal(count)  # many ties, or none
    order = rng.permutation(count)
    first, end = sorted(rng.choice(count + 1, 2, replace=False))
    if end - first < 1:
        return
    nth = int(rng.integers(first, end))
    before = order.copy()
    _select(order, keys, first, end, nth)
    ranked = sorted(before[first:end], key=lambda item: (keys[item], item))
    assert order[nth] == ranked[nth - first]
    assert set(order[first:nth]) == set(ranked[:nth - first])
    np.testing.assert_array_equal(order[:first], before[:first])  # nothing outside the range moves
    np.testing.assert_array_equal(order[end:], before[end:])


@pytest.mark.parametrize("grid", [False, True])
def test_every_node_holds_its_items_and_splits_them_at_the_median(grid):
    """Random triangles, and a grid of them (ties in every centroid coordinate): every item in one leaf, each
    node's box holds its items', its children split its range in halves, every centroid of the first half at or
    below every one of the second on the axis of the widest spread."""
    rng = np.random.default_rng(5)
    if grid:
        x, y = np.meshgrid(np.arange(40.0), np.arange(30.0))
        base = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
        corners = np.stack([base, base + [1.0, 0.0, 0.0], base + [0.0, 1.0, 0.0]], axis=1)
    else:
        corners = rng.uniform(-50.0, 50.0, (1500, 1, 3)) + rng.uniform(-2.0, 2.0, (1500, 3, 3))
    low, high, centroids = corners.min(axis=1), corners.max(axis=1), corners.mean(axis=1)
    order, lower, upper, children, ranges = build_tree(low, high, centroids, LEAF_SIZE)
    np.testing.assert_array_equal(np.sort(order), np.arange(len(corners)))
    leaves = 0
    for node in range(len(ranges)):
        first, count = ranges[node]
        items = order[first:first + count]
        assert np.all(lower[node] <= low[items]) and np.all(upper[node] >= high[items])
        np.testing.assert_array_equal(lower[node], low[items].min(axis=0))
        if children[node, 0] < 0:
            assert 1 <= count <= LEAF_SIZE
            leaves += count
            continue
        left, right = children[node]
        middle = first + count // 2
        assert tuple(ranges[left]) == (first, count // 2) and tuple(ranges[right]) == (middle, count - count // 2)
        axis = int(np.argmax(np.ptp(centroids[items], axis=0)))
        assert centroids[order[first:middle], axis].max() <= centroids[order[middle:first + count], axis].min()
    assert leaves == len(corners)
