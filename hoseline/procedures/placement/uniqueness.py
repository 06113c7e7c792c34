"""Is the placed shape the only one?  Other stable equilibria at the same mounts, length and twist.

Three sources, each checked by Newton at the final clamps:
- forks met along the placement path (continuation.Fork): the branches not taken are followed
  through the rest of the published sequence (rest of the place phase, lock, twist).  Where
  they meet the answer again the fork was a detour of the path, not a second answer; where they
  end elsewhere the user could get that shape too (e.g. by pushing the hose the other way);
- the symmetry of the mounts (symmetry.py): the mirror image in their common plane, or the half
  turn about their common axis, when it solves the same clamped problem and differs from the shape;
- the end fitting turned the other way round to the same clamp, at a twist of half a turn or more.
A candidate that cannot be followed to the end leaves the verdict "not checked" (Result.unique None),
never "yes".

The verdict (Result.unique) describes the final answer only; the forks met on the way are
listed separately (Result.path_forks).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from hoseline.mechanics.newton import RodProperties, node_positions, solve_equilibrium, total_energy
from hoseline.mechanics.rod import Clamps, RodState
from hoseline.model.problem import Problem
from hoseline.procedures.placement.continuation import EQUAL_ENERGY, ContinuationLog, Fork, PlacementError
from hoseline.procedures.placement.result import OtherEquilibrium, Result
from hoseline.procedures.placement.symmetry import equivalent_states

DISTINCT = 1e-6  # of the length: shapes closer than this are the same equilibrium
ANGLE_TOLERANCE_DEG = 1e-9  # a twist this close to half a turn counts as one
BRANCHES_FOLLOWED = 3  # fork branches followed to the end at most (each costs about one placement)

Finish = Callable[..., tuple[Clamps, RodState, float, float]]  # (log, phase, fraction, state[, twist_deg, first_step])


@dataclass
class Candidate:
    """Another equilibrium found: where it came from, its clamps and state (None if it could not be followed)."""

    origin: str
    clamps: Clamps | None
    state: RodState | None
    lock_angle_deg: float = 0.0
    other_way: bool = False  # the shape of the end fitting turned the other way round (a mirror image at +-180 deg)
    rejoined: bool = False  # a fork's branch that met the main run's equilibrium at the lock (its end is the answer's)

    @property
    def stable(self) -> bool:
        return self.state is not None


def fork_branches(props: RodProperties, final: Clamps, state: RodState, forks: list[Fork], finish: Finish) -> list[Candidate]:
    """The branches not taken at the forks of the path, each followed to the end of the sequence by `finish` (at most
    BRANCHES_FOLLOWED; the others are returned as candidates not followed), from the fork with the step the path took
    on from it: the same sequence as the branch taken."""
    candidates = []
    for fork in forks:
        for rank, other in enumerate(fork.others):
            origin = (f"the other branch of the fork met in phase '{fork.phase}' at fraction {fork.fraction:.4f}"
                      f" ({fork.energy_gaps[rank]:.4g} N*mm above the branch taken there)")
            if len(candidates) >= BRANCHES_FOLLOWED:
                candidates.append(Candidate(f"{origin} was not followed (at most {BRANCHES_FOLLOWED} are)", None, None))
                continue
            try:
                clamps, end_state, lock_angle_deg, _ = finish(ContinuationLog(), fork.phase, fork.fraction, other,
                                                              first_step=fork.step)
            except (PlacementError, ValueError) as exc:
                candidates.append(Candidate(f"{origin} could not be followed to the end: {exc}", None, None))
                continue
            candidates.append(Candidate(origin, clamps, end_state, lock_angle_deg, rejoined=clamps is final))
    return candidates


def other_way_round(problem: Problem, twist_start: RodState | None, finish: Finish,
                    found: list[Candidate]) -> list[Candidate]:
    """The placement twisted the other way round to the same clamp (twist - 360 deg, towards zero), when that turn is no
    longer than the one asked (|twist| >= 180 deg): at half a turn both ways clamp the fitting identically and an
    assembler may turn either way; a preset, springs or the obstacles can make the two shapes differ where the
    mirror image, which shows it for a plain hose, does not exist.  A shorter twist's other way is a longer turn
    than asked and is not tried.  twist_start: the equilibrium at the lock, the twist phase's start; `finish` follows
    it (with its twist in degrees).  found: the candidates found so far; none is needed when the mirror image is among
    them (it is the other way's shape, or the shape itself when that is symmetric)."""
    twist = problem.end_twist_deg
    if twist_start is None or abs(twist) < 180.0 - ANGLE_TOLERANCE_DEG or any(c.other_way for c in found):
        return []
    other = twist - math.copysign(360.0, twist)
    origin = (f"the end fitting turned the other way round ({other:g} deg instead of {twist:g} deg): the same "
              "clamp, and which shape a hose takes depends on the way its fitting was turned")
    try:
        clamps, end_state, lock_angle_deg, _ = finish(ContinuationLog(), "twist", 0.0, twist_start, other)
    except (PlacementError, ValueError) as exc:
        return [Candidate(f"{origin} could not be followed to the end: {exc}", None, None)]
    return [Candidate(origin, clamps, end_state, lock_angle_deg)]


def symmetric_images(problem: Problem, props: RodProperties, final: Clamps, state: RodState,
                     lock_angle_deg: float) -> list[Candidate]:
    """The images of `state` under the mounts' symmetry that Newton confirms as stable equilibria."""
    twist = math.remainder(problem.end_twist_deg, 360.0)
    candidates = []
    for image, reflection in equivalent_states(problem, props, final, state):
        image, report = solve_equilibrium(props, final, image, max_iterations=5)
        if not (report.converged and report.unstable_directions == 0):
            continue
        if not reflection:
            origin = "the half turn of this shape about the common axis of both mounts"
        elif abs(abs(twist) - 180.0) < ANGLE_TOLERANCE_DEG:
            origin = ("the mirror image of this shape in the mounts' common plane: the shape the hose takes when "
                      f"the end fitting is turned the other way ({-problem.end_twist_deg:g} deg instead of "
                      f"{problem.end_twist_deg:g} deg); both turns clamp the fitting identically, so it is the same "
                      "physical assembly, and which shape a hose takes depends on the way its fitting was turned")
        else:
            origin = "the mirror image of this shape in the mounts' common plane (mounts and gravity are symmetric about it)"
        candidates.append(Candidate(origin, final, image, lock_angle_deg,
                                    other_way=reflection and abs(abs(twist) - 180.0) < ANGLE_TOLERANCE_DEG))
    return candidates


def judge_uniqueness(result: Result, props: RodProperties, final: Clamps, state: RodState,
                     candidates: list[Candidate], forks: list[Fork]) -> list[Candidate]:
    """Fill result.unique, other_equilibria, path_forks and the events from the candidates found;
    return the candidates that are distinct stable equilibria (one per other_equilibria entry)."""
    result.path_forks = [fork.describe() for fork in forks]
    seen = [node_positions(props, final, state)]
    distinct = []
    energy = total_energy(props, final, state)
    unchecked = []
    for candidate in candidates:
        if not candidate.stable:
            result.events.append(f"uniqueness: {candidate.origin}")
            unchecked.append(candidate.origin)
            continue
        nodes = node_positions(props, candidate.clamps, candidate.state)
        distances = [float(np.max(np.linalg.norm(nodes - other, axis=1))) for other in seen]
        if min(distances) <= DISTINCT * props.length:
            if candidate.rejoined:
                result.events.append(f"uniqueness: {candidate.origin} ends on this shape again: it meets the path "
                                     "taken at the lock (end roll free), and the twist from there is the same")
            elif distances[0] <= DISTINCT * props.length and candidate.clamps is not final:
                result.events.append(f"uniqueness: {candidate.origin} ends on this shape again")
            continue
        seen.append(nodes)
        gap = total_energy(props, candidate.clamps, candidate.state) - energy
        gap = 0.0 if abs(gap) <= EQUAL_ENERGY * max(abs(energy), 1e-300) else gap  # rounding of an equal energy
        same_clamps = bool(np.max(np.abs(candidate.clamps.end_frame - final.end_frame)) <= 1e-9)
        other = OtherEquilibrium(candidate.origin, distances[0], gap, candidate.lock_angle_deg,
                                 same_clamps)
        result.other_equilibria.append(other)
        distinct.append(candidate)
        result.events.append(f"not unique: {other.describe()}")
    result.unique = result.stability_margin != 0.0 and not result.other_equilibria
    if result.unique and unchecked:  # another shape may lie where the search could not go: not known
        result.unique, result.unchecked = None, "; ".join(unchecked)
    return distinct
