"""Benchmark: what a sweep writes, how large, and the swept envelope's time and memory on large layouts.

    python bench/bench_sweep_outputs.py [--poses 601] [--out DIR]

1. The demo sweep and a demo sweep of `--poses` poses, written in full (write_sweep_report):
   the size of every file, report.html in particular (target: under 3.5 MB for 601 poses).
2. The swept envelope alone (swept_envelope) on the demo and on synthetic layouts whose dense
   grid at half the radius would need tens of GB: time, the peak of the memory Python and NumPy
   allocate (tracemalloc), triangles, the cell used against the cell asked for.  Target: every
   layout under 5 s and 300 MB.
One core.  The kernels are compiled by a short warm-up first.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

for variable in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(variable, "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hoseline.demos.sweep import JOUNCE_MM, STEER_DEG, demo_sweep  # noqa: E402
from hoseline.procedures.sweep.envelope import swept_envelope  # noqa: E402
from hoseline.procedures.sweep.quasi_static import run_sweep  # noqa: E402
from hoseline.report.sweep_report import write_sweep_report  # noqa: E402

DENSE_BYTES_PER_NODE = 56  # what the former dense grid held per node: coordinates, distance, index, field


def sagging_hoses(length: float, span: float, poses: int, rise: float, segments: int = 100) -> np.ndarray:
    """(poses, segments + 1, 3) mm: a hose sagging between fixed mounts `span` apart, its middle lifted
    by `rise` and swung sideways over the poses (as tests/test_sweep_envelope.py)."""
    s = np.linspace(0.0, 1.0, segments + 1)
    bow = np.sin(np.pi * s)
    sag = 0.5 * np.sqrt(length**2 - span**2)
    return np.array([np.column_stack([span * s, 0.5 * sag * fraction * bow, (rise * fraction - sag) * bow])
                     for fraction in np.linspace(0.0, 1.0, poses)])


def report_sizes(poses: int | None, out: Path) -> None:
    """Run the demo (or a demo of `poses` poses), write everything, print the sizes."""
    travel = 4 * STEER_DEG + 4 * JOUNCE_MM  # degrees plus mm, one pose count per unit
    sweep = demo_sweep() if poses is None else demo_sweep(steps_per_degree=(poses - 1) / travel)
    result = run_sweep(sweep)
    started = time.perf_counter()
    write_sweep_report(result, out)
    print(f"\n{result.pose_count} poses: written in {time.perf_counter() - started:.2f} s to {out}")
    for path in sorted(out.iterdir()):
        print(f"  {path.name:22s} {path.stat().st_size / 1e6:8.3f} MB")


def envelope_figures(name: str, centerlines: np.ndarray, radius: float) -> None:
    """Time, peak memory and size of the envelope of `centerlines` (mm) with `radius` (mm)."""
    points = centerlines.reshape(-1, 3)
    dense = np.prod((points.max(axis=0) - points.min(axis=0) + 3.0 * radius) / (0.5 * radius))
    tracemalloc.start()
    started = time.perf_counter()
    envelope = swept_envelope(centerlines, radius)
    seconds = time.perf_counter() - started
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    print(f"  {name:34s} {seconds:6.2f} s  peak {peak / 2**20:6.0f} MB  {len(envelope.faces):7d} triangles  "
          f"cell {envelope.cell:.3g} mm (asked {envelope.requested_cell:.3g}, radius meshed {envelope.radius:.3g})  "
          f"dense grid would need {dense * DENSE_BYTES_PER_NODE / 1e9:7.2f} GB")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=601)
    parser.add_argument("--out", type=Path, default=None,
                        help="where to write the reports (default: a temporary folder)")
    options = parser.parse_args()

    swept_envelope(sagging_hoses(300.0, 200.0, 2, 10.0), 5.0)  # compiles the kernel
    with tempfile.TemporaryDirectory() as temporary:
        out = options.out or Path(temporary)
        report_sizes(None, out / "demo")
        report_sizes(options.poses, out / f"demo_{options.poses}")

    print("\nswept envelope")
    demo = run_sweep(demo_sweep())
    envelope_figures(f"demo ({demo.pose_count} poses)", demo.centerlines, demo.sweep.problem.hose.outer_radius)
    envelope_figures("3 m hose, 6 mm, moving 1 m", sagging_hoses(3000.0, 2000.0, 30, 1000.0), 3.0)
    envelope_figures("mounts 5 m apart, 2 mm cable", sagging_hoses(5000.0, 4990.0, 30, 200.0), 1.0)
    envelope_figures("10 m hose, 20 mm, 600 poses", sagging_hoses(10000.0, 9000.0, 600, 2000.0), 10.0)


if __name__ == "__main__":
    main()
