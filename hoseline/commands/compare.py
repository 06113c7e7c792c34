"""`hoseline compare problem.toml scan.ply [more scans] -o out/ [--twist 180] [--check]`: the model against scans.

Exit codes as for `solve` (0 done, 2 bad input, 3 the solver failed), and with --check 5 when a
scan's deviation is above its thresholds.  On an error nothing is written.
"""

from __future__ import annotations

import math
from pathlib import Path

import typer
from rich.console import Console

from hoseline.commands.common import (BAD_INPUT, CHECK_FAILED, OUT_HELP, QUIET_HELP, compile_solver,
                                      errors_to_exit_codes, fail)
from hoseline.commands.scan_inputs import (NOISE_HELP, SCANS_HELP, TWIST_HELP, deviation_table, fitted,
                                           load_problem_file, load_scan, placed, scan_twists)


def compare_command(
    problem_file: Path = typer.Argument(..., help="TOML problem file (see README)"),
    scans: list[Path] = typer.Argument(..., help=SCANS_HELP),
    out: Path = typer.Option(..., "-o", "--out", help=OUT_HELP),
    twist: list[float] = typer.Option(None, "--twist", help=TWIST_HELP),
    max_mean: float = typer.Option(None, "--max-mean", help="mean deviation limit, mm (default: the thesis' 1 mm "
                                                             "untwisted, 6 mm twisted)"),
    max_deviation: float = typer.Option(None, "--max-deviation", help="largest deviation allowed, mm (default: none)"),
    reference_points: Path = typer.Option(None, "--reference-points",
                                          help="text file of points x y z (mm) whose distance to the model is listed"),
    check: bool = typer.Option(False, "--check", help=f"exit with {CHECK_FAILED} when a scan fails its limits, or "
                                                       "deviates by more than its own noise and the model's "
                                                       "discretisation explain"),
    noise_check: bool = typer.Option(True, "--noise-check/--limits-only", help=NOISE_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
) -> None:
    """Compare the placed model with scans: deviation table and plot, 3D overlay, scatter of repeated scans."""
    from hoseline.procedures.scans.deviation import Thresholds
    from hoseline.procedures.scans.validation import compare_scan
    from hoseline.report.validation import write_validation_report

    problem = load_problem_file(problem_file)
    twists = scan_twists(twist, len(scans), problem)
    max_mean, max_deviation = _limit(max_mean, "--max-mean"), _limit(max_deviation, "--max-deviation")
    clouds = [load_scan(path) for path in scans]
    references = None if reference_points is None else load_scan(reference_points, "reference points", min_points=1)
    with errors_to_exit_codes(out):
        compile_solver(quiet, problem)
        fits = [fitted(cloud, problem, path) for cloud, path in zip(clouds, scans)]
        results = placed(problem, twists)
        comparisons = []
        for path, cloud, angle, f in zip(scans, clouds, twists, fits):
            limits = Thresholds(Thresholds.thesis(angle).mean if max_mean is None else max_mean, max_deviation,
                                noise_check)
            comparisons.append(compare_scan(results[angle], cloud, path.stem, fit=f, thresholds=limits,
                                            reference_points=references))
        write_validation_report(out, comparisons, envelope=_envelope(comparisons, twists))
    if not quiet:
        Console().print(deviation_table(comparisons))
        Console().print(f"wrote {out / 'report.html'} and the data beside it")
    if check and not all(c.passed for c in comparisons):
        raise typer.Exit(CHECK_FAILED)


def _limit(value: float | None, option: str) -> float | None:
    """A deviation limit option (mm): None, or positive and finite (else exit 2)."""
    if value is not None and not (math.isfinite(value) and value > 0.0):
        raise fail(f"{option} {value}: give a positive limit in mm", BAD_INPUT)
    return value


def _envelope(comparisons, twists: list[float]):
    """Scatter envelope of the largest group of scans at one twist (None if no twist has two)."""
    from hoseline.procedures.scans.scatter import scatter_envelope

    groups: dict[float, list] = {}
    for comparison, angle in zip(comparisons, twists):
        groups.setdefault(angle, []).append(comparison)
    largest = max(groups.values(), key=len)
    return scatter_envelope([c.fit.points for c in largest]) if len(largest) > 1 else None
