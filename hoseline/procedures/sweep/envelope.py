"""The swept envelope of the hose: the space it takes up over all poses of a sweep, as a mesh.

The envelope is the union of the hose's tube (outer radius around the centreline) over the
poses.  Its surface is the zero level of the distance to the nearest centreline point of
any pose, less the radius, sampled on a grid and triangulated by marching cubes.  The
centrelines are resampled finer than the grid, so the surface is within about one grid
cell (`cell`, mm) of the exact union.  Between two poses the hose moves by the sweep's
pose spacing; the envelope covers the poses computed, not what happens between them.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree
from skimage.measure import marching_cubes


def swept_envelope(centerlines: np.ndarray, radius: float, cell: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) mm and triangles (F, 3) of the union of the tubes around `centerlines`.

    centerlines: (M, N+1, 3) mm, one centreline per pose.  radius: mm, the outer radius.
    cell: mm, grid spacing (default: half the radius).
    """
    cell = 0.5 * radius if cell is None else cell
    points = _resampled(centerlines, 0.5 * cell)
    tree = cKDTree(points)
    low = points.min(axis=0) - radius - 2.0 * cell
    high = points.max(axis=0) + radius + 2.0 * cell
    shape = np.ceil((high - low) / cell).astype(int) + 1
    axes = [low[k] + cell * np.arange(shape[k]) for k in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    # far from the hose the exact distance does not matter: cap the search
    distance, _ = tree.query(grid, distance_upper_bound=radius + 2.0 * cell)
    field = np.minimum(distance, radius + 2.0 * cell) - radius
    vertices, faces, _, _ = marching_cubes(field.reshape(shape), level=0.0, spacing=(cell, cell, cell))
    return vertices + low, faces.astype(np.int64)


def _resampled(centerlines: np.ndarray, spacing: float) -> np.ndarray:
    """All centreline points, with extra points on every segment so that none is longer than `spacing` (mm)."""
    starts = centerlines[:, :-1].reshape(-1, 3)
    steps = centerlines[:, 1:].reshape(-1, 3) - starts
    pieces = max(1, int(np.ceil(np.max(np.linalg.norm(steps, axis=1)) / spacing)))
    fractions = np.arange(pieces) / pieces
    inner = starts[:, None, :] + fractions[None, :, None] * steps[:, None, :]
    return np.vstack([inner.reshape(-1, 3), centerlines[:, -1]])
