"""The smallest gap of the whole assembly to each obstacle, and where it is: the hose and its end fittings.

The contact model's own gaps (ContactModel.smallest_gaps) are those of the flexible hose, which the
barrier keeps out of every obstacle; the rigid end fittings (model/fittings.py) are held at the
mounts and not part of it, and a plane's station pairs leave out the start station (held, its gap
never changes).  An engineer reading "smallest gap" means the whole assembly, as the sweep's
clearance does (geometry/clearance.nearest_with_fittings): this module adds the fittings and the
start station, and finds where the smallest gap is by halving the chain of the nearest piece (the
smallest gap of a chain is that of the nearer half), to one segment of it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hoseline.mechanics.contact_motion import only
from hoseline.mechanics.contact_newton import ContactModel
from hoseline.model.problem import Problem

SEARCHED_BEYOND = 1e-6  # hose radii past the smallest gap that the halving's mesh searches look (rounding: the halves'
# gaps are the chain's to the last bits, but need not be found in the same order)


@dataclass(frozen=True)
class NearestGap:
    """The smallest gap (mm, surface to surface; negative where a fitting enters the obstacle) of one piece of the
    assembly to one obstacle: on, the piece ("hose", "start fitting", "end fitting"); arc_length, mm along the
    assembly from the start outlet at the middle of the nearest segment of that piece (negative on the start fitting,
    beyond the hose length on the end fitting, as the sweep's clearance)."""

    gap: float
    on: str
    arc_length: float


def nearest_gaps(problem: Problem, model: ContactModel, nodes: np.ndarray) -> dict[str, NearestGap]:
    """NearestGap per obstacle of `model` (not "self"): the hose with centreline `nodes` (N+1, 3) mm and the
    problem's end fittings."""
    pieces = [("hose", nodes, model.hose_radius)]
    if problem.fittings is not None:
        for which, port, fitting in problem.fittings.pieces():
            line = fitting.centreline(port)  # from the port to the outlet
            pieces.append((f"{which} fitting", line if which == "end" else line[::-1],
                           fitting.radius(problem.hose.outer_diameter)))
    obstacles = only(model, range(len(model.names)), self_contact=False)  # (not the hose against itself)
    gaps = [_chain_gaps(obstacles, points) for _, points, _ in pieces]
    nearest = {}
    for index, name in enumerate(model.names):
        chain_gap, gap, on, points = min(((gaps_of[name], gaps_of[name] + model.hose_radius - radius, on, points)
                                          for gaps_of, (on, points, radius) in zip(gaps, pieces)),
                                         key=lambda found: found[1])  # (the first of equal gaps)
        if not math.isfinite(gap):
            nearest[name] = NearestGap(gap, on, math.nan)
            continue
        middle = _along(points, _nearest_segment(only(model, [index], self_contact=False), points, chain_gap) + 0.5)
        if on == "start fitting":  # its points run from the outlet back to the port
            arc = -middle
        elif on == "end fitting":
            arc = problem.hose.length + middle
        else:
            arc = middle
        nearest[name] = NearestGap(gap, on, arc)
    return nearest


def _chain_gaps(model: ContactModel, points: np.ndarray, within: float = math.inf) -> dict[str, float]:
    """The smallest gap (mm) of the chain of capsules of the hose radius through `points` (K, 3) to each obstacle,
    its first point included (the model's plane pairs leave it out); inf for a mesh farther than `within` mm."""
    gaps = model.smallest_gaps(points, within)
    for row, owner in zip(model.planes, model.owners_planes):
        name = model.names[int(owner)]
        gaps[name] = min(gaps[name], float(np.dot(points[0] - row[:3], row[3:])) - model.hose_radius)
    return gaps


def _nearest_segment(alone: ContactModel, points: np.ndarray, smallest: float) -> int:
    """The index of the segment of the chain through `points` nearest the one obstacle of `alone` (no self-contact),
    whose smallest gap (mm, as _chain_gaps) is `smallest`, by halving: the nearer half (the first of equal ones) is
    kept.  A mesh is searched only within a hair (SEARCHED_BEYOND hose radii) of that gap: a half farther off gives
    inf, at a fraction of the cost of its own gap, and the one that holds it its exact gap."""
    first, last = 0, len(points) - 1
    within = smallest + SEARCHED_BEYOND * alone.hose_radius
    while last - first > 1:
        middle = (first + last) // 2
        if (min(_chain_gaps(alone, points[first:middle + 1], within).values())
                <= min(_chain_gaps(alone, points[middle:last + 1], within).values())):
            last = middle
        else:
            first = middle
    return first


def _along(points: np.ndarray, position: float) -> float:
    """mm along the polyline through `points` to the fractional point index `position`."""
    lengths = np.linalg.norm(np.diff(points, axis=0), axis=1)
    whole = int(math.floor(position))
    return float(np.sum(lengths[:whole]) + (position - whole) * lengths[min(whole, len(lengths) - 1)])
