"""The problem file that solves to the shape shown: the end fitting's twist at assembly that a fresh placement needs.

A fresh placement (procedures/placement/sequence.py) clamps the start of the hose at
frame_from_tangent(start.direction), locks the end's roll where the hose is torque-free at the
end of its place phase, and turns the end by the problem's twist from there.  The studio carries
the equilibrium through drags instead: the end keeps the roll it was locked at, moved with its
fitting (an out-of-plane drag clocks it against the roll a fresh assembly would lock), and a
start fitting turned about its own axis keeps that roll.  The file has a field for neither roll
but the twist.  A hose of round section does not feel a roll of all its sections by one angle
(the shape and the energy stay), so the start's roll is moved onto the end, and the end's
clocking against the fresh lock is added to the twist: the saved problem, placed afresh, clamps
the hose as shown.  A frame cannot tell whole turns of twist, so whole turns more or less are tried.
Whether it gives the shape shown is checked by placing it, never assumed: a hose that is not round, a fixed clip's locked
roll or another branch of the path can still differ, and the page then asks which to save.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from hoseline.mechanics.rotations import frame_from_tangent
from hoseline.model.problem import Problem
from hoseline.procedures.placement.continuation import PlacementError
from hoseline.procedures.placement.result import Result
from hoseline.procedures.placement.sequence import solve
from hoseline.procedures.placement.tracking import Fittings

SAVED_SHAPE_TOLERANCE = 0.1  # mm: a saved file whose fresh placement is this close to the shape shown saves it
SAME_TWIST = 1e-9  # degrees: a twist this close to the problem's is the problem's (no second placement)
WHOLE_TURNS = (0, 1, -1)  # tried in this order: frames cannot tell a whole turn of twist, the placed shape can


def saved_twist(problem: Problem, clamped: Fittings, fresh: Result, shown: np.ndarray) -> dict:
    """The twist at assembly to save and how its fresh placement compares with the shape shown.

    problem: the problem shown.  clamped: where the hose is clamped now (start and end frames,
    rows d1, d2, d3; the end frame with the twist).  fresh: the fresh placement of `problem`.
    shown: (N+1, 3) the stations shown, mm.  The twist is the problem's plus the change that
    clamps the ends as shown (clamp_change), give or take a whole turn (the first of WHOLE_TURNS
    whose placement is within SAVED_SHAPE_TOLERANCE, else the closest).  Returns {"twist",
    "twist_change" (degrees, signed), "distance" (mm, the largest between stations), "same"}, with
    "failed" (why) instead of "distance" when no such placement can be made.
    """
    change = clamp_change(clamped, fresh)
    best = None
    for turns in WHOLE_TURNS:
        trial = change + 360.0 * turns
        try:
            placed = fresh if abs(trial) <= SAME_TWIST else solve(replace(problem, end_twist_deg=problem.end_twist_deg + trial))
        except PlacementError as exc:
            best = best or {"twist_change": trial, "failed": str(exc)}
            continue
        distance = float(np.max(np.linalg.norm(placed.centerline - shown, axis=1)))
        if best is None or "failed" in best or distance < best["distance"]:
            best = {"twist_change": trial, "distance": distance}
        if distance <= SAVED_SHAPE_TOLERANCE:
            break
    return {"twist": problem.end_twist_deg + best["twist_change"], **best,
            "same": best.get("distance", math.inf) <= SAVED_SHAPE_TOLERANCE}


def clamp_change(clamped: Fittings, fresh: Result) -> float:
    """The change of the twist at assembly (degrees, in (-180, 180]) with which a fresh placement clamps the hose's
    ends as `clamped` does, up to whole turns (`fresh`: the fresh placement at the twist as set, whose end frame is the
    fresh lock turned by that twist)."""
    start_roll = _signed_angle(frame_from_tangent(clamped.start_frame[2])[0], clamped.start_frame[0],
                               clamped.start_frame[2])
    end_clocking = _signed_angle(fresh.end_frame[0], clamped.end_frame[0], -clamped.end_frame[2])
    return math.remainder(end_clocking + start_roll, 360.0)


def _signed_angle(a: np.ndarray, b: np.ndarray, axis: np.ndarray) -> float:
    """Degrees turning the vector a onto b about the unit `axis` (both normal to it), in (-180, 180]."""
    return math.degrees(math.atan2(float(np.dot(np.cross(a, b), axis)), float(np.dot(a, b))))
