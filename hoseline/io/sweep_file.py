"""Read sweep files: a problem file (TOML) with the motion of the mounts and the surroundings.

The hose, the mounts at design position and the environment are those of a problem file
(read by problem_file.py; see README).  A sweep file adds::

    [start]
    body = "chassis"            # optional: the body the fitting moves with (default: fixed)
    [end]
    body = "knuckle"

    [[bodies]]                  # one per moving body
    name = "knuckle"
    poses = "knuckle.csv"       # a pose table (see pose_table.py), relative to this file, or:
    stages = [                  # generated motion, stage after stage
      { name = "steer", rotate = [0.0, 30.0], axis = [0, 0, 1], point = [-185, -7, 0], steps = 30 },
      { name = "steer", rotate = [30.0, 0.0], axis = [0, 0, 1], point = [-185, -7, 0], steps = 30 },
      { name = "jounce", translate = [0.0, 50.0], axis = [0, 0, 1], steps = 25 },
    ]

    [[obstacles]]
    name = "strut"              # optional, default: the file name without extension
    file = "strut.stl"          # STL, OBJ, PLY or STEP, relative to this file, mm
    clearance = 25.4            # mm, optional (default one inch)
    body = "knuckle"            # optional: moves with this body (default: fixed)

    [sweep]
    compare_free_roll = true    # optional: also sweep with the end fitting free to spin

    [contact]                   # optional, as in a problem file: planes, spheres, cylinders, boxes, meshes
                                # and self-contact, kept out of at every pose
    [[contact.obstacles]]       # as in a problem file, plus:
    body = "knuckle"            # optional: the obstacle moves with this body (default: fixed)

    [[clips]]                   # as in a problem file, plus:
    body = "knuckle"            # optional: the clip moves with this body (default: fixed)

rotate: [from, to] degrees about `axis` through `point` (mm); translate: [from, to] mm
along `axis`; steps: intervals of the stage (default 20).  Axes and points are in world
coordinates at design position.  A stage's name is a joint coordinate, starting at 0;
stages of the same name move the same coordinate (see model/motion.generated_motion).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

from pydantic import AfterValidator, Field, model_validator

from hoseline.io.obstacle_mesh import ObstacleFileError, read_mesh
from hoseline.io.pose_table import PoseTableError, read_pose_table
from hoseline.io.problem_file import (
    Direction,
    Point,
    ProblemFileError,
    _not_negative,
    _Section,
    _validated,
    problem_from_dict,
    read_toml,
)
from hoseline.model import limits
from hoseline.model.motion import BodyMotion, Rotation, Translation, generated_motion
from hoseline.model.sweep import DEFAULT_CLEARANCE, Obstacle, SweepProblem

SWEEP_TABLES = ("bodies", "obstacles", "sweep")


class SweepFileError(ProblemFileError):
    """A sweep file that cannot describe a sweep; the message names the field, the value and the fix."""


def _range(largest: float, unit: str):
    """[from, to]: two finite numbers within +-largest (unit)."""

    def check(value: list[float]) -> list[float]:
        if len(value) != 2 or not all(math.isfinite(v) for v in value):
            raise ValueError("must be [from, to], two finite numbers")
        if not all(abs(v) <= largest for v in value):
            raise ValueError(f"must lie within +-{largest:g} {unit}")
        return value

    return AfterValidator(check)


def _steps(value: int) -> int:
    if not 1 <= value <= limits.STAGE_STEPS:
        raise ValueError(f"must be at least 1 and at most {limits.STAGE_STEPS}")
    return value


class StageSection(_Section):
    """A generated stage of a body's motion: a rotation or a translation."""

    name: str | None = None
    rotate: Annotated[list[float], _range(limits.ANGLE_DEG, "degrees (ten turns)")] | None = None
    translate: Annotated[list[float], _range(limits.COORDINATE_MM, "mm (100 m)")] | None = None
    axis: Direction
    point: Point | None = None
    steps: Annotated[int, AfterValidator(_steps)] = 20

    @model_validator(mode="after")
    def _one_motion(self) -> "StageSection":
        if (self.rotate is None) == (self.translate is None):
            raise ValueError("a stage needs exactly one of rotate = [from, to] (degrees) or translate = [from, to] (mm)")
        if self.rotate is not None and self.point is None:
            raise ValueError("a rotate stage needs point = [x, y, z] (mm), a point on its axis")
        if self.translate is not None and self.point is not None:
            raise ValueError("a translate stage takes no point: remove it (the axis is a direction)")
        return self

    def generator(self) -> Rotation | Translation:
        if self.rotate is not None:
            return Rotation(self.axis, self.point, tuple(self.rotate), self.steps, self.name or "rotation")
        return Translation(self.axis, tuple(self.translate), self.steps, self.name or "translation")


class BodySection(_Section):
    """[[bodies]]: a moving body, by a pose table or by generated stages."""

    name: str
    poses: str | None = None
    stages: list[StageSection] | None = None

    @model_validator(mode="after")
    def _one_source(self) -> "BodySection":
        if (self.poses is None) == (self.stages is None):
            raise ValueError(
                f"body {self.name!r} needs exactly one of poses = \"table.csv\" (a pose table) or stages = [...] "
                "(rotate / translate stages)"
            )
        if self.stages is not None and not self.stages:
            raise ValueError(f"body {self.name!r}: stages is empty; give at least one rotate or translate stage")
        return self


class ObstacleSection(_Section):
    """[[obstacles]]: a mesh file, its required clearance, the body it moves with."""

    name: str | None = None
    file: str
    clearance: Annotated[float, _not_negative("mm", limits.CLEARANCE_MM)] = DEFAULT_CLEARANCE
    body: str | None = None


