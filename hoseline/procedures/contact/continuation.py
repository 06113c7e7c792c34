"""Natural-parameter continuation of the equilibrium with contact along a path of clamps.

As procedures/placement/continuation.py's follow, with the contact Newton
(mechanics/contact_newton.py): each step starts from the previous equilibrium, which never
penetrates, so the step filter keeps every later state out of the obstacles too.  FoldWatch looks
ahead for folds (the determinant of the tangent Hessian, free from the converged Newton's factor,
asks the lowest eigenvalues where it falls towards zero): a step that would reach a predicted fold
is shortened to stop before it, and the hose snaps just past it without a Newton try.  A step that
does not converge is halved (or, where the path bisects a predicted fold, shortened towards it).
Stability is checked at every step.  Where the path
loses it (a step ends on an unstable equilibrium) or ends in a fold (the steps keep failing, or
a predicted fold is reached: the hose snaps), the hose is relaxed downhill to a stable
equilibrium at that fraction by the contact Newton's downhill mode (minimise_with_contact), the
snap is recorded as an event of the log with where it happened and how far the hose moved, and
the path is followed on from there; only if no stable equilibrium is found does the path fail
with PlacementError naming where.
With obstacles that move along the path (a sweep's, ObstaclePath) the previous equilibrium may be
inside them at the next fraction, or one may have passed through the hose on the way: each step
starts from a state the move check admits (procedures/contact/moving.py), else it is halved.
"""

from __future__ import annotations

from typing import Callable

import math

import numpy as np

from hoseline.mechanics.contact import SEGMENT_SEGMENT, STATION_KINDS
from hoseline.mechanics.contact_newton import (
    NEUTRAL_MODE,
    ContactModel,
    evaluate_contact,
    lowest_stiffnesses,
    minimise_with_contact,
    solve_with_contact,
    tangent_log_det,
)
from hoseline.mechanics.newton import NewtonReport, RodProperties
from hoseline.mechanics.rod import Clamps, RodState, centerline
from hoseline.procedures.contact.moving import ObstaclePath
from hoseline.procedures.placement.continuation import ContinuationLog, PlacementError, Progress, StepControl, secant

CONTACT_TOLERANCE = 1e-9  # loosest final residual: the barrier's stiffness (pressure / gap) lifts the rounding floor
DOWNHILL_ITERATIONS = 1000  # of minimise_with_contact after a fold: a snap may travel far (a loop forming: 430)
STEP_ITERATIONS = 60  # of solve_with_contact per step: a step not converged by then is halved (25 would halve
# more steps on the strut of bench/bench_contact_placement.py --mesh, 1.7 against 2.2 s, and cost the floor path of
# bench/bench_contact.py 40 %: 67 against 47 ms)
POLISHED_TOLERANCE = 1e-12  # what the end of a path is polished to, if POLISH_ITERATIONS reach it
POLISH_ITERATIONS = 6  # a 1 mm hose of 0.1 mm diameter on a sphere (fuzzing) needed 3 to 6: left at 1.03e-10 after 2
STALLED_ITERATIONS = 3  # of Newton steps cut below contact_newton.STALLED_STEP in a row: the path step is halved
STEP_HALVINGS = 10  # of a Newton step within a continuation step: a step that needs more is halved instead
LAST_STEP_HALVINGS = 30  # for the smallest step, before the branch is judged to end in a fold
MOST_SNAPS = 100  # of one path: a path that keeps snapping is not being followed (a coarse hose coiling on itself
# crept on by hundreds of tiny snaps for minutes in the fuzzing campaign): it fails, saying so
MOST_ITERATIONS = 20_000  # Newton iterations of one path: a path beyond them creeps (the fuzzing campaign's soft hose
# of 250 mm segments took 222 785 in 75 s before it failed; the strut takes 579, the plectoneme 1265)
FOLD_MODES = 2  # the lowest eigenvalues the fold predictor extrapolates to zero (the one that vanishes at the fold is
# not the lowest until close to it: on the plectoneme's first fold it was the second lowest 0.007 of the path before)
APPROACH = 0.75  # of the distance to a predicted fold: the step taken towards it (a late prediction is not passed;
# on the plectoneme they came early: 0.640, 0.652, 0.658 from 0.604 on, for a fold at 0.6616)
DETERMINANT_REACH = 4.0  # of the next step: a fold the determinant predicts within it has the eigenvalues asked (the
# determinant's other factors fall too: on the plectoneme 0.06 of the path before its first fold it predicted it 0.24 ahead)
PROBE = 0.01  # of control.first: the first step of a branch after a snap, from which the eigenvalues see a fold ahead (the
# plectoneme's second fold lies 0.0061 of its twist phase, 0.15 of its first step, past the first)
SMALLEST_MOVE = 1e-9  # of the path: the shortest step the move check of moving obstacles halves down to (an obstacle
# pushing the hose may move less than the gap, d_hat / 2 or less, per step until there is a prediction)


