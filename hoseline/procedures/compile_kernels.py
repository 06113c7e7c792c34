"""Compile the kernels a run needs before it starts: on an installation's first run, or when a worker starts.

compile_kernels() places a small hose the way solve() places any (the straight hose buckled,
carried to its mount, twisted; stability read at the end), which compiles, or loads from the
cache of hoseline/compilation.py, every kernel of a placement with the argument types every
placement uses; with clearance=True it also asks a clearance query (sweeps), with
stiffeners=True it places the hose with the thesis' stiffener springs (their kernels take other
argument types).  Kernels no part asked for compile when first used (clips, for one).

A worker of a cluster calls it once when it starts (for Dask: in a WorkerPlugin's setup).
Workers on one machine share the cache folder: the first compiles while the others wait for
it, then load.  Loading every kernel of a placement from the cache takes about 0.4 s of CPU.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from hoseline.compilation import compiling, is_compiled
from hoseline.model import Hose, Mount, Problem
from hoseline.model.stiffeners import thesis_preset
from hoseline.procedures.geometry.clearance import TriangleIndex
from hoseline.procedures.placement.sequence import solve

# The thesis brake hose, coarse: 16 segments give 48 unknowns, above the 40 from which the
# stability check runs its compiled iteration instead of a dense eigen-decomposition.
SMALL_PLACEMENT = Problem(
    Hose(length=330.6, outer_diameter=10.1, bending_stiffness=149563.0, torsional_stiffness=2454930.0, segments=16),
    Mount([-13.0, 0.0, -11.25], [0.0, 1.0, 0.0]),
    Mount([-173.064, -7.0, -11.25], [1.0, 0.0, 0.0]),
    180.0,
)


def compile_kernels(clearance: bool = False, stiffeners: bool = False) -> None:
    """Compile, or load from the cache, every kernel of a placement; with `clearance` those of a
    clearance query, with `stiffeners` those of a placement with stiffener springs."""
    with compiling("placement"):
        solve(SMALL_PLACEMENT)
    if clearance:
        with compiling("clearance"):
            triangle = np.array([[0.0, 0.0, 10.0], [1.0, 0.0, 10.0], [0.0, 1.0, 10.0]])
            TriangleIndex(triangle, np.array([[0, 1, 2]])).nearest(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]), 0.5)
    if stiffeners:
        with compiling("stiffeners"):  # untwisted: the twist path takes seconds with springs, and no other kernel
            preset = thesis_preset(SMALL_PLACEMENT.hose.length)
            hose = replace(SMALL_PLACEMENT.hose, segments=preset.segments, stiffeners=preset.stiffeners)
            solve(replace(SMALL_PLACEMENT, hose=hose, end_twist_deg=0.0))


def kernels_compiled(clearance: bool = False, stiffeners: bool = False) -> bool:
    """Whether compile_kernels(clearance, stiffeners) has already filled the cache for this version and CPU."""
    wanted = ("placement", "clearance" if clearance else None, "stiffeners" if stiffeners else None)
    return all(is_compiled(part) for part in wanted if part)
