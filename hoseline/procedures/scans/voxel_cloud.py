"""A point cloud reduced to a voxel grid: the centroid and the number of points of each occupied voxel.

A scan of millions of points holds far more points than the shape of a hose needs: on a grid
of a tenth of the hose radius a 330 mm brake hose occupies about 10^5 voxels, whatever the
scanner's density.  A least-squares fit that weights each centroid by its point count gives
the answer of all the points, up to the curvature of the surface inside a voxel (on a tube of
radius r the centroid of a voxel of edge a lies about a^2 / (24 r) inside the surface:
0.002 mm at a = r / 10, r = 5 mm).  Units: mm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MAX_KEY_BITS = 62  # voxel number and point index packed into one int64 sort key


@dataclass
class VoxelCloud:
    """Occupied voxels of a point cloud.

    points: (m, 3) centroid of the points in each voxel, mm.  counts: (m,) points per voxel.
    inverse: (n,) voxel of each original point (None for a subset).
    """

    points: np.ndarray
    counts: np.ndarray
    inverse: np.ndarray | None = None

    def subset(self, keep: np.ndarray) -> "VoxelCloud":
        """The voxels where the boolean mask `keep` (m,) is True (without the inverse)."""
        return VoxelCloud(self.points[keep], self.counts[keep])


def voxel_cloud(points: np.ndarray, edge: float, weights: np.ndarray | None = None) -> VoxelCloud:
    """Reduce points (n, 3), mm, to the centroids of the cubes of `edge` mm they occupy.

    edge = 0 keeps every point as a voxel of its own.  weights: (n,) points each input point
    stands for (the counts of a finer grid; default 1).  Raises ValueError when the cloud spans
    too many voxels to number them (a scan kilometres across: wrong units).
    """
    points = np.asarray(points, dtype=float)
    n = points.shape[0]
    if edge == 0.0:
        return VoxelCloud(points, np.ones(n, dtype=np.int64) if weights is None else np.asarray(weights), np.arange(n))
    columns = [points[:, axis] for axis in range(3)]
    low = np.array([column.min() for column in columns])  # column by column: ~5x faster than min(axis=0)
    cells = np.array([int((column.max() - low[axis]) / edge) + 1 for axis, column in enumerate(columns)])
    index_bits = max(n - 1, 1).bit_length()
    if int(np.prod(cells.astype(object))).bit_length() + index_bits > MAX_KEY_BITS:
        raise ValueError(f"the scan spans {np.ptp(points, axis=0).round(1).tolist()} mm, too large for voxels of "
                         f"{edge:g} mm; check that it is in mm")
    key = np.zeros(n, dtype=np.int64)
    for axis, column in enumerate(columns):  # the voxel number, without building an (n, 3) integer array
        key *= cells[axis]
        key += ((column - low[axis]) / edge).astype(np.int64)  # truncation is floor: the values are >= 0
    # Sorting the voxel number with the point index in its low bits gives the order of an
    # argsort: NumPy's vectorised sort does 5 M int64 in ~0.1 s, its argsort takes ~1 s.
    key <<= index_bits
    key |= np.arange(n, dtype=np.int64)
    key.sort()
    order = key & ((1 << index_bits) - 1)
    key >>= index_bits
    starts = np.concatenate([[0], np.flatnonzero(key[1:] != key[:-1]) + 1])
    del key
    inverse = np.empty(n, dtype=np.int64)
    inverse[order] = np.repeat(np.arange(starts.size), np.diff(np.append(starts, n)))
    del order
    if weights is None:
        counts, weighted = np.bincount(inverse, minlength=starts.size), columns
    else:
        counts = np.bincount(inverse, weights=weights, minlength=starts.size).astype(np.int64)
        weighted = [column * weights for column in columns]
    sums = [np.bincount(inverse, weights=column, minlength=starts.size) for column in weighted]
    return VoxelCloud(np.column_stack(sums) / counts[:, None], counts, inverse)
