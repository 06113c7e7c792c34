"""The heavy hose of issue 28 placed onto the floor its fittings point at: w L^3 / EI = 80 (L = 2000 mm,
EI = 1.6e5 N*mm^2, 0.163 kg/m), mounts 200 mm above the floor, in the x-z plane.  Used by the tests
(tests/test_contact_bring_in.py, against a free-boundary shooting solution) and the benchmark
(bench/bench_contact_placement.py)."""

from __future__ import annotations

import math

from hoseline.io.problem_file import problem_from_dict
from hoseline.model.problem import Problem

LENGTH, STIFFNESS, RADIUS = 2000.0, 1.6e5, 5.0  # mm, N*mm^2, mm
WEIGHT = 80.0 * STIFFNESS / LENGTH ** 3  # N/mm: w L^3 / EI = 80
GRAVITY = 9.81  # m/s^2

# (start (x, z) mm, start angle, end (x, z) mm, end angle): the hose's tangent leaving the start and arriving at the
# end (rad, from +x towards +z).  Fittings 60 degrees below horizontal towards the floor, 200 mm above it; and an
# asymmetric layout.  Both with the lying part in tension: with more slack it is pushed together and buckles sideways
# on the frictionless floor (mounts 850 mm from the middle: the hose lies in a loop 348 mm wide).
SYMMETRIC = ((-940.0, 200.0), -math.pi / 3, (940.0, 200.0), math.pi / 3)
ASYMMETRIC = ((-930.0, 200.0), -math.pi / 3, (950.0, 240.0), math.radians(50.0))


def floor_data(start, start_angle, end, end_angle, segments: int = 100) -> dict:
    """The problem file's tables (mm, degrees, kg/m) of the heavy hose between mounts (x, z) mm above the floor z = 0,
    leaving the start at start_angle and arriving at the end at end_angle (rad, from +x towards +z)."""
    return {"hose": {"length": LENGTH, "outer_diameter": 2 * RADIUS, "bending_stiffness": STIFFNESS,
                     "mass_per_length": WEIGHT * 1e3 / GRAVITY, "segments": segments},
            "start": {"point": [start[0], 0.0, start[1]],
                      "direction": [math.cos(start_angle), 0.0, math.sin(start_angle)]},
            "end": {"point": [end[0], 0.0, end[1]], "direction": [-math.cos(end_angle), 0.0, -math.sin(end_angle)]},
            "environment": {"gravity": [0.0, 0.0, -GRAVITY]},
            "contact": {"obstacles": [{"kind": "plane", "point": [0, 0, 0], "normal": [0, 0, 1], "name": "floor"}]}}


def floor_problem(layout=SYMMETRIC, segments: int = 100) -> Problem:
    """The Problem of floor_data for a layout (SYMMETRIC or ASYMMETRIC)."""
    return problem_from_dict(floor_data(*layout, segments))
