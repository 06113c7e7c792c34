"""The hose shape as IGES in the thesis' form (Thomas 2004, appendix D), ready for a CAD sweep.

Entities, all built and written by OpenCASCADE's IGES writer, unit mm, with labels:
- 116 points CM1..CMn: the centre of every segment (the thesis' centre-of-mass markers);
- 106 form 12 copious data (a polyline) "POLYLINE": from the start fitting tip through
  the segment centres to the end fitting tip;
- 100 circle "PROFILE": the hose's outer radius, centred on the start tip on the plane
  normal to the hose there, placed in space by a 124 transformation matrix;
- 126 B-spline curve "SPLINE": the smooth centreline through every station;
- with end fittings (model/fittings.py), one more 106 form 12 polyline per fitting, "FITSTART"
  and "FITEND": its centreline from the port to the outlet (the bend sampled).

In CATIA: Rib (or Sweep) with PROFILE as the profile and POLYLINE or SPLINE as the centre
curve, option 'keep angle', gives the hose as a solid.
"""

from __future__ import annotations

import io
import math

import numpy as np
from OCP.collections import HArray1_double
from OCP.Geom import Geom_CartesianPoint
from OCP.GeomToIGES import GeomToIGES_GeomCurve, GeomToIGES_GeomPoint
from OCP.gp import gp_Pnt
from OCP.IGESControl import IGESControl_Writer
from OCP.IGESGeom import IGESGeom_CopiousData
from OCP.TCollection import TCollection_HAsciiString

from hoseline.io.occt import centerline_spline, quiet, start_circle
from hoseline.procedures.placement.result import Result

XYZ_TRIPLES = 2  # copious data type: (x, y, z) per point


def iges_bytes(result: Result, file_name: str = "hose.igs") -> bytes:
    """The IGES file's bytes: points, polyline, profile circle and spline of the solved hose (mm).

    file_name: recorded in the file's global section.
    """
    quiet()
    writer = IGESControl_Writer("MM", 0)
    header = writer.Model().GlobalSection()
    header.SetFileName(TCollection_HAsciiString(file_name))
    header.SetAuthorName(TCollection_HAsciiString("hoseline"))
    header.SetSendName(TCollection_HAsciiString(result.problem.name))
    writer.Model().SetGlobalSection(header)

    stations = result.centerline
    centres = 0.5 * (stations[1:] + stations[:-1])
    points = GeomToIGES_GeomPoint()
    points.SetModel(writer.Model())
    for number, centre in enumerate(centres, start=1):
        entity = points.TransferPoint(Geom_CartesianPoint(gp_Pnt(*map(float, centre))))
        _add(writer, entity, f"CM{number}")

    _add(writer, _polyline(np.vstack([stations[:1], centres, stations[-1:]])), "POLYLINE")
    fittings = result.problem.fittings
    for name, port, fitting in fittings.pieces() if fittings else ():
        _add(writer, _polyline(fitting.centreline(port)), "FITSTART" if name == "start" else "FITEND")

    curves = GeomToIGES_GeomCurve()
    curves.SetModel(writer.Model())
    _add(writer, curves.TransferCurve(start_circle(result), 0.0, 2.0 * math.pi), "PROFILE")
    spline = centerline_spline(result)
    _add(writer, curves.TransferCurve(spline, spline.FirstParameter(), spline.LastParameter()), "SPLINE")

    writer.ComputeModel()
    stream = io.BytesIO()
    if not writer.Write(stream):
        raise RuntimeError("OpenCASCADE could not write the IGES model")
    return stream.getvalue()


def _polyline(path: np.ndarray) -> IGESGeom_CopiousData:
    """A 106 form 12 polyline through the (K, 3) points `path` (mm)."""
    coordinates = HArray1_double(1, path.size)
    for index, value in enumerate(path.ravel(), start=1):
        coordinates.SetValue(index, float(value))
    polyline = IGESGeom_CopiousData()
    polyline.Init(XYZ_TRIPLES, 0.0, coordinates)
    polyline.SetPolyline(True)  # form 12: the points joined by straight lines
    return polyline


def _add(writer: IGESControl_Writer, entity, label: str) -> None:
    """Label an entity (8 characters at most) and add it to the model."""
    entity.SetLabel(TCollection_HAsciiString(label))
    writer.AddEntity(entity)
