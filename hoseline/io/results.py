"""Write a placement result: centerline.csv for CAD and spreadsheets, result.json for everything else."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from hoseline.io.atomic import staged_directory, write_text
from hoseline.io.problem_file import problem_to_dict
from hoseline.procedures.placement.result import Result

STATION_UNITS = {
    "s": "mm",
    "centerline": "mm",
    "curvature": "1/mm",
    "twist_rate": "rad/mm",
    "bending_moment": "N*mm",
    "twisting_moment": "N*mm",
    "internal_moment": "N*mm",
    "internal_force": "N",
}
SEGMENT_UNITS = {"frames": "unit vectors: per segment [d1, d2, d3], d3 the tangent, at s = (i + 1/2) L / N"}


def write_results(result: Result, out_dir: str | Path) -> Path:
    """Write centerline.csv and result.json into `out_dir`, both or neither.

    centerline.csv: header s,x,y,z, one row per station from the start to the end fitting, mm.
    result.json: {"summary": result.summary(), "problem": the input in the problem-file
    format, "units": units of the arrays, "stations": {name: per-station values},
    "segments": {"frames": per-segment material frames}, "fittings": the two clamped fitting frames}.
    Non-finite numbers are written as null (JSON has no NaN).
    Returns out_dir.
    """
    out_dir = Path(out_dir)
    with staged_directory(out_dir) as staging:
        write_text(staging / "centerline.csv", centerline_csv(result))
        write_text(staging / "result.json", _json(result_document(result)) + "\n")
    return out_dir


def centerline_csv(result: Result) -> str:
    """The centreline as CSV text: s,x,y,z in mm."""
    rows = ["s,x,y,z"]
    for s, (x, y, z) in zip(result.s, result.centerline):
        rows.append(f"{s:.10g},{x:.10g},{y:.10g},{z:.10g}")
    return "\n".join(rows) + "\n"


def result_document(result: Result) -> dict:
    """Everything result.json holds, as plain JSON types."""
    stations = {name: getattr(result, name) for name in STATION_UNITS}
    return _plain(
        {
            "summary": result.summary(),
            "problem": problem_to_dict(result.problem),
            "units": {**STATION_UNITS, **SEGMENT_UNITS},
            "stations": stations,
            "segments": {"frames": result.frames},
            "fittings": {"start_frame": result.start_frame, "end_frame": result.end_frame},
        }
    )


def _json(value, indent: str = "") -> str:
    """JSON with one key per line and each list of numbers (a station, a vector) on one line."""
    inner = indent + "  "
    if isinstance(value, dict) and value:
        items = [f"{inner}{json.dumps(key)}: {_json(item, inner)}" for key, item in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + indent + "}"
    if isinstance(value, list) and value and isinstance(value[0], (list, dict)):
        return "[\n" + ",\n".join(inner + _json(item, inner) for item in value) + "\n" + indent + "]"
    return json.dumps(value)


def _plain(value):
    """Numpy arrays and scalars to lists and Python numbers; NaN and infinities to None."""
    if isinstance(value, dict):
        return {key: _plain(item) for key, item in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_plain(item) for item in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
