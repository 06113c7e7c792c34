"""The swept envelope of the hose: the space it takes up over all poses of a sweep, as a closed mesh.

The envelope is the union of the hose's tube (outer radius around the centreline, a chain of
straight segments) over the poses.  Its surface is the zero level of the distance to the
nearest centreline segment of any pose, less the radius.  That distance is evaluated exactly
at the nodes of a grid and the surface triangulated by marching cubes, so it lies within
about one grid cell of the exact union: much closer on the tubes' round faces, about a cell
where the tubes of different poses cross.  Between two poses the hose moves by the sweep's
pose spacing; the envelope covers the poses computed, not what happens between them.

Memory and time are bounded whatever the layout.  The grid is never allocated whole: it is
cut into blocks of BLOCK_CELLS cells along each edge, and only the blocks within reach of a
segment are visited, one at a time: the distance is written into the block's nodes segment
by segment (compiled with Numba), the block is meshed, and the blocks' meshes are welded
where neighbours share their faces of nodes.  The cell is half the radius unless that would
compute more than DISTANCE_BUDGET node-segment distances, visit more than NODE_BUDGET nodes
or give more than TRIANGLE_BUDGET triangles; then it is coarsened until all fit, and the
cell used is returned with the mesh.  A tube thinner than THINNEST cells would fall apart on
the grid: it is meshed that thick (the envelope is then larger than the union by less than a
cell), and the radius meshed is returned too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from skimage.measure import marching_cubes

BLOCK_CELLS = 32  # cells along each edge of a block: 33^3 nodes, 0.3 MB of distances in memory at a time
DISTANCE_BUDGET = 300_000_000  # node-segment distances at most (about 1 s on one core), or
DISTANCES_PER_SEGMENT = 400  # per segment when there are more: a segment much shorter than the cell costs 7^3
NODE_BUDGET = 30_000_000  # nodes of the blocks visited at most (marching cubes: about 1 s)
TRIANGLE_BUDGET = 500_000  # triangles of the envelope at most (a 25 MB binary STL)
COARSEN_AT_LEAST = 1.15  # factor by which the cell grows, at least, when a budget is exceeded
PROJECT_AFTER = 1.0 / 16.0  # fraction of the blocks meshed before their triangles are projected onto all
THINNEST = 1.0  # cells: a thinner tube falls apart on the grid (measured: pieces below 0.8 cell), so it is widened


@dataclass(frozen=True)
class Envelope:
    """A swept envelope as a closed triangle mesh.

    vertices: (V, 3) mm.  faces: (F, 3) vertex indices, outward normals by the right-hand rule.
    cell: mm, the grid spacing used: the surface is within about one cell of the exact union
        of the tubes.  requested_cell: mm, the spacing asked for (cell is larger when the
        budgets required it).  radius: mm, the tube radius meshed: the hose's, or THINNEST
        cells when the hose is thinner than that (the envelope is then larger than the union
        by the difference, less than a cell).  nodes: grid nodes of the blocks visited.
    """

    vertices: np.ndarray
    faces: np.ndarray
    cell: float
    requested_cell: float
    radius: float
    nodes: int

    @property
    def coarsened(self) -> bool:
        """Whether the cell had to be made larger than asked to keep within the budgets."""
        return self.cell > self.requested_cell


def swept_envelope(centerlines: np.ndarray, radius: float, cell: float | None = None) -> Envelope:
    """The union of the tubes of `radius` around `centerlines`, meshed within the budgets.

    centerlines: (M, N+1, 3) mm, one centreline per pose.  radius: mm, the outer radius.
    cell: mm, the grid spacing asked for (default: half the radius); coarsened when the layout
        would need more than DISTANCE_BUDGET distances, NODE_BUDGET nodes or TRIANGLE_BUDGET
        triangles.  A tube thinner than THINNEST cells is meshed that thick.
    """
    centerlines = np.asarray(centerlines, dtype=float)
    starts = np.ascontiguousarray(centerlines[:, :-1].reshape(-1, 3))
    ends = np.ascontiguousarray(centerlines[:, 1:].reshape(-1, 3))
    requested = 0.5 * radius if cell is None else float(cell)
    cell = requested
    while True:
        try:
            meshed = max(radius, THINNEST * cell)
            blocks = _Blocks(starts, ends, meshed, cell)
            vertices, faces = _mesh(blocks, starts, ends, meshed)
            return Envelope(vertices, faces, cell, requested, meshed, blocks.nodes)
        except _OverBudget as over:
            cell *= max(COARSEN_AT_LEAST, over.factor)


class _OverBudget(Exception):
    """The cell is too fine for a budget; `factor`: by how much it should grow (estimated)."""

    def __init__(self, factor: float) -> None:
        super().__init__(factor)
        self.factor = factor


class _Blocks:
    """The blocks of the grid (spacing `cell`, mm) within reach of the segments, and which segments reach each.

    The grid's nodes are low + cell * (i, j, k).  Block (a, b, c) holds the nodes
    BLOCK_CELLS * (a, b, c) + (0..BLOCK_CELLS)^3: neighbours share a face of nodes.  A node
    farther than `reach` from every segment is outside the tubes by two cells at least and
    keeps the distance `reach`.  Raises _OverBudget before allocating beyond the budgets.
    """

    def __init__(self, starts: np.ndarray, ends: np.ndarray, radius: float, cell: float) -> None:
        self.cell = cell
        self.reach = radius + 2.0 * cell
        lower = np.minimum(starts, ends) - self.reach
        upper = np.maximum(starts, ends) + self.reach
        self.low = lower.min(axis=0) - cell
        # nodes in the box of each segment widened by the reach: the distances written for it
        boxes = np.floor((upper - self.low) / cell) - np.ceil((lower - self.low) / cell) + 1.0
        distances = float(np.sum(np.prod(boxes, axis=1)))
        budget = max(DISTANCE_BUDGET, DISTANCES_PER_SEGMENT * len(starts))  # coarsening cannot go below 7^3 each
        if distances > budget:
            raise _OverBudget((distances / budget) ** (1.0 / 3.0))
        nodes = np.floor((upper.max(axis=0) - self.low) / cell).astype(np.int64) + 2  # along each axis
        self.counts = -(-(nodes - 1) // BLOCK_CELLS)  # blocks along each axis
        self.index, self.segments = self._reached(starts, ends)
        self.nodes = len(self.index) * (BLOCK_CELLS + 1) ** 3
        if self.nodes > NODE_BUDGET:
            raise _OverBudget((self.nodes / NODE_BUDGET) ** (1.0 / 3.0))

    def _reached(self, starts: np.ndarray, ends: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
        """(B, 3) indices of the blocks some segment reaches, and for each the indices of those segments.

        Segments are cut into pieces no longer than a block, so that a piece's widened box
        covers few blocks beyond those it passes through.  (Their number is bounded by the
        distance budget: each piece accounts for more than (2 reach / cell)^2 of the distances.)
        """
        size = BLOCK_CELLS * self.cell
        pieces = np.maximum(1, np.ceil(np.linalg.norm(ends - starts, axis=1) / size)).astype(np.int64)
        owner = np.repeat(np.arange(len(starts)), pieces)
        step = np.arange(len(owner)) - np.repeat(np.cumsum(pieces) - pieces, pieces)
        along = (ends - starts)[owner] / pieces[owner, None]
        a = starts[owner] + step[:, None] * along
        b = a + along
        # block k holds the nodes from low + k size to low + (k + 1) size, both included
        first = np.maximum(np.ceil((np.minimum(a, b) - self.reach - self.low) / size - 1.0), 0).astype(np.int64)
        last = np.minimum(np.floor((np.maximum(a, b) + self.reach - self.low) / size), self.counts - 1).astype(np.int64)
        spans = last - first + 1
        per_piece = np.prod(spans, axis=1)
        piece = np.repeat(np.arange(len(owner)), per_piece)
        local = np.arange(len(piece)) - np.repeat(np.cumsum(per_piece) - per_piece, per_piece)
        span = spans[piece]
        block = first[piece] + np.column_stack([local // (span[:, 1] * span[:, 2]), (local // span[:, 2]) % span[:, 1],
                                                local % span[:, 2]])
        blocks, which = np.unique(np.ravel_multi_index(block.T, self.counts), return_inverse=True)
        pairs = np.unique(which * len(starts) + owner[piece])  # by block, then segment; each pair once
        first_pair = np.searchsorted(pairs, np.arange(1, len(blocks)) * len(starts))
        return np.column_stack(np.unravel_index(blocks, self.counts)), np.split(pairs % len(starts), first_pair)


def _mesh(blocks: _Blocks, starts: np.ndarray, ends: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """The mesh (vertices mm, faces) of all blocks, welded.

    Raises _OverBudget as soon as the triangles, counted or projected from the blocks meshed
    so far (visited in a shuffled order, so that they are a fair sample), exceed TRIANGLE_BUDGET.
    """
    total = len(blocks.index)
    position_parts, face_parts, shared_parts = [], [], []
    offset = triangles = 0
    for done, b in enumerate(np.random.default_rng(0).permutation(total), start=1):
        origin = blocks.index[b] * BLOCK_CELLS
        field = _block_distance(origin, BLOCK_CELLS, blocks.low, blocks.cell, starts, ends, blocks.segments[b],
                                blocks.reach)
        field -= radius
        if field.min() <= 0.0 <= field.max():
            vertices, faces, _, _ = marching_cubes(field, level=0.0, allow_degenerate=False)
            position_parts.append(vertices + origin)  # grid index units
            shared_parts.append(np.any((vertices == 0.0) | (vertices == BLOCK_CELLS), axis=1))  # on a face of the block
            face_parts.append(faces + offset)
            offset += len(vertices)
            triangles += len(faces)
        projected = triangles * total / done  # triangles go as 1 / cell^2
        if triangles > TRIANGLE_BUDGET or (done >= PROJECT_AFTER * total and projected > 1.25 * TRIANGLE_BUDGET):
            raise _OverBudget(math.sqrt(projected / TRIANGLE_BUDGET))
    if not face_parts:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    positions, faces = _welded(np.vstack(position_parts), np.vstack(face_parts), np.concatenate(shared_parts))
    return blocks.low + blocks.cell * positions, faces


def _welded(positions: np.ndarray, faces: np.ndarray, shared: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One vertex for each place where neighbouring blocks both put one (on their shared face of nodes).

    positions: (V, 3) grid index units.  faces: (F, 3).  shared: (V,) the vertices on a face
    of their block, the only ones that can have a twin (each block's own are distinct).
    """
    candidates = np.nonzero(shared)[0]
    # twins are equal to the last bit: both blocks interpolate the same two node values, and
    # float32 block coordinates plus whole grid indices are exact in float64
    _, first, twin = np.unique(positions[candidates], axis=0, return_index=True, return_inverse=True)
    target = np.arange(len(positions))
    target[candidates] = candidates[first[twin.reshape(-1)]]
    kept = target == np.arange(len(positions))
    renumbered = np.cumsum(kept) - 1
    return positions[kept], renumbered[target[faces]]