def follow_contact(
    phase: str,
    path: Callable[[float], Clamps],
    props: RodProperties,
    state: RodState,
    model: ContactModel | ObstaclePath,
    *,
    start: float = 0.0,
    control: StepControl = StepControl(),
    log: ContinuationLog | None = None,
    progress: Progress | None = None,
    before: RodState | None = None,
) -> tuple[RodState, int]:
    """Follow the stable equilibrium with contact from fraction `start` (where `state` is one) to 1.

    Returns (state at fraction 1, Newton iterations used).  model: the obstacles' ContactModel, or an
    ObstaclePath when they move along the path: each step then starts from the secant prediction of the
    last two equilibria (`before`, the equilibrium one whole path back, if given, stands in for the first)
    or from the last equilibrium, the first the move check admits (procedures/contact/moving.py); where
    neither is admitted the step is halved.  log: if given, its iteration and step counters grow and
    every snap (loss of stability or fold) is recorded in log.events.  progress: optional
    callable(phase, fraction) after each step.  Raises PlacementError with the phase, the fraction and
    Newton's message when the path cannot be followed, when it snaps more than MOST_SNAPS times or takes more
    than MOST_ITERATIONS Newton iterations, or when the obstacles cannot move on without passing through the
    hose (no admitted step longer than SMALLEST_MOVE).
    """
    moving = model if isinstance(model, ObstaclePath) else None
    clamps_now, placed = path(start), moving.at(start) if moving is not None else None
    previous = None if before is None else (start - 1.0, before)  # for the secant prediction
    t, dt, iterations, snaps = start, min(control.first, 1.0 - start), 0, 0
    folds = FoldWatch(props)
    folds.add(t, state, clamps_now, placed.model if moving is not None else model)  # (its determinant not known)
    fold_at = None  # a fold predicted just before t + dt: the hose snaps at t + dt without a Newton try
    while t < 1.0 - 1e-14:
        t_next = min(1.0, t + dt)
        clamps = path(t_next)
        tolerance = max(control.tolerance, CONTACT_TOLERANCE) if t_next == 1.0 else control.path_tolerance
        begin, model_next, placed_next = state, model, None
        if moving is not None:
            placed_next = moving.at(t_next)
            model_next = placed_next.model
            guesses = [state] if previous is None else [secant(previous, (t, state), t_next), state]
            begin = moving.obstacles.start(props, (clamps_now, state, placed), clamps, placed_next, guesses)
            if begin is None and 0.5 * dt < SMALLEST_MOVE:
                raise PlacementError(
                    f"{phase} with contact: the contact obstacles cannot move on from fraction {t:.4f} without "
                    f"passing through the hose (every step down to {dt:.2g} of the path would carry one across it or "
                    "into it); make the hose clear the moving obstacles, or move them less between poses")
            if begin is None:
                dt, fold_at = 0.5 * dt, None
                continue
        if fold_at is not None:  # FoldWatch: the branch ends in a fold just before t_next, where the hose snaps
            report, start_from = None, begin
            what = f"the equilibrium branch ended in a fold predicted at fraction {fold_at:.5f}"
        else:
            trial, report = _step(props, clamps, begin, model_next, tolerance, 0.5 * dt < control.smallest,
                                  moving is not None)
            iterations += report.iterations
            if log is not None:
                log.iterations += report.iterations
            if iterations > MOST_ITERATIONS:
                raise PlacementError(
                    f"placement phase '{phase}' with contact failed at fraction {t:.4f}: its path took more than "
                    f"{MOST_ITERATIONS} Newton iterations (the contact Newton converges too slowly for the path's "
                    f"steps to grow: a barrier far stiffer than the hose, segments {props.segment_length:.3g} mm long "
                    f"for a hose of outer radius {model_radius(model):.3g} mm, stiffness up to "
                    f"{props.largest_stiffness:.3g} N*mm^2); try more segments, or place without the obstacles or "
                    "self-contact and read the clearance")
            start_from, what = None, ""
            if report.converged and report.unstable_directions != 0:  # lost stability between t and t_next
                start_from, what = trial, (f"stability lost between fractions {t:.4f} and {t_next:.4f} "
                                           f"({report.unstable_directions} unstable direction(s))")
            elif not report.converged and 0.5 * dt >= control.smallest:
                dt = folds.failed(t, dt)  # halved, or shortened towards a fold predicted within the try
                continue
            elif not report.converged:  # the branch ends in a fold: the hose snaps
                start_from, what = begin, f"the equilibrium branch ended near fraction {t:.4f} (fold)"
        if start_from is not None:
            relaxed, downhill = _snap(phase, clamps, props, state, start_from, model_next, tolerance, t_next, what, log)
            iterations += downhill.iterations
            if relaxed is None and fold_at is not None:  # no stable state past the predicted fold: halve as before
                dt, fold_at, folds.aim, folds.trusted = 0.5 * dt, None, None, False
                continue
            if relaxed is None:
                raise _nothing_stable(phase, props, t, t_next, report, downhill, state,
                                      (clamps_now, placed.model if moving is not None else model))
            snaps += 1
            if snaps > MOST_SNAPS:
                h = props.segment_length
                raise PlacementError(
                    f"placement phase '{phase}' with contact failed at fraction {t_next:.4f}: the hose snapped more than "
                    f"{MOST_SNAPS} times on the way (it keeps meeting folds: a hose coiling onto itself or creeping "
                    f"along an obstacle); segments {h:.3g} mm long for a hose of outer radius {model_radius(model):.3g} mm"
                    " may be too coarse to follow it: try more segments, less twist or obstacles further from the path")
            trial, folds = relaxed, FoldWatch(props, probing=True)  # a new branch: a short first step, to see ahead
            dt, report = min(PROBE * control.first, 1.0 - t_next), downhill
        previous = (t, state) if start_from is None else None  # no secant across a snap
        folds.add(t_next, trial, clamps, model_next,
                  math.nan if report.factored is None else tangent_log_det(*report.factored))
        state, t, clamps_now, placed = trial, t_next, clamps, placed_next
        if log is not None:
            log.steps += 1
        if progress is not None:
            progress(phase, t)
        fold_at = None
        if folds.aim is not None:  # this step went towards a predicted fold
            dt, fold_at = folds.converged(t, control)
        elif start_from is None:
            grown = dt
            if folds.probing:  # the first step of a branch after a snap: on at the usual first step, if no fold is near
                grown = control.first
            elif report.iterations <= control.fast_iterations:
                grown = min(control.largest, 2.0 * dt)
            dt = folds.ahead(t, grown)
    state, used = polish(props, path(1.0), state, placed.model if moving is not None else model, log)
    return state, iterations + used


