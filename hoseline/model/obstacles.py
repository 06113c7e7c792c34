"""Obstacles the hose must not enter: analytic shapes, in user units (mm).

- Plane: the half-space behind a plane (a floor, a wall); the hose stays on the side its
  `normal` points to.
- Sphere: a ball of `radius` about `centre`.
- Cylinder: a rod of `radius` about the axis from `start` to `end`, with rounded (hemispherical)
  ends: a capsule.  The rounded ends keep the distance to it smooth; make the axis longer than
  the part the hose can reach when a flat end matters.

Each gives the primitives the contact kernels (mechanics/contact.py) measure exact distances to.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hoseline.model.mounts import unit_vector

OBSTACLE_KINDS = ("plane", "sphere", "cylinder")


def _point(value, label: str) -> np.ndarray:
    p = np.asarray(value, dtype=float).reshape(-1)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ValueError(f"{label} = {list(p)}: must be three finite coordinates in mm")
    return p


def _radius(value: float, label: str) -> float:
    if not (np.isfinite(value) and value > 0.0):
        raise ValueError(f"{label} = {value!r}: must be a positive radius in mm")
    return float(value)


@dataclass(frozen=True)
class Plane:
    """The half-space {x : normal . (x - point) < 0}.  point: (3,) mm on the plane.  normal: towards the free side."""

    point: np.ndarray
    normal: np.ndarray
    name: str = "plane"

    def __post_init__(self) -> None:
        object.__setattr__(self, "point", _point(self.point, f"obstacle {self.name!r} point"))
        object.__setattr__(self, "normal", unit_vector(self.normal, f"obstacle {self.name!r} normal"))


@dataclass(frozen=True)
class Sphere:
    """A ball.  centre: (3,) mm.  radius: mm."""

    centre: np.ndarray
    radius: float
    name: str = "sphere"

    def __post_init__(self) -> None:
        object.__setattr__(self, "centre", _point(self.centre, f"obstacle {self.name!r} centre"))
        object.__setattr__(self, "radius", _radius(self.radius, f"obstacle {self.name!r} radius"))


@dataclass(frozen=True)
class Cylinder:
    """A rod of `radius` mm about the axis from `start` to `end` (mm), ends rounded (a capsule)."""

    start: np.ndarray
    end: np.ndarray
    radius: float
    name: str = "cylinder"

    def __post_init__(self) -> None:
        object.__setattr__(self, "start", _point(self.start, f"obstacle {self.name!r} start"))
        object.__setattr__(self, "end", _point(self.end, f"obstacle {self.name!r} end"))
        object.__setattr__(self, "radius", _radius(self.radius, f"obstacle {self.name!r} radius"))
        if np.linalg.norm(self.end - self.start) <= 0.0:
            raise ValueError(f"obstacle {self.name!r}: start and end coincide: give an axis of positive length")


Obstacle = Plane | Sphere | Cylinder
