"""A sweep: the placed hose carried through the motion of the bodies its mounts sit on, among obstacles."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hoseline.model import limits
from hoseline.model.motion import BodyMotion, Pose, Stage
from hoseline.model.problem import Problem, reaches

DEFAULT_CLEARANCE = 25.4  # mm, one inch: the usual requirement


@dataclass(frozen=True)
class Obstacle:
    """Surroundings the hose must keep clear of: a triangle mesh, fixed or moving with a body.

    name: for reports.  vertices: (V, 3) mm at design position.  faces: (F, 3) vertex indices.
    clearance: mm, the required distance from the hose surface.  body: name of the body it
    moves with, or None for fixed surroundings.  source: where the mesh came from (a file name).
    """

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    clearance: float = DEFAULT_CLEARANCE
    body: str | None = None
    source: str = ""

    def __post_init__(self) -> None:
        if not (np.isfinite(self.clearance) and self.clearance >= 0.0):
            raise ValueError(f"obstacle '{self.name}': clearance = {self.clearance!r} must be zero or positive (mm)")
        if len(self.faces) == 0:
            raise ValueError(f"obstacle '{self.name}': the mesh has no triangles")


@dataclass(frozen=True)
class SweepProblem:
    """Everything a sweep needs.

    problem: the hose and its mounts at design position (the twist is locked at assembly).
    start_body, end_body: names of the bodies the mounts move with, or None for fixed.
    motions: the moving bodies, all with the same number of poses.
    obstacles: the surroundings.
    compare_free_roll: also sweep with the end fitting free to spin about its axis (the
        common modelling error) and report how far that answer is from the right one.
    clip_bodies: the body each of problem.clips moves with (None: fixed), empty for all fixed.
    contact_bodies: the body each of problem.contact moves with (None: fixed), empty for all fixed.
    """

    problem: Problem
    start_body: str | None
    end_body: str | None
    motions: tuple[BodyMotion, ...]
    obstacles: tuple[Obstacle, ...] = ()
    compare_free_roll: bool = True
    clip_bodies: tuple[str | None, ...] = ()
    contact_bodies: tuple[str | None, ...] = ()

    def __post_init__(self) -> None:
        if not self.motions:
            raise ValueError("a sweep needs at least one moving body")
        names = [m.name for m in self.motions]
        counts = {m.name: len(m.poses) for m in self.motions}
        if len(set(counts.values())) != 1:
            raise ValueError(f"all moving bodies need the same number of poses, got {counts}")
        for role, body in (("start.body", self.start_body), ("end.body", self.end_body)):
            if body is not None and body not in names:
                raise ValueError(f"{role} = {body!r}: no such body; bodies: {', '.join(names)}")
        if self.clip_bodies and len(self.clip_bodies) != len(self.problem.clips):
            raise ValueError(f"{len(self.clip_bodies)} clip bodies for {len(self.problem.clips)} clips: give one per clip")
        for index, body in enumerate(self.clip_bodies):
            if body is not None and body not in names:
                raise ValueError(f"clips[{index}].body = {body!r}: no such body; bodies: {', '.join(names)}")
        if self.contact_bodies and len(self.contact_bodies) != len(self.problem.contact):
            raise ValueError(f"{len(self.contact_bodies)} contact bodies for {len(self.problem.contact)} contact "
                             "obstacles: give one per obstacle")
        for index, body in enumerate(self.contact_bodies):
            if body is not None and body not in names:
                raise ValueError(f"contact.obstacles[{index}].body = {body!r}: no such body; bodies: {', '.join(names)}")
        for obstacle in self.obstacles:
            if obstacle.body is not None and obstacle.body not in names:
                raise ValueError(f"obstacle '{obstacle.name}': body = {obstacle.body!r}: no such body")
        self._within_size_limits()
        self._hose_reaches_at_every_pose()

    def _within_size_limits(self) -> None:
        """Refuse a sweep whose result arrays or clearance search would not fit in memory."""
        segments = self.problem.hose.segments
        stations = self.pose_count * (segments + 1)
        if stations > limits.SWEEP_STATIONS:
            raise ValueError(
                f"{self.pose_count} poses of a hose of {segments} segments are {stations} stations to compute and "
                f"store, more than {limits.SWEEP_STATIONS}: use fewer poses (steps, pose table rows) or segments"
            )
        triangles = sum(len(obstacle.faces) for obstacle in self.obstacles)
        if triangles > limits.OBSTACLE_TRIANGLES:
            raise ValueError(
                f"the obstacles have {triangles} triangles, more than {limits.OBSTACLE_TRIANGLES}: "
                "export coarser meshes (a tolerance of 0.1 mm is plenty for clearance)"
            )

    def _hose_reaches_at_every_pose(self) -> None:
        """Refuse, before any solving, a pose that moves the mounts as far apart as the hose is long, naming it."""
        length = self.problem.hose.length
        starts = self._tips(self.start_body, self.problem.start.point)
        ends = self._tips(self.end_body, self.problem.end.point)
        for index, distance in enumerate(np.linalg.norm(ends - starts, axis=1)):
            if not reaches(length, float(distance)):
                raise ValueError(
                    f"at pose {index} ({self.pose_label(index)}) the mounts are {distance:.6g} mm apart and the hose "
                    f"is {length:g} mm long: it cannot reach; keep the motion within reach or use a hose longer than "
                    f"{distance:.6g} mm"
                )

    def _tips(self, body: str | None, point: np.ndarray) -> np.ndarray:
        """(M, 3) where the fitting tip `point` (mm, design position) is at each pose of `body`."""
        if body is None:
            return np.tile(point, (self.pose_count, 1))
        motion = next(m for m in self.motions if m.name == body)
        rotations = np.array([pose.rotation for pose in motion.poses])
        return rotations @ point + np.array([pose.position for pose in motion.poses])

    def pose_label(self, index: int) -> str:
        """The travel of pose `index` as 'name = value unit', e.g. 'jounce = 20 mm'."""
        stage = next((s for s in self.stages if s.first <= index < s.first + s.count), Stage("travel", "", 0, 0))
        return f"{stage.name} = {self.travel[index]:g} {stage.unit}".rstrip()

    @property
    def pose_count(self) -> int:
        """Number of poses M of the sweep."""
        return len(self.motions[0].poses)

    @property
    def travel(self) -> np.ndarray:
        """(M,) travel of each pose, in its stage's unit (from the first moving body)."""
        return self.motions[0].travel

    @property
    def stages(self) -> tuple[Stage, ...]:
        """The stages of the travel axis (from the first moving body)."""
        return self.motions[0].stages

    def clip_body(self, index: int) -> str | None:
        """The body clip `index` moves with (None: fixed)."""
        return self.clip_bodies[index] if self.clip_bodies else None

    def contact_body(self, index: int) -> str | None:
        """The body contact obstacle `index` (of problem.contact) moves with (None: fixed)."""
        return self.contact_bodies[index] if self.contact_bodies else None

    def pose(self, body: str | None, index: int) -> Pose:
        """Pose of `body` at sweep pose `index` (the design position for None)."""
        if body is None:
            return Pose()
        return next(m for m in self.motions if m.name == body).poses[index]