class FoldWatch:
    """Where the branch being followed ends in a fold, predicted from its last two equilibria (docs/model.md,
    Contact, "Passing folds").

    At a fold an eigenvalue lambda of the Hessian on the constraint tangent space (N*mm/rad^2) goes to zero as
    sqrt(t_fold - t) (t: the path fraction), so lambda^2 is linear in t near it.  The one that vanishes may lie above
    another until close to the fold, where the two cross (an avoided crossing: each turns sharply), so the watch
    extrapolates the square of the product of the FOLD_MODES lowest (smooth through such a crossing, linear near the
    fold while the other stays finite) along the line through the last two equilibria to zero.
    It looks ahead (`ahead`, after each converged step):
    - the eigenvalues (dense: contact_newton.lowest_stiffnesses, 0.5 ms for 50 segments, 2 ms for 100) are asked only
      where the square of the determinant of that Hessian (contact_newton.tangent_log_det, free from the converged
      Newton's factor) extrapolates to zero within DETERMINANT_REACH of the next step, or after the first, short
      (PROBE) step of a branch that starts at a snap; and once they saw no fold near, not again on the branch until
      log |det| falls faster (per unit of the path) than it did there: the determinant also falls where the hose lets
      go of a contact (the barrier's stiffness leaves it), which is no fold (the strut of bench_contact_placement.py
      --mesh: 10 eigenvalue solves found none), while towards a fold the fall steepens without end;
    - where they predict a fold in the later half of the next step (or anywhere in it after a probe), the path steps
      APPROACH of the way to it (a fold first predicted nearer, in the first half, is no fold: a genuine one would have
      been seen from the equilibrium before; the strut's lowest eigenvalues fall 17-fold as the hose slides on it and
      rise again, and that prediction, 0.012 ahead of a step of 0.2, receded after each step towards it);
    - after each step towards it the next prediction must come nearer (`converged`), else the watch ends and the path
      takes the step it would have taken (`fallback`);
    - once the fold is within two control.smallest after a prediction that came nearer, the path steps
      control.smallest past it, where the hose snaps without a Newton try; if nothing stable is found downhill there,
      the path halves as before and the watch is off for the branch (`trusted`).
    Behind it, for a fold the look-ahead missed (`failed`): at the second failed try in a row from an equilibrium that
    was itself reached by a step shortened after a failure (the path bisecting; a try that fails where half of it
    converges and the path grows on from there was a step grown too long: no eigenvalues), a fold predicted in the
    later half of the failed try is stepped towards as above, else the try is halved.
    """

    def __init__(self, props: RodProperties, probing: bool = False):
        self.props = props
        self.points: list[list] = []  # [t, state, clamps, model, product^2 or None, log |det|] of the last two
        self.probing = probing  # the branch starts at a snap: its first step is short, and the eigenvalues are asked
        self.aim: float | None = None  # the distance (fraction) to the fold the last step went towards, if it did
        self.fallback = 0.0  # the step that halving would have taken: where the fold recedes, the path goes on with it
        self.failures = 0  # path steps from the last equilibrium that failed
        self.bisecting = False  # the last equilibrium was reached by a step shortened after a failure
        self.trusted = True  # False once a predicted fold proved wrong on this branch (nothing stable past it)
        self.calm: float | None = None  # the determinant's fall (_determinant_fall) where the eigenvalues last saw no
        # fold near on this branch: not asked again while it falls no faster (a contact let go, not a fold)

    def add(self, t: float, state: RodState, clamps: Clamps, model: ContactModel, log_det: float = math.nan) -> None:
        """An equilibrium of the branch at fraction t, held by `clamps`, against `model`; log_det: log |det| of its
        Hessian on the constraint tangent space (contact_newton.tangent_log_det), NaN if not known."""
        self.points = self.points[-1:] + [[t, state, clamps, model, None, log_det]]
        self.bisecting, self.failures = self.failures > 0, 0

    def _determinant_fold(self) -> float | None:
        """The fraction where the square of the determinant of the Hessian on the constraint tangent space (the product
        of all its eigenvalues, which the converged Newton's factor gives free) extrapolates to zero along the line
        through the last two equilibria, or None (fewer, a determinant not known, or not falling)."""
        if len(self.points) < 2:
            return None
        (t0, *_, before), (t1, *_, now) = self.points[-2:]
        ratio = math.exp(2.0 * (now - before))  # det^2 now / det^2 before (NaN where either is not known)
        return t1 + ratio * (t1 - t0) / (1.0 - ratio) if ratio < 1.0 else None

    def ahead(self, t: float, dt: float) -> float:
        """The next step from the equilibrium at fraction t, where the path would step dt: APPROACH of the way to a fold
        the lowest eigenvalues predict within dt (the watch starts), asked where the determinant predicts a fold within
        DETERMINANT_REACH * dt or on the first step after a snap; else dt."""
        probing, self.probing = self.probing, False
        if not self.trusted:
            return dt
        fall = self._determinant_fall()
        if not probing:
            near = self._determinant_fold()
            if near is None or near > t + DETERMINANT_REACH * dt:
                return dt
            if self.calm is not None and fall <= self.calm:  # falling no faster than where no fold was near
                return dt
        ahead = self.fold()
        nearest = t if probing else t + 0.5 * dt  # a fold first predicted in the first half of a step: see the class doc
        if ahead is None or not nearest < ahead <= min(t + dt, 1.0):  # (a fold past the path's end is not met)
            self.calm = fall if math.isfinite(fall) else None
            return dt
        self.aim, self.fallback, self.calm = ahead - t, dt, None
        return APPROACH * self.aim

    def _determinant_fall(self) -> float:
        """How fast log |det| of the Hessian on the constraint tangent space falls between the last two equilibria,
        per unit of the path fraction (negative where it rises; NaN where either is not known)."""
        if len(self.points) < 2:
            return math.nan
        (t0, *_, before), (t1, *_, now) = self.points[-2:]
        return (before - now) / (t1 - t0)

    def _squared(self, point: list) -> float:
        """The product of the FOLD_MODES lowest eigenvalues at an equilibrium, squared (NaN if there are fewer)."""
        if point[4] is None:
            values = lowest_stiffnesses(evaluate_contact(self.props, point[2], point[1], point[3]), FOLD_MODES)
            point[4] = float(np.prod(values)) ** 2 if values.size == FOLD_MODES else math.nan
        return point[4]

    def fold(self) -> float | None:
        """The fraction of the fold predicted from the last two equilibria, or None (fewer, or the product not falling
        between them)."""
        if len(self.points) < 2 or not self.trusted:
            return None
        (t0, *_), (t1, *_) = self.points
        now = self._squared(self.points[1])
        if not now > 0.0:  # (NaN fails)
            return None
        before = self._squared(self.points[0])
        return t1 + now * (t1 - t0) / (before - now) if now < before else None

    def failed(self, t: float, dt: float) -> float:
        """The next step from the equilibrium at fraction t after a try dt long from it failed: APPROACH of the way to
        a fold predicted in the later half of the failed try where the path is bisecting (the watch starts), else half
        the failed try as before."""
        self.failures += 1
        ahead = self.fold() if self.aim is None and self.bisecting and self.failures >= 2 else None
        if ahead is None or not t + 0.5 * dt <= ahead <= t + dt:
            self.aim = None
            return 0.5 * dt
        self.aim, self.fallback = ahead - t, 0.5 * dt
        return APPROACH * self.aim

    def converged(self, t: float, control: StepControl) -> tuple[float, float | None]:
        """(the next step, the fold's fraction if the hose snaps at its end) after a step towards a fold converged at
        fraction t: where the fold's prediction came nearer, APPROACH of the way on to it, or once it is within two
        control.smallest (where halving makes its last try), control.smallest past it, where the hose snaps; else the
        watch ends with the fallback step."""
        ahead = self.fold()
        if ahead is None or ahead - t >= self.aim:
            self.aim = None
            return self.fallback, None
        self.aim = ahead - t
        if self.aim <= 2.0 * control.smallest and ahead < 1.0:
            return self.aim + control.smallest, ahead
        return min(control.largest, APPROACH * self.aim), None


