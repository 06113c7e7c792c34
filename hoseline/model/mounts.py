"""Mounts: where a hose end is held and which way the fitting points.

A mount is a point (mm) and a direction pointing from the fitting into the hose
span (the thesis convention: the hose leaves B along A->B and leaves D along D->C).
At the start mount the hose tangent is +direction; at the end mount the hose
arrives along -direction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def unit_vector(vector, name: str) -> np.ndarray:
    """Normalise a 3-vector; refuse zero, NaN or infinite vectors with a message naming the field."""
    v = np.asarray(vector, dtype=float).reshape(-1)
    if v.shape != (3,):
        raise ValueError(f"{name} = {list(v)}: must have exactly three components (x, y, z)")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} = {list(v)}: components must be finite numbers")
    scale = float(np.max(np.abs(v)))  # scaled first: the norm of [1e308, 1e308, 0] would overflow to inf
    norm = scale * float(np.linalg.norm(v / scale)) if scale > 0.0 else 0.0
    if norm < 1e-12:
        raise ValueError(f"{name} = {list(v)}: a direction cannot be the zero vector; give the fitting axis, e.g. [1, 0, 0]")
    return (v / scale) / float(np.linalg.norm(v / scale))


@dataclass(frozen=True)
class Mount:
    """A hose fitting: its tip point and the direction from the fitting into the hose.

    point: mm, the fitting tip where the hose centreline starts or ends.
    direction: unit vector from the fitting into the hose span (normalised on construction).
    """

    point: np.ndarray
    direction: np.ndarray

    def __post_init__(self) -> None:
        p = np.asarray(self.point, dtype=float).reshape(-1)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"mount point = {list(p)}: must be three finite coordinates in mm")
        object.__setattr__(self, "point", p)
        object.__setattr__(self, "direction", unit_vector(self.direction, "mount direction"))

    @classmethod
    def from_points(cls, behind, tip) -> "Mount":
        """Mount at `tip`, pointing from `behind` to `tip` (the thesis' A->B); points in mm."""
        behind = np.asarray(behind, dtype=float)
        tip = np.asarray(tip, dtype=float)
        return cls(point=tip, direction=unit_vector(tip - behind, "mount direction (tip - behind)"))


def single_plane_offset(start: Mount, end: Mount) -> float | None:
    """Distance in mm of the end mount from the plane through the start mount spanned by both directions.

    The "flex in only one plane" measure (SAE J1273; cited as J1927 by Keil & Thomas):
    with n = d0 x d1 normalised, the component of (P1 - P0) along n.  None when the
    directions are parallel or antiparallel (the plane is not defined).
    """
    normal = np.cross(start.direction, end.direction)
    norm = float(np.linalg.norm(normal))
    if norm < 1e-9:
        return None
    return float(np.dot(end.point - start.point, normal / norm))


def mount_distance(start: Mount, end: Mount) -> float:
    """Straight distance in mm between the two fitting tips."""
    return float(math.dist(start.point, end.point))
