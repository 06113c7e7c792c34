"""One equilibrium of a placed hose carried through changes of its fittings and properties, step by step.

Interactive work (the studio) moves a fitting a little, or changes the length or a stiffness
a little, many times a second.  Each change is a step of continuation from the current
equilibrium (a warm start), so a drag is a path, followed as the placement follows its path:

- fittings moved (tips, frames, weight): one Newton solve from the current equilibrium; when it
  fails, ends on an unstable equilibrium or moves the hose much more than the fittings moved
  (a possible jump over a fold), the step is followed by continuation.follow along the straight
  interpolation of the tips and the shortest rotation between the frames, with stability
  monitoring and branch switching, as a sweep does between two poses;
- properties changed (length, stiffnesses): Newton at the new properties, the change halved
  while that fails; an equilibrium that comes out unstable is pushed along its critical modes
  and relaxed downhill to the lowest stable state (continuation.relax_to_stable).

The end roll stays clamped: the twist locked at assembly moves with the end fitting.  A step
that cannot be completed raises PlacementError and leaves the tracked equilibrium as it was.

Clips (model/clips.py) are held as the placement left them (mechanics/rod.ClipHold, as a sweep
holds them): each on its station, a fixed clip with the roll locked at assembly carried with its
frame, rotating and sliding clips free to roll, a sliding clip's arc length an unknown of every
step.  Moving a clip is a change of the fittings like any other: its point and frame are
interpolated with the fittings' on a followed step.

With contact (Problem.contact, Problem.self_contact) every step runs the contact Newton
(mechanics/contact_newton.py) from the current equilibrium, which clears every obstacle, and is
followed by contact continuation (procedures/contact/continuation.follow_contact, which relaxes
downhill at a fold and logs the snap) when the direct solve fails, ends unstable or jumps; a
change of properties that leaves the hose unstable relaxes it downhill with the barrier
(minimise_with_contact).  The obstacles do not move.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from hoseline.mechanics.clipped_newton import station_positions
from hoseline.mechanics.contact_newton import ContactModel, minimise_with_contact, solve_with_contact
from hoseline.mechanics.newton import RodProperties, node_positions, solve_equilibrium
from hoseline.mechanics.rod import Clamps, ClipHold, RodState
from hoseline.mechanics.rotations import rotation_matrix, rotation_vector
from hoseline.model.problem import Problem
from hoseline.procedures.contact import placement as contact_placement
from hoseline.procedures.contact.continuation import CONTACT_TOLERANCE, follow_contact
from hoseline.procedures.placement.continuation import (
    ContinuationLog,
    PlacementError,
    StepControl,
    follow,
    push_along_modes,
    relax_to_stable,
)
from hoseline.procedures.placement.result import Result
from hoseline.procedures.placement.path import weight_vector
from hoseline.procedures.placement.sequence import rod_properties
from hoseline.procedures.placement.stations import build_result

JUMP_FACTOR = 3.0  # a step moving a station more than this times the fittings' movement is followed in sub-steps
CAREFUL = StepControl(first=0.1, largest=0.1)  # sub-steps of a suspicious step
PLAIN = StepControl(first=1.0, largest=1.0)  # one step, halved as needed
SMALLEST_PROPERTY_STEP = 1.0 / 64.0  # of a property change, before it is refused


@dataclass(frozen=True)
class Fittings:
    """Where the fittings and clips hold the hose: tips (mm) and frames (rows d1, d2, d3; d3 along the hose).

    clip_points (c, 3) mm and clip_frames (c, 3, 3): the clips in the problem's order, each frame
    as the clip holds the hose (a fixed clip's locked roll included); a ball clip's frame only
    orients what is drawn (it holds the position only).
    """

    start_point: np.ndarray
    start_frame: np.ndarray
    end_point: np.ndarray
    end_frame: np.ndarray
    clip_points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    clip_frames: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3)))


@dataclass(frozen=True)
class Step:
    """What one change cost: Newton iterations, seconds, the events logged and the largest station movement (mm)."""

    iterations: int
    seconds: float
    events: list[str]
    movement: float


class Tracker:
    """The equilibrium of `problem`'s hose, starting from a placement `result`, carried through changes."""

    def __init__(self, problem: Problem, result: Result) -> None:
        self.problem = problem
        self.props = rod_properties(problem)
        # the clips as held at the end of the placement (the roll found folded into the frame: free rolls start at zero)
        holds = tuple(
            ClipHold(int(np.argmin(np.abs(result.s - clip.arc_length))), clip.point, clip.frame,
                     clip.kind in ("rotating", "sliding"), clip.kind == "sliding")
            for clip in result.clips
        )
        count = len(holds)
        self.clamps = _clamps(problem, Fittings(problem.start.point, result.start_frame, problem.end.point,
                                                result.end_frame, *_clip_arrays(holds)), holds)
        self.state = RodState(result.frames.copy(), result.end_force.copy(), 0.0,
                              np.array([clip.force for clip in result.clips]).reshape(count, 3), np.zeros(count),
                              np.array([clip.arc_length for clip in result.clips]))
        self.residual = result.residual
        self.log = ContinuationLog()
        self.contact = _contact_model(problem)

    @property
    def fittings(self) -> Fittings:
        """The fittings and clips as they hold the hose now."""
        c = self.clamps
        return Fittings(c.start_point, c.start_frame, c.end_point, c.end_frame, *_clip_arrays(c.clips))

    @property
    def centerline(self) -> np.ndarray:
        """(N+1, 3) station positions, mm."""
        if self.clamps.clips:  # a sliding clip stretches the spans next to it
            return station_positions(self.props, self.clamps, self.state)[1]
        return node_positions(self.props, self.clamps, self.state)

    def move(self, problem: Problem, fittings: Fittings) -> Step:
        """Carry the equilibrium to `problem`'s hose held by `fittings` (the problem's mount points are not used).

        Raises PlacementError when no equilibrium can be followed there (nothing changes then),
        ValueError when the segment count differs (a new placement is needed).
        """
        started = time.perf_counter()
        props = rod_properties(problem)
        if props.segments != self.props.segments:
            raise ValueError("the segment count changed: place the hose again")
        if len(fittings.clip_points) != len(self.clamps.clips):
            raise ValueError(f"{len(fittings.clip_points)} clip positions for {len(self.clamps.clips)} clips")
        clamps = _clamps(problem, fittings, self.clamps.clips)
        before = self.centerline
        logged, counted = len(self.log.events), self.log.iterations
        state = self.state
        contact = _contact_model(problem, self.problem, self.contact)  # its stiffness follows the hose
        # the equilibrium tracked clears every obstacle: under clamps from the same start point, with the same hose and
        # obstacles, it is where it was, and the solve does not search it for penetration again
        clear = (np.array_equal(clamps.start_point, self.clamps.start_point) and _same_properties(props, self.props)
                 and _same_obstacles(contact, self.contact))
        try:
            if not _same_properties(props, self.props):
                state = self._change_properties(self.props, props, self.clamps, state, contact)
            state = self._move_fittings(props, self.clamps, clamps, state, contact, clear)
        except PlacementError:
            del self.log.events[logged:]
            raise
        self.problem, self.props, self.clamps, self.state, self.contact = problem, props, clamps, state, contact
        movement = float(np.max(np.linalg.norm(self.centerline - before, axis=1)))
        return Step(self.log.iterations - counted, time.perf_counter() - started, self.log.events[logged:], movement)

    def result(self, lock_angle_deg: float, complete: bool = True) -> Result:
        """The tracked equilibrium as a Result (stations, moments, reactions, stability margin).

        lock_angle_deg: the lock angle of the placement it started from, degrees.
        complete: False leaves out what a drawn frame does not need and costs most (the stability margin: None; each
        obstacle's smallest gap to the whole assembly: NaN), to be read from a complete result later.
        """
        barrier = self.contact is not None  # its margin replaces the rod's: the rod's is not found
        result = build_result(self.problem, self.props, self.clamps, self.state, lock_angle_deg, self.log,
                              time.perf_counter(), self.residual, stability=complete and not barrier)
        if barrier:
            result = contact_placement.with_contact(result, self.props, self.clamps, self.state, self.contact,
                                                    stability=complete, locate_gaps=complete)
        return result

    def _move_fittings(self, props: RodProperties, old: Clamps, new: Clamps, state: RodState,
                       contact: ContactModel | None, clear: bool = False) -> RodState:
        """The equilibrium under `new` clamps, from `state` in equilibrium under `old` (kept out of the
        obstacles of `contact`, if given; clear: `state` under `new` is known to clear them)."""
        if contact is None:
            trial, report = solve_equilibrium(props, new, state)
        else:
            trial, report = solve_with_contact(props, new, state, contact, tolerance=CONTACT_TOLERANCE,
                                               start_is_clear=clear)
        self.log.iterations += report.iterations
        if report.converged:
            moved = np.max(np.linalg.norm(_stations(props, new, trial) - _stations(props, old, state), axis=1))
            if report.unstable_directions == 0 and moved <= _jump_limit(old, new, props.length):
                self.residual = report.residual
                return trial

        def path(t: float) -> Clamps:
            return _interpolate(old, new, t)

        control = CAREFUL if report.converged else PLAIN
        if contact is not None:
            reached = follow_contact("move", path, props, state, contact, control=control, log=self.log)[0]
            reached, final = solve_with_contact(props, new, reached, contact, tolerance=CONTACT_TOLERANCE)
        else:
            reached = follow("move", path, props, state, self.log, control=control)
            reached, final = solve_equilibrium(props, new, reached)
        self.log.iterations += final.iterations
        if not final.converged:
            raise PlacementError(f"the step was followed to its end, but Newton did not converge there (residual "
                                 f"{final.residual:.2e}: {final.message}); move in smaller steps")
        self.residual = final.residual
        return reached

    def _change_properties(self, old: RodProperties, new: RodProperties, clamps: Clamps, state: RodState,
                           contact: ContactModel | None) -> RodState:
        """The equilibrium with properties `new`, from `state` in equilibrium with `old` (same clamps; kept out
        of the obstacles of `contact`, the new hose's model, if given)."""
        done, step = 0.0, 1.0
        while done < 1.0:
            target = min(1.0, done + step)
            props = _blend(old, new, target)
            if contact is None:
                trial, report = solve_equilibrium(props, clamps, state)
            else:
                trial, report = solve_with_contact(props, clamps, state, contact, tolerance=CONTACT_TOLERANCE)
            self.log.iterations += report.iterations
            if not report.converged:
                step *= 0.5
                if step < SMALLEST_PROPERTY_STEP:
                    raise PlacementError(
                        f"no equilibrium near the current shape for the new hose properties (Newton residual "
                        f"{report.residual:.2e} at {target:.3f} of the change); change them in smaller steps"
                    )
                continue
            if report.unstable_directions != 0:
                trial = self._relax(props, clamps, trial, report.unstable_directions, contact)
                self.log.events.append(f"properties: stability lost at {target:.3f} of the change; moved to the "
                                       "stable branch along the critical mode")
            self.residual = report.residual
            done, state = target, trial
        return state

    def _relax(self, props: RodProperties, clamps: Clamps, unstable: RodState, directions: int,
               contact: ContactModel | None) -> RodState:
        """A stable equilibrium downhill of the unstable equilibrium `unstable` (with `directions` unstable
        directions); PlacementError when none is found."""
        if contact is None:
            relaxed = relax_to_stable(props, clamps, push_along_modes(props, clamps, unstable, directions), self.log)
            found = None if relaxed is None else relaxed[0]
        else:
            found, report = minimise_with_contact(props, clamps, unstable, contact, tolerance=CONTACT_TOLERANCE)
            self.log.iterations += report.iterations
            if not report.converged or report.unstable_directions != 0:
                found = None
        if found is None:
            raise PlacementError("the hose lost stability with the new properties and no stable shape was found")
        return found


def _contact_model(problem: Problem, before: Problem | None = None, model: ContactModel | None = None
                   ) -> ContactModel | None:
    """The contact model of `problem`'s obstacles and self-contact, or None without contact; `model`, the one of
    `before`, is reused when the obstacles (the same objects), self-contact and hose radius are (a mesh's search
    trees are not built again at every step)."""
    if not problem.has_contact:
        return None
    same = (model is not None and before is not None and problem.self_contact == before.self_contact
            and problem.hose.outer_radius == before.hose.outer_radius and len(problem.contact) == len(before.contact)
            and all(a is b for a, b in zip(problem.contact, before.contact)))
    return contact_placement.problem_contact_model(problem, model if same else None)


def _same_obstacles(a: ContactModel | None, b: ContactModel | None) -> bool:
    """Whether two contact models hold the same obstacles (the same arrays), hose radius and self-contact pairs: a hose
    clear of one is clear of the other."""
    return (a is not None and b is not None and a.hose_radius == b.hose_radius and a.self_exclusion == b.self_exclusion
            and a.planes is b.planes and a.balls is b.balls and a.capsules is b.capsules and a.mesh is b.mesh)


def twisted(frame: np.ndarray, twist_deg: float) -> np.ndarray:
    """An end fitting frame (rows d1, d2, d3) turned by twist_deg degrees about the fitting direction -d3."""
    return frame @ rotation_matrix(-frame[2] * math.radians(twist_deg)).T


def _clamps(problem: Problem, fittings: Fittings, holds: tuple[ClipHold, ...]) -> Clamps:
    """The clamps of the fittings, both ends locked, with the problem's weight; the clips `holds` moved to the
    fittings' clip points and frames."""
    return Clamps(
        start_point=np.asarray(fittings.start_point, dtype=float),
        start_frame=np.asarray(fittings.start_frame, dtype=float),
        end_point=np.asarray(fittings.end_point, dtype=float),
        end_frame=np.asarray(fittings.end_frame, dtype=float),
        roll_free=False,
        line_weight=weight_vector(problem),
        clips=tuple(
            replace(hold, point=np.array(point, dtype=float), frame=None if hold.frame is None else np.array(frame, dtype=float))
            for hold, point, frame in zip(holds, fittings.clip_points, fittings.clip_frames)
        ),
    )


def _clip_arrays(holds: tuple[ClipHold, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Points (c, 3) mm and frames (c, 3, 3) of clips (the identity for a ball clip, which has none)."""
    points = np.array([hold.point for hold in holds], dtype=float).reshape(-1, 3)
    frames = np.array([np.eye(3) if hold.frame is None else hold.frame for hold in holds], dtype=float).reshape(-1, 3, 3)
    return points, frames


def _stations(props: RodProperties, clamps: Clamps, state: RodState) -> np.ndarray:
    """(N+1, 3) station positions, mm (each segment of its own length where sliding clips stretch their spans)."""
    return station_positions(props, clamps, state)[1] if clamps.clips else node_positions(props, clamps, state)


def _interpolate(a: Clamps, b: Clamps, t: float) -> Clamps:
    """The clamps a fraction t of the way from a to b: tips on the straight line, frames by the shortest rotation."""

    def frame(fa: np.ndarray, fb: np.ndarray) -> np.ndarray:
        return fa @ rotation_matrix(t * rotation_vector(fb.T @ fa)).T

    return Clamps(
        start_point=(1.0 - t) * a.start_point + t * b.start_point,
        start_frame=frame(a.start_frame, b.start_frame),
        end_point=(1.0 - t) * a.end_point + t * b.end_point,
        end_frame=frame(a.end_frame, b.end_frame),
        roll_free=False,
        line_weight=(1.0 - t) * a.line_weight + t * b.line_weight,
        clips=tuple(
            replace(ca, point=(1.0 - t) * ca.point + t * cb.point,
                    frame=None if ca.frame is None else frame(ca.frame, cb.frame))
            for ca, cb in zip(a.clips, b.clips)
        ),
    )


def _jump_limit(old: Clamps, new: Clamps, length: float) -> float:
    """Largest station movement (mm) a step may make without being followed in sub-steps."""
    moves = []
    for point_a, point_b, frame_a, frame_b in (
        (old.start_point, new.start_point, old.start_frame, new.start_frame),
        (old.end_point, new.end_point, old.end_frame, new.end_frame),
    ) + tuple((a.point, b.point, _frame_or_identity(a), _frame_or_identity(b)) for a, b in zip(old.clips, new.clips)):
        angle = float(np.linalg.norm(rotation_vector(frame_b.T @ frame_a)))
        moves.append(float(np.linalg.norm(point_b - point_a)) + length * angle)
    weight_change = float(np.linalg.norm(new.line_weight - old.line_weight) / max(np.linalg.norm(old.line_weight), 1e-300))
    allowance = length * min(weight_change, 1.0)  # a change of weight may move the hose by up to its length
    return JUMP_FACTOR * max(moves) + allowance + 1e-6 * length


def _frame_or_identity(hold: ClipHold) -> np.ndarray:
    return np.eye(3) if hold.frame is None else hold.frame


def _same_properties(a: RodProperties, b: RodProperties) -> bool:
    return (a.segment_length == b.segment_length and bool(np.array_equal(a.stiffness, b.stiffness))
            and (a.braid is None) == (b.braid is None) and (a.braid is None or bool(np.array_equal(a.braid, b.braid))))


def _blend(old: RodProperties, new: RodProperties, t: float) -> RodProperties:
    """Properties a fraction t of the way from old to new (stiffness and segment length linear)."""
    if t >= 1.0:
        return new
    return replace(
        new,
        stiffness=(1.0 - t) * old.stiffness + t * new.stiffness,
        segment_length=(1.0 - t) * old.segment_length + t * new.segment_length,
    )
