"""`hoseline solve problem.toml -o out/ [--export iges,step,...]`: place one hose, write its files."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console

from hoseline.commands.common import BAD_INPUT, OUT_HELP, QUIET_HELP, errors_to_exit_codes, fail, progress_bar, read_input
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
) -> None:
    """Place the hose of a problem file; write centerline.csv, result.json and the exports asked for."""
    from hoseline.io.atomic import staged_directory
    from hoseline.io.exports import write_exports
    from hoseline.io.problem_file import ProblemFileError, load_problem
    from hoseline.io.results import write_results
    from hoseline.procedures.placement.sequence import solve
    from hoseline.report.table import summary_table

    formats = export_formats(export)
    problem = read_input(load_problem, problem_file, "problem file", (ProblemFileError,))
    with errors_to_exit_codes(out):
        with progress_bar(quiet) as progress:
            result = solve(problem, progress=progress)
        with staged_directory(out) as staging:
            write_results(result, staging)
            exported = write_exports(result, staging, formats)
    if not quiet:
        Console().print(summary_table([result], [problem.name]))
        Console().print(f"wrote {out / 'centerline.csv'} and {out / 'result.json'}")
        print_exports(out, exported)


def export_formats(text: str) -> list[str]:
    """The --export list, or exit 2 naming the unknown format."""
    try:
        return parse_formats(text)
    except ValueError as exc:
        raise fail(f"--export {text}: {exc}", BAD_INPUT) from None


def print_exports(folder: Path, files) -> None:
    """One line per exported file (hoseline.io.exports.ExportedFile): path, size, time to make and write it."""
    for file in files:
        line = f"wrote {folder / file.name} ({file.size / 1024:.0f} KiB in {file.seconds:.2f} s)"
        Console().print(line, soft_wrap=True)
