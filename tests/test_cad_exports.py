"""The CAD and mesh exports, each read back by a real reader: OpenCASCADE, pyiges and trimesh."""

import math
from dataclasses import replace

import numpy as np
import pyiges
import pytest
import trimesh
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepGProp import BRepGProp
from OCP.GCPnts import GCPnts_AbscissaPoint
from OCP.GeomAPI import GeomAPI_ProjectPointOnCurve
from OCP.gp import gp_Pnt
from OCP.GProp import GProp_GProps
from OCP.IFSelect import IFSelect_ReturnStatus
from OCP.IGESControl import IGESControl_Reader
from OCP.IGESToBRep import IGESToBRep_BasicCurve
from OCP.Message import Message_ProgressRange
from OCP.RWGltf import RWGltf_CafReader
from OCP.RWStl import RWStl
from OCP.STEPControl import STEPControl_Reader
from OCP.TCollection import TCollection_AsciiString, TCollection_ExtendedString
from OCP.TDocStd import TDocStd_Document
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_SOLID
from OCP.TopExp import TopExp_Explorer
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS
from typer.testing import CliRunner

from hoseline import cli
from hoseline.commands import common
from hoseline.procedures.placement import sequence as placement
from hoseline.io import export_names, exports
from hoseline.io.iges_mounts import read_named_points
from hoseline.io.mesh import CHORD_TOLERANCE_MM, tube_mesh
from hoseline.io.occt import quiet
from hoseline.io.step_shape import SweepError, tube_solid

STATION_TOLERANCE_MM = 0.01


@pytest.fixture(scope="module")
def exported(twisted_hose, tmp_path_factory):
    """Every export of the twisted hose, written once into one folder."""
    folder = tmp_path_factory.mktemp("exports")
    files = exports.write_exports(twisted_hose, folder, list(export_names.FILE_NAMES))
    assert [file.name for file in files] == list(exports.FILE_NAMES.values())
    return folder


def edges(shape):
    """The edges of an OpenCASCADE shape."""
    found, explorer = [], TopExp_Explorer(shape, TopAbs_EDGE)
    while explorer.More():
        found.append(TopoDS.Edge(explorer.Current()))
        explorer.Next()
    return found


def distance_to_curve(curve, point) -> float:
    """Shortest distance in mm from a point to an OpenCASCADE curve."""
    return GeomAPI_ProjectPointOnCurve(gp_Pnt(*map(float, point)), curve).LowerDistance()


def test_step_reads_back_as_a_valid_tube_around_the_stations(twisted_hose, exported):
    quiet()
    reader = STEPControl_Reader()
    assert reader.ReadFile(str(exported / "hose.step")) == IFSelect_ReturnStatus.IFSelect_RetDone
    reader.TransferRoots()
    shapes = [reader.Shape(index) for index in range(1, reader.NbShapes() + 1)]
    solids = [shape for shape in shapes if shape.ShapeType() == TopAbs_SOLID]
    assert len(solids) == 1 and BRepCheck_Analyzer(solids[0]).IsValid()

    hose = twisted_hose.problem.hose
    properties = GProp_GProps()
    BRepGProp.VolumeProperties_s(solids[0], properties)
    assert properties.Mass() == pytest.approx(math.pi * hose.outer_radius**2 * hose.length, rel=0.005)

    (centreline,) = [edge for shape in shapes if shape.ShapeType() != TopAbs_SOLID for edge in edges(shape)]
    curve = BRep_Tool.Curve_s(centreline, 0.0, 0.0)
    assert max(distance_to_curve(curve, point) for point in twisted_hose.centerline) < STATION_TOLERANCE_MM
    assert GCPnts_AbscissaPoint.Length_s(BRepAdaptor_Curve(centreline)) == pytest.approx(hose.length, rel=1e-3)
    text = (exported / "hose.step").read_text()
    assert "AUTOMOTIVE_DESIGN" in text  # AP214
    assert "PRODUCT('hose'" in text and "PRODUCT('centerline'" in text