@njit(cache=True)
def _block_distance(origin, block_cells, low, cell, starts, ends, segments, reach):
    """(n, n, n) distances (mm) from the nodes of one block (n = block_cells + 1) to the nearest
    of `segments`, capped at `reach`.

    origin: (3,) grid index of the block's first node; the node (i, j, k) is at
    low + cell * (origin + (i, j, k)).  starts, ends: (S, 3) mm, segment ends.
    """
    n = block_cells + 1
    squared = np.full((n, n, n), reach * reach)
    lo = np.empty(3, np.int64)
    hi = np.empty(3, np.int64)
    for s in segments:
        ax, ay, az = starts[s, 0], starts[s, 1], starts[s, 2]
        ux, uy, uz = ends[s, 0] - ax, ends[s, 1] - ay, ends[s, 2] - az
        length2 = ux * ux + uy * uy + uz * uz
        inverse = 1.0 / length2 if length2 > 0.0 else 0.0  # a point-like segment: its start
        for d in range(3):
            a, b = starts[s, d], ends[s, d]
            lo[d] = max(0, math.ceil((min(a, b) - reach - low[d]) / cell) - origin[d])
            hi[d] = min(block_cells, math.floor((max(a, b) + reach - low[d]) / cell) - origin[d])
        for i in range(lo[0], hi[0] + 1):
            px = low[0] + cell * (origin[0] + i) - ax
            for j in range(lo[1], hi[1] + 1):
                py = low[1] + cell * (origin[1] + j) - ay
                along_xy = px * ux + py * uy
                for k in range(lo[2], hi[2] + 1):
                    pz = low[2] + cell * (origin[2] + k) - az
                    t = min(1.0, max(0.0, (along_xy + pz * uz) * inverse))
                    dx, dy, dz = px - t * ux, py - t * uy, pz - t * uz
                    d2 = dx * dx + dy * dy + dz * dz
                    if d2 < squared[i, j, k]:
                        squared[i, j, k] = d2
    return np.sqrt(squared)
