"""Data files of a sweep: poses.csv (one row per pose), shapes.csv (every station of every pose), sweep.json,
envelope.stl (the swept envelope) and obstacle_<name>.stl for each obstacle made in code rather than read from a file.

Numbers are written as io/csv_numbers.py says (8 significant digits, round-off as 0).  The report
(HTML, PNG) is written by report/sweep_report.py, which puts these files beside it.
"""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import numpy as np

from hoseline.io.atomic import write_text
from hoseline.io.csv_numbers import cell, without_round_off
from hoseline.io.obstacle_mesh import write_stl
from hoseline.io.problem_file import problem_to_dict
from hoseline.io.results import _json, _plain
from hoseline.model.sweep import SweepProblem
from hoseline.procedures.sweep.envelope import Envelope
from hoseline.procedures.sweep.result import SweepResult

ENVELOPE_FILE = "envelope.stl"


def poses_csv(result: SweepResult) -> str:
    """One row per pose: stage, travel, the fitting tips and directions, clearance to each obstacle,
    bend radius, moments, reactions, clip loads, and per [contact] obstacle its force, smallest gap and
    length in contact (mm, N, N*mm; directions are unit vectors into the hose).  Reactions, clip loads and
    contact forces come as magnitudes (<name>_N, <name>_Nmm) and as world components (<name>_x_N, ...)."""
    columns = {"pose": np.arange(result.pose_count), "stage": [_stage(result, k) for k in range(result.pose_count)],
               "travel": without_round_off(result.sweep.travel)}
    for end in ("start", "end"):
        points = without_round_off(getattr(result, f"{end}_points"))
        directions = without_round_off(getattr(result, f"{end}_directions"))
        columns.update({f"{end}_{axis}_mm": points[:, i] for i, axis in enumerate("xyz")})
        columns.update({f"{end}_direction_{axis}": directions[:, i] for i, axis in enumerate("xyz")})
    for clearance in result.clearances:
        columns[f"clearance_{clearance.obstacle.name}_mm"] = without_round_off(clearance.distance)
        columns[f"clearance_{clearance.obstacle.name}_s_mm"] = without_round_off(clearance.s)
    columns["min_bend_radius_mm"] = without_round_off(result.min_bend_radius)
    columns["max_twisting_moment_Nmm"] = without_round_off(result.max_twisting_moment)
    columns["max_differential_torque_Nmm"] = without_round_off(result.max_differential_torque)
    columns["single_plane_offset_mm"] = without_round_off(result.single_plane_offset)
    for name in ("start_force", "start_moment", "end_force", "end_moment"):  # the mounts' reactions on the hose
        columns |= _vector_columns(name, getattr(result, name), "N" if name.endswith("force") else "Nmm")
    for j, clip in enumerate(result.sweep.problem.clips):  # each clip's load on the hose (and where it holds it)
        label = f"clip_{j + 1}"
        columns |= _vector_columns(f"{label}_force", result.clip_forces[:, j], "N")
        columns |= _vector_columns(f"{label}_moment", result.clip_moments[:, j], "Nmm")
        if clip.slides:
            columns[f"{label}_arc_length_mm"] = without_round_off(result.clip_arc_lengths[:, j])
    for contact in result.contacts:  # each [contact] obstacle's push on the hose, the smallest gap, the length touching
        label = f"contact_{contact.name}"
        columns |= _vector_columns(f"{label}_force", contact.total_force, "N")
        columns[f"{label}_gap_mm"] = without_round_off(contact.min_gap)
        columns[f"{label}_length_mm"] = without_round_off(contact.length_in_contact)
    if result.separation is not None:
        columns["free_roll_separation_mm"] = without_round_off(result.separation)
    columns["newton_iterations"] = result.iterations
    stream = io.StringIO()
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow(columns)
    for k in range(result.pose_count):
        writer.writerow(cell(values[k]) for values in columns.values())
    return stream.getvalue()


def _vector_columns(name: str, vectors: np.ndarray, unit: str) -> dict[str, np.ndarray]:
    """Columns of a vector per pose, (M, 3) in `unit`: its magnitude (<name>_<unit>), then its world
    components (<name>_x_<unit>, <name>_y_<unit>, <name>_z_<unit>), round-off relative to the largest of them all."""
    components = without_round_off(vectors)
    return {f"{name}_{unit}": without_round_off(np.linalg.norm(vectors, axis=1))} | {
        f"{name}_{axis}_{unit}": components[:, i] for i, axis in enumerate("xyz")}


