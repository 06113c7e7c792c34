"""`hoseline sweep sweep.toml -o out/` (or `--demo`): the hose through the motion of its mounts, and the report.

Exit codes as for `solve`: 0 done, 2 bad input (sweep file, pose tables, meshes, paths), 3 the solver
failed.  On an error nothing is written; otherwise all files appear together.
"""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console
from rich.table import Table

from hoseline.commands.common import (BAD_INPUT, OUT_HELP, QUIET_HELP, compile_solver, errors_to_exit_codes, fail,
                                      progress_bar, read_input)


def sweep_command(
    sweep_file: Path = typer.Argument(None, help="TOML sweep file: a problem file with [\\[bodies]] and [\\[obstacles]] "
                                                 "(see docs/sweep.md)"),
    out: Path = typer.Option(..., "-o", "--out", help=OUT_HELP),
    demo: bool = typer.Option(False, "--demo", help="run the built-in demo (thesis hose, steer and jounce, a strut)"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
) -> None:
    """Carry the hose through the motion of its mounts; write report.html, PNGs, envelope.stl and the numbers."""
    from hoseline.io.sweep_file import SweepFileError, load_sweep
    from hoseline.procedures.sweep.quasi_static import run_sweep
    from hoseline.report.sweep_report import write_sweep_report

    if (sweep_file is None) == (not demo):
        raise fail("give either a sweep file or --demo (not both)", BAD_INPUT)
    if demo:
        from hoseline.demos.sweep import demo_sweep  # the demo's strut is made with trimesh: only for the demo

        sweep, text = demo_sweep(), ""
    else:
        sweep = read_input(load_sweep, sweep_file, "sweep file", (SweepFileError,))
        text = sweep_file.read_text(encoding="utf-8")

    with errors_to_exit_codes(out):
        compile_solver(quiet, sweep.problem, clearance=True)
        with progress_bar(quiet) as progress:
            result = run_sweep(sweep, progress=progress)
        write_sweep_report(result, out, text)
    if not quiet:
        Console().print(_worst_table(result))
        Console().print(f"wrote {out / 'report.html'} and the data beside it")


def _worst_table(result) -> Table:
    """The worst cases of a SweepResult as a Rich table."""
    table = Table(title=f"{result.sweep.problem.name}: {result.pose_count} poses, worst cases")
    for column in ("quantity", "worst", "limit", "pose"):
        table.add_column(column)
    for row in result.worst_cases():
        style = "" if row["ok"] is None else ("green" if row["ok"] else "bold red")
        limit = "" if row["limit"] is None else f"{row['limit']:.4g} {row['unit']}"
        table.add_row(row["quantity"], f"[{style}]{row['value']:.4g} {row['unit']}[/]" if style else
                      f"{row['value']:.4g} {row['unit']}", limit, row["travel"])
    return table
