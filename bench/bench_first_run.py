"""Benchmark: the first run after installation (cold, an empty kernel cache) against later runs (warm).

    python bench/bench_first_run.py [--repeats 3] [--cli]

Each run is a fresh interpreter, as a user's or a worker's would be.  Cold: NUMBA_CACHE_DIR is a
new empty folder, so every kernel compiles; warm: the same folder again, so every kernel loads
from the cache (hoseline/compilation.py).  Timed inside the interpreter: importing the solver,
and the first placement of the thesis brake hose (100 segments, 180 degrees of twist), wall and
CPU time.  --cli also times `hoseline demo --quiet --export none` end to end (the process's wall
time, which includes its imports).  Prints medians over --repeats runs and the machine's load,
since compile times follow what else the machine's cores are doing.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

FIRST_SOLVE = """
import json, time
started = time.perf_counter()
from hoseline.model import Hose, Mount, Problem
from hoseline.procedures.placement.sequence import solve
imported = time.perf_counter() - started
hose = Hose(length=330.6, outer_diameter=10.1, bending_stiffness=149563.0, torsional_stiffness=2454930.0, segments=100)
start, end = Mount([-13.0, 0.0, -11.25], [0.0, 1.0, 0.0]), Mount([-173.064, -7.0, -11.25], [1.0, 0.0, 0.0])
problem = Problem(hose, start, end, 180.0)
wall, cpu = time.perf_counter(), time.process_time()
solve(problem)
print(json.dumps({"import": imported, "wall": time.perf_counter() - wall, "cpu": time.process_time() - cpu}))
"""


def first_solve(cache: Path) -> dict:
    """Seconds to import the solver and to run the first placement, in a fresh interpreter using `cache`."""
    done = subprocess.run([sys.executable, "-c", FIRST_SOLVE], env={**os.environ, "NUMBA_CACHE_DIR": str(cache)},
                          cwd=cache.parent, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.splitlines()[-1])


def cli_demo(cache: Path, out: Path) -> float:
    """Wall seconds of `hoseline demo --quiet --export none` using `cache`."""
    hoseline = Path(sys.executable).with_name("hoseline")
    started = time.perf_counter()
    subprocess.run([str(hoseline), "demo", "-o", str(out), "--quiet", "--export", "none"],
                   env={**os.environ, "NUMBA_CACHE_DIR": str(cache)}, cwd=out.parent, capture_output=True, check=True)
    return time.perf_counter() - started


def load() -> str:
    """The 1-minute load average and the core count."""
    return f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--cli", action="store_true", help="also time `hoseline demo` cold and warm")
    args = parser.parse_args()
    print(f"load before: {load()}")
    runs: dict[str, list] = {"cold": [], "warm": [], "cli cold": [], "cli warm": []}
    for _ in range(args.repeats):
        folder = Path(tempfile.mkdtemp(prefix="hoseline-bench-"))
        try:
            runs["cold"].append(first_solve(folder / "cache"))
            runs["warm"].append(first_solve(folder / "cache"))
            if args.cli:
                runs["cli cold"].append(cli_demo(folder / "cli-cache", folder / "out"))
                runs["cli warm"].append(cli_demo(folder / "cli-cache", folder / "out"))
        finally:
            shutil.rmtree(folder, ignore_errors=True)
    print(f"load after: {load()}")
    print(f"first placement of the thesis hose (100 segments, 180 deg), medians of {args.repeats} fresh interpreters:")
    for kind in ("cold", "warm"):
        median = {key: statistics.median(run[key] for run in runs[kind]) for key in ("import", "wall", "cpu")}
        label = "cold (empty cache)" if kind == "cold" else "warm (cache hit)  "
        print(f"  {label}: solve {median['wall']:6.2f} s wall, {median['cpu']:6.2f} s CPU; "
              f"import {median['import']:.2f} s")
    if args.cli:
        for kind in ("cli cold", "cli warm"):
            print(f"  hoseline demo, {kind[4:]}: {statistics.median(runs[kind]):6.2f} s wall (whole process)")


if __name__ == "__main__":
    main()
