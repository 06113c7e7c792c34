"""Contact forces to a requested accuracy: the placed hose carried to twice its segments, and again, until the
estimated errors of each obstacle's total force and of the mounts' reactions are within it.

With contact the forces converge at order 1-2 in the segment length (docs/model.md, Accuracy of the forces): a
touch-down falls between stations, and the lifted span's own error is about 0.5 % of a mount reaction at a segment
of 1/200 of a 2 m hose.  A placement with twice the segments costs far more than the first (its continuation takes
more and smaller steps), so the finer hose is not placed again: its frames are interpolated from the placed ones
(prolonged) and every obstacle the interpolation touches is brought in again along the side the placement chose
(procedures/contact/bring_in.py, a travel of a fraction of a millimetre), so that every state on the way is an
equilibrium that penetrates nothing, as in the placement.  The same branch, the same sides.

The error of the finer equilibrium is estimated from the pair (accuracy.contact_errors), plus the barrier's
standoff from d_hat halved.  The order: 1 (the difference itself) from two counts, the contact estimate's
conservative assumption; from three counts the order the forces show (observed_order, Roache's grid convergence
index: between 1 and 2, the contact's and the rod's), the estimate then taken FORCE_MARGIN times, Roache's factor
of safety for a three-grid study.  Relative to what: each obstacle's total force to its
magnitude, and the mounts' reactions to the smaller of the two, but no smaller than SCALE_FLOOR of the largest load
on the hose (its weight, an obstacle's force), so that a reaction near zero does not ask for endless refinement.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from hoseline.mechanics.rod import Clamps, RodState
from hoseline.mechanics.rotations import rotation_matrix, rotation_vector
from hoseline.procedures.placement.accuracy import ContactErrors, ContactSnapshot

ENTRY_CLEARANCE = 5.0  # barrier reaches d_hat: how far the obstacles clear the prolonged hose where they start coming in
DOUBLINGS = 2  # at most 4x the placement's segments: a default must not cost seconds
SCALE_FLOOR = 0.01  # a reaction's error is relative to no less than this fraction of the largest load on the hose
FORCE_MARGIN = 1.25  # the estimate with an observed order, made this much larger (Roache's three-grid safety factor)
LOWEST_ORDER, HIGHEST_ORDER = 1.0, 2.0  # an observed order is taken within these: the contact's and the rod's


@dataclass(frozen=True)
class ForceRefinement:
    """What the refinement did, for result.json.

    asked: the relative accuracy asked for.  segments: the placement's and each finer count solved.
    estimated: the estimated relative error at the last count (the larger of the forces' and the reactions').
    met: whether it is within `asked`.  why: when not met, why the refinement stopped."""

    asked: float
    segments: tuple[int, ...]
    estimated: float | None
    met: bool
    why: str = ""

    def summary(self) -> dict:
        """For result.json (percent)."""
        return {"asked_percent": 100.0 * self.asked, "segments": list(self.segments),
                "estimated_percent": None if self.estimated is None else 100.0 * self.estimated,
                "met": self.met, "why": self.why}


def prolonged(clamps: Clamps, state: RodState) -> tuple[Clamps, RodState]:
    """The clamps and a starting state of the same hose with twice the segments.

    Each segment becomes two whose frames are turned a quarter of the way towards the neighbouring segment's (the
    start and end fittings' frames beyond the ends): on an arc of constant curvature that is the finer arc itself.
    The clips' stations double; the forces, rolls and arc lengths are kept as the Newton's start."""
    frames = state.frames
    padded = np.concatenate([clamps.start_frame[None], frames,
                             (frames[-1] if clamps.end_frame is None else clamps.end_frame)[None]])
    finer = np.empty((2 * len(frames), 3, 3))
    for k in range(len(frames)):
        before, here, after = padded[k], padded[k + 1], padded[k + 2]
        finer[2 * k] = here @ rotation_matrix(0.25 * rotation_vector(before.T @ here)).T
        finer[2 * k + 1] = here @ rotation_matrix(0.25 * rotation_vector(after.T @ here)).T
    clips = tuple(replace(clip, node=2 * clip.node) for clip in clamps.clips)
    return replace(clamps, clips=clips), replace(state, frames=finer)


def observed_order(coarser: ContactSnapshot, coarse: ContactSnapshot, fine: ContactSnapshot) -> float:
    """The order of the forces' and reactions' error in the segment length, from three counts each twice the last:
    log2 of the ratio of successive changes, the lowest over the reactions and the obstacles' forces, within
    LOWEST_ORDER and HIGHEST_ORDER (an oscillating or stalled change gives the lowest)."""
    pairs = [(coarser.reactions, coarse.reactions, fine.reactions)]
    pairs += [(coarser.forces[name], coarse.forces[name], force) for name, force in fine.forces.items()]
    orders = []
    for first, second, third in pairs:
        before, after = float(np.linalg.norm(second - first)), float(np.linalg.norm(third - second))
        orders.append(LOWEST_ORDER if after == 0.0 or before <= after else np.log2(before / after))
    return float(np.clip(min(orders), LOWEST_ORDER, HIGHEST_ORDER))


def relative_error(errors: ContactErrors, fine: ContactSnapshot, weight: float) -> float:
    """The larger relative error of the obstacles' total forces and the mounts' reactions (module doc).

    weight: the hose's weight, N."""
    magnitudes = {name: float(np.linalg.norm(force)) for name, force in fine.forces.items()}
    scale = SCALE_FLOOR * max([weight, *magnitudes.values()])
    forces = [errors.forces[name] / magnitude for name, magnitude in magnitudes.items() if magnitude > scale]
    reaction = errors.reactions / max(scale, float(np.min(np.linalg.norm(fine.reactions, axis=1))))
    return max([reaction, *forces])
