"""Placement with contact from a problem file, against the same hose without: median wall time of 5 solves.

Cases (tests/test_contact_placement.py): a weightless hose (335 mm, 50 segments) whose free arch passes
through a drum (cylinder of radius 30 mm), placed without contact, with the drum (brought in after the free
placement), with the drum and self-contact on, and with the drum present along the whole path (placement =
"along_path"); the heavy hose of hoseline/demos/floor.py placed onto the floor its fittings point at (symmetric and
asymmetric), against the same hose without the floor, and with the forces refined to 0.5 % (the default of a file
without hose.segments, force_accuracy.py; the error estimate included); and a planar loop closing on itself (1000 mm between coaxial mounts 150 mm apart, self-contact,
50 segments; once); and the plectoneme (tests/test_contact_selfloop.py, tests/test_contact_fold.py): 200 mm
between coaxial mounts 100 mm apart twisted 720 and 1080 deg, which snaps (the contact Newton's downhill mode) at its
folds and losses of stability (median of 5).  Each case also gives its failed path tries (Newton tries of the contact
continuation that did not converge, counted in one more solve: contact_breakdown.failed_tries).  --mesh: the issue's case, the thesis hose (100 segments, 180 deg
of twist) with one fixed clip at station 50 and self-contact, pushed 1 mm aside by a strut (a cylinder of
radius 15 mm meshed with 100 000 triangles) at station 25, against the same hose with the clip and no
contact, and with the strut as an analytic cylinder; with --sweep also each one's sweep of 200 poses, the end
fitting moved 10 mm down (poses per second of the solver, median of 3 sweeps).  --mesh placements: median of 3
solves after a first one (whose time, the kernels loaded from Numba's cache and the mesh packed included, is shown
apart; later solves take the packing kept for the same mesh, contact_mesh.pack_meshes), and the median time of
packing the mesh afresh.  --breakdown: each placement with contact once more, timed by part
(contact_breakdown.py: the path's converged and failed steps, walks downhill, narrowings; the mesh searches, and
what the placement would take were they free).  Run:
python bench/bench_contact_placement.py [--loop] [--plectoneme] [--mesh [--sweep] [--sphere] [--breakdown]]
"""

import math
import os
import sys
import time
from dataclasses import replace

import numpy as np
import trimesh

from contact_breakdown import breakdown, failed_tries
from hoseline.demos.floor import ASYMMETRIC, SYMMETRIC, floor_data
from hoseline.model.problem import DEFAULT_FORCE_ACCURACY
from hoseline.demos.thesis_hose import demo_problem
from hoseline.io.problem_file import problem_from_dict
from hoseline.mechanics.contact_mesh import _packed_meshes
from hoseline.model.clips import Clip
from hoseline.model.motion import Translation, generated_motion
from hoseline.model.obstacles import Cylinder, Mesh, Sphere
from hoseline.model.sweep import SweepProblem
from hoseline.procedures.placement.sequence import solve
from hoseline.procedures.sweep.quasi_static import run_sweep

BASE = {"hose": {"length": 335.0, "outer_diameter": 10.0, "bending_stiffness": 1e5, "segments": 50},
        "start": {"point": [-100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]},
        "end": {"point": [100.0, 0.0, -80.0], "direction": [0.0, 0.0, 1.0]}}
DRUM = {"kind": "cylinder", "start": [0.0, -200.0, 0.0], "end": [0.0, 200.0, 0.0], "radius": 30.0, "name": "drum"}
LOOP = {"hose": {"length": 1000.0, "outer_diameter": 10.0, "bending_stiffness": 1e5, "torsional_stiffness": 1e5,
                 "segments": 50},
        "start": {"point": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0]},
        "end": {"point": [150.0, 2.0, 0.0], "direction": [-1.0, 0.0, 0.0]}, "contact": {"self": True}}

# --sweep: the end fitting moved 10 mm down in 200 poses (0.05 mm a pose), the hose held by its clip and the strut
SWEEP_MOTION = Translation(np.array([0.0, 0.0, -1.0]), (0.0, 10.0), steps=199, name="drop")

