"""What every command shares: exit codes, option help, one-line errors, the first-run compile notice, the progress bar.

Exit codes: 0 success, 2 bad input (files, paths, options), 3 the solver failed, 4 an export
could not be made, 5 a check failed (compare --check).  Heavy modules (the solver, exports)
are imported inside the functions that need them, so that `hoseline --help` starts at once.
"""

from __future__ import annotations

import errno
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager, nullcontext
from pathlib import Path

import typer
from rich.console import Console
from rich.text import Text

BAD_INPUT = 2
SOLVER_FAILED = 3
EXPORT_FAILED = 4
CHECK_FAILED = 5

OUT_HELP = "output directory (created; files of the same name are replaced)"
QUIET_HELP = "no progress bar and no summary; errors are still printed"


def fail(message: str, code: int) -> typer.Exit:
    """Print one red line on stderr and return the exit to raise."""
    Console(stderr=True).print(Text(f"error: {message}", style="red"), soft_wrap=True)
    return typer.Exit(code)


def read_input(reader: Callable, path: Path, what: str, errors: tuple[type[Exception], ...], *args):
    """reader(path, *args), with bad content (`errors`) or an unreadable file ending the command
    with one red line and exit code BAD_INPUT.  what: e.g. "problem file", for the message."""
    try:
        return reader(path, *args)
    except errors as exc:
        raise fail(str(exc), BAD_INPUT) from None
    except OSError as exc:
        raise fail(f"cannot read {what} {path}: {exc.strerror or exc}", BAD_INPUT) from None


FIRST_RUN = "first run: compiling the solver, once per installation"
NO_CACHE = "compiling the solver (no writable cache folder: every run compiles; set NUMBA_CACHE_DIR to keep it)"


def solver_parts(problem) -> dict[str, bool]:
    """The parts of the solver (procedures/compile_kernels.py) that placing `problem` uses beyond a plain placement."""
    return {"stiffeners": problem.hose.stiffeners is not None, "clips": bool(problem.clips),
            "contact": problem.has_contact, "preset": problem.hose.preset is not None,
            "braid": problem.hose.braid is not None}


def compile_solver(quiet: bool, problem=None, **parts: bool) -> None:
    """Compile the solver's kernels for `problem` (its stiffener springs, clips and contact) and the
    `parts` asked for (clearance=True: clearance queries; see compile_kernels) if this installation has
    not yet, saying so meanwhile (a spinner on a terminal, a line in a log) and then how long it took;
    nothing is said when quiet.  See hoseline/procedures/compile_kernels.py."""
    from hoseline.compilation import persistent, version_folder
    from hoseline.procedures.compile_kernels import compile_kernels, kernels_compiled

    if problem is not None:
        parts = {**solver_parts(problem), **{name: True for name, asked in parts.items() if asked}}
    if kernels_compiled(**parts):
        return
    if quiet:
        compile_kernels(**parts)
        return
    console = Console(stderr=True)
    message = FIRST_RUN if persistent() else NO_CACHE
    if not console.is_terminal:
        console.print(message)
    started = time.perf_counter()
    with console.status(message) if console.is_terminal else nullcontext():
        compile_kernels(**parts)
    kept = f"kept in {version_folder()}" if persistent() else "not kept"
    console.print(f"compiled the solver in {time.perf_counter() - started:.0f} s ({kept})", soft_wrap=True)


@contextmanager
def progress_bar(quiet: bool) -> Iterator[Callable[[str, float], None] | None]:
    """A progress(phase, fraction) callback drawing one Rich bar per phase, or None when quiet."""
    if quiet:
        yield None
        return
    from rich.progress import BarColumn, Progress, TaskProgressColumn, TextColumn, TimeElapsedColumn

    columns = (TextColumn("{task.description:<18}"), BarColumn(), TaskProgressColumn(), TimeElapsedColumn())
    with Progress(*columns, console=Console(stderr=True)) as bar:
        tasks: dict[str, int] = {}

        def report(phase: str, fraction: float) -> None:
            if phase not in tasks:
                tasks[phase] = bar.add_task(phase, total=1.0)
            bar.update(tasks[phase], completed=min(max(fraction, 0.0), 1.0))

        yield report


@contextmanager
def errors_to_exit_codes(out_dir: Path) -> Iterator[None]:
    """Turn the expected failures into one red line and an exit code.

    An output path that cannot become a directory (it, or its nearest existing parent, is a
    file) is refused on entry, before any solving.
    """
    from hoseline.io.exports import ExportError
    from hoseline.procedures.placement.continuation import PlacementError

    try:
        existing = next(path for path in (out_dir, *out_dir.parents) if path.exists())
    except OSError as exc:  # e.g. a name longer than the file system allows
        fix = "a shorter" if exc.errno == errno.ENAMETOOLONG else "another"
        raise fail(f"cannot write to {out_dir}: {exc.strerror or exc}; choose {fix} -o", BAD_INPUT) from None
    if not existing.is_dir():
        raise fail(f"cannot write to {out_dir}: {existing} is a file, not a directory; choose another -o", BAD_INPUT)
    try:
        yield
    except PlacementError as exc:
        raise fail(f"the solver failed: {exc}", SOLVER_FAILED) from None
    except ExportError as exc:
        raise fail(f"export failed, nothing written: {exc}", EXPORT_FAILED) from None
    except OSError as exc:
        reason = exc.strerror or exc
        if exc.filename and not Path(exc.filename).absolute().is_relative_to(_staging_anchor(out_dir)):
            raise fail(f"cannot use {exc.filename}: {reason}", BAD_INPUT) from None  # not the output's fault
        fix = "a shorter" if exc.errno == errno.ENAMETOOLONG else "another"
        raise fail(f"cannot write to {out_dir}: {reason}; choose {fix} -o", BAD_INPUT) from None


def _staging_anchor(out_dir: Path) -> Path:
    """The nearest existing parent of `out_dir`, where its files are staged (io/atomic.py)."""
    return next(path for path in out_dir.absolute().parents if path.exists())
