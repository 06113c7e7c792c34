"""Quasi-static sweep: the placed hose carried through the motion of the bodies its mounts sit on.

1. The hose is placed at design position (placement.solve): the twist is locked at assembly.
2. Both fittings then move with their bodies, clamped throughout: a body pose (R, p) takes
   a fitting tip P to R P + p and its frame F to F R^T.
3. Each pose starts from the previous equilibrium.  A secant predictor and one Newton
   solve usually reach it in two or three iterations.  When that fails, ends on an
   unstable equilibrium, or moves the hose much more than the mounts (or contact obstacles) moved, the step is
   followed instead by continuation (continuation.follow) along the interpolated body
   poses (slerp of the rotations), with sub-steps, stability monitoring and branch
   switching; a loss of stability there is a snap-through, recorded with its jump.
4. At every pose: bend radius, twisting moment and reactions, and the nearest approach to
   every obstacle (exact, clearance.py).  Clips move with their bodies like the fittings
   (point and frame), each clip's roll as found at assembly (fixed clips locked, rotating
   and sliding clips free); their reactions, and the arc length of sliding clips, per pose.
5. With contact ([contact] in the problem: obstacles fixed or moving with a body, self-contact)
   every pose is solved with the contact Newton, with the obstacles moved to the pose
   (procedures/contact/moving.py): first from the secant prediction without the Newton's step
   filter, kept where the move check admits the whole move to the answer (no obstacle, nor the
   hose itself, can have been crossed on the way there); else from the secant prediction or the
   previous equilibrium, the first that the move check admits, with the filter; and followed by
   contact continuation (procedures/contact/) along the interpolated poses
   of the bodies, obstacles' too, when that fails; a fold or a loss of stability there is a snap
   downhill.  Per pose and obstacle: the smallest gap, the total force and the length in contact;
   the start mount's reaction includes the contact loads.
6. Optionally the same sweep with the end fitting free to spin (the common modelling error
   the seed paper warns about), and the separation of the two answers.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from hoseline.mechanics.blas_threads import one_blas_thread
from hoseline.mechanics.clipped_newton import clip_arc_lengths, clip_reactions, station_positions
from hoseline.mechanics.newton import NewtonReport, node_positions, solve_equilibrium
from hoseline.mechanics.rod import Clamps, ClipHold, RodState
from hoseline.model.motion import Pose, interpolate
from hoseline.model.mounts import Mount, single_plane_offset
from hoseline.model.sweep import SweepProblem
from hoseline.procedures.geometry.clearance import TriangleIndex, nearest_with_fittings
from hoseline.procedures.placement.continuation import (
    ContinuationLog,
    PlacementError,
    Progress,
    StepControl,
    follow,
    secant,
)
from hoseline.procedures.placement.hose_health import hose_health
from hoseline.procedures.placement.path import weight_vector
from hoseline.procedures.placement.sequence import rod_properties, solve
from hoseline.procedures.placement.result import Result
from hoseline.procedures.sweep.result import ObstacleClearance, Snap, SweepContact, SweepResult

if TYPE_CHECKING:
    from hoseline.mechanics.contact_newton import ContactModel
    from hoseline.procedures.contact.moving import PlacedObstacles

# The contact modules (procedures/contact/, mechanics/contact*.py, with SciPy's sparse graphs) are imported where a
# sweep with contact uses them, so that one without contact does not load them.

JUMP_FACTOR = 3.0  # a step moving a station more than this times the mounts' movement is followed in sub-steps
CAREFUL = StepControl(first=0.1, largest=0.1)  # sub-steps of a suspicious step
PLAIN = StepControl(first=1.0, largest=1.0)  # one step, halved as needed
UNFILTERED_ITERATIONS = 10  # of a pose's first try with contact, Newton without its step filter (_contact_solve): a
# pose the sweep carries smoothly takes one to eight; one an obstacle pushes into the hose fails early (its start
# inside) or creeps, and the filtered Newton and the continuation take it on
UNFILTERED_HALVINGS = 10  # of a Newton step in that try
UNFILTERED_WAITING = 16  # after k refused tries in a row, the next 2^k - 1 poses (at most this many) go without one:
# an obstacle pushing the hose pose after pose refuses most (random sweeps over planes, boxes, balls and cylinders
# took up to 1.8 times the Newton iterations trying at every pose)


@dataclass
class _Reached:
    """One pose reached: the state, its clamps and stations, the contact model there (None without contact), the
    Newton iterations and what was logged."""

    state: RodState
    clamps: Clamps
    nodes: np.ndarray  # its stations, mm
    contact: ContactModel | None
    iterations: int
    events: list[str]
    jump: float


class _Tracker:
    """Carries one equilibrium of the hose from pose to pose.

    assembly: the placement at design position.  roll_free: the end fitting may spin about
    its axis (the comparison run).
    """

    def __init__(self, sweep: SweepProblem, assembly: Result, roll_free: bool) -> None:
        self.sweep = sweep
        self.props = rod_properties(sweep.problem)
        self.weight = weight_vector(sweep.problem)
        self.roll_free = roll_free
        self.start_frame = assembly.start_frame
        self.end_frame = assembly.end_frame
        self.log = ContinuationLog()
        self.bodies = (sweep.start_body, sweep.end_body) + tuple(sweep.clip_body(j) for j in range(len(assembly.clips)))
        contact_bodies = tuple(sweep.contact_body(j) for j in range(len(sweep.problem.contact)))
        self.poses = {body: Pose() for body in (*self.bodies, *contact_bodies)}  # of every body that carries something
        # the clips as held at assembly (the roll found included: a free roll starts from zero here)
        self.clips = tuple(
            ClipHold(int(np.argmin(np.abs(assembly.s - clip.arc_length))), clip.point, clip.frame,
                     clip.kind in ("rotating", "sliding"), clip.kind == "sliding")
            for clip in assembly.clips
        )
        count = len(self.clips)
        self.state = RodState(assembly.frames.copy(), assembly.end_force.copy(), 0.0,
                              np.array([clip.force for clip in assembly.clips]).reshape(count, 3), np.zeros(count),
                              np.array([clip.arc_length for clip in assembly.clips]))
        self.before: RodState | None = None  # the equilibrium one pose back, for the secant predictor
        self.obstacles = None
        if sweep.problem.has_contact:
            from hoseline.procedures.contact.moving import MovingObstacles
            from hoseline.procedures.contact.placement import problem_contact_model

            self.obstacles = MovingObstacles(problem_contact_model(sweep.problem), contact_bodies)
        self.placed = self.obstacles.at(self.poses) if self.obstacles is not None else None
        self.clamps_now = self.clamps(self.poses)  # the clamps of the equilibrium reached last
        self.nodes = stations(self.props, self.clamps_now, self.state)  # its stations, mm
        self.unfiltered_refused = 0  # poses in a row whose try without the step filter was refused (_contact_solve)
        self.unfiltered_waiting = 0  # poses left to solve without that try

    def clamps(self, poses: Mapping[str | None, Pose]) -> Clamps:
        """The clamps with each body at poses[body]: the fittings' and the clips'."""
        problem = self.sweep.problem
        start, end, *clip_poses = (poses[body] for body in self.bodies)
        return Clamps(
            start_point=start.point(problem.start.point),
            start_frame=start.frame(self.start_frame),
            end_point=end.point(problem.end.point),
            end_frame=end.frame(self.end_frame),
            roll_free=self.roll_free,
            line_weight=self.weight,
            clips=tuple(
                ClipHold(clip.node, pose.point(clip.point), None if clip.frame is None else pose.frame(clip.frame),
                         clip.roll_free, clip.sliding)
                for clip, pose in zip(self.clips, clip_poses)
            ),
        )

    def move_to(self, index: int) -> _Reached:
        """Reach the equilibrium at sweep pose `index` from the current one."""
        target = {body: self.sweep.pose(body, index) for body in self.poses}
        clamps = self.clamps(target)
        # the last equilibrium's stations under the new clamps: only the start point moves them (station_positions)
        old_nodes = self.nodes + (clamps.start_point - self.clamps_now.start_point)
        limit = JUMP_FACTOR * self._largest_carry(target, old_nodes) + 1e-6 * self.props.length
        guesses = [self.state] if self.before is None else [_secant(self.before, self.state), self.state]
        placed = None
        if self.obstacles is None:
            trial, report = solve_equilibrium(self.props, clamps, guesses[0])
            iterations = report.iterations
        else:
            placed = self.obstacles.at(target)
            trial, report, iterations = self._contact_solve(clamps, placed, guesses)
        events: list[str] = []
        nodes = stations(self.props, clamps, trial) if report.converged else None
        jump = _largest_movement(old_nodes, nodes) if nodes is not None else math.inf
        if not (report.converged and report.unstable_directions == 0 and jump <= limit):
            start_poses = self.poses

            def poses(t: float) -> dict[str | None, Pose]:
                return {body: interpolate(start_poses[body], target[body], t) for body in target}

            def path(t: float) -> Clamps:
                return self.clamps(poses(t))

            control = PLAIN if not report.converged else CAREFUL
            logged, counted = len(self.log.events), self.log.iterations
            if self.obstacles is None:
                trial = follow(f"step to pose {index}", path, self.props, self.state, self.log, control=control)
            else:
                from hoseline.procedures.contact.continuation import follow_contact
                from hoseline.procedures.contact.moving import ObstaclePath

                trial = follow_contact(f"step to pose {index}", path, self.props, self.state,
                                       ObstaclePath(self.obstacles, poses), control=control, log=self.log,
                                       before=self.before)[0]
            events = self.log.events[logged:]
            iterations += self.log.iterations - counted
            nodes = stations(self.props, clamps, trial)
            jump = _largest_movement(old_nodes, nodes)
            # a new branch or a sharp turn: no secant across it (with contact only across a snap: the move check
            # keeps a poor prediction from being used, and an obstacle that moves with the hose needs one)
            self.before = self.state if self.obstacles is not None and not events else None
        else:
            self.before = self.state
        self.state, self.poses, self.placed, self.clamps_now, self.nodes = trial, target, placed, clamps, nodes
        return _Reached(trial, clamps, nodes, None if placed is None else placed.model, iterations, events, jump)

    def _contact_solve(self, clamps: Clamps, placed: PlacedObstacles,
                       guesses: list[RodState]) -> tuple[RodState, NewtonReport, int]:
        """(state, report, Newton iterations) of the contact Newton at the next pose (clamps, obstacles `placed`).

        First Newton without its step filter from the first guess, taken where it converges and the move check admits
        the whole move from the last equilibrium to it (MovingObstacles.move_is_clear: no obstacle, nor the hose
        itself, can have been crossed on the way, whatever path Newton's iterates took; the one check in place of the
        move check of the start and the step filter of each Newton step, a third of a pose's time on the 100 000-
        triangle strut of bench/bench_contact_placement.py).  Where it does not, as before: from the prediction or the
        last equilibrium, the first the move check admits, with the step filter.  After k refused tries in a row the
        next 2^k - 1 poses (at most UNFILTERED_WAITING) are solved the filtered way at once."""
        from hoseline.mechanics.contact_newton import solve_with_contact
        from hoseline.procedures.contact.continuation import CONTACT_TOLERANCE

        before = (self.clamps_now, self.state, self.placed)
        spent = 0
        if self.unfiltered_waiting > 0:
            self.unfiltered_waiting -= 1
        else:
            trial, report = solve_with_contact(self.props, clamps, guesses[0], placed.model,
                                               tolerance=CONTACT_TOLERANCE, max_iterations=UNFILTERED_ITERATIONS,
                                               max_halvings=UNFILTERED_HALVINGS, start_is_clear=True, filtered=False)
            if report.converged and self.obstacles.move_is_clear(self.props, before, (clamps, trial, placed)):
                self.unfiltered_refused = 0
                return trial, report, report.iterations
            spent = report.iterations
            self.unfiltered_refused += 1
            self.unfiltered_waiting = min(2 ** self.unfiltered_refused - 1, UNFILTERED_WAITING)
        begin = self.obstacles.start(self.props, before, clamps, placed, guesses)
        if begin is None:
            return self.state, NewtonReport(False, 0, math.inf, -1, "no start the move check admits"), spent
        trial, report = solve_with_contact(self.props, clamps, begin, placed.model, tolerance=CONTACT_TOLERANCE,
                                           start_is_clear=True)
        return trial, report, spent + report.iterations

    def _largest_carry(self, target: Mapping[str | None, Pose], nodes: np.ndarray) -> float:
        """A bound (mm) of how far a station moves if the hose moved rigidly with either mount, a clip, or the body
        of a contact obstacle (`nodes`: the stations now, mm)."""
        problem = self.sweep.problem
        moves = [0.0]
        points = (problem.start.point, problem.end.point) + tuple(clip.point for clip in self.clips)
        for body, point in zip(self.bodies, points):
            if body is None:  # fixed: at its design position at every pose
                continue
            old, new = self.poses[body], target[body]
            moves.append(float(np.linalg.norm(new.point(point) - old.point(point))) + self.props.length * old.angle_to(new))
        for body in () if self.obstacles is None else set(self.obstacles.bodies) - {None}:
            carry = self.poses[body].inverse().then(target[body])
            moves.append(float(np.max(np.linalg.norm(carry.points(nodes) - nodes, axis=1))))
        return max(moves)


def _secant(before: RodState, current: RodState) -> RodState:
    """The next equilibrium guessed by repeating the last step (poses about evenly spaced)."""
    return secant((0.0, before), (1.0, current), 2.0)


def stations(props, clamps: Clamps, state: RodState) -> np.ndarray:
    """Station positions (N+1, 3) mm; with clips at each segment's length (sliding clips stretch their spans)."""
    return station_positions(props, clamps, state)[1] if clamps.clips else node_positions(props, clamps, state)


