"""The discrete rod's state and boundary conditions, in internal units (mm, N, rad).

RodState holds the unknowns (one frame per segment) and the multiplier (end force);
Clamps holds what the continuation prescribes (fitting frames, end point, weight).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit


@dataclass
class Clamps:
    """Boundary data of one equilibrium problem.

    start_point: mm.  start_frame: 3x3 frame (rows d1, d2, d3) of the start fitting, d3
    along the hose tangent.  end_point (mm) and end_frame: the end fitting, or both None
    for a free tip.  roll_free: the end frame may spin about its d3 (zero torque about the
    hose axis).  line_weight: (3,) weight per length vector, N/mm.  end_load: (3,) dead
    load on a free tip, N.
    """

    start_point: np.ndarray
    start_frame: np.ndarray
    end_point: np.ndarray | None
    end_frame: np.ndarray | None
    roll_free: bool
    line_weight: np.ndarray
    end_load: np.ndarray = field(default_factory=lambda: np.zeros(3))
    clips: tuple["ClipHold", ...] = ()

    @property
    def end_clamped(self) -> bool:
        return self.end_point is not None


@dataclass(frozen=True)
class ClipHold:
    """One intermediate support of the rod (mechanics/clipped.py), in internal units.

    node: station index k (1 <= k <= N-1) held, at arc length k h.  point: (3,) mm, where the
    station is held.  frame: (3, 3) clip frame (rows d1, d2, d3; d3 along the hose) or None for
    a ball clip (position only).  roll_free: the frame may spin about its d3 (a rotating clip,
    or any framed clip while it is carried to its place).  sliding: the hose may slide through
    the clip (a guide ring, framed and roll free): its arc length is an unknown
    (RodState.clip_arc_lengths) and the segments of the spans next to the node stretch to put
    the node there (mechanics/clipped.py, stretch_terms).
    """

    node: int
    point: np.ndarray
    frame: np.ndarray | None
    roll_free: bool
    sliding: bool = False


@dataclass
class RodState:
    """Unknowns of the rod: segment frames (N,3,3), end-mount force mu (N), end roll (rad, accumulated).

    With clips (Clamps.clips): clip_forces (c, 3), the force of each clip on the hose (N), and
    clip_rolls (c,), the roll of each clip frame about its axis (rad, accumulated; used while
    the clip's roll is free).  Empty without clips; a solve starts them at zero if they do not
    match the clamps' clips.  clip_arc_lengths (c,): the arc length of each clip, mm (an unknown
    of sliding clips); a solve starts them at the clips' stations if they do not match.
    """

    frames: np.ndarray
    end_force: np.ndarray
    roll: float = 0.0
    clip_forces: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    clip_rolls: np.ndarray = field(default_factory=lambda: np.zeros(0))
    clip_arc_lengths: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def copy(self) -> "RodState":
        return RodState(self.frames.copy(), self.end_force.copy(), self.roll, self.clip_forces.copy(),
                        self.clip_rolls.copy(), self.clip_arc_lengths.copy())


@njit(cache=True)
def centerline(frames, start_point, h):
    """Node positions (N+1, 3) in mm: x_0 = start point, x_{i+1} = x_i + h d3_i."""
    n = frames.shape[0]
    out = np.empty((n + 1, 3))
    for k in range(3):  # element by element: a row assignment compiles Numba's shape-error messages
        out[0, k] = start_point[k]
    for i in range(n):
        for k in range(3):  # element by element: a vector expression here would allocate per segment
            out[i + 1, k] = out[i, k] + h * frames[i, 2, k]
    return out


@njit(cache=True)
def segment_loads(frames, end_force, line_weight, h):
    """w_i = h * (end force + weight of the hose beyond segment i's centre), N*mm; see energy.py."""
    n = frames.shape[0]
    out = np.empty((n, 3))
    for i in range(n):
        beyond = (n - i - 0.5) * h  # length of hose beyond the segment's centre, mm
        for k in range(3):  # element by element: a vector expression here would allocate per segment
            out[i, k] = h * (end_force[k] + beyond * line_weight[k])
    return out


@njit(cache=True)
def constraint_jacobian_t(frames, h):
    """J^T (3N, 3): J = d(x_N)/d(delta), block i is -h [d3_i]x, so J^T block i is h [d3_i]x."""
    n = frames.shape[0]
    out = np.zeros((3 * n, 3))
    for i in range(n):
        t = frames[i, 2]
        r = 3 * i
        out[r, 1] = -h * t[2]
        out[r, 2] = h * t[1]
        out[r + 1, 0] = h * t[2]
        out[r + 1, 2] = -h * t[0]
        out[r + 2, 0] = -h * t[1]
        out[r + 2, 1] = h * t[0]
    return out


def gravity_energy(frames: np.ndarray, start_point: np.ndarray, line_weight: np.ndarray, h: float) -> float:
    """Potential of the weight relative to the start point, N*mm: -sum_i (h q) . (x_mid_i - x_0)."""
    nodes = centerline(frames, start_point, h)
    mids = 0.5 * (nodes[1:] + nodes[:-1]) - start_point
    return float(-h * np.sum(mids @ line_weight))
