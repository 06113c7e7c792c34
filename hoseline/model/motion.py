"""Rigid-body motion of the parts the hose is mounted on: poses, and simple generators of them.

A pose (R, p) moves a body from its design position, where the problem file gives the
mounts, to where it is: a point P of the body goes to R P + p, and a fitting frame F
(rows d1, d2, d3) to F R^T.  Quaternions are unit quaternions, scalar first
(w, x, y, z), and rotate body coordinates into world coordinates (active rotation).

Generators for quick studies: a rotation about a fixed axis (steer), a translation along
a fixed axis (jounce and rebound), run in sequence (see generated_motion); axes and
points are in world coordinates at design position.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hoseline.model.mounts import unit_vector


def quaternion_matrix(quaternion) -> np.ndarray:
    """Rotation matrix of a unit quaternion (w, x, y, z), scalar first; dimensionless."""
    w, x, y, z = np.asarray(quaternion, dtype=float) / np.linalg.norm(quaternion)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_quaternion(rotation: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z), scalar first and w >= 0, of a rotation matrix."""
    r = np.asarray(rotation, dtype=float)
    trace = np.trace(r)
    if trace > 0.0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    else:
        i = int(np.argmax(np.diag(r)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1.0 + r[i, i] - r[j, j] - r[k, k], 0.0))
        q = [0.0] * 4
        q[0] = (r[k, j] - r[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (r[j, i] + r[i, j]) / s
        q[1 + k] = (r[k, i] + r[i, k]) / s
    q = np.array(q)
    return q if q[0] >= 0.0 else -q


def axis_angle_matrix(axis, angle_rad: float) -> np.ndarray:
    """Rotation by angle_rad (right-hand rule) about the unit axis."""
    half = 0.5 * angle_rad
    return quaternion_matrix(np.concatenate([[math.cos(half)], math.sin(half) * np.asarray(axis, dtype=float)]))


@dataclass(frozen=True)
class Pose:
    """Where a body is: rotation (3x3, body to world) and translation (mm) from its design position."""

    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def point(self, point) -> np.ndarray:
        """A body point given at design position (mm), where the pose puts it (mm)."""
        return self.rotation @ np.asarray(point, dtype=float) + self.position

    def points(self, points: np.ndarray) -> np.ndarray:
        """Many body points (n, 3) given at design position (mm), where the pose puts them (mm)."""
        return np.asarray(points, dtype=float) @ self.rotation.T + self.position

    def frame(self, frame: np.ndarray) -> np.ndarray:
        """A frame (rows d1, d2, d3) given at design position, turned with the body."""
        return frame @ self.rotation.T

    def then(self, other: "Pose") -> "Pose":
        """This pose followed by `other` (other applied in world coordinates after this one)."""
        return Pose(other.rotation @ self.rotation, other.rotation @ self.position + other.position)

    def inverse(self) -> "Pose":
        """The pose that undoes this one."""
        return Pose(self.rotation.T, -self.rotation.T @ self.position)

    def angle_to(self, other: "Pose") -> float:
        """Angle (rad) of the rotation between this pose's and `other`'s orientation."""
        relative = other.rotation @ self.rotation.T
        return math.acos(min(1.0, max(-1.0, 0.5 * (np.trace(relative) - 1.0))))


def interpolate(a: Pose, b: Pose, t: float) -> Pose:
    """The pose a fraction t (0..1) of the way from a to b: slerp of the rotation, straight line of the position."""
    qa, qb = matrix_quaternion(a.rotation), matrix_quaternion(b.rotation)
    cosine = float(qa @ qb)
    if cosine < 0.0:  # the shorter way round
        qb, cosine = -qb, -cosine
    if cosine > 1.0 - 1e-12:
        q = qa + t * (qb - qa)
    else:
        angle = math.acos(cosine)
        q = (math.sin((1.0 - t) * angle) * qa + math.sin(t * angle) * qb) / math.sin(angle)
    return Pose(quaternion_matrix(q), (1.0 - t) * a.position + t * b.position)


@dataclass(frozen=True)
class Stage:
    """A named part of a sweep: what its travel means and which poses belong to it.

    name: e.g. "steer", "jounce", or the first column of a pose table.  unit: of the travel
    ("deg", "mm", "s", ...).  first, count: the poses [first, first + count) of the sweep.
    """

    name: str
    unit: str
    first: int
    count: int


@dataclass(frozen=True)
class BodyMotion:
    """The poses of one body along the sweep, with the travel each pose is plotted against.

    name: the body's name.  poses: one Pose per sweep pose.  travel: (M,) the travel value of
    each pose in its stage's unit.  stages: the stages, in order, covering all poses.
    """

    name: str
    poses: tuple[Pose, ...]
    travel: np.ndarray
    stages: tuple[Stage, ...]

    def __post_init__(self) -> None:
        if len(self.poses) != len(self.travel) or len(self.poses) == 0:
            raise ValueError(f"body '{self.name}': {len(self.poses)} poses but {len(self.travel)} travel values")
        for index, pose in enumerate(self.poses):
            if not (np.all(np.isfinite(pose.rotation)) and np.all(np.isfinite(pose.position))):
                raise ValueError(f"body '{self.name}': pose {index} is not finite: give finite translations and rotations")


@dataclass(frozen=True)
class Rotation:
    """A generated stage: rotation about a fixed axis through a point (e.g. steer about the kingpin).

    axis: direction (normalised).  point: mm, a point on the axis.  angles_deg: (from, to)
    degrees, right-hand rule.  steps: intervals (the stage has steps + 1 poses).
    """

    axis: np.ndarray
    point: np.ndarray
    angles_deg: tuple[float, float]
    steps: int = 20
    name: str = "steer"
    unit: str = field(default="deg", init=False)

    def pose(self, value: float) -> Pose:
        """The pose at `value` degrees."""
        rotation = axis_angle_matrix(unit_vector(self.axis, f"{self.name}.axis"), math.radians(value))
        point = np.asarray(self.point, dtype=float)
        return Pose(rotation, point - rotation @ point)

    def values(self) -> np.ndarray:
        """(steps + 1,) the stage's angles, degrees."""
        return np.linspace(self.angles_deg[0], self.angles_deg[1], self.steps + 1)


@dataclass(frozen=True)
class Translation:
    """A generated stage: translation along a fixed axis (e.g. jounce and rebound).

    axis: direction (normalised).  distances: (from, to) mm along it.  steps: intervals.
    """

    axis: np.ndarray
    distances: tuple[float, float]
    steps: int = 20
    name: str = "jounce"
    unit: str = field(default="mm", init=False)

    def pose(self, value: float) -> Pose:
        """The pose at `value` mm."""
        return Pose(np.eye(3), value * unit_vector(self.axis, f"{self.name}.axis"))

    def values(self) -> np.ndarray:
        """(steps + 1,) the stage's distances along the axis, mm."""
        return np.linspace(self.distances[0], self.distances[1], self.steps + 1)


def generated_motion(name: str, stages: list[Rotation | Translation]) -> BodyMotion:
    """The motion of body `name` through the generator stages, one after the other.

    Each stage name is a joint coordinate (e.g. "steer", "jounce") that starts at 0, the
    design position; a stage moves its coordinate from its first to its last value while
    the others keep theirs.  Stages of the same name move the same coordinate (they must
    have the same axis and point).  The body's pose applies the coordinates in the order
    they first appear: the first moves the body, the next moves the result, and so on.
    A stage starting where its coordinate already is does not repeat that pose.
    """
    joints: dict[str, Rotation | Translation] = {}
    for stage in stages:
        first = joints.setdefault(stage.name, stage)
        if not _same_joint(first, stage):
            raise ValueError(f"stage {stage.name!r} appears twice with different motions: give the same axis and point, "
                             "or another name")
    current = {joint: 0.0 for joint in joints}
    poses: list[Pose] = []
    travel: list[float] = []
    marks: list[Stage] = []
    for stage in stages:
        values = stage.values()
        if poses and values[0] == current[stage.name]:
            values = values[1:]
        marks.append(Stage(stage.name, stage.unit, len(poses), len(values)))
        for value in values:
            current[stage.name] = float(value)
            pose = Pose()
            for joint, generator in joints.items():
                pose = pose.then(generator.pose(current[joint]))
            poses.append(pose)
            travel.append(float(value))
    return BodyMotion(name, tuple(poses), np.array(travel), tuple(marks))


def _same_joint(a: Rotation | Translation, b: Rotation | Translation) -> bool:
    """Whether two stages move the same joint (same kind, axis and point)."""
    if type(a) is not type(b) or not np.allclose(unit_vector(a.axis, a.name), unit_vector(b.axis, b.name)):
        return False
    return not isinstance(a, Rotation) or bool(np.allclose(a.point, b.point))