def _largest_movement(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance (mm) between corresponding stations of two shapes."""
    return float(np.max(np.linalg.norm(a - b, axis=1)))


def run_sweep(sweep: SweepProblem, *, progress: Progress | None = None,
              equilibria: list[tuple[Clamps, RodState]] | None = None, judge_assembly: bool = True) -> SweepResult:
    """Carry the hose of `sweep` through all its poses; measure clearance and health at each.

    progress: optional callable(phase, fraction) for a progress bar.
    equilibria: if given, the (clamps, state) of every pose is appended to it, in pose order (the
        SweepResult keeps no frames; the variation study's sensitivities differentiate these).
    judge_assembly: give the assembly (the placement at design position) its uniqueness verdict and error estimate;
        without, its unique is None ("not checked") and its discretisation_error None (a study's samples, which read
        the poses only).
    Raises PlacementError (from the placement or the continuation) when a pose cannot be reached.
    """
    with one_blas_thread():  # many small dense solves: BLAS threads only contend
        return _run_sweep(sweep, progress, equilibria, judge_assembly)


def _run_sweep(sweep: SweepProblem, progress: Progress | None, equilibria: list | None,
               judge_assembly: bool) -> SweepResult:
    """run_sweep on one BLAS thread."""
    started = time.perf_counter()
    problem = sweep.problem
    assembly = solve(problem, progress=_prefixed(progress, "assembly"), estimate_error=judge_assembly,
                     check_uniqueness=judge_assembly)
    count = sweep.pose_count
    n_nodes = problem.hose.segments + 1
    tracker = _Tracker(sweep, assembly, roll_free=False)
    indexes = [TriangleIndex(o.vertices, o.faces) for o in sweep.obstacles]

    centerlines = np.empty((count, n_nodes, 3))
    stretched = np.empty((count, n_nodes))  # arc length of the stations (sliding clips move them)
    n_clips = len(problem.clips)
    clip_loads = np.empty((2, count, n_clips, 3))  # force N, moment N*mm of each clip on the hose
    clip_arcs = np.empty((count, n_clips))
    mounts = np.empty((4, count, 3))  # start point, end point, start direction, end direction
    health = []
    iterations = np.zeros(count, dtype=int)
    near = [[] for _ in sweep.obstacles]
    touching = []  # per pose: the ObstacleContact of every contact obstacle (and "self")
    snaps: list[Snap] = []
    events: list[str] = []
    solve_time = clearance_time = 0.0
    for k in range(count):
        tick = time.perf_counter()
        reached = tracker.move_to(k)
        solve_time += time.perf_counter() - tick
        if equilibria is not None:
            equilibria.append((reached.clamps, reached.state))
        nodes = reached.nodes
        centerlines[k] = nodes
        if n_clips:
            stretched[k] = station_positions(tracker.props, reached.clamps, reached.state)[0]
            clip_loads[:, k] = clip_reactions(tracker.props, reached.clamps, reached.state)
            clip_arcs[k] = clip_arc_lengths(tracker.props, reached.clamps, reached.state)
        mounts[:, k] = _mount_geometry(reached.clamps)
        health.append(hose_health(tracker.props, reached.clamps, reached.state, problem.hose.outer_radius))
        if reached.contact is not None:
            reports, beyond = _contacts_at(k, tracker, reached)
            touching.append(reports)
            health[-1] = replace(health[-1], start_force=health[-1].start_force - beyond[0])
        iterations[k] = reached.iterations
        if reached.events:
            events.extend(reached.events)
            if k > 0:  # the step from the design position to the first pose is not part of the sweep
                snaps.append(Snap(k, reached.jump, reached.events))
        tick = time.perf_counter()
        fittings = _fitting_lines(sweep, k)
        for obstacle, index, found in zip(sweep.obstacles, indexes, near):
            found.append(_nearest(index, sweep.pose(obstacle.body, k), nodes, problem.hose.outer_radius, fittings))
        clearance_time += time.perf_counter() - tick
        if progress is not None:
            progress("sweep", (k + 1) / count)

    free_centerlines = separation = None
    if sweep.compare_free_roll:
        tick = time.perf_counter()
        free_centerlines, free_events = _free_roll_sweep(sweep, assembly, progress)
        events.extend(f"end free to spin: {event}" for event in free_events)
        separation = np.max(np.linalg.norm(free_centerlines - centerlines, axis=2), axis=1)
        solve_time += time.perf_counter() - tick

    return SweepResult(
        sweep=sweep,
        assembly=assembly,
        s=assembly.s,
        centerlines=centerlines,
        start_points=mounts[0],
        end_points=mounts[1],
        start_directions=mounts[2],
        end_directions=mounts[3],
        bend_radius=np.array([h.bend_radius for h in health]),
        twisting_moment=np.array([h.twisting_moment for h in health]),
        start_force=np.array([h.start_force for h in health]),
        start_moment=np.array([h.start_moment for h in health]),
        end_force=np.array([h.end_force for h in health]),
        end_moment=np.array([h.end_moment for h in health]),
        single_plane_offset=np.array([_single_plane(mounts[:, k]) for k in range(count)]),
        clearances=[
            ObstacleClearance(
                obstacle=obstacle,
                distance=np.array([p.distance for p in found]),
                s=np.array([p.s for p in found]),
                on_hose=np.array([p.on_hose for p in found]),
                on_obstacle=np.array([p.on_obstacle for p in found]),
            )
            for obstacle, found in zip(sweep.obstacles, near)
        ],
        iterations=iterations,
        free_centerlines=free_centerlines,
        separation=separation,
        snaps=snaps,
        events=events,
        solve_seconds=solve_time,
        clearance_seconds=clearance_time,
        wall_time=time.perf_counter() - started,
        clip_forces=clip_loads[0],
        clip_moments=clip_loads[1],
        clip_arc_lengths=clip_arcs,
        station_arc_lengths=stretched if any(clip.slides for clip in problem.clips) else None,
        contacts=_per_obstacle(touching),
    )


def _contacts_at(index: int, tracker: _Tracker, reached: _Reached) -> tuple[list, np.ndarray]:
    """The contact reports and the contact forces beyond each station (procedures/contact/placement.contact_reports)
    at pose `index`; PlacementError if the hose enters anything there (the contact solver's guarantee failed)."""
    from hoseline.procedures.contact.placement import contact_reports

    reports, beyond = contact_reports(tracker.sweep.problem, tracker.props, reached.clamps, reached.state,
                                      reached.contact)
    worst = min(reports, key=lambda report: report.min_gap)
    if worst.min_gap < 0.0:
        raise PlacementError(f"sweep with contact: at pose {index} the hose enters {worst.name!r} by "
                             f"{-worst.min_gap:.3g} mm; this is a solver error, please report it with the sweep file")
    return reports, beyond


def _per_obstacle(touching: list) -> list[SweepContact]:
    """The per-pose contact reports (a list per pose) regrouped per obstacle, over the poses."""
    if not touching:
        return []
    return [
        SweepContact(
            name=first.name,
            kind=first.kind,
            min_gap=np.array([pose[j].min_gap for pose in touching]),
            total_force=np.array([pose[j].total_force for pose in touching]),
            length_in_contact=np.array([pose[j].length_in_contact for pose in touching]),
            points=[pose[j].point for pose in touching],
            forces=[np.linalg.norm(pose[j].force, axis=1) for pose in touching],
        )
        for j, first in enumerate(touching[0])
    ]


def _free_roll_sweep(sweep: SweepProblem, assembly: Result, progress: Progress | None) -> tuple[np.ndarray, list[str]]:
    """Centrelines (M, N+1, 3) of the sweep with the end fitting free to spin about its axis, and its events.

    With the roll free, no twist can be locked in: the start is the placement without twist
    (its end frame is the torque-free lock angle).
    """
    problem = sweep.problem
    if problem.end_twist_deg != 0.0:
        assembly = solve(replace(problem, end_twist_deg=0.0), progress=_prefixed(progress, "assembly, roll free"),
                         estimate_error=False, check_uniqueness=False)  # its shape only
    tracker = _Tracker(sweep, assembly, roll_free=True)
    shapes = np.empty((sweep.pose_count, problem.hose.segments + 1, 3))
    for k in range(sweep.pose_count):
        reached = tracker.move_to(k)
        shapes[k] = stations(tracker.props, reached.clamps, reached.state)
        if progress is not None:
            progress("sweep, end roll free", (k + 1) / sweep.pose_count)
    return shapes, tracker.log.events


def _nearest(index: TriangleIndex, pose: Pose, nodes: np.ndarray, outer_radius: float, fittings=(None, None)):
    """Nearest approach of the hose (and its end fittings: (centreline, radius) or None each) to an obstacle
    at `pose`: computed in the obstacle's own coordinates (the hose moved by the inverse pose), answered in
    world coordinates."""
    inverse = pose.inverse()
    local = tuple(None if piece is None else (inverse.points(piece[0]), piece[1]) for piece in fittings)
    found = nearest_with_fittings(index, inverse.points(nodes), outer_radius, local)
    return replace(found, on_hose=pose.point(found.on_hose), on_obstacle=pose.point(found.on_obstacle))


def _fitting_lines(sweep: SweepProblem, index: int) -> tuple:
    """(start, end): each end fitting's centreline (mm) moved with its mount's body at pose `index`, and its
    outer radius (mm); None where the hose has no fitting."""
    problem = sweep.problem
    fittings = problem.fittings
    if fittings is None:
        return (None, None)
    lines = []
    for port, fitting, body in ((fittings.start_port, fittings.start, sweep.start_body),
                                (fittings.end_port, fittings.end, sweep.end_body)):
        lines.append(None if fitting is None else (sweep.pose(body, index).points(fitting.centreline(port)),
                                                   fitting.radius(problem.hose.outer_diameter)))
    return tuple(lines)


def _mount_geometry(clamps: Clamps) -> np.ndarray:
    """(4, 3): start tip, end tip (mm), start and end directions into the hose."""
    return np.array([clamps.start_point, clamps.end_point, clamps.start_frame[2], -clamps.end_frame[2]])


def _single_plane(mounts: np.ndarray) -> float:
    """Single-plane offset (mm) of the mounts (4, 3) as _mount_geometry gives them; NaN if undefined."""
    offset = single_plane_offset(Mount(mounts[0], mounts[2]), Mount(mounts[1], mounts[3]))
    return math.nan if offset is None else offset


def _prefixed(progress: Progress | None, label: str) -> Progress | None:
    """progress with `label` put in front of the phase name (None stays None)."""
    if progress is None:
        return None
    return lambda phase, fraction: progress(f"{label}: {phase}", fraction)
