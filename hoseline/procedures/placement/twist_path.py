"""A placed hose twisted step by step: its shape at every step and whether it moves smoothly.

The thesis saw its 8-spring stiffener model jump during the twist from 0 to 180 deg
("the hose model traveled much further during twisting from 100-160 deg"); a model that
moves smoothly between its end states earns more trust at the angles in between.  The
hose is placed at 0 deg, then the end fitting is turned through the given angles by
continuation (with the stability checks of continuation.py), recording the shape at each.
A step is a jump when its largest station movement exceeds JUMP_FACTOR times the median
step and JUMP_FLOOR mm.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from hoseline.mechanics.newton import node_positions
from hoseline.mechanics.rod import Clamps, RodState
from hoseline.model.problem import Problem
from hoseline.procedures.placement.continuation import ContinuationLog, PlacementError, StepControl, follow
from hoseline.procedures.placement.path import PlacementPath
from hoseline.procedures.placement.sequence import rod_properties, solve

JUMP_FACTOR = 3.0
JUMP_FLOOR = 1.0  # mm


@dataclass
class TwistPath:
    """Shapes of one hose model along a twist.

    label: name in reports.  twists_deg: (k,) twist of each recorded shape, degrees.
    centerlines: (k, N+1, 3) mm.  steps: (k-1,) largest station movement from one recorded
    shape to the next, mm.  events: the continuation's log (branch switches, snaps).
    failure: why the twist could not be followed further ("" when it reached the last angle).
    """

    label: str
    twists_deg: np.ndarray
    centerlines: np.ndarray
    steps: np.ndarray
    events: list[str] = field(default_factory=list)
    failure: str = ""

    @property
    def jumps(self) -> list[tuple[float, float]]:
        """(twist at the end of the step, degrees; movement, mm) of every sudden step."""
        limit = max(JUMP_FACTOR * float(np.median(self.steps)), JUMP_FLOOR)
        return [(float(t), float(m)) for t, m in zip(self.twists_deg[1:], self.steps) if m > limit]

    @property
    def smooth(self) -> bool:
        """No sudden step and no failure along the twist."""
        return not self.jumps and not self.failure


def follow_twist(problem: Problem, twists_deg: np.ndarray, label: str) -> TwistPath:
    """Place `problem`'s hose at 0 deg, then twist it through `twists_deg` (increasing, from 0), recording each shape.

    A twist step that cannot be followed ends the path there (TwistPath.failure says why).
    """
    if problem.clips:  # the twisted clamps below hold the two fittings only
        raise ValueError("a twist path of a problem with clips is not supported yet")
    twists_deg = np.asarray(twists_deg, dtype=float)
    placed = solve(replace(problem, end_twist_deg=0.0))
    props = rod_properties(problem)
    path = PlacementPath(problem)
    state = RodState(placed.frames, placed.end_force)
    log = ContinuationLog()
    shapes = [placed.centerline]
    failure = ""

    def clamps_at(twist_deg: float) -> Clamps:
        return path.twisted(placed.end_frame, twist_deg)

    for low, high in zip(twists_deg[:-1], twists_deg[1:]):
        try:
            state = follow(f"twist {low:g}-{high:g} deg", lambda t: clamps_at(low + t * (high - low)), props, state,
                           log, control=StepControl(first=1.0, largest=1.0))
        except PlacementError as exc:
            failure = str(exc)
            break
        shapes.append(node_positions(props, clamps_at(high), state))
    centerlines = np.stack(shapes)
    steps = np.max(np.linalg.norm(np.diff(centerlines, axis=0), axis=2), axis=1)
    recorded = twists_deg[: len(shapes)]
    return TwistPath(label, recorded, centerlines, steps, list(placed.events) + log.events, failure)
