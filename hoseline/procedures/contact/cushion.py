"""A placement path with contact followed on a cushion: a wider barrier along the way, the model's own at the end.

Why.  The barrier (mechanics/contact.py) pushes across gaps below d_hat, 0.01 mm by default, and a
Newton step of the contact continuation is linear: where the hose slides along a round obstacle of
radius R, a step of length s brings it s^2 / 2R nearer, and the step filter admits no step that
shrinks a gap below a tenth of itself.  With the hose resting at gaps of a few thousandths of a
millimetre, each step slides it a fraction of a millimetre: the issue's case (the thesis hose,
a fixed clip, a strut pressing 1 mm into its path) took 1912 Newton iterations against the
cylinder and 7053 against the strut as 100 000 triangles, against 340 without contact.

How.  The path is followed with the barrier acting across CUSHION_RADII hose radii (the same
reference pressure, ContactModel.with_activation): the hose rests on a cushion about that deep
and slides on it in long steps (the same strut: 569 and 726 iterations in all).  At the end of the path
the cushion is narrowed NARROWING-fold at a time to the model's own d_hat, each a Newton solve
from the last state under the path's final clamps (6 to 9 iterations each on the strut), and the
end is polished as follow_contact's.  Where Newton fails a narrowing (the hose drops by about the
cushion's depth onto what it rests on: the plectoneme's passes of bench/bench_contact_placement.py,
and its drum before Newton's restoring steps carried it through), the hose settles there by a walk
downhill (minimise_with_contact), kept if no station moves more than SETTLING_DIAMETERS hose
diameters (the drum's moved 0.5 and 0.05 mm, the same equilibrium as the slow path below to 5e-13 mm,
in 53 Newton iterations instead of 80; tests/test_contact_cushion.py takes the restoring steps away
to reach it).  So
the result is an equilibrium with the model's barrier, and on the issue's case the one the path
with the model's barrier all along ends at (the same to 5e-13 mm with the cylinder,
tests/test_contact_cushion.py, and 2e-9 mm with the mesh).  Each
phase of the placement ends narrowed, before the end's and the fixed clips' roll is locked at the
torque-free angle: an angle found on the cushion belongs to a hose held off by it (locked there,
the same case ended 0.057 mm away, on another equilibrium).

A phase that starts where the last one ended (the twist phase, resting on the strut at gaps below
d_hat) is not in balance under the cushion, which pushes harder at those gaps: the barrier is first
widened to the cushion under the path's first clamps by a walk downhill (minimise_with_contact;
plain Newton meets an indefinite Hessian there and failed, the first step of the twist taken for a
fold: ten failed solves and a false snap event on the issue's strut as 100 000 triangles).

Where the widening, or a narrowing by Newton and downhill, does not end at a stable state, the event
is logged and the path is followed (again, from its start) with the model's own barrier: the slow
path, never a result of the cushion that the model's barrier does not confirm.
"""

from __future__ import annotations

from typing import Callable

from hoseline.mechanics.contact_newton import ContactModel, minimise_with_contact, solve_with_contact
from hoseline.mechanics.newton import RodProperties
from hoseline.mechanics.rod import Clamps, RodState
from hoseline.procedures.contact.continuation import CONTACT_TOLERANCE, follow_contact, largest_movement, polish
from hoseline.procedures.placement.continuation import ContinuationLog, Progress, StepControl

CUSHION_RADII = 0.2  # the barrier distance along a placement path, in hose radii (1 mm for the thesis hose; on the
# issue's case 0.06 r took 1.2 and 4.2 s, 0.5 r 0.87 and 4.6 s, 0.2 r 0.78 and 4.5 s: cylinder and mesh, one run each)
NARROWING = 10.0  # the cushion is narrowed by this factor at a time at the end of a path
WIDENING_ITERATIONS = 200  # of the downhill walks onto the cushion at a path's start (the strut: 12) and
# off it where a narrowing's Newton fails (the plectoneme of bench/bench_contact_placement.py: 18 and 10; its drum
# without Newton's restoring steps: 7 and 6)
SETTLING_DIAMETERS = 1.0  # the farthest a narrowing's walk downhill may move a station, in hose diameters (the drum:
# 0.05, the plectoneme 0.35): the cushion holds the hose off by a fifth of its radius


