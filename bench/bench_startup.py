"""Benchmark: the command line's start-up, whole processes with the kernels compiled (warm).

    python bench/bench_startup.py [--repeats 5]

Runs, each --repeats times in a fresh process of the hoseline beside this script: `hoseline --help`;
`hoseline solve` of the thesis brake hose (the demo's problem: 100 segments, 180 degrees of twist; it writes
centerline.csv and result.json); `hoseline sweep` of a small sweep without meshes or contact (the hose at 10
segments, three poses of its end mount's body; it writes the report, its PNGs and the envelope).  Prints the
medians and ranges of the wall times, the solve's own time as result.json gives it (the placement with its
uniqueness check and error estimate, and the kernels' loading, which happens on the first call), and the machine's
load before and after, since wall times follow what else the cores are doing.  The kernels are compiled first
(`hoseline compile`) so that no run waits for the compiler.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SOURCE = Path(__file__).resolve().parents[1]
COMMAND = "import sys; from hoseline.cli import app; app(sys.argv[1:])"
SWEEP = """name = "small sweep"
[hose]
length = 330.6
outer_diameter = 10.1
bending_stiffness = 149563.0
torsional_stiffness = 2454930.0
segments = 10
[start]
point = [-13.0, 0.0, -11.25]
direction = [0.0, 1.0, 0.0]
[end]
body = "knuckle"
point = [-173.064, -7.0, -11.25]
direction = [1.0, 0.0, 0.0]
twist = 180.0
[[bodies]]
name = "knuckle"
poses = "knuckle.csv"
"""
POSES = "jounce [mm], x, y, z, qw, qx, qy, qz\n0, 0, 0, 0, 1, 0, 0, 0\n10, 0, 0, 10, 1, 0, 0, 0\n20, 0, 0, 20, 1, 0, 0, 0\n"


def hoseline(*args: str) -> tuple[float, float]:
    """Run `hoseline *args` in a fresh interpreter (this checkout first on the path); its wall and CPU time, s."""
    environment = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(SOURCE), os.environ.get("PYTHONPATH")]))}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run([sys.executable, "-c", COMMAND, *args], env=environment, check=True, stdout=subprocess.DEVNULL,
                   cwd=tempfile.gettempdir())  # not this checkout's folder: python -c puts the current one first
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime


def line(label: str, runs: list[tuple[float, float]]) -> str:
    """Median and range of the wall times, median of the CPU times."""
    wall = [w for w, _ in runs]
    cpu = statistics.median(c for _, c in runs)
    return f"  {label:<40} {statistics.median(wall):6.3f} s wall ({min(wall):.3f}-{max(wall):.3f}), {cpu:.3f} s CPU"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    repeats = parser.parse_args().repeats
    hoseline("compile", "--quiet")
    with tempfile.TemporaryDirectory(prefix="hoseline-startup-") as folder:
        folder = Path(folder)
        subprocess.run([sys.executable, "-c", "import sys; from hoseline.demos.thesis_hose import demo_problem; "
                        "from hoseline.io.problem_file import problem_to_toml; "
                        "open(sys.argv[1], 'w').write(problem_to_toml(demo_problem(180.0)))", folder / "thesis.toml"],
                       env={**os.environ, "PYTHONPATH": str(SOURCE)}, check=True, cwd=folder)
        (folder / "sweep.toml").write_text(SWEEP)
        (folder / "knuckle.csv").write_text(POSES)
        load = os.getloadavg()[0]
        help_times, solve_times, solving, sweep_times = [], [], [], []
        for _ in range(repeats):
            help_times.append(hoseline("--help"))
            solve_times.append(hoseline("solve", str(folder / "thesis.toml"), "-o", str(folder / "solved"), "--quiet"))
            solved = json.loads((folder / "solved" / "result.json").read_text())["summary"]["wall_time_s"]
            solving.append((solved, solved))
            sweep_times.append(hoseline("sweep", str(folder / "sweep.toml"), "-o", str(folder / "swept"), "--quiet"))
    print(f"hoseline start-up, warm, {repeats} runs each (load {load:.1f} before, {os.getloadavg()[0]:.1f} after; "
          f"{os.cpu_count()} cores)")
    print(line("hoseline --help", help_times))
    print(line("hoseline solve, thesis hose (100 seg.)", solve_times))
    print(line("  of which the solve (result.json)", solving).split(",")[0])
    print(line("hoseline sweep, 3 poses, no meshes", sweep_times))


if __name__ == "__main__":
    main()
