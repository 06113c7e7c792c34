"""`hoseline studio [problem.toml | sweep.toml]`: the hose placed by hand in the browser, the solver following.

Starts a local web server (127.0.0.1 unless --host says otherwise) and opens the browser on it.
Exit codes: 0 stopped (Ctrl+C), 2 bad input (the file, the address), 3 the hose cannot be placed.
"""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console

from hoseline.commands.common import BAD_INPUT, SOLVER_FAILED, fail, read_input

DEFAULT_PORT = 8765


def studio_command(
    file: Path = typer.Argument(None, help="problem or sweep file (TOML); default: the built-in sweep demo "
                                           "(the thesis hose, a steered and sprung knuckle, a strut)"),
    port: int = typer.Option(DEFAULT_PORT, "--port", help="TCP port (0: any free one)"),
    host: str = typer.Option("127.0.0.1", "--host", help="address to listen on; anything but 127.0.0.1 lets other "
                                                          "machines drive the studio"),
    no_browser: bool = typer.Option(False, "--no-browser", help="do not open the browser; print the address only"),
) -> None:
    """Place a hose by hand in the browser: drag the fittings, move sliders, play a sweep; the shape follows."""
    from hoseline.procedures.placement.continuation import PlacementError
    from hoseline.studio.launch import bind, serve
    from hoseline.studio.session import Session, StudioError

    if not 0 <= port <= 65535:
        raise fail(f"--port {port}: give a port from 0 to 65535", BAD_INPUT)
    console = Console(stderr=True)
    problem, sweep = _read(file)
    try:
        session = Session(problem) if sweep is None else Session(sweep=sweep)
    except StudioError as exc:
        raise fail(f"{file}: {exc}", BAD_INPUT) from None
    except PlacementError as exc:
        raise fail(f"the solver failed: {exc}", SOLVER_FAILED) from None
    try:
        listener = bind(host, port)
    except OSError as exc:
        hint = "; give another --port (0: any free one)" if port else ""
        raise fail(f"cannot listen on {host}:{port}: {exc.strerror or exc}{hint}", BAD_INPUT) from None
    if host not in ("127.0.0.1", "localhost", "::1"):
        console.print(f"[yellow]warning: listening on {host}: other machines that reach it can drive the studio "
                      "and upload files; use the default 127.0.0.1 unless you mean that[/]")

    def announce(url: str) -> None:
        console.print(f"hoseline studio at {url} (Ctrl+C to stop)")

    try:
        serve(session, listener, not no_browser, announce)
    except KeyboardInterrupt:
        pass


def _read(file: Path | None):
    """(problem, None) or (None, sweep) of the file; the built-in sweep demo without one."""
    from hoseline.demos.sweep import demo_sweep
    from hoseline.io.problem_file import ProblemFileError, load_problem, read_toml
    from hoseline.io.sweep_file import SweepFileError, load_sweep

    if file is None:
        return None, demo_sweep()
    data = read_input(read_toml, file, "problem or sweep file", (ProblemFileError,), ProblemFileError)
    if "bodies" in data:
        return None, read_input(load_sweep, file, "sweep file", (SweepFileError,))
    return read_input(load_problem, file, "problem file", (ProblemFileError,)), None
