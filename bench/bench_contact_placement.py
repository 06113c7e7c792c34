"""Placement with contact from a problem file, against the same hose without: median wall time of 5 solves.

Cases (tests/test_contact_placement.py): a weightless hose (335 mm, 50 segments) whose free arch passes
through a drum (cylinder of radius 30 mm), placed without contact, with the drum, and with the drum and
self-contact on; and a planar loop closing on itself (1000 mm between coaxial mounts 150 mm apart, self-contact,
50 segments; once, it takes tens of seconds); and the plectoneme (tests/test_contact_selfloop.py): 200 mm
between coaxial mounts 100 mm apart twisted 720 deg, which snaps (the contact Newton's downhill mode) into a
loop touching itself (once, about 10 s).  Run: python bench/bench_contact_placement.py [--loop] [--plectoneme]
"""

import sys
import time

import numpy as np

from hoseline.io.problem_file import problem_from_dict
from hoseline.procedures.placement.sequence import solve

BASE = {"hose": {"length": 335.0, "outer_diameter": 10.0, "bending_stiffness": 1e5, "segments": 50},
        "start": {"point": [-100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]},
        "end": {"point": [100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]}}
DRUM = {"kind": "cylinder", "start": [0.0, -200.0, 0.0], "end": [0.0, 200.0, 0.0], "radius": 30.0, "name": "drum"}
LOOP = {"hose": {"length": 1000.0, "outer_diameter": 10.0, "bending_stiffness": 1e5, "torsional_stiffness": 1e5,
                 "segments": 50},
        "start": {"point": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0]},
        "end": {"point": [150.0, 2.0, 0.0], "direction": [-1.0, 0.0, 0.0]}, "contact": {"self": True}}

PLECTONEME = {"hose": {"length": 200.0, "outer_diameter": 4.0, "bending_stiffness": 1e5, "torsional_stiffness": 8e4,
                       "segments": 40},
              "start": {"point": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0]},
              "end": {"point": [100.0, 0.0, 0.0], "direction": [-1.0, 0.0, 0.0], "twist": 720.0},
              "contact": {"self": True}}


def main() -> None:
    cases = [("no contact", BASE), ("drum", BASE | {"contact": {"obstacles": [DRUM]}}),
             ("drum and self-contact", BASE | {"contact": {"self": True, "obstacles": [DRUM]}})]
    for label, data in cases:
        problem = problem_from_dict(data)
        result = solve(problem, estimate_error=False)  # compiles
        times = []
        for _ in range(5):
            started = time.perf_counter()
            result = solve(problem, estimate_error=False)
            times.append(time.perf_counter() - started)
        print(f"{label:24s} median {1e3 * np.median(times):8.1f} ms  {result.iterations:5d} Newton iterations  "
              f"{result.steps:4d} steps")
    if "--loop" in sys.argv:
        started = time.perf_counter()
        result = solve(problem_from_dict(LOOP), estimate_error=False)
        contact = result.contacts[0]
        print(f"{'loop closing on itself':24s} once   {time.perf_counter() - started:8.1f} s   {result.iterations:5d} Newton "
              f"iterations  {result.steps:4d} steps; smallest gap {contact.min_gap:.4f} mm, "
              f"push {float(np.linalg.norm(contact.total_force)):.3f} N at s = {contact.arc_length} mm")
    if "--plectoneme" in sys.argv:
        started = time.perf_counter()
        result = solve(problem_from_dict(PLECTONEME), estimate_error=False)
        contact = result.contacts[0]
        snaps = sum("snaps downhill" in event for event in result.events)
        print(f"{'plectoneme (720 deg)':24s} once   {time.perf_counter() - started:8.1f} s   {result.iterations:5d} Newton "
              f"iterations  {result.steps:4d} steps, {snaps} snap(s); smallest gap {contact.min_gap:.4f} mm, "
              f"stable {result.stable}")


if __name__ == "__main__":
    main()
