"""`hoseline compare`, `hoseline calibrate` and `hoseline validation-demo`: the model against scans.

    hoseline compare problem.toml scan.ply [more scans] -o out/ [--twist 180] [--check]
    hoseline calibrate problem.toml scan0.ply scan180.ply --twist 0 --twist 180 -o out/
    hoseline validation-demo -o out/validation

Registers on the Typer app of hoseline.cli (imported at the end of cli.py).  Exit codes as
for `solve` (0 done, 2 bad input, 3 the solver failed), and with --check 5 when a scan's
deviation is above its thresholds.  On an error nothing is written.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import typer
from rich.console import Console
from rich.table import Table

from hoseline.cli import BAD_INPUT, OUT_HELP, QUIET_HELP, _errors_to_exit_codes, _fail, _read_input, app
from hoseline.io.problem_file import ProblemFileError, load_problem, problem_to_toml
from hoseline.io.scans import ScanFileError, read_scan
from hoseline.model.problem import Problem
from hoseline.procedures.calibration import PARAMETERS, ScanCase, calibrate
from hoseline.procedures.centerline_fit import fit_centerline
from hoseline.procedures.deviation import Thresholds
from hoseline.procedures.placement import solve
from hoseline.procedures.result import Result
from hoseline.procedures.scatter import scatter_envelope
from hoseline.procedures.validation import Comparison, compare_scan
from hoseline.report.validation import write_validation_report
from hoseline.validation_demo import run_validation_demo

VALIDATION_FAILED = 5

SCANS_HELP = "point clouds of the hose in the problem's mounts: .ply, .stl or text x y z (.xyz, .csv, .txt), mm"
TWIST_HELP = "twist of the end fitting for each scan, degrees (once per scan, or once for all; default: the problem's)"


@app.command("compare")
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
    check: bool = typer.Option(False, "--check", help=f"exit with {VALIDATION_FAILED} when a scan fails its limits"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
) -> None:
    """Compare the placed model with scans: deviation table and plot, 3D overlay, scatter of repeated scans."""
    problem = _load_problem(problem_file)
    twists = _twists(twist, len(scans), problem)
    max_mean, max_deviation = _limit(max_mean, "--max-mean"), _limit(max_deviation, "--max-deviation")
    clouds = [_load_scan(path) for path in scans]
    references = None if reference_points is None else _load_scan(reference_points, "reference points", min_points=1)
    with _errors_to_exit_codes(out):
        fits = [_fitted(cloud, problem, path) for cloud, path in zip(clouds, scans)]
        placed = _placed(problem, twists)
        comparisons = []
        for path, cloud, angle, f in zip(scans, clouds, twists, fits):
            limits = Thresholds(Thresholds.thesis(angle).mean if max_mean is None else max_mean, max_deviation)
            comparisons.append(compare_scan(placed[angle], cloud, path.stem, fit=f, thresholds=limits,
                                            reference_points=references))
        write_validation_report(out, comparisons, envelope=_envelope(comparisons, twists))
    if not quiet:
        Console().print(_deviation_table(comparisons))
        Console().print(f"wrote {out / 'report.html'} and the data beside it")
    if check and not all(c.passed for c in comparisons):
        raise typer.Exit(VALIDATION_FAILED)


@app.command("calibrate")
def calibrate_command(
    problem_file: Path = typer.Argument(..., help="TOML problem file with the initial values (see README)"),
    scans: list[Path] = typer.Argument(..., help=SCANS_HELP),
    out: Path = typer.Option(..., "-o", "--out", help=OUT_HELP),
    twist: list[float] = typer.Option(None, "--twist", help=TWIST_HELP),
    fit: str = typer.Option("bending_stiffness,torsion_factor", "--fit",
                            help=f"comma-separated parameters to fit, from: {', '.join(PARAMETERS)}"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
) -> None:
    """Fit stiffness (and optionally weight, length) to scans at several twists; write the report and calibrated.toml."""
    problem = _load_problem(problem_file)
    twists = _twists(twist, len(scans), problem)
    names = [name.strip() for name in fit.split(",") if name.strip()]
    unknown = [name for name in names if name not in PARAMETERS]
    if unknown or not names:
        reason = f"unknown parameter {unknown[0]!r}" if unknown else "no parameter given"
        raise _fail(f"--fit {fit!r}: {reason}; choose from {', '.join(PARAMETERS)}", BAD_INPUT)
    clouds = [_load_scan(path) for path in scans]
    with _errors_to_exit_codes(out):
        fits = [_fitted(cloud, problem, path) for cloud, path in zip(clouds, scans)]
        calibration = calibrate(problem, [ScanCase(angle, f.points) for angle, f in zip(twists, fits)], names)
        calibrated = replace(problem, hose=calibration.hose)
        placed = _placed(calibrated, twists)
        comparisons = [compare_scan(placed[angle], cloud, path.stem, fit=f)
                       for path, cloud, angle, f in zip(scans, clouds, twists, fits)]
        write_validation_report(out, comparisons, calibration=calibration,
                                extra_files={"calibrated.toml": problem_to_toml(calibrated)})
    if not quiet:
        table = Table(title="calibration")
        for column in ("parameter", "initial", "fitted", "± 1 sigma", "identified"):
            table.add_column(column)
        for p in calibration.parameters:
            table.add_row(p.name, f"{p.initial:.6g}", f"{p.value:.6g}", "n/a" if p.std is None else f"{p.std:.3g}",
                          "yes" if p.identifiable else "NO")
        Console().print(table)
        for note in calibration.notes:
            Console().print(f"note: {note}")
        Console().print(_deviation_table(comparisons))
        Console().print(f"wrote {out / 'report.html'} and {out / 'calibrated.toml'}")


@app.command("validation-demo")
def validation_demo_command(
    out: Path = typer.Option(Path("out/validation"), "-o", "--out", help=OUT_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
) -> None:
    """Synthetic scans of the thesis brake hose: compare, calibrate, scatter, and the stiffener model's twist path."""
    with _errors_to_exit_codes(out):
        outcome = run_validation_demo(out)
    if not quiet:
        Console().print(_deviation_table(outcome.comparisons))
        for p in outcome.calibration.parameters:
            Console().print(f"{p.name}: {p.initial:.6g} -> {p.value:.6g}" + (f" ± {p.std:.3g}" if p.std else ""))
        for path in outcome.twist_paths:
            verdict = "smooth" if path.smooth else f"NOT smooth: {path.jumps or path.failure}"
            Console().print(f"{path.label}: {verdict}")
        Console().print(f"wrote {out}/ (scans/, problem_*.toml, report/)")