def polish(props: RodProperties, clamps: Clamps, state: RodState, model: ContactModel,
           log: ContinuationLog | None = None) -> tuple[RodState, int]:
    """(state, iterations): the end of a path polished.  Newton converges quadratically, so a few more iterations
    (at most POLISH_ITERATIONS) take the residual from CONTACT_TOLERANCE to rounding (the load balance then holds to
    its last digits); the polished state is kept if it converged stable, else `state`."""
    polished, report = solve_with_contact(props, clamps, state, model, tolerance=POLISHED_TOLERANCE,
                                          max_iterations=POLISH_ITERATIONS)
    if log is not None:
        log.iterations += report.iterations
    if report.converged and report.unstable_directions == 0:
        return polished, report.iterations
    return state, report.iterations


def largest_movement(props: RodProperties, clamps: Clamps, before: RodState, after: RodState) -> float:
    """The largest distance (mm) a station moved from `before` to `after`, both held by `clamps`."""
    h = props.segment_length
    return float(np.max(np.linalg.norm(centerline(after.frames, clamps.start_point, h)
                                       - centerline(before.frames, clamps.start_point, h), axis=1)))


def model_radius(model: ContactModel | ObstaclePath) -> float:
    """The hose's outer radius (mm) of a contact model, or of the design model of moving obstacles."""
    return model.obstacles.design.hose_radius if isinstance(model, ObstaclePath) else model.hose_radius


