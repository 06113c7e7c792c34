"""`hoseline validation-demo -o out/validation`: synthetic scans of the thesis hose, compared and calibrated."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console

from hoseline.commands.common import OUT_HELP, QUIET_HELP, compile_solver, errors_to_exit_codes
from hoseline.commands.scan_inputs import deviation_table


def validation_demo_command(
    out: Path = typer.Option(Path("out/validation"), "-o", "--out", help=OUT_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
) -> None:
    """Synthetic scans of the thesis brake hose: compare, calibrate, scatter, and the stiffener model's twist path."""
    from hoseline.demos.validation import run_validation_demo

    with errors_to_exit_codes(out):
        compile_solver(quiet, stiffeners=True)
        outcome = run_validation_demo(out)
    if not quiet:
        Console().print(deviation_table(outcome.comparisons))
        for p in outcome.calibration.parameters:
            Console().print(f"{p.name}: {p.initial:.6g} -> {p.value:.6g}" + (f" ± {p.std:.3g}" if p.std else ""))
        for path in outcome.twist_paths:
            verdict = "smooth" if path.smooth else f"NOT smooth: {path.jumps or path.failure}"
            Console().print(f"{path.label}: {verdict}")
        Console().print(f"wrote {out}/ (scans/, problem_*.toml, report/)")