def follow_on_cushion(
    phase: str,
    path: Callable[[float], Clamps],
    props: RodProperties,
    state: RodState,
    model: ContactModel,
    *,
    start: float = 0.0,
    control: StepControl = StepControl(),
    log: ContinuationLog,
    progress: Progress | None = None,
) -> RodState:
    """Follow the stable equilibrium with contact from fraction `start` (where `state` is one) to 1 on a cushion of
    CUSHION_RADII hose radii, then narrow the barrier to the model's own d_hat (see the module doc).

    Returns the equilibrium at fraction 1 with `model`'s barrier.  log: its counters grow, snaps and a failed
    narrowing are recorded in log.events.  Raises PlacementError as follow_contact does.
    """
    def slow_path() -> RodState:  # the path followed with the model's own barrier all along
        return follow_contact(phase, path, props, state, model, start=start, control=control, log=log,
                              progress=progress)[0]

    cushion = CUSHION_RADII * model.hose_radius
    if cushion <= model.activation:
        return slow_path()
    widened = _widened(path(start), props, state, model, cushion, control, log)
    if widened is None:
        log.events.append(f"{phase}: the contact barrier did not widen to the cushion of {cushion:.3g} mm at fraction "
                          f"{start:.4f}; followed with the barrier of {model.activation:.3g} mm")
        return slow_path()
    cushioned = follow_contact(phase, path, props, widened, model.with_activation(cushion), start=start,
                               control=control, log=log, progress=progress)[0]
    clamps, narrowed, activation = path(1.0), cushioned, cushion
    while activation > model.activation:
        activation = max(activation / NARROWING, model.activation)
        last = activation == model.activation
        tolerance = max(control.tolerance, CONTACT_TOLERANCE) if last else control.path_tolerance
        narrowed, failure = _narrowed(props, clamps, narrowed, model.with_activation(activation), tolerance, log)
        if narrowed is None:
            log.events.append(f"{phase}: the contact cushion of {cushion:.3g} mm did not narrow to {activation:.3g} mm "
                              f"at the end of the path ({failure}); followed again with the barrier of "
                              f"{model.activation:.3g} mm")
            return slow_path()
    return polish(props, clamps, narrowed, model, log)[0]


def _narrowed(props: RodProperties, clamps: Clamps, state: RodState, model: ContactModel, tolerance: float,
              log: ContinuationLog) -> tuple[RodState | None, str]:
    """(the stable equilibrium under `clamps` with `model`'s barrier next to `state`, an equilibrium with a wider
    one, or None; why not).  Newton first; where it fails (the hose drops by about the cushion's depth, and its
    steps meet the narrower barrier's curvature), the hose settles downhill onto what it rests on
    (minimise_with_contact), accepted if no station moves more than SETTLING_DIAMETERS hose diameters: farther,
    it has left where the cushioned path put it, and the path followed with the model's barrier decides."""
    narrowed, report = solve_with_contact(props, clamps, state, model, tolerance=tolerance)
    log.iterations += report.iterations
    if report.converged and report.unstable_directions == 0:
        return narrowed, ""
    newton = report.message or f"{report.unstable_directions} unstable direction(s)"
    settled, report = minimise_with_contact(props, clamps, state, model, tolerance=tolerance,
                                            max_iterations=WIDENING_ITERATIONS)
    log.iterations += report.iterations
    if not report.converged or report.unstable_directions != 0:
        return None, f"{newton}; downhill: {report.message or f'{report.unstable_directions} unstable direction(s)'}"
    moved = largest_movement(props, clamps, state, settled)
    if moved > SETTLING_DIAMETERS * 2.0 * model.hose_radius:
        return None, f"{newton}; downhill it moved {moved:.3g} mm, more than {SETTLING_DIAMETERS:g} hose diameter(s)"
    return settled, ""


def _widened(clamps: Clamps, props: RodProperties, state: RodState, model: ContactModel, cushion: float,
             control: StepControl, log: ContinuationLog) -> RodState | None:
    """The stable equilibrium under `clamps` with the barrier widened from the model's d_hat to `cushion` (mm), downhill
    from `state` (minimise_with_contact); None if none is found.  `state` is an equilibrium with the model's barrier
    (a phase starting where the last one ended narrowed), which the cushion's wider barrier pushes off what it rests
    on; plain Newton from it meets an indefinite Hessian (a push of the wide barrier at a gap of thousandths of a mm
    against the curvature of the distance) and fails (the twist phase of the issue's strut failed ten times in a row,
    then was taken for a fold)."""
    widened, report = minimise_with_contact(props, clamps, state, model.with_activation(cushion),
                                            tolerance=control.path_tolerance, max_iterations=WIDENING_ITERATIONS)
    log.iterations += report.iterations
    return widened if report.converged and report.unstable_directions == 0 else None
