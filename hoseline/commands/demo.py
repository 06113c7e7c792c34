"""`hoseline demo -o out/demo`: the thesis brake hose at 0 and 180 degrees of twist, every export."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console

from hoseline.commands.common import OUT_HELP, QUIET_HELP, compile_solver, errors_to_exit_codes, progress_bar
from hoseline.commands.solve import EXPORT_HELP, export_formats, print_exports


def demo_command(
    out: Path = typer.Option(Path("out/demo"), "-o", "--out", help=OUT_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
    export: str = typer.Option("all", "--export", "-e", help=EXPORT_HELP),
) -> None:
    """Place the thesis brake hose (mounts from its IGES file) at 0 and 180 degrees of twist; write all files."""
    from hoseline.demos import thesis_hose
    from hoseline.report.table import summary_table

    formats = export_formats(export)
    with errors_to_exit_codes(out):
        compile_solver(quiet)
        with progress_bar(quiet) as progress:
            labels, results, exported = thesis_hose.run_demo(out, progress=progress, formats=formats)
    if not quiet:
        Console().print(summary_table(results, labels, title="thesis brake hose (Goodyear5052, 330.6 mm)"))
        Console().print(f"wrote {out}/ (twist_000/, twist_180/, shapes.png)")
        for twist, files in zip(thesis_hose.TWISTS_DEG, exported):
            print_exports(out / thesis_hose.twist_folder(twist), files)
