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

from hoseline.mechanics.bounding_volumes import LEAF_SIZE, STACK_SIZE, build_tree, corners_of, segment_search
from hoseline.mechanics.proximity import point_of, segment_triangle_distance


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
        self.order, self.lower, self.upper, self.children, self.ranges = build_tree(
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
def _nearest(nodes, triangles, normals, lower, upper, children, ranges, hint):
    """Branch and bound over the tree for every segment of the chain `nodes`.

    Returns (distance, segment, on_hose, on_obstacle, position): centreline distance (mm),
    the segment index, the closest points (tuples), and the triangle's position in tree order.
    """
    n_seg = nodes.shape[0] - 1
    best = math.inf
    best_segment = 0
    best_position = hint
    on_hose = point_of(nodes, 0)
    on_obstacle = point_of(triangles[hint], 0)
    # a first bound: the last nearest triangle against the whole chain
    a, b, c = corners_of(triangles, hint)
    for i in range(n_seg):
        d, x, y = segment_triangle_distance(point_of(nodes, i), point_of(nodes, i + 1), a, b, c)
        if d < best:
            best, best_segment, on_hose, on_obstacle = d, i, x, y
    start = best_segment
    stack = np.empty(STACK_SIZE, dtype=np.int64)
    for k in range(n_seg):
        i = (start + k) % n_seg  # begin where the hose was nearest: tightens the bound early
        d, position, x, y = segment_search(
            point_of(nodes, i), point_of(nodes, i + 1), best, triangles, normals, lower, upper, children, ranges, 0, stack
        )
        if d < best:
            best, best_segment, best_position, on_hose, on_obstacle = d, i, position, x, y
    return best, best_segment, on_hose, on_obstacle, best_position
