"""Clips: intermediate supports that hold the hose at a station between its two mounts.

A clip holds the hose at `arc_length` mm from the start fitting, at `point` (mm):
- fixed: position, direction and roll held (a clamped bracket);
- rotating: position and direction held, the hose may roll about the clip axis (a loose sleeve);
- sliding: position and direction held, the hose may roll about the clip axis and slide along it
  (a frictionless guide ring): the arc length at the clip is found by the solve, `arc_length` is
  only where the placement starts it (rounded to the nearest station);
- ball: position held only (a loop of wire).
`direction` (fixed, rotating and sliding clips) is the hose's tangent through the clip, from the
start side to the end side.  A fixed, rotating or ball clip sits on a station of the discrete
hose: its arc length must be a whole number of segments (clip_node says which and, if not, what
to change).  A fixed clip's `twist_deg` turns it from the torque-free roll the placement locks it at,
right-handed about its direction, as the end's twist turns the end fitting (in the placement's twist
phase, procedures/placement/path.py): a bracket clamped on a hose already twisted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hoseline.model.mounts import unit_vector

CLIP_KINDS = ("fixed", "rotating", "sliding", "ball")
FRAMED_KINDS = ("fixed", "rotating", "sliding")  # the kinds that hold the hose's direction
ON_STATION = 1e-9  # relative to the segment length: an arc length this close to a station is on it


@dataclass(frozen=True)
class Clip:
    """One clip.  kind: one of CLIP_KINDS.  point: (3,) mm.  arc_length: mm from the start fitting.
    direction: unit tangent of the hose through the clip (fixed, rotating, sliding), None for a ball
    clip.  name: free text for reports.  For a sliding clip arc_length is the starting guess.
    twist_deg: a fixed clip's turn from its torque-free locked roll, degrees, right-handed about direction."""

    kind: str
    point: np.ndarray
    arc_length: float
    direction: np.ndarray | None = None
    name: str = ""
    twist_deg: float = 0.0

    def __post_init__(self) -> None:
        label = f"clip {self.name!r}" if self.name else "clip"
        if self.kind not in CLIP_KINDS:
            raise ValueError(f"{label}: type = {self.kind!r}: must be one of {', '.join(CLIP_KINDS)}")
        p = np.asarray(self.point, dtype=float).reshape(-1)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"{label}: point = {list(p)}: must be three finite coordinates in mm")
        object.__setattr__(self, "point", p)
        if not math.isfinite(self.arc_length):
            raise ValueError(f"{label}: arc_length = {self.arc_length!r}: must be a finite length in mm")
        if self.kind in FRAMED_KINDS:
            if self.direction is None:
                raise ValueError(f"{label}: a {self.kind} clip holds the hose's direction: give direction = [x, y, z]")
            object.__setattr__(self, "direction", unit_vector(self.direction, f"{label} direction"))
        elif self.direction is not None:
            raise ValueError(f"{label}: a ball clip holds the position only: remove direction")
        if not math.isfinite(self.twist_deg):
            raise ValueError(f"{label}: twist = {self.twist_deg!r}: must be a finite angle in degrees")
        if self.twist_deg != 0.0 and self.kind != "fixed":
            raise ValueError(f"{label}: twist = {self.twist_deg:g}: only a fixed clip holds the hose's roll (a "
                             f"{self.kind} clip lets it roll): remove twist or make the clip fixed")

    @property
    def holds_direction(self) -> bool:
        return self.kind in FRAMED_KINDS

    @property
    def slides(self) -> bool:
        """The arc length at the clip is an unknown (a sliding clip)."""
        return self.kind == "sliding"


def clip_node(arc_length: float, length: float, segments: int) -> int | None:
    """The station index of a clip at `arc_length` mm on a hose of `length` mm cut into
    `segments`, or None if it falls between stations."""
    position = arc_length * segments / length
    node = round(position)
    return node if abs(position - node) <= ON_STATION * max(1.0, position) else None


def off_station_message(label: str, arc_length: float, length: float, segments: int) -> str:
    """Why a clip's arc length does not fit the segment count, and the nearest fixes."""
    h = length / segments
    below, above = math.floor(arc_length / h) * h, math.ceil(arc_length / h) * h
    counts = [n for n in range(max(4, segments // 2), 4 * segments + 1) if clip_node(arc_length, length, n) is not None]
    fix = f", or hose.segments = {min(counts, key=lambda n: abs(n - segments))}" if counts else ""
    usable = " or ".join(f"{s:.6g}" for s in (below, above) if 0.0 < s < length - 0.5 * h)
    return (f"{label}: arc_length = {arc_length:g} mm is not at a station of the {segments}-segment hose "
            f"(stations every {h:g} mm): use arc_length = {usable} mm{fix}")
