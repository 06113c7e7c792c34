"""Placement of a hose by continuation: Keil & Thomas' divide and conquer.

1. The hose starts straight on the start mount (its tangent along start.direction).
2. Phase "place": its free end is carried to the end mount: the position along the
   straight line to the end point, the frame rotated about n = t0 x t1 (the cross product
   of the two tangents) into the end tangent t1 = -end.direction, while the end is free to
   spin about its own axis (no twist locked in).  Gravity is ramped in with the same
   fraction (a straight hose cannot carry a sideways load).
3. The torque-free roll found there is recorded (the lock angle) and clamped.
4. Phase "twist": the end fitting is turned about end.direction to the requested angle.

The very first move shortens the chord of a straight, inextensible hose: a buckling
bifurcation.  Both sides of the buckle in the bending plane are solved and the stable one
of lower energy is kept (the end rotation decides it); the out-of-plane sides are tried
only when neither in-plane side is stable.  Stability is monitored along the whole path
(see continuation.py).

With contact (Problem.contact, Problem.self_contact) the same sequence runs with the contact
Newton (procedures/contact/): after the first step (taken without contact, from the straight
hose, which must clear every obstacle, as must the buckled shape) the place and twist phases
and the final equilibrium keep the hose out of the obstacles and itself (each phase followed on a
cushion, a wider barrier narrowed to the model's at its end: procedures/contact/cushion.py); the
result reports the contacts per obstacle.  The mounts' symmetry images and the error estimate are
skipped then.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from hoseline.mechanics import clipped_newton
from hoseline.mechanics.braid import braid_coefficients
from hoseline.mechanics.clipped_newton import clip_rolls
from hoseline.mechanics.newton import RodProperties, end_frame_of, node_positions, solve_equilibrium, total_energy
from hoseline.mechanics.rod import Clamps, ClipHold, RodState
from hoseline.mechanics.rotations import perpendicular, rotate_frames, rotation_matrix, rotation_vector
from hoseline.mechanics.stiffeners import spring_set
from hoseline.model.hose import MIN_SEGMENTS, Hose
from hoseline.model.preset import preset_rest_rotations
from hoseline.model.problem import Problem
from hoseline.procedures.placement.continuation import (
    ContinuationLog,
    PlacementError,
    Progress,
    StepControl,
    follow,
    relax_to_stable,
)
from hoseline.procedures.placement.path import PlacementPath, tangent_turn
from hoseline.procedures.placement.result import Result
from hoseline.procedures.placement.stiffening import phase_in_springs
from hoseline.procedures.placement.stations import build_result
from hoseline.procedures.placement.accuracy import coarse_guess, coarse_segments, richardson_error
from hoseline.procedures.placement.uniqueness import DISTINCT, fork_branches, judge_uniqueness, other_way_round, symmetric_images

if TYPE_CHECKING:
    from hoseline.procedures.contact.bring_in import BroughtIn

# The contact modules (procedures/contact/, mechanics/contact*.py, with SciPy's linear algebra and sparse graphs) are
# imported where a placement with contact uses them, so that one without contact does not load them.

__all__ = ["solve", "PlacementError", "rod_properties"]


def rod_properties(problem: Problem) -> RodProperties:
    """Internal-unit rod properties of the problem's hose (with its stiffener springs, preset and braid, if any)."""
    hose = problem.hose
    return RodProperties(hose.stiffness_vector, hose.segment_length, int(hose.segments), stiffener_springs(hose),
                         preset_rest_rotations(hose.preset, int(hose.segments), hose.segment_length), braid_data(hose))


def braid_data(hose: Hose) -> np.ndarray | None:
    """The hose's braid coupling packed for the kernels (mechanics/braid.py), or None without a braid."""
    braid = hose.braid
    if braid is None:
        return None
    return braid_coefficients(int(braid.strands), braid.strand_axial_stiffness, braid.angle_deg,
                              braid.layer_radius(hose.outer_radius), braid.slack_strain)


def stiffener_springs(hose: Hose) -> tuple | None:
    """The hose's stiffener springs packed for the kernels, or None for the plain rod.

    Inside the hose a spring spans a segment; at each fitting it spans half of one (the
    joint there is h/2 long), anchored at the same points round the axis.
    """
    stiffeners = hose.stiffeners
    if stiffeners is None:
        return None
    h = hose.segment_length
    full = stiffeners.anchors(hose.outer_radius, h, h)
    half = stiffeners.anchors(hose.outer_radius, h, 0.5 * h)
    return spring_set(full, half, stiffeners.table.deformation, stiffeners.table.force)


