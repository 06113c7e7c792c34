"""Benchmark: a heavy hose lowered onto a floor, with contact against the same path without it.

    python bench/bench_contact.py [--repeats 5]

The case of tests/test_contact_floor.py (100 segments, 1000 mm, 0.5 kg/m): placed with its end high,
where it clears the floor, then the end carried to its mount.  Prints the median wall time of that
path with the contact Newton (mechanics/contact_newton.py; the hose lies on the floor at the end) and
with the plain Newton and no floor (the hose hangs through where the floor would be), their ratio,
the Newton iterations, and one contact Newton iteration's assembly and dense KKT solve, with the
machine's load.  The issue's targets (an obstacle of 100 000 triangles, self-contact on, sweeps at
1000 poses/s) need meshes and sweeps with contact, which are not written yet.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

for variable in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(variable, "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hoseline.mechanics.contact_newton import _kkt_step, evaluate_contact  # noqa: E402
from hoseline.model.hose import Hose  # noqa: E402
from hoseline.model.mounts import Mount  # noqa: E402
from hoseline.model.obstacles import Plane  # noqa: E402
from hoseline.model.problem import Problem  # noqa: E402
from hoseline.procedures.contact.continuation import follow_contact  # noqa: E402
from hoseline.procedures.contact.model import contact_model, reference_pressure  # noqa: E402
from hoseline.procedures.placement.continuation import ContinuationLog, follow  # noqa: E402
from hoseline.procedures.placement.sequence import place_only  # noqa: E402


def median_time(call, repeats: int) -> float:
    """Median wall time of call() in seconds over `repeats` runs (after one warm-up run)."""
    call()
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        call()
        times.append(time.perf_counter() - started)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    repeats = parser.parse_args().repeats
    hose = Hose(length=1000.0, outer_diameter=10.0, bending_stiffness=2e4, torsional_stiffness=2e4,
                mass_per_length=0.5, segments=100)
    down = np.array([0.0, 0.0, -1.0])
    problem = Problem(hose, Mount(np.array([-420.0, 0.0, 150.0]), down), Mount(np.array([300.0, 0.0, 500.0]), down),
                      gravity=np.array([0.0, 0.0, -9.81]))
    props, high, start, _ = place_only(problem)
    floor = Plane(np.zeros(3), np.array([0.0, 0.0, 1.0]), "floor")
    model = contact_model([floor], 5.0, props.segment_length, reference_pressure(0.5 * 9.81e-3, 2e4, 1000.0))
    end = np.array([420.0, 0.0, 150.0])

    def path(t):
        return replace(high, end_point=(1.0 - t) * high.end_point + t * end)

    counts = {}

    def with_contact():
        counts["contact"] = follow_contact("lower", path, props, start, model)[1]

    def without_contact():
        log = ContinuationLog()
        follow("lower", path, props, start, log)
        counts["plain"] = log.iterations

    contact_time = median_time(with_contact, repeats)
    plain_time = median_time(without_contact, repeats)
    state, _ = follow_contact("lower", path, props, start, model)
    final = path(1.0)
    iteration_time = median_time(lambda: _kkt_step(evaluate_contact(props, final, state, model)), 5 * repeats)
    print(f"load average {os.getloadavg()[0]:.2f} (1 min), {props.segments} segments, median of {repeats}")
    print(f"path with contact (floor): {contact_time * 1e3:8.1f} ms, {counts['contact']} Newton iterations")
    print(f"same path without contact: {plain_time * 1e3:8.1f} ms, {counts['plain']} Newton iterations")
    print(f"ratio: {contact_time / plain_time:.1f}x")
    print(f"one contact iteration (assembly + dense KKT): {iteration_time * 1e3:.2f} ms")


if __name__ == "__main__":
    main()
