"""A bounding-volume hierarchy (axis-aligned boxes, median split) and its searches (compiled).

Used by the clearance search (procedures/geometry/clearance.py: the nearest triangle of an
obstacle mesh) and by contact with meshes (mechanics/contact_mesh.py: the triangles and edges
within reach of each station or segment).  A box is opened only if it can hold something
nearer than the bound (box_gap is a lower bound of the distance to anything inside it), so a
search costs about log2(items) boxes per query instead of a loop over every item.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from hoseline.mechanics.proximity import (
    corner_of,
    point_between,
    point_of,
    segment_plane_gap,
    segment_triangle_distance,
)

LEAF_SIZE = 16  # triangles or edges per leaf: fewer levels for the walks down two trees, more items per leaf to
# measure (bench/bench_contact_placement.py --mesh: the 100 000-triangle strut 0.66-0.68 s against 0.75-0.76 s with 4,
# 0.69-0.71 s with 8, 0.67-0.69 s with 32 and 64; a hose pressed on an icosphere of 81 920 triangles 3.1 against
# 3.7 s; its sweep, the clearance queries of bench/bench_sweep.py and the moving meshes unchanged within noise)
LEAF_PIECES = 4  # of a segment, for the leaf test of leaves_within (leaf_within)
STACK_SIZE = 256  # far above the depth of a median-split tree (about log2(items / LEAF_SIZE))


@njit(cache=True)
def build_tree(item_lower, item_upper, centroids, leaf_size):
    """Top-down median split on the longest axis of the centroids' box, over items given by their boxes.

    item_lower, item_upper, centroids: (F, 3) mm per item (a triangle, an edge).
    Returns (order, lower, upper, children, ranges): the items in tree order; per node its
    box corners (M, 3), children (M, 2) (-1 for a leaf) and its range [first, first + count)
    in tree order (M, 2).  A node's items are split at their median by a selection (_select, O(n)
    a node), not a sort: the build is O(n log n), where sorting every node's items made it
    O(n log^2 n) (the two trees of a strut of 100 000 triangles and 150 000 edges: 113 -> 45 ms).
    """
    count = item_lower.shape[0]
    capacity = 2 * count  # a binary tree with at least one triangle per leaf has fewer nodes
    order = np.empty(count, np.int64)
    for item in range(count):  # np.arange(count), which compiles for 0.6 s
        order[item] = item
    lower = np.empty((capacity, 3))
    upper = np.empty((capacity, 3))
    children = -np.ones((capacity, 2), dtype=np.int64)
    ranges = np.zeros((capacity, 2), dtype=np.int64)
    stack = [(0, 0, count)]
    used = 1
    while len(stack) > 0:
        node, first, end = stack.pop()
        low_centroid = np.full(3, np.inf)
        high_centroid = np.full(3, -np.inf)
        for k in range(3):
            lower[node, k] = np.inf
            upper[node, k] = -np.inf
        for position in range(first, end):
            item = order[position]
            for k in range(3):
                lower[node, k] = min(lower[node, k], item_lower[item, k])
                upper[node, k] = max(upper[node, k], item_upper[item, k])
                low_centroid[k] = min(low_centroid[k], centroids[item, k])
                high_centroid[k] = max(high_centroid[k], centroids[item, k])
        ranges[node, 0] = first
        ranges[node, 1] = end - first
        if end - first <= leaf_size:
            continue
        axis = int(np.argmax(high_centroid - low_centroid))
        middle = (first + end) // 2
        _select(order, centroids[:, axis], first, end, middle)
        children[node, 0] = used
        children[node, 1] = used + 1
        stack.append((used, first, middle))
        stack.append((used + 1, middle, end))
        used += 2
    return order, lower[:used].copy(), upper[:used].copy(), children[:used].copy(), ranges[:used].copy()


@njit(cache=True, inline="always")
def _before(a, b, keys):
    # the strict order of the selection: by key, ties by item number (so the split is the same on every machine)
    return keys[a] < keys[b] or (keys[a] == keys[b] and a < b)


@njit(cache=True)
def _select(order, keys, first, end, nth):
    """Rearrange order[first:end] so that order[nth] is the item it would hold sorted (by _before), those before
    it earlier and those after it later (Hoare's quickselect, median-of-three pivots: O(n) expected).

    Written by hand (Numba): np.argpartition has no tie rule (which of tied centroids, common on a regular mesh,
    go left would depend on its implementation) and works on a gathered copy of the node's keys."""
    low, high = first, end - 1
    while high > low:
        middle = (low + high) // 2
        a, b, c = order[low], order[middle], order[high]
        if _before(b, a, keys):
            a, b = b, a
        if _before(c, b, keys):
            b = c if _before(a, c, keys) else a
        pivot = b
        i, j = low, high
        while i <= j:
            while _before(order[i], pivot, keys):
                i += 1
            while _before(pivot, order[j], keys):
                j -= 1
            if i <= j:
                order[i], order[j] = order[j], order[i]
                i += 1
                j -= 1
        if nth <= j:
            high = j
        elif nth >= i:
            low = i
        else:
            return


@njit(cache=True)
def refit_boxes(items, lower, upper, children, ranges, first, end):
    """Refit, in place, the boxes of the nodes [first, end) of a tree built by build_tree to its items moved.

    items: (F, k, 3) mm, each item (a triangle, an edge) as its k corner points, in tree order.
    lower, upper, children, ranges: the tree (build_tree; a node's children come after it, so the
    nodes are refitted last to first).  The topology is kept: after a rigid motion of the items the
    boxes are exact again (the items' bounds), the split only less balanced than a rebuild's.
    """
    for node in range(end - 1, first - 1, -1):
        if children[node, 0] >= 0:
            left, right = children[node, 0], children[node, 1]
            for k in range(3):
                lower[node, k] = min(lower[left, k], lower[right, k])
                upper[node, k] = max(upper[left, k], upper[right, k])
            continue
        for k in range(3):
            lower[node, k] = np.inf
            upper[node, k] = -np.inf
        for position in range(ranges[node, 0], ranges[node, 0] + ranges[node, 1]):
            for corner in range(items.shape[1]):
                for k in range(3):
                    lower[node, k] = min(lower[node, k], items[position, corner, k])
                    upper[node, k] = max(upper[node, k], items[position, corner, k])


@njit(cache=True)
def chain_tree(starts, ends, reaches):
    """The boxes of a binary tree over a chain of n segments (the hose's stations or segments), for leaves_within.

    starts, ends: (n, 3) mm, segment i from starts[i] to ends[i] (a station: both the same).  reaches: (n,) mm,
    each segment's box grown by its reach (none at or below 0: an empty box, nothing is within).  The tree is
    implicit over the chain's order (neighbours along a hose lie close together, so no sorting is needed): node
    j has the children 2j and 2j + 1, leaf i is node size + i, size the power of two at or above n.
    Returns (lower (2 size, 3), upper (2 size, 3), size).
    """
    n = starts.shape[0]
    size = 1
    while size < n:
        size *= 2
    lower = np.full((2 * size, 3), np.inf)
    upper = np.full((2 * size, 3), -np.inf)
    for i in range(n):
        if reaches[i] > 0.0:
            for k in range(3):
                lower[size + i, k] = min(starts[i, k], ends[i, k]) - reaches[i]
                upper[size + i, k] = max(starts[i, k], ends[i, k]) + reaches[i]
    for j in range(size - 1, 0, -1):
        for k in range(3):
            lower[j, k] = min(lower[2 * j, k], lower[2 * j + 1, k])
            upper[j, k] = max(upper[2 * j, k], upper[2 * j + 1, k])
    return lower, upper, size


@njit(cache=True)
def leaves_within(starts, ends, reaches, chain, lower, upper, children, ranges, root):
    """Every (segment, leaf) pair of a chain of segments (chain_tree) and a tree's leaves below `root` whose leaf box
    may come within the segment's reach (leaf_within; the grown boxes of both trees' inner nodes hold their
    children's, so they meet where a leaf's do), found by one walk down both trees at once instead of one walk
    from the root per segment.

    Returns (segments, leaves): the segment index and the leaf node of each pair, in no particular order.
    """
    chain_lower, chain_upper, size = chain
    segments, leaves = [0 for _ in range(0)], [0 for _ in range(0)]
    stack = np.empty((2 * STACK_SIZE, 2), np.int64)  # depth of both trees at most, two pushed per level
    stack[0, 0], stack[0, 1] = root, 1
    top = 1
    while top > 0:
        top -= 1
        node, link = stack[top, 0], stack[top, 1]
        apart = False
        for k in range(3):
            if lower[node, k] > chain_upper[link, k] or upper[node, k] < chain_lower[link, k]:
                apart = True
        if apart:
            continue
        on_leaf, on_chain_leaf = children[node, 0] < 0, link >= size
        if on_leaf and on_chain_leaf:
            i = link - size
            low, high = point_of(lower, node), point_of(upper, node)  # tuples: a row's view costs a reference count
            if leaf_within(point_of(starts, i), point_of(ends, i), low, high, reaches[i]):
                segments.append(i)
                leaves.append(node)
            continue
        # open the larger box (by the sum of its sides), or the one that is not a leaf
        node_size, link_size = 0.0, 0.0
        for k in range(3):
            node_size += upper[node, k] - lower[node, k]
            link_size += chain_upper[link, k] - chain_lower[link, k]
        if on_chain_leaf or (not on_leaf and node_size >= link_size):
            stack[top, 0], stack[top, 1] = children[node, 0], link
            stack[top + 1, 0], stack[top + 1, 1] = children[node, 1], link
        else:
            stack[top, 0], stack[top, 1] = node, 2 * link
            stack[top + 1, 0], stack[top + 1, 1] = node, 2 * link + 1
        top += 2
    return np.array(segments, dtype=np.int64), np.array(leaves, dtype=np.int64)


@njit(cache=True, inline="always")
def corners_of(triangles, t):
    """The three corners of triangle t of an (F, 3, 3) array, as tuples."""
    return corner_of(triangles, t, 0), corner_of(triangles, t, 1), corner_of(triangles, t, 2)


@njit(cache=True)
def box_gap(p, q, lower, upper):
    """A lower bound (mm) of the distance from segment pq to an axis-aligned box.

    The larger of: the gap between the box and the segment's own box, and the distance from
    the box to the segment's midpoint less half the segment's length.
    """
    boxes = 0.0
    ball = 0.0
    half = 0.0
    for k in range(3):
        low, high = min(p[k], q[k]), max(p[k], q[k])
        middle = 0.5 * (low + high)
        half += (high - low) ** 2
        if high < lower[k]:
            boxes += (lower[k] - high) ** 2
        elif low > upper[k]:
            boxes += (low - upper[k]) ** 2
        if middle < lower[k]:
            ball += (lower[k] - middle) ** 2
        elif middle > upper[k]:
            ball += (middle - upper[k]) ** 2
    return max(math.sqrt(boxes), math.sqrt(ball) - 0.5 * math.sqrt(half))


@njit(cache=True, inline="always")
def leaf_within(p, q, lower, upper, reach):
    """Whether segment pq may come within `reach` (mm) of a box, the leaf test of leaves_within: box_gap below it,
    and for a segment, the box_gap of one of its LEAF_PIECES equal pieces too (sharper for a segment long against
    the box: the distance is the smallest of the pieces'; box_gap of the whole is never above a piece's, so it
    rejects first).  Where the pieces' ends move by at most m, each bound changes by at most 2 m (leaf_lists.py)."""
    if not box_gap(p, q, lower, upper) < reach:
        return False
    return _is_point(p, q) or _pieces_gap(p, q, lower, upper, reach) < reach


@njit(cache=True)
def leaf_bounds(starts, ends, segments, leaves, lower, upper):
    """The bound behind leaf_within of each (segment, leaf) pair (mm): the larger of box_gap of segment
    starts[i] to ends[i] and the smallest box_gap of its LEAF_PIECES pieces (of a station, its box_gap); leaf_within
    holds where it is below the reach."""
    bounds = np.empty(segments.shape[0])
    for pair in range(segments.shape[0]):
        i, node = segments[pair], leaves[pair]
        p, q = point_of(starts, i), point_of(ends, i)
        low, high = point_of(lower, node), point_of(upper, node)
        whole = box_gap(p, q, low, high)
        bounds[pair] = whole if _is_point(p, q) else max(whole, _pieces_gap(p, q, low, high, -math.inf))
    return bounds


@njit(cache=True, inline="always")
def _is_point(p, q):
    # whether the segment pq is a point (a station)
    return p[0] == q[0] and p[1] == q[1] and p[2] == q[2]


@njit(cache=True, inline="always")
def _pieces_gap(p, q, lower, upper, enough):
    # the smallest box_gap (mm) of the LEAF_PIECES equal pieces of segment pq, or the first one below `enough`
    smallest = math.inf
    for piece in range(LEAF_PIECES):
        a = point_between(p, q, piece / LEAF_PIECES)
        b = point_between(p, q, (piece + 1) / LEAF_PIECES)
        smallest = min(smallest, box_gap(a, b, lower, upper))
        if smallest < enough:
            break
    return smallest


@njit(cache=True, inline="always")
def segment_search(p, q, bound, triangles, normals, lower, upper, children, ranges, root, stack):
    """Branch and bound over the tree from node `root` for the segment pq, looking for a triangle nearer than `bound` (mm).

    stack: scratch space of STACK_SIZE ints.  Returns (distance, position, on_segment, on_triangle):
    the centreline distance and the triangle's position in tree order when one is nearer than
    `bound`; else (bound, -1, p, p).
    """
    best, best_position, on_segment, on_triangle = bound, -1, p, p
    stack[0] = root
    top = 1
    while top > 0:
        top -= 1
        node = stack[top]
        if box_gap(p, q, point_of(lower, node), point_of(upper, node)) >= best:
            continue
        if children[node, 0] < 0:
            first, count = ranges[node, 0], ranges[node, 1]
            for position in range(first, first + count):
                a, b, c = corners_of(triangles, position)
                if segment_plane_gap(p, q, a, point_of(normals, position)) >= best:
                    continue
                d, x, y = segment_triangle_distance(p, q, a, b, c)
                if d < best:
                    best, best_position, on_segment, on_triangle = d, position, x, y
            continue
        left, right = children[node, 0], children[node, 1]
        left_gap = box_gap(p, q, point_of(lower, left), point_of(upper, left))
        if left_gap <= box_gap(p, q, point_of(lower, right), point_of(upper, right)):
            stack[top], stack[top + 1] = right, left  # the nearer child is opened first
        else:
            stack[top], stack[top + 1] = left, right
        top += 2
    return best, best_position, on_segment, on_triangle