def solve(
    problem: Problem,
    *,
    progress: Progress | None = None,
    alternatives: bool = False,
    control: StepControl = StepControl(),
    estimate_error: bool = True,
    check_uniqueness: bool = True,
    force_accuracy: float | None = None,
) -> Result:
    """Place the hose of `problem` and return its stable equilibrium.

    progress: optional callable(phase, fraction) called after each continuation step.
    alternatives: also return the other stable equilibria found (as Results in result.alternatives).
    estimate_error: estimate the discretisation error from one coarser solve (result.discretisation_error, mm).
    check_uniqueness: search for other stable equilibria (uniqueness.py); without it result.unique is None ("not
    checked", result.unchecked says so), for a caller that reads the shape only (a study's sweep samples).
    Raises PlacementError with the phase, fraction and residual when the path cannot be followed; ValueError for
    alternatives without check_uniqueness.
    force_accuracy: with obstacles, a relative accuracy (e.g. 0.005) of each obstacle's total force and the mounts'
    reactions: the placed hose is then carried to twice its segments, and again, until the estimated error is
    within it (force_accuracy.py; result.force_refinement says how far it got); the shape, forces and error estimate
    returned are the finest, the uniqueness verdict and the alternatives the placement's.
    """
    if alternatives and not check_uniqueness:
        raise ValueError("solve: alternatives need check_uniqueness=True (the other equilibria are what it finds)")
    started = time.perf_counter()
    props = rod_properties(problem)
    log = ContinuationLog()
    sequence = _Sequence(problem, props, control, progress)
    state, first = _initial_buckle(sequence.place_props, sequence.path.place, control.first, sequence.path.axis, log)
    state = sequence.clear_buckle(state, first, log)
    final, state, lock_angle_deg, residual = sequence.finish(log, "place", first, state)

    result = build_result(problem, props, final, state, lock_angle_deg, log, started, residual)
    if sequence.contact is not None:
        from hoseline.procedures.contact.placement import with_contact

        result = with_contact(result, props, final, state, sequence.contact)
        result.obstacle_placement = sequence.brought_in or []
    if check_uniqueness:
        others = fork_branches(props, final, state, log.forks, sequence.finish)
        if sequence.contact is None:
            others += symmetric_images(problem, props, final, state, lock_angle_deg)  # with clips: those they allow
        else:
            result.events.append("uniqueness: with contact, the mounts' symmetry images are not checked (the obstacles "
                                 "need not share the symmetry); the other branches of the first buckle are")
        # after the images: where the mirror is the other way's shape, its origin says why
        others += other_way_round(problem, sequence.twist_start, sequence.finish, others)
        others = judge_uniqueness(result, props, final, state, others, log.forks)
    else:
        result.path_forks = [fork.describe() for fork in log.forks]
        result.unique, result.unchecked = None, "the search for other equilibria was not asked for"
    if alternatives:
        result.alternatives = [
            build_result(problem, props, other.clamps, other.state, other.lock_angle_deg, log, started, residual)
            for other in others
        ]
        if sequence.contact is not None:
            result.alternatives = [
                with_contact(other_result, props, other.clamps, other.state, sequence.contact)
                for other_result, other in zip(result.alternatives, others)
            ]
    if force_accuracy is not None and problem.contact:
        result = _refined_for_forces(sequence, result, final, state, force_accuracy, log, started)
    elif estimate_error and sequence.contact is not None:  # accuracy.contact_errors: half the segments, half d_hat
        from hoseline.mechanics.contact_newton import solve_with_contact
        from hoseline.procedures.contact.continuation import CONTACT_TOLERANCE
        from hoseline.procedures.placement.accuracy import BARRIER_NARROWING, contact_errors, snapshot

        coarse_count = coarse_segments(props.segments, MIN_SEGMENTS)
        narrowed_model = sequence.contact.with_activation(BARRIER_NARROWING * sequence.contact.activation)
        narrowed, narrowed_report = solve_with_contact(props, final, state, narrowed_model,
                                                       tolerance=max(control.tolerance, CONTACT_TOLERANCE))
        coarse = None
        if coarse_count < props.segments and narrowed_report.converged:
            try:
                coarse = solve(replace(problem, hose=replace(problem.hose, segments=coarse_count)), control=control,
                               estimate_error=False, progress=progress)
            except PlacementError as error:
                result.events.append(f"accuracy: the placement with {coarse_count} segments failed: {error}")
        if coarse is None or _coarse_clamps(final, state, props.segments, coarse_count, props.length) is None:
            result.events.append(f"accuracy: with contact, the discretisation error is not estimated (it needs the "
                                 f"placement with {coarse_count} segments, every clip on one of its stations, and the "
                                 "equilibrium with half the barrier's reach)")
        else:
            narrowed_result = with_contact(
                build_result(problem, props, final, narrowed, lock_angle_deg, log, started, residual), props, final,
                narrowed, narrowed_model, stability=False)
            errors = contact_errors(snapshot(result), snapshot(coarse), snapshot(narrowed_result))
            result.discretisation_error = errors.station
            result.events.append(errors.describe())
    elif estimate_error:
        coarse_count = coarse_segments(props.segments, MIN_SEGMENTS)
        coarse_final = _coarse_clamps(final, state, props.segments, coarse_count, props.length)
        if coarse_final is None:
            result.events.append(f"accuracy: the discretisation error is not estimated: a clip is not on a station of "
                                 f"the {coarse_count}-segment hose of the coarse solve, or two held stations are less "
                                 "than two segments apart there (use an even station count, or more segments)")
        else:  # the coarse rod only: its clamps carry the clips on the coarse stations
            coarse = rod_properties(replace(problem, hose=replace(problem.hose, segments=coarse_count), clips=()))
            if not problem.clips:
                coarse_final = _coarse_lock(sequence, coarse, coarse_final, control.tolerance, result.events)
            result.discretisation_error = (None if coarse_final is None else
                                           richardson_error(props, coarse, coarse_final, state, control.tolerance, final))
    result.wall_time = time.perf_counter() - started
    return result


