"""Clearance between the hose and an obstacle mesh: exact distances with a bounding-volume hierarchy.

The hose surface is the tube of the outer radius around its centreline, a chain of straight
segments, so its distance to a triangle is the segment-to-triangle distance minus the
radius.  A bounding-volume hierarchy (axis-aligned boxes, median split) over the
obstacle's triangles finds the nearest triangle by branch and bound: a box is opened only
if it can hold something nearer than the best distance found so far (a lower bound from
the box to a ball around the segment).  The result is exact, not a sample of the surface;
tests compare it with the brute-force minimum over all triangles.

A sweep asks again at every pose; the previous answer's triangle gives a first bound, so
most of the tree is pruned at once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numba import njit

from hoseline.procedures.geometry.proximity import segment_plane_gap, segment_triangle_distance

LEAF_SIZE = 4
STACK_SIZE = 256  # far above the depth of a median-split tree (about log2(triangles / LEAF_SIZE))


@dataclass(frozen=True)
class Proximity:
    """The nearest approach of the hose to one obstacle at one pose.

    distance: mm from the hose surface to the obstacle (centreline distance minus the outer
        radius); negative when the hose cuts into the obstacle.
    s: mm, arc length along the hose where it comes nearest.
    on_hose: (3,) mm, the point of the centreline nearest to the obstacle.
    on_obstacle: (3,) mm, the nearest point of the obstacle.
    triangle: index of the obstacle's nearest triangle (in its mesh's face order).
    """

    distance: float
    s: float
    on_hose: np.ndarray
    on_obstacle: np.ndarray
    triangle: int


class TriangleIndex:
    """A bounding-volume hierarchy over the triangles of a mesh, for nearest-distance queries.

    vertices: (V, 3) mm.  faces: (F, 3) vertex indices.
    """

    def __init__(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        vertices = np.ascontiguousarray(vertices, dtype=float)
        faces = np.ascontiguousarray(faces, dtype=np.int64)
        if faces.ndim != 2 or faces.shape[1] != 3 or faces.shape[0] == 0:
            raise ValueError(f"a triangle mesh needs faces of shape (F, 3) with F > 0, got {faces.shape}")
        corners = vertices[faces]  # (F, 3 corners, 3 coordinates)
        self.order, self.lower, self.upper, self.children, self.ranges = _build(
            corners.min(axis=1), corners.max(axis=1), corners.mean(axis=1), LEAF_SIZE
        )
        self.triangles = np.ascontiguousarray(corners[self.order])
        normals = np.cross(self.triangles[:, 1] - self.triangles[:, 0], self.triangles[:, 2] - self.triangles[:, 0])
        norms = np.linalg.norm(normals, axis=1)
        # degenerate triangles get a zero normal: their plane bound is zero and prunes nothing
        self.normals = np.divide(normals, norms[:, None], out=np.zeros_like(normals), where=norms[:, None] > 0.0)
        self._hint = 0  # position (in tree order) of the last nearest triangle

    @property
    def size(self) -> int:
        """Number of triangles."""
        return int(self.order.shape[0])

    def nearest(self, nodes: np.ndarray, outer_radius: float) -> Proximity:
        """Nearest approach of the hose with centreline `nodes` ((N+1, 3), mm) and outer radius (mm)."""
        nodes = np.ascontiguousarray(nodes, dtype=float)
        distance, segment, on_hose, on_obstacle, position = _nearest(
            nodes, self.triangles, self.normals, self.lower, self.upper, self.children, self.ranges, self._hint
        )
        on_hose, on_obstacle = np.array(on_hose), np.array(on_obstacle)
        self._hint = position
        lengths = np.linalg.norm(np.diff(nodes, axis=0), axis=1)
        s = float(np.sum(lengths[:segment]) + np.linalg.norm(on_hose - nodes[segment]))
        return Proximity(distance - outer_radius, s, on_hose, on_obstacle, int(self.order[position]))


def nearest_with_fittings(
    index: TriangleIndex,
    nodes: np.ndarray,
    outer_radius: float,
    fittings: tuple[tuple[np.ndarray, float] | None, tuple[np.ndarray, float] | None] = (None, None),
) -> Proximity:
    """Nearest approach of the hose and its end fittings (model/fittings.py) to the obstacle of `index`.

    nodes: (N+1, 3) mm, the flexible hose's centreline; outer_radius: mm.
    fittings: (start, end), each (its centreline (K, 3) mm from the port to the outlet, its outer radius mm) or None.
    The arc length s runs along the whole assembly from the start outlet: negative on the start
    fitting (-c at its port, c its centreline length), beyond the hose length on the end fitting.
    """
    best = index.nearest(nodes, outer_radius)
    for which, piece in zip(("start", "end"), fittings):
        if piece is None:
            continue
        points, radius = piece
        found = index.nearest(points, radius)
        if found.distance < best.distance:
            to_outlet = _polyline_length(points) - found.s
            best = replace(found, s=-to_outlet if which == "start" else _polyline_length(nodes) + to_outlet)
    return best


def _polyline_length(points: np.ndarray) -> float:
    """mm along the polyline through `points` (K, 3)."""
    return float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1)))


@njit(cache=True)
def _build(tri_lower, tri_upper, centroids, leaf_size):
    """Top-down median split on the longest axis of the centroids' box.

    Returns (order, lower, upper, children, ranges): the triangles in tree order; per node its
    box corners (M, 3), children (M, 2) (-1 for a leaf) and its range [first, first + count)
    in tree order (M, 2).
    """
    count = tri_lower.shape[0]
    capacity = 2 * count  # a binary tree with at least one triangle per leaf has fewer nodes
    order = np.arange(count)
    lower = np.empty((capacity, 3))
    upper = np.empty((capacity, 3))
    children = -np.ones((capacity, 2), dtype=np.int64)
    ranges = np.zeros((capacity, 2), dtype=np.int64)
    stack = [(0, 0, count)]
    used = 1
    while len(stack) > 0:
        node, first, end = stack.pop()
        members = order[first:end]
        for k in range(3):
            lower[node, k] = tri_lower[members, k].min()
            upper[node, k] = tri_upper[members, k].max()
        ranges[node, 0] = first
        ranges[node, 1] = end - first
        if end - first <= leaf_size:
            continue
        spread = np.empty(3)
        for k in range(3):
            spread[k] = centroids[members, k].max() - centroids[members, k].min()
        axis = int(np.argmax(spread))
        order[first:end] = members[np.argsort(centroids[members, axis], kind="mergesort")]
        middle = (first + end) // 2
        children[node, 0] = used
        children[node, 1] = used + 1
        stack.append((used, first, middle))
        stack.append((used + 1, middle, end))
        used += 2
    return order, lower[:used].copy(), upper[:used].copy(), children[:used].copy(), ranges[:used].copy()


@njit(cache=True, inline="always")
def _point(points, i):
    """Row i of an (n, 3) array as a tuple."""
    return (points[i, 0], points[i, 1], points[i, 2])


@njit(cache=True, inline="always")
def _corners(triangles, t):
    """The three corners of triangle t of an (F, 3, 3) array, as tuples."""
    return _point(triangles[t], 0), _point(triangles[t], 1), _point(triangles[t], 2)


@njit(cache=True)
def _box_gap(p, q, lower, upper):
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
def segment_search(p, q, bound, triangles, normals, lower, upper, children, ranges, stack):
    """Branch and bound over the tree for the segment pq, looking for something nearer than `bound` (mm).

    stack: scratch space of STACK_SIZE ints.  Returns (distance, position, on_segment, on_triangle):
    the centreline distance and the triangle's position in tree order when one is nearer than
    `bound`; else (bound, -1, p, p).
    """
    best, best_position, on_segment, on_triangle = bound, -1, p, p
    stack[0] = 0
    top = 1
    while top > 0:
        top -= 1
        node = stack[top]
        if _box_gap(p, q, lower[node], upper[node]) >= best:
            continue
        if children[node, 0] < 0:
            first, count = ranges[node, 0], ranges[node, 1]
            for position in range(first, first + count):
                a, b, c = _corners(triangles, position)
                if segment_plane_gap(p, q, a, _point(normals, position)) >= best:
                    continue
                d, x, y = segment_triangle_distance(p, q, a, b, c)
                if d < best:
                    best, best_position, on_segment, on_triangle = d, position, x, y
            continue
        left, right = children[node, 0], children[node, 1]
        if _box_gap(p, q, lower[left], upper[left]) <= _box_gap(p, q, lower[right], upper[right]):
            stack[top], stack[top + 1] = right, left  # the nearer child is opened first
        else:
            stack[top], stack[top + 1] = left, right
        top += 2
    return best, best_position, on_segment, on_triangle


@njit(cache=True)
def _nearest(nodes, triangles, normals, lower, upper, children, ranges, hint):
    """Branch and bound over the tree for every segment of the chain `nodes`.

    Returns (distance, segment, on_hose, on_obstacle, position): centreline distance (mm),
    the segment index, the closest points (tuples), and the triangle's position in tree order.
    """
    n_seg = nodes.shape[0] - 1
    best = math.inf
    best_segment = 0
    best_position = hint
    on_hose = _point(nodes, 0)
    on_obstacle = _point(triangles[hint], 0)
    # a first bound: the last nearest triangle against the whole chain
    a, b, c = _corners(triangles, hint)
    for i in range(n_seg):
        d, x, y = segment_triangle_distance(_point(nodes, i), _point(nodes, i + 1), a, b, c)
        if d < best:
            best, best_segment, on_hose, on_obstacle = d, i, x, y
    start = best_segment
    stack = np.empty(STACK_SIZE, dtype=np.int64)
    for k in range(n_seg):
        i = (start + k) % n_seg  # begin where the hose was nearest: tightens the bound early
        d, position, x, y = segment_search(
            _point(nodes, i), _point(nodes, i + 1), best, triangles, normals, lower, upper, children, ranges, stack
        )
        if d < best:
            best, best_segment, best_position, on_hose, on_obstacle = d, i, position, x, y
    return best, best_segment, on_hose, on_obstacle, best_position
