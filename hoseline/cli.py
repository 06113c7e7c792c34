"""Command line: `hoseline solve problem.toml -o out/ [--export iges,step,...]` and `hoseline demo`.

Exit codes: 0 success, 2 bad input (problem file, paths, export names), 3 the solver failed,
4 an export could not be made.  On an error nothing is written.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TaskProgressColumn, TextColumn, TimeElapsedColumn
from rich.text import Text

from hoseline.io.atomic import staged_directory
from hoseline.io.exports import FILE_NAMES, ExportedFile, ExportError, parse_formats, write_exports
from hoseline.io.problem_file import ProblemFileError, load_problem
from hoseline.io.results import write_results
from hoseline.procedures import placement
from hoseline.report.table import summary_table

BAD_INPUT = 2
SOLVER_FAILED = 3
EXPORT_FAILED = 4

app = typer.Typer(
    help="Where a flexible hose lies between two mounts.", no_args_is_help=True, add_completion=False
)

OUT_HELP = "output directory (created; files of the same name are replaced)"
QUIET_HELP = "no progress bar and no summary; errors are still printed"
EXPORT_HELP = (
    "comma-separated CAD and model files to write beside the results: "
    + ", ".join(f"{name} ({file})" for name, file in FILE_NAMES.items())
    + "; all or none"
)


def _fail(message: str, code: int) -> typer.Exit:
    """Print one red line on stderr and return the exit to raise."""
    Console(stderr=True).print(Text(f"error: {message}", style="red"), soft_wrap=True)
    return typer.Exit(code)


def _read_input(reader: Callable, path: Path, what: str, errors: tuple[type[Exception], ...], *args):
    """reader(path, *args), with bad content (`errors`) or an unreadable file ending the command
    with one red line and exit code BAD_INPUT.  what: e.g. "problem file", for the message."""
    try:
        return reader(path, *args)
    except errors as exc:
        raise _fail(str(exc), BAD_INPUT) from None
    except OSError as exc:
        raise _fail(f"cannot read {what} {path}: {exc.strerror or exc}", BAD_INPUT) from None


@contextmanager
def _progress(quiet: bool) -> Iterator[Callable[[str, float], None] | None]:
    """A progress(phase, fraction) callback drawing one Rich bar per phase, or None when quiet."""
    if quiet:
        yield None
        return
    columns = (TextColumn("{task.description:<18}"), BarColumn(), TaskProgressColumn(), TimeElapsedColumn())
    with Progress(*columns, console=Console(stderr=True)) as bar:
        tasks: dict[str, int] = {}

        def report(phase: str, fraction: float) -> None:
            if phase not in tasks:
                tasks[phase] = bar.add_task(phase, total=1.0)
            bar.update(tasks[phase], completed=min(max(fraction, 0.0), 1.0))

        yield report


@contextmanager
def _errors_to_exit_codes(out_dir: Path) -> Iterator[None]:
    """Turn the expected failures into one red line and an exit code.

    An output path that cannot become a directory (it, or its nearest existing parent, is a
    file) is refused on entry, before any solving.
    """
    existing = next(path for path in (out_dir, *out_dir.parents) if path.exists())
    if not existing.is_dir():
        raise _fail(f"cannot write to {out_dir}: {existing} is a file, not a directory; choose another -o", BAD_INPUT)
    try:
        yield
    except placement.PlacementError as exc:
        raise _fail(f"the solver failed: {exc}", SOLVER_FAILED) from None
    except ExportError as exc:
        raise _fail(f"export failed, nothing written: {exc}", EXPORT_FAILED) from None
    except OSError as exc:
        raise _fail(f"cannot write to {out_dir}: {exc}", BAD_INPUT) from None


@app.command("solve")
def solve_command(
    problem_file: Path = typer.Argument(..., help="TOML problem file (see README)"),
    out: Path = typer.Option(..., "-o", "--out", help=OUT_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
    export: str = typer.Option("none", "--export", "-e", help=EXPORT_HELP),
) -> None:
    """Place the hose of a problem file; write centerline.csv, result.json and the exports asked for."""
    formats = _formats(export)
    problem = _read_input(load_problem, problem_file, "problem file", (ProblemFileError,))

    with _errors_to_exit_codes(out):
        with _progress(quiet) as progress:
            result = placement.solve(problem, progress=progress)
        with staged_directory(out) as staging:
            write_results(result, staging)
            exported = write_exports(result, staging, formats)
    if not quiet:
        Console().print(summary_table([result], [problem.name]))
        Console().print(f"wrote {out / 'centerline.csv'} and {out / 'result.json'}")
        _print_exports(out, exported)


@app.command("demo")
def demo_command(
    out: Path = typer.Option(Path("out/demo"), "-o", "--out", help=OUT_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
    export: str = typer.Option("all", "--export", "-e", help=EXPORT_HELP),
) -> None:
    """Place the thesis brake hose (mounts from its IGES file) at 0 and 180 degrees of twist; write all files."""
    from hoseline import demo  # loads OpenCASCADE (about a second): only for the demo

    formats = _formats(export)
    with _errors_to_exit_codes(out):
        with _progress(quiet) as progress:
            labels, results, exported = demo.run_demo(out, progress=progress, formats=formats)
    if not quiet:
        Console().print(summary_table(results, labels, title="thesis brake hose (Goodyear5052, 330.6 mm)"))
        Console().print(f"wrote {out}/ (twist_000/, twist_180/, shapes.png)")
        for twist, files in zip(demo.TWISTS_DEG, exported):
            _print_exports(out / demo.twist_folder(twist), files)


def _formats(text: str) -> list[str]:
    """The --export list, or exit 2 naming the unknown format."""
    try:
        return parse_formats(text)
    except ValueError as exc:
        raise _fail(f"--export {text}: {exc}", BAD_INPUT) from None


def _print_exports(folder: Path, files: list[ExportedFile]) -> None:
    """One line per exported file: path, size, time to make and write it."""
    for file in files:
        line = f"wrote {folder / file.name} ({file.size / 1024:.0f} KiB in {file.seconds:.2f} s)"
        Console().print(line, soft_wrap=True)


import hoseline.commands.sweep  # noqa: E402,F401  registers `hoseline sweep` on app
import hoseline.commands.compare  # noqa: E402,F401  registers `hoseline compare`, `calibrate`, `validation-demo`
