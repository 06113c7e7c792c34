"""Contact with triangle meshes (obstacle meshes, boxes): the pairs within reach and the gaps of the step filter.

Pairs.  The hose is a chain of capsules (radius r about each segment).  The distance between a
segment and a triangle it does not cross is attained at an end of the segment or on an edge of
the triangle (inside both, the segment would have to be parallel to the face, and the nearest
pair slides to an end or an edge), so the exact distance of the hose to a mesh is the smallest
station-triangle or segment-edge distance (contact.py's STATION_TRIANGLE and SEGMENT_EDGE, with
exact gradients and Hessians; the IPC point-triangle and edge-edge pairs).  One segment-triangle
distance per pair would not do as a barrier: a segment lying on a face (a hose resting on a
floor) is at the distance min(d_p, d_q) from it, with a kink where it lies flat, and Newton's
quadratic convergence needs a C2 energy; with stations a flat face gives exactly the
station-plane pairs of an analytic plane.
Edges left out: an edge between two triangles in one plane that continue each other (a
floor's or a box face's diagonal).  Over a flat region the distance of a point of a segment is
linear along it, so it is smallest at an end, a station, and the edge would only push a second
time where the hose lies across it.  Kept: boundary edges, ridges, valleys, edges of three or
more triangles, folds.  Triangles of zero area (a line) are left out; their edges stay where
other triangles border them.  Exactly coincident vertices are merged first (a STEP file's faces
and an STL's triangles do not share theirs).

Search.  A bounding-volume hierarchy over the triangles and one over the kept edges of each mesh
(mechanics/bounding_volumes.py, the tree of the clearance search), so a query opens about
log2(triangles) boxes and a 100 000-triangle mesh costs a station a few dozen distance
evaluations, not 100 000.

Step filter (conservative advancement, contact_newton.step_filter).  A mesh is a surface, not a
solid: a station or segment could pass through a thin triangle within one step and end clear on
the other side, so the analytic obstacles' argument (a primitive cannot cross a body without
ending inside it) does not hold.  Instead no point of the hose may travel farther than its
current gap to the mesh: a rotation delta_i moves every point of segment i by at most
reach_(i+1) = h sum_(l <= i) |delta_l| per unit of the step, so the step is cut to
(1 - SAFE_FRACTION) G_i / reach_(i+1) over the segments, G_i the exact gap of segment i to the
mesh (segment_gaps: the segment-triangle distance of mechanics/proximity.py, zero where the
segment crosses a triangle, less r).  Then no point comes nearer than SAFE_FRACTION of its gap
anywhere along the step, whatever the mesh's thickness.  The price: the bound ignores direction,
so a hose sliding along a mesh it rests on (gaps below d_hat) moves a step of at most about its
gap per segment rotation bound; the analytic plane does not have that limit.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit

from hoseline.mechanics.bounding_volumes import LEAF_SIZE, STACK_SIZE, build_tree, items_within, point_of, segment_search
from hoseline.mechanics.contact import SEGMENT_EDGE, STATION_TRIANGLE, segment_parameters, triangle_parameters
from hoseline.model.obstacles import has_area

FLAT = 1e-9  # sine of the angle below which two triangles sharing an edge lie in one plane


def _empty_tree():
    return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 2), np.int64), np.zeros((0, 2), np.int64)


@dataclass(frozen=True)
class MeshArrays:
    """The triangle meshes of a contact model, packed for the kernels (mm), each mesh with its own trees.

    triangles (F, 3, 3): corners, in tree order, mesh after mesh.  normals (F, 3): unit normals.
    triangle_tree: (lower (M, 3), upper (M, 3), children (M, 2), ranges (M, 2)) of every mesh's tree,
    node and item indices global.  triangle_roots (K,): the root node of each mesh's tree.
    triangle_mesh (F,): the mesh of each triangle.  edges (E, 2, 3), edge_tree, edge_roots, edge_mesh:
    the same for the kept edges (-1 as root: a mesh without kept edges).
    owners (K,): index of each mesh's obstacle in ContactModel.names.
    """

    triangles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3)))
    normals: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    triangle_tree: tuple = field(default_factory=_empty_tree)
    triangle_roots: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    triangle_mesh: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 3)))
    edge_tree: tuple = field(default_factory=_empty_tree)
    edge_roots: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    edge_mesh: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    owners: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))

    @property
    def count(self) -> int:
        """Number of meshes."""
        return int(self.owners.shape[0])

    def owner(self, kind: int, second: int) -> int:
        """Index in ContactModel.names of the obstacle of a STATION_TRIANGLE or SEGMENT_EDGE pair."""
        mesh = self.triangle_mesh[second] if kind == STATION_TRIANGLE else self.edge_mesh[second]
        return int(self.owners[mesh])

    def pairs(self, nodes: np.ndarray, hose_radius: float, cutoff: float):
        """(kinds, first, second, gaps) of the station-triangle and segment-edge pairs with a gap below `cutoff` mm."""
        return mesh_pairs(nodes, hose_radius, cutoff, self.triangles, *self.triangle_tree, self.triangle_roots,
                          self.edges, *self.edge_tree, self.edge_roots)

    def segment_gaps(self, starts: np.ndarray, ends: np.ndarray, hose_radius: float,
                     bound: float) -> tuple[np.ndarray, np.ndarray]:
        """(gaps (K, n) mm, triangles (K, n)): the exact gap of each capsule of `hose_radius` about the segments from
        `starts` to `ends` ((n, 3) mm) to each mesh (negative inside, -r crossing a triangle) and its nearest
        triangle; `bound` and -1 where the mesh is farther than `bound` mm."""
        return segment_gaps(starts, ends, hose_radius, bound, self.triangles, self.normals, *self.triangle_tree,
                            self.triangle_roots)


def pack_meshes(meshes: list[tuple[np.ndarray, np.ndarray]], owners: list[int]) -> MeshArrays:
    """MeshArrays of `meshes`, each (vertices (V, 3) mm, faces (F, 3) vertex indices), of the obstacles `owners`."""
    if not meshes:
        return MeshArrays()
    parts = [_mesh_parts(vertices, faces) for vertices, faces in meshes]
    triangles, triangle_tree, triangle_roots = _forest([part[0] for part in parts])
    edges, edge_tree, edge_roots = _forest([part[1] for part in parts])
    return MeshArrays(
        triangles=triangles,
        normals=_unit_normals(triangles),
        triangle_tree=triangle_tree,
        triangle_roots=triangle_roots,
        triangle_mesh=np.repeat(np.arange(len(parts)), [len(part[0]) for part in parts]),
        edges=edges,
        edge_tree=edge_tree,
        edge_roots=edge_roots,
        edge_mesh=np.repeat(np.arange(len(parts)), [len(part[1]) for part in parts]),
        owners=np.asarray(owners, dtype=np.int64),
    )


def _mesh_parts(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(triangles (F, 3, 3), kept edges (E, 2, 3)) of one mesh: coincident vertices merged, zero-area
    triangles and flat interior edges left out (see the module doc)."""
    vertices, merged = np.unique(np.asarray(vertices, dtype=float), axis=0, return_inverse=True)
    faces = merged.reshape(-1)[np.asarray(faces, dtype=np.int64)]
    faces = faces[has_area(vertices[faces])]  # model.obstacles.Mesh refuses a mesh without any
    corners = vertices[faces]
    normals = _unit_normals(corners)
    # every edge of every triangle: its two vertices (sorted), the triangle, the opposite vertex
    ends = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    opposite = np.concatenate([faces[:, 2], faces[:, 0], faces[:, 1]])
    owner = np.tile(np.arange(len(faces)), 3)
    ends.sort(axis=1)
    order = np.lexsort((ends[:, 1], ends[:, 0]))
    ends, opposite, owner = ends[order], opposite[order], owner[order]
    starts = np.flatnonzero(np.r_[True, np.any(ends[1:] != ends[:-1], axis=1)])
    counts = np.diff(np.r_[starts, len(ends)])
    keep = counts != 2
    pairs = starts[counts == 2]
    a, b = vertices[ends[pairs, 0]], vertices[ends[pairs, 1]]
    n1, n2 = normals[owner[pairs]], normals[owner[pairs + 1]]
    along = np.cross(n1, b - a)  # in the first triangle's plane, across the edge
    coplanar = np.linalg.norm(np.cross(n1, n2), axis=1) < FLAT
    continued = (np.einsum("ij,ij->i", vertices[opposite[pairs]] - a, along)
                 * np.einsum("ij,ij->i", vertices[opposite[pairs + 1]] - a, along)) < 0.0
    keep[counts == 2] = ~(coplanar & continued)
    kept_edges = ends[starts[keep]]
    return corners, np.stack([vertices[kept_edges[:, 0]], vertices[kept_edges[:, 1]]], axis=1)


