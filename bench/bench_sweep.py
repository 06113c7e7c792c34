"""Benchmark: a 1000-pose sweep of the thesis hose (100 segments) past a 100 000-triangle strut.

    python bench/bench_sweep.py [--poses 1000] [--triangles 100000] [--free-roll]

The demo's motion (steer 25 degrees each way about an inclined kingpin, then 40 mm of
jounce and rebound) with the pose spacing set for the requested pose count, and the strut
as a finely meshed cylinder of well-shaped triangles.  One core.  Prints poses per second
of the solver, Newton iterations per pose, the clearance query time per pose and the
sweep's total (without the placement at design position and without compiling, which a
short warm-up sweep does first).  Target: under 3 s for 1000 poses.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

for variable in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(variable, "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hoseline.model.sweep import Obstacle  # noqa: E402
from hoseline.procedures.sweep.quasi_static import run_sweep  # noqa: E402
from hoseline.demos.sweep import JOUNCE_MM, STEER_DEG, STRUT_CENTRE, STRUT_HEIGHT, STRUT_RADIUS, demo_sweep  # noqa: E402


def cylinder_mesh(triangles: int) -> Obstacle:
    """The strut as an open cylinder of about `triangles` near-square-split cells."""
    around = max(8, int(math.sqrt(triangles * math.pi * STRUT_RADIUS / STRUT_HEIGHT)))
    rows = max(1, triangles // (2 * around))
    angles = 2.0 * math.pi * np.arange(around) / around
    heights = np.linspace(-0.5 * STRUT_HEIGHT, 0.5 * STRUT_HEIGHT, rows + 1)
    a, z = np.meshgrid(angles, heights)
    vertices = np.column_stack([STRUT_RADIUS * np.cos(a).ravel(), STRUT_RADIUS * np.sin(a).ravel(), z.ravel()]) + STRUT_CENTRE
    j, i = np.meshgrid(np.arange(rows), np.arange(around), indexing="ij")
    p = (j * around + i).ravel()
    q = (j * around + (i + 1) % around).ravel()
    faces = np.vstack([np.column_stack([p, q, q + around]), np.column_stack([p, q + around, p + around])])
    return Obstacle("strut", vertices, faces)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=1000)
    parser.add_argument("--triangles", type=int, default=100_000)
    parser.add_argument("--free-roll", action="store_true", help="also run the free-roll comparison")
    options = parser.parse_args()

    travel = 4 * STEER_DEG + 4 * JOUNCE_MM  # degrees plus mm, one pose count per unit
    strut = cylinder_mesh(options.triangles)
    warm = replace(demo_sweep(steps_per_degree=0.1), obstacles=(strut,), compare_free_roll=False)
    run_sweep(warm)  # compiles every kernel

    sweep = replace(demo_sweep(steps_per_degree=(options.poses - 1) / travel), obstacles=(strut,),
                    compare_free_roll=options.free_roll)
    started = time.perf_counter()
    result = run_sweep(sweep)
    total = time.perf_counter() - started
    placement = result.assembly.wall_time
    count = result.pose_count
    print(f"poses                      {count}")
    print(f"obstacle triangles         {len(strut.faces)}")
    print(f"solver                     {result.solve_seconds:.3f} s = {count / result.solve_seconds:.0f} poses/s"
          + (" (locked and free-roll runs)" if options.free_roll else ""))
    print(f"Newton iterations per pose {np.mean(result.iterations):.2f} (max {np.max(result.iterations)})")
    print(f"clearance query per pose   {1e3 * result.clearance_seconds / count:.3f} ms")
    print(f"sweep total                {total - placement:.3f} s (placement at design position {placement:.3f} s "
          f"not counted)")
    print(f"least clearance            {result.clearances[0].distance.min():.2f} mm; snaps {len(result.snaps)}")


if __name__ == "__main__":
    main()
