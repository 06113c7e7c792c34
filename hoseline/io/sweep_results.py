"""Data files of a sweep: poses.csv (one row per pose), shapes.csv (every station of every pose), sweep.json.

The report (HTML, PNG) and the swept envelope (STL) are written by report/sweep_report.py,
which puts these files beside them.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import numpy as np

from hoseline.io.atomic import write_text
from hoseline.io.problem_file import problem_to_dict
from hoseline.io.results import _json, _plain
from hoseline.procedures.sweep.result import SweepResult


def poses_csv(result: SweepResult) -> str:
    """One row per pose: stage, travel, clearance to each obstacle, bend radius, moments, reactions (mm, N, N*mm)."""
    columns = {"pose": np.arange(result.pose_count), "stage": [_stage(result, k) for k in range(result.pose_count)],
               "travel": result.sweep.travel}
    for clearance in result.clearances:
        columns[f"clearance_{clearance.obstacle.name}_mm"] = clearance.distance
        columns[f"clearance_{clearance.obstacle.name}_s_mm"] = clearance.s
    columns["min_bend_radius_mm"] = result.min_bend_radius
    columns["max_twisting_moment_Nmm"] = result.max_twisting_moment
    columns["max_differential_torque_Nmm"] = result.max_differential_torque
    columns["single_plane_offset_mm"] = result.single_plane_offset
    for name in ("start_force", "start_moment", "end_force", "end_moment"):
        unit = "N" if name.endswith("force") else "Nmm"
        columns[f"{name}_{unit}"] = np.linalg.norm(getattr(result, name), axis=1)
    if result.separation is not None:
        columns["free_roll_separation_mm"] = result.separation
    columns["newton_iterations"] = result.iterations
    stream = io.StringIO()
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow(columns)
    for k in range(result.pose_count):
        writer.writerow(_cell(values[k]) for values in columns.values())
    return stream.getvalue()


def shapes_csv(result: SweepResult) -> str:
    """Every station of every pose: pose, s, x, y, z (mm)."""
    rows = ["pose,s,x,y,z"]
    for k, line in enumerate(result.centerlines):
        rows.extend(f"{k},{s:.6g},{x:.8g},{y:.8g},{z:.8g}" for s, (x, y, z) in zip(result.s, line))
    return "\n".join(rows) + "\n"


def sweep_document(result: SweepResult) -> dict:
    """What sweep.json holds: the problem, the run's figures, worst cases, snaps, events, per-pose values."""
    return _plain({
        "problem": problem_to_dict(result.sweep.problem),
        "bodies": {"start": result.sweep.start_body, "end": result.sweep.end_body},
        "obstacles": [{"name": o.name, "file": o.source, "clearance_mm": o.clearance, "body": o.body,
                       "triangles": len(o.faces)} for o in result.sweep.obstacles],
        "performance": result.performance(),
        "worst_cases": result.worst_cases(),
        "first_violation": {c.obstacle.name: c.first_violation for c in result.clearances},
        "snaps": [{"pose": s.pose, "travel": result.travel_label(s.pose), "jump_mm": s.jump, "events": s.events}
                  for s in result.snaps],
        "events": result.events,
        "stages": [{"name": s.name, "unit": s.unit, "first_pose": s.first, "poses": s.count}
                   for s in result.sweep.stages],
        "travel": result.sweep.travel,
        "assembly": result.assembly.summary(),
    })


def write_sweep_data(result: SweepResult, folder: str | Path) -> None:
    """Write poses.csv, shapes.csv and sweep.json into an existing folder (atomically, file by file)."""
    folder = Path(folder)
    write_text(folder / "poses.csv", poses_csv(result))
    write_text(folder / "shapes.csv", shapes_csv(result))
    write_text(folder / "sweep.json", _json(sweep_document(result)) + "\n")


def _stage(result: SweepResult, k: int) -> str:
    return next(s.name for s in result.sweep.stages if s.first <= k < s.first + s.count)


def _cell(value) -> str:
    if isinstance(value, (float, np.floating)):
        return "" if not np.isfinite(value) else f"{value:.8g}"
    return str(value)