BALL_RADIUS = 20.0  # mm, of --sphere's ball

PLECTONEME = {"hose": {"length": 200.0, "outer_diameter": 4.0, "bending_stiffness": 1e5, "torsional_stiffness": 8e4,
                       "segments": 40},
              "start": {"point": [0.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0]},
              "end": {"point": [100.0, 0.0, 0.0], "direction": [-1.0, 0.0, 0.0], "twist": 720.0},
              "contact": {"self": True}}


def strut(centre: np.ndarray, axis: np.ndarray, radius: float, length: float, around: int, rows: int) -> Mesh:
    """An open cylinder of `radius` mm about `axis` through `centre`, `length` mm long, 2 around rows triangles."""
    axis = axis / np.linalg.norm(axis)
    side = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    side /= np.linalg.norm(side)
    other = np.cross(axis, side)
    angles = 2.0 * np.pi * np.arange(around) / around
    heights = np.linspace(-0.5 * length, 0.5 * length, rows + 1)
    ring = radius * (np.cos(angles)[:, None] * side + np.sin(angles)[:, None] * other)
    vertices = (centre + heights[:, None, None] * axis + ring[None]).reshape(-1, 3)
    j, i = np.meshgrid(np.arange(rows), np.arange(around), indexing="ij")
    p, q = (j * around + i).ravel(), (j * around + (i + 1) % around).ravel()
    faces = np.vstack([np.column_stack([p, q, q + around]), np.column_stack([p, q + around, p + around])])
    return Mesh(vertices, faces, "strut")


def strut_cases():
    """The thesis hose (100 segments, 180 deg) with a fixed clip at station 50 (no contact), and pushed 1 mm aside at
    station 25 by a strut of radius 15 mm meshed with 100 000 triangles, self-contact on; the same with the strut as
    an analytic cylinder; the clipped hose's placement and the side (unit vector) the strut stands on.  Also the studio
    benchmark's case with contact (bench_studio.py)."""
    plain = demo_problem(180.0, segments=100)
    free = solve(plain)
    h = plain.hose.segment_length
    clip = Clip("fixed", free.centerline[50], 50 * h, free.frames[49, 2] + free.frames[50, 2])
    clipped = replace(plain, clips=(clip,))
    placed = solve(clipped, estimate_error=False)
    tangent = placed.frames[24, 2] + placed.frames[25, 2]
    side = -np.cross(tangent, placed.frames[25, 0])  # on the other side (+t x d1) the clip's path runs through it
    side /= np.linalg.norm(side)
    radius = 15.0
    centre = placed.centerline[25] + side * (plain.hose.outer_radius + radius - 1.0)  # 1 mm into the free shape
    axis = np.cross(tangent, side) / np.linalg.norm(np.cross(tangent, side))
    obstacle = strut(centre, axis, radius, 200.0, 500, 100)
    touching = replace(clipped, contact=(obstacle,), self_contact=True)
    round_strut = replace(touching, contact=(Cylinder(centre - 100.0 * axis, centre + 100.0 * axis, radius, "strut"),))
    return clipped, touching, round_strut, placed, side