def _unit_normals(corners: np.ndarray) -> np.ndarray:
    """(F, 3) unit normals (b - a) x (c - a) of the triangles `corners` (F, 3, 3), each with an area."""
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return normals / np.linalg.norm(normals, axis=1)[:, None]


def _forest(item_corners: list[np.ndarray]) -> tuple[np.ndarray, tuple, np.ndarray]:
    """(items in tree order (n, k, 3), tree arrays with global indices, root of each part (-1: empty)) of one
    tree per part, item_corners: each part's items (n_i, k, 3) as their corner points."""
    items, trees, roots = [], [], []
    nodes = count = 0
    for corners in item_corners:
        if len(corners) == 0:
            roots.append(-1)
            continue
        order, lower, upper, children, ranges = build_tree(corners.min(axis=1), corners.max(axis=1),
                                                           corners.mean(axis=1), LEAF_SIZE)
        items.append(corners[order])
        trees.append((lower, upper, np.where(children >= 0, children + nodes, -1), ranges + [count, 0]))
        roots.append(nodes)
        nodes += len(lower)
        count += len(order)
    shape = item_corners[0].shape[1:]
    if not items:
        return np.zeros((0, *shape)), _empty_tree(), np.array(roots, dtype=np.int64)
    tree = tuple(np.ascontiguousarray(np.concatenate([tree[k] for tree in trees])) for k in range(4))
    return np.ascontiguousarray(np.concatenate(items)), tree, np.array(roots, dtype=np.int64)