def _refined_for_forces(sequence: "_Sequence", placed: Result, final: Clamps, state: RodState, accuracy: float,
                        log: ContinuationLog, started: float) -> Result:
    """The placed result carried to twice its segments, and again, until the estimated relative error of the obstacles'
    forces and the mounts' reactions is within `accuracy` (force_accuracy.py); its uniqueness verdict, alternatives
    and obstacle sides are the placement's, its events the placement's and the refinement's."""
    from hoseline.mechanics.contact_newton import solve_with_contact
    from hoseline.procedures.contact.bring_in import bring_in
    from hoseline.procedures.contact.continuation import CONTACT_TOLERANCE
    from hoseline.procedures.contact.placement import (problem_contact_model, stability_margin_with_contact,
                                                       with_contact)
    from hoseline.procedures.placement.accuracy import BARRIER_NARROWING, contact_errors, snapshot
    from hoseline.procedures.placement.force_accuracy import (DOUBLINGS, ENTRY_CLEARANCE, FORCE_MARGIN, ForceRefinement,
                                                              observed_order, prolonged, relative_error)

    problem, control = sequence.problem, sequence.control
    counts, notes, shots = [int(problem.hose.segments)], [], [snapshot(placed)]
    finest, estimated, finest_parts = placed, None, None

    def ended(met: bool, why: str = "") -> Result:
        if finest_parts is not None:  # the barrier's stability margin of the result returned only (a dense eigenproblem)
            finest.stability_margin = stability_margin_with_contact(*finest_parts)
        finest.force_refinement = ForceRefinement(accuracy, tuple(counts), estimated, met, why)
        if not met:
            finest.events.append(f"force accuracy {100 * accuracy:g} % not reached: {why}")
        return finest

    if not any(np.any(contact.total_force) for contact in placed.contacts if contact.name != "self"):
        placed.events.append("force accuracy: no obstacle touches the hose, so the segments stay as placed")
        return placed
    if any(clip.slides for clip in problem.clips):
        return ended(False, "a sliding clip's station is not carried to a finer hose")
    if sequence.brought_in is not None:
        sides = [choice.hose_side for choice in sequence.brought_in]
    else:
        sides = list(problem.contact_sides) or [None] * len(problem.contact)
    weight = float(np.linalg.norm(final.line_weight)) * problem.hose.length  # N
    clamps, current = final, state
    for _ in range(DOUBLINGS):
        fine_problem = replace(problem, hose=replace(problem.hose, segments=2 * counts[-1]))
        props = rod_properties(fine_problem)
        clamps, start = prolonged(clamps, current)
        model = problem_contact_model(fine_problem)
        try:
            current, _, residual = bring_in(problem.contact, sides, props, clamps, start, model, control=control,
                                            clearance=ENTRY_CLEARANCE * model.activation)
        except PlacementError as error:
            return ended(False, f"the hose of {props.segments} segments could not be brought to the obstacles again "
                                f"({error})")
        narrowed_model = model.with_activation(BARRIER_NARROWING * model.activation)
        narrowed, report = solve_with_contact(props, clamps, current, narrowed_model,
                                              tolerance=max(control.tolerance, CONTACT_TOLERANCE))
        if not report.converged:
            return ended(False, f"the equilibrium of {props.segments} segments with half the barrier's reach did not "
                                "converge (its error is not estimated)")
        fine = with_contact(build_result(fine_problem, props, clamps, current, placed.lock_angle_deg, log, started,
                                         residual), props, clamps, current, model, stability=False)
        narrowed_shot = snapshot(with_contact(build_result(fine_problem, props, clamps, narrowed, placed.lock_angle_deg,
                                                           log, started, report.residual), props, clamps, narrowed,
                                              narrowed_model, stability=False))
        shots.append(snapshot(fine))
        if len(shots) < 3:  # two counts: order 1, the contact estimate's
            errors = contact_errors(shots[-1], shots[-2], narrowed_shot)
            estimated = relative_error(errors, shots[-1], weight)
        else:
            errors = contact_errors(shots[-1], shots[-2], narrowed_shot, observed_order(*shots[-3:]))
            estimated = FORCE_MARGIN * relative_error(errors, shots[-1], weight)
        counts.append(props.segments)
        fine.discretisation_error = errors.station
        for name in ("unique", "unchecked", "other_equilibria", "path_forks", "alternatives", "obstacle_placement"):
            setattr(fine, name, getattr(placed, name))
        notes.append(f"force accuracy: {props.segments} segments, estimated relative error of the forces and "
                     f"reactions {100 * estimated:.3g} % ({100 * accuracy:g} % asked); {errors.describe()}")
        fine.events = placed.events + notes
        finest, finest_parts = fine, (props, clamps, current, model)
        if estimated <= accuracy:
            return ended(True)
    return ended(False, f"{DOUBLINGS} doublings of the segments (the default's cost limit); give hose.segments, or "
                        "--accuracy, for more")


