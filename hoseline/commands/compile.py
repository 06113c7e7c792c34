"""`hoseline compile`: compile every part of the solver now, once per installation (the Makefile runs it)."""

from __future__ import annotations

import time

import typer
from rich.console import Console

from hoseline.commands.common import QUIET_HELP, compile_solver

PARTS = ("clearance", "stiffeners", "clips", "contact", "preset", "braid")  # beyond the plain placement (compile_kernels)


def compile_command(quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP)) -> None:
    """Compile the solver's kernels for every kind of problem (placement, clearance, stiffener springs, clips,
    contact, preset, braid) into this installation's cache, so that no later run waits for the compiler."""
    from hoseline.compilation import persistent, version_folder

    started = time.perf_counter()
    compile_solver(quiet, **dict.fromkeys(PARTS, True))
    if not quiet:
        where = f"in {version_folder()}" if persistent() else "nowhere: no writable cache folder (set NUMBA_CACHE_DIR)"
        Console().print(f"the solver is compiled, kept {where} ({time.perf_counter() - started:.1f} s)", soft_wrap=True)