def mesh_case() -> None:
    """The thesis hose with a fixed clip, without contact and with a 100 000-triangle strut and self-contact."""
    clipped, touching, round_strut, placed, side = strut_cases()
    plain, [obstacle] = demo_problem(180.0, segments=100), touching.contact
    print(f"thesis hose, 100 segments, 180 deg, fixed clip at station 50; strut of {obstacle.faces.shape[0]} triangles; "
          f"load average {os.getloadavg()[0]:.1f}")
    cases = [("clip, no contact", clipped), ("clip, cylinder, self-contact", round_strut),
             ("clip, mesh strut, self-contact", touching)]
    if "--sphere" in sys.argv:  # a ball of radius 20 mm in the strut's place, 1 mm into the free shape, and meshed finely
        ball_centre = placed.centerline[25] + side * (plain.hose.outer_radius + BALL_RADIUS - 1.0)
        ball = trimesh.creation.icosphere(subdivisions=6, radius=BALL_RADIUS)  # 81 920 triangles
        cases += [("clip, sphere, self-contact", replace(touching, contact=(Sphere(ball_centre, BALL_RADIUS, "ball"),))),
                  (f"clip, icosphere ({ball.faces.shape[0]}), self-c.",
                   replace(touching, contact=(Mesh(ball.vertices + ball_centre, ball.faces, "ball"),)))]
    plain_time = math.nan  # s, the median without contact (the first case), for --breakdown's ratios
    for label, problem in cases:
        started = time.perf_counter()  # the first in this process: the contact kernels loaded from Numba's cache
        result = solve(problem, estimate_error=False)
        first = time.perf_counter() - started
        times = []
        for _ in range(3):  # each a new problem, whose mesh packing (its trees) is kept from the first
            started = time.perf_counter()
            solve(problem, estimate_error=False)
            times.append(time.perf_counter() - started)
        gap = result.summary().get("contact", {}).get("min_gap_mm")
        failed = failed_tries(lambda: solve(problem, estimate_error=False))
        print(f"{label:32s} median {1e3 * np.median(times):8.1f} ms (first {1e3 * first:.0f} ms)  {result.iterations:5d} "
              f"Newton iterations  {result.steps:4d} steps, {failed} failed"
              + (f"; smallest gap {gap:.4f} mm" if gap is not None else ""), flush=True)
        if "--breakdown" in sys.argv and problem.contact:
            print_breakdown(breakdown(lambda: solve(problem, estimate_error=False)), float(np.median(times)), plain_time)
        elif not problem.contact:
            plain_time = float(np.median(times))
        if "--sweep" in sys.argv:  # median of 3 sweeps (each places the hose first: not in the figure)
            sweeps = [run_sweep(SweepProblem(problem, None, "arm", (generated_motion("arm", [SWEEP_MOTION]),),
                                             compare_free_roll=False)) for _ in range(3)]
            rates = [sweep.performance()["poses per second (solver)"] for sweep in sweeps]
            print(f"{'':32s} sweep of {sweeps[0].pose_count} poses: {np.median(rates):8.0f} poses/s (median of 3; "
                  f"{min(rates):.0f}-{max(rates):.0f}), "
                  f"{sweeps[0].performance()['Newton iterations per pose']:.1f} Newton iterations per pose", flush=True)
    packing = []
    for _ in range(3):
        started = time.perf_counter()
        _packed_meshes([obstacle.triangles()], [0])
        packing.append(time.perf_counter() - started)
    print(f"packing the strut's mesh afresh (its trees, merged vertices, patches, edges): median "
          f"{1e3 * np.median(packing):.0f} ms")
    print(f"load average {os.getloadavg()[0]:.1f}")


def print_breakdown(figures: dict, median: float, plain_time: float) -> None:
    """The lines of --breakdown: contact_breakdown.breakdown's figures of one solve, and as multiples of the placement
    without contact (plain_time, s) the median (s) scaled by the share left were the mesh searches free, and were the
    path steps that do not converge free as well."""
    seconds, counts = figures["seconds"], figures["counts"]
    total = seconds["total"]
    print(f"{'':32s} one solve timed by part: {1e3 * total:.0f} ms, {counts.get('evaluations', 0)} evaluations for "
          f"{figures['iterations']} Newton iterations")
    for part in ("path steps, converged", "path steps, not converged", "walks downhill", "narrowings and polish",
                 "mesh searches"):
        if part in seconds:
            calls = (", ".join(f"{name.split()[-1]} {count}" for name, count in counts.items()
                               if name.startswith("mesh search")) if part == "mesh searches" else
                     f"{counts[part]} calls, {counts[part + ': Newton iterations']} Newton iterations, mesh searches "
                     f"{1e3 * seconds.get(part + ': mesh searches', 0.0):.1f} ms")
            print(f"{'':34s}{part:26s} {1e3 * seconds[part]:7.1f} ms ({100 * seconds[part] / total:4.1f} %): {calls}")
    searches = seconds.get("mesh searches", 0.0)
    failed = seconds.get("path steps, not converged", 0.0) - seconds.get("path steps, not converged: mesh searches", 0.0)
    for label, left in (("the mesh searches free", total - searches),
                        ("those and the path steps that do not converge free", total - searches - failed)):
        print(f"{'':34s}were {label}: {left / total * median / plain_time:.1f}x the placement without contact")


