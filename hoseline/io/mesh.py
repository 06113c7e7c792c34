"""The hose as a closed triangle mesh (STL, PLY, binary glTF) for viewers and clearance tools.

The tube follows the solver's straight segments: one ring of vertices per station, on the
plane that bisects the two segments meeting there (a mitred joint), so each segment's part
of the surface lies exactly on a cylinder of the hose's outer radius around that segment.
The rings are carried from segment to segment without twist (rotation-minimising), and two
fans close the ends: the mesh is watertight.  Every vertex is at the outer radius from the
segment axes; between vertices the facets cut inside the round surface by at most the
chord tolerance (0.01 mm by default).
"""

from __future__ import annotations

import math

import numpy as np
import trimesh

from hoseline.procedures.placement.result import Result

MESH_FORMATS = ("stl", "ply", "glb")
CHORD_TOLERANCE_MM = 0.01


def tube_mesh(result: Result, chord_tolerance: float = CHORD_TOLERANCE_MM) -> trimesh.Trimesh:
    """The hose surface as a watertight mesh, vertices in mm, faces wound outward.

    chord_tolerance: largest gap in mm between a facet and the round hose surface; sets
    the number of vertices around the hose (at least 8).
    """
    radius = result.problem.hose.outer_radius
    stations = result.centerline
    tangents = np.diff(stations, axis=0)
    tangents /= np.linalg.norm(tangents, axis=1)[:, None]
    sides = max(8, math.ceil(math.pi / math.acos(max(1.0 - chord_tolerance / radius, -1.0))))
    angles = 2.0 * math.pi * np.arange(sides) / sides
    first, second = _untwisted_normals(tangents)

    rings = np.empty((len(stations), sides, 3))
    for index, point in enumerate(stations):
        segment = max(index - 1, 0)  # station i > 0 closes segment i-1
        around = np.outer(np.cos(angles), first[segment]) + np.outer(np.sin(angles), second[segment])
        rings[index] = point + radius * around
        if 0 < index < len(tangents):  # slide along segment i-1 onto the bisecting plane
            bisector = tangents[index - 1] + tangents[index]
            slide = -radius * (around @ bisector) / np.dot(tangents[index - 1], bisector)
            rings[index] += np.outer(slide, tangents[index - 1])

    vertices = np.vstack([rings.reshape(-1, 3), stations[0], stations[-1]])
    around = np.arange(sides)
    following = (around + 1) % sides
    faces = []
    for segment in range(len(tangents)):
        here, there = segment * sides, (segment + 1) * sides
        faces.append(np.column_stack([here + around, here + following, there + following]))
        faces.append(np.column_stack([here + around, there + following, there + around]))
    start_centre, end_centre = len(vertices) - 2, len(vertices) - 1
    last = len(tangents) * sides
    faces.append(np.column_stack([np.full(sides, start_centre), following, around]))
    faces.append(np.column_stack([np.full(sides, end_centre), last + around, last + following]))
    return trimesh.Trimesh(vertices, np.vstack(faces), process=False)


def mesh_bytes(result: Result, file_type: str) -> bytes:
    """The tube mesh as the bytes of an STL (binary), PLY (binary) or GLB (binary glTF 2.0) file, in mm."""
    if file_type not in MESH_FORMATS:
        raise ValueError(f"mesh format {file_type!r}: choose one of {', '.join(MESH_FORMATS)}")
    return tube_mesh(result).export(file_type=file_type)


def _untwisted_normals(tangents: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit normals per segment, carried from one segment to the next by the smallest rotation."""
    first = np.empty_like(tangents)
    helper = np.eye(3)[np.argmin(np.abs(tangents[0]))]
    first[0] = np.cross(tangents[0], helper)
    first[0] /= np.linalg.norm(first[0])
    for index in range(1, len(tangents)):
        previous, current = tangents[index - 1], tangents[index]
        axis = np.cross(previous, current)
        sine, cosine = np.linalg.norm(axis), np.dot(previous, current)
        vector = first[index - 1]
        if sine > 1e-15:  # Rodrigues: rotate about the axis normal to both segments
            axis /= sine
            vector = vector * cosine + np.cross(axis, vector) * sine + axis * np.dot(axis, vector) * (1.0 - cosine)
        vector = vector - np.dot(vector, current) * current
        first[index] = vector / np.linalg.norm(vector)
    return first, np.cross(tangents, first)
