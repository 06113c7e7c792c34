"""Benchmark: `hoseline compile` from an empty kernel cache, part by part and all at once.

    python bench/bench_compile_parts.py [--runs 1]

Part by part: one fresh interpreter compiles every part of compile_kernels() in turn into a new empty
NUMBA_CACHE_DIR (the placement first, whose stability check compiles in a second process on a machine with
two cores) and prints each part's wall time and CPU time, this process's plus its helper processes'.
All at once: another fresh interpreter runs compile_kernels() with every part, as `hoseline compile` does
(on two cores the other parts compile in a second process beside the contact part), into another empty
folder.  The machine's load is printed too, since compile times follow what else the cores are doing.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

PARTS = ("placement", "clearance", "stiffeners", "clips", "contact", "preset", "braid")

TIMED = """
import json, resource, sys, time
from hoseline.procedures.compile_kernels import compile_kernels

def cpu():
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime

times = {}
for group in json.loads(sys.argv[1]):
    wall, used = time.perf_counter(), cpu()
    compile_kernels(**{part: True for part in group if part != "placement"})
    times["+".join(group)] = (time.perf_counter() - wall, cpu() - used)
print(json.dumps(times))
"""


def timed(groups: list[list[str]]) -> dict[str, tuple[float, float]]:
    """{group: (wall s, CPU s)} of compile_kernels() for each group of parts in turn, in a fresh interpreter
    with an empty cache."""
    source = Path(__file__).resolve().parents[1]
    with tempfile.TemporaryDirectory(prefix="hoseline-compile-parts-") as cache:
        environment = {**os.environ, "NUMBA_CACHE_DIR": cache,
                       "PYTHONPATH": os.pathsep.join(filter(None, [str(source), os.environ.get("PYTHONPATH")]))}
        run = subprocess.run([sys.executable, "-c", TIMED, json.dumps(groups)], env=environment, check=True,
                             capture_output=True, text=True)
    return json.loads(run.stdout.splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1, help="times to repeat both measurements")
    args = parser.parse_args()
    print(f"hoseline compile from an empty cache ({os.cpu_count()} cores; CPU: the process and its helpers)")
    for _ in range(args.runs):
        load = os.getloadavg()[0]
        times = timed([[part] for part in PARTS])
        print(f"part by part (load {load:.1f} at the start, {os.getloadavg()[0]:.1f} at the end):")
        for part, (wall, cpu) in times.items():
            print(f"  {part:<11} {wall:6.1f} s wall  {cpu:6.1f} s CPU")
        print(f"  {'sum':<11} {sum(w for w, _ in times.values()):6.1f} s wall  "
              f"{sum(c for _, c in times.values()):6.1f} s CPU")
        load = os.getloadavg()[0]
        (wall, cpu), = timed([list(PARTS)]).values()
        print(f"all at once, as `hoseline compile` (load {load:.1f} at the start, {os.getloadavg()[0]:.1f} at the end):"
              f" {wall:.1f} s wall, {cpu:.1f} s CPU")


if __name__ == "__main__":
    main()
