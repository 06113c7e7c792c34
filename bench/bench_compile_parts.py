"""Benchmark: `hoseline compile` part by part, from an empty kernel cache.

    python bench/bench_compile_parts.py

One fresh interpreter compiles every part of compile_kernels() in turn (as `hoseline compile` does: the
placement first, whose stability check compiles in a second process on a machine with two cores) into a new
empty NUMBA_CACHE_DIR, and prints each part's wall and CPU time (this process's; the helper process of the
placement is counted in its wall time only) and the machine's load, since compile times follow what else the
cores are doing.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

PARTS = ("placement", "clearance", "stiffeners", "clips", "contact", "preset", "braid")

TIMED = """
import json, sys, time
from hoseline.procedures.compile_kernels import compile_kernels
times = {}
for part in json.loads(sys.argv[1]):
    wall, cpu = time.perf_counter(), time.process_time()
    compile_kernels(**({} if part == "placement" else {part: True}))
    times[part] = (time.perf_counter() - wall, time.process_time() - cpu)
print(json.dumps(times))
"""


def main() -> None:
    source = Path(__file__).resolve().parents[1]
    with tempfile.TemporaryDirectory(prefix="hoseline-compile-parts-") as cache:
        environment = {**os.environ, "NUMBA_CACHE_DIR": cache,
                       "PYTHONPATH": os.pathsep.join(filter(None, [str(source), os.environ.get("PYTHONPATH")]))}
        load = os.getloadavg()[0]
        run = subprocess.run([sys.executable, "-c", TIMED, json.dumps(PARTS)], env=environment, check=True,
                             capture_output=True, text=True)
    times = json.loads(run.stdout.splitlines()[-1])
    print(f"hoseline compile from an empty cache, part by part (load {load:.1f} at the start, "
          f"{os.getloadavg()[0]:.1f} at the end; {os.cpu_count()} cores)")
    for part, (wall, cpu) in times.items():
        print(f"  {part:<11} {wall:6.1f} s wall  {cpu:6.1f} s CPU")
    print(f"  {'all':<11} {sum(w for w, _ in times.values()):6.1f} s wall  {sum(c for _, c in times.values()):6.1f} s CPU")


if __name__ == "__main__":
    main()
