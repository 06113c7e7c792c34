"""How far a model centreline is from measured points: per station, mean, RMS, max and where.

The thesis' form: given reference points (the axis midpoints of fitted cylinders), the
shortest distance from each to the model's centreline polyline.  The same is done for
every station of a fitted scan centreline.  Pass/fail against thresholds; the thesis
accepted a mean below 1 mm at 0 deg of twist and below 6 mm at 180 deg.  Units: mm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

THESIS_MEAN_LIMIT_UNTWISTED = 1.0  # mm, at 0 deg
THESIS_MEAN_LIMIT_TWISTED = 6.0  # mm, at 180 deg


def closest_on_polyline(points: np.ndarray, polyline: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Shortest distance from each point to a polyline.

    points: (n, 3); polyline: (m, 3), mm.  Returns (distance (n,), arc length of the closest
    point along the polyline (n,), closest point (n, 3)).
    """
    points = np.atleast_2d(np.asarray(points, dtype=float))
    start, edge = polyline[:-1], np.diff(polyline, axis=0)
    lengths2 = np.maximum(np.einsum("ij,ij->i", edge, edge), 1e-300)
    s_nodes = np.concatenate([[0.0], np.cumsum(np.sqrt(lengths2))])
    distance = np.empty(points.shape[0])
    arc = np.empty(points.shape[0])
    closest = np.empty_like(points)
    for chunk in range(0, points.shape[0], 2048):  # (chunk, segments) arrays stay small
        p = points[chunk : chunk + 2048]
        t = np.clip(np.einsum("nsk,sk->ns", p[:, None, :] - start[None], edge) / lengths2, 0.0, 1.0)
        foot = start[None] + t[:, :, None] * edge[None]
        d2 = np.einsum("nsk,nsk->ns", p[:, None, :] - foot, p[:, None, :] - foot)
        best = np.argmin(d2, axis=1)
        rows = np.arange(p.shape[0])
        distance[chunk : chunk + 2048] = np.sqrt(d2[rows, best])
        arc[chunk : chunk + 2048] = s_nodes[best] + t[rows, best] * np.sqrt(lengths2[best])
        closest[chunk : chunk + 2048] = foot[rows, best]
    return distance, arc, closest


@dataclass(frozen=True)
class Thresholds:
    """Acceptance limits of a comparison, mm: the mean deviation, and optionally the largest; noise: also require
    the mean deviation to be within what the scan's own noise and the model's discretisation explain
    (validation.Comparison.noise_allowance)."""

    mean: float
    max: float | None = None
    noise: bool = True

    @classmethod
    def thesis(cls, twist_deg: float) -> "Thresholds":
        """The thesis' criteria: mean below 1 mm untwisted, below 6 mm twisted (given for 180 deg)."""
        twisted = abs(twist_deg) > 1e-9
        return cls(THESIS_MEAN_LIMIT_TWISTED if twisted else THESIS_MEAN_LIMIT_UNTWISTED)


@dataclass
class Deviation:
    """Distances from measured points to a model centreline.

    points: (n, 3) measured points (scan stations or reference points), mm.
    distance: (n,) shortest distance of each to the model centreline, mm.
    s_model: (n,) arc length of the closest model point from the start fitting, mm.
    closest: (n, 3) the closest model points, mm.
    """

    points: np.ndarray
    distance: np.ndarray
    s_model: np.ndarray
    closest: np.ndarray

    @property
    def mean(self) -> float:
        """Mean distance, mm."""
        return float(np.mean(self.distance))

    @property
    def rms(self) -> float:
        """Root-mean-square distance, mm."""
        return float(np.sqrt(np.mean(self.distance**2)))

    @property
    def max(self) -> float:
        """Largest distance, mm."""
        return float(np.max(self.distance))

    @property
    def s_at_max(self) -> float:
        """Arc length along the model where the largest deviation is, mm."""
        return float(self.s_model[int(np.argmax(self.distance))])

    def passes(self, thresholds: Thresholds) -> bool:
        """True when the mean (and the largest, if limited) deviation is within the thresholds."""
        return self.mean <= thresholds.mean and (thresholds.max is None or self.max <= thresholds.max)

    def summary(self) -> dict:
        """Mean, RMS, max and where, mm."""
        return {"stations": int(self.distance.size), "mean_mm": self.mean, "rms_mm": self.rms,
                "max_mm": self.max, "s_at_max_mm": self.s_at_max}


def deviation(model_centerline: np.ndarray, points: np.ndarray) -> Deviation:
    """Shortest distances from measured points (n, 3) to the model centreline polyline (N+1, 3), mm."""
    distance, arc, closest = closest_on_polyline(points, model_centerline)
    return Deviation(np.atleast_2d(np.asarray(points, dtype=float)), distance, arc, closest)