def main() -> None:
    if "--mesh" in sys.argv:
        mesh_case()
        return
    drum_along = {"placement": "along_path", "obstacles": [DRUM]}
    floor_free = {key: value for key, value in floor_data(*SYMMETRIC).items() if key != "contact"}
    cases = [("no contact", BASE), ("drum", BASE | {"contact": {"obstacles": [DRUM]}}),
             ("drum and self-contact", BASE | {"contact": {"self": True, "obstacles": [DRUM]}}),
             ("drum, along the path", BASE | {"contact": drum_along}),
             ("floor: no contact", floor_free), ("floor (symmetric)", floor_data(*SYMMETRIC)),
             ("floor (asymmetric)", floor_data(*ASYMMETRIC))]
    for label, data in cases:
        problem = problem_from_dict(data)
        result = solve(problem, estimate_error=False)  # compiles
        times = []
        for _ in range(5):
            started = time.perf_counter()
            result = solve(problem, estimate_error=False)
            times.append(time.perf_counter() - started)
        failed = failed_tries(lambda: solve(problem, estimate_error=False)) if problem.contact else 0
        print(f"{label:24s} median {1e3 * np.median(times):8.1f} ms  {result.iterations:5d} Newton iterations  "
              f"{result.steps:4d} steps, {failed} failed")
    for label, layout in (("symmetric", SYMMETRIC), ("asymmetric", ASYMMETRIC)):  # the default of a file without segments
        problem = problem_from_dict(floor_data(*layout))
        times = []
        for _ in range(5):
            started = time.perf_counter()
            result = solve(problem, force_accuracy=DEFAULT_FORCE_ACCURACY)
            times.append(time.perf_counter() - started)
        refinement = result.force_refinement
        print(f"{f'floor ({label}), 0.5 %':24s} median {1e3 * np.median(times):8.1f} ms  segments "
              f"{' -> '.join(map(str, refinement.segments))}, estimated {100 * refinement.estimated:.2g} % (with the "
              "error estimate: the default of hoseline solve on a file without hose.segments)")
    if "--loop" in sys.argv:
        started = time.perf_counter()
        result = solve(problem_from_dict(LOOP), estimate_error=False)
        contact = result.contacts[0]
        failed = failed_tries(lambda: solve(problem_from_dict(LOOP), estimate_error=False))
        print(f"{'loop closing on itself':24s} once   {time.perf_counter() - started:8.1f} s   {result.iterations:5d} Newton "
              f"iterations  {result.steps:4d} steps, {failed} failed; smallest gap {contact.min_gap:.4f} mm, "
              f"push {float(np.linalg.norm(contact.total_force)):.3f} N at s = {contact.arc_length} mm")
    if "--plectoneme" in sys.argv:  # twisted two and three turns, median of 5 solves after a first
        for turns in (2, 3):
            problem = problem_from_dict(PLECTONEME | {"end": PLECTONEME["end"] | {"twist": 360.0 * turns}})
            result = solve(problem, estimate_error=False)
            times = []
            for _ in range(5):
                started = time.perf_counter()
                solve(problem, estimate_error=False)
                times.append(time.perf_counter() - started)
            contact = result.contacts[0]
            snaps = sum("snaps downhill" in event for event in result.events)
            failed = failed_tries(lambda: solve(problem, estimate_error=False))
            print(f"{f'plectoneme ({360 * turns} deg)':24s} median {1e3 * np.median(times):8.1f} ms  {result.iterations:5d} "
                  f"Newton iterations  {result.steps:4d} steps, {failed} failed, {snaps} snap(s); smallest gap "
                  f"{contact.min_gap:.4f} mm, energy {result.elastic_energy:.3f} N*mm, stable {result.stable}")
    print(f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
