"""Natural-parameter continuation of the equilibrium with contact along a path of clamps.

As procedures/placement/continuation.py's follow, with the contact Newton
(mechanics/contact_newton.py): each step starts from the previous equilibrium, which never
penetrates, so the step filter keeps every later state out of the obstacles too.  A step that
does not converge is halved.  Stability is checked at every step; a state that loses it is
not followed through a fork here (the contact Newton has no downhill mode yet): the path
fails with PlacementError naming where.
"""

from __future__ import annotations

from typing import Callable

from hoseline.mechanics.contact_newton import ContactModel, solve_with_contact
from hoseline.mechanics.newton import RodProperties
from hoseline.mechanics.rod import Clamps, RodState
from hoseline.procedures.placement.continuation import ContinuationLog, PlacementError, Progress, StepControl

CONTACT_TOLERANCE = 1e-9  # loosest final residual: the barrier's stiffness (pressure / gap) lifts the rounding floor


def follow_contact(
    phase: str,
    path: Callable[[float], Clamps],
    props: RodProperties,
    state: RodState,
    model: ContactModel,
    *,
    start: float = 0.0,
    control: StepControl = StepControl(),
    log: ContinuationLog | None = None,
    progress: Progress | None = None,
) -> tuple[RodState, int]:
    """Follow the stable equilibrium with contact from fraction `start` (where `state` is one) to 1.

    Returns (state at fraction 1, Newton iterations used).  log: if given, its iteration and step
    counters grow.  progress: optional callable(phase, fraction) after each step.  Raises
    PlacementError with the phase, the fraction and Newton's message when the path cannot be followed.
    """
    t, dt, iterations = start, min(control.first, 1.0 - start), 0
    while t < 1.0 - 1e-14:
        t_next = min(1.0, t + dt)
        tolerance = max(control.tolerance, CONTACT_TOLERANCE) if t_next == 1.0 else control.path_tolerance
        trial, report = solve_with_contact(props, path(t_next), state, model, tolerance=tolerance)
        iterations += report.iterations
        if log is not None:
            log.iterations += report.iterations
        if not report.converged or report.unstable_directions != 0:
            dt *= 0.5
            if dt < control.smallest:
                problem = report.message or f"{report.unstable_directions} unstable direction(s)"
                raise PlacementError(
                    f"placement phase '{phase}' with contact failed at fraction {t_next:.4f} (last converged "
                    f"{t:.4f}): residual {report.residual:.2e} ({problem})"
                )
            continue
        state, t = trial, t_next
        if log is not None:
            log.steps += 1
        if progress is not None:
            progress(phase, t)
        if report.iterations <= control.fast_iterations:
            dt = min(control.largest, 2.0 * dt)
    return state, iterations
