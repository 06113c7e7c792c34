"""Benchmark: placing a hose with a clip against the same hose without one.

    python bench/bench_clips.py [--repeats 5]

The thesis brake hose (100 segments, 180 degrees of twist) placed without clips, then with one
clip of each kind at station 50, where the hose without clips passes (its point and tangent
there; the sliding clip started 2 stations further on).  Prints the median wall time of solve()
(with the uniqueness checks; the error estimate included) and of one Newton iteration's assembly
and bordered solve, and their ratios to the hose without clips, the continuation steps and Newton
iterations, with the machine's load; for the sliding clip the arc length it found (mm).
"""

from __future__ import annotations

import argparse
import os
import sys
from dataclasses import replace
from pathlib import Path

for variable in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(variable, "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import median_time  # noqa: E402
from hoseline.demos.thesis_hose import demo_problem  # noqa: E402
from hoseline.mechanics.newton import _step_kernel, evaluate  # noqa: E402
from hoseline.mechanics.rod import RodState  # noqa: E402
from hoseline.model.clips import Clip  # noqa: E402
from hoseline.procedures.placement.path import PlacementPath  # noqa: E402
from hoseline.procedures.placement.sequence import rod_properties, solve  # noqa: E402


def iteration_time(problem, result, repeats: int) -> float:
    """Median time of one Newton iteration's work (assembly and bordered solve) at the placed shape, s."""
    props = rod_properties(problem)
    clamps = PlacementPath(problem).place(1.0)
    state = RodState(result.frames, result.end_force, clip_arc_lengths=np.array([c.arc_length for c in result.clips]))

    def iterate():
        system = evaluate(props, clamps, state)
        if clamps.clips:
            from hoseline.mechanics.clipped_newton import _step

            _step(system, 0.0)  # with a sliding clip: the wider border of its arc length
        else:
            _step_kernel(system.band, system.jac_t, system.grad, system.constraint, 0.0, True)

    return median_time(iterate, 50 * repeats)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    plain = demo_problem(180.0, segments=100)
    free = solve(plain)
    station, h = 50, plain.hose.segment_length
    tangent = free.frames[station - 1, 2] + free.frames[station, 2]
    cases = [("no clip", plain)] + [
        (kind, replace(plain, clips=(Clip(kind, free.centerline[station], (station + 2 * (kind == "sliding")) * h,
                                          None if kind == "ball" else tangent),)))
        for kind in ("fixed", "rotating", "sliding", "ball")
    ]
    print(f"thesis hose, 100 segments, 180 deg; median of {args.repeats}; load average {os.getloadavg()[0]:.1f}")
    base_solve = base_iteration = None
    for label, problem in cases:
        result = solve(problem)
        placement = median_time(lambda: solve(problem), args.repeats)
        iteration = iteration_time(problem, result, args.repeats)
        base_solve = base_solve or placement
        base_iteration = base_iteration or iteration
        found = f", arc length {result.clips[0].arc_length:.4f} mm (free hose: {station * h:.4f})" if label == "sliding" else ""
        print(f"{label:>9}: placement {placement * 1e3:8.1f} ms ({placement / base_solve:4.2f}x), "
              f"iteration {iteration * 1e6:7.1f} us ({iteration / base_iteration:4.2f}x), "
              f"{result.steps} steps, {result.iterations} Newton iterations{found}")


if __name__ == "__main__":
    main()