def shapes_csv(result: SweepResult) -> str:
    """Every station of every pose: pose, s, x, y, z (mm, 8 significant digits; s per pose where a
    sliding clip moves the stations along the hose)."""
    s = without_round_off(result.s if result.station_arc_lengths is None else result.station_arc_lengths)
    centerlines = without_round_off(result.centerlines)
    rows = ["pose,s,x,y,z"]
    for k, line in enumerate(centerlines):
        s_pose = s if s.ndim == 1 else s[k]
        rows.extend(f"{k},{cell(length)},{cell(x)},{cell(y)},{cell(z)}" for length, (x, y, z) in zip(s_pose, line))
    return "\n".join(rows) + "\n"


def sweep_document(result: SweepResult, envelope: Envelope | None = None) -> dict:
    """What sweep.json holds: the problem, the obstacles (and their files), the run's figures, worst
    cases, snaps, events, stages, travel, and the envelope's grid when one was made."""
    written = obstacle_files(result.sweep)
    document = {
        "problem": problem_to_dict(result.sweep.problem),
        "bodies": {"start": result.sweep.start_body, "end": result.sweep.end_body},
        "obstacles": [{"name": o.name, "file": written.get(k, o.source), "clearance_mm": o.clearance, "body": o.body,
                       "triangles": len(o.faces)} for k, o in enumerate(result.sweep.obstacles)],
        "performance": result.performance(),
        "worst_cases": result.worst_cases(),
        "first_violation": {c.obstacle.name: c.first_violation for c in result.clearances},
        "snaps": [{"pose": s.pose, "travel": result.travel_label(s.pose), "jump_mm": s.jump, "events": s.events}
                  for s in result.snaps],
        "events": result.events,
        "stages": [{"name": s.name, "unit": s.unit, "first_pose": s.first, "poses": s.count}
                   for s in result.sweep.stages],
        "travel": without_round_off(result.sweep.travel),
        "assembly": result.assembly.summary(),
    }
    if result.contacts:
        bodies = {o.name: result.sweep.contact_body(j) for j, o in enumerate(result.sweep.problem.contact)}
        document["contact"] = [{"name": c.name, "kind": c.kind, "body": bodies.get(c.name),
                                "min_gap_mm": without_round_off(c.min_gap),
                                "total_force_N": without_round_off(c.total_force),
                                "length_in_contact_mm": without_round_off(c.length_in_contact)}
                               for c in result.contacts]
    if envelope is not None:
        document["envelope"] = {
            "file": ENVELOPE_FILE,
            "cell_mm": envelope.cell,
            "requested_cell_mm": envelope.requested_cell,
            "radius_mm": envelope.radius,
            "triangles": len(envelope.faces),
            "accuracy": "the surface is within about one cell of the exact union of the hose's tube over the poses "
                        "(of radius_mm: the hose's, or one cell when the hose is thinner)",
        }
    return _plain(document)


def write_sweep_data(result: SweepResult, folder: str | Path, envelope: Envelope | None = None) -> None:
    """Write poses.csv, shapes.csv, sweep.json, the envelope (if given) and the obstacles made in code
    into an existing folder (atomically, file by file)."""
    folder = Path(folder)
    write_text(folder / "poses.csv", poses_csv(result))
    write_text(folder / "shapes.csv", shapes_csv(result))
    if envelope is not None:
        write_stl(folder / ENVELOPE_FILE, envelope.vertices, envelope.faces)
    for k, name in obstacle_files(result.sweep).items():
        obstacle = result.sweep.obstacles[k]
        write_stl(folder / name, obstacle.vertices, obstacle.faces)
    write_text(folder / "sweep.json", _json(sweep_document(result, envelope)) + "\n")


def obstacle_files(sweep: SweepProblem) -> dict[int, str]:
    """File names for the obstacles not read from a file (no `source`), by obstacle index: obstacle_<name>.stl."""
    names: dict[int, str] = {}
    for k, obstacle in enumerate(sweep.obstacles):
        if obstacle.source:
            continue
        stem = re.sub(r"[^A-Za-z0-9_-]+", "_", obstacle.name).strip("_") or str(k)
        name = f"obstacle_{stem}.stl"
        names[k] = name if name not in names.values() else f"obstacle_{stem}_{k}.stl"
    return names


def _stage(result: SweepResult, k: int) -> str:
    return next(s.name for s in result.sweep.stages if s.first <= k < s.first + s.count)