class _Sequence:
    """The published sequence after the first step, from any phase and fraction: the rest of
    the place phase (end roll free), the lock, the twist, and the final equilibrium."""

    def __init__(self, problem: Problem, props: RodProperties, control: StepControl, progress: Progress | None):
        self.problem, self.props, self.control, self.progress = problem, props, control, progress
        if problem.hose.stiffeners is not None and any(clip.slides for clip in problem.clips):
            raise PlacementError("placement: a sliding clip on a hose with stiffeners is not supported (the springs' "
                                 "law under the stretch of the spans next to the clip is not modelled); use a rotating "
                                 "clip at a chosen arc_length or remove the stiffeners")
        self.path = PlacementPath(problem)
        self.place_props = replace(props, springs=None)  # stiffener springs come in once placed (stiffening.py)
        self.locked_frame: np.ndarray | None = None  # of the main run, for forks met while twisting
        self.locked_state: RodState | None = None  # the main run's equilibrium at the lock (end roll free)
        self.twist_start: RodState | None = None  # the same with the roll locked: where the twist phase starts
        self.locked_clips: tuple[ClipHold, ...] = ()
        self.lock_angle_deg = 0.0
        # the model the sequence follows: with "bring_in" self-contact only (None without it), the obstacles
        # brought in after the free placement (procedures/contact/bring_in.py); with "along_path" all of it
        self.contact = self.path_contact = None
        if problem.has_contact:
            from hoseline.mechanics.contact_motion import only
            from hoseline.procedures.contact.placement import problem_contact_model

            self.contact = self.path_contact = problem_contact_model(problem)
            if problem.contact and problem.contact_placement == "bring_in":
                self.path_contact = only(self.contact, [], self_contact=True) if problem.self_contact else None
        self.brought_in: list[BroughtIn] | None = None  # how each obstacle came in, on the main run
        self.main_end: tuple[Clamps, RodState, float, float] | None = None  # what finish returned on the main run

    def clear_buckle(self, state: RodState, fraction: float, log: ContinuationLog) -> RodState:
        """With contact, the first buckled shape (of `state` and the other sides relaxed at the first step, at
        `fraction` of the place phase) that clears every obstacle, noted as an event when it is not `state`;
        `state` itself without contact."""
        if self.path_contact is None or not log.forks:
            return state
        from hoseline.procedures.contact.placement import is_clear

        clamps = self.path.place(fraction)
        for other in log.forks[-1].others:
            if is_clear(self.props, clamps, state, self.path_contact):
                break
            if is_clear(self.props, clamps, other, self.path_contact):
                log.events.append("place: with contact, kept the buckled side that clears the obstacles (the one of "
                                  "lowest energy enters one)")
                return other
        return state

    def _follow(self, phase: str, path, props: RodProperties, state: RodState, log: ContinuationLog, fraction: float,
                control: StepControl) -> RodState:
        """follow, or with contact follow_on_cushion (procedures/contact/cushion.py: the contact continuation on a
        wider barrier, narrowed to the model's at the end of the phase, before any roll is locked)."""
        if self.path_contact is None:
            return follow(phase, path, props, state, log, start=fraction, control=control, progress=self.progress)
        from hoseline.procedures.contact.cushion import follow_on_cushion

        return follow_on_cushion(phase, path, props, state, self.path_contact, start=fraction, control=control,
                                 log=log, progress=self.progress)

    def finish(self, log: ContinuationLog, phase: str, fraction: float, state: RodState, twist_deg: float | None = None,
               first_step: float | None = None):
        """(final clamps, equilibrium, lock angle in degrees, residual) from `state` at `fraction` of `phase`, twisted
        to twist_deg degrees (default the problem's); first_step: the first continuation step in `phase` (a fraction
        of it; default the step control's, as when the phase starts).  The first call is the main run; a later one (another branch)
        that reaches the lock on the main run's equilibrium there ends where the main run ended (the rest of the
        sequence is the same from the same state), which it returns without following the twist again, saying so in
        `log`."""
        main = self.locked_frame is None
        control = self.control if first_step is None else replace(self.control, first=first_step)
        end = self._finish(log, phase, fraction, state, twist_deg, control)
        if main:
            self.main_end = end
        return end

    def _rejoins_main(self, clamps: Clamps, locked_state: RodState) -> bool:
        """Whether `locked_state`, an equilibrium at the lock (the place phase's end clamps), is the main run's there:
        stations and sliding clips' arc lengths within DISTINCT of the length, frames, end roll and clip rolls within
        DISTINCT rad."""
        main, props = self.locked_state, self.props
        if (main is None or main.clip_rolls.shape != locked_state.clip_rolls.shape
                or main.clip_arc_lengths.shape != locked_state.clip_arc_lengths.shape):
            return False
        nodes = node_positions(props, clamps, locked_state) - node_positions(props, clamps, main)
        return bool(np.max(np.abs(nodes)) <= DISTINCT * props.length
                    and np.max(np.abs(locked_state.frames - main.frames)) <= DISTINCT
                    and np.all(np.abs(locked_state.clip_arc_lengths - main.clip_arc_lengths) <= DISTINCT * props.length)
                    and np.all(np.abs(locked_state.clip_rolls - main.clip_rolls) <= DISTINCT)
                    and abs(math.remainder(locked_state.roll - main.roll, 2.0 * math.pi)) <= DISTINCT)

    def _finish(self, log: ContinuationLog, phase: str, fraction: float, state: RodState, twist_deg: float | None,
                resumed: StepControl):
        """finish, the sequence itself; `resumed`: the step control of the phase it resumes."""
        problem, props, control = self.problem, self.props, self.control
        twist_deg = problem.end_twist_deg if twist_deg is None else twist_deg
        if phase == "place":
            place_path = self.path.place
            if self.path_contact is not None:
                from hoseline.procedures.contact.placement import check_clear, check_held_paths

                check_clear("the straight hose the placement starts from", props, place_path(0.0),
                            RodState(np.repeat(self.path.start_frame[None], props.segments, axis=0), np.zeros(3), 0.0),
                            self.path_contact)
                check_held_paths(place_path, [clip.arc_length for clip in problem.clips], self.path_contact)
                check_clear(f"the buckled hose at fraction {fraction:g} of the place phase (the first step, taken "
                            "without contact)", props, place_path(fraction), state, self.path_contact)
            state = self._follow("place", place_path, self.place_props, state, log, fraction, resumed)
            if props.springs is not None:
                state = phase_in_springs(props, place_path(1.0), state, log, self.progress)
            locked_frame = end_frame_of(place_path(1.0), state)
            lock_angle_deg = math.degrees(math.remainder(state.roll, 2.0 * math.pi))
            locked_state = state
            if (self.main_end is not None and twist_deg == problem.end_twist_deg
                    and self._rejoins_main(place_path(1.0), locked_state)):
                log.events.append("place: rejoined the main run's equilibrium at the lock (end roll free); from there "
                                  "the sequence is the main run's")
                return self.main_end
            locked_clips, free_rolls = self.path.locked_clips(state)
            state = RodState(state.frames, state.end_force, 0.0, state.clip_forces, free_rolls, state.clip_arc_lengths)
            fraction = 0.0
            if self.locked_frame is None:
                self.locked_frame, self.lock_angle_deg, self.locked_clips = locked_frame, lock_angle_deg, locked_clips
                self.locked_state, self.twist_start = locked_state, state
        elif phase == "twist":
            locked_frame, lock_angle_deg, locked_clips = self.locked_frame, self.lock_angle_deg, self.locked_clips
            control = resumed
        else:
            raise ValueError(f"the placement cannot be resumed in phase {phase!r}")

        def twist_path(t: float) -> Clamps:
            return self.path.twisted(locked_frame, twist_deg * t, locked_clips, t)

        # the largest turn of the phase: the end's, or a fixed clip's (turned along with it)
        twist = math.radians(max([abs(twist_deg)] + [abs(clip.twist_deg) for clip in problem.clips]))
        if twist != 0.0 and fraction < 1.0:
            twist_control = replace(  # steps of at most 30 deg at first, 45 deg later
                control,
                first=min(control.first, math.radians(30.0) / twist),
                largest=min(control.largest, math.radians(45.0) / twist),
            )
            state = self._follow("twist", twist_path, props, state, log, fraction, twist_control)
        final = twist_path(1.0)
        if self.path_contact is None:
            state, report = solve_equilibrium(props, final, state, tolerance=control.tolerance)
        else:
            from hoseline.mechanics.contact_newton import solve_with_contact
            from hoseline.procedures.contact.continuation import CONTACT_TOLERANCE

            state, report = solve_with_contact(props, final, state, self.path_contact,
                                               tolerance=max(control.tolerance, CONTACT_TOLERANCE))
        log.iterations += report.iterations
        if not report.converged or report.unstable_directions != 0:
            raise PlacementError(
                f"placement: the final equilibrium is not a converged stable state (residual {report.residual:.2e}, "
                f"{report.unstable_directions} unstable directions)"
            )
        if any(clip.sliding for clip in final.clips):
            final, state, report = _remesh_sliding(props, final, state, report, control.tolerance, log)
        if self.path_contact is not self.contact:  # the obstacles brought in to the placed hose
            from hoseline.procedures.contact.bring_in import bring_in

            sides = problem.contact_sides or (None,) * len(problem.contact)
            state, brought_in, residual = bring_in(problem.contact, sides, props, final, state, self.contact,
                                                   control=control, log=log, progress=self.progress)
            if self.brought_in is None:
                self.brought_in = brought_in
            return final, state, lock_angle_deg, residual
        return final, state, lock_angle_deg, report.residual


