"""Read pose tables: the motion of a body as exported by suspension kinematics tools (CSV).

Format: one header line, then one row per pose, in the order of the sweep::

    jounce [mm], x, y, z, qw, qx, qy, qz
    -50.0, 0.0, 0.0, -50.0, 1.0, 0.0, 0.0, 0.0
    ...

- The first column is the travel (or time) the poses are plotted against; its header
  names it, with the unit in brackets if wanted ("jounce [mm]", "time [s]").
- x, y, z: the body's translation in mm; qw, qx, qy, qz: its rotation as a unit
  quaternion.  The columns are found by name, in any order, so a table may give the
  quaternion scalar first (qw, qx, qy, qz) or scalar last (qx, qy, qz, qw).
- Poses are relative to the design position, where the problem file gives the mounts:
  the identity (0, 0, 0, 1, 0, 0, 0) is the design position.
- Empty lines and lines starting with # are skipped.  Quaternions must have unit norm
  (within 1e-3; they are then normalised).  Translations lie within +-1e5 mm (100 m) and the
  travel within +-1e9 (model/limits.py).
"""

from __future__ import annotations

import csv
import io
import math
import re
from pathlib import Path

import numpy as np

from hoseline.model import limits
from hoseline.model.motion import BodyMotion, Pose, Stage, matrix_quaternion, quaternion_matrix

POSE_COLUMNS = ("x", "y", "z", "qw", "qx", "qy", "qz")
NORM_TOLERANCE = 1e-3


class PoseTableError(ValueError):
    """A pose table that cannot be read; the message names the file, line and column."""


def read_pose_table(path: str | Path, body: str) -> BodyMotion:
    """The motion of `body` from the pose table at `path` (see the module docstring).

    Raises PoseTableError naming the line and column of bad input; OSError if unreadable.
    """
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = exc.object[: exc.start].count(b"\n") + 1
        raise PoseTableError(f"{path} line {line}: not UTF-8 text; save the table as UTF-8 (or plain ASCII) CSV") from None
    rows = [(number, row) for number, row in enumerate(csv.reader(io.StringIO(text, newline="")), start=1)
            if row and any(cell.strip() for cell in row) and not row[0].lstrip().startswith("#")]
    if not rows:
        raise PoseTableError(f"{path}: empty; expected a header line such as 'travel [mm], {', '.join(POSE_COLUMNS)}'")
    header_line, header = rows[0]
    names = [cell.strip() for cell in header]
    columns = _columns(path, header_line, names)
    travel_name, unit = _name_and_unit(names[0])
    travel, poses = [], []
    for number, row in rows[1:]:
        if len(row) != len(names):
            raise PoseTableError(f"{path} line {number}: {len(row)} values, but the header has {len(names)} columns")
        values = [_number(path, number, name, cell) for name, cell in zip(names, row)]
        _in_range(path, number, names[0], values[0], limits.TRAVEL, "in its unit")
        for c in ("x", "y", "z"):
            _in_range(path, number, c, values[columns[c]], limits.COORDINATE_MM, "mm (100 m); give translations in mm")
        quaternion = np.array([values[columns[c]] for c in ("qw", "qx", "qy", "qz")])
        norm = float(np.linalg.norm(quaternion))
        if abs(norm - 1.0) > NORM_TOLERANCE:
            raise PoseTableError(
                f"{path} line {number}: quaternion (qw, qx, qy, qz) = ({', '.join(f'{q:g}' for q in quaternion)}) has "
                f"norm {norm:.4g}: give a unit quaternion (the design position is 1, 0, 0, 0)"
            )
        travel.append(values[0])
        poses.append(Pose(quaternion_matrix(quaternion), np.array([values[columns[c]] for c in ("x", "y", "z")])))
    if not poses:
        raise PoseTableError(f"{path}: a header but no poses; add one line per pose below the header")
    return BodyMotion(body, tuple(poses), np.array(travel), (Stage(travel_name, unit, 0, len(poses)),))


def _columns(path: Path, line: int, names: list[str]) -> dict[str, int]:
    """Column index of x, y, z, qw, qx, qy, qz; the first column is the travel."""
    lowered = [name.lower() for name in names]
    if lowered[0] in POSE_COLUMNS:
        raise PoseTableError(
            f"{path} line {line}: the first column is '{names[0]}', but it must be the travel or time the poses "
            f"are plotted against, e.g. 'jounce [mm]', followed by {', '.join(POSE_COLUMNS)}"
        )
    for name in set(lowered):
        if lowered.count(name) > 1:
            raise PoseTableError(f"{path} line {line}: column '{name}' appears {lowered.count(name)} times")
    missing = [c for c in POSE_COLUMNS if c not in lowered]
    unknown = [n for n, low in zip(names[1:], lowered[1:]) if low not in POSE_COLUMNS]
    if missing or unknown:
        detail = f"missing {', '.join(missing)}" if missing else ""
        detail += ("; " if missing and unknown else "") + (f"unknown {', '.join(unknown)}" if unknown else "")
        raise PoseTableError(
            f"{path} line {line}: header columns {detail}: expected a travel column, then x, y, z (mm) and the "
            "unit quaternion qw, qx, qy, qz (any order, e.g. scalar last: qx, qy, qz, qw)"
        )
    return {c: lowered.index(c) for c in POSE_COLUMNS}


def _name_and_unit(header: str) -> tuple[str, str]:
    """'jounce [mm]' -> ('jounce', 'mm'); 'time' -> ('time', '')."""
    match = re.fullmatch(r"\s*(.*?)\s*[\[(]\s*(.*?)\s*[\])]\s*", header)
    return (match.group(1), match.group(2)) if match else (header.strip(), "")


def _number(path: Path, line: int, column: str, cell: str) -> float:
    """A finite number from a cell, or an error naming the line and column."""
    try:
        value = float(cell)
    except ValueError:
        raise PoseTableError(f"{path} line {line}, column {column}: '{cell.strip()}' is not a number") from None
    if not math.isfinite(value):
        raise PoseTableError(f"{path} line {line}, column {column}: {cell.strip()} is not a finite number")
    return value


def _in_range(path: Path, line: int, column: str, value: float, largest: float, unit: str) -> None:
    """Refuse a value beyond +-largest, naming the line and column."""
    if abs(value) > largest:
        raise PoseTableError(f"{path} line {line}, column {column}: {value:g} is outside +-{largest:g} {unit}")


def pose_table_text(travel_header: str, travel, poses) -> str:
    """A pose table (scalar-first quaternions) that read_pose_table reads back.

    travel_header: e.g. "jounce [mm]".  travel: one value per pose.  poses: Pose objects.
    """
    lines = [", ".join((travel_header,) + POSE_COLUMNS)]
    for value, pose in zip(travel, poses):
        numbers = (value, *pose.position, *matrix_quaternion(pose.rotation))
        lines.append(", ".join(repr(float(v)) for v in numbers))
    return "\n".join(lines) + "\n"
