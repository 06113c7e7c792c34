"""What the CAD readers and writers share on top of OpenCASCADE (the OCP bindings, package cadquery-ocp-novtk).

- quiet(): OpenCASCADE prints progress lines ("Total number of loaded entities ...") on
  stdout; this keeps only its failures.
- centerline_spline(): the hose centreline as a B-spline, the one curve that both the IGES
  (entity 126) and the STEP export carry.
- start_circle(): the hose's outer circle at the start fitting, the profile a CAD sweep needs.
"""

from __future__ import annotations

from OCP.collections import HArray1_double, HArray1_gp_Pnt
from OCP.Geom import Geom_BSplineCurve, Geom_Circle
from OCP.GeomAPI import GeomAPI_Interpolate
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt, gp_Vec
from OCP.Message import Message, Message_Gravity

from hoseline.procedures.placement.result import Result


def quiet() -> None:
    """Let OpenCASCADE's default messenger print failures only (it is process-wide; calling again is harmless)."""
    printers = Message.DefaultMessenger_s().Printers()
    for index in range(1, printers.Size() + 1):
        printers.Value(index).SetTraceLevel(Message_Gravity.Message_Fail)


def centerline_spline(result: Result) -> Geom_BSplineCurve:
    """Cubic B-spline through every station, parametrised by arc length s in mm.

    The end tangents are the fitting axes (the hose leaves the start fitting along its
    direction and arrives at the end fitting along the negative of its direction), so the
    curve meets the fittings as the clamped hose does.  It passes through the stations to
    rounding; between them it deviates from the solver's straight segments by at most
    about h^2 * curvature / 8 (h the segment length).
    """
    stations = result.centerline
    points = HArray1_gp_Pnt(1, len(stations))
    parameters = HArray1_double(1, len(stations))
    for index, (point, s) in enumerate(zip(stations, result.s), start=1):
        points.SetValue(index, gp_Pnt(*map(float, point)))
        parameters.SetValue(index, float(s))
    interpolation = GeomAPI_Interpolate(points, parameters, False, 1e-9)
    start_tangent = result.problem.start.direction
    end_tangent = -result.problem.end.direction
    interpolation.Load(gp_Vec(*map(float, start_tangent)), gp_Vec(*map(float, end_tangent)), False)
    interpolation.Perform()
    if not interpolation.IsDone():
        raise RuntimeError("OpenCASCADE could not interpolate the centreline (coincident stations?)")
    return interpolation.Curve()


def start_circle(result: Result) -> Geom_Circle:
    """The hose's outer circle (radius in mm) at the start fitting tip, in the plane normal to the start direction."""
    problem = result.problem
    axis = gp_Ax2(gp_Pnt(*map(float, problem.start.point)), gp_Dir(*map(float, problem.start.direction)))
    return Geom_Circle(axis, problem.hose.outer_radius)
