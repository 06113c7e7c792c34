"""`hoseline calibrate problem.toml scan0.ply scan180.ply --twist 0 --twist 180 -o out/`: fit the hose to scans.

Exit codes as for `solve` (0 done, 2 bad input, 3 the solver failed).  On an error nothing is written.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import typer
from rich.console import Console
from rich.table import Table

from hoseline.commands.common import BAD_INPUT, OUT_HELP, QUIET_HELP, compile_solver, errors_to_exit_codes, fail
from hoseline.commands.scan_inputs import (SCANS_HELP, TWIST_HELP, deviation_table, fitted, load_problem_file,
                                           load_scan, placed, scan_twists)
from hoseline.procedures.scans.parameters import PARAMETERS


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
    from hoseline.io.problem_file import problem_to_toml
    from hoseline.procedures.scans.calibration import ScanCase, calibrate
    from hoseline.procedures.scans.validation import compare_scan
    from hoseline.report.validation import write_validation_report

    problem = load_problem_file(problem_file)
    twists = scan_twists(twist, len(scans), problem)
    names = [name.strip() for name in fit.split(",") if name.strip()]
    unknown = [name for name in names if name not in PARAMETERS]
    if unknown or not names:
        reason = f"unknown parameter {unknown[0]!r}" if unknown else "no parameter given"
        raise fail(f"--fit {fit!r}: {reason}; choose from {', '.join(PARAMETERS)}", BAD_INPUT)
    clouds = [load_scan(path) for path in scans]
    with errors_to_exit_codes(out):
        compile_solver(quiet)
        fits = [fitted(cloud, problem, path) for cloud, path in zip(clouds, scans)]
        calibration = calibrate(problem, [ScanCase(angle, f.points) for angle, f in zip(twists, fits)], names)
        calibrated = replace(problem, hose=calibration.hose)
        results = placed(calibrated, twists)
        comparisons = [compare_scan(results[angle], cloud, path.stem, fit=f)
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
        Console().print(deviation_table(comparisons))
        Console().print(f"wrote {out / 'report.html'} and {out / 'calibrated.toml'}")
