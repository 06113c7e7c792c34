"""Phasing the stiffener springs in at the placed position.

The thesis' spring tables are slack up to a few tenths of a millimetre and then rise by
thousands of newtons within 0.01 mm, so Newton's method cannot start them from the
straight hose's buckling step.  The hose is therefore placed as a plain rod, and the spring
forces are then scaled from 0 to their full value by continuation, with the end fitting
still free to turn about its axis (so the lock angle is torque-free with the springs), after
which the twist is applied with the springs at full strength.
"""

from __future__ import annotations

from dataclasses import replace

from hoseline.mechanics.newton import RodProperties, solve_equilibrium
from hoseline.mechanics.rod import Clamps, RodState
from hoseline.mechanics.stiffeners import scaled_springs
from hoseline.procedures.placement.continuation import ContinuationLog, PlacementError, Progress, push_along_modes, relax_to_stable

SMALLEST_STEP = 1e-3  # of the spring strength


def phase_in_springs(
    props: RodProperties, clamps: Clamps, state: RodState, log: ContinuationLog, progress: Progress | None = None
) -> RodState:
    """Equilibrium with the full springs of `props`, continued from `state` (an equilibrium without them).

    clamps: the placed position (end roll free).  Steps start at 5 % of the spring strength,
    grow after easy steps and are halved on failure; a step ending on an unstable
    equilibrium moves to the lowest stable one next to it (logged).
    Raises PlacementError when a step below 0.1 % still fails.
    """
    strength, step = 0.0, 0.05
    while strength < 1.0:
        target = min(1.0, strength + step)
        trial_props = replace(props, springs=scaled_springs(props.springs, target))
        trial, report = solve_equilibrium(trial_props, clamps, state, max_iterations=40)
        log.iterations += report.iterations
        accepted = report.converged and report.unstable_directions == 0
        if not accepted:  # walk downhill from the last state, or from either side of a saddle
            candidates = [state]
            if report.converged:
                candidates += push_along_modes(trial_props, clamps, trial, report.unstable_directions)
            relaxed = relax_to_stable(trial_props, clamps, candidates, log)
            accepted = relaxed is not None
            trial = relaxed[0] if accepted else trial
        if not accepted:
            step *= 0.5
            if step < SMALLEST_STEP:
                raise PlacementError(
                    f"placement phase 'springs' failed at {100 * strength:.2f} % of the spring strength: "
                    f"Newton residual {report.residual:.2e} ({report.message or 'no stable equilibrium'})"
                )
            continue
        log.steps += 1
        state, strength = trial, target
        if progress is not None:
            progress("springs", strength)
        if report.iterations <= 15:
            step = min(0.25, 2.0 * step)
    return state
