"""The hose as STEP AP214 through OpenCASCADE: a solid tube and its centreline, named for the CAD tree.

Two products, unit mm:
- "hose": the start fitting's disc of the outer radius swept along the centreline
  B-spline, a closed solid;
- "centerline": the B-spline through every station (the same curve as the IGES SPLINE).
"""

from __future__ import annotations

import io

from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakeWire
from OCP.BRepCheck import BRepCheck_Analyzer
from OCP.BRepOffsetAPI import BRepOffsetAPI_MakePipe
from OCP.IFSelect import IFSelect_ReturnStatus
from OCP.Interface import Interface_Static
from OCP.STEPCAFControl import STEPCAFControl_Writer
from OCP.STEPControl import STEPControl_StepModelType
from OCP.TCollection import TCollection_ExtendedString
from OCP.TDataStd import TDataStd_Name
from OCP.TDocStd import TDocStd_Document
from OCP.TopoDS import TopoDS_Edge, TopoDS_Shape
from OCP.XCAFDoc import XCAFDoc_DocumentTool

from hoseline.io.occt import centerline_spline, quiet, start_circle
from hoseline.procedures.placement.result import Result


class SweepError(RuntimeError):
    """OpenCASCADE could not sweep the hose into a valid solid; the message says what to check."""


def tube_solid(result: Result) -> tuple[TopoDS_Shape, TopoDS_Edge]:
    """(the hose solid, the centreline edge), in mm.

    Raises SweepError when the centreline bends tighter than the outer radius somewhere (the
    tube would fold onto itself, which OpenCASCADE does not notice), or when the sweep fails.
    """
    radius = result.problem.hose.outer_radius
    if result.min_bend_radius <= 0.0:
        raise SweepError(
            f"the centreline bends with radius {result.min_bend_radius + radius:.3g} mm, tighter than the hose's "
            f"outer radius {radius:g} mm: the swept tube would fold onto itself"
        )
    centreline = BRepBuilderAPI_MakeEdge(centerline_spline(result)).Edge()
    profile = BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(start_circle(result)).Edge()).Wire()
    sweep = BRepOffsetAPI_MakePipe(BRepBuilderAPI_MakeWire(centreline).Wire(), BRepBuilderAPI_MakeFace(profile).Face())
    sweep.Build()
    if not sweep.IsDone() or not BRepCheck_Analyzer(sweep.Shape()).IsValid():
        raise SweepError(f"OpenCASCADE could not sweep the hose of outer radius {radius:g} mm into a valid solid")
    return sweep.Shape(), centreline


def step_bytes(result: Result) -> bytes:
    """The STEP AP214 file's bytes: products "hose" (solid) and "centerline" (B-spline edge), mm."""
    quiet()
    solid, centreline = tube_solid(result)
    document = TDocStd_Document(TCollection_ExtendedString("hoseline"))
    shapes = XCAFDoc_DocumentTool.ShapeTool_s(document.Main())
    for shape, name in ((solid, "hose"), (centreline, "centerline")):
        TDataStd_Name.Set_s(shapes.AddShape(shape, False), TCollection_ExtendedString(name))
    writer = STEPCAFControl_Writer()
    Interface_Static.SetCVal_s("write.step.schema", "AP214IS")
    Interface_Static.SetCVal_s("write.step.unit", "MM")
    if not writer.Transfer(document, STEPControl_StepModelType.STEPControl_AsIs):
        raise RuntimeError("OpenCASCADE could not translate the hose to STEP")
    stream = io.BytesIO()
    if writer.WriteStream(stream) != IFSelect_ReturnStatus.IFSelect_RetDone:
        raise RuntimeError("OpenCASCADE could not write the STEP model")
    return stream.getvalue()
