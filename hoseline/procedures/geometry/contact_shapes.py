"""Triangle meshes of a problem's contact obstacles (model/obstacles.py), to draw them and measure clearance to them.

The solver keeps the hose out of the exact analytic shapes; the studio and the sweep report need
triangles to draw, and the studio's clearance readouts and colour map measure to the same
triangles (required clearance 0: the hose may touch them).  Boxes and meshes are triangles already
(the solver's own surface, exact).  Spheres and capsules are tessellated finely enough that the facets lie
within 0.5 % of the radius of the true surface (inside it: a tessellation's vertices are on the
surface, its faces inside), so the drawn clearance of a touching hose reads a little over zero,
never under.  A plane is drawn as a square about the hose's mounts, `PLANE_EXTENT` hose lengths
wide (a half-space has no edge to draw).
"""

from __future__ import annotations

import numpy as np

from hoseline.model.obstacles import Box, Cylinder, Mesh, Obstacle, Plane, Sphere
from hoseline.model.problem import Problem
from hoseline.model.sweep import Obstacle as MeshObstacle

PLANE_EXTENT = 4.0  # the drawn square of a plane, in hose lengths
SOURCE = "[contact]"  # the source of these meshes (they come from the problem file's contact table)


def contact_meshes(problem: Problem, plane_extent: float = PLANE_EXTENT) -> list[MeshObstacle]:
    """One mesh per obstacle of problem.contact, named as the obstacle, required clearance 0 (mm).

    plane_extent: the side of a plane's square, in hose lengths.
    """
    centre = 0.5 * (problem.start.point + problem.end.point)
    return [_mesh(obstacle, centre, plane_extent * problem.hose.length) for obstacle in problem.contact]


def _mesh(obstacle: Obstacle, centre: np.ndarray, extent: float) -> MeshObstacle:
    """The triangles of one obstacle (mm); a plane as a square of side `extent` about `centre`'s projection."""
    import trimesh  # loaded only when a problem with contact is opened

    if isinstance(obstacle, Plane):
        normal = obstacle.normal
        foot = centre - float(np.dot(centre - obstacle.point, normal)) * normal
        u = np.cross(normal, np.eye(3)[int(np.argmin(np.abs(normal)))])
        u /= np.linalg.norm(u)
        v = np.cross(normal, u)
        half = 0.5 * extent
        vertices = foot + half * np.array([-u - v, u - v, u + v, -u + v])
        faces = np.array([[0, 1, 2], [0, 2, 3]])  # counter-clockwise seen from the free side
    elif isinstance(obstacle, Sphere):
        mesh = trimesh.creation.icosphere(subdivisions=4, radius=obstacle.radius)
        vertices, faces = mesh.vertices + obstacle.centre, mesh.faces
    elif isinstance(obstacle, Cylinder):
        axis = obstacle.end - obstacle.start
        length = float(np.linalg.norm(axis))
        mesh = trimesh.creation.capsule(height=length, radius=obstacle.radius, count=[48, 48])
        rotation = trimesh.geometry.align_vectors([0.0, 0.0, 1.0], axis / length)
        rotation[:3, 3] = 0.5 * (obstacle.start + obstacle.end)
        mesh.apply_transform(rotation)
        vertices, faces = mesh.vertices, mesh.faces
    elif isinstance(obstacle, (Box, Mesh)):  # their own triangles: the solver's exact surface
        vertices, faces = obstacle.triangles()
    else:
        raise TypeError(f"contact obstacle {obstacle.name!r}: {type(obstacle).__name__} cannot be drawn")
    return MeshObstacle(obstacle.name, np.asarray(vertices, dtype=float), np.asarray(faces, dtype=np.int64),
                        clearance=0.0, source=SOURCE)
