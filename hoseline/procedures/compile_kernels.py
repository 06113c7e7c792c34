"""Compile the kernels a run needs before it starts: on an installation's first run, or when a worker starts.

compile_kernels() places a small hose the way solve() places any (the straight hose buckled,
carried to its mount, twisted; stability read at the end), which compiles, or loads from the
cache of hoseline/compilation.py, every kernel of a placement with the argument types every
placement uses; with clearance=True it also asks a clearance query (sweeps), with
stiffeners=True it places the hose with the thesis' stiffener springs (their kernels take other
argument types), with clips=True a hose held by a fixed and a sliding clip, with contact=True a
heavy hose that snaps down onto a floor (the contact Newton, its downhill mode and step filter,
with every kind of obstacle and self-contact), with preset=True the hose with a set (model/preset.py: its
rest rotations are another argument type), with braid=True the hose with a braid (mechanics/braid.py).
A hose with two of springs, a set and a braid at once compiles its combination on its first run.  `hoseline compile`
compiles every part; the Makefile runs it when it installs hoseline, as an ahead-of-time build would, so that the
first run after `make` compiles nothing.

On a machine with two cores or more, a first run compiles in two processes: this one compiles
the Newton iteration (newton_kernels), while a second compiles the stability check
(stability_kernels, with the factorisation it shares) and, when asked, the clearance query into the
same cache folder; the small placement then loads the stability check and compiles the little
left.  Both work on small made-up arrays of the types a placement passes (tests/test_compiled_cache.py
checks that a placement then adds no signature to them); a mismatch would cost only time.  Then, when
contact is asked, a second process compiles the other parts (clips above all) while this one compiles
contact, the longest, and loads them after.  The wait drops from the sum to about the longer of the
two, for some more CPU (each process compiles the NumPy functions its kernels use, and loads the
other's kernels).  bench/bench_compile_parts.py measures each part and the whole.

A worker of a cluster calls compile_kernels() once when it starts (for Dask: in a
WorkerPlugin's setup).  Workers on one machine share the cache folder: the first compiles
while the others wait for it, then load.  Loading every kernel of a placement from the cache
takes about 0.4 s of CPU.
"""

from __future__ import annotations

import os
import subprocess
import sys
from contextlib import contextmanager
from dataclasses import replace

import numpy as np

from hoseline.compilation import PACKAGE, compiling, is_compiled, persistent, version_folder
from hoseline.model import Hose, Mount, Problem
from hoseline.model.clips import Clip
from hoseline.model.braid import Braid
from hoseline.model.obstacles import Box, Cylinder, Mesh, Plane, Sphere
from hoseline.model.preset import Preset

# The solver's modules are imported by the functions that compile them: a run that finds its parts compiled
# (kernels_compiled) loads none of them here, only those it uses.

# The thesis brake hose, coarse: 16 segments give 48 unknowns, above the 40 from which the
# stability check runs its compiled iteration instead of a dense eigen-decomposition.
SMALL_PLACEMENT = Problem(
    Hose(length=330.6, outer_diameter=10.1, bending_stiffness=149563.0, torsional_stiffness=2454930.0, segments=16),
    Mount([-13.0, 0.0, -11.25], [0.0, 1.0, 0.0]),
    Mount([-173.064, -7.0, -11.25], [1.0, 0.0, 0.0]),
    180.0,
)


SMALL_PRESET = Preset(curvature=1.0 / 250.0, angle_deg=-40.0)  # a set of 250 mm radius
SMALL_BRAID = Braid(angle_deg=38.0, strands=12, strand_axial_stiffness=1500.0, slack_strain=0.005)  # strands engage


def _grid_sheet(cells: int, corner: list[float], size: float) -> Mesh:
    """A square sheet of cells x cells squares, 2 triangles each, `size` mm wide, in a plane z = corner[2]."""
    ticks = np.linspace(0.0, size, cells + 1)
    x, y = np.meshgrid(ticks, ticks, indexing="ij")
    vertices = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)]) + corner
    i, j = np.meshgrid(np.arange(cells), np.arange(cells), indexing="ij")
    a = (i * (cells + 1) + j).ravel()
    faces = np.vstack([np.column_stack([a, a + cells + 1, a + 1]), np.column_stack([a + 1, a + cells + 1, a + cells + 2])])
    return Mesh(vertices, faces, "sheet")


