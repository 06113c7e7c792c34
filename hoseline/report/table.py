"""The summary an engineer reads first: one Rich table, one column per result."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from rich.table import Table

from hoseline.procedures.placement.result import Result


def _number(value: float | None, digits: int = 4) -> str:
    """`digits` significant digits; n/a for None; no minus sign on zero."""
    return "n/a" if value is None else f"{value + 0.0:.{digits}g}"


def _stability(result: Result) -> str:
    """The margin and its verdict; n/a when it was not computed."""
    if result.stable is None:
        return "n/a"
    return f"{_number(result.stability_margin)} ({'stable' if result.stable else 'UNSTABLE'})"


def _fixed(value: float | None, decimals: int = 2) -> str:
    """`decimals` digits after the point (mm, degrees); n/a for None; no minus sign on zero."""
    return "n/a" if value is None else f"{round(value, decimals) + 0.0:.{decimals}f}"


def _uniqueness(result: Result) -> str:
    """yes, not checked with why, or no with what else the hose can do."""
    if result.unique is None:
        return f"not checked: {result.unchecked}"
    if result.unique:
        return "yes"
    if not result.other_equilibria:
        return "no: neutral (a family of shapes)"
    same = sum(other.same_clamps for other in result.other_equilibria)
    parts = [f"{same} other shape(s) of the same assembly"] if same else []
    if len(result.other_equilibria) > same:
        parts.append(f"{len(result.other_equilibria) - same} with the fitting clocked differently")
    return "no: " + ", ".join(parts)


# (quantity, unit, how to read it off a Result)
ROWS: tuple[tuple[str, str, Callable[[Result], str]], ...] = (
    ("end twist", "deg", lambda r: _fixed(r.problem.end_twist_deg, 1)),
    ("lock angle", "deg", lambda r: _fixed(r.lock_angle_deg)),
    ("elastic energy", "N*mm", lambda r: _number(r.elastic_energy)),
    ("gravity energy", "N*mm", lambda r: _number(r.gravity_energy)),
    ("stability margin", "N/rad^2", _stability),
    ("unique shape", "", lambda r: _uniqueness(r)),
    ("forks on the path", "", lambda r: str(len(r.path_forks))),
    ("min inside bend radius", "mm", lambda r: _fixed(r.min_bend_radius)),
    ("bend radius margin", "mm", lambda r: _fixed(r.bend_radius_margin)),
    ("single-plane offset", "mm", lambda r: _fixed(r.single_plane_offset)),
    ("max twisting moment", "N*mm", lambda r: _number(r.max_twisting_moment)),
    ("max bending moment", "N*mm", lambda r: _number(float(r.bending_moment.max()))),
    ("iterations / steps", "", lambda r: f"{r.iterations} / {r.steps}"),
    ("residual", "", lambda r: _number(r.residual, 2)),
    ("discretisation error", "mm", lambda r: _number(r.discretisation_error, 2)),
    ("time", "s", lambda r: _fixed(r.wall_time)),
)


def summary_table(results: Sequence[Result], labels: Sequence[str], title: str = "hoseline") -> Table:
    """A table with one row per quantity and one column per result (labels are the column heads)."""
    table = Table(title=title)
    table.add_column("quantity")
    table.add_column("unit")
    for label in labels:
        table.add_column(label, justify="right")
    for name, unit, read in ROWS:
        table.add_row(name, unit, *(read(result) for result in results))
    for index in range(max((len(result.clips) for result in results), default=0)):  # per clip: its load on the hose
        clips = [result.clips[index] if index < len(result.clips) else None for result in results]
        table.add_row(f"clip {index + 1} force", "N",
                      *("" if clip is None else f"{_number(float(np.linalg.norm(clip.force)))} ({clip.kind})" for clip in clips))
        table.add_row(f"clip {index + 1} moment", "N*mm",
                      *("" if clip is None else _number(float(np.linalg.norm(clip.moment))) for clip in clips))
        table.add_row(f"clip {index + 1} axial torque", "N*mm",
                      *("" if clip is None else _number(clip.axial_torque) for clip in clips))
        if any(clip is not None and clip.locked_roll_deg is not None for clip in clips):  # fixed clips
            table.add_row(f"clip {index + 1} locked roll", "deg",
                          *("" if clip is None or clip.locked_roll_deg is None else _fixed(clip.locked_roll_deg)
                            for clip in clips))
    return table
