"""Read obstacle meshes (STL, OBJ, PLY, ...; STEP through OpenCASCADE) and write meshes as binary STL.

Meshes are read with trimesh; STEP files are read and tessellated by OpenCASCADE (the OCP
bindings) to within STEP_DEFLECTION.  Coordinates are taken as mm, in the same axes as the
problem file, and must lie within +-1e5 mm (model/limits.py).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hoseline.io.atomic import write_bytes
from hoseline.model import limits

STEP_SUFFIXES = (".step", ".stp")
STEP_DEFLECTION = 0.1  # mm, largest distance between a STEP surface and its triangles
STEP_ANGLE = 0.3  # rad, largest angle between neighbouring facet normals of a curved STEP face
STL_HEADER = b"binary STL written by hoseline, mm"  # not "solid ...", which readers take for an ASCII STL
STL_TRIANGLE = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])


class ObstacleFileError(ValueError):
    """A mesh file that cannot be read as triangles; the message names the file and the fix."""


def read_mesh(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) mm and triangles (F, 3) of the mesh file at `path` (all its parts merged).

    Raises ObstacleFileError for content that is not a triangle mesh, OSError if unreadable.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(2, "no such file", str(path))
    if path.suffix.lower() in STEP_SUFFIXES:
        return _read_step(path)
    import trimesh  # about 0.35 s to load: only where a mesh is read or written

    try:
        mesh = trimesh.load(path, force="mesh", process=False)  # processing would drop non-finite triangles silently
    except ModuleNotFoundError as exc:  # trimesh guesses the encoding of text that is not UTF-8 with an optional module
        raise ObstacleFileError(
            f"{path}: cannot be read as a mesh: its text is neither ASCII nor UTF-8 (damaged, or another encoding; "
            f"reading it would need the module {exc.name}); export the part again as binary STL, OBJ or PLY"
        ) from None
    except Exception as exc:  # trimesh raises many kinds for a foreign or broken file
        raise ObstacleFileError(
            f"{path}: cannot be read as a mesh ({type(exc).__name__}: {exc}); use STL, OBJ, PLY or STEP"
        ) from None
    faces = np.asarray(getattr(mesh, "faces", np.empty((0, 3))), dtype=np.int64)
    if faces.ndim != 2 or faces.shape[0] == 0:
        raise ObstacleFileError(f"{path}: holds no triangles; export the part as a surface mesh (STL, OBJ, PLY)")
    return _checked(path, np.asarray(mesh.vertices, dtype=float), faces)


def _checked(path: Path, vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mesh, if its vertices are 3D points, finite and within the coordinate range and its triangles index them."""
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
        raise ObstacleFileError(
            f"{path}: the reader found vertices of shape {vertices.shape} and faces of shape {faces.shape}, not 3D "
            "points and triangles (a damaged line, e.g. a vertex with two numbers): export the mesh again"
        )
    if not np.all(np.isfinite(vertices)):
        raise ObstacleFileError(f"{path}: has vertices that are not finite numbers (NaN or infinite coordinates): export the mesh again")
    largest = float(np.max(np.abs(vertices), initial=0.0))
    if largest > limits.COORDINATE_MM:
        raise ObstacleFileError(
            f"{path}: a vertex coordinate is {largest:g} mm, outside +-{limits.COORDINATE_MM:g} mm (100 m): "
            "export the mesh in mm"
        )
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise ObstacleFileError(f"{path}: triangles refer to vertices the file does not have: export the mesh again")
    return vertices, faces


def _read_step(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of every face of a STEP file, tessellated by OpenCASCADE."""
    from OCP.BRep import BRep_Tool  # OpenCASCADE takes about a second to load: only for STEP files
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.IFSelect import IFSelect_ReturnStatus
    from OCP.STEPControl import STEPControl_Reader
    from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS

    from hoseline.io.occt import quiet

    quiet()
    reader = STEPControl_Reader()
    if reader.ReadFile(str(path)) != IFSelect_ReturnStatus.IFSelect_RetDone or reader.TransferRoots() == 0:
        raise ObstacleFileError(f"{path}: OpenCASCADE cannot read it as STEP; export the part again as STEP AP203/214 or STL")
    shape = reader.OneShape()
    BRepMesh_IncrementalMesh(shape, STEP_DEFLECTION, False, STEP_ANGLE, True)
    vertices, faces = [], []
    explorer = TopExp_Explorer(shape, TopAbs_FACE)
    while explorer.More():
        face = TopoDS.Face(explorer.Current())
        location = TopLoc_Location()
        triangulation = BRep_Tool.Triangulation_s(face, location)
        if triangulation is not None:
            move = location.Transformation()
            first = len(vertices)
            for i in range(1, triangulation.NbNodes() + 1):
                point = triangulation.Node(i).Transformed(move)
                vertices.append((point.X(), point.Y(), point.Z()))
            reversed_face = face.Orientation() == TopAbs_REVERSED
            for i in range(1, triangulation.NbTriangles() + 1):
                a, b, c = triangulation.Triangle(i).Get()
                faces.append((first + a - 1, first + c - 1, first + b - 1) if reversed_face else
                             (first + a - 1, first + b - 1, first + c - 1))
        explorer.Next()
    if not faces:
        raise ObstacleFileError(f"{path}: the STEP file has no faces to tessellate (only curves or points?)")
    return _checked(path, np.array(vertices, dtype=float), np.array(faces, dtype=np.int64))


def write_stl(path: str | Path, vertices: np.ndarray, faces: np.ndarray) -> Path:
    """Write a binary STL (mm) atomically: an 80-byte header, the triangle count, then per triangle its unit normal
    (right-hand rule; zero for a degenerate one), its three vertices and a zero attribute, in little-endian float32.

    vertices: (V, 3) mm; faces: (F, 3) vertex indices.  Written here rather than with trimesh, which takes
    0.3-0.5 s to load for a sweep that writes its envelope and reads no mesh.
    """
    corners = np.asarray(vertices, dtype=float)[np.asarray(faces, dtype=np.int64)]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    lengths = np.linalg.norm(normals, axis=1)[:, None]
    triangles = np.zeros(len(corners), STL_TRIANGLE)
    triangles["normal"] = np.divide(normals, lengths, out=np.zeros_like(normals), where=lengths > 0.0)
    triangles["vertices"] = corners
    header = STL_HEADER.ljust(80, b" ") + len(triangles).to_bytes(4, "little")
    return write_bytes(path, header + triangles.tobytes())
