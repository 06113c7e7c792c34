"""Benchmark: `compare` on scans of 1 and 5 million points, PLY binary and text: time, memory, accuracy.

    python bench/bench_scans.py [--sizes 1,5] [--repeats 3] [--no-reference] [--keep DIR]

The scans are synthetic scans (procedures/scans/synthetic_scan.py) of the thesis brake hose at
180 degrees of twist as a scanner export would hold them: seen from one side, with a 20 mm gap,
0.05 mm noise and 0.5 % stray points, as binary PLY (float32 x, y, z) and as text (x y z, four
decimals).  Each run is a fresh process, as `hoseline compare` is: it reads the scan, fits its
centreline, places the model and measures the deviation (no report drawn).  Printed per scan,
medians over the repeats: read, fit, placement and compare (all four) wall times, the compare's
CPU time (all threads: about the wall time on an idle machine, which a shared one is not) and
the largest peak memory; then the distance of the answer from the full-cloud answer (the same
fit with every point in the final cylinders instead of the voxel centroids, every_point=True):
largest distance between stations, and differences of the mean and largest deviation from the
model.  Then `hoseline compare` end to end (imports and report files included), once per file.
Targets for 5 M points: compare within 5 s, 2 GiB, answer within 0.01 mm.  Both cores are used,
as the command line uses them (the neighbour searches run in parallel).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

RADIUS = 5.05  # mm, the thesis hose
TWIST = 180.0  # degrees
GIB = 1024**3


def thesis_problem(segments: int):
    """The thesis brake hose with weight between the appendix A mounts, twisted 180 degrees."""
    from hoseline import Hose, Mount, Problem
    from hoseline.model.hose import isotropic_torsional_stiffness

    hose = Hose(length=330.6, outer_diameter=2 * RADIUS, bending_stiffness=149563.0, segments=segments,
                torsional_stiffness=25.0 * isotropic_torsional_stiffness(149563.0), mass_per_length=0.3)
    return Problem(hose, Mount([-13.0, 0.0, -11.25], [0.0, 1.0, 0.0]), Mount([-173.064, -7.0, -11.25], [1.0, 0.0, 0.0]),
                   TWIST, np.array([0.0, 0.0, -9.81]))


def write_scans(millions: float, folder: Path) -> None:
    """A scan of about `millions` million points as binary PLY (float32) and as text, and problem.toml, in `folder`."""
    from hoseline import solve
    from hoseline.io.problem_file import problem_to_toml

    (folder / "problem.toml").write_text(problem_to_toml(thesis_problem(40)))
    from hoseline.procedures.scans.synthetic_scan import ScanDefects, synthetic_scan

    truth = solve(thesis_problem(160))
    area = 2.0 * np.pi * RADIUS * truth.s[-1]
    defects = ScanDefects(density=2.0 * millions * 1e6 / area, noise=0.05, outlier_fraction=0.005,
                          view=(0.2, 0.3, -1.0), gaps=((150.0, 170.0),))  # one side seen: half the surface
    points = synthetic_scan(truth.s, truth.centerline, RADIUS, defects, seed=7).astype(np.float32)
    ply, text = folder / f"scan_{millions:g}M.ply", folder / f"scan_{millions:g}M.xyz"
    header = (f"ply\nformat binary_little_endian 1.0\ncomment synthetic scan, mm\nelement vertex {points.shape[0]}\n"
              "property float x\nproperty float y\nproperty float z\nend_header\n")
    ply.write_bytes(header.encode("ascii") + points.astype("<f4").tobytes())
    np.savetxt(text, points, fmt="%.4f")


def child(scan: str, every_point: bool) -> None:
    """One compare in this process; prints times (s), peak memory (bytes) and the answer as JSON."""
    from hoseline import solve
    from hoseline.io.scans import read_scan
    from hoseline.procedures.scans.centerline_fit import fit_centerline
    from hoseline.procedures.scans.validation import compare_scan

    problem = thesis_problem(40)
    started, cpu = time.perf_counter(), time.process_time()
    cloud = read_scan(scan)
    read = time.perf_counter()
    fit = fit_centerline(cloud, RADIUS, start_hint=problem.start.point, every_point=every_point)
    fitted = time.perf_counter()
    result = solve(problem)
    placed = time.perf_counter()
    comparison = compare_scan(result, cloud, Path(scan).stem, fit=fit)
    done = time.perf_counter()
    print(json.dumps({
        "read": read - started, "fit": fitted - read, "place": placed - fitted, "compare": done - started,
        "cpu": time.process_time() - cpu,
        "peak": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024, "points": cloud.shape[0],
        "stations": fit.points.tolist(), "mean": comparison.deviation.mean, "max": comparison.deviation.max,
        "radius": fit.radius_median,
    }))


def run_child(scan: Path, every_point: bool = False) -> dict:
    """child() in a fresh process."""
    command = [sys.executable, __file__, "--child", str(scan)] + (["--every-point"] if every_point else [])
    output = subprocess.run(command, check=True, capture_output=True, text=True).stdout
    return json.loads(output.strip().splitlines()[-1])


def run_cli(problem: Path, scan: Path, out: Path) -> tuple[float, int]:
    """`hoseline compare problem scan -o out --quiet`: wall time (s) and peak memory (bytes)."""
    command = [str(Path(sys.executable).with_name("hoseline")), "compare", str(problem), str(scan), "-o", str(out),
               "--quiet"]
    started = time.perf_counter()
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(process.pid, 0)
    wall = time.perf_counter() - started
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"{' '.join(command)} failed: {process.stderr.read().decode()}")
    return wall, usage.ru_maxrss * 1024


def accuracy(answer: dict, reference: dict) -> str:
    """Largest station distance and deviation differences of an answer from the reference, mm."""
    a, b = np.array(answer["stations"]), np.array(reference["stations"])
    distance = cKDTree(b).query(a)[0]
    return (f"{distance.max():.4f} {abs(answer['mean'] - reference['mean']):.4f} "
            f"{abs(answer['max'] - reference['max']):.4f}  ({a.shape[0]}/{b.shape[0]} stations)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="1,5", help="scan sizes, millions of points, comma-separated")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-reference", action="store_true", help="skip the full-cloud answer (~1 min per M points)")
    parser.add_argument("--keep", type=Path, help="write the scans here and keep them (default: a temporary folder)")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    parser.add_argument("--every-point", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--write", type=float, help=argparse.SUPPRESS)
    options = parser.parse_args()
    if options.child:
        child(options.child, options.every_point)
        return
    if options.write:
        write_scans(options.write, options.keep)
        return

    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start")
    with tempfile.TemporaryDirectory() as temporary:
        folder = options.keep or Path(temporary)
        folder.mkdir(parents=True, exist_ok=True)
        problem = folder / "problem.toml"
        print(f"{'scan':<18} {'points':>10} {'read':>7} {'fit':>7} {'place':>7} {'compare':>8} {'(CPU)':>8} "
              f"{'peak':>8}   from the full-cloud answer: station, mean, max (mm)")
        medians, answers = {}, {}
        for millions in (float(size) for size in options.sizes.split(",")):
            # Written by another process: a process started from this one reports at least this one's
            # memory as its peak (Linux carries the resident size over fork and exec), so this one stays small.
            subprocess.run([sys.executable, __file__, "--write", str(millions), "--keep", str(folder)], check=True)
            ply, text = folder / f"scan_{millions:g}M.ply", folder / f"scan_{millions:g}M.xyz"
            reference = None if options.no_reference else run_child(ply, every_point=True)
            for label, scan in ((f"{millions:g} M, PLY binary", ply), (f"{millions:g} M, text", text)):
                runs = [run_child(scan) for _ in range(options.repeats)]
                median = {key: float(np.median([r[key] for r in runs]))
                          for key in ("read", "fit", "place", "compare", "cpu")}
                peak = max(r["peak"] for r in runs)
                medians[label], answers[label] = median, runs[0]
                against = "" if reference is None else accuracy(runs[0], reference)
                times = " ".join(f"{median[key]:>{7 if key in ('compare', 'cpu') else 6}.2f}s"
                                 for key in ("read", "fit", "place", "compare", "cpu"))
                print(f"{label:<18} {runs[0]['points']:>10,} {times} {peak / GIB:>5.2f}GiB   {against}", flush=True)
            if reference is not None:
                print(f"{'':<18} full-cloud answer: fit {reference['fit']:.1f} s, peak {reference['peak'] / GIB:.2f} "
                      f"GiB; mean {reference['mean']:.4f} mm, max {reference['max']:.4f} mm, radius "
                      f"{reference['radius']:.4f} mm")
            for label, scan in ((f"{millions:g} M, PLY binary", ply), (f"{millions:g} M, text", text)):
                wall, peak = run_cli(problem, scan, folder / "out")
                print(f"hoseline compare, {label}: {wall:.2f} s wall (imports and report files included), peak "
                      f"{peak / GIB:.2f} GiB", flush=True)
        for kind in ("PLY binary", "text"):
            pair = [label for label in medians if label.endswith(kind)]
            for small, large in zip(pair, pair[1:]):
                print(f"{large} against {small}: compare {medians[large]['compare'] / medians[small]['compare']:.2f}x "
                      f"the time; answers (two scans of one shape) apart: {accuracy(answers[large], answers[small])}")
        print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
