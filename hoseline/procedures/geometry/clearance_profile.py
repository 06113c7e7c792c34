"""Clearance along the hose: the distance from every segment of the centreline to an obstacle, up to a cut-off.

clearance.TriangleIndex.nearest answers the one nearest approach of the whole hose; a colour
map along the hose needs the distance of every segment.  Each segment gets its own branch and
bound over the same bounding-volume hierarchy, started at the cut-off: a box or triangle no
nearer than that is skipped, so segments far from the obstacle cost one box test.  Distances
at or beyond the cut-off are reported as the cut-off (the colour map saturates there).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hoseline.mechanics.bounding_volumes import STACK_SIZE, segment_search
from hoseline.procedures.geometry.clearance import TriangleIndex


def clearance_profile(index: TriangleIndex, nodes: np.ndarray, outer_radius: float, cutoff: float) -> np.ndarray:
    """(N,) distance (mm) from the surface of each hose segment to the obstacle, capped at `cutoff` (mm).

    index: the obstacle's triangles.  nodes: (N+1, 3) centreline, mm.  outer_radius: mm.
    Negative where a segment's tube cuts into the obstacle.
    """
    nodes = np.ascontiguousarray(nodes, dtype=float)
    centreline = _segment_distances(
        nodes, index.triangles, index.normals, index.lower, index.upper, index.children, index.ranges,
        cutoff + outer_radius,
    )
    return centreline - outer_radius


@njit(cache=True)
def _segment_distances(nodes, triangles, normals, lower, upper, children, ranges, cutoff):
    """Centreline distance of every segment of `nodes` to the triangles, at most `cutoff` (mm)."""
    n_seg = nodes.shape[0] - 1
    out = np.empty(n_seg)
    stack = np.empty(STACK_SIZE, dtype=np.int64)
    for i in range(n_seg):
        p = (nodes[i, 0], nodes[i, 1], nodes[i, 2])
        q = (nodes[i + 1, 0], nodes[i + 1, 1], nodes[i + 1, 2])
        out[i] = segment_search(p, q, cutoff, triangles, normals, lower, upper, children, ranges, 0, stack)[0]
    return out
