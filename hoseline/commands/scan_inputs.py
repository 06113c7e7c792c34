"""What compare and calibrate share: the problem, the scans, their twists, the placed model, the table.

Each helper ends the command with exit code 2 and one red line when its input is bad.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

from rich.table import Table

from hoseline.commands.common import BAD_INPUT, fail, read_input

SCANS_HELP = "point clouds of the hose in the problem's mounts: .ply, .stl or text x y z (.xyz, .csv, .txt), mm"
NOISE_HELP = ("judge by what the scan's own noise and the model's discretisation explain as well as by the limits "
              "(default), or by the limits alone")
TWIST_HELP = "twist of the end fitting for each scan, degrees (once per scan, or once for all; default: the problem's)"


def load_problem_file(path: Path):
    """The Problem of a problem file, or exit 2 with the reason."""
    from hoseline.io.problem_file import ProblemFileError, load_problem

    return read_input(load_problem, path, "problem file", (ProblemFileError,))


def load_scan(path: Path, what: str = "scan", min_points: int = 20):
    """The points of a scan file (mm); what: "scan" or "reference points", for the message."""
    from hoseline.io.scans import ScanFileError, read_scan

    return read_input(read_scan, path, what, (ScanFileError,), min_points)


def scan_twists(given: list[float] | None, count: int, problem) -> list[float]:
    """One twist per scan, degrees: as given, one for all, or the problem's."""
    if not given:
        return [problem.end_twist_deg] * count
    bad = [angle for angle in given if not math.isfinite(angle)]
    if bad:
        raise fail(f"--twist {bad[0]}: give a finite angle in degrees", BAD_INPUT)
    if len(given) == 1:
        return list(given) * count
    if len(given) != count:
        raise fail(f"--twist given {len(given)} times for {count} scans: give it once per scan or once for all", BAD_INPUT)
    return list(given)


def fitted(cloud, problem, path: Path):
    """The scan's fitted centreline; a cloud that is no hose, or not where the problem's hose can be, is bad input."""
    from hoseline.procedures.scans.centerline_fit import fit_centerline
    from hoseline.procedures.scans.cloud_checks import check_reach

    hose = problem.hose
    fittings = 0.0 if problem.fittings is None else problem.fittings.length_allowance
    try:
        check_reach(cloud, problem.start.point, problem.end.point, hose.length + hose.outer_radius + fittings)
        return fit_centerline(cloud, hose.outer_radius, start_hint=problem.start.point)
    except ValueError as exc:
        raise fail(f"scan {path}: {exc}", BAD_INPUT) from None


def placed(problem, twists: list[float]) -> dict:
    """The Problem placed at each distinct twist (degrees), as Results: scans at the same twist share one solve."""
    from hoseline.procedures.placement.sequence import solve

    return {angle: solve(replace(problem, end_twist_deg=angle)) for angle in dict.fromkeys(twists)}


def deviation_table(comparisons) -> Table:
    """The deviation of each scan Comparison as a Rich table."""
    table = Table(title="deviation of the scan centreline from the model (mm)")
    for column in ("scan", "twist", "stations", "mean", "RMS", "max", "at s", "limit", "noise allows", "verdict"):
        table.add_column(column, justify="right")
    for c in comparisons:
        d = c.deviation
        table.add_row(c.label, f"{c.result.problem.end_twist_deg:g}", str(d.distance.size), f"{d.mean:.3f}",
                      f"{d.rms:.3f}", f"{d.max:.3f}", f"{d.s_at_max:.1f}", f"{c.thresholds.mean:g}",
                      f"{c.noise_allowance:.3f}", c.verdict)
    return table
