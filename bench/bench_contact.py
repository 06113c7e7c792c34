"""Benchmark: a heavy hose lowered onto a floor, with contact against the same path without it.

    python bench/bench_contact.py [--repeats 5]

The case of tests/test_contact_floor.py (100 segments, 1000 mm, 0.5 kg/m): placed with its end high,
where it clears the floor, then the end carried to its mount.  Prints the median wall time of that
path with the contact Newton (mechanics/contact_newton.py; the hose lies on the floor at the end) and
with the plain Newton and no floor (the hose hangs through where the floor would be), their ratio,
the Newton iterations; a sweep-like sequence of 200 poses, the end mount moved 0.25 mm sideways
between poses, each solved from the last (poses/s, with contact and without); one contact Newton
iteration at rest on the floor: its assembly, the banded + low-rank KKT solve (contact_solve.py)
and the dense one it replaced (LAPACK sytrf), and how many solves fell back to the dense one; with
the machine's load.  The issue's other targets (an obstacle of 100 000 triangles, self-contact on)
need meshes, which are not written yet.
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

from threadpoolctl import threadpool_limits  # noqa: E402

from timing import median_time  # noqa: E402
from hoseline.mechanics.contact_newton import _kkt_step, evaluate_contact, solve_with_contact  # noqa: E402
from hoseline.mechanics.contact_solve import dense_step, kkt_solves  # noqa: E402
from hoseline.mechanics.newton import solve_equilibrium  # noqa: E402
from hoseline.model.hose import Hose  # noqa: E402
from hoseline.model.mounts import Mount  # noqa: E402
from hoseline.model.obstacles import Plane  # noqa: E402
from hoseline.model.problem import Problem  # noqa: E402
from hoseline.procedures.contact.continuation import follow_contact  # noqa: E402
from hoseline.procedures.contact.model import contact_model, reference_pressure  # noqa: E402
from hoseline.procedures.placement.continuation import ContinuationLog, follow  # noqa: E402
from hoseline.procedures.placement.sequence import place_only  # noqa: E402


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

    kkt_solves.clear()
    contact_time = median_time(with_contact, repeats)
    solves = dict(kkt_solves)
    plain_time = median_time(without_contact, repeats)
    state, _ = follow_contact("lower", path, props, start, model)
    final = path(1.0)
    plain_state = follow("lower", path, props, start, ContinuationLog())

    poses = [replace(final, end_point=final.end_point + np.array([0.0, 0.25 * k, 0.0])) for k in range(1, 201)]

    def sweep(solve, first):
        current, iterations = first, 0
        for clamps in poses:
            current, report = solve(clamps, current)
            if not report.converged:
                raise RuntimeError(f"sweep pose failed: {report.message}")
            iterations += report.iterations
        counts["sweep"] = iterations

    sweep_contact = median_time(lambda: sweep(lambda c, s: solve_with_contact(props, c, s, model, tolerance=1e-9), state),
                                repeats)
    sweep_contact_iterations = counts["sweep"]
    sweep_plain = median_time(lambda: sweep(lambda c, s: solve_equilibrium(props, c, s), plain_state), repeats)
    system = evaluate_contact(props, final, state, model)
    with threadpool_limits(1):
        assembly_time = median_time(lambda: evaluate_contact(props, final, state, model), 5 * repeats)
        solve_time = median_time(lambda: _kkt_step(system), 5 * repeats)
        dense_time = median_time(lambda: dense_step(system.dense(), system.jac_t, system.grad, system.constraint),
                                 5 * repeats)
    print(f"load average {os.getloadavg()[0]:.2f} (1 min), {props.segments} segments, median of {repeats}")
    print(f"path with contact (floor): {contact_time * 1e3:8.1f} ms, {counts['contact']} Newton iterations")
    print(f"same path without contact: {plain_time * 1e3:8.1f} ms, {counts['plain']} Newton iterations")
    print(f"ratio: {contact_time / plain_time:.1f}x")
    print(f"sweep of {len(poses)} poses with contact: {len(poses) / sweep_contact:8.0f} poses/s, "
          f"{sweep_contact_iterations} Newton iterations; without: {len(poses) / sweep_plain:8.0f} poses/s")
    print(f"one contact iteration at rest ({len(system.pairs[0])} pairs, rank {system.columns.shape[1]}): assembly "
          f"{assembly_time * 1e3:.3f} ms, banded + low-rank KKT {solve_time * 1e3:.3f} ms "
          f"(dense assembly + sytrf {dense_time * 1e3:.3f} ms)")
    print(f"KKT solves on the path: {solves.get('banded', 0)} banded, {solves.get('dense', 0)} dense fall-backs")


if __name__ == "__main__":
    main()
