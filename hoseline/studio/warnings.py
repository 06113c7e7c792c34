"""Warnings on the shape the studio shows, whether or not the problem file sets limits.

    kink      the inside bend radius (centreline radius less the outer radius) at zero or below: the hose is
              bent round a radius no larger than its own and its wall folds;
    bend      the inside bend radius below the hose's minimum (hose.min_bend_radius), or, where the file gives
              none, below TYPICAL_BEND_RADIUS_PER_OD outer diameters: rubber hydraulic and brake hose catalogues
              rarely allow less (their minimum bend radii run from about 3.5 to 10 outer diameters, e.g. 50 mm
              for a 13 mm hose; the thesis hose's assumed 35 mm is 3.5 of its 10.1 mm), so a tighter bend is
              worth checking against the catalogue whatever the hose;
    reaction  a mount's force above REACTION_FACTOR times the larger of the hose's weight and its Euler load
              pi^2 EI / L^2 (the force scales of a hose hanging under its weight and of one bent between its
              ends): such a force comes from the hose pulled nearly taut (or pushed far past buckling), not
              from routing it.

Units at the user boundary: mm, N.
"""

from __future__ import annotations

import math

import numpy as np

from hoseline.model.problem import Problem
from hoseline.procedures.placement.result import Result

TYPICAL_BEND_RADIUS_PER_OD = 3.0  # inside bend radius, in outer diameters, below which a bend is warned of
REACTION_FACTOR = 10.0  # a reaction this many times the hose's own force scale is warned of


def bend_limit(problem: Problem) -> dict:
    """The inside bend radius (mm) the shape is judged against: the hose's minimum, or the typical one; and
    whether the file gave it."""
    hose = problem.hose
    if hose.min_bend_radius is not None:
        return {"radius": hose.min_bend_radius, "given": True}
    return {"radius": TYPICAL_BEND_RADIUS_PER_OD * hose.outer_diameter, "given": False}


def force_scale(problem: Problem) -> dict:
    """The hose's own force scales, N: its weight (mass per length times its length and gravity) and its Euler load
    pi^2 EI / L^2 (EI the smaller bending stiffness, N*mm^2; L the free length, mm)."""
    hose = problem.hose
    stiffness = min(hose.bending_stiffness, hose.bending_stiffness_2 or hose.bending_stiffness)
    return {"weight": hose.mass_per_length * float(np.linalg.norm(problem.gravity)) * 1e-3 * hose.length,
            "euler": math.pi ** 2 * stiffness / hose.length ** 2}


def shape_warnings(problem: Problem, result: Result) -> list[dict]:
    """The warnings on `result` (the shape of `problem`): each {"kind": "kink" | "bend" | "reaction", "readout": the
    readout it concerns ("min_bend_radius", "start_reaction", "end_reaction"), "text": what to tell the user}."""
    found = []
    radius = result.min_bend_radius
    if math.isfinite(radius):
        at = float(result.s[int(np.argmax(result.curvature))])
        limit = bend_limit(problem)
        if radius <= 0.0:
            found.append({"kind": "kink", "readout": "min_bend_radius", "text": (
                f"kink: the bend radius to the inside of the bend is {radius:.3g} mm at s = {at:.4g} mm: the hose is "
                f"bent round less than its own radius ({problem.hose.outer_radius:g} mm) and its wall folds")})
        elif radius < limit["radius"]:
            why = ("the hose's minimum (hose.min_bend_radius)" if limit["given"] else
                   f"{TYPICAL_BEND_RADIUS_PER_OD:g} outer diameters, a typical catalogue minimum (the file gives no "
                   "hose.min_bend_radius: set the catalogue's)")
            found.append({"kind": "bend", "readout": "min_bend_radius", "text": (
                f"bend radius {radius:.3g} mm at s = {at:.4g} mm is below {limit['radius']:.3g} mm, {why}")})
    scales = force_scale(problem)
    largest = max(scales["weight"], scales["euler"])
    for end, force in (("start", result.start_force), ("end", result.end_force)):
        magnitude = float(np.linalg.norm(force))
        if magnitude > REACTION_FACTOR * largest:
            found.append({"kind": "reaction", "readout": f"{end}_reaction", "text": (
                f"{end} reaction {magnitude:.4g} N is over {REACTION_FACTOR:g} times the larger of the hose's weight "
                f"({scales['weight']:.3g} N) and its Euler load pi^2 EI/L^2 ({scales['euler']:.3g} N): the hose is "
                "pulled nearly taut")})
    return found