def _remesh_sliding(props: RodProperties, final: Clamps, state: RodState, report, tolerance: float,
                    log: ContinuationLog):
    """Move each sliding clip to the station nearest the arc length it slid to, and solve again.

    While it slides, a sliding clip keeps its station and the spans next to it stretch or shrink
    (clipped_newton.segment_lengths); far from where it started the segments are unequal, which
    costs accuracy.  Here the clip's station becomes the one nearest its arc length (the frames
    resampled at the new segment centres, Newton from there), until no clip moves (at most four
    rounds); a round whose solve fails is dropped with an event, keeping the shape before it.
    Returns (final clamps, state, Newton report)."""
    h, count = props.segment_length, props.segments
    for _ in range(4):
        arcs = clipped_newton.clip_arc_lengths(props, final, state)
        nodes = [min(max(round(float(arc) / h), 1), count - 1) if clip.sliding else clip.node
                 for clip, arc in zip(final.clips, arcs)]
        if nodes == [clip.node for clip in final.clips]:
            break
        if any(b - a < 2 for a, b in zip([0] + nodes, nodes + [count])):  # a span of one segment is a rigid link
            log.events.append("sliding clips: kept on their stations (the stations nearest their arc lengths leave "
                              "a span of one segment)")
            break
        moved = replace(final, clips=tuple(replace(clip, node=node) for clip, node in zip(final.clips, nodes)))
        old_s = np.concatenate([[0.0], np.cumsum(clipped_newton.segment_lengths(props, final, state)[0])])
        new_lengths = clipped_newton.segment_lengths(props, moved, state)[0]
        centres = np.cumsum(new_lengths) - 0.5 * new_lengths
        inside = np.clip(np.searchsorted(old_s, centres) - 1, 0, count - 1)
        guess = RodState(state.frames[inside].copy(), state.end_force.copy(), state.roll, state.clip_forces.copy(),
                         state.clip_rolls.copy(), state.clip_arc_lengths.copy())
        solved, moved_report = solve_equilibrium(props, moved, guess, tolerance=tolerance)
        log.iterations += moved_report.iterations
        if not moved_report.converged or moved_report.unstable_directions != 0:
            log.events.append("sliding clips: the solve on the stations nearest their arc lengths failed "
                              f"({moved_report.message or 'unstable'}); kept the stretched segments")
            break
        final, state, report = moved, solved, moved_report
        log.events.append("sliding clips: moved to the stations nearest their arc lengths "
                          + ", ".join(f"{float(a):.6g} mm" for a, clip in zip(state.clip_arc_lengths, final.clips)
                                      if clip.sliding))
    return final, state, report


