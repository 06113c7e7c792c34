"""Mounts from IGES: named points (entity 116) as CATIA and other CAD systems write them.

The thesis convention (Thomas 2004, appendix A) is the default: the user makes four points
A, B, C, D in CAD; the hose leaves B along A->B and leaves D along D->C.  Each fitting is
named by its tip and a second point on its axis, either behind the tip (A behind B) or
ahead of it, on the hose side (C ahead of D).

OpenCASCADE reads the entities (labels, 406 name properties, 124 transformations, the file's
unit).  It sets an unreadable number to zero without a word, and it does not say on which line
a file is damaged, so the record layout and every parameter record are checked here first:
a malformed or truncated file is refused with the line to look at.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from OCP.IFSelect import IFSelect_ReturnStatus
from OCP.IGESControl import IGESControl_Reader

from hoseline.io.occt import quiet
from hoseline.model.limits import COORDINATE_MM, coordinate_within
from hoseline.model.mounts import Mount

POINT_ENTITY = 116
NAME_PROPERTY = (406, 15)
COINCIDENT_MM = 1e-6  # two points closer than this give no fitting axis

_SECTIONS = "SGDPT"
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([EeDd][+-]?\d+)?")
_HOLLERITH = re.compile(r"\s*(\d+)H")


class IgesError(ValueError):
    """An IGES file that cannot give the mount points; the message names the file and the line or labels."""


@dataclass(frozen=True)
class FittingLabels:
    """Labels of one fitting's points in an IGES file.

    tip: the point where the hose centreline starts or ends.
    behind: a point on the fitting axis behind the tip; the hose leaves the tip along behind->tip.
    ahead: a point on the fitting axis ahead of the tip (hose side); the hose leaves the tip along tip->ahead.
    Give exactly one of behind and ahead.
    """

    tip: str
    behind: str | None = None
    ahead: str | None = None

    def __post_init__(self) -> None:
        if (self.behind is None) == (self.ahead is None):
            raise ValueError(
                f"fitting with tip {self.tip!r}: give exactly one of 'behind' (a point behind the tip: the hose "
                "leaves the tip along behind->tip) and 'ahead' (a point on the hose side: along tip->ahead)"
            )

    @property
    def axis(self) -> str:
        """Label of the second point on the fitting axis."""
        return self.behind if self.behind is not None else self.ahead


THESIS_START = FittingLabels(tip="B", behind="A")
THESIS_END = FittingLabels(tip="D", ahead="C")


def mounts_from_iges(
    path: str | Path, start: FittingLabels = THESIS_START, end: FittingLabels = THESIS_END
) -> tuple[Mount, Mount]:
    """The start and end mounts from the named points of an IGES file.

    path: the IGES file.  start, end: which labels make each fitting (default: the thesis'
    A, B, C, D).  Returns (start mount, end mount), points in mm, directions from the
    fitting into the hose.
    Raises IgesError for a damaged file (naming the line), a missing or duplicated label
    (listing the labels found) and coincident tip and axis points.
    """
    points = read_named_points(path)
    return _mount(path, points, start), _mount(path, points, end)


def clip_points_from_iges(path: str | Path, clips: list[FittingLabels | str]) -> list[tuple[np.ndarray, np.ndarray | None]]:
    """Point (mm) and direction (unit, from the start side to the end side) of clips from the named
    points of an IGES file: FittingLabels for a clip that holds the direction (its tip and one more
    point on its axis, as for the fittings), a single label for a ball clip (direction None).
    Raises IgesError as mounts_from_iges does."""
    points = read_named_points(path)
    out: list[tuple[np.ndarray, np.ndarray | None]] = []
    for labels in clips:
        if isinstance(labels, str):
            out.append((_point(path, points, labels), None))
        else:
            mount = _mount(path, points, labels)
            out.append((mount.point, mount.direction))
    return out


def read_named_points(path: str | Path) -> dict[str, list[np.ndarray]]:
    """Every labelled point (entity 116) of an IGES file: label -> coordinates in mm (one entry per point).

    The label is the entity's name property (406 form 15) if it has one, else the 8-character
    label of its directory entry.  Transformation matrices (124) and the file's unit are applied.
    Raises IgesError for a damaged file; OSError when it cannot be read.
    """
    path = Path(path)
    _check_records(path, path.read_bytes())
    quiet()
    reader = IGESControl_Reader()
    if reader.ReadFile(str(path)) != IFSelect_ReturnStatus.IFSelect_RetDone:
        raise IgesError(f"{path}: OpenCASCADE could not read this IGES file")
    model = reader.IGESModel()
    failures = model.GlobalCheck()
    if failures.NbFails():
        raise IgesError(f"{path}: global section (G lines): {failures.CFail(1)}")
    mm_per_unit = model.GlobalSection().UnitValue()
    points: dict[str, list[np.ndarray]] = {}
    for number in range(1, model.NbEntities() + 1):
        entity = model.Entity(number)
        label = _label(entity) if entity.TypeNumber() == POINT_ENTITY else ""
        if label:
            points.setdefault(label, []).append(np.array(entity.TransformedValue().Coord()) * mm_per_unit)
    return points


def _label(entity) -> str:
    """The name property (406 form 15) of an IGES entity if present, else its directory-entry label."""
    properties = entity.Properties()
    while properties.More():
        item = properties.Value()
        if (item.TypeNumber(), item.FormNumber()) == NAME_PROPERTY:
            return item.Value().ToCString().strip()
        properties.Next()
    return entity.ShortLabel().ToCString().strip() if entity.HasShortLabel() else ""


def _mount(path, points: dict[str, list[np.ndarray]], labels: FittingLabels) -> Mount:
    """The mount of one fitting; refuses missing, duplicated and coincident points."""
    tip, axis = (_point(path, points, label) for label in (labels.tip, labels.axis))
    for label, point in ((labels.tip, tip), (labels.axis, axis)):
        if not all(coordinate_within(v) for v in point):
            raise IgesError(
                f"{path}: point {label} at {_coordinates(point)} mm lies outside +-{COORDINATE_MM:g} mm (100 m): "
                "check the coordinates and the unit in the global section"
            )
    distance = float(np.linalg.norm(axis - tip))
    if distance < COINCIDENT_MM:
        raise IgesError(
            f"{path}: points {labels.tip} and {labels.axis} coincide at {_coordinates(tip)} mm "
            f"(distance {distance:.3g} mm): the fitting axis needs two distinct points"
        )
    if labels.behind is not None:
        return Mount.from_points(axis, tip)
    return Mount(point=tip, direction=axis - tip)


def _point(path, points: dict[str, list[np.ndarray]], label: str) -> np.ndarray:
    """The one point with `label`; the error lists the labels that were found."""
    found = points.get(label, [])
    if len(found) == 1:
        return found[0]
    listing = ", ".join(f"{name} (x{len(p)})" if len(p) > 1 else name for name, p in sorted(points.items()))
    listing = listing or "none"
    if not found:
        raise IgesError(f"{path}: no point labelled {label!r}; labelled points found: {listing}")
    places = "; ".join(_coordinates(p) for p in found)
    raise IgesError(
        f"{path}: {len(found)} points are labelled {label!r} ({places} mm): rename all but one in CAD; "
        f"labelled points found: {listing}"
    )


def _coordinates(point: np.ndarray) -> str:
    return "(" + ", ".join(f"{v:g}" for v in point) + ")"


# --- the record layout: 80-column lines, sections S G D P T, consecutive sequence numbers ---


def _check_records(path: Path, data: bytes) -> None:
    """Refuse a file whose fixed-format layout or parameter records are damaged, naming the line."""
    if b"\0" in data:
        raise IgesError(f"{path}: not an IGES text file (binary IGES is not supported)")
    lines = data.decode("latin-1").splitlines()
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines:
        raise IgesError(f"{path}: the file is empty")
    sections: dict[str, list[str]] = {letter: [] for letter in _SECTIONS}
    first_line = {}
    order = 0
    for number, line in enumerate(lines, start=1):
        where = f"{path}: line {number}"
        if len(line) < 73:
            raise IgesError(f"{where}: {len(line)} characters where an IGES record has 80 (truncated or re-wrapped)")
        letter = line[72]
        if letter == "C":
            raise IgesError(f"{where}: compressed IGES is not supported; export uncompressed (fixed) IGES")
        if letter not in _SECTIONS or _SECTIONS.index(letter) < order:
            raise IgesError(f"{where}: column 73 holds {letter!r}, expected the sections S, G, D, P, T in order")
        order = _SECTIONS.index(letter)
        sequence = line[73:80].strip()
        expected = len(sections[letter]) + 1
        if not sequence.isdigit() or int(sequence) != expected:
            raise IgesError(f"{where}: sequence number {sequence!r} in columns 74-80, expected {expected}")
        first_line.setdefault(letter, number)
        sections[letter].append(line)
    if len(sections["T"]) != 1:
        raise IgesError(f"{path}: line {len(lines)}: the file ends without its terminate (T) record: it is truncated")
    counts = _terminate_counts(path, len(lines), sections["T"][0])
    for letter in "SGDP":
        if counts[letter] != len(sections[letter]):
            raise IgesError(
                f"{path}: line {len(lines)}: the terminate record counts {counts[letter]} {letter} lines, "
                f"the file has {len(sections[letter])}: it is truncated or lines were lost"
            )
    if len(sections["D"]) % 2:
        raise IgesError(f"{path}: line {first_line['D'] + len(sections['D']) - 1}: odd number of directory (D) lines")
    delimiter, end = _delimiters("".join(line[:72] for line in sections["G"]))
    for index in range(0, len(sections["D"]), 2):
        _check_entity(path, sections, first_line, index + 1, delimiter, end)


def _terminate_counts(path: Path, line_number: int, line: str) -> dict[str, int]:
    """The S, G, D, P line counts of the terminate record."""
    counts = {}
    for position, letter in enumerate("SGDP"):
        field = line[8 * position : 8 * position + 8]
        if field[0] != letter or not field[1:].strip().isdigit():
            raise IgesError(f"{path}: line {line_number}: malformed terminate record {line[:32]!r}")
        counts[letter] = int(field[1:])
    return counts


def _delimiters(global_text: str) -> tuple[str, str]:
    """The parameter and record delimiters declared at the start of the global section (default ',' and ';')."""
    delimiter = global_text[2] if global_text.startswith("1H") else ","
    rest = global_text[4:] if global_text.startswith("1H") else global_text[1:]
    end = rest[2] if rest.startswith("1H") else ";"
    return delimiter, end


def _check_entity(path: Path, sections, first_line, sequence: int, delimiter: str, end: str) -> None:
    """Check one entity: its parameter lines point back to it and its record is a list of IGES values."""
    entry, second = sections["D"][sequence - 1], sections["D"][sequence]
    entry_line = first_line["D"] + sequence - 1
    fields = entry[:8], entry[8:16], second[24:32]
    if not all(field.strip().lstrip("-").isdigit() for field in fields):
        raise IgesError(f"{path}: line {entry_line}: malformed directory entry {entry[:32]!r}")
    kind, pointer, count = (int(field) for field in fields)
    records = sections["P"][pointer - 1 : pointer - 1 + count] if pointer >= 1 else []
    if count < 1 or len(records) != count:
        raise IgesError(f"{path}: line {entry_line}: entity {kind} points at parameter lines the file does not have")
    first_record = first_line["P"] + pointer - 1
    for offset, record in enumerate(records):
        back_pointer = record[64:72].strip()
        if not back_pointer.isdigit() or int(back_pointer) != sequence:
            raise IgesError(
                f"{path}: line {first_record + offset}: parameter line does not belong to "
                f"the entity {kind} of directory line {entry_line}"
            )
    try:
        values = _split_parameters("".join(record[:64] for record in records), delimiter, end)
    except _BadParameter as bad:
        line = first_record + min(bad.position // 64, count - 1)
        raise IgesError(f"{path}: line {line}: {bad.reason} (entity {kind}, directory line {entry_line})") from None
    if not values[0].isdigit() or int(values[0]) != kind:
        raise IgesError(
            f"{path}: line {first_record}: the parameters start with {values[0]!r}, "
            f"the directory line {entry_line} says entity {kind}"
        )


class _BadParameter(Exception):
    """A parameter record that is not a list of IGES values: where (character position) and why."""

    def __init__(self, position: int, reason: str):
        super().__init__(reason)
        self.position, self.reason = position, reason


def _split_parameters(text: str, delimiter: str, end: str) -> list[str]:
    """The values of one parameter record: numbers, pointers, empty (default) values and nH strings."""
    values, position = [], 0
    while True:
        hollerith = _HOLLERITH.match(text, position)
        if hollerith:  # nHxxx: exactly n characters, which may include the delimiters
            stop = hollerith.end() + int(hollerith.group(1))
        else:
            stops = [i for i in (text.find(delimiter, position), text.find(end, position)) if i >= 0]
            if not stops:
                raise _BadParameter(len(text) - 1, f"the parameters do not end with {end!r}")
            stop = min(stops)
        token = text[position:stop].strip()
        if not hollerith and token and not _NUMBER.fullmatch(token):
            raise _BadParameter(stop - 1, f"{token!r} is not a number")
        values.append(token)
        following = text[stop : stop + 1]
        if following == end:
            return values
        if following != delimiter:
            raise _BadParameter(stop, f"expected {delimiter!r} or {end!r} after {token!r}")
        position = stop + 1
