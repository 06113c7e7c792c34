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
Left out, so that a flat surface pushes only along its normal and each station counts once: an
edge between two triangles in one plane that continue each other (a floor's or a box face's
diagonal: over a flat region the distance of a point of a segment is linear along it, smallest at a
station), and likewise an edge's end where exactly two edges continue each other in a straight line
(MeshArrays.corners).
Patches.  The triangles joined across such flat edges form a patch, a planar polygon (a box face, a
facet of a faceted cylinder, a whole floor).  A station pairs with the nearest triangle of each patch
within reach (MeshArrays.patches): the distance to the patch is the smallest of its triangles', so it
is counted once, changes continuously as the station passes from one triangle's region to the next
(where the nearest triangle changes, both are equally near; over a flat edge or vertex both measure
the same point of the plane), and pushes along the plane's normal over the patch.  Two patches meeting
at a ridge each count the ridge (as IPC's point-triangle pairs do).  Session 22 replaced a rule by
which each triangle decided alone (its face and its flat features by a side test on each flat edge,
its vertices on sharp edges always): a vertex region reaches over the neighbours in the plane, so a
pair at a vertex appeared or left at a gap within d_hat, steps of about half a pair's energy in the
barrier near boxes' corners and faceted struts (tests/test_contact_mesh.py), where Newton stalled.
A segment at a straight joint of two edges pairs with one of them, by one side test on the joint's
line shared by both (MeshArrays.joints), not by a distance tie.
Kept: boundary edges, ridges, valleys, edges of three or more triangles, folds.  Triangles of zero
area (a line) are left out; their edges stay where other triangles border them.  Exactly
coincident vertices are merged first (a STEP file's faces and an STL's triangles do not share theirs).

Search.  A bounding-volume hierarchy over the triangles and one over the kept edges of each mesh
(mechanics/bounding_volumes.py, the tree of the clearance search), so a query opens about
log2(triangles) boxes and a 100 000-triangle mesh costs a station a few dozen distance
evaluations, not 100 000.

Step filter (contact_newton.StepFilter).  A mesh is a surface, not a solid: a station or segment
could pass through a thin triangle within one step and end clear on the other side, so the
analytic obstacles' argument (a primitive cannot cross a body without ending inside it) does not
hold.  Plain conservative advancement (no point travels farther than its gap, with the isotropic
bound h sum |delta_l| of a rotation step's move) holds but stalls a hose resting at gaps of 1e-4 mm
that has to slide.  So the whole path of the step is checked, which a sliding hose does not come
nearer along: a frame rotated by alpha delta turns its tangent on a circular arc, so station k's
path lies within (h/8) sum_(l<k) (alpha |delta_l|)^2 of its chord (the interpolation error bound,
|d2/dtau2 exp(tau theta) t| <= theta^2), and the chord's exact gap to the meshes (segment_gaps)
less that bound must stay above SAFE_FRACTION of the station's gap now.  A segment's interior
first touches a mesh only at a kept edge (touching a face, one of its stations or a kept edge
touches too), so each segment-edge pair within reach is checked along the segment carried by its
ends' chords (swept_edges_clear).  Every first contact being a station-triangle or segment-edge
touch, no accepted step enters or passes through a mesh.

Written by hand (Numba), as contact.py: no library gives these pairs, their search and the swept
checks with the exact derivatives the barrier needs.
"""

from __future__ import annotations

import hashlib
import math
import threading
from collections import OrderedDict
from dataclasses import dataclass, field, replace

import numpy as np
from numba import njit
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from hoseline.mechanics.bounding_volumes import (
    LEAF_SIZE,
    STACK_SIZE,
    box_gap,
    build_tree,
    chain_tree,
    corners_of,
    leaves_within,
    segment_search,
)
from hoseline.mechanics.contact import (
    EDGE_AB,
    EDGE_AC,
    EDGE_BC,
    SEGMENT_EDGE,
    STATION_TRIANGLE,
    VERTEX_A,
    VERTEX_B,
    VERTEX_C,
    segment_closest,
    triangle_parameters,
)
from hoseline.mechanics.leaf_lists import MARGIN_RADII, REACH_RADII, LeafLists
from hoseline.mechanics.proximity import (
    corner_of,
    point_between,
    point_of,
    segment_plane_gap,
    segment_triangle_distance,
)
from hoseline.model.obstacles import has_area

FLAT = 1e-9  # sine of the angle below which two triangles sharing an edge lie in one plane
COVERED, JOINT, CORNER = 0, 1, 2  # MeshArrays.corners: what an edge's end is
PACKED_KEPT = 4  # packings of mesh sets kept for new problems with the same obstacles (pack_meshes)
_PACKED: OrderedDict[bytes, MeshArrays] = OrderedDict()  # by content digest, the last used last
_PACKED_LOCK = threading.Lock()  # the studio's server threads may pack at once
LISTED_TRIANGLES = 2000  # meshes with fewer triangles are walked at every search in one call, without leaf lists (a
# box lifted through the hose, tests/test_sweep_moving_contact.py: 0.37 s, 0.45 with lists, 0.36 before them)


PROBES_PER_MESH = 3  # segments searched first, with no bound, for a bound of the search of all (smallest_gaps)
BOUNDING_BOXES = 64  # boxes of a mesh's tree (its first levels) of the cheap lower bound of its gap (smallest_gaps)


def _empty_tree():
    return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 2), np.int64), np.zeros((0, 2), np.int64)


@dataclass(frozen=True)
class MeshArrays:
    """The triangle meshes of a contact model, packed for the kernels (mm), each mesh with its own trees.

    triangles (F, 3, 3): corners, in tree order, mesh after mesh.  normals (F, 3): unit normals.
    patches (F,): the flat patch of each triangle (global over the meshes): triangles joined across flat
    edges, the pieces of one planar face; a station pairs with the nearest triangle of each patch within
    reach (mesh_pairs).  planar (F,): bit 1 << f (contact.EDGE_AB, ..., VERTEX_C) set for each feature f of the
    triangle inside its patch, its flat edges and its vertices on no kept edge: a station whose nearest point of
    the patch is there is over the patch, and its distance's derivatives are the plane's
    (contact.station_triangle_terms).
    triangle_tree: (lower (M, 3), upper (M, 3), children (M, 2), ranges (M, 2)) of every mesh's tree,
    node and item indices global.  triangle_roots (K,): the root node of each mesh's tree (-1: the mesh left out
    of the searches, contact_motion.only).
    triangle_mesh (F,): the mesh of each triangle.  edges (E, 2, 3), edge_tree, edge_roots, edge_mesh:
    the same for the kept edges (-1 as root: a mesh without kept edges).  corners (E, 2): CORNER, JOINT or
    COVERED for each end of an edge (_edge_corners): a segment pairs with an edge at a corner, but where the
    edge continues straight on into another (that one is as near, and the end would push the hose along the
    edge) only on its side of the joint.  joints (E, 2, 3, 3): for such an end, the joint (A, V, B): V the
    shared vertex, A the JOINT edge's other end, B the COVERED edge's, the same for both; the side is that of
    (y - V) . (B - A), y the point of the line AB nearest the segment (the same bits from either edge), and
    the JOINT edge takes a segment on the joint itself (zero).
    owners (K,): index of each mesh's obstacle in ContactModel.names.
    """

    triangles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3)))
    patches: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    planar: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    normals: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    triangle_tree: tuple = field(default_factory=_empty_tree)
    triangle_roots: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    triangle_mesh: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 3)))
    corners: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), np.int64))
    joints: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 3, 3)))
    edge_tree: tuple = field(default_factory=_empty_tree)
    edge_roots: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    edge_mesh: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    owners: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    # the leaves near the hose of the last searches (leaf_lists.py); not copied by dataclasses.replace: a mesh moved
    # or left out has other trees, and starts its own
    leaf_lists: LeafLists = field(default_factory=LeafLists, init=False, compare=False, repr=False)
    # the first BOUNDING_BOXES boxes of each tree, (lower, upper) by root (_bounding_boxes); likewise not copied
    bounding_boxes: dict = field(default_factory=dict, init=False, compare=False, repr=False)

    @property
    def count(self) -> int:
        """Number of meshes."""
        return int(self.owners.shape[0])

    def owner(self, kind: int, second: int) -> int:
        """Index in ContactModel.names of the obstacle of a STATION_TRIANGLE or SEGMENT_EDGE pair."""
        mesh = self.triangle_mesh[second] if kind == STATION_TRIANGLE else self.edge_mesh[second]
        return int(self.owners[mesh])

    def pairs(self, nodes: np.ndarray, hose_radius: float, cutoffs, *, every_feature: bool = False,
              stop_inside: bool = False):
        """(kinds, first, second, gaps) of the station-triangle and segment-edge pairs with a gap below the cutoff mm
        of their station or segment: cutoffs, one for all, or (station cutoffs (N+1,), segment cutoffs (N,)).
        every_feature: also the pairs at features a neighbour covers (flat edges, straight edge ends), as the
        step filter must watch: a step can carry the hose to where they are the nearest.
        stop_inside: where a pair is at a gap of zero or less (the hose inside the mesh: the barrier's energy is
        infinite, and a line search's trial there is refused whatever the other pairs), that pair alone, found first
        (a trial that cut into the icosphere of bench/bench_contact_placement.py --mesh --sphere listed up to 60 000
        pairs, and such trials took half its placement's time)."""
        if np.isscalar(cutoffs):
            cutoffs = (np.full(nodes.shape[0], float(cutoffs)), np.full(nodes.shape[0] - 1, float(cutoffs)))
        station_cutoffs, segment_cutoffs = cutoffs
        if self.triangles.shape[0] < LISTED_TRIANGLES:  # a walk down a small tree costs less than keeping a list
            return walked_mesh_pairs(nodes, hose_radius, station_cutoffs, segment_cutoffs, self.triangles,
                                     self.patches, *self.triangle_tree, self.triangle_roots, self.edges, self.corners,
                                     self.joints, *self.edge_tree, self.edge_roots, every_feature, stop_inside)
        stations = nodes[1:]
        near_stations = self._leaves("stations", stations, stations, station_cutoffs[1:] + hose_radius, hose_radius)
        near_segments = self._leaves("segments", nodes[:-1], nodes[1:], segment_cutoffs + hose_radius, hose_radius)
        return mesh_pairs(nodes, hose_radius, station_cutoffs, segment_cutoffs, self.triangles, self.patches,
                          self.triangle_tree[3], *near_stations, self.edges, self.corners, self.joints,
                          self.edge_tree[3], *near_segments, every_feature, stop_inside)

    def segment_gaps(self, starts: np.ndarray, ends: np.ndarray, hose_radius: float,
                     bound: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(gaps (K, n) mm, triangles (K, n)): the exact gap of each capsule of `hose_radius` about the segments from
        `starts` to `ends` ((n, 3) mm) to each mesh (negative inside, -r crossing a triangle) and its nearest
        triangle; the bound and -1 where the mesh is farther than `bound` mm (one for all, or (n,) one each: the
        search of a fine mesh costs the more, the larger it is)."""
        bounds = np.full(starts.shape[0], float(bound)) if np.ndim(bound) == 0 else np.asarray(bound, dtype=float)
        return segment_gaps(starts, ends, hose_radius, bounds, self.triangles, self.normals, *self.triangle_tree,
                            self.triangle_roots)

    def station_gaps(self, nodes: np.ndarray, hose_radius: float, bounds: np.ndarray) -> np.ndarray:
        """(N+1,) the smallest gap (mm) of each station of `nodes` ((N+1, 3) mm) over every mesh, bounds[k] (mm) where
        none is nearer: np.min(segment_gaps(nodes, nodes, ...)[0], axis=0) to the bit, but from the leaves near the
        stations (leaf_lists.py), not a search of each tree from its root per station."""
        stations = nodes[1:]
        listed = None if self.triangles.shape[0] < LISTED_TRIANGLES else self._listed(
            "stations", stations, stations, bounds[1:] + hose_radius, hose_radius)
        if listed is None:  # a small mesh, or bounds too long for a list: the search from the root is sooner done
            return np.min(self.segment_gaps(nodes, nodes, hose_radius, bounds)[0], axis=0)
        first = np.min(self.segment_gaps(nodes[:1], nodes[:1], hose_radius, bounds[:1])[0], axis=0)  # the held one
        return np.concatenate([first, nearest_in_leaves(stations, bounds[1:], hose_radius, *listed, self.triangles,
                                                        self.normals, *self.triangle_tree[:2], self.triangle_tree[3])])

    def _tree(self, search: str) -> tuple[tuple, np.ndarray]:
        """((lower, upper, children, ranges), roots) of the triangle trees (search "stations") or the edge trees
        ("segments")."""
        return (self.triangle_tree, self.triangle_roots) if search == "stations" else (self.edge_tree, self.edge_roots)

    def _listed(self, search: str, starts: np.ndarray, ends: np.ndarray, reaches: np.ndarray, hose_radius: float):
        """(segments, leaves) within reaches (mm) of the chain starts, ends (mm) in the tree of `search` (_tree), from
        a leaf list (leaf_lists.py) where one holds or is made; None where none is (the caller walks or searches)."""
        tree, roots = self._tree(search)
        return self.leaf_lists.leaves(search, starts, ends, reaches, tree, roots, MARGIN_RADII * hose_radius,
                                      _leaves_in_order, REACH_RADII * hose_radius)

    def _leaves(self, search: str, starts: np.ndarray, ends: np.ndarray, reaches: np.ndarray, hose_radius: float):
        """_listed, or where no list holds, one walk (_leaves_in_order)."""
        listed = self._listed(search, starts, ends, reaches, hose_radius)
        if listed is not None:
            return listed
        tree, roots = self._tree(search)
        return _leaves_in_order(starts, ends, reaches, *tree, roots)

    def smallest_gaps(self, starts: np.ndarray, ends: np.ndarray, hose_radius: float, first_bound: float,
                      within: float = math.inf, beyond: float = math.inf) -> np.ndarray:
        """(K,) the smallest gap (mm) of the capsules of `hose_radius` about the segments from `starts` to `ends` to
        each mesh; inf for a mesh farther than `within` mm (whether something is that near, not how far), and for a
        mesh whose lower bound (below) is at least `beyond` mm, that bound (a sphere trace from afar steps safely by
        it: the exact gap of a fine mesh tens of mm off costs 0.5 to 1.5 ms, 100 000 triangles).

        First every segment is searched below `first_bound` mm (d_hat: a hose in contact is done, 0.2 ms on the
        strut of bench_contact_placement.py --mesh).  For a mesh farther off, each segment's gap is bounded from below
        by that of its own box to the first BOUNDING_BOXES boxes of the mesh's tree (no triangle opened); the
        PROBES_PER_MESH segments of the lowest bounds are searched with no bound, and the smallest gap they reach
        bounds the search of the segments whose own bound lies below it.  (A bound grown eightfold from d_hat
        searched every segment within up to 8 times the gap; probes chosen by the root's box alone, which holds most
        of a hose wrapped on a strut, reached 5 to 8 times the gap.)"""
        smallest = np.full(self.count, np.inf)
        wanted = self.triangle_roots >= 0  # (a mesh left out has no tree: inf)
        if starts.shape[0] == 0 or not np.any(wanted):
            return smallest
        first = min(float(first_bound), within)
        gaps, nearest = self.segment_gaps(starts, ends, hose_radius, first)
        found = wanted & np.any(nearest >= 0, axis=1)
        smallest[found] = np.min(np.where(nearest >= 0, gaps, np.inf), axis=1)[found]
        wanted &= ~found
        if not np.any(wanted) or first >= within:
            return smallest
        bounds = self._segment_bounds(starts, ends, hose_radius)  # (K, n) mm
        far = wanted & (np.min(bounds, axis=1) >= beyond)
        smallest[far] = np.min(bounds[far], axis=1)
        wanted &= ~far
        if not np.any(wanted):
            return smallest
        probes = np.unique(np.argsort(bounds[wanted], axis=1, kind="stable")[:, :PROBES_PER_MESH])
        gaps, nearest = self.segment_gaps(starts[probes], ends[probes], hose_radius, within)
        reached = np.min(np.where(nearest >= 0, gaps, np.inf), axis=1)  # (K,) a gap reached: the smallest is no larger
        bound = float(np.max(np.minimum(reached, within)[wanted]))
        below = np.full(self.count, np.inf)  # stays inf where a probe's gap is the smallest
        candidates = np.flatnonzero(np.any(bounds[wanted] < bound, axis=0))  # the others cannot come nearer
        if candidates.size:
            gaps, nearest = self.segment_gaps(starts[candidates], ends[candidates], hose_radius, bound)
            below = np.min(np.where(nearest >= 0, gaps, np.inf), axis=1)
        smallest[wanted] = np.minimum(reached, below)[wanted]
        return smallest

    def _segment_bounds(self, starts: np.ndarray, ends: np.ndarray, hose_radius: float) -> np.ndarray:
        """(K, n) a lower bound (mm) of the gap of each segment's capsule of `hose_radius` (from `starts` to `ends`,
        mm) to each mesh, inf for a mesh left out: the distance of the segment's own box to the nearest of the first
        BOUNDING_BOXES boxes of the mesh's tree, less the radius."""
        low, high = np.minimum(starts, ends), np.maximum(starts, ends)
        bounds = np.full((self.count, starts.shape[0]), np.inf)
        for mesh, root in enumerate(self.triangle_roots):
            if root < 0:
                continue
            lower, upper = self._bounding_boxes(int(root))
            apart = np.maximum(np.maximum(lower[None] - high[:, None], low[:, None] - upper[None]), 0.0)
            bounds[mesh] = np.sqrt(np.min(np.einsum("sbk,sbk->sb", apart, apart), axis=1)) - hose_radius
        return bounds

    def _bounding_boxes(self, root: int) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) (B, 3) mm of the first BOUNDING_BOXES boxes of the tree from node `root` (level by level,
        each inner node replaced by its two children), kept."""
        if root not in self.bounding_boxes:
            children = self.triangle_tree[2]
            nodes = np.array([root])
            while nodes.size < BOUNDING_BOXES and np.any(children[nodes, 0] >= 0):
                inner = children[nodes, 0] >= 0
                nodes = np.concatenate([nodes[~inner], children[nodes[inner]].ravel()])
            self.bounding_boxes[root] = (self.triangle_tree[0][nodes], self.triangle_tree[1][nodes])
        return self.bounding_boxes[root]


def pack_meshes(meshes: list[tuple[np.ndarray, np.ndarray]], owners: list[int]) -> MeshArrays:
    """MeshArrays of `meshes`, each (vertices (V, 3) mm, faces (F, 3) vertex indices), of the obstacles `owners`.

    The last PACKED_KEPT packings are kept by their content (a digest of every vertex, face and owner): a new
    problem with the same obstacles (another hose length, a mesh file read again) takes them without building
    the trees again (0.18 s for 100 000 triangles); each caller gets its own leaf lists."""
    if not meshes:
        return MeshArrays()
    digest = hashlib.blake2b(np.asarray(owners, dtype=np.int64).tobytes())
    for vertices, faces in meshes:
        for array in (np.asarray(vertices, dtype=float), np.asarray(faces, dtype=np.int64)):
            digest.update(repr(array.shape).encode())
            digest.update(np.ascontiguousarray(array))
    key = digest.digest()
    with _PACKED_LOCK:
        packed = _PACKED.get(key)
        if packed is not None:
            _PACKED.move_to_end(key)
    if packed is None:
        packed = _packed_meshes(meshes, owners)
        with _PACKED_LOCK:
            _PACKED[key] = packed
            while len(_PACKED) > PACKED_KEPT:
                _PACKED.popitem(last=False)
    return replace(packed)  # its own (empty) leaf lists: an init=False field


def _packed_meshes(meshes: list[tuple[np.ndarray, np.ndarray]], owners: list[int]) -> MeshArrays:
    """pack_meshes, without the kept packings."""
    parts = [_mesh_parts(vertices, faces) for vertices, faces in meshes]
    triangles, triangle_tree, triangle_roots, order = _forest([part[0] for part in parts])
    edges, edge_tree, edge_roots, edge_order = _forest([part[1] for part in parts])
    return MeshArrays(
        triangles=triangles,
        patches=np.concatenate([part[2] + offset for part, offset in zip(parts, _offsets(parts))])[order],
        planar=np.concatenate([part[4] for part in parts])[order],
        normals=_unit_normals(triangles),
        triangle_tree=triangle_tree,
        triangle_roots=triangle_roots,
        triangle_mesh=np.repeat(np.arange(len(parts)), [len(part[0]) for part in parts]),
        edges=edges,
        corners=np.concatenate([part[3][0] for part in parts])[edge_order],
        joints=np.concatenate([part[3][1] for part in parts])[edge_order],
        edge_tree=edge_tree,
        edge_roots=edge_roots,
        edge_mesh=np.repeat(np.arange(len(parts)), [len(part[1]) for part in parts]),
        owners=np.asarray(owners, dtype=np.int64),
    )


def _mesh_parts(vertices: np.ndarray, faces: np.ndarray) -> tuple:
    """(triangles (F, 3, 3), kept edges (E, 2, 3), patches (F,) numbered from 0, (corners (E, 2), joints (E, 2, 3, 3)),
    planar (F,), as in MeshArrays) of one mesh: coincident vertices merged, zero-area triangles and flat interior
    edges left out, the triangles joined across flat edges into patches (see the module doc)."""
    vertices, merged = np.unique(np.asarray(vertices, dtype=float), axis=0, return_inverse=True)
    faces = merged.reshape(-1)[np.asarray(faces, dtype=np.int64)]
    faces = faces[has_area(vertices[faces])]  # model.obstacles.Mesh refuses a mesh without any
    corners = vertices[faces]
    normals = _unit_normals(corners)
    count = len(faces)
    # every edge of every triangle (ab, bc, ca): its two vertices (sorted), the triangle, the opposite vertex
    ends = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    opposite = np.concatenate([faces[:, 2], faces[:, 0], faces[:, 1]])
    owner = np.tile(np.arange(count), 3)
    ends.sort(axis=1)
    order = np.lexsort((ends[:, 1], ends[:, 0]))
    ends, opposite, owner = ends[order], opposite[order], owner[order]
    new_edge = np.r_[True, np.any(ends[1:] != ends[:-1], axis=1)]
    starts = np.flatnonzero(new_edge)
    counts = np.diff(np.r_[starts, len(ends)])
    keep = counts != 2
    pairs = starts[counts == 2]
    a, b = vertices[ends[pairs, 0]], vertices[ends[pairs, 1]]
    n1, n2 = normals[owner[pairs]], normals[owner[pairs + 1]]
    along = np.cross(n1, b - a)  # in the first triangle's plane, across the edge
    coplanar = np.linalg.norm(np.cross(n1, n2), axis=1) < FLAT
    continued = (np.einsum("ij,ij->i", vertices[opposite[pairs]] - a, along)
                 * np.einsum("ij,ij->i", vertices[opposite[pairs + 1]] - a, along)) < 0.0
    flat = coplanar & continued
    keep[counts == 2] = ~flat
    kept_edges = ends[starts[keep]]
    # the patches: triangles joined across flat edges (scipy's connected components of that graph)
    joined = coo_matrix((np.ones(int(flat.sum())), (owner[pairs[flat]], owner[pairs[flat] + 1])), shape=(count, count))
    patches = connected_components(joined, directed=False)[1].astype(np.int64)
    # each triangle's features inside its patch: its flat edges, and its vertices on no kept edge
    kept_record = np.empty(len(ends), bool)
    kept_record[order] = keep[np.cumsum(new_edge) - 1]
    on_kept_edge = np.zeros(len(vertices), bool)
    on_kept_edge[kept_edges.reshape(-1)] = True
    inside = np.stack([*~kept_record.reshape(3, count)[[0, 2, 1]], *~on_kept_edge[faces].T])  # ab, ca, bc; a, b, c
    shifts = np.array([EDGE_AB, EDGE_AC, EDGE_BC, VERTEX_A, VERTEX_B, VERTEX_C])[:, None]
    planar = np.sum(inside.astype(np.int64) << shifts, axis=0)
    edges = np.stack([vertices[kept_edges[:, 0]], vertices[kept_edges[:, 1]]], axis=1)
    return corners, edges, patches, _edge_corners(kept_edges, edges), planar


def _offsets(parts: list[tuple]) -> list[int]:
    """The first global patch number of each mesh's parts (_mesh_parts), so that patches of two meshes differ."""
    counts = [int(part[2].max()) + 1 if len(part[2]) else 0 for part in parts]
    return list(np.cumsum([0, *counts[:-1]]))


def _edge_corners(ends: np.ndarray, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(corners (E, 2) int, joints (E, 2, 3, 3) mm) of the edges (vertex indices `ends` (E, 2), points `edges`
    (E, 2, 3)), as MeshArrays: each end a CORNER, or where exactly two edges continue each other in a straight
    line, JOINT for one of them and COVERED for the other, both with the joint (A, V, B)."""
    directions = (edges[:, 1] - edges[:, 0]) / np.linalg.norm(edges[:, 1] - edges[:, 0], axis=1)[:, None]
    vertex = ends.T.reshape(-1)  # the first ends, then the second ends
    away = np.concatenate([directions, -directions])  # from the vertex along the edge
    order = np.argsort(vertex, kind="stable")
    counts = np.bincount(vertex, minlength=int(vertex.max()) + 1)[vertex]
    kind = np.full(len(vertex), CORNER)
    two = order[counts[order] == 2].reshape(-1, 2)  # the two edge ends at each vertex of two edges
    straight = np.einsum("ij,ij->i", away[two[:, 0]], away[two[:, 1]]) < -1.0 + FLAT
    joint, covered = two[straight, 0], two[straight, 1]
    kind[joint] = JOINT
    kind[covered] = COVERED
    count = len(edges)
    far = np.concatenate([edges[:, 1], edges[:, 0]])  # the other end of the edge of each end
    joints = np.zeros((len(vertex), 3, 3))
    joints[joint] = joints[covered] = np.stack([far[joint], np.concatenate([edges[:, 0], edges[:, 1]])[joint],
                                                far[covered]], axis=1)
    return (np.ascontiguousarray(kind.reshape(2, count).T),
            np.ascontiguousarray(joints.reshape(2, count, 3, 3).transpose(1, 0, 2, 3)))


def _unit_normals(corners: np.ndarray) -> np.ndarray:
    """(F, 3) unit normals (b - a) x (c - a) of the triangles `corners` (F, 3, 3), each with an area."""
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return normals / np.linalg.norm(normals, axis=1)[:, None]


def _forest(item_corners: list[np.ndarray]) -> tuple[np.ndarray, tuple, np.ndarray, np.ndarray]:
    """(items in tree order (n, k, 3), tree arrays with global indices, root of each part (-1: empty), the index of
    each item in tree order among all parts' items) of one tree per part, item_corners: each part's items
    (n_i, k, 3) as their corner points."""
    items, trees, roots, orders = [], [], [], []
    nodes = count = 0
    for corners in item_corners:
        if len(corners) == 0:
            roots.append(-1)
            continue
        order, lower, upper, children, ranges = build_tree(corners.min(axis=1), corners.max(axis=1),
                                                           corners.mean(axis=1), LEAF_SIZE)
        items.append(corners[order])
        orders.append(order + count)
        trees.append((lower, upper, np.where(children >= 0, children + nodes, -1), ranges + [count, 0]))
        roots.append(nodes)
        nodes += len(lower)
        count += len(order)
    shape = item_corners[0].shape[1:]
    if not items:
        return np.zeros((0, *shape)), _empty_tree(), np.array(roots, dtype=np.int64), np.zeros(0, np.int64)
    tree = tuple(np.ascontiguousarray(np.concatenate([tree[k] for tree in trees])) for k in range(4))
    return (np.ascontiguousarray(np.concatenate(items)), tree, np.array(roots, dtype=np.int64),
            np.concatenate(orders))


@njit(cache=True)
def mesh_pairs(nodes, hose_radius, station_cutoffs, segment_cutoffs, triangles, patches, t_ranges, near_stations,
               station_leaves, edges, corners, joints, e_ranges, near_segments, segment_leaves, every_feature,
               stop_inside):
    """Station-triangle and segment-edge pairs with a gap (mm) below the cutoff (mm) of their station or segment.

    nodes (N+1, 3) mm (station 0 is held: not paired); station_cutoffs (N+1,), segment_cutoffs (N,) mm.
    patches (F,): each triangle's flat patch; a station pairs with the nearest triangle of each patch (the first
    met of equally near ones), or with every triangle within its cutoff if every_feature.
    near_stations, station_leaves: the triangle tree's leaves within reach of stations 1..N (indexed from 0;
    _leaves_in_order, through leaf_lists.LeafLists); near_segments, segment_leaves: the edge tree's of each segment.
    stop_inside: return the first pair found at a gap of zero or less alone (see MeshArrays.pairs).
    Returns (kinds, first (station or segment), second (triangle or edge), gaps) as contact.pair_gaps.
    """
    kinds, first, second, gaps = [0 for _ in range(0)], [0 for _ in range(0)], [0 for _ in range(0)], [0.0 for _ in range(0)]
    found, leaves = near_stations, station_leaves
    # the patches of the station's pairs listed so far, by hash (open addressing): a finely meshed curved surface
    # gives every triangle its own patch, hundreds within a station's cutoff, where a search of the listed pairs
    # took time as their square (a station's pairs are never more than its leaves' triangles: the table is kept
    # at most half full)
    keys = np.full(_table_size(found, leaves, t_ranges), -1, np.int64)
    listed_at = np.empty(keys.shape[0], np.int64)
    slots = [0 for _ in range(0)]  # the table's slots in use, to empty at the next station
    station = -1  # the station whose pairs are being listed
    for pair in range(found.shape[0]):
        k, leaf = found[pair] + 1, leaves[pair]
        if k != station:
            for slot in slots:
                keys[slot] = -1
            slots.clear()
            station = k
        cutoff = station_cutoffs[k]
        x = point_of(nodes, k)
        for position in range(t_ranges[leaf, 0], t_ranges[leaf, 0] + t_ranges[leaf, 1]):
            a, b, c = corners_of(triangles, position)
            u, v, _ = triangle_parameters(x, a, b, c)
            distance = 0.0
            for j in range(3):
                distance += (x[j] - ((1.0 - u - v) * a[j] + u * b[j] + v * c[j])) ** 2
            gap = np.sqrt(distance) - hose_radius
            if not gap < cutoff:
                continue
            if stop_inside and gap <= 0.0:
                return _one_pair(STATION_TRIANGLE, k, position, gap)
            if not every_feature:
                slot = _slot(keys, patches[position])
                if keys[slot] >= 0:  # this station's pair with the patch is listed: keep the nearer triangle
                    same = listed_at[slot]
                    if gap < gaps[same]:
                        second[same], gaps[same] = position, gap
                    continue
                keys[slot], listed_at[slot] = patches[position], len(kinds)
                slots.append(slot)
            kinds.append(STATION_TRIANGLE)
            first.append(k)
            second.append(position)
            gaps.append(gap)
    found, leaves = near_segments, segment_leaves
    for pair in range(found.shape[0]):
        i, leaf = found[pair], leaves[pair]
        cutoff = segment_cutoffs[i]
        p, q = point_of(nodes, i), point_of(nodes, i + 1)
        for position in range(e_ranges[leaf, 0], e_ranges[leaf, 0] + e_ranges[leaf, 1]):
            gap = segment_closest(p, q, corner_of(edges, position, 0), corner_of(edges, position, 1))[0] - hose_radius
            if not gap < cutoff:
                continue
            if not every_feature and not _edge_takes(p, q, corners[position], joints[position]):
                continue  # beyond a straight joint, where the edge that continues this one takes the segment
            if stop_inside and gap <= 0.0:
                return _one_pair(SEGMENT_EDGE, i, position, gap)
            kinds.append(SEGMENT_EDGE)
            first.append(i)
            second.append(position)
            gaps.append(gap)
    return (np.array(kinds, dtype=np.int64), np.array(first, dtype=np.int64), np.array(second, dtype=np.int64),
            np.array(gaps, dtype=np.float64))


@njit(cache=True)
def _one_pair(kind, first, second, gap):
    """(kinds, first, second, gaps) of one pair, as mesh_pairs returns them."""
    return (np.full(1, kind, np.int64), np.full(1, first, np.int64), np.full(1, second, np.int64),
            np.full(1, gap, np.float64))


@njit(cache=True)
def _table_size(found, leaves, ranges):
    """A power of two at least twice the most triangles in one station's leaves (found: the stations, in order)."""
    most, count = 0, 0
    for pair in range(found.shape[0]):
        if pair > 0 and found[pair] != found[pair - 1]:
            count = 0
        count += ranges[leaves[pair], 1]
        most = max(most, count)
    size = 2
    while size < 2 * most:
        size *= 2
    return size


@njit(cache=True, inline="always")
def _slot(keys, patch):
    """The slot of `patch` in the table `keys` (open addressing, linear probing): where it is, or the empty one where
    it would go."""
    mask = keys.shape[0] - 1
    slot = (((patch * 2654435761) & 0xFFFFFFFF) * keys.shape[0]) >> 32  # Knuth's multiplicative hash, its high bits
    while keys[slot] >= 0 and keys[slot] != patch:
        slot = (slot + 1) & mask
    return slot


@njit(cache=True)
def walked_mesh_pairs(nodes, hose_radius, station_cutoffs, segment_cutoffs, triangles, patches, t_lower, t_upper,
                      t_children, t_ranges, t_roots, edges, corners, joints, e_lower, e_upper, e_children, e_ranges,
                      e_roots, every_feature, stop_inside):
    """mesh_pairs with the leaves found by one walk down each tree (the triangles': t_*, the edges': e_*), in one
    call: for a small mesh, whose walks cost less than the calls around a leaf list."""
    stations = nodes[1:]
    near_stations = _leaves_in_order(stations, stations, station_cutoffs[1:] + hose_radius, t_lower, t_upper,
                                     t_children, t_ranges, t_roots)
    near_segments = _leaves_in_order(nodes[:-1], nodes[1:], segment_cutoffs + hose_radius, e_lower, e_upper,
                                     e_children, e_ranges, e_roots)
    return mesh_pairs(nodes, hose_radius, station_cutoffs, segment_cutoffs, triangles, patches, t_ranges,
                      near_stations[0], near_stations[1], edges, corners, joints, e_ranges, near_segments[0],
                      near_segments[1], every_feature, stop_inside)


@njit(cache=True)
def _leaves_in_order(starts, ends, reaches, lower, upper, children, ranges, roots):
    """(segments, leaves): every leaf of every mesh's tree (roots; -1: left out) within the reach (mm) of a segment
    of the chain starts[i] to ends[i] (bounding_volumes.leaves_within), ordered by segment, then mesh, then as
    one walk per segment from the root meets them (the right child first: leaf ranges descending), so that the
    pairs come in the order of a search per segment, and the sums over them round alike."""
    chain = chain_tree(starts, ends, reaches)
    segment, leaf, mesh = [0 for _ in range(0)], [0 for _ in range(0)], [0 for _ in range(0)]
    for m in range(roots.shape[0]):
        if roots[m] >= 0:
            found, at = leaves_within(starts, ends, reaches, chain, lower, upper, children, ranges, roots[m])
            for pair in range(found.shape[0]):
                segment.append(found[pair])
                leaf.append(at[pair])
                mesh.append(m)
    segment, leaf, mesh = np.array(segment, np.int64), np.array(leaf, np.int64), np.array(mesh, np.int64)
    last = ranges[leaf, 0].max() + 1 if leaf.shape[0] else 1
    order = np.argsort((segment * roots.shape[0] + mesh) * last + (last - 1 - ranges[leaf, 0]), kind="mergesort")
    return segment[order], leaf[order]


@njit(cache=True)
def _edge_takes(p, q, corners, joints):
    # whether segment pq is on the edge's side of each straight joint at its ends (MeshArrays.joints)
    for end in range(2):
        if corners[end] != CORNER:
            a, v, b = joints[end, 0], joints[end, 1], joints[end, 2]
            t = segment_closest(p, q, a, b)[2]
            along = 0.0
            for k in range(3):
                along += (a[k] + t * (b[k] - a[k]) - v[k]) * (b[k] - a[k])
            if along > 0.0 if corners[end] == JOINT else along <= 0.0:
                return False
    return True


@njit(cache=True)
def segment_gaps(starts, ends, hose_radius, bounds, triangles, normals, lower, upper, children, ranges, roots):
    """The exact gap (mm) of each segment starts[i] to ends[i] to each mesh and the nearest triangle, (K, n) each;
    bounds[i] and -1 beyond bounds[i] (and for a mesh whose root is -1: left out).

    The segment-triangle distance (mechanics/proximity.py, zero where the segment crosses a triangle)
    less the hose radius, by branch and bound over each mesh's tree.
    """
    n_seg = starts.shape[0]
    gaps = np.empty((roots.shape[0], n_seg))
    for m in range(roots.shape[0]):
        gaps[m] = bounds
    nearest = -np.ones((roots.shape[0], n_seg), np.int64)
    stack = np.empty(STACK_SIZE, np.int64)
    for m in range(roots.shape[0]):
        if roots[m] < 0:  # a mesh left out (contact_motion.only)
            continue
        for i in range(n_seg):
            d, position, _, _ = segment_search(point_of(starts, i), point_of(ends, i), bounds[i] + hose_radius,
                                               triangles, normals, lower, upper, children, ranges, roots[m], stack)
            if position >= 0:
                gaps[m, i] = d - hose_radius
                nearest[m, i] = position
    return gaps, nearest


@njit(cache=True)
def nearest_in_leaves(points, bounds, hose_radius, near, leaves, triangles, normals, lower, upper, ranges):
    """(n,) the gap (mm) of each point (n, 3) mm to the nearest triangle of its listed leaves (near[p] the point of
    leaf leaves[p]; lower, upper, ranges: the tree's), bounds[i] (mm) where none is nearer; the tests and
    arithmetic of segment_gaps's search, so that the same triangle gives the same bits."""
    best = bounds + hose_radius
    found = np.zeros(points.shape[0], np.bool_)
    for pair in range(near.shape[0]):
        i, leaf = near[pair], leaves[pair]
        x = point_of(points, i)
        if box_gap(x, x, point_of(lower, leaf), point_of(upper, leaf)) >= best[i]:  # nothing nearer than the nearest
            continue
        for position in range(ranges[leaf, 0], ranges[leaf, 0] + ranges[leaf, 1]):
            a, b, c = corners_of(triangles, position)
            if segment_plane_gap(x, x, a, point_of(normals, position)) >= best[i]:
                continue
            d = segment_triangle_distance(x, x, a, b, c)[0]
            if d < best[i]:
                best[i], found[i] = d, True
    gaps = np.empty(points.shape[0])
    for i in range(points.shape[0]):  # np.where(found, best - hose_radius, bounds), which compiles for 0.9 s
        gaps[i] = best[i] - hose_radius if found[i] else bounds[i]
    return gaps


@njit(cache=True)
def _plane_bound(d, s, t, p, q, a, b, other_p, other_q):
    # a lower bound (mm) of the distance of segment other_p other_q to the edge ab, whose closest pair to segment pq
    # is p + s (q - p), a + t (b - a) at distance d: the plane through the edge's point normal to the pair separates
    # the edge from everything on the segment's side
    if d <= 0.0:
        return 0.0
    bound = math.inf
    for end in (other_p, other_q):
        along = 0.0
        for k in range(3):
            y = a[k] + t * (b[k] - a[k])
            along += (p[k] + s * (q[k] - p[k]) - y) * (end[k] - y)
        bound = min(bound, along / d)
    return bound


@njit(cache=True)
def _squared_distance(x, y):
    # |x - y|^2 of two points (3,), mm^2
    return (x[0] - y[0]) ** 2 + (x[1] - y[1]) ** 2 + (x[2] - y[2]) ** 2


@njit(cache=True)
def swept_edges_clear(start, end, first, second, edges, clearances, evaluations):
    """Whether each hose segment first[p], carried from its place in `start` to that in `end` ((N+1, 3) mm, its ends
    on straight lines), stays farther than clearances[p] mm from edge second[p], for every listed pair.

    Branch and bound on the fraction tau of the move.  At tau_a the plane through the edge's closest point,
    normal to the closest pair, separates the edge from the segment; along the move the distance of the segment's
    ends from that plane is linear in tau, so over [tau_a, tau_b] the distance is at least the smaller of its
    values at the two ends of the interval (likewise from tau_b); an interval is split until that bound clears
    or a distance does not.  A segment sliding along an edge keeps its distance from the plane: no split.
    Undecided after `evaluations` distances per pair: not clear (the step is then cut).
    """
    intervals = np.empty((evaluations + 2, 2))
    for pair in range(first.shape[0]):
        i, clearance = first[pair], clearances[pair]
        a, b = corner_of(edges, second[pair], 0), corner_of(edges, second[pair], 1)
        p0, q0, p1, q1 = point_of(start, i), point_of(start, i + 1), point_of(end, i), point_of(end, i + 1)
        move = math.sqrt(max(_squared_distance(p0, p1), _squared_distance(q0, q1)))  # the larger end's move
        start_pair = segment_closest(p0, q0, a, b)
        if start_pair[0] - move > clearance:  # cannot come nearer than its move: no search
            continue
        intervals[0] = (0.0, 1.0)
        count, used = 1, 0
        while count > 0:
            count -= 1
            ta, tb = intervals[count]
            pa, qa = point_between(p0, p1, ta), point_between(q0, q1, ta)
            pb, qb = point_between(p0, p1, tb), point_between(q0, q1, tb)
            # at the start, the pair just found (p0 + 0 (p1 - p0) is p0 to the bit)
            da, sa, ua = start_pair if ta == 0.0 else segment_closest(pa, qa, a, b)
            db, sb, ub = segment_closest(pb, qb, a, b)
            used += 2
            if min(da, db) <= clearance:
                return False
            if max(_plane_bound(da, sa, ua, pa, qa, a, b, pb, qb), _plane_bound(db, sb, ub, pb, qb, a, b, pa, qa)) > clearance:
                continue
            if used >= evaluations:
                return False
            tm = 0.5 * (ta + tb)
            intervals[count] = (ta, tm)
            intervals[count + 1] = (tm, tb)
            count += 2
    return True