def test_iges_reads_back_in_opencascade_in_the_thesis_form(twisted_hose, exported):
    quiet()
    reader = IGESControl_Reader()
    assert reader.ReadFile(str(exported / "hose.igs")) == IFSelect_ReturnStatus.IFSelect_RetDone
    model = reader.IGESModel()
    entities = {}
    for number in range(1, model.NbEntities() + 1):
        entity = model.Entity(number)
        entities.setdefault(entity.TypeNumber(), []).append(entity)
    segments = twisted_hose.problem.hose.segments
    assert {kind: len(found) for kind, found in entities.items()} == {116: segments, 106: 1, 100: 1, 124: 1, 126: 1}
    stations = twisted_hose.centerline
    centres = 0.5 * (stations[1:] + stations[:-1])

    points = read_named_points(exported / "hose.igs")  # our mount reader: labels CM1..CMn at the segment centres
    np.testing.assert_allclose([points[f"CM{i + 1}"][0] for i in range(segments)], centres, atol=1e-6)

    (polyline,) = entities[106]
    assert polyline.FormNumber() == 12 and polyline.NbPoints() == segments + 2
    corners = [polyline.Point(index).Coord() for index in range(1, segments + 3)]
    np.testing.assert_allclose(corners, np.vstack([stations[:1], centres, stations[-1:]]), atol=1e-6)

    (circle,) = entities[100]
    assert circle.HasTransf() and circle.ShortLabel().ToCString().strip() == "PROFILE"
    assert circle.Radius() == pytest.approx(twisted_hose.problem.hose.outer_radius)
    np.testing.assert_allclose(circle.TransformedCenter().Coord(), stations[0], atol=1e-6)
    normal = np.array(circle.TransformedAxis().Coord())  # the circle's plane is normal to the hose at the start
    np.testing.assert_allclose(np.cross(normal, twisted_hose.problem.start.direction), 0.0, atol=1e-9)

    (spline,) = entities[126]
    curve = IGESToBRep_BasicCurve().TransferBSplineCurve(spline)
    assert max(distance_to_curve(curve, point) for point in stations) < STATION_TOLERANCE_MM
    roots = reader.NbRootsForTransfer()
    assert reader.TransferRoots() == roots == segments + 3  # every point and curve becomes a shape


def test_iges_reads_back_in_pyiges(twisted_hose, exported):
    iges = pyiges.read(str(exported / "hose.igs"))
    points = iges.points()
    assert len(points) == twisted_hose.problem.hose.segments
    assert [point.d["entity_label"].strip() for point in points[:2]] == ["CM1", "CM2"]
    centres = 0.5 * (twisted_hose.centerline[1:] + twisted_hose.centerline[:-1])
    np.testing.assert_allclose([point.coordinate for point in points], centres, atol=1e-6)
    kinds = [entity.d["entity_type_number"] for entity in iges]
    assert kinds.count(106) == kinds.count(100) == kinds.count(124) == kinds.count(126) == 1
    (arc,) = iges.circular_arcs()
    assert arc.d["transform"] > 0  # placed by the 124 matrix


@pytest.mark.parametrize("name", ["hose.stl", "hose.ply", "hose.glb"])
def test_meshes_read_back_watertight_with_the_hose_radius(twisted_hose, exported, name):
    mesh = trimesh.load(exported / name, force="mesh")
    assert mesh.is_watertight and mesh.is_winding_consistent
    hose = twisted_hose.problem.hose
    sides = (len(mesh.vertices) - 2) // (hose.segments + 1)
    polygon_area = 0.5 * sides * hose.outer_radius**2 * math.sin(2 * math.pi / sides)
    assert mesh.volume == pytest.approx(polygon_area * hose.length, rel=1e-6)  # mitred joints keep the volume
    assert hose.outer_radius * (1 - math.cos(math.pi / sides)) <= CHORD_TOLERANCE_MM


