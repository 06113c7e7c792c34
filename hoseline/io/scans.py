"""Read point clouds of a scanned hose surface: PLY, XYZ/CSV/TXT and the vertices of STL.

Points are taken as they are, in mm, in the coordinate system of the mounts (the
scanner's reference markers put them there).  Messages for bad files name the file, the
line (or the element) and the fix.  write_ply writes a cloud (binary PLY) atomically.

Scans of millions of points: binary PLY vertices are read straight into a structured array
(the faces after them are not read); text and ascii PLY are parsed by NumPy's C reader
(np.loadtxt, streaming the file), and only when it refuses a file is it read again line by
line, to name the line that is wrong.
"""

from __future__ import annotations

import re
import struct
import warnings
from pathlib import Path

import numpy as np

from hoseline.io.atomic import write_bytes
from hoseline.model.limits import COORDINATE_MM

FORMATS = {".ply": "PLY", ".xyz": "text", ".csv": "text", ".txt": "text", ".asc": "text", ".pts": "text", ".stl": "STL"}
PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2", "ushort": "u2",
    "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4",
    "double": "f8", "float64": "f8",
}
MIN_POINTS = 20
PLY_HEADER_BYTES = 1 << 20


class ScanFileError(ValueError):
    """A scan file that cannot be read as a point cloud; the message names the place and the fix."""


def read_scan(path: str | Path, min_points: int = MIN_POINTS) -> np.ndarray:
    """Points (n, 3) in mm from a PLY, XYZ/CSV/TXT or STL file (format by the file's extension).

    min_points: fewer points are refused (1 for a file of reference points).
    Non-finite points and coordinates beyond +-COORDINATE_MM (model/limits.py: a unit mistake or a
    damaged file, not a hose) are refused; duplicate STL vertices are merged.
    Raises ScanFileError for content that is not a point cloud, OSError when unreadable.
    """
    path = Path(path)
    kind = FORMATS.get(path.suffix.lower())
    if kind is None:
        raise ScanFileError(
            f"{path}: unknown scan format '{path.suffix}': use .ply, .stl or a text file (.xyz, .csv, .txt, .asc, .pts)"
        )
    reader = {"PLY": _read_ply, "STL": _read_stl, "text": _read_text}[kind]
    points = reader(path)
    if points.shape[0] < min_points:
        raise ScanFileError(f"{path}: only {points.shape[0]} points; at least {min_points} are needed")
    if not np.isfinite(points).all():
        bad = np.flatnonzero(~np.all(np.isfinite(points), axis=1))
        raise ScanFileError(f"{path}: point {bad[0]} is not finite ({points[bad[0]].tolist()}); remove it from the scan")
    outside = np.flatnonzero(np.any(np.abs(points) > COORDINATE_MM, axis=1))
    if outside.size:
        raise ScanFileError(
            f"{path}: point {outside[0]} ({points[outside[0]].tolist()}) lies beyond +-{COORDINATE_MM:g} mm "
            f"({outside.size} such points): give the scan in mm, in the coordinate system of the mounts"
        )
    return points


def write_ply(path: str | Path, points: np.ndarray) -> Path:
    """Write points (n, 3), mm, as a binary little-endian PLY with float64 x, y, z (atomically)."""
    points = np.ascontiguousarray(points, dtype="<f8")
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment hoseline point cloud, mm\n"
        f"element vertex {points.shape[0]}\nproperty double x\nproperty double y\nproperty double z\nend_header\n"
    )
    return write_bytes(path, header.encode("ascii") + points.tobytes())


def _read_text(path: Path) -> np.ndarray:
    """x y z per line (spaces, tabs, commas or semicolons); one header line and # comments are skipped."""
    with open(path, "rb") as file:
        head = file.read(4096).split(b"\n")
    skip = 0
    for number, line in enumerate(head[:2], start=1):  # a header such as "x,y,z" on the first two lines
        fields = _fields(line.decode("utf-8-sig", errors="replace"))
        if fields and _numbers(fields[:3]) is not None:
            break
        if fields:
            skip = number
    sample = b"".join(line.split(b"#", 1)[0] for line in head[skip:])  # the separator of the first rows
    delimiter = "," if b"," in sample else ";" if b";" in sample else None  # None: any whitespace
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data": read_scan counts the points
            return np.loadtxt(path, delimiter=delimiter, skiprows=skip, usecols=(0, 1, 2), comments="#", ndmin=2,
                              encoding="utf-8-sig")
    except (ValueError, UnicodeDecodeError):  # mixed separators or a bad line: read again line by line
        return _read_text_lines(path.read_bytes(), str(path))


def _fields(line: str) -> list[str]:
    """The fields of a text line without its # comment, split at spaces, tabs, commas and semicolons."""
    return [f for f in re.split(r"[\s,;]+", line.split("#", 1)[0].strip()) if f]


def _numbers(fields: list[str]) -> list[float] | None:
    """The fields as floats, or None if one is not a number."""
    try:
        return [float(f) for f in fields]
    except ValueError:
        return None


def _read_text_lines(data: bytes, source: str) -> np.ndarray:
    """_read_text one line at a time (slow): names the first line that is not x y z."""
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise ScanFileError(f"{source}: not a text file; save the points as UTF-8 text with x, y, z per line") from None
    rows = []
    for number, line in enumerate(text.splitlines(), start=1):
        fields = _fields(line)
        if not fields:
            continue
        values = _numbers(fields[:3])
        if values is None:
            if not rows and number <= 2:  # a header such as "x,y,z"
                continue
            raise ScanFileError(f"{source}, line {number}: '{line.split('#', 1)[0].strip()[:60]}' is not three "
                                "numbers x y z (mm)")
        if len(values) < 3:
            raise ScanFileError(f"{source}, line {number}: '{line.split('#', 1)[0].strip()[:60]}' has {len(values)} "
                                "numbers; give x y z (mm)")
        rows.append(values)
    return np.array(rows, dtype=float).reshape(-1, 3)