def _load_problem(path: Path) -> Problem:
    return _read_input(load_problem, path, "problem file", (ProblemFileError,))


def _load_scan(path: Path, what: str = "scan", min_points: int = 20):
    """The points of a scan file (mm); what: "scan" or "reference points", for the message."""
    return _read_input(read_scan, path, what, (ScanFileError,), min_points)


def _twists(given: list[float] | None, count: int, problem: Problem) -> list[float]:
    """One twist per scan, degrees: as given, one for all, or the problem's."""
    if not given:
        return [problem.end_twist_deg] * count
    bad = [angle for angle in given if not math.isfinite(angle)]
    if bad:
        raise _fail(f"--twist {bad[0]}: give a finite angle in degrees", BAD_INPUT)
    if len(given) == 1:
        return list(given) * count
    if len(given) != count:
        raise _fail(f"--twist given {len(given)} times for {count} scans: give it once per scan or once for all", BAD_INPUT)
    return list(given)


def _fitted(cloud, problem: Problem, path: Path):
    """The scan's fitted centreline; a cloud that is no hose is bad input."""
    try:
        return fit_centerline(cloud, problem.hose.outer_radius, start_hint=problem.start.point)
    except ValueError as exc:
        raise _fail(f"scan {path}: {exc}", BAD_INPUT) from None


def _limit(value: float | None, option: str) -> float | None:
    """A deviation limit option (mm): None, or positive and finite (else exit 2)."""
    if value is not None and not (math.isfinite(value) and value > 0.0):
        raise _fail(f"{option} {value}: give a positive limit in mm", BAD_INPUT)
    return value


def _placed(problem: Problem, twists: list[float]) -> dict[float, Result]:
    """The problem placed at each distinct twist (degrees): scans at the same twist share one solve."""
    return {angle: solve(replace(problem, end_twist_deg=angle)) for angle in dict.fromkeys(twists)}


def _envelope(comparisons: list[Comparison], twists: list[float]):
    """Scatter envelope of the largest group of scans at one twist (None if no twist has two)."""
    groups: dict[float, list[Comparison]] = {}
    for comparison, angle in zip(comparisons, twists):
        groups.setdefault(angle, []).append(comparison)
    largest = max(groups.values(), key=len)
    return scatter_envelope([c.fit.points for c in largest]) if len(largest) > 1 else None


def _deviation_table(comparisons: list[Comparison]) -> Table:
    table = Table(title="deviation of the scan centreline from the model (mm)")
    for column in ("scan", "twist", "stations", "mean", "RMS", "max", "at s", "limit", "verdict"):
        table.add_column(column, justify="right")
    for c in comparisons:
        d = c.deviation
        table.add_row(c.label, f"{c.result.problem.end_twist_deg:g}", str(d.distance.size), f"{d.mean:.3f}",
                      f"{d.rms:.3f}", f"{d.max:.3f}", f"{d.s_at_max:.1f}", f"{c.thresholds.mean:g}",
                      "PASS" if c.passed else "FAIL")
    return table
