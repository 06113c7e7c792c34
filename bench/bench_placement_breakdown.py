"""Where an in-process `solve` of the thesis hose to 180 deg spends its time, part by part.

    python bench/bench_placement_breakdown.py [--segments 100] [--repeats 31] [--estimate-error]

Each part of placement/sequence.solve is timed with perf_counter by wrapping the function that does it (the wrappers
cost about a microsecond each); prints the median of every part over the runs, the median of the whole solve, and
`place_only` (the placement without the verdict) for comparison.  One core, as bench/run.py.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from collections import defaultdict
from pathlib import Path

for variable in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(variable, "1")

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from run import thesis_problem  # noqa: E402

from hoseline.procedures.placement import sequence  # noqa: E402

PARTS = {  # name in sequence's namespace -> label
    "_initial_buckle": "first step: the buckled hose",
    "fork_branches": "uniqueness: the forks' other branches",
    "symmetric_images": "uniqueness: the mounts' symmetry images",
    "other_way_round": "uniqueness: the twist the other way round",
    "judge_uniqueness": "uniqueness: the verdict from the candidates",
    "build_result": "the Result (stations, forces, stability margin)",
    "_coarse_lock": "error estimate: the coarse rod's lock",
    "richardson_error": "error estimate: the coarse solve",
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--segments", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=31)
    parser.add_argument("--estimate-error", action="store_true", help="include the error estimate (solve's default)")
    args = parser.parse_args()

    spent: dict[str, float] = defaultdict(float)

    def timed(label, function):
        def wrapper(*a, **k):
            started = time.perf_counter()
            try:
                return function(*a, **k)
            finally:
                spent[label] += time.perf_counter() - started
        return wrapper

    for name, label in PARTS.items():
        setattr(sequence, name, timed(label, getattr(sequence, name)))
    finish = sequence._Sequence.finish

    def timed_finish(self, *a, **k):  # the main run's rest of the sequence (the uniqueness runs are inside their part)
        main = self.locked_frame is None
        started = time.perf_counter()
        try:
            return finish(self, *a, **k)
        finally:
            if main:
                spent["place and twist: the main run"] += time.perf_counter() - started

    sequence._Sequence.finish = timed_finish
    problem = thesis_problem(args.segments)
    sequence.solve(problem, estimate_error=args.estimate_error)  # warm up
    per_part: dict[str, list[float]] = defaultdict(list)
    totals, bare = [], []
    for _ in range(args.repeats):
        spent.clear()
        started = time.perf_counter()
        result = sequence.solve(problem, estimate_error=args.estimate_error)
        totals.append(time.perf_counter() - started)
        for label in list(PARTS.values()) + ["place and twist: the main run"]:
            per_part[label].append(spent.get(label, 0.0))
        started = time.perf_counter()
        sequence.place_only(problem)
        bare.append(time.perf_counter() - started)
    load = os.getloadavg()[0]
    print(f"thesis hose to 180 deg, {args.segments} segments, in process, one core, median of {args.repeats} "
          f"(load average {load:.2f}); unique = {result.unique}, {result.iterations} Newton iterations")
    accounted = 0.0
    for label, times in sorted(per_part.items(), key=lambda item: -statistics.median(item[1])):
        median = statistics.median(times)
        accounted += median
        if median > 0.0:
            print(f"  {label:<52}{median * 1e3:8.2f} ms")
    total = statistics.median(totals)
    print(f"  {'the rest (set-up, bookkeeping)':<52}{max(total - accounted, 0.0) * 1e3:8.2f} ms")
    print(f"  {'solve, whole':<52}{total * 1e3:8.2f} ms")
    print(f"  {'place_only (no verdict, no Result)':<52}{statistics.median(bare) * 1e3:8.2f} ms")


if __name__ == "__main__":
    main()