def _ply_header(path: Path) -> bytes:
    """The start of a PLY file: its first MiB, which holds the header of any point cloud export."""
    with open(path, "rb") as file:
        return file.read(PLY_HEADER_BYTES)


def _read_ply(path: Path) -> np.ndarray:
    """The x, y, z properties of the vertex element (ascii, binary little or big endian)."""
    source = str(path)
    data = _ply_header(path)
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise ScanFileError(f"{source}: not a PLY file (it must start with 'ply' and have an 'end_header' line)")
    body_start = data.find(b"\n", end) + 1 or len(data)
    header = data[:end].decode("ascii", errors="replace").splitlines()
    fmt, elements = None, []  # elements: [name, count, [(property, dtype or None for lists)]]
    for number, line in enumerate(header, start=1):
        words = line.split()
        if not words or words[0] in ("comment", "obj_info", "ply"):
            continue
        if len(words) < {"format": 2, "element": 3, "property": 3}.get(words[0], 1):
            raise ScanFileError(f"{source}, header line {number}: '{line.strip()}' is incomplete")
        if words[0] == "format":
            fmt = words[1]
        elif words[0] == "element":
            if not words[2].isdigit():
                raise ScanFileError(f"{source}, header line {number}: '{line.strip()}': the count must be a whole number")
            elements.append([words[1], int(words[2]), []])
        elif words[0] == "property" and elements:
            if words[1] == "list":
                elements[-1][2].append((words[-1], None))
            elif words[1] in PLY_TYPES:
                elements[-1][2].append((words[2], PLY_TYPES[words[1]]))
            else:
                raise ScanFileError(f"{source}, header line {number}: unknown property type '{words[1]}'")
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise ScanFileError(f"{source}: PLY format '{fmt}' is not ascii, binary_little_endian or binary_big_endian")
    if not elements or elements[0][0] != "vertex":
        raise ScanFileError(f"{source}: the first PLY element must be 'vertex'; export the point cloud with vertices first")
    _, count, properties = elements[0]
    names = [name for name, _ in properties]
    if not {"x", "y", "z"} <= set(names):
        raise ScanFileError(f"{source}: the PLY vertices have no x, y, z properties (found {', '.join(names)})")
    if any(dtype is None for _, dtype in properties):
        raise ScanFileError(f"{source}: list properties on PLY vertices are not supported; export x, y, z only")
    if fmt == "ascii":
        header_lines = data[:body_start].count(b"\n")
        try:
            points = np.loadtxt(path, skiprows=header_lines, max_rows=count, usecols=[names.index(a) for a in "xyz"],
                                comments=None, ndmin=2, encoding="latin-1")
        except ValueError:
            points = None
        if points is None or points.shape[0] != count:  # read again line by line to name the line
            return _read_ply_ascii_lines(path.read_bytes()[body_start:], source, count, names, header_lines + 1)
        return points
    order = "<" if fmt == "binary_little_endian" else ">"
    dtype = np.dtype([(name, order + code) for name, code in properties])
    if path.stat().st_size - body_start < dtype.itemsize * count:
        raise ScanFileError(f"{source}: the header announces {count} vertices; the file is too short for them")
    table = np.fromfile(path, dtype=dtype, count=count, offset=body_start)
    points = np.empty((count, 3))
    for axis, name in enumerate("xyz"):
        points[:, axis] = table[name]
    return points


def _read_ply_ascii_lines(body: bytes, source: str, count: int, names: list[str], first_line: int) -> np.ndarray:
    """The x, y, z of `count` ascii PLY vertex lines, one at a time (slow): names the first bad line.

    body: the file after the header; first_line: the body's first line number in the file.
    """
    lines = body.decode("ascii", errors="replace").split("\n")[:count]
    if len(lines) < count or (count and not lines[-1].strip()):
        raise ScanFileError(f"{source}: the header announces {count} vertices; the file has fewer lines")
    table = np.empty((count, len(names)))
    for index, line in enumerate(lines):
        row = _numbers(line.split()[: len(names)]) or []
        if len(row) != len(names):
            raise ScanFileError(f"{source}, line {first_line + index}: '{line.strip()[:60]}' is not "
                                f"{len(names)} numbers ({', '.join(names)})")
        table[index] = row
    return table[:, [names.index(a) for a in "xyz"]]


def _read_stl(path: Path) -> np.ndarray:
    """The distinct vertices of an ASCII or binary STL."""
    data, source = path.read_bytes(), str(path)
    if len(data) >= 84:
        triangles = struct.unpack("<I", data[80:84])[0]
        if len(data) == 84 + 50 * triangles:
            record = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
            table = np.frombuffer(data, dtype=record, count=triangles, offset=84)
            return np.unique(table["vertices"].reshape(-1, 3).astype(float), axis=0)
    text = data.decode("ascii", errors="replace")
    if not text.lstrip().startswith("solid"):
        raise ScanFileError(f"{source}: neither a binary STL (size does not match its triangle count) nor an ASCII STL")
    found = re.findall(r"vertex\s+(\S+)\s+(\S+)\s+(\S+)", text)
    try:
        vertices = np.array(found, dtype=float).reshape(-1, 3)
    except ValueError:
        raise ScanFileError(f"{source}: an STL 'vertex' line does not hold three numbers") from None
    return np.unique(vertices, axis=0)
