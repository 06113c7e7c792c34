"""Scan clouds that cannot show a hose, refused before the fit with what is wrong with them.

A scan of a hose of radius r is a tube: many distinct points (at a grid of a quarter of r, the
coarse grid of centerline_fit.py), spread across the hose by about r in every direction normal
to it (r/sqrt(2) all round, about r/3 from one side).  A cloud with too few distinct points (a
point repeated, a scan in metres rather than mm), or one whose points lie on a line or a plane
(rms distance from their best line or plane below FLAT_FRACTION of r, once isolated outliers are
dropped), gives the fit nothing to find; a cloud out of the hose's reach of the problem's mounts
is of another part, or in other coordinates.  Units: mm.
"""

from __future__ import annotations

import numpy as np

MIN_DISTINCT = 25  # distinct points at the coarse grid a hose scan shows at least (one section's worth)
FLAT_FRACTION = 0.1  # of the radius: a cloud thinner than this across its best line or plane is flat
MIN_IN_REACH = 0.5  # of the points: at least this many must lie where the hose can be
REACH_SAMPLE = 100_000  # points the share in reach is counted on


def check_count(distinct: np.ndarray, radius: float, grid: float) -> None:
    """Raise ValueError when the distinct points (n, 3) of a scan at a grid of `grid` mm are too few for a hose of
    outer radius `radius` mm."""
    count = distinct.shape[0]
    if count < MIN_DISTINCT:
        raise ValueError(f"holds {count} distinct point(s) at a grid of {grid:.3g} mm (a quarter of the hose's radius "
                         f"{radius:g} mm), fewer than the {MIN_DISTINCT} of one section of a hose scan: a point "
                         "repeated, too few points, or a scan in other units than mm")


def check_spread(distinct: np.ndarray, radius: float) -> None:
    """Raise ValueError when the distinct points (n, 3) of a scan (its isolated outliers dropped) lie on a line or
    a plane for a hose of outer radius `radius` mm."""
    spread = np.linalg.svd(distinct - distinct.mean(axis=0), compute_uv=False) / np.sqrt(distinct.shape[0])
    if spread[1] < FLAT_FRACTION * radius:
        raise ValueError(f"its points lie on a line ({spread[1]:.3g} mm rms off it, {spread[0]:.3g} mm rms along "
                         f"it): a scan of a hose of radius {radius:g} mm is a tube around the hose, at least "
                         f"{FLAT_FRACTION * radius:.3g} mm across")
    if spread[2] < FLAT_FRACTION * radius:
        raise ValueError(f"its points lie on a plane ({spread[2]:.3g} mm rms off it): a scan of a hose of radius "
                         f"{radius:g} mm is a tube around the hose, at least {FLAT_FRACTION * radius:.3g} mm across "
                         "in every direction")


def check_reach(points: np.ndarray, start: np.ndarray, end: np.ndarray, reach: float) -> None:
    """Raise ValueError when fewer than MIN_IN_REACH of the scan's points (n, 3) lie within `reach` mm (the hose's
    length and outer radius, with its fittings) of both mounts `start` and `end` (mm), where a hose held by them
    can be.  The share is counted on an even subsample of at most REACH_SAMPLE points (a scan of millions needs no
    more, nor its memory for the distances)."""
    points = points[:: max(1, points.shape[0] // REACH_SAMPLE)]
    near = (np.linalg.norm(points - start, axis=1) <= reach) & (np.linalg.norm(points - end, axis=1) <= reach)
    if np.mean(near) < MIN_IN_REACH:
        centre = np.median(points, axis=0)
        raise ValueError(f"only {np.mean(near):.0%} of its points lie within the hose's reach of the mounts ({reach:.4g} "
                         f"mm of both); its median point {np.round(centre, 3).tolist()} is "
                         f"{np.linalg.norm(centre - start):.4g} mm from the start mount: is it in the problem's "
                         "coordinates, and in mm?")
