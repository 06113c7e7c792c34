"""A-posteriori accuracy: how far the placed shape is from the exact one, from one coarser solve.

The discrete rod converges with order 2 in the segment length h (docs/model.md: observed
orders 1.98-2.01), so the station error behaves like C h^2.  With the shape x_N of N segments
and x_M of M = N/2 segments at the same clamps, Richardson extrapolation estimates the error
of x_N as |x_M - x_N| / ((N/M)^2 - 1).  The coarse shape is solved by Newton from the fine
one (the same branch, a few iterations), and compared at the fine stations through a cubic
spline of its stations (interpolation error O(h^4), far below the estimate).
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline

from hoseline.mechanics.clipped_newton import station_positions
from hoseline.mechanics.newton import RodProperties, node_positions, solve_equilibrium
from hoseline.mechanics.rod import Clamps, RodState

CONVERGENCE_ORDER = 2


def coarse_segments(segments: int, minimum: int) -> int:
    """The segment count of the coarser solve: half, and at least `minimum`."""
    return max(minimum, segments // 2)


def richardson_error(fine: RodProperties, coarse: RodProperties, clamps: Clamps, state: RodState,
                     tolerance: float, fine_clamps: Clamps | None = None) -> float | None:
    """Estimated largest station error of the fine equilibrium `state`, mm; None if the coarse
    solve does not converge to a stable state or is not coarser.

    fine, coarse: the rod at N and M < N segments (same hose).  clamps: the final clamps (they do
    not depend on the segment count).  tolerance: relative residual of the coarse Newton solve.
    fine_clamps: the fine solve's clamps where they differ (clips sit on stations), else clamps.
    """
    if coarse.segments >= fine.segments:
        return None
    midpoints = (np.arange(coarse.segments) + 0.5) * coarse.segment_length
    nearest = np.minimum((midpoints / fine.segment_length).astype(int), fine.segments - 1)
    guess = RodState(state.frames[nearest].copy(), state.end_force.copy(), 0.0)
    if clamps.clips:  # sliding clips start where the fine solve found them
        guess.clip_arc_lengths = state.clip_arc_lengths.copy()
    coarse_state, report = solve_equilibrium(coarse, clamps, guess, tolerance=tolerance)
    if not report.converged or report.unstable_directions != 0:
        return None
    if clamps.clips:  # stations at their arc lengths (sliding clips stretch their spans)
        s_fine, fine_nodes = station_positions(fine, clamps if fine_clamps is None else fine_clamps, state)
        s_coarse, coarse_nodes = station_positions(coarse, clamps, coarse_state)
    else:
        fine_nodes = node_positions(fine, clamps, state)
        coarse_nodes = node_positions(coarse, clamps, coarse_state)
        s_fine = fine.segment_length * np.arange(fine.segments + 1)
        s_coarse = coarse.segment_length * np.arange(coarse.segments + 1)
    difference = CubicSpline(s_coarse, coarse_nodes, axis=0)(s_fine) - fine_nodes
    ratio = (fine.segments / coarse.segments) ** CONVERGENCE_ORDER
    return float(np.max(np.linalg.norm(difference, axis=1))) / (ratio - 1.0)
