"""The hose as STEP AP214 through OpenCASCADE: a solid tube and its centreline, named for the CAD tree.

Two products, unit mm:
- "hose": the start fitting's disc of the outer radius swept along the centreline
  B-spline, a closed solid;
- "centerline": the B-spline through every station (the same curve as the IGES SPLINE);
- with end fittings (model/fittings.py), per fitting "fitting_start" / "fitting_end": a solid
  tube of the fitting's radius (a cylinder per straight leg, a torus piece for the bend, a
  ball at a sharp corner, fused), and "fitting_start_centerline" / "fitting_end_centerline":
  its centreline (lines and the arc) from the port to the outlet.
"""

from __future__ import annotations

import io

import numpy as np

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

from OCP.BRepAlgoAPI import BRepAlgoAPI_Fuse
from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder, BRepPrimAPI_MakeSphere, BRepPrimAPI_MakeTorus
from OCP.GC import GC_MakeArcOfCircle
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt, gp_Vec
from OCP.TopAbs import TopAbs_SOLID
from OCP.TopExp import TopExp_Explorer

from hoseline.io.occt import centerline_spline, quiet, start_circle
from hoseline.model.fittings import Fitting
from hoseline.model.mounts import Mount
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


def fitting_shapes(port: Mount, fitting: Fitting, radius: float) -> tuple[TopoDS_Shape, TopoDS_Shape]:
    """(the fitting's solid tube of `radius` mm, its centreline wire from the port to the outlet), in mm.

    Raises SweepError for a bend of centreline radius not above the tube radius (the torus would fold).
    """
    if 0.0 < fitting.bend_radius <= radius:
        raise SweepError(f"the fitting at the port {port.point.tolist()} mm bends with centreline radius "
                         f"{fitting.bend_radius:g} mm, not above its outer radius {radius:g} mm: the tube would fold onto "
                         "itself; give a larger bend_radius, or 0 for a sharp corner")
    outlet = fitting.outlet(port)
    pieces, edges, lines = [], [], []
    if fitting.bend_angle_deg == 0.0:
        lines.append((port.point, outlet.point))
    else:
        tangent = fitting.tangent_length
        vertex = port.point + fitting.length * port.direction
        before, after = vertex - tangent * port.direction, vertex + tangent * outlet.direction
        lines.append((port.point, before))
        if tangent > 0.0:
            bend = fitting.bend_direction(port)
            centre = before + fitting.bend_radius * bend
            axes = gp_Ax2(_point(centre), _direction(np.cross(port.direction, bend)), _direction(-bend))
            pieces.append(BRepPrimAPI_MakeTorus(axes, fitting.bend_radius, radius, fitting.bend_angle).Shape())
            arc = GC_MakeArcOfCircle(_point(before), gp_Vec(*map(float, port.direction)), _point(after)).Value()
            lines.append(arc)
        else:  # a sharp corner: the ball closes the gap between the two cylinders
            pieces.append(BRepPrimAPI_MakeSphere(_point(vertex), radius).Shape())
        lines.append((after, outlet.point))
    for item in lines:
        if not isinstance(item, tuple):  # the arc
            edges.append(BRepBuilderAPI_MakeEdge(item).Edge())
            continue
        start, end = item
        length = float(np.linalg.norm(end - start))
        if length > 1e-9:
            axis = gp_Ax2(_point(start), _direction(end - start))
            pieces.append(BRepPrimAPI_MakeCylinder(axis, radius, length).Shape())
            edges.append(BRepBuilderAPI_MakeEdge(_point(start), _point(end)).Edge())
    solid = pieces[0]
    for piece in pieces[1:]:
        solid = BRepAlgoAPI_Fuse(solid, piece).Shape()
    found = TopExp_Explorer(solid, TopAbs_SOLID)
    if not found.More() or not BRepCheck_Analyzer(solid).IsValid():
        raise SweepError(f"OpenCASCADE could not build the fitting at the port {port.point.tolist()} mm as a solid")
    wire = BRepBuilderAPI_MakeWire()
    for edge in edges:
        wire.Add(edge)
    return found.Current(), wire.Wire()


def _point(vector) -> gp_Pnt:
    return gp_Pnt(*map(float, vector))


def _direction(vector) -> gp_Dir:
    return gp_Dir(*map(float, vector))


def step_bytes(result: Result) -> bytes:
    """The STEP AP214 file's bytes: products "hose" (solid) and "centerline" (B-spline edge), mm, and per
    end fitting "fitting_<end>" (solid) and "fitting_<end>_centerline" (wire)."""
    quiet()
    solid, centreline = tube_solid(result)
    document = TDocStd_Document(TCollection_ExtendedString("hoseline"))
    shapes = XCAFDoc_DocumentTool.ShapeTool_s(document.Main())
    products = [(solid, "hose"), (centreline, "centerline")]
    problem = result.problem
    for name, port, fitting in problem.fittings.pieces() if problem.fittings else ():
        fitting_solid, fitting_wire = fitting_shapes(port, fitting, fitting.radius(problem.hose.outer_diameter))
        products += [(fitting_solid, f"fitting_{name}"), (fitting_wire, f"fitting_{name}_centerline")]
    for shape, name in products:
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
