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
the hose as shown.  Whether it gives the shape shown is checked by placing it
(Session.compare_with_placement), never assumed: a hose that is not round, a fixed clip's locked
roll or another branch of the path can still differ, and the page then asks which to save.
"""

from __future__ import annotations

import math

import numpy as np

from hoseline.mechanics.rotations import frame_from_tangent
from hoseline.procedures.placement.result import Result
from hoseline.procedures.placement.tracking import Fittings

SAVED_SHAPE_TOLERANCE = 0.1  # mm: a saved file whose fresh placement is this close to the shape shown saves it


def assembly_twist(twist_deg: float, clamped: Fittings, fresh: Result) -> float:
    """The twist at assembly (degrees) with which a fresh placement clamps the hose's ends as `clamped` does.

    twist_deg: the problem's twist now, degrees.  clamped: where the hose is clamped now (its
    start and end frames, rows d1, d2, d3; the end frame with the twist).  fresh: the fresh
    placement of the same problem (its end frame is the fresh lock turned by twist_deg).  The
    change is taken the shorter way round each end (within +-180 degrees per end).
    """
    start_roll = _signed_angle(frame_from_tangent(clamped.start_frame[2])[0], clamped.start_frame[0],
                               clamped.start_frame[2])
    end_clocking = _signed_angle(fresh.end_frame[0], clamped.end_frame[0], -clamped.end_frame[2])
    return twist_deg + end_clocking + start_roll


def _signed_angle(a: np.ndarray, b: np.ndarray, axis: np.ndarray) -> float:
    """Degrees turning the vector a onto b about the unit `axis` (both normal to it), in (-180, 180]."""
    return math.degrees(math.atan2(float(np.dot(np.cross(a, b), axis)), float(np.dot(a, b))))