@njit(cache=True)
def mesh_pairs(nodes, hose_radius, cutoff, triangles, t_lower, t_upper, t_children, t_ranges, t_roots,
               edges, e_lower, e_upper, e_children, e_ranges, e_roots):
    """Station-triangle and segment-edge pairs with a gap (mm) below `cutoff` mm (see the module doc).

    nodes (N+1, 3) mm (station 0 is held: not paired).  Returns (kinds, first (station or segment),
    second (triangle or edge), gaps) as contact.pair_gaps.
    """
    kinds, first, second, gaps = [0 for _ in range(0)], [0 for _ in range(0)], [0 for _ in range(0)], [0.0 for _ in range(0)]
    stack = np.empty(STACK_SIZE, np.int64)
    reach = cutoff + hose_radius
    for k in range(1, nodes.shape[0]):
        x = point_of(nodes, k)
        for root in t_roots:
            if root < 0:
                continue
            for position in items_within(x, x, reach, t_lower, t_upper, t_children, t_ranges, root, stack):
                a, b, c = triangles[position, 0], triangles[position, 1], triangles[position, 2]
                u, v, _ = triangle_parameters(nodes[k], a, b, c)
                r = nodes[k] - ((1.0 - u - v) * a + u * b + v * c)
                gap = np.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]) - hose_radius
                if gap < cutoff:
                    kinds.append(STATION_TRIANGLE)
                    first.append(k)
                    second.append(position)
                    gaps.append(gap)
    for i in range(nodes.shape[0] - 1):
        p, q = point_of(nodes, i), point_of(nodes, i + 1)
        for root in e_roots:
            if root < 0:
                continue
            for position in items_within(p, q, reach, e_lower, e_upper, e_children, e_ranges, root, stack):
                gap = _segment_distance(nodes[i], nodes[i + 1], edges[position, 0], edges[position, 1]) - hose_radius
                if gap < cutoff:
                    kinds.append(SEGMENT_EDGE)
                    first.append(i)
                    second.append(position)
                    gaps.append(gap)
    return (np.array(kinds, dtype=np.int64), np.array(first, dtype=np.int64), np.array(second, dtype=np.int64),
            np.array(gaps, dtype=np.float64))