# A heavy hose, too long to hang clear of the floor below its mounts: the place phase loses stability and the
# hose snaps down onto the floor (the contact Newton, its downhill mode); the other obstacles lie out of reach,
# which still compiles their kernels (the argument types are those of any contact model): the sheet of 2048
# triangles those of the leaf lists (mechanics/contact_mesh.LISTED_TRIANGLES), the box those of a small mesh.
CONTACT_PLACEMENT = Problem(
    Hose(length=400.0, outer_diameter=8.0, bending_stiffness=500.0, torsional_stiffness=385.0, mass_per_length=0.5,
         segments=16),
    Mount([0.0, 0.0, 100.0], [1.0, 0.0, 0.0]),
    Mount([150.0, 0.0, 100.0], [-1.0, 0.0, 0.0]),
    0.0,
    gravity=np.array([0.0, 0.0, -9.81]),
    contact=(Plane(np.zeros(3), np.array([0.0, 0.0, 1.0]), "floor"),
             Sphere(np.array([0.0, 500.0, 0.0]), 10.0, "sphere"),
             Cylinder(np.array([0.0, -500.0, 0.0]), np.array([100.0, -500.0, 0.0]), 10.0, "cylinder"),
             Box(np.array([500.0, 0.0, 50.0]), np.array([20.0, 20.0, 20.0]), name="box"),
             _grid_sheet(32, [-500.0, -500.0, 600.0], 100.0)),
    self_contact=True,
)


def compile_kernels(clearance: bool = False, stiffeners: bool = False, clips: bool = False,
                    contact: bool = False, preset: bool = False, braid: bool = False) -> None:
    """Compile, or load from the cache, every kernel of a placement; with `clearance` those of a
    clearance query, with `stiffeners` those of a placement with stiffener springs, with `clips`
    those of a placement with clips, with `contact` those of a placement with contact, with `preset`
    those of a hose with a set, with `braid` those of a braided hose."""
    from hoseline.procedures.placement.sequence import solve

    asked = {"clearance": clearance, "stiffeners": stiffeners, "clips": clips, "contact": contact, "preset": preset,
             "braid": braid}
    with compiling("placement"):
        if not is_compiled("placement"):
            # the clearance query shares no kernel with a placement: the second process compiles it too
            with _second_process(["stability_kernels()"] + (["_compile_part('clearance')"] if clearance else [])):
                newton_kernels()
        solve(SMALL_PLACEMENT)
    # contact takes about as long as the other parts together: while this process compiles it, a second one
    # compiles those; this one then loads them from the cache (so that it holds every kernel, as without the second)
    rest = [part for part, wanted in asked.items() if wanted and part != "contact"]
    beside = [part for part in rest if not is_compiled(part)]
    if contact:
        with _second_process([f"_compile_part({part!r})" for part in beside] if not is_compiled("contact") else []):
            _compile_part("contact")
    for part in rest:
        _compile_part(part)


def _compile_part(part: str) -> None:
    # compile_kernels' `part` (beyond the placement), under its lock; from the cache when already compiled
    from hoseline.mechanics.contact_motion import moved_model
    from hoseline.model.motion import Pose
    from hoseline.model.stiffeners import thesis_preset
    from hoseline.procedures.contact.placement import problem_contact_model
    from hoseline.procedures.geometry.clearance import TriangleIndex
    from hoseline.procedures.placement.sequence import solve

    with compiling(part):
        if part == "clearance":
            triangle = np.array([[0.0, 0.0, 10.0], [1.0, 0.0, 10.0], [0.0, 1.0, 10.0]])
            TriangleIndex(triangle, np.array([[0, 1, 2]])).nearest(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]), 0.5)
        elif part == "stiffeners":  # untwisted: the twist path takes seconds with springs, and no other kernel
            springs = thesis_preset(SMALL_PLACEMENT.hose.length)
            hose = replace(SMALL_PLACEMENT.hose, segments=springs.segments, stiffeners=springs.stiffeners)
            solve(replace(SMALL_PLACEMENT, hose=hose, end_twist_deg=0.0))
        elif part == "clips":
            solve(replace(SMALL_PLACEMENT, clips=small_clips()), estimate_error=False)
        elif part == "contact":
            solve(CONTACT_PLACEMENT, estimate_error=False)
            # without the sheet, its meshes are small: their searches walk the trees in one call (walked_mesh_pairs)
            small = problem_contact_model(replace(CONTACT_PLACEMENT, contact=CONTACT_PLACEMENT.contact[:-1]))
            small.pairs(np.linspace([0.0, 0.0, 100.0], [150.0, 0.0, 100.0], 17), small.activation)
            model = problem_contact_model(CONTACT_PLACEMENT)  # a sweep's obstacles moved with their bodies
            moved_model(model, [Pose(position=np.array([1.0, 0.0, 0.0]))] * len(model.names))
        elif part == "preset":
            solve(replace(SMALL_PLACEMENT, hose=replace(SMALL_PLACEMENT.hose, preset=SMALL_PRESET)))
        elif part == "braid":
            solve(replace(SMALL_PLACEMENT, hose=replace(SMALL_PLACEMENT.hose, braid=SMALL_BRAID)))
        else:
            raise ValueError(f"no part {part!r} to compile")