def test_mesh_vertices_lie_on_the_outer_radius_of_their_segments(twisted_hose):
    mesh = tube_mesh(twisted_hose)
    stations = twisted_hose.centerline
    ring = (len(mesh.vertices) - 2) // len(stations)
    rings = np.asarray(mesh.vertices[:-2]).reshape(len(stations), ring, 3)
    tangents = np.diff(stations, axis=0) / twisted_hose.problem.hose.segment_length
    for index in range(len(stations)):
        for segment in {max(index - 1, 0), min(index, len(tangents) - 1)}:  # both segments meeting at a joint
            offset = rings[index] - stations[segment]
            across = offset - np.outer(offset @ tangents[segment], tangents[segment])
            np.testing.assert_allclose(
                np.linalg.norm(across, axis=1), twisted_hose.problem.hose.outer_radius, rtol=1e-9
            )


def test_meshes_open_in_opencascade(twisted_hose, exported):
    quiet()
    triangles = len(tube_mesh(twisted_hose).faces)
    assert RWStl.ReadFile_s(str(exported / "hose.stl")).NbTriangles() == triangles
    document = TDocStd_Document(TCollection_ExtendedString("gltf"))
    reader = RWGltf_CafReader()
    reader.SetDocument(document)
    assert reader.Perform(TCollection_AsciiString(str(exported / "hose.glb")), Message_ProgressRange())
    read, faces = 0, TopExp_Explorer(reader.SingleShape(), TopAbs_FACE)
    while faces.More():
        read += BRep_Tool.Triangulation_s(TopoDS.Face(faces.Current()), TopLoc_Location()).NbTriangles()
        faces.Next()
    assert read == triangles


def test_a_fold_is_refused_and_nothing_is_written(twisted_hose, tmp_path):
    folded = replace(twisted_hose, min_bend_radius=-1.0)
    with pytest.raises(SweepError, match="tighter than the hose's outer radius"):
        tube_solid(folded)
    with pytest.raises(exports.ExportError, match="hose.step"):
        exports.write_exports(folded, tmp_path / "out", ["iges", "step", "stl"])
    assert not (tmp_path / "out").exists()
    assert list(tmp_path.iterdir()) == []  # no staging left behind


def test_format_names():
    assert export_names.parse_formats("iges, STP,glb,cmd,iges") == ["iges", "step", "gltf", "adams"]
    assert export_names.parse_formats("all") == list(export_names.FILE_NAMES)
    assert export_names.parse_formats("none") == []
    with pytest.raises(ValueError, match="unknown export format 'dxf': choose from iges, step"):
        export_names.parse_formats("iges,dxf")


def test_cli_solve_exports_beside_the_results(tmp_path):
    from cases import THESIS_TOML, write

    problem = write(tmp_path / "brake.toml", THESIS_TOML)
    result = CliRunner().invoke(
        cli.app, ["solve", str(problem), "-o", str(tmp_path / "out"), "--export", "iges,step,stl,adams"]
    )
    assert result.exit_code == 0, result.output
    names = sorted(path.name for path in (tmp_path / "out").iterdir())
    assert names == ["centerline.csv", "hose.cmd", "hose.igs", "hose.step", "hose.stl", "result.json"]
    assert "hose.step (" in result.output


def test_cli_unknown_export_exits_2_before_solving(tmp_path, monkeypatch):
    from cases import THESIS_TOML, write

    monkeypatch.setattr(placement, "solve", lambda *a, **k: pytest.fail("solved despite a bad --export"))
    problem = write(tmp_path / "brake.toml", THESIS_TOML)
    result = CliRunner().invoke(cli.app, ["solve", str(problem), "-o", str(tmp_path / "out"), "--export", "iges,dwg"])
    assert result.exit_code == common.BAD_INPUT
    assert "unknown export format 'dwg'" in result.output
    assert not (tmp_path / "out").exists()


def test_cli_export_failure_exits_4_and_writes_nothing(tmp_path, monkeypatch):
    from cases import THESIS_TOML, write

    solve = placement.solve
    monkeypatch.setattr(placement, "solve", lambda problem, **k: replace(solve(problem, **k), min_bend_radius=-1.0))
    problem = write(tmp_path / "brake.toml", THESIS_TOML)
    result = CliRunner().invoke(cli.app, ["solve", str(problem), "-o", str(tmp_path / "out"), "-e", "step"])
    assert result.exit_code == common.EXPORT_FAILED
    assert "export failed, nothing written: hose.step" in result.output
    assert not (tmp_path / "out").exists()