FIRST_STEP_HALVINGS = 3  # a first step with no stable buckled shape is tried again at half the fraction, this often


def _initial_buckle(props: RodProperties, place_path, fraction: float, axis: np.ndarray,
                    log: ContinuationLog) -> tuple[RodState, float]:
    """(equilibrium, fraction) at the first fraction of the place phase, where the straight hose has buckled.

    Tried at `fraction` and, where no stable buckled shape is found there (a coarse hose whose clips pull
    it far in one step), at half of it, up to FIRST_STEP_HALVINGS times; the fraction reached is returned.
    """
    first = fraction
    for halving in range(FIRST_STEP_HALVINGS + 1):
        state = _buckle_at(props, place_path, fraction, axis, log)
        if state is not None:
            if halving:
                log.events.append(f"place: no stable buckled shape at the first step's fraction {first:g}; found at "
                                  f"{fraction:g}")
            return state, fraction
        fraction *= 0.5
    raise PlacementError(
        f"placement phase 'place' failed at fraction {first:g}: no stable buckled shape was found for the first step "
        f"from the straight hose (nor at {2 * fraction:g})"
    )


def _buckle_at(props: RodProperties, place_path, fraction: float, axis: np.ndarray,
               log: ContinuationLog) -> RodState | None:
    """The stable buckled equilibrium at `fraction` of the place phase, or None.

    Candidates: the clamped-clamped first buckling mode, bending about +axis and -axis
    (in the plane the end rotation bends the hose), with the amplitude that takes up the
    chord shortening, plus the end rotation spread linearly; both are relaxed downhill to
    equilibrium and the stable one of lower energy is kept.  Out-of-plane sides are tried
    only if neither in-plane side is stable.
    """
    clamps = place_path(fraction)
    length = props.length
    chord = float(np.linalg.norm(clamps.end_point - clamps.start_point))
    shortening = max(length - chord, 1e-6 * length)
    amplitude = 2.0 * math.sqrt(length * shortening) / math.pi  # w = A/2 (1 - cos 2 pi s / L)
    s_mid = (np.arange(props.segments) + 0.5) * props.segment_length
    slope = amplitude * math.pi / length * np.sin(2.0 * math.pi * s_mid / length)
    end_rotation = _rotation_vector_between(clamps.start_frame, clamps.end_frame)
    ramp = np.outer(s_mid / length, end_rotation)
    tangent = clamps.start_frame[2]

    def candidate(bend_axis: np.ndarray) -> RodState:
        # start frame, bent by the mode about bend_axis, then turned by the spread end rotation
        if clamps.clips:
            return RodState(_span_buckles(props, clamps, bend_axis), np.zeros(3), 0.0)
        straight = np.repeat(clamps.start_frame[None], props.segments, axis=0)
        frames = rotate_frames(rotate_frames(straight, np.outer(slope, bend_axis)), ramp)
        return RodState(frames, np.zeros(3), 0.0)

    out_of_plane = np.cross(tangent, axis)
    for label, axes in (("in the bending plane", (axis, -axis)), ("out of the bending plane", (out_of_plane, -out_of_plane))):
        candidates = [candidate(a) for a in axes]
        relaxed = relax_to_stable(props, clamps, candidates, log)
        if relaxed is None:
            continue
        best, distinct = relaxed
        log.record_fork("place", fraction, props, clamps, distinct)
        energies = ", ".join(f"{total_energy(props, clamps, state):.6g}" for state in distinct)
        log.events.append(
            f"place: the straight hose buckles at the first step (fraction {fraction:g}); both sides {label} "
            f"were relaxed: {len(distinct)} distinct stable equilibri{'um' if len(distinct) == 1 else 'a'} "
            f"(energy {energies} N*mm); kept the lowest"
        )
        return best
    return None


