"""Placement to a requested accuracy: the segment count chosen from the a-posteriori error estimate."""

from __future__ import annotations

import math
from dataclasses import replace

from hoseline.model.hose import MIN_SEGMENTS
from hoseline.model.problem import Problem
from hoseline.procedures.placement.accuracy import CONTACT_ORDER, CONVERGENCE_ORDER
from hoseline.procedures.placement.continuation import PlacementError, Progress, StepControl
from hoseline.procedures.placement.result import Result
from hoseline.procedures.placement.sequence import solve

SAFETY = 1.2  # the count predicted from the error law, made this much larger
# The error estimate is an estimate: against independent Kirchhoff solutions (tests/test_accuracy_references.py,
# five cases at 20, 40 and 100 segments) the true error was up to 1.9 % above it (before the coarse rod found its own
# lock angle, up to 5.7 %, and 67 % on a non-coplanar hose).  An accuracy is met when the estimate times this margin is.
ESTIMATE_MARGIN = 1.25
FEWEST_SEGMENTS = 10  # no fewer when the estimate asks for fewer: a coarse rod's estimate is itself rough
MOST_SEGMENTS = 5000
ROUNDS = 4


def solve_to_accuracy(problem: Problem, accuracy: float, *, progress: Progress | None = None,
                      control: StepControl = StepControl()) -> Result:
    """Place the hose with a segment count whose estimated largest station error, times ESTIMATE_MARGIN, is at most
    `accuracy` (mm).

    Starts from the problem's segment count; each round predicts the count from the error law
    (error ~ 1/N^2, with contact 1/N plus the barrier's standoff, which more segments do not remove: accuracy.py)
    and solves again, until the estimate meets the accuracy.  Raises PlacementError
    when the error cannot be estimated or more than MOST_SEGMENTS would be needed.
    """
    if not (math.isfinite(accuracy) and accuracy > 0.0):
        raise ValueError(f"accuracy {accuracy!r} mm: give a positive number of mm")
    order = CONTACT_ORDER if problem.has_contact else CONVERGENCE_ORDER  # of the error estimate (accuracy.py)
    step = clip_segment_step(problem)
    segments = _multiple(int(problem.hose.segments), step)
    tried: dict[int, Result] = {}
    for _ in range(ROUNDS):
        result = solve(replace(problem, hose=replace(problem.hose, segments=segments)), progress=progress,
                       control=control)
        tried[segments] = result
        error = result.discretisation_error
        if error is None:
            raise PlacementError(f"the discretisation error at {segments} segments could not be estimated (the solve "
                                 "with half the segments did not reach a stable equilibrium); give hose.segments instead")
        if error * ESTIMATE_MARGIN <= accuracy:
            result.events.append(f"accuracy: {segments} segments, estimated station error {error:.3g} mm, with the "
                                 f"estimate's margin ({ESTIMATE_MARGIN:g}x) {error * ESTIMATE_MARGIN:.3g} mm <= "
                                 f"{accuracy:g} mm asked for")
            return result
        needed = math.ceil(segments * (error * ESTIMATE_MARGIN / accuracy) ** (1.0 / order) * SAFETY)
        if needed > MOST_SEGMENTS:
            raise PlacementError(f"an accuracy of {accuracy:g} mm needs about {needed} segments (estimated error "
                                 f"{error:.3g} mm at {segments}), more than {MOST_SEGMENTS}: ask for less accuracy")
        segments = _multiple(max(needed, FEWEST_SEGMENTS, MIN_SEGMENTS, segments + 1), step)
    raise PlacementError(f"accuracy {accuracy:g} mm not reached in {ROUNDS} rounds (segment counts tried: "
                         f"{', '.join(map(str, tried))})")


def clip_segment_step(problem: Problem) -> int:
    """The segment counts that keep every fixed, rotating and ball clip on a station of the hose and of
    the half-as-fine hose of the error estimate are the multiples of this number (1 without such clips).

    A clip at station k of N segments sits at the fraction k / N = p / q (in lowest terms) of the
    length: it is on a station of every multiple of q, and on an even one of every multiple of 2 q.
    Sliding clips find their own station."""
    from fractions import Fraction
    from math import lcm

    from hoseline.model.clips import clip_node

    segments = int(problem.hose.segments)
    step = 1
    for clip in problem.clips:
        if not clip.slides:
            fraction = Fraction(clip_node(clip.arc_length, problem.hose.length, segments), segments)
            step = lcm(step, 2 * fraction.denominator)
    return step


def _multiple(count: int, step: int) -> int:
    """The least multiple of `step` not below `count`."""
    return -(-count // step) * step

