"""The problem file that solves to the shape shown: the twists at assembly (the end fitting's, each fixed clip's) that
a fresh placement needs.

A fresh placement (procedures/placement/sequence.py) clamps the start of the hose at
frame_from_tangent(start.direction), locks the end's roll where the hose is torque-free at the
end of its place phase, and turns the end by the problem's twist from there.  The studio carries
the equilibrium through drags instead: the end keeps the roll it was locked at, moved with its
fitting (an out-of-plane drag clocks it against the roll a fresh assembly would lock), and a
start fitting turned about its own axis keeps that roll; so does a fixed clip, dragged or
turned.  The file has a field for neither roll but the twists (the end's, and a fixed clip's:
model/clips.py).  A hose of round section does not feel a roll of all its sections by one angle
(the shape and the energy stay), so the start's roll is moved onto the end and the fixed clips,
and the end's and each fixed clip's clocking against the fresh lock is added to its twist: the
saved problem, placed afresh, clamps the hose as shown.  A frame cannot tell whole turns of twist,
so whole turns more or less of the end's are tried.  Whether it gives the shape shown is checked
by placing it, never assumed: a hose that is not round or another branch of the path can still
differ, and the page then asks which to save.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from hoseline.mechanics.rotations import frame_from_tangent
from hoseline.model.problem import Problem
from hoseline.procedures.placement.continuation import PlacementError, Progress
from hoseline.procedures.placement.result import Result
from hoseline.procedures.placement.sequence import solve
from hoseline.procedures.placement.tracking import Fittings

SAVED_SHAPE_TOLERANCE = 0.1  # mm: a saved file whose fresh placement is this close to the shape shown saves it
SAME_TWIST = 1e-9  # degrees: a twist this close to the problem's is the problem's (no second placement)
WHOLE_TURNS = (0, 1, -1)  # tried in this order: frames cannot tell a whole turn of twist, the placed shape can


def saved_twists(problem: Problem, clamped: Fittings, fresh: Result, shown: np.ndarray,
                 progress: Progress | None = None) -> dict:
    """The twists at assembly to save (the end's, each fixed clip's) and how their fresh placement compares with the
    shape shown.

    problem: the problem shown.  clamped: where the hose is clamped now (start, end and clip frames,
    rows d1, d2, d3; the end frame with the twist).  fresh: the fresh placement of `problem`.
    shown: (N+1, 3) the stations shown, mm.  progress: passed to the placements (continuation.Progress).
    The twist is the problem's plus the change that
    clamps the ends as shown (clamp_change), give or take a whole turn (the first of WHOLE_TURNS
    whose placement is within SAVED_SHAPE_TOLERANCE, else the closest); each fixed clip's the
    problem's plus the change that holds it as shown (clip_twist_changes).  Returns {"twist",
    "twist_change" (degrees, signed), "clip_twists" (degrees, per clip of the problem; 0 for all
    but fixed clips), "distance" (mm, the largest between stations), "same"}, with "failed" (why)
    instead of "distance" when no such placement can be made.
    """
    change = clamp_change(clamped, fresh)
    turned = clip_twist_changes(problem, clamped, fresh)
    clip_twists = [clip.twist_deg + turn for clip, turn in zip(problem.clips, turned)]
    clips_same = all(abs(twist - clip.twist_deg) <= SAME_TWIST for clip, twist in zip(problem.clips, clip_twists))
    best = None
    for turns in WHOLE_TURNS:
        trial = change + 360.0 * turns
        try:
            placed = fresh if abs(trial) <= SAME_TWIST and clips_same else solve(
                saved_problem(problem, problem.end_twist_deg + trial, clip_twists), progress=progress)
        except PlacementError as exc:
            best = best or {"twist_change": trial, "failed": str(exc)}
            continue
        distance = float(np.max(np.linalg.norm(placed.centerline - shown, axis=1)))
        if best is None or "failed" in best or distance < best["distance"]:
            best = {"twist_change": trial, "distance": distance}
        if distance <= SAVED_SHAPE_TOLERANCE:
            break
    return {"twist": problem.end_twist_deg + best["twist_change"], **best, "clip_twists": clip_twists,
            "same": best.get("distance", math.inf) <= SAVED_SHAPE_TOLERANCE}


def saved_problem(problem: Problem, twist_deg: float, clip_twists: list[float]) -> Problem:
    """`problem` with the end's twist at assembly `twist_deg` and each clip's twist of `clip_twists` (degrees)."""
    return replace(problem, end_twist_deg=twist_deg,
                   clips=tuple(replace(clip, twist_deg=twist) for clip, twist in zip(problem.clips, clip_twists)))


def clamp_change(clamped: Fittings, fresh: Result) -> float:
    """The change of the twist at assembly (degrees, in (-180, 180]) with which a fresh placement clamps the hose's
    ends as `clamped` does, up to whole turns (`fresh`: the fresh placement at the twist as set, whose end frame is the
    fresh lock turned by that twist)."""
    end_clocking = _signed_angle(fresh.end_frame[0], clamped.end_frame[0], -clamped.end_frame[2])
    return math.remainder(end_clocking + _start_roll(clamped), 360.0)


def clip_twist_changes(problem: Problem, clamped: Fittings, fresh: Result) -> list[float]:
    """Per clip of `problem`, the change of a fixed clip's twist (degrees, in (-180, 180]) with which a fresh placement
    holds it as `clamped` does (its frame against the fresh one, which is the fresh lock turned by the clip's twist as
    set, less the start's roll that the saved file moves off the whole hose); 0 for the other kinds."""
    start_roll = _start_roll(clamped)
    return [math.remainder(_signed_angle(placed.frame[0], frame[0], frame[2]) - start_roll, 360.0)
            if clip.kind == "fixed" else 0.0
            for clip, placed, frame in zip(problem.clips, fresh.clips, clamped.clip_frames)]


def _start_roll(clamped: Fittings) -> float:
    """The start fitting's roll (degrees) about its direction from the frame a fresh placement clamps it at."""
    return _signed_angle(frame_from_tangent(clamped.start_frame[2])[0], clamped.start_frame[0], clamped.start_frame[2])


def _signed_angle(a: np.ndarray, b: np.ndarray, axis: np.ndarray) -> float:
    """Degrees turning the vector a onto b about the unit `axis` (both normal to it), in (-180, 180]."""
    return math.degrees(math.atan2(float(np.dot(np.cross(a, b), axis)), float(np.dot(a, b))))
