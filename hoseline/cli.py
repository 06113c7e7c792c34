"""The hoseline command: assembles the commands of hoseline/commands/, one module each.

    hoseline solve problem.toml -o out/ [--export iges,step,...]
    hoseline demo | sweep | compare | calibrate | validation-demo | studio | study | compile

Exit codes: 0 success, 2 bad input (files, paths, options), 3 the solver failed, 4 an export
could not be made, 5 a check failed.  On an error nothing is written.  The command modules
import the solver and the file formats only when they run, so `hoseline --help` is quick.
"""

from __future__ import annotations

import atexit
import gc
import os

FULL_COLLECTION_EVERY = 100  # collections of the middle generation per full collection (Python's default: 10)

# Before NumPy loads: OpenBLAS (NumPy's and SciPy's own copies) otherwise starts a pool of threads per
# library that spin after each call.  The solver's dense algebra is small and runs on one BLAS thread anyway
# (mechanics/blas_threads.py); the pools cost a warm solve 0.2 s of CPU (of 0.8), and 0.02 s of wall time on a quiet
# machine (0.60 -> 0.58 s, medians), more under load.  A value the user set is kept.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

# At exit the interpreter collects its garbage once more, walking every object left, Numba's compiler state
# included: 0.15-0.4 s after a solve.  A command has written and closed its files by then (atomically), and
# this handler, registered first, runs after every other: freezing what is left skips that walk (what only
# reference cycles hold is left to the operating system, as at os._exit; the rest is released as before).
atexit.register(gc.freeze)
# A full collection walks every object alive; a command's start-up creates several hundred thousand that live as
# long as it does (NumPy's, Numba's, SciPy's modules, the kernels), and the default (one full collection per ten of
# the middle generation) ran them over and over: 0.1 s of a solve's 0.8 s of CPU.  One per hundred.
gc.set_threshold(*gc.get_threshold()[:2], FULL_COLLECTION_EVERY)

import typer  # noqa: E402

from hoseline.commands import (  # noqa: E402  (after the setting above: the commands import NumPy)
    calibrate, compare, compile, demo, solve, studio, study, sweep, validation_demo,
)

app = typer.Typer(
    help="Where a flexible hose lies between two mounts.", no_args_is_help=True, add_completion=False
)
app.command("solve")(solve.solve_command)
app.command("demo")(demo.demo_command)
app.command("sweep")(sweep.sweep_command)
app.command("compare")(compare.compare_command)
app.command("calibrate")(calibrate.calibrate_command)
app.command("validation-demo")(validation_demo.validation_demo_command)
app.command("studio")(studio.studio_command)
app.command("study")(study.study_command)
app.command("compile")(compile.compile_command)
