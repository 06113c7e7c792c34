"""Synthetic scans of a hose: surface points around a known centreline, as a scanner would see them.

For tests and the validation demo: the known shape (computed finer than any model that is
fitted to it) is wrapped in a tube of the hose radius, sampled at random, seen from one side
only if asked, with gaps, noise and stray points.  Units: mm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline


@dataclass(frozen=True)
class ScanDefects:
    """What makes a scan imperfect.

    density: surface points per mm^2 (before one-sided coverage removes the hidden side).
    noise: standard deviation of the measurement noise per coordinate, mm.
    outlier_fraction: stray points, as a fraction of the surface points, uniform in the
        bounding box grown by ten radii.
    view: direction from the scanner towards the hose; only the surface facing the scanner
        is kept (None: all round).
    gaps: (from, to) arc-length ranges with no points, mm.
    """

    density: float = 1.5
    noise: float = 0.05
    outlier_fraction: float = 0.01
    view: tuple[float, float, float] | None = None
    gaps: tuple[tuple[float, float], ...] = ()


def synthetic_scan(
    s: np.ndarray, centerline: np.ndarray, radius: float, defects: ScanDefects = ScanDefects(), seed: int = 0
) -> np.ndarray:
    """Surface points (n, 3) of a tube of `radius` mm around the centreline through (s, centerline).

    s: (N+1,) arc length of the stations, mm; centerline: (N+1, 3), mm.  The centreline is
    interpolated by a cubic spline in s, so the surface is smooth.  seed: random seed.
    """
    rng = np.random.default_rng(seed)
    spline = CubicSpline(s, centerline, axis=0)
    count = int(defects.density * 2.0 * np.pi * radius * s[-1])
    along = rng.uniform(s[0], s[-1], count)
    for low, high in defects.gaps:
        along = along[(along < low) | (along > high)]
    tangents = spline(along, 1)
    tangents /= np.linalg.norm(tangents, axis=1)[:, None]
    helper = np.where(np.abs(tangents[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    e1 = np.cross(tangents, helper)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(tangents, e1)
    angle = rng.uniform(0.0, 2.0 * np.pi, along.size)
    normals = np.cos(angle)[:, None] * e1 + np.sin(angle)[:, None] * e2
    points = spline(along) + radius * normals
    if defects.view is not None:
        points = points[normals @ np.asarray(defects.view, dtype=float) < 0.0]
    points = points + rng.normal(scale=defects.noise, size=points.shape)
    low, high = centerline.min(axis=0) - 10.0 * radius, centerline.max(axis=0) + 10.0 * radius
    strays = rng.uniform(low, high, size=(int(defects.outlier_fraction * points.shape[0]), 3))
    return rng.permutation(np.vstack([points, strays]))
