"""What the page may send over the WebSocket, checked before anything is done with it.

    {"type": "set", "seq": 7, "start": {"point": [x, y, z], "quaternion": [w, x, y, z]},
     "end": {...}, "twist": 180.0, "hose": {"length": 330.6, "bending_stiffness": ...,
     "torsion_factor": 25.0, "mass_per_length": 0.1}, "pose": 12,
     "clips": [{"point": [x, y, z], "quaternion": [w, x, y, z]}, ...]}
        a target: every key but type and seq optional.  Fittings: the tip (mm) and the unit
        quaternion (scalar first) turning the world axes onto the fitting frame (d3 along the
        hose; for the end fitting, without the twist).  clips: every clip of the problem, in its
        order, the same way (the point held, mm, and the clip frame, d3 along the hose; a ball
        clip's orientation is not used).  twist: degrees at assembly.  hose: mm,
        N*mm^2, dimensionless, kg/m.  pose: a pose of the open sweep (the fittings follow its
        bodies).  Targets coalesce: only the latest is solved.
    {"type": "place", "seq": 8}     run the placement sequence again from the straight hose
    {"type": "segments", "seq": 9, "segments": 200}
        cut the hose into this many segments and place it again (a discretisation is not continued)
    {"type": "clearance", "seq": 10, "obstacle": 0, "required": 25.4}
        the clearance (mm) required to obstacle number `obstacle` of the session message
    {"type": "undo", "seq": 11}, {"type": "redo", "seq": 12}
        put the session back to before the last edit, or do the last undone edit again (history.py)

edit: optional in every message but undo and redo, the number of the user's gesture that sent it
(a drag from press to release, a value typed); the session before a gesture is kept for undo.

seq: a number the page counts up; each state message says which seq it has reached.
"""

from __future__ import annotations

import json
import math
from typing import Annotated, Literal

import pydantic
from pydantic import AfterValidator, BaseModel, ConfigDict

MAX_MESSAGE_BYTES = 64 * 1024  # a target is a few hundred bytes
MAX_CLIPS = 200  # clips in one target (a problem has a handful)


class MessageError(ValueError):
    """A message the page should not have sent; the text says what is wrong."""


def _finite(values: list[float]) -> list[float]:
    if not all(math.isfinite(v) for v in values):
        raise ValueError("must be finite numbers")
    return values


def _unit_quaternion(values: list[float]) -> list[float]:
    norm = math.sqrt(sum(v * v for v in _finite(values)))
    if not 0.5 < norm < 2.0:
        raise ValueError("must be a unit quaternion [w, x, y, z]")
    return [v / norm for v in values]


Point = Annotated[list[float], pydantic.Field(min_length=3, max_length=3), AfterValidator(_finite)]
Quaternion = Annotated[list[float], pydantic.Field(min_length=4, max_length=4), AfterValidator(_unit_quaternion)]


class _Message(BaseModel):
    model_config = ConfigDict(extra="forbid")


class FittingTarget(_Message):
    """A fitting's tip (mm) and orientation."""

    point: Point
    quaternion: Quaternion


class HoseTarget(_Message):
    """Hose properties from the sliders (None: unchanged)."""

    length: float | None = None
    bending_stiffness: float | None = None
    torsion_factor: float | None = None
    mass_per_length: float | None = None


class Target(_Message):
    """Where the page wants the hose: see the module docstring."""

    type: Literal["set"]
    seq: int
    edit: int | None = None
    start: FittingTarget | None = None
    end: FittingTarget | None = None
    twist: float | None = None
    hose: HoseTarget | None = None
    pose: int | None = None
    clips: Annotated[list[FittingTarget], pydantic.Field(max_length=MAX_CLIPS)] | None = None


class Command(_Message):
    """An action that does not coalesce with others (see the module docstring for each type's fields)."""

    type: Literal["place", "segments", "clearance", "undo", "redo"]
    seq: int
    edit: int | None = None
    segments: int | None = None
    obstacle: int | None = None
    required: float | None = None

    @pydantic.model_validator(mode="after")
    def _fields_of_its_type(self) -> "Command":
        needed = {"place": (), "segments": ("segments",), "clearance": ("obstacle", "required"), "undo": (),
                  "redo": ()}[self.type]
        for name in ("segments", "obstacle", "required"):
            given = getattr(self, name) is not None
            if given != (name in needed):
                raise ValueError(f"{'give' if not given else 'remove'} '{name}' for a '{self.type}' message")
        if self.required is not None and not math.isfinite(self.required):
            raise ValueError("required: must be a finite clearance in mm")
        return self


def parse_message(text: str | bytes) -> Target | Command:
    """The page's message, checked; MessageError says what is wrong."""
    if len(text) > MAX_MESSAGE_BYTES:
        raise MessageError(f"message of {len(text)} bytes, more than {MAX_MESSAGE_BYTES}")
    try:
        data = json.loads(text)
    except ValueError as exc:
        raise MessageError(f"not JSON: {exc}") from None
    except RecursionError:  # the parser recurses once per level of arrays or objects within each other
        raise MessageError("JSON nested too deeply to read (hundreds of levels)") from None
    kind = data.get("type") if isinstance(data, dict) else None
    model = {"set": Target, "place": Command, "segments": Command, "clearance": Command, "undo": Command,
             "redo": Command}.get(kind)
    if model is None:
        raise MessageError(f"unknown message type {kind!r}: expected 'set', 'place', 'segments', 'clearance', "
                           "'undo' or 'redo'")
    try:
        return model.model_validate(data)
    except pydantic.ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(part) for part in first["loc"])
        raise MessageError(f"{kind} message: {where}: {first['msg']}") from None