def small_clips() -> tuple[Clip, Clip]:
    """A fixed clip a third along SMALL_PLACEMENT's shape and a sliding one two thirds along (where they sit)."""
    from hoseline.procedures.placement.sequence import solve

    placed = solve(SMALL_PLACEMENT, estimate_error=False)
    h = SMALL_PLACEMENT.hose.segment_length
    held = []
    for kind, station in (("fixed", 5), ("sliding", 11)):
        tangent = placed.frames[station - 1, 2] + placed.frames[station, 2]
        held.append(Clip(kind, placed.centerline[station], station * h, tangent))
    return tuple(held)


def kernels_compiled(clearance: bool = False, stiffeners: bool = False, clips: bool = False,
                     contact: bool = False, preset: bool = False, braid: bool = False) -> bool:
    """Whether compile_kernels(clearance, stiffeners, clips, contact, preset, braid) has already filled the cache
    for this version and CPU."""
    wanted = {"placement": True, "clearance": clearance, "stiffeners": stiffeners, "clips": clips, "contact": contact,
              "preset": preset, "braid": braid}
    return all(is_compiled(part) for part, asked in wanted.items() if asked)


def newton_kernels() -> None:
    """Compile the Newton iteration, both kinds (solve_equilibrium), on a small bent hose."""
    from hoseline.mechanics.newton import RodProperties, solve_equilibrium
    from hoseline.mechanics.rod import Clamps, RodState, centerline
    from hoseline.mechanics.rotations import rotate_frames

    segments = 16
    bend = np.outer(np.linspace(0.0, 1.0, segments), [0.2, 0.0, 0.0])  # rad about x, growing along the hose
    frames = rotate_frames(np.tile(np.eye(3), (segments, 1, 1)), bend)
    nodes = centerline(frames, np.zeros(3), 1.0)
    props = RodProperties(np.full(3, 1e4), 1.0, segments)
    clamps = Clamps(np.zeros(3), np.eye(3), nodes[-1], frames[-1].copy(), True, np.zeros(3))
    for minimise in (False, True):
        solve_equilibrium(props, clamps, RodState(frames, np.zeros(3)), max_iterations=1, minimise=minimise)


def stability_kernels() -> None:
    """Compile the stability check (smallest_eigenpairs) on a made-up Hessian of 48 unknowns, enough
    for its compiled iteration."""
    from hoseline.mechanics.energy import BANDWIDTH
    from hoseline.mechanics.stability import smallest_eigenpairs

    unknowns = 48
    band = np.zeros((unknowns, BANDWIDTH + 1))
    band[:, 0] = np.arange(1.0, unknowns + 1.0)
    jac_t = np.zeros((unknowns, 3))
    jac_t[:3] = np.eye(3)
    smallest_eigenpairs(band, jac_t, count=1)


@contextmanager
def _second_process(calls: list[str]):
    # run `calls` (calls of this module's functions, in turn) in another process during the body, into the same
    # cache folder, when there is a second core and a cache that outlives the process; wait for it after
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    if not calls or cores < 2 or not persistent():
        yield
        return
    search_path = os.pathsep.join(filter(None, [str(PACKAGE.parent), os.environ.get("PYTHONPATH")]))  # this hoseline
    environment = {**os.environ, "NUMBA_CACHE_DIR": str(version_folder().parent), "PYTHONPATH": search_path}
    names = sorted({call.split("(")[0] for call in calls})
    code = f"from {__name__} import {', '.join(names)}; " + "; ".join(calls)
    helper = subprocess.Popen([sys.executable, "-c", code], env=environment,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        yield
    finally:
        helper.wait()  # a failed helper only costs time: this process compiles what it lacks