CRUSHED_NEXT_TO = 2  # segments: a hardest push this close to a held station is blamed on that station's path


def hardest_push(props: RodProperties, clamps: Clamps, state: RodState, model: ContactModel) -> str:
    """Where the hose of `state` is pressed hardest (obstacle, segment or station, push N, gap mm), for the message
    of a path that cannot go on; next to the end fitting or a clip, what drives it there and what to do ("" if
    nothing touches)."""
    h = props.segment_length
    nodes = centerline(state.frames, clamps.start_point, h)
    kinds, first, second, _ = model.pairs(nodes, model.activation)
    if kinds.size == 0:
        return ""
    terms = model.terms(nodes, model.stiffness * h, kinds, first, second)
    forces, gaps = terms[3], terms[6]
    hardest = int(np.argmax(np.linalg.norm(forces, axis=1)))
    kind, where = int(kinds[hardest]), int(first[hardest])
    place = f"station {where}" if kind in STATION_KINDS else f"segment {where}"
    text = (f". Where the path last reached, the hose is pressed hardest against "
            f"{model.owner(kind, int(second[hardest]))!r} at {place} ({np.linalg.norm(forces[hardest]):.4g} N, gap "
            f"{gaps[hardest]:.2g} mm)")
    if kind == SEGMENT_SEGMENT:  # the hose against itself
        return text + (": the hose cannot pass through itself on this path. Give it more length or less twist, move "
                       "the mounts apart, or place it without self-contact (self = false) and read its clearance")
    held = [(clip.node, f"the clip at station {clip.node}") for clip in clamps.clips]
    held.append((props.segments, "the end fitting"))
    near = [name for node, name in held if abs(node - where) <= CRUSHED_NEXT_TO]
    if near:
        text += (f", next to {near[0]}: the placement carries it on a straight line from where it sits on the straight "
                 "hose (the end fitting turning onto its mount), and that line drives the hose into the obstacle. Move "
                 "the obstacle or the mount or clip, or place without the obstacle and read its clearance")
    return text


