"""Benchmark: full placement of the thesis brake hose to 180 deg twist, hoseline against peers.

    python bench/run.py [--repeats 15] [--no-peers]

Prints one table (medians over repeated runs, single core) and the shape differences:
- hoseline at 50/100/200 segments: wall time per full placement (straight hose -> placed ->
  twisted 180 deg) with the uniqueness verdict (`solve`, what the command line runs) and without it
  (`place_only`, the bare placement a study's samples run), Newton iterations, time per iteration;
- PyElastica and MuJoCo (bench/peers/), 100 elements, driven along the same path as damped
  dynamics run to rest (stopped when the shape changes less than 0.01 mm), when they are
  installed (`pip install -e .[bench]`); each is warmed up first (Numba compilation), then
  timed --peer-repeats times (median);
- shape error of each against a fine reference (hoseline at 800 segments), as the largest
  distance between stations at equal arc length; the answer at 180 deg is not unique (two
  mirror images), so each shape is compared with the nearer image.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

for variable in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(variable, "1")  # one core, for every solver alike

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hoseline import Hose, Mount, Problem, solve  # noqa: E402
from hoseline.procedures.placement.sequence import place_only  # noqa: E402

TWIST_DEG = 180.0


def thesis_problem(segments: int) -> Problem:
    """The thesis brake hose (Goodyear5052), weightless, mounts of appendix A."""
    hose = Hose(
        length=330.6,
        outer_diameter=10.1,
        bending_stiffness=292.7985 * 510.8053,
        torsional_stiffness=96.12 * 25540.26,
        segments=segments,
    )
    return Problem(hose, Mount([-13.0, 0.0, -11.25], [0.0, 1.0, 0.0]), Mount([-173.064, -7.0, -11.25], [1.0, 0.0, 0.0]), TWIST_DEG)


def resample(points: np.ndarray, count: int = 101) -> np.ndarray:
    """Stations at equal arc-length fractions along a polyline (mm)."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    targets = np.linspace(0.0, s[-1], count)
    return np.column_stack([np.interp(targets, s, points[:, k]) for k in range(3)])


def shape_error(points: np.ndarray, references: list[np.ndarray]) -> float:
    """Largest station distance (mm) to the nearest of the reference shapes."""
    sampled = resample(points)
    return min(float(np.max(np.linalg.norm(sampled - resample(ref), axis=1))) for ref in references)


def time_hoseline(segments: int, repeats: int, estimate_error: bool = False):
    """Median seconds and the result of the placement; with estimate_error, the a-posteriori error
    estimate (one more Newton solve at half the segments) is included."""
    problem = thesis_problem(segments)
    solve(problem)  # compile and warm up
    times, result = [], None
    for _ in range(repeats):
        started = time.perf_counter()
        result = solve(problem, estimate_error=estimate_error)
        times.append(time.perf_counter() - started)
    return statistics.median(times), result


def time_bare(segments: int, repeats: int) -> float:
    """Median seconds of the bare placement (place_only: no verdict, no Result, no error estimate)."""
    problem = thesis_problem(segments)
    place_only(problem)
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        place_only(problem)
        times.append(time.perf_counter() - started)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--no-peers", action="store_true")
    parser.add_argument("--peer-repeats", type=int, default=3, help="timed runs of each peer (after a warm-up)")
    args = parser.parse_args()

    reference = solve(thesis_problem(800), alternatives=True)
    references = [reference.centerline] + [alt.centerline for alt in reference.alternatives]
    rows = []
    hoseline_100 = None
    estimate_rows = []
    bare_rows = []
    for segments in (50, 100, 200):
        median, result = time_hoseline(segments, args.repeats)
        bare = time_bare(segments, args.repeats)
        with_estimate, estimated = time_hoseline(segments, args.repeats, estimate_error=True)
        estimate_rows.append((segments, with_estimate * 1e3, estimated.discretisation_error,
                              shape_error(result.centerline, references)))
        if segments == 100:
            hoseline_100 = (median, result)
        rows.append(
            (
                f"hoseline {segments}",
                median * 1e3,
                f"{result.iterations} Newton",
                median * 1e6 / result.iterations,
                shape_error(result.centerline, references),
            )
        )
        bare_rows.append((segments, bare * 1e3))

    peer_rows = []
    if not args.no_peers:
        for name, module_name in (("PyElastica", "peers.pyelastica_peer"), ("MuJoCo", "peers.mujoco_peer")):
            try:
                module = __import__(module_name, fromlist=["run"])
            except ImportError as error:
                peer_rows.append((name, f"not installed ({error.name}); pip install -e .[bench]"))
                continue
            module.run(segments=10, twist_deg=TWIST_DEG, tol_mm=0.01)  # compile and warm up, as for hoseline
            runs = [module.run(segments=100, twist_deg=TWIST_DEG, tol_mm=0.01) for _ in range(args.peer_repeats)]
            outcome = sorted(runs, key=lambda run: run["wall_time"])[len(runs) // 2]  # the median run
            error = shape_error(np.asarray(outcome["centerline"]), references)
            vs_hoseline = shape_error(
                np.asarray(outcome["centerline"]),
                [hoseline_100[1].centerline] + [a.centerline for a in solve(thesis_problem(100), alternatives=True).alternatives],
            )
            rows.append((f"{name} 100", outcome["wall_time"] * 1e3, f"{outcome['sim_steps']} steps", float("nan"), error))
            peer_rows.append(
                (
                    name,
                    f"{outcome['wall_time'] / hoseline_100[0]:.0f}x the time of hoseline 100; "
                    f"shape differs from hoseline 100 by {vs_hoseline:.3f} mm; {outcome.get('notes', '')}",
                )
            )

    print(f"Thesis brake hose, placement to {TWIST_DEG:.0f} deg twist, one core, median of {args.repeats} runs "
          f"(load average {os.getloadavg()[0]:.2f} at the end)")
    print(f"{'solver':<16}{'time [ms]':>12}{'work':>18}{'us/iter':>10}{'shape error [mm]':>18}")
    for name, ms, work, per_iteration, error in rows:
        per = "" if per_iteration != per_iteration else f"{per_iteration:.0f}"
        print(f"{name:<16}{ms:>12.2f}{work:>18}{per:>10}{error:>18.4f}")
    print("shape error: largest distance to hoseline at 800 segments (nearer mirror image), 101 stations")
    print("hoseline rows: `solve` with the uniqueness verdict; the bare placement (place_only) without it:")
    for segments, ms in bare_rows:
        print(f"  hoseline {segments}: {ms:.2f} ms bare")
    print("with the a-posteriori error estimate (solve's default; the rows above leave it out):")
    for segments, ms, estimate, error in estimate_rows:
        print(f"  hoseline {segments}: {ms:.2f} ms, estimated error {estimate:.4f} mm (shape error above {error:.4f} mm)")
    for name, text in peer_rows:
        print(f"{name}: {text}")


if __name__ == "__main__":
    main()
