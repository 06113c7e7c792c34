"""The studio's working state: the problem being edited, the hose's current equilibrium, obstacles and a sweep.

One Session per server.  Every change the page asks for (a fitting moved, a slider, a sweep pose)
is a step of continuation from the current equilibrium (procedures/placement/tracking.py); "place
again" runs the published placement sequence (procedures/placement/sequence.solve) from the
straight hose.  Changes are checked by the same code as problem files (io/problem_file.py), so
the page cannot make a problem that a file could not hold.

The fittings: the start fitting's frame and the end fitting's frame at zero twist (the frame the
placement locked, moved with the fitting since) are what the page drags; the end fitting is
clamped at that frame turned by the twist at assembly.  Clips are dragged the same way: each
clip's point and frame as it holds the hose (a fixed clip keeps the roll locked at assembly,
carried with its frame); the problem's clip keeps its arc length (on its station) and takes the
dragged point and the frame's d3 as its direction.  With end fittings (model/fittings.py) the page
drags the ports instead, each carrying its rigid fitting (studio/ports.py): the outlets, where the
flexible hose is clamped, follow rigidly, and the problem keeps the ports with each elbow's
reference turned with its port.  A sweep's poses move the fittings and the
clips riding on bodies from their design position, where the sweep was opened, as a sweep run does.

Not thread-safe: the server calls it from one worker thread only.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, replace

import numpy as np

from hoseline.io.problem_file import ProblemFileError, problem_from_dict, problem_to_dict, problem_to_toml
from hoseline.model import limits
from hoseline.model.motion import Pose, quaternion_matrix
from hoseline.model.problem import Problem
from hoseline.model.sweep import DEFAULT_CLEARANCE, Obstacle, SweepProblem
from hoseline.procedures.geometry.clearance import TriangleIndex
from hoseline.procedures.geometry.contact_shapes import SOURCE as CONTACT_SOURCE, contact_meshes
from hoseline.procedures.placement.continuation import PlacementError, Progress
from hoseline.procedures.placement.result import Result
from hoseline.procedures.placement.sequence import solve
from hoseline.procedures.placement.tracking import Fittings, Step, Tracker, twisted
from hoseline.studio.comparison import placement_comparison
from hoseline.studio.messages import HoseTarget, Target
from hoseline.studio.ports import PortAnchor, piece_outline
from hoseline.studio.saving import saved_problem, saved_twists


MAX_TWIST_STEP = 90.0  # degrees of twist per step of continuation (a frame cannot tell 270 from -90)


class StudioError(ValueError):
    """A change the studio refuses (bad values, a hose that cannot reach); the message is shown on the page."""


@dataclass
class ShownObstacle:
    """An obstacle on the page with its search tree for clearance."""

    obstacle: Obstacle
    index: TriangleIndex


class Session:
    """The problem, the hose's equilibrium and the surroundings the page shows.

    problem: the problem to start from (placed at once).  sweep: a sweep whose motion the
    timeline plays and whose obstacles are shown (its problem is used if given).
    """

    def __init__(self, problem: Problem | None = None, *, sweep: SweepProblem | None = None) -> None:
        if (problem is None) == (sweep is None):
            raise ValueError("give a problem or a sweep")
        self.obstacles: list[ShownObstacle] = []
        self.sweep: SweepProblem | None = None
        self.pose_index: int | None = None
        self.revision = 0  # counts the changes of the session's content (files opened, obstacles added)
        self.last_step: Step | None = None
        self.comparison: dict | None = None
        if sweep is not None:
            self.open_sweep(sweep)
        else:
            self.open_problem(problem)

    # --- opening things ---

    def open_problem(self, problem: Problem) -> None:
        """Edit `problem` from now on (the obstacles stay, those of the last problem's [contact] replaced by
        this one's; a sweep's motion is dropped); place it.

        Raises PlacementError when it cannot be placed (the session stays as it was).
        The studio shows the hose at its segment count: a file's force accuracy (which `hoseline solve` refines the
        segments for) is dropped, so that a saved file solves to the shape shown.
        """
        problem = replace(problem, force_accuracy=None)
        self._adopt(problem, solve(problem))
        self.sweep, self.pose_index = None, None
        kept = [shown for shown in self.obstacles if shown.obstacle.source != CONTACT_SOURCE]
        self.obstacles = kept + _shown(contact_meshes(problem))
        self.revision += 1

    def open_sweep(self, sweep: SweepProblem) -> None:
        """Edit the sweep's problem at design position, show its obstacles (and those of its [contact]), play its
        motion; place it."""
        obstacles = _shown(list(sweep.obstacles) + contact_meshes(sweep.problem))
        self._adopt(sweep.problem, solve(sweep.problem))
        self.sweep, self.pose_index, self.obstacles = sweep, None, obstacles
        self.design = self.handles()
        self.revision += 1

    def add_obstacle(self, name: str, vertices: np.ndarray, faces: np.ndarray, source: str) -> None:
        """Show a fixed obstacle (mm) with the default required clearance."""
        obstacle = Obstacle(name, vertices, faces, DEFAULT_CLEARANCE, None, source)
        self.obstacles.append(ShownObstacle(obstacle, TriangleIndex(vertices, faces)))
        self.revision += 1

    def set_mounts(self, start, end) -> None:
        """Put the fittings on new mounts (model.Mount, e.g. from an IGES file) and place the hose there."""
        data = problem_to_dict(self.problem)
        data["start"] = {"point": start.point.tolist(), "direction": start.direction.tolist()}
        data["end"].update(point=end.point.tolist(), direction=end.direction.tolist())
        problem = self._validated(data)
        self._adopt(problem, solve(problem))
        self.pose_index = None
        self.revision += 1

    # --- the hose ---

    def place_again(self) -> None:
        """Run the published placement sequence from the straight hose and continue from its result."""
        self._adopt(self.problem, solve(self.problem))

    def set_segments(self, segments: int) -> None:
        """Cut the hose into `segments` and place it again (a shape of one discretisation is not
        continued into another): the fittings, length and twist stay as they are now."""
        data = problem_to_dict(self.problem)
        data["hose"]["segments"] = segments
        problem = self._validated(data)
        self._adopt(problem, solve(problem))

    def set_required_clearance(self, index: int, required_mm: float) -> None:
        """The clearance (mm) required to obstacle `index`: the colour map and readouts judge against it."""
        if not 0 <= index < len(self.obstacles):
            raise StudioError(f"obstacle {index} does not exist: there are {len(self.obstacles)}")
        if not limits.within(required_mm, (0.0, limits.CLEARANCE_MM)):
            raise StudioError(f"required clearance = {required_mm:g} mm: give 0 to {limits.CLEARANCE_MM:g} mm")
        shown = self.obstacles[index]
        self.obstacles[index] = replace(shown, obstacle=replace(shown.obstacle, clearance=float(required_mm)))

    def _adopt(self, problem: Problem, placement: Result) -> None:
        """Continue from a fresh placement of `problem`."""
        self.problem, self.placement = problem, placement
        self.tracker = Tracker(problem, placement)
        self.end_base = twisted(placement.end_frame, -problem.end_twist_deg)
        self.anchor = None if problem.fittings is None else PortAnchor.at(problem.fittings, placement.start_frame,
                                                                          self.end_base)
        self.port_frames = None if self.anchor is None else (self.anchor.start_port, self.anchor.end_port)
        self.comparison = self._compared(placement)
        self.last_step = None

    def apply(self, target: Target) -> None:
        """Carry the hose to `target` (fittings, twist, hose properties, or a sweep pose) by continuation.

        Raises StudioError (bad values) or PlacementError (no equilibrium there); nothing changes then.
        """
        twist = self.problem.end_twist_deg if target.twist is None else target.twist
        if target.pose is not None:
            handles = self._pose_fittings(target.pose)
        else:
            handles = self.handles()
            if target.start is not None:
                handles = replace(handles, start_point=np.array(target.start.point),
                                  start_frame=_frame(target.start.quaternion))
            if target.end is not None:
                handles = replace(handles, end_point=np.array(target.end.point), end_frame=_frame(target.end.quaternion))
            if target.clips is not None:
                if len(target.clips) != len(self.problem.clips):
                    raise StudioError(f"clips: {len(target.clips)} given for the problem's {len(self.problem.clips)}: "
                                      "give every clip's point and quaternion, in the problem's order")
                handles = replace(handles, clip_points=np.array([c.point for c in target.clips]).reshape(-1, 3),
                                  clip_frames=np.array([_frame(c.quaternion) for c in target.clips]).reshape(-1, 3, 3))
        data = problem_to_dict(self.problem)  # with fittings, [start] and [end] are the ports
        data["start"] = {"point": handles.start_point.tolist(), "direction": handles.start_frame[2].tolist()}
        data["end"] = {"point": handles.end_point.tolist(), "direction": (-handles.end_frame[2]).tolist(), "twist": twist}
        if self.anchor is not None:
            data["fittings"] = self.anchor.fitting_tables(data["fittings"], handles.start_frame, handles.end_frame)
        if target.hose is not None:
            data["hose"] = _hose_section(data["hose"], self.problem, target.hose)
        if self.problem.clips:
            data["clips"] = self._clip_sections(data["clips"], data["hose"]["length"], handles)
        problem = self._validated(data)  # its start and end are the outlets (Fitting.outlet of the ports)
        fittings = handles
        if self.anchor is not None:
            start_outlet, end_outlet = self.anchor.outlet_frames(handles.start_frame, handles.end_frame)
            fittings = replace(handles, start_frame=start_outlet, end_frame=end_outlet)
        self.last_step = self._twist_to(problem, replace(fittings, start_point=problem.start.point,
                                                         end_point=problem.end.point))
        self.problem, self.end_base = problem, fittings.end_frame
        if self.anchor is not None:
            self.port_frames = (handles.start_frame, handles.end_frame)
        if target.pose is not None:
            self.pose_index = target.pose
        self.comparison = None

    def _twist_to(self, problem: Problem, fittings: Fittings) -> Step:
        """Move the tracker to `problem` with `fittings` (the end frame at zero twist) and the problem's twist.

        A frame says nothing of whole turns, and a step between two frames takes the shorter way
        round, so a change of twist is made in steps of at most MAX_TWIST_STEP degrees, each taking
        the way the twist goes.  All or nothing: a failing step leaves the tracker as it was.
        """
        before, centerline = copy.copy(self.tracker), self.tracker.centerline
        change = problem.end_twist_deg - self.problem.end_twist_deg
        count = max(1, math.ceil(abs(change) / MAX_TWIST_STEP))
        steps = []
        try:
            for k in range(1, count + 1):
                twist = problem.end_twist_deg - change * (count - k) / count
                steps.append(self.tracker.move(replace(problem, end_twist_deg=twist),
                                               replace(fittings, end_frame=twisted(fittings.end_frame, twist))))
        except Exception:
            self.tracker = before
            raise
        movement = float(np.max(np.linalg.norm(self.tracker.centerline - centerline, axis=1)))
        return Step(sum(s.iterations for s in steps), sum(s.seconds for s in steps),
                    [event for s in steps for event in s.events], movement)

    def compare_with_placement(self, progress: Progress | None = None) -> dict:
        """Place the current problem afresh and say how far that shape is from the one shown (idle work).

        progress: called after each continuation step of the placements (continuation.Progress); an exception it
        raises abandons the comparison (nothing kept) and comes out of here."""
        if self.comparison is None:
            try:
                self.comparison = self._compared(solve(self.problem, progress=progress), progress)
            except PlacementError as exc:
                self.comparison = {"same": False, "failed": str(exc)}
        return self.comparison

    def _compared(self, fresh: Result, progress: Progress | None = None) -> dict:
        """The comparison of the shape shown with `fresh`, a fresh placement of the problem (view.placement_comparison),
        and, as "saved", with the problem file as saved (saving.saved_twists: its twists at assembly and how far its
        fresh placement is from the shape shown)."""
        comparison = placement_comparison(self.tracker.centerline, self.end_frame, fresh)
        comparison["saved"] = saved_twists(self.problem, self.tracker.fittings, fresh, self.tracker.centerline, progress)
        return comparison

    @property
    def end_frame(self) -> np.ndarray:
        """The end fitting's frame as clamped (twist included)."""
        return self.tracker.fittings.end_frame

    def fittings_at_zero_twist(self) -> Fittings:
        """Where the flexible hose is clamped now (the outlets with end fittings), the end frame without the twist."""
        fittings = self.tracker.fittings
        return replace(fittings, end_frame=self.end_base)

    def handles(self) -> Fittings:
        """What the page drags: the ports (mm; frames as in studio/ports.py) with end fittings, else the ends of the
        hose; the end frame without the twist at assembly; the clips as they hold the hose."""
        fittings = self.fittings_at_zero_twist()
        if self.anchor is None:
            return fittings
        ports = self.problem.fittings
        return replace(fittings, start_point=ports.start_port.point, start_frame=self.port_frames[0],
                       end_point=ports.end_port.point, end_frame=self.port_frames[1])

    def pieces(self) -> dict:
        """The end fittings as the page draws them: per end that has one, its centreline in its port's frame (mm,
        ports.piece_outline) and radius (mm)."""
        if self.anchor is None:
            return {}
        frames = dict(zip(("start", "end"), self.port_frames))
        return {name: piece_outline(port.point, frames[name], port.direction, fitting, self.problem.hose.outer_diameter)
                for name, port, fitting in self.problem.fittings.pieces()}

    def obstacle_pose(self, shown: ShownObstacle) -> Pose:
        """Where an obstacle is: moved with its body to the sweep pose shown, else at design position."""
        if self.sweep is None or self.pose_index is None:
            return Pose()
        return self.sweep.pose(shown.obstacle.body, self.pose_index)

    def result(self, complete: bool = True) -> Result:
        """The shape shown as a Result (for the exports and the readouts); not `complete`: without the readouts that
        cost most (Tracker.result), for the frames of a drag."""
        return self.tracker.result(self.placement.lock_angle_deg, complete)

    def problem_toml(self, assembled: bool = False) -> str:
        """The problem as a problem file (mounts and hose as now): with the twists at assembly (the end's, each fixed
        clip's) that place it as shown (saving.saved_twists, found by a fresh placement if none was made since the last
        change; the twists as set when no fresh placement can be made), or, `assembled`, with the twists as set (the
        shape "Place again" gives)."""
        if assembled:
            return problem_to_toml(self.problem)
        saved = self.compare_with_placement().get("saved")
        return problem_to_toml(self.problem if saved is None
                               else saved_problem(self.problem, saved["twist"], saved["clip_twists"]))

    def sweep_to_run(self) -> SweepProblem:
        """The open sweep with the hose and twist as now, at the sweep's design mounts."""
        if self.sweep is None:
            raise StudioError("no sweep is open: open a sweep file (a problem file with [[bodies]]) first")
        design = self.sweep.problem
        problem = replace(design, hose=self.problem.hose, end_twist_deg=self.problem.end_twist_deg,
                          gravity=self.problem.gravity)
        return replace(self.sweep, problem=problem)

    # --- helpers ---

    def _pose_fittings(self, index: int) -> Fittings:
        """What the page drags (Session.handles: the ports with end fittings; end frame at zero twist) and the clips
        at sweep pose `index`, moved with their bodies."""
        if self.sweep is None:
            raise StudioError("no sweep is open: the timeline needs a sweep file")
        if not 0 <= index < self.sweep.pose_count:
            raise StudioError(f"pose {index} is outside the sweep's 0..{self.sweep.pose_count - 1}")
        if any(body is not None for body in self.sweep.contact_bodies):
            raise StudioError("the sweep's [contact] obstacles move with bodies, which the timeline does not do yet: "
                              "run the sweep and open its report")
        sweep, design = self.sweep, self.design
        start = sweep.pose(sweep.start_body, index)
        end = sweep.pose(sweep.end_body, index)
        clips = [sweep.pose(sweep.clip_body(j), index) for j in range(len(design.clip_points))]
        return Fittings(start.point(design.start_point), start.frame(design.start_frame),
                        end.point(design.end_point), end.frame(design.end_frame),
                        np.array([pose.point(p) for pose, p in zip(clips, design.clip_points)]).reshape(-1, 3),
                        np.array([pose.frame(f) for pose, f in zip(clips, design.clip_frames)]).reshape(-1, 3, 3))

    def _clip_sections(self, sections: list[dict], length_mm: float, fittings: Fittings) -> list[dict]:
        """The [[clips]] tables at the fittings' clip points and directions (d3 of their frames), each at the
        same station of a hose `length_mm` long (a sliding clip's starting arc length scaled with the length)."""
        holds, segments = self.tracker.clamps.clips, self.problem.hose.segments
        tables = []
        for section, hold, point, frame in zip(sections, holds, fittings.clip_points, fittings.clip_frames):
            section = dict(section, point=point.tolist())
            if "direction" in section:
                section["direction"] = frame[2].tolist()
            if hold.sliding:
                section["arc_length"] = section["arc_length"] * length_mm / self.problem.hose.length
            else:
                section["arc_length"] = hold.node * length_mm / segments
            tables.append(section)
        return tables

    def _validated(self, data: dict) -> Problem:
        """The problem of a problem-file dict, checked as a file is (StudioError with the file's message).

        The page never changes the contact obstacles: they are taken over from the problem shown, not
        read again (a mesh obstacle's file would be read at every drag), with their hose_side hints and the
        placement's way with them ([contact] placement), and checked with the rest.
        """
        edited = {key: value for key, value in data.items() if key != "contact"}
        current = self.problem
        try:
            problem = problem_from_dict(edited, source="studio")
            return replace(problem, contact=current.contact, self_contact=current.self_contact,
                           contact_sides=current.contact_sides, contact_placement=current.contact_placement)
        except ProblemFileError as exc:
            raise StudioError(str(exc).removeprefix("studio: ")) from None
        except ValueError as exc:  # the Problem's own checks of contact with the rest (model/problem.py)
            raise StudioError(str(exc)) from None


def _shown(obstacles: list[Obstacle]) -> list[ShownObstacle]:
    """The obstacles with their search trees."""
    return [ShownObstacle(o, TriangleIndex(o.vertices, o.faces)) for o in obstacles]


def _frame(quaternion: list[float]) -> np.ndarray:
    """Fitting frame (rows d1, d2, d3) of an object turned by the unit quaternion (w, x, y, z)."""
    return quaternion_matrix(quaternion).T


def _hose_section(section: dict, problem: Problem, hose: HoseTarget) -> dict:
    """The [hose] table with the page's values put in (torsion factor kept when EI changes)."""
    section = dict(section)
    factor = problem.hose.torsion_factor if hose.torsion_factor is None else hose.torsion_factor
    for key in ("length", "bending_stiffness", "mass_per_length"):
        value = getattr(hose, key)
        if value is not None:
            section[key] = value
    if "bending_stiffness_2" in section and hose.bending_stiffness is not None:
        section["bending_stiffness_2"] *= hose.bending_stiffness / problem.hose.bending_stiffness
    del section["torsional_stiffness"]
    section["torsion_factor"] = factor
    return section