class SweepSection(_Section):
    """[sweep]: options of the sweep."""

    compare_free_roll: bool = True


class MountBody(_Section):
    """[start] body and [end] body: the body the fitting moves with."""

    body: str


class SweepTables(_Section):
    """The tables a sweep file adds to a problem file."""

    bodies: list[BodySection]
    obstacles: list[ObstacleSection] = Field(default_factory=list)
    sweep: SweepSection = Field(default_factory=SweepSection)
    start: MountBody | None = None
    end: MountBody | None = None


def load_sweep(path: str | Path) -> SweepProblem:
    """Read a sweep file, its pose tables and obstacle meshes (paths relative to the file).

    Raises SweepFileError naming the field, the value and the fix (or the line of a pose
    table), and OSError when the sweep file itself cannot be read.
    """
    path = Path(path)
    return sweep_from_dict(read_toml(path, SweepFileError), source=str(path), base_dir=path.parent)


def sweep_from_dict(data: dict, source: str = "<dict>", base_dir: str | Path | None = None) -> SweepProblem:
    """Validate a parsed sweep file and build the SweepProblem (files relative to base_dir)."""
    base = Path.cwd() if base_dir is None else Path(base_dir)
    problem_part = {key: value for key, value in data.items() if key not in SWEEP_TABLES}
    sweep_part = {key: data[key] for key in SWEEP_TABLES if key in data}
    for role in ("start", "end"):
        table = problem_part.get(role)
        if isinstance(table, dict) and "body" in table:
            rest = {key: value for key, value in table.items() if key != "body"}
            if rest:
                problem_part[role] = rest
            else:  # only the body: the mount itself comes from elsewhere (e.g. [mounts] iges)
                del problem_part[role]
            sweep_part[role] = {"body": table["body"]}
    clip_bodies = contact_bodies = ()
    if isinstance(problem_part.get("clips"), list):  # [[clips]] body = ...
        clip_bodies, problem_part["clips"] = _take_bodies(problem_part["clips"], "clips", source)
    contact = problem_part.get("contact")
    if isinstance(contact, dict) and isinstance(contact.get("obstacles"), list):  # [[contact.obstacles]] body = ...
        contact_bodies, obstacles = _take_bodies(contact["obstacles"], "contact.obstacles", source)
        problem_part["contact"] = dict(contact, obstacles=obstacles)
    if "bodies" not in sweep_part:
        raise SweepFileError(
            f"{source}: missing [[bodies]]: a sweep needs at least one moving body, with poses = \"table.csv\" "
            "or stages = [...]; and [start] or [end] body = its name"
        )
    try:
        problem = problem_from_dict(problem_part, source=source, base_dir=base)
    except SweepFileError:
        raise
    except ProblemFileError as exc:
        raise SweepFileError(str(exc)) from None
    tables = _validated(SweepTables, sweep_part, source, error=SweepFileError)
    motions = tuple(_motion(body, base, source) for body in tables.bodies)
    obstacles = tuple(_obstacle(item, base, source) for item in tables.obstacles)
    try:
        return SweepProblem(
            problem=problem,
            start_body=tables.start.body if tables.start else None,
            end_body=tables.end.body if tables.end else None,
            motions=motions,
            obstacles=obstacles,
            compare_free_roll=tables.sweep.compare_free_roll,
            clip_bodies=clip_bodies if any(body is not None for body in clip_bodies) else (),
            contact_bodies=contact_bodies if any(body is not None for body in contact_bodies) else (),
        )
    except ValueError as exc:
        raise SweepFileError(f"{source}: {exc}") from None


def _take_bodies(tables: list, label: str, source: str) -> tuple[tuple[str | None, ...], list]:
    """(the body of each table (None: fixed), the tables without it): the sweep's part of a [[clips]] or
    [[contact.obstacles]] table (label: its name), which the problem file does not take."""
    bodies = tuple(table.get("body") if isinstance(table, dict) else None for table in tables)
    for index, body in enumerate(bodies):
        if body is not None and not isinstance(body, str):
            raise SweepFileError(f"{source}: {label}[{index}].body = {body!r}: must be the name of a [[bodies]] table")
    return bodies, [{key: value for key, value in table.items() if key != "body"} if isinstance(table, dict) else table
                    for table in tables]


def _motion(body: BodySection, base: Path, source: str) -> BodyMotion:
    """The motion of one [[bodies]] entry."""
    if body.stages is not None:
        try:
            return generated_motion(body.name, [stage.generator() for stage in body.stages])
        except ValueError as exc:
            raise SweepFileError(f"{source}: body {body.name!r}: {exc}") from None
    try:
        return read_pose_table(base / body.poses, body.name)
    except PoseTableError as exc:
        raise SweepFileError(f"{source}: body {body.name!r}: {exc}") from None
    except OSError as exc:
        raise SweepFileError(
            f"{source}: body {body.name!r}: poses = \"{body.poses}\": cannot read {base / body.poses}: {exc.strerror or exc}"
        ) from None


def _obstacle(item: ObstacleSection, base: Path, source: str) -> Obstacle:
    """The Obstacle of one [[obstacles]] entry, its mesh read."""
    file = base / item.file
    name = item.name or Path(item.file).stem
    try:
        vertices, faces = read_mesh(file)
    except ObstacleFileError as exc:
        raise SweepFileError(f"{source}: obstacle {name!r}: {exc}") from None
    except OSError as exc:
        raise SweepFileError(f"{source}: obstacle {name!r}: file = \"{item.file}\": cannot read {file}: {exc.strerror or exc}") from None
    return Obstacle(name, vertices, faces, item.clearance, item.body, source=str(item.file))
