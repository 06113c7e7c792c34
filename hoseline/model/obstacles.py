"""Obstacles the hose must not enter: analytic shapes, in user units (mm).

- Plane: the half-space behind a plane (a floor, a wall); the hose stays on the side its
  `normal` points to.
- Sphere: a ball of `radius` about `centre`.
- Cylinder: a rod of `radius` about the axis from `start` to `end`, with rounded (hemispherical)
  ends: a capsule.  The rounded ends keep the distance to it smooth; make the axis longer than
  the part the hose can reach when a flat end matters.
- Box: a rectangular block of `size` about `center`, its edges along `axes`; sharp edges and
  corners (exact: its faces are its 12 triangles).
- Mesh: a triangle mesh (a part's surface, read from STL, OBJ, PLY or STEP by io/obstacle_mesh.py);
  a surface, not a solid: the hose stays on the side it starts on.

Each gives the primitives the contact kernels (mechanics/contact.py, mechanics/contact_mesh.py)
measure exact distances to.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hoseline.model.mounts import unit_vector

OBSTACLE_KINDS = ("plane", "sphere", "cylinder", "box", "mesh")
ZERO_AREA = 1e-12  # a triangle whose |(b - a) x (c - a)|^2 is below this times (|b - a|^2 + |c - a|^2)^2 is a line


def has_area(corners: np.ndarray) -> np.ndarray:
    """Which triangles of `corners` (F, 3, 3) mm have an area (are not a line or a point): (F,) bool."""
    ab, ac = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    normals = np.cross(ab, ac)
    scale = np.einsum("ij,ij->i", ab, ab) + np.einsum("ij,ij->i", ac, ac)
    return np.einsum("ij,ij->i", normals, normals) > ZERO_AREA * scale * scale


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
    kind = "plane"

    def __post_init__(self) -> None:
        object.__setattr__(self, "point", _point(self.point, f"obstacle {self.name!r} point"))
        object.__setattr__(self, "normal", unit_vector(self.normal, f"obstacle {self.name!r} normal"))


@dataclass(frozen=True)
class Sphere:
    """A ball.  centre: (3,) mm.  radius: mm."""

    centre: np.ndarray
    radius: float
    name: str = "sphere"
    kind = "sphere"

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
    kind = "cylinder"

    def __post_init__(self) -> None:
        object.__setattr__(self, "start", _point(self.start, f"obstacle {self.name!r} start"))
        object.__setattr__(self, "end", _point(self.end, f"obstacle {self.name!r} end"))
        object.__setattr__(self, "radius", _radius(self.radius, f"obstacle {self.name!r} radius"))
        if np.linalg.norm(self.end - self.start) <= 0.0:
            raise ValueError(f"obstacle {self.name!r}: start and end coincide: give an axis of positive length")


@dataclass(frozen=True)
class Box:
    """A rectangular block.  center: (3,) mm.  size: (3,) mm, its edge lengths along `axes`.

    axes: (3, 3), rows the directions of its edges (perpendicular; scaled to unit length); default
    the coordinate axes.
    """

    center: np.ndarray
    size: np.ndarray
    axes: np.ndarray = field(default_factory=lambda: np.eye(3))
    name: str = "box"
    kind = "box"

    def __post_init__(self) -> None:
        label = f"obstacle {self.name!r}"
        object.__setattr__(self, "center", _point(self.center, f"{label} center"))
        size = np.asarray(self.size, dtype=float).reshape(-1)
        if size.shape != (3,) or not np.all(np.isfinite(size) & (size > 0.0)):
            raise ValueError(f"{label} size = {size.tolist()}: must be three positive edge lengths in mm")
        object.__setattr__(self, "size", size)
        axes = np.asarray(self.axes, dtype=float)
        if axes.shape != (3, 3) or not np.all(np.isfinite(axes)) or np.any(np.linalg.norm(axes, axis=1) <= 0.0):
            raise ValueError(f"{label} axes: must be three nonzero directions [[x, y, z], [x, y, z], [x, y, z]]")
        axes = axes / np.linalg.norm(axes, axis=1)[:, None]
        if np.max(np.abs(axes @ axes.T - np.eye(3))) > 1e-6:
            raise ValueError(f"{label} axes = {axes.tolist()}: the three directions must be perpendicular "
                             "(the box's edges)")
        object.__setattr__(self, "axes", axes)

    def triangles(self) -> tuple[np.ndarray, np.ndarray]:
        """(vertices (8, 3) mm, faces (12, 3)): the box's surface, each face two triangles."""
        signs = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
        vertices = self.center + (signs * self.size) @ self.axes
        faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                          [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
        return vertices, faces


@dataclass(frozen=True)
class Mesh:
    """A triangle mesh.  vertices: (V, 3) mm.  faces: (F, 3) vertex indices.  file: where it was read from (for reports)."""

    vertices: np.ndarray
    faces: np.ndarray
    name: str = "mesh"
    file: str = ""
    kind = "mesh"

    def __post_init__(self) -> None:
        label = f"obstacle {self.name!r}"
        vertices = np.asarray(self.vertices, dtype=float)
        faces = np.asarray(self.faces)
        if vertices.ndim != 2 or vertices.shape[1] != 3 or not np.all(np.isfinite(vertices)):
            raise ValueError(f"{label}: vertices must be finite 3D points in mm (shape (V, 3)); export the mesh again")
        if faces.ndim != 2 or faces.shape[1] != 3 or faces.shape[0] == 0 or not np.issubdtype(faces.dtype, np.integer):
            raise ValueError(f"{label}: needs triangles, faces of shape (F, 3) with F > 0; export it as a surface mesh")
        if faces.min() < 0 or faces.max() >= len(vertices):
            raise ValueError(f"{label}: triangles refer to vertices the mesh does not have; export the mesh again")
        if not np.any(has_area(vertices[faces])):
            raise ValueError(f"{label}: every triangle has zero area (a line or a point): no surface to touch; "
                             "export the part's surface")
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "faces", faces.astype(np.int64))

    def triangles(self) -> tuple[np.ndarray, np.ndarray]:
        """(vertices (V, 3) mm, faces (F, 3))."""
        return self.vertices, self.faces


Obstacle = Plane | Sphere | Cylinder | Box | Mesh
