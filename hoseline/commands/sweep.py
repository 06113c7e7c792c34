"""`hoseline sweep sweep.toml -o out/` (or `--demo`): the hose through the motion of its mounts, and the report.

Registers on the Typer app of hoseline.cli (imported at the end of cli.py).  Exit codes
as for `solve`: 0 done, 2 bad input (sweep file, pose tables, meshes, paths), 3 the solver
failed.  On an error nothing is written; otherwise all files appear together.
"""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console
from rich.table import Table

from hoseline.cli import BAD_INPUT, OUT_HELP, QUIET_HELP, _errors_to_exit_codes, _fail, _progress, _read_input, app
from hoseline.io.sweep_file import SweepFileError, load_sweep
from hoseline.procedures.sweep import run_sweep
from hoseline.procedures.sweep_result import SweepResult
from hoseline.report.sweep_report import write_sweep_report
from hoseline.sweep_demo import demo_sweep


@app.command("sweep")
def sweep_command(
    sweep_file: Path = typer.Argument(None, help="TOML sweep file: a problem file with [\\[bodies]] and [\\[obstacles]] "
                                                 "(see docs/sweep.md)"),
    out: Path = typer.Option(..., "-o", "--out", help=OUT_HELP),
    demo: bool = typer.Option(False, "--demo", help="run the built-in demo (thesis hose, steer and jounce, a strut)"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
) -> None:
    """Carry the hose through the motion of its mounts; write report.html, PNGs, envelope.stl and the numbers."""
    if (sweep_file is None) == (not demo):
        raise _fail("give either a sweep file or --demo (not both)", BAD_INPUT)
    if demo:
        sweep, text = demo_sweep(), ""
    else:
        sweep = _read_input(load_sweep, sweep_file, "sweep file", (SweepFileError,))
        text = sweep_file.read_text(encoding="utf-8")

    with _errors_to_exit_codes(out):
        with _progress(quiet) as progress:
            result = run_sweep(sweep, progress=progress)
        write_sweep_report(result, out, text)
    if not quiet:
        Console().print(_worst_table(result))
        Console().print(f"wrote {out / 'report.html'} and the data beside it")


def _worst_table(result: SweepResult) -> Table:
    """The worst cases as a Rich table."""
    table = Table(title=f"{result.sweep.problem.name}: {result.pose_count} poses, worst cases")
    for column in ("quantity", "worst", "limit", "pose"):
        table.add_column(column)
    for row in result.worst_cases():
        style = "" if row["ok"] is None else ("green" if row["ok"] else "bold red")
        limit = "" if row["limit"] is None else f"{row['limit']:.4g} {row['unit']}"
        table.add_row(row["quantity"], f"[{style}]{row['value']:.4g} {row['unit']}[/]" if style else
                      f"{row['value']:.4g} {row['unit']}", limit, row["travel"])
    return table
