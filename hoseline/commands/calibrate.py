"""`hoseline calibrate problem.toml s0.ply s180.ply --twist 0 --twist 180 -o out/ [--check]`: fit the hose to scans.

Exit codes as for `solve` (0 done, 2 bad input, 3 the solver failed), and with --check 5 when
the calibrated model still misses a scan's limits (as `compare --check`).  A failed fit (a
parameter at its bound, limits missed, a flipped twist sign, a parameter confounded with a
fixed one) is said on stderr as `warning:` lines and in the report.  On an error nothing is written.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import typer
from rich.console import Console
from rich.table import Table
from rich.text import Text

from hoseline.commands.common import (BAD_INPUT, CHECK_FAILED, OUT_HELP, QUIET_HELP, compile_solver,
                                      errors_to_exit_codes, fail)
from hoseline.commands.compare import _limit
from hoseline.commands.scan_inputs import (NOISE_HELP, SCANS_HELP, TWIST_HELP, deviation_table, fitted,
                                           load_problem_file, load_scan, placed, scan_twists)
from hoseline.procedures.scans.parameters import PARAMETERS


def calibrate_command(
    problem_file: Path = typer.Argument(..., help="TOML problem file with the initial values (see README)"),
    scans: list[Path] = typer.Argument(..., help=SCANS_HELP),
    out: Path = typer.Option(..., "-o", "--out", help=OUT_HELP),
    twist: list[float] = typer.Option(None, "--twist", help=TWIST_HELP),
    fit: str = typer.Option("bending_stiffness,torsion_factor", "--fit",
                            help=f"comma-separated parameters to fit, from: {', '.join(PARAMETERS)}"),
    max_mean: float = typer.Option(None, "--max-mean", help="mean deviation limit, mm (default: the thesis' 1 mm "
                                                             "untwisted, 6 mm twisted)"),
    max_deviation: float = typer.Option(None, "--max-deviation", help="largest deviation allowed, mm (default: none)"),
    check: bool = typer.Option(False, "--check",
                               help=f"exit with {CHECK_FAILED} when the calibrated model misses a scan's limits, "
                                    "or deviates by more than the scan's noise and the discretisation explain"),
    noise_check: bool = typer.Option(True, "--noise-check/--limits-only", help=NOISE_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
) -> None:
    """Fit stiffness (and optionally weight, length) to scans at several twists; write the report and calibrated.toml.

    Units: mm, degrees."""
    from hoseline.io.problem_file import problem_to_toml
    from hoseline.procedures.scans.calibration import ScanCase, calibrate, identifiable_parameters
    from hoseline.procedures.scans.deviation import Thresholds
    from hoseline.procedures.scans.validation import compare_scan
    from hoseline.report.validation import write_validation_report

    problem = load_problem_file(problem_file)
    poisson_ratio = _poisson_ratio(problem_file)
    twists = scan_twists(twist, len(scans), problem)
    max_mean, max_deviation = _limit(max_mean, "--max-mean"), _limit(max_deviation, "--max-deviation")
    limits = [Thresholds(Thresholds.thesis(angle).mean if max_mean is None else max_mean, max_deviation, noise_check)
              for angle in twists]
    names = [name.strip() for name in fit.split(",") if name.strip()]
    unknown = [name for name in names if name not in PARAMETERS]
    if unknown or not names:
        reason = f"unknown parameter {unknown[0]!r}" if unknown else "no parameter given"
        raise fail(f"--fit {fit!r}: {reason}; choose from {', '.join(PARAMETERS)}", BAD_INPUT)
    try:  # a parameter the problem cannot start from (a braid's, without [hose.braid])
        identifiable_parameters(problem, names)
    except ValueError as exc:
        raise fail(f"--fit {fit!r}: {exc}", BAD_INPUT) from None
    clouds = [load_scan(path) for path in scans]
    with errors_to_exit_codes(out):
        compile_solver(quiet, problem)
        fits = [fitted(cloud, problem, path) for cloud, path in zip(clouds, scans)]
        calibration = calibrate(problem, [ScanCase(angle, f.points) for angle, f in zip(twists, fits)], names,
                                poisson_ratio=poisson_ratio, thresholds=limits)
        calibrated = replace(problem, hose=calibration.hose)
        results = placed(calibrated, twists)
        comparisons = [compare_scan(results[angle], cloud, path.stem, fit=f, thresholds=limit)
                       for path, cloud, angle, f, limit in zip(scans, clouds, twists, fits, limits)]
        write_validation_report(out, comparisons, calibration=calibration,
                                extra_files={"calibrated.toml": problem_to_toml(calibrated, poisson_ratio)})
    errors = Console(stderr=True)
    for warning in calibration.warnings:  # said even when quiet: the fit failed
        errors.print(Text(f"warning: {warning}", style="bold yellow"), soft_wrap=True)
    if not quiet:
        table = Table(title=f"calibration (torsion factor: GJ over EI / (1 + {poisson_ratio:g}); 1 sigma from "
                            "the scans' scatter and the model's discretisation)")
        for column in ("parameter", "initial", "fitted", "± 1 sigma", "scatter", "discret.", "identified"):
            table.add_column(column)
        for p in calibration.parameters:
            table.add_row(p.name, f"{p.initial:.6g}", f"{p.value:.6g}", *(_sigma(v) for v in (
                p.std, p.std_scatter, p.std_discretisation)), "yes" if p.identifiable else "NO")
        Console().print(table)
        for note in calibration.notes:
            Console().print(f"note: {note}", soft_wrap=True)
        Console().print(deviation_table(comparisons))
        Console().print(f"wrote {out / 'report.html'} and {out / 'calibrated.toml'}")
    if check and not all(c.passed for c in comparisons):
        raise typer.Exit(CHECK_FAILED)


def _poisson_ratio(problem_file: Path) -> float:
    """The problem file's hose.poisson_ratio (the torsion factor's nu), default 0.5; the file is already validated."""
    from hoseline.io.problem_file import ProblemFileError, read_toml
    from hoseline.model.hose import DEFAULT_POISSON_RATIO

    hose = read_toml(problem_file, ProblemFileError).get("hose", {})
    return float(hose.get("poisson_ratio", DEFAULT_POISSON_RATIO))


def _sigma(value: float | None) -> str:
    """A standard uncertainty for the table, n/a when there is none."""
    return "n/a" if value is None else f"{value:.3g}"
