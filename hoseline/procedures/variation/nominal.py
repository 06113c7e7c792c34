"""The nominal placement as two equilibria, the clamps of a perturbed hose, and Newton from the nominal hose.

The published placement ends in two equilibria: at the end of the place phase (end fitting free
to roll: the roll found is the lock angle; every framed clip free to roll too) and, after the lock
(of the end and of fixed clips) and the twist, the final one.  A
perturbed hose (tolerances.perturbed) has its own clamps for both (PerturbedPlacement); its
start fitting's frame is the nominal one turned by the tilt of the start direction, so that it
changes smoothly with the deviation (a placement picks the frame by a convention from the
direction alone, frame_from_tangent, which may jump by a roll about the tangent; for a round
section, EI1 = EI2, that roll changes the lock angle only, not the shape).

Used by the sensitivities (derivatives along the deviations) and by the warm start of samples:
Newton from the nominal equilibria to the perturbed ones, first the roll-free one (a new lock
angle), then the final one, in smaller steps of the deviation when one step does not converge.  Near a fork the warm start can reach another branch than the
published sequence from the straight hose; samples.py checks it on a subset.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from hoseline.mechanics.newton import RodProperties, end_frame_of, evaluate, solve_equilibrium
from hoseline.mechanics.rod import Clamps, RodState
from hoseline.mechanics.rotations import frame_from_tangent, rotation_matrix, rotation_vector
from hoseline.model.problem import Problem
from hoseline.procedures.placement.path import PlacementPath
from hoseline.procedures.placement.sequence import place_only, rod_properties
from hoseline.procedures.variation.tolerances import COORDINATES, INDEX, perturbed, tilt_axes

EQUILIBRIUM = 1e-8  # relative residual below which the reconstructed nominal equilibria are accepted


class PerturbedPlacement:
    """The rod and the placement clamps of `problem` with the deviation `deviation` (user units)."""

    def __init__(self, problem: Problem, deviation: np.ndarray) -> None:
        self.problem = perturbed(problem, deviation)
        self.props = rod_properties(self.problem)
        self.path = PlacementPath(self.problem)
        nominal_frame = frame_from_tangent(problem.start.direction)
        tilt = np.radians(deviation[INDEX["start.tilt_a"]:INDEX["start.tilt_b"] + 1]) @ tilt_axes(problem.start.direction)
        self.path.start_frame = nominal_frame @ rotation_matrix(tilt).T

    def free(self) -> Clamps:
        """The clamps at the end of the place phase, end fitting free to roll."""
        return self.path.place(1.0)

    def final(self, rolled: RodState) -> Clamps:
        """The final clamps with the end fitting locked at the roll of `rolled` (rad, from the free clamps' frame)
        and twisted, each fixed clip locked at its clip roll there (rotating and ball clips stay as they are)."""
        locked = end_frame_of(self.free(), rolled)
        clips, _ = self.path.locked_clips(rolled)
        return self.path.twisted(locked, self.problem.end_twist_deg, clips)


def rolled(roll: float, clip_rolls: np.ndarray) -> RodState:
    """A state that carries only rolls (rad): the end roll and the clip rolls, for PerturbedPlacement.final."""
    count = len(clip_rolls)
    return RodState(np.empty((0, 3, 3)), np.zeros(3), float(roll), np.zeros((count, 3)), np.asarray(clip_rolls, float))


@dataclass(frozen=True)
class NominalPlacement:
    """The nominal hose's equilibria: props; free_state (roll-free, its roll the lock angle in rad);
    final clamps and final state."""

    problem: Problem
    props: RodProperties
    free_state: RodState
    final: Clamps
    state: RodState


def nominal_placement(problem: Problem) -> NominalPlacement:
    """Place the nominal hose and reconstruct both equilibria of its placement.

    Raises PlacementError when it cannot be placed, ValueError for stiffener springs (phased in after
    the lock: not covered) or when the equilibria are not reconstructed.
    """
    if problem.hose.stiffeners is not None:
        raise ValueError("the stiffener springs are not covered (they are phased in after the lock)")
    if any(clip.kind == "sliding" for clip in problem.clips):
        raise ValueError("sliding clips are not covered (the placement moves a sliding clip to the nearest station "
                         "at its end, a step in the parameters)")
    props, final, state, lock_angle_deg = place_only(problem)
    untwisted, placed = final, state
    if problem.end_twist_deg != 0.0:
        _, untwisted, placed, _ = place_only(replace(problem, end_twist_deg=0.0))
    free_clamps = PerturbedPlacement(problem, np.zeros(len(COORDINATES))).free()
    free_state = RodState(placed.frames, placed.end_force, math.radians(lock_angle_deg), placed.clip_forces,
                          _free_clip_rolls(free_clamps, untwisted, placed), placed.clip_arc_lengths)
    free = evaluate(props, free_clamps, free_state).residual
    residual = evaluate(props, final, state).residual
    if max(free, residual) > EQUILIBRIUM:
        raise ValueError(f"the nominal equilibria were not reconstructed (residuals {free:.2e}, {residual:.2e})")
    return NominalPlacement(problem, props, free_state, final, state)


def _free_clip_rolls(free: Clamps, locked: Clamps, state: RodState) -> np.ndarray:
    """The clip rolls (rad) of the roll-free equilibrium: a fixed clip's is the angle its locked frame (in
    `locked`, the untwisted final clamps) is turned from its roll-free frame (in `free`) about the clip's axis; a
    rotating clip's stays free in `state`; a ball clip has none (0)."""
    rolls = np.zeros(len(free.clips))
    for j, (loose, held) in enumerate(zip(free.clips, locked.clips)):
        if loose.frame is None:
            continue
        if held.roll_free:
            rolls[j] = state.clip_rolls[j]
        else:  # held.frame = loose.frame @ R(roll d3)^T, so held.frame^T @ loose.frame = R(roll d3)
            rolls[j] = float(rotation_vector(held.frame.T @ loose.frame) @ loose.frame[2])
    return rolls


WARM_SCHEDULES = ((1.0,), (0.5, 1.0), (0.25, 0.5, 0.75, 1.0))  # fractions of the deviation, tried in turn


def warm_start(nominal: NominalPlacement, deviation: np.ndarray) -> tuple[Problem, RodProperties, Clamps, RodState] | None:
    """(problem, rod, final clamps, equilibrium) of the perturbed hose by Newton from the nominal equilibria,
    in one step or, failing that, in WARM_SCHEDULES' smaller steps of the deviation; None when no schedule
    reaches a stable equilibrium (the caller then places the hose from the start)."""
    for fractions in WARM_SCHEDULES:
        free, state = nominal.free_state, nominal.state
        for fraction in fractions:
            side = PerturbedPlacement(nominal.problem, fraction * np.asarray(deviation))
            free, report = solve_equilibrium(side.props, side.free(), free)
            if not (report.converged and report.unstable_directions == 0):
                break
            clamps = side.final(free)
            state, report = solve_equilibrium(side.props, clamps, state)
            if not (report.converged and report.unstable_directions == 0):
                break
        else:
            return side.problem, side.props, clamps, state
    return None