def _step(props: RodProperties, clamps: Clamps, begin: RodState, model: ContactModel, tolerance: float,
          last_try: bool, start_is_clear: bool) -> tuple[RodState, NewtonReport]:
    """One path step's Newton from `begin` (clear of the obstacles; start_is_clear: the move check showed it) under
    `clamps`; the last try, at the smallest step, gets more halvings of its Newton steps and is not stopped as
    stalled."""
    return solve_with_contact(props, clamps, begin, model, tolerance=tolerance, max_iterations=STEP_ITERATIONS,
                              max_halvings=LAST_STEP_HALVINGS if last_try else STEP_HALVINGS,
                              start_is_clear=start_is_clear, stall=0 if last_try else STALLED_ITERATIONS)


def _snap(phase: str, clamps: Clamps, props: RodProperties, before: RodState, start_from: RodState,
          model: ContactModel, tolerance: float, t_next: float, what: str,
          log: ContinuationLog | None) -> tuple[RodState | None, NewtonReport]:
    """The stable equilibrium downhill of `start_from` under `clamps` (the snap at fraction t_next; None if there is
    none) and the downhill walk's report; the event goes to the log (`before`: the last equilibrium, for how far the
    hose moved)."""
    relaxed, report = minimise_with_contact(props, clamps, start_from, model, tolerance=tolerance,
                                            max_iterations=DOWNHILL_ITERATIONS)
    if log is not None:
        log.iterations += report.iterations
    if not report.converged or report.unstable_directions != 0:
        return None, report
    if report.message == NEUTRAL_MODE:  # no snap: the step only looked unstable
        return relaxed, report
    jump = largest_movement(props, clamps, before, relaxed)
    if log is not None:
        log.events.append(f"{phase}: {what}; with contact, the hose snaps downhill to a stable equilibrium at "
                          f"fraction {t_next:.4f}, largest station movement {jump:.3f} mm")
    return relaxed, report


def _nothing_stable(phase: str, props: RodProperties, t: float, t_next: float, failure: NewtonReport,
                    downhill: NewtonReport, before: RodState, reached: tuple[Clamps, ContactModel]) -> PlacementError:
    """The error of a path that found no stable equilibrium downhill at fraction t_next, saying where `before` (the
    equilibrium at fraction t) is pressed hardest under `reached`, the clamps and contact model at fraction t
    (obstacles that move along the path have moved on by t_next, into where the hose was)."""
    problem = failure.message or f"{failure.unstable_directions} unstable direction(s)"
    return PlacementError(
        f"placement phase '{phase}' with contact failed at fraction {t_next:.4f} (last converged {t:.4f}): "
        f"residual {failure.residual:.2e} ({problem}), and no stable equilibrium was found downhill "
        f"({downhill.message or f'{downhill.unstable_directions} unstable direction(s)'})"
        + hardest_push(props, reached[0], before, reached[1]))