@njit(cache=True)
def segment_gaps(starts, ends, hose_radius, bound, triangles, normals, lower, upper, children, ranges, roots):
    """The exact gap (mm) of each segment starts[i] to ends[i] to each mesh and the nearest triangle, (K, n) each;
    `bound` and -1 beyond it.

    The segment-triangle distance (mechanics/proximity.py, zero where the segment crosses a triangle)
    less the hose radius, by branch and bound over each mesh's tree.
    """
    n_seg = starts.shape[0]
    gaps = np.full((roots.shape[0], n_seg), bound)
    nearest = -np.ones((roots.shape[0], n_seg), np.int64)
    stack = np.empty(STACK_SIZE, np.int64)
    for m in range(roots.shape[0]):
        for i in range(n_seg):
            d, position, _, _ = segment_search(point_of(starts, i), point_of(ends, i), bound + hose_radius,
                                               triangles, normals, lower, upper, children, ranges, roots[m], stack)
            if position >= 0:
                gaps[m, i] = d - hose_radius
                nearest[m, i] = position
    return gaps, nearest


@njit(cache=True)
def _segment_distance(p, q, a, b):
    # distance (mm) of segments pq and ab
    s, t = segment_parameters(p, q, a, b)
    r = (1.0 - s) * p + s * q - (1.0 - t) * a - t * b
    return np.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2])


@njit(cache=True)
def swept_edges_clear(start, end, first, second, edges, clearances, evaluations):
    """Whether each hose segment first[p], carried from its place in `start` to that in `end` ((N+1, 3) mm, its ends
    on straight lines), stays farther than clearances[p] mm from edge second[p], for every listed pair.

    Branch and bound on the fraction tau of the move: the segment moves by at most L = the longer of its ends'
    moves per unit of tau, so over [tau_a, tau_b] its distance is at least (d_a + d_b - L (tau_b - tau_a)) / 2;
    an interval is split until that bound clears or a distance does not.  Undecided after `evaluations` distances
    per pair: not clear (the step is then cut).
    """
    intervals = np.empty((evaluations + 2, 4))
    for p in range(first.shape[0]):
        i, a, b, clearance = first[p], edges[second[p], 0], edges[second[p], 1], clearances[p]
        p0, q0, p1, q1 = start[i], start[i + 1], end[i], end[i + 1]
        move = max(np.sqrt(np.sum((p1 - p0) ** 2)), np.sqrt(np.sum((q1 - q0) ** 2)))
        d0, d1 = _segment_distance(p0, q0, a, b), _segment_distance(p1, q1, a, b)
        if min(d0, d1) <= clearance:
            return False
        intervals[0] = (0.0, d0, 1.0, d1)
        count, used = 1, 2
        while count > 0:
            count -= 1
            ta, da, tb, db = intervals[count]
            if da + db - move * (tb - ta) > 2.0 * clearance:
                continue
            if used == evaluations:
                return False
            tm = 0.5 * (ta + tb)
            dm = _segment_distance(p0 + tm * (p1 - p0), q0 + tm * (q1 - q0), a, b)
            used += 1
            if dm <= clearance:
                return False
            intervals[count] = (ta, da, tm, dm)
            intervals[count + 1] = (tm, dm, tb, db)
            count += 2
    return True