def _coarse_lock(sequence: _Sequence, coarse: RodProperties, final: Clamps, tolerance: float,
                 events: list[str]) -> Clamps | None:
    """The final clamps of the coarse solve of the error estimate with the end fitting locked where the coarse rod's
    own torque-free roll puts it, then twisted as the fine one: the lock angle has a discretisation error of its own,
    which the fine rod's lock would hide from the estimate (a non-coplanar hose at 45 deg: the estimate 0.6 of the
    true error, tests/test_accuracy_references.py).  The coarse equilibrium with the end roll free is solved by
    Newton from the fine one at the lock.  None, with an event, when it does not converge to a stable state.
    Without clips (the coarse clips' locked rolls are not redone)."""
    if sequence.locked_state is None:
        return final
    place_end = sequence.path.place(1.0)
    locked, report = solve_equilibrium(coarse, place_end, coarse_guess(sequence.props, coarse, sequence.locked_state),
                                       tolerance=tolerance)
    if not report.converged or report.unstable_directions != 0:
        events.append("accuracy: the discretisation error is not estimated: the coarse rod's torque-free lock did not "
                      "converge to a stable state")
        return None
    return replace(final, end_frame=sequence.path.twisted(end_frame_of(place_end, locked),
                                                          sequence.problem.end_twist_deg).end_frame)


