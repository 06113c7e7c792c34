"""A-posteriori accuracy: how far the placed shape is from the exact one, from one coarser solve.

The discrete rod converges with order 2 in the segment length h (docs/model.md: observed
orders 1.98-2.01), so the station error behaves like C h^2.  With the shape x_N of N segments
and x_M of M = N/2 segments at the same clamps, Richardson extrapolation estimates the error
of x_N as |x_M - x_N| / ((N/M)^2 - 1).  The coarse shape is solved by Newton from the fine
one (the same branch, a few iterations), and compared at the fine stations through the cubic
through the four coarse stations around each (interpolation error O(h^4), far below the
estimate; local, so that a solve loads no spline library).

With contact the order is one (docs/model.md, Contact: a touch-down or lift-off point falls between
stations, and the reaction concentrated there is carried by the stations next to it), and the barrier
adds an error that does not shrink with h: the hose rests a gap in (0, d_hat) off the obstacle, so
the wrap or the lying part is displaced by that much (a hose pulled taut over a drum: +0.15 % of the
push per micrometre).  contact_errors adds the two: the half-segment placement's difference (order 1)
and twice the difference made by halving d_hat at the same segments (the gap is proportional to d_hat),
for the stations, each obstacle's total force and the mounts' reactions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hoseline.mechanics.clipped_newton import station_positions
from hoseline.mechanics.newton import RodProperties, node_positions, solve_equilibrium
from hoseline.mechanics.rod import Clamps, RodState

CONVERGENCE_ORDER = 2
CONTACT_ORDER = 1  # with contact (module doc)
BARRIER_NARROWING = 0.5  # the error estimate's second barrier reach, a fraction of d_hat


def coarse_segments(segments: int, minimum: int) -> int:
    """The segment count of the coarser solve: half, and at least `minimum`."""
    return max(minimum, segments // 2)


def coarse_guess(fine: RodProperties, coarse: RodProperties, state: RodState) -> RodState:
    """A first guess of the coarse rod's equilibrium from the fine one's `state`: each coarse segment takes the frame
    of the fine segment at its middle; the end force and the end roll as they are."""
    midpoints = (np.arange(coarse.segments) + 0.5) * coarse.segment_length
    nearest = np.minimum((midpoints / fine.segment_length).astype(int), fine.segments - 1)
    return RodState(state.frames[nearest].copy(), state.end_force.copy(), state.roll)


def local_cubic(s_known: np.ndarray, points: np.ndarray, s_wanted: np.ndarray) -> np.ndarray:
    """`points` (n, 3) at the increasing arc lengths `s_known` (n,) interpolated at `s_wanted` (m,), mm: at each, the
    cubic through the four known points around it (Lagrange; the first or last four near the ends, all of them when
    fewer); the error is O(h^4) on a smooth curve of spacing h."""
    order = min(4, len(s_known))
    first = np.clip(np.searchsorted(s_known, s_wanted) - order // 2, 0, len(s_known) - order)
    nodes = first[:, None] + np.arange(order)  # (m, order) the known points each is interpolated from
    knots = s_known[nodes]
    weights = np.ones(nodes.shape)
    for j in range(order):
        for k in range(order):
            if k != j:
                weights[:, j] *= (s_wanted - knots[:, k]) / (knots[:, j] - knots[:, k])
    return np.einsum("mj,mjd->md", weights, points[nodes])


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
    guess = coarse_guess(fine, coarse, state)
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
    difference = local_cubic(s_coarse, coarse_nodes, s_fine) - fine_nodes
    ratio = (fine.segments / coarse.segments) ** CONVERGENCE_ORDER
    return float(np.max(np.linalg.norm(difference, axis=1))) / (ratio - 1.0)


@dataclass(frozen=True)
class ContactErrors:
    """Estimated errors of a placement with contact: each the segment count's part (order 1) plus the barrier's.

    station: largest station error, mm, of which station_barrier from the barrier's standoff (it does not shrink
    with more segments).  reactions: the larger error of the two mounts' force vectors, N.  forces: per obstacle
    name, the error of its total force vector, N.
    """

    station: float
    station_barrier: float
    reactions: float
    forces: dict[str, float]

    def describe(self) -> str:
        """One line for the result's events."""
        forces = ", ".join(f"{name!r} {error:.3g} N" for name, error in self.forces.items())
        return (f"accuracy: with contact, estimated errors: stations {self.station:.3g} mm (of which the barrier's "
                f"standoff {self.station_barrier:.3g} mm), mount reactions {self.reactions:.3g} N, total forces: "
                f"{forces} (order 1 in the segment length plus the barrier's reach: docs/model.md, Contact)")


@dataclass(frozen=True)
class ContactSnapshot:
    """What contact_errors compares of one equilibrium with contact.

    s: (N+1,) arc length of the stations, mm.  centerline: (N+1, 3) the stations, mm.  reactions: (2, 3) the
    start and end mounts' forces on the hose, N.  forces: per obstacle name, its total force on the hose (3,), N.
    """

    s: np.ndarray
    centerline: np.ndarray
    reactions: np.ndarray
    forces: dict[str, np.ndarray]


def snapshot(result) -> ContactSnapshot:
    """The ContactSnapshot of a Result with contact."""
    return ContactSnapshot(result.s, result.centerline, np.array([result.start_force, result.end_force]),
                           {contact.name: contact.total_force for contact in result.contacts})


def contact_errors(fine: ContactSnapshot, coarse: ContactSnapshot, narrowed: ContactSnapshot,
                   order: float = CONTACT_ORDER) -> ContactErrors:
    """The ContactErrors of the equilibrium `fine` from `coarse`, the same problem placed with fewer segments, and
    `narrowed`, the fine equilibrium solved again with the barrier's reach d_hat times BARRIER_NARROWING.

    order: of the error in the segment length (CONTACT_ORDER unless observed on three counts)."""
    segments = ((len(fine.s) - 1) / (len(coarse.s) - 1)) ** order - 1.0
    barrier = 1.0 / (1.0 - BARRIER_NARROWING)  # the error at d_hat from the change to BARRIER_NARROWING d_hat

    def error(fine_value, coarse_value, narrowed_value):
        return (float(np.linalg.norm(coarse_value - fine_value)) / segments
                + barrier * float(np.linalg.norm(narrowed_value - fine_value)))

    coarse_at_fine = local_cubic(coarse.s, coarse.centerline, fine.s)
    shape = float(np.max(np.linalg.norm(coarse_at_fine - fine.centerline, axis=1))) / segments
    standoff = barrier * float(np.max(np.linalg.norm(narrowed.centerline - fine.centerline, axis=1)))
    reactions = max(error(fine.reactions[k], coarse.reactions[k], narrowed.reactions[k]) for k in range(2))
    forces = {name: error(force, coarse.forces[name], narrowed.forces[name]) for name, force in fine.forces.items()}
    return ContactErrors(shape + standoff, standoff, reactions, forces)
