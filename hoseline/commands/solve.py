"""`hoseline solve problem.toml -o out/ [--export iges,step,...]`: place one hose, write its files."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import typer
from rich.console import Console

from hoseline.commands.common import (BAD_INPUT, OUT_HELP, QUIET_HELP, compile_solver, errors_to_exit_codes, fail,
                                      progress_bar, read_input)
from hoseline.io.export_names import FILE_NAMES, parse_formats

EXPORT_HELP = (
    "comma-separated CAD and model files to write beside the results: "
    + ", ".join(f"{name} ({file})" for name, file in FILE_NAMES.items())
    + "; all or none"
)


def solve_command(
    problem_file: Path = typer.Argument(..., help="TOML problem file (see README)"),
    out: Path = typer.Option(..., "-o", "--out", help=OUT_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
    export: str = typer.Option("none", "--export", "-e", help=EXPORT_HELP),
    accuracy: str = typer.Option(None, "--accuracy", help="largest station error wanted, mm (e.g. 0.01mm): the "
                                                          "segment count is raised until the estimate meets it"),
) -> None:
    """Place the hose of a problem file; write centerline.csv, result.json and the exports asked for."""
    from hoseline.io.atomic import staged_directory
    from hoseline.io.exports import write_exports
    from hoseline.io.problem_file import ProblemFileError, load_problem
    from hoseline.io.results import write_results
    from hoseline.procedures.placement.refinement import solve_to_accuracy
    from hoseline.procedures.placement.sequence import solve
    from hoseline.report.table import summary_table

    formats = export_formats(export)
    wanted = None if accuracy is None else accuracy_mm(accuracy)
    problem = read_input(load_problem, problem_file, "problem file", (ProblemFileError,))
    with errors_to_exit_codes(out):
        compile_solver(quiet)
        with progress_bar(quiet) as progress:
            if wanted is None:
                result = solve(problem, progress=progress)
            else:
                result = solve_to_accuracy(problem, wanted, progress=progress)
        with staged_directory(out) as staging:
            write_results(result, staging)
            exported = write_exports(result, staging, formats)
    if not quiet:
        Console().print(summary_table([result], [problem.name]))
        if problem.fittings is not None:
            print_lengths(problem)
        print_contacts(result)
        Console().print(f"wrote {out / 'centerline.csv'} and {out / 'result.json'}")
        print_exports(out, exported)


def accuracy_mm(text: str) -> float:
    """The --accuracy value in mm ("0.01mm" or "0.01"), or exit 2 saying what to give."""
    number = text.strip().lower().removesuffix("mm").strip()
    try:
        value = float(number)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0.0):
        raise fail(f"--accuracy {text!r}: give a positive length in mm, e.g. 0.01mm", BAD_INPUT)
    return value


def export_formats(text: str) -> list[str]:
    """The --export list, or exit 2 naming the unknown format."""
    try:
        return parse_formats(text)
    except ValueError as exc:
        raise fail(f"--export {text}: {exc}", BAD_INPUT) from None


def print_lengths(problem) -> None:
    """The free (cut) length and the catalogue's overall length of a hose with end fittings, mm."""
    fittings = problem.fittings
    parts = " + ".join(f"{fitting.length_allowance:.2f} ({name})" for name, _, fitting in fittings.pieces())
    Console().print(f"free length {problem.hose.length:.2f} mm, overall length "
                    f"{fittings.overall_length(problem.hose.length):.2f} mm (the fittings add {parts} mm)")


def print_contacts(result) -> None:
    """One line per obstacle of a placement with contact: length in contact (mm), total force (N), smallest gap (mm)."""
    for contact in result.contacts:
        what = "itself" if contact.name == "self" else f"{contact.name!r} ({contact.kind})"
        Console().print(f"contact with {what}: {contact.length_in_contact:.1f} mm of hose at {contact.gap.size} "
                        f"point(s), force {float(np.linalg.norm(contact.total_force)):.4g} N, smallest gap "
                        f"{contact.min_gap:.3g} mm")


def print_exports(folder: Path, files) -> None:
    """One line per exported file (hoseline.io.exports.ExportedFile): path, size, time to make and write it."""
    for file in files:
        line = f"wrote {folder / file.name} ({file.size / 1024:.0f} KiB in {file.seconds:.2f} s)"
        Console().print(line, soft_wrap=True)