def _coarse_clamps(final: Clamps, state: RodState, segments: int, coarse_segments: int, length: float) -> Clamps | None:
    """The final clamps for the coarse solve of the error estimate: the clips on the coarse
    stations, rotating and sliding clips turned by the roll they found (so the coarse solve starts
    from zero roll), a sliding clip on the coarse station nearest the arc length it found (length:
    the hose's, mm); None if a fixed, rotating or ball clip falls between coarse stations."""
    if not final.clips:
        return final
    if 2 * coarse_segments != segments or any(clip.node % 2 for clip in final.clips if not clip.sliding):
        return None
    rolls = clip_rolls(final, state)
    arcs = state.clip_arc_lengths if state.clip_arc_lengths.shape == (len(final.clips),) else None

    def coarse_node(j: int, clip: ClipHold) -> int:
        if clip.sliding and arcs is not None:
            return round(float(arcs[j]) * coarse_segments / length)
        return clip.node // 2

    clips = tuple(
        replace(clip, node=coarse_node(j, clip),
                frame=clip.frame if not clip.roll_free else clip.frame @ rotation_matrix(roll * clip.frame[2]).T)
        for j, (clip, roll) in enumerate(zip(final.clips, rolls))
    )
    held = [0] + [clip.node for clip in clips] + [coarse_segments]
    if any(b - a < 2 for a, b in zip(held[:-1], held[1:])):  # a span of one segment is a rigid link
        return None
    return replace(final, clips=clips)


def _span_buckles(props: RodProperties, clamps: Clamps, bend_axis: np.ndarray) -> np.ndarray:
    """Segment frames (N, 3, 3) of a hose whose every span between held stations (start, clips,
    end) runs along its chord, buckled by the clamped-clamped mode about bend_axis (made normal
    to the chord) with the amplitude that takes up the span's chord shortening."""
    h = props.segment_length
    held = [(0, clamps.start_point)] + [(clip.node, clip.point) for clip in clamps.clips]
    held.append((props.segments, clamps.end_point))
    frames = np.empty((props.segments, 3, 3))
    for (first, point_a), (last, point_b) in zip(held[:-1], held[1:]):
        span = (last - first) * h
        chord_vector = point_b - point_a
        chord = float(np.linalg.norm(chord_vector))
        along = chord_vector / chord if chord > 1e-12 * span else clamps.start_frame[2]
        turn_axis, turn_angle = tangent_turn(clamps.start_frame[2], along, along, span)
        base = clamps.start_frame @ rotation_matrix(turn_axis * turn_angle).T
        normal = bend_axis - (bend_axis @ along) * along
        normal = normal / np.linalg.norm(normal) if np.linalg.norm(normal) > 1e-9 else perpendicular(along)
        amplitude = 2.0 * math.sqrt(span * max(span - chord, 1e-6 * span)) / math.pi
        s_mid = (np.arange(last - first) + 0.5) * h
        slope = amplitude * math.pi / span * np.sin(2.0 * math.pi * s_mid / span)
        frames[first:last] = rotate_frames(np.repeat(base[None], last - first, axis=0), np.outer(slope, normal))
    return frames


def _rotation_vector_between(frame_a: np.ndarray, frame_b: np.ndarray) -> np.ndarray:
    """World rotation vector R with frame_b = frame_a @ R^T (rad)."""
    return rotation_vector(frame_b.T @ frame_a)


def place_only(problem: Problem, control: StepControl = StepControl()) -> tuple[RodProperties, Clamps, RodState, float]:
    """The published sequence alone, for studies that place many hoses: (rod, final clamps, stable
    equilibrium, lock angle in degrees), without the Result, the uniqueness checks or the error estimate.

    Raises PlacementError as solve() does.
    """
    props = rod_properties(problem)
    log = ContinuationLog()
    sequence = _Sequence(problem, props, control, None)
    state, first = _initial_buckle(sequence.place_props, sequence.path.place, control.first, sequence.path.axis, log)
    state = sequence.clear_buckle(state, first, log)
    final, state, lock_angle_deg, _ = sequence.finish(log, "place", first, state)
    return props, final, state, lock_angle_deg
