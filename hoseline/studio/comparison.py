"""How a fresh placement of the problem shown in the studio differs from the shape shown (the "place again" readout)."""

from __future__ import annotations

import math

import numpy as np

from hoseline.procedures.placement.result import Result

SAME_SHAPE = 1e-6  # of the length: a fresh placement closer than this is the shape shown


def placement_comparison(centerline: np.ndarray, end_frame: np.ndarray, placement: Result) -> dict:
    """How a fresh placement of the same problem differs from the shape shown.

    distance: mm, largest distance between stations.  clocking: degrees between the end
    fitting frames (non-zero when the hose was moved after assembly: its end keeps the roll it
    was locked at, a fresh assembly locks another).  same: within SAME_SHAPE of the length.
    (Session.compare_with_placement says {"same": False, "failed": why} when a fresh placement fails.)
    """
    distance = float(np.max(np.linalg.norm(placement.centerline - centerline, axis=1)))
    cosine = 0.5 * (float(np.trace(placement.end_frame.T @ end_frame)) - 1.0)  # of the angle between the frames
    clocking = math.degrees(math.acos(min(1.0, max(-1.0, cosine))))
    return {
        "distance": distance,
        "clocking": clocking,
        "same": distance <= SAME_SHAPE * placement.problem.hose.length,
        "unique": placement.unique,
        "lock_angle": placement.lock_angle_deg,
        "events": list(placement.events),
    }
