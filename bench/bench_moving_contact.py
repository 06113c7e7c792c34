"""Benchmark: a sweep of a hose lying on a floor that moves with a body, against the same floor fixed.

    python bench/bench_moving_contact.py [--poses 100] [--floor plane|box] [--repeats 3] [--triangles 100000]

The heavy hose of bench_contact.py (1000 mm, 100 segments, 0.5 kg/m, EI 2e4 N*mm^2) between
horizontal mounts 700 mm apart, 200 mm up, lying on a floor at z = 0 (a [contact] plane, or a box of
12 triangles, a mesh).  The end mount moves 100 mm sideways and 20 mm up over the poses.  Moving: the
floor moves with the end mount (it rises 20 mm, lifting the hose; procedures/contact/moving.py);
fixed: the floor stays.  Prints the median poses per second of the solver (without the placement
at design position; after a warm-up sweep that compiles), Newton iterations per pose, the load; and
the time to carry a mesh obstacle of about --triangles triangles to a pose (mechanics/contact_motion.
moved_model: its arrays moved, its trees refitted) against packing it again there (the trees rebuilt).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

for variable in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(variable, "1")

import numpy as np  # noqa: E402
import trimesh  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import median_time  # noqa: E402
from hoseline.io.sweep_file import sweep_from_dict  # noqa: E402
from hoseline.mechanics.contact_motion import moved_model  # noqa: E402
from hoseline.model.motion import Pose, axis_angle_matrix  # noqa: E402
from hoseline.model.obstacles import Mesh  # noqa: E402
from hoseline.procedures.contact.model import contact_model  # noqa: E402
from hoseline.procedures.sweep.quasi_static import run_sweep  # noqa: E402

FLOORS = {"plane": {"kind": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0]},
          "box": {"kind": "box", "center": [0.0, 0.0, -5.0], "size": [3000.0, 3000.0, 10.0]}}


def sweep_file(poses: int, floor: str, moving: bool) -> dict:
    """The sweep file of the benchmark (see the module doc)."""
    return {"hose": {"length": 1000.0, "outer_diameter": 10.0, "bending_stiffness": 2e4, "torsional_stiffness": 2e4,
                     "mass_per_length": 0.5, "segments": 100},
            "start": {"point": [-350.0, 0.0, 200.0], "direction": [1.0, 0.0, 0.0]},
            "end": {"point": [350.0, 0.0, 200.0], "direction": [-1.0, 0.0, 0.0], "body": "arm"},
            "environment": {"gravity": [0.0, 0.0, -9.81]},
            "contact": {"obstacles": [dict(FLOORS[floor], name="floor", **({"body": "arm"} if moving else {}))]},
            "bodies": [{"name": "arm", "stages": [{"name": "shift", "translate": [0.0, float(np.hypot(100.0, 20.0))],
                                                   "axis": [0.0, 100.0, 20.0], "steps": poses - 1}]}],
            "sweep": {"compare_free_roll": False}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=100)
    parser.add_argument("--floor", choices=sorted(FLOORS), default="plane")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--triangles", type=int, default=100_000)
    arguments = parser.parse_args()
    run_sweep(sweep_from_dict(sweep_file(5, arguments.floor, True)))  # compiles
    for moving in (True, False):
        rates, iterations = [], 0.0
        for _ in range(arguments.repeats):
            result = run_sweep(sweep_from_dict(sweep_file(arguments.poses, arguments.floor, moving)))
            rates.append(result.performance()["poses per second (solver)"])
            iterations = result.performance()["Newton iterations per pose"]
            [floor] = result.contacts
            assert np.all(floor.min_gap >= 0.0) and np.linalg.norm(floor.total_force[-1]) > 0.0
        print(f"{arguments.floor} floor {'moving with the end' if moving else 'fixed':20s}: "
              f"{np.median(rates):7.1f} poses/s, {iterations:.1f} Newton iterations per pose, "
              f"snaps {len(result.snaps)}")
    carry_mesh(arguments.triangles, arguments.repeats)
    print(f"load {os.getloadavg()[0]:.1f}")


def carry_mesh(triangles: int, repeats: int) -> None:
    """Print the time to carry a sphere mesh of about `triangles` triangles to a pose, and to pack it there anew."""
    subdivisions = max(1, int(round(np.log(triangles / 20.0) / np.log(4.0))))
    ball = trimesh.creation.icosphere(subdivisions=subdivisions, radius=40.0)
    pose = Pose(axis_angle_matrix(np.array([0.0, 0.6, 0.8]), 0.3), np.array([5.0, -2.0, 1.0]))
    model = contact_model([Mesh(ball.vertices, ball.faces, "ball")], 5.0, 10.0, 1.0)
    carried = median_time(lambda: moved_model(model, [pose]), repeats)
    packed = median_time(lambda: contact_model([Mesh(pose.points(ball.vertices), ball.faces, "ball")], 5.0, 10.0, 1.0),
                         repeats)
    print(f"a mesh of {len(ball.faces)} triangles carried to a pose: {1e3 * carried:.1f} ms; "
          f"packed again there: {1e3 * packed:.1f} ms")


if __name__ == "__main__":
    main()
