"""Fuzzing the command line: inputs made by mutating valid files, random feasible problems, and the oracle.

Shared by tests/test_fuzz_cli.py (a short run in `make test`) and bench/fuzz.py (the long campaign).

Each kind of input starts from valid files and runs one command in-process:

    problem         the thesis problem file (cases.THESIS_TOML, also with a clip), mutated -> hoseline solve
    iges            a problem with [mounts] from the thesis IGES file, the IGES mutated -> hoseline solve
    feasible        a random problem within the documented ranges, length > mount distance -> hoseline solve
    sweep           a sweep file with a pose table and a strut mesh, the TOML mutated -> hoseline sweep
    poses           the same sweep, its pose table mutated                          -> hoseline sweep
    mesh            the same sweep, its obstacle mesh (STL, OBJ or PLY) mutated      -> hoseline sweep
    feasible_sweep  a random hose (up to 90 m long) and a random motion within reach -> hoseline sweep
    cloud           a problem and a synthetic scan (text or PLY), the scan mutated   -> hoseline compare
    contact         a random problem with [contact]: self-contact on or off and up to three planes, spheres,
                    cylinders and boxes across its free shape or its straight start (clear of it, touching it
                    or through it; some with a hose_side), or near the hose;
                    or the thesis problem with a [contact] table, mutated              -> hoseline solve

The oracle (run_input) says what happened: exit 0, 2, 3 or 4 with nothing wrong, or one of
FAILURES: an exception other than SystemExit (a traceback), another exit code, files left
behind after a failure, an error without an "error:" line, a refused feasible input, a refused
contact layout whose message names no obstacle (nor the self-contact) or says nothing to change, or an
exit-0 result that is not finite, converged, stable and of exact length, or (with contact) enters an
obstacle or itself (a smallest gap below 0).  Units: mm.
"""

from __future__ import annotations

import json
import math
import re
import shutil
import signal
import traceback
from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

import numpy as np
from cases import THESIS_TOML
from hypothesis import strategies as st
from typer.testing import CliRunner

from hoseline import cli
from hoseline.procedures.contact.continuation import CONTACT_TOLERANCE

KINDS = ("problem", "iges", "feasible", "sweep", "poses", "mesh", "feasible_sweep", "cloud", "contact")
FAILURES = ("traceback", "hang", "exit_code", "partial_output", "unclear_error", "refused_valid", "bad_result")
TIMEOUT_S = 60  # a run longer than this is a hang
# a contact placement's refusal names an obstacle or the self-contact, and one of these says what to change
SELF_CONTACT = re.compile(r"\bitself\b|self-contact|'self'", re.IGNORECASE)
FIXES = ("move", "give", "remove", "shorten", "lengthen", "try", "choose", "use ", "change", "leave", "add")

IGES_FILE = Path(__file__).parent.parent / "hoseline" / "data" / "mounts_thesis_appendix_a.igs"
SWEEP_FILES = ("report.html", "view.png", "curves.png", "envelope.stl", "poses.csv", "shapes.csv", "sweep.json")

# numbers and values a mutation puts where a number was: extremes, non-finite, wrong types
EXTREMES = (
    "0", "-0.0", "1", "-1", "3", "4", "10001", "2000", "-2000", "1e5", "100001", "1e15", "-1e15", "1e300", "1e308",
    "-1e308", "1e-300", "5e-324", "nan", "inf", "-inf", "1e999", "99999999999999999999999", "0x10", "330.6",
    '"text"', "true", "[]", "[1, 2]", "[0, 0, 0]", "[1e308, 1e308, 1e308]", "[nan, 0, 0]", "{}", "",
)
GARBAGE = ("[hose]", "[[bodies]]", "= 1", "length =", "x", "\x00\x01", "\ufeff", "é", "#", ",,,,", "solid", "endsolid",
           "facet normal 0 0 0", "vertex 1e308 0 0", "element vertex 99999999999", "end_header", "v 1 2", "f 1 2 3",
           "f 1 99 100000", "nan nan nan", "1 2 3", "1e400 0 0", '"', "[", "]", "{", "}", "a = [", "'''")
NUMBER = re.compile(r"(?<![\w.])[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?(?![\w.])")


@dataclass
class FuzzInput:
    """One generated input: the files of a fresh folder and the command line that reads them.

    kind: one of KINDS.  files: name -> content.  args: the command line; an argument that
    names one of `files` becomes its path, "OUT" the output folder.  out: the output
    folder's name in the fresh folder (may be too long, or under a file).  obstacles: the names
    of the contact obstacles of a problem whose placement without them succeeds: a solver failure
    must then name one of them (or the hose's self-contact) and say what to change.
    """

    kind: str
    files: dict[str, bytes]
    args: list[str]
    out: str = "out"
    feasible: bool = False
    obstacles: tuple[str, ...] = ()


@dataclass
class Outcome:
    """What one input did: its exit code and, if something was wrong, which FAILURE and the detail."""

    kind: str
    exit_code: int | None
    failure: str | None = None
    detail: str = ""
    output: str = ""
    seconds: float = 0.0
    notes: list[str] = field(default_factory=list)


# --- mutations of text ---


@st.composite
def mutated(draw, data: bytes, iges: bool = False) -> bytes:
    """`data` after one to three mutations: lines deleted, duplicated, swapped, garbled or inserted, numbers
    replaced by extremes or scaled, keys swapped, bytes inserted, the file truncated."""
    for _ in range(draw(st.integers(1, 3))):
        operations = ["delete", "duplicate", "swap", "garble", "insert", "number", "scale", "keys", "bytes", "truncate"]
        if iges:
            operations += ["iges_number"] * 4
        data = _mutate(draw, draw(st.sampled_from(operations)), data)
    return data


def _mutate(draw, operation: str, data: bytes) -> bytes:
    lines = data.split(b"\n")
    line = draw(st.integers(0, max(0, len(lines) - 1)))
    if operation == "delete":
        del lines[line]
    elif operation == "duplicate":
        lines.insert(line, lines[line])
    elif operation == "swap":
        other = draw(st.integers(0, len(lines) - 1))
        lines[line], lines[other] = lines[other], lines[line]
    elif operation in ("garble", "insert"):
        text = draw(st.one_of(st.sampled_from(GARBAGE), st.text(max_size=40))).encode("utf-8", "surrogatepass")
        if operation == "garble":
            lines[line] = text
        else:
            lines.insert(line, text)
    elif operation in ("number", "scale", "iges_number"):
        return _replace_number(draw, operation, data)
    elif operation == "keys":
        keyed = [i for i, text in enumerate(lines) if b"=" in text]
        if len(keyed) >= 2:
            a, b = draw(st.sampled_from(keyed)), draw(st.sampled_from(keyed))
            (key_a, _, value_a), (key_b, _, value_b) = lines[a].partition(b"="), lines[b].partition(b"=")
            lines[a], lines[b] = key_b + b"=" + value_a, key_a + b"=" + value_b
    elif operation == "bytes":
        at = draw(st.integers(0, len(data)))
        return data[:at] + draw(st.binary(min_size=1, max_size=8)) + data[at:]
    elif operation == "truncate":
        return data[: draw(st.integers(0, len(data)))]
    return b"\n".join(lines)


def _replace_number(draw, operation: str, data: bytes) -> bytes:
    """One number of the text replaced by an extreme (or scaled); for IGES, in place within the 80 columns."""
    text = data.decode("latin-1")
    if operation == "iges_number":
        spans = [m.span() for m in NUMBER.finditer(text) if _in_parameter_data(text, m.start())]
    else:
        spans = [m.span() for m in NUMBER.finditer(text)]
    if not spans:
        return data
    start, end = draw(st.sampled_from(spans))
    if operation == "scale":
        value = float(text[start:end]) if _is_float(text[start:end]) else 1.0
        factor = draw(st.sampled_from((-1.0, 0.0, 1e-9, 0.5, 1.5, 10.0, 1e3, 1e6, 1e12)))
        new = repr(value * factor)
    elif operation == "iges_number":
        new = draw(st.sampled_from(("0", "1E308", "-1E308", "1E999", "1.0D5", "1E15", "-13.0", "2000.0", "1E5",
                                    "100001.0", "7", "1.E-300", "1E400")))
        width = end - start
        line_start = text.rfind("\n", 0, start) + 1
        column = start - line_start
        room = 64 - column  # the parameter data of a P line ends in column 64
        rest_of_data = text[end : line_start + 64].rstrip(" ")
        if len(new) + len(rest_of_data) > room:
            new = new[: max(1, width)]
        padded = new + rest_of_data
        padded = padded.ljust(64 - column)
        return (text[:start] + padded + text[line_start + 64 :]).encode("latin-1")
    else:
        new = draw(st.sampled_from(EXTREMES))
    return (text[:start] + new + text[end:]).encode("latin-1")


def _in_parameter_data(text: str, position: int) -> bool:
    """Whether `position` lies in columns 1-64 of a P (parameter) line of an IGES file."""
    line_start = text.rfind("\n", 0, position) + 1
    line_end = text.find("\n", position)
    line = text[line_start : line_end if line_end >= 0 else len(text)]
    return len(line) >= 73 and line[72] == "P" and position - line_start < 64


def _is_float(text: str) -> bool:
    try:
        return math.isfinite(float(text))
    except ValueError:
        return False


# --- the valid files the mutations start from ---

THESIS_PROBLEM = THESIS_TOML.encode()
# the same with a clip holding the middle station (station 5 of 10) off the straight line
THESIS_WITH_CLIP = (THESIS_TOML + '\n[[clips]]\ntype = "ball"\narc_length = 165.3\npoint = [-93.0, 50.0, -11.25]\n').encode()

IGES_PROBLEM = b"""name = "brake hose from CAD"
[mounts]
iges = "mounts.igs"
[hose]
length = 330.6
outer_diameter = 10.1
bending_stiffness = 149563.0
torsion_factor = 25.0
segments = 8
[end]
twist = 180.0
"""

SWEEP_TOML = THESIS_TOML.replace("[end]\n", '[end]\nbody = "knuckle"\n') + """
[[bodies]]
name = "knuckle"
poses = "knuckle.csv"

[[obstacles]]
file = "strut.{ext}"
clearance = 20.0

[sweep]
compare_free_roll = false
"""

STAGES_TOML = THESIS_TOML.replace("[end]\n", '[end]\nbody = "knuckle"\n') + """
[[bodies]]
name = "knuckle"
stages = [
  { name = "steer", rotate = [0.0, 10.0], axis = [0, 0, 1], point = [-185, -7, 0], steps = 2 },
  { name = "jounce", translate = [0.0, 10.0], axis = [0, 0, 1], steps = 2 },
]
"""

KNUCKLE_CSV = b"jounce [mm], x, y, z, qw, qx, qy, qz\n0, 0, 0, 0, 1, 0, 0, 0\n10, 0, 0, 10, 1, 0, 0, 0\n20, 0, 0, 20, 1, 0, 0, 0\n"

CLOUD_PROBLEM_SEGMENTS = 12


@cache
def strut_mesh(ext: str) -> bytes:
    """The demo's strut as a coarse cylinder (12 facets round), as an ASCII STL, OBJ or PLY file."""
    import trimesh

    mesh = trimesh.creation.cylinder(radius=25.0, height=300.0, sections=12)
    mesh.apply_translation([-60.0, 175.0, 0.0])
    exported = mesh.export(file_type=ext, **({"encoding": "ascii"} if ext in ("ply",) else {}))
    return exported if isinstance(exported, bytes) else exported.encode()


@cache
def cloud_files() -> tuple[bytes, bytes, bytes]:
    """(problem file, scan as text x y z, scan as ASCII PLY): the weighted thesis hose and a sparse synthetic scan."""
    from validation_cases import brake_hose

    from hoseline import solve
    from hoseline.io.problem_file import problem_to_toml
    from hoseline.procedures.scans.synthetic_scan import ScanDefects, synthetic_scan

    truth = solve(brake_hose(segments=24, twist=0.0))
    points = synthetic_scan(truth.s, truth.centerline, 5.05, ScanDefects(density=0.4, noise=0.1), seed=3)
    text = "x y z\n" + "\n".join(f"{x:.4f} {y:.4f} {z:.4f}" for x, y, z in points) + "\n"
    ply = (f"ply\nformat ascii 1.0\nelement vertex {len(points)}\nproperty float x\nproperty float y\n"
           f"property float z\nend_header\n") + "\n".join(f"{x:.4f} {y:.4f} {z:.4f}" for x, y, z in points) + "\n"
    problem = problem_to_toml(brake_hose(segments=CLOUD_PROBLEM_SEGMENTS, twist=0.0))
    return problem.encode(), text.encode(), ply.encode()


# --- strategies, one per kind ---

OUT_NAMES = ("out", "out", "out", "out", "out", "out", "nested/deeper/out", "x" * 300, "INPUT/inner")


def out_names():
    """Mostly a plain output folder; sometimes nested, too long for the file system, or under a file."""
    return st.sampled_from(OUT_NAMES)


@st.composite
def problem_inputs(draw) -> FuzzInput:
    base = draw(st.sampled_from((THESIS_PROBLEM, THESIS_PROBLEM, THESIS_WITH_CLIP)))
    return FuzzInput("problem", {"problem.toml": draw(mutated(base))}, ["solve", "problem.toml", "-o", "OUT", "-q"],
                     draw(out_names()))


@st.composite
def iges_inputs(draw) -> FuzzInput:
    iges = IGES_FILE.read_bytes()
    problem = IGES_PROBLEM
    if draw(st.booleans()):
        iges = draw(mutated(iges, iges=True))
    else:
        problem = draw(mutated(IGES_PROBLEM))
    return FuzzInput("iges", {"problem.toml": problem, "mounts.igs": iges}, ["solve", "problem.toml", "-o", "OUT", "-q"])


def _log_uniform(low: float, high: float):
    return st.floats(math.log10(low), math.log10(high)).map(lambda e: 10.0**e)


def _unit_vectors():
    return st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda v: math.hypot(*v) > 0.1)


@st.composite
def feasible_problem(draw, largest_length: float = 9e4, largest_segments: int = 16) -> dict:
    """A random problem within the documented ranges whose hose is longer than the mount distance."""
    length = draw(_log_uniform(1.0, largest_length))
    diameter = min(2000.0, max(0.1, length * draw(_log_uniform(1e-4, 0.25))))
    diameter = min(diameter, length / 4.0)
    section = math.pi * diameter**4 / 64.0  # mm^4: EI stays a sensible modulus of it (limits.EFFECTIVE_MODULUS_NMM2)
    bending = draw(_log_uniform(max(1e-3, 1e-6 * section) * (1.0 + 1e-9), min(1e12, 1e6 * section) * (1.0 - 1e-9)))
    direction = np.array(draw(_unit_vectors()))
    start = np.array(draw(st.tuples(*[st.floats(-1000.0, 1000.0)] * 3)))
    end = start + draw(st.floats(0.0, 0.98)) * length * direction / np.linalg.norm(direction)
    hose = {
        "length": length, "outer_diameter": diameter, "bending_stiffness": bending,
        # GJ = factor EI / 1.5 stays within the stiffness range too (with room for the rounding of factor * EI / 1.5)
        "torsion_factor": draw(_log_uniform(max(1e-3, 1.5e-3 / bending * (1.0 + 1e-9)),
                                            min(1e3, 1.5e12 / bending * (1.0 - 1e-9)))),
        "segments": draw(st.integers(4, largest_segments)),
        "mass_per_length": draw(st.one_of(st.just(0.0), _log_uniform(1e-3, 1e3))),
    }
    gravity = [0.0, 0.0, 0.0]
    if hose["mass_per_length"] > 0.0 and draw(st.booleans()):
        unit = np.array(draw(_unit_vectors()))
        gravity = list(draw(st.floats(0.1, 99.0)) * unit / np.linalg.norm(unit))
    return {
        "hose": hose,
        "start": {"point": list(start), "direction": list(draw(_unit_vectors()))},
        "end": {"point": list(end), "direction": list(draw(_unit_vectors())),
                "twist": draw(st.floats(-3600.0, 3600.0))},
        "environment": {"gravity": gravity},
    }


def toml_text(data: dict, extra: str = "") -> bytes:
    """A problem dict (as feasible_problem gives) as TOML, numbers written exactly; `extra` appended."""
    lines = []
    for table, values in data.items():
        lines.append(f"[{table}]")
        for key, value in values.items():
            if isinstance(value, list):
                value = "[" + ", ".join(repr(float(v)) for v in value) + "]"
            else:
                value = repr(value) if isinstance(value, int) else repr(float(value))
            lines.append(f"{key} = {value}")
    return ("\n".join(lines) + "\n" + extra).encode()


@st.composite
def feasible_inputs(draw) -> FuzzInput:
    return FuzzInput("feasible", {"problem.toml": toml_text(draw(feasible_problem()))},
                     ["solve", "problem.toml", "-o", "OUT", "-q"], feasible=True)


@st.composite
def sweep_inputs(draw) -> FuzzInput:
    ext = draw(st.sampled_from(("stl", "obj", "ply")))
    text = draw(st.sampled_from((SWEEP_TOML, STAGES_TOML))).replace("{ext}", ext).encode()
    files = {"sweep.toml": draw(mutated(text)), "knuckle.csv": KNUCKLE_CSV, f"strut.{ext}": strut_mesh(ext)}
    return FuzzInput("sweep", files, ["sweep", "sweep.toml", "-o", "OUT", "-q"], draw(out_names()))


@st.composite
def pose_inputs(draw) -> FuzzInput:
    files = {"sweep.toml": SWEEP_TOML.replace("{ext}", "stl").encode(), "knuckle.csv": draw(mutated(KNUCKLE_CSV)),
             "strut.stl": strut_mesh("stl")}
    return FuzzInput("poses", files, ["sweep", "sweep.toml", "-o", "OUT", "-q"])


@st.composite
def mesh_inputs(draw) -> FuzzInput:
    ext = draw(st.sampled_from(("stl", "obj", "ply")))
    files = {"sweep.toml": SWEEP_TOML.replace("{ext}", ext).encode(), "knuckle.csv": KNUCKLE_CSV,
             f"strut.{ext}": draw(mutated(strut_mesh(ext)))}
    return FuzzInput("mesh", files, ["sweep", "sweep.toml", "-o", "OUT", "-q"])


@st.composite
def feasible_sweep_inputs(draw) -> FuzzInput:
    """A random hose (large layouts included) moved by a small translation of its end mount, within reach."""
    data = draw(feasible_problem(largest_length=9e4, largest_segments=10))
    length = data["hose"]["length"]
    start, end = np.array(data["start"]["point"]), np.array(data["end"]["point"])
    axis = np.array(draw(_unit_vectors()))
    axis /= np.linalg.norm(axis)
    # keep every pose within reach: the end moves at most a fraction of the slack, never past 0.99 L
    slack = 0.99 * length - np.linalg.norm(end - start)
    travel = float(draw(st.floats(0.0, 1.0)) * max(slack, 0.0))
    data["end"]["body"] = "moving"
    stage = (f'[[bodies]]\nname = "moving"\nstages = [{{ name = "shift", translate = [0.0, {travel!r}], '
             f'axis = [{", ".join(repr(float(v)) for v in axis)}], steps = {draw(st.integers(1, 3))} }}]\n'
             f"[sweep]\ncompare_free_roll = {'true' if draw(st.booleans()) else 'false'}\n")
    body = data["end"].pop("body")
    text = toml_text(data).decode().replace("[end]\n", f'[end]\nbody = "{body}"\n') + stage
    return FuzzInput("feasible_sweep", {"sweep.toml": text.encode()}, ["sweep", "sweep.toml", "-o", "OUT", "-q"],
                     feasible=True)


@st.composite
def cloud_inputs(draw) -> FuzzInput:
    problem, text, ply = cloud_files()
    name, content = draw(st.sampled_from((("scan.xyz", text), ("scan.ply", ply))))
    return FuzzInput("cloud", {"problem.toml": problem, name: draw(mutated(content))},
                     ["compare", "problem.toml", name, "-o", "OUT", "-q"])


THESIS_WITH_CONTACT = (THESIS_TOML + """
[contact]
self = true
[[contact.obstacles]]
kind = "plane"
point = [0.0, 0.0, -40.0]
normal = [0.0, 0.0, 1.0]
[[contact.obstacles]]
kind = "box"
center = [-90.0, 60.0, -11.25]
size = [20.0, 20.0, 20.0]
""").encode()


def _numbers(values) -> str:
    return "[" + ", ".join(repr(float(x)) for x in values) + "]"


def _across(direction: np.ndarray, other) -> np.ndarray:
    """A unit vector perpendicular to the unit `direction`, towards `other` (any vector not along it)."""
    across = np.cross(direction, np.asarray(other, dtype=float))
    if np.linalg.norm(across) < 1e-6:
        across = np.cross(direction, np.eye(3)[int(np.argmin(np.abs(direction)))])
    return across / np.linalg.norm(across)


def _free_centerline(data: dict) -> np.ndarray | None:
    """The stations (mm) of the problem placed without contact, None if that placement fails."""
    from hoseline.io.problem_file import problem_from_dict
    from hoseline.procedures.placement.continuation import PlacementError
    from hoseline.procedures.placement.sequence import solve

    try:
        return solve(problem_from_dict(data), estimate_error=False).centerline
    except PlacementError:
        return None


@st.composite
def contact_obstacle(draw, name: str, anchor: np.ndarray, length: float, radius: float, up: np.ndarray | None,
                     mounts: tuple[np.ndarray, np.ndarray]) -> str:
    """One [[contact.obstacles]] table whose surface passes `depth` mm beyond the hose point `anchor` (mm): clear of
    it (depth < 0), touching it, a little or deeply into it; a plane under it (its normal `up`, against gravity, if
    given) or any way up, a sphere, a cylinder or a box across it, with or without a hose_side.  Mostly sized and
    placed to keep the `mounts` (points, mm) outside, so that most layouts are placed; sometimes not (a refusal)."""
    kind = draw(st.sampled_from(("plane", "sphere", "cylinder", "box")))
    side = np.array(draw(_unit_vectors()))
    side /= np.linalg.norm(side)  # from the obstacle towards the hose: the side the hose is pushed to
    if kind == "plane" and up is not None and draw(st.booleans()):
        side = up
    reach = draw(st.sampled_from(("clear", "touching", "shallow", "deep")))
    depth = {"clear": -draw(st.floats(0.1, 2.0)) * radius, "touching": draw(st.floats(-0.01, 0.01)) * radius,
             "shallow": draw(st.floats(0.0, 2.0)) * radius, "deep": draw(st.floats(0.0, 0.3)) * length}[reach]
    size = draw(st.floats(0.02, 0.5)) * length + radius  # a radius or half an edge, mm
    extents = [draw(st.floats(0.05, 1.0)) * length + radius for _ in range(2)]  # a cylinder's half-length, box edges
    room = min(float(np.linalg.norm(mount - anchor)) for mount in mounts) - 3.0 * radius  # to the nearer mount
    if draw(st.integers(0, 3)) > 0:  # keep the mounts outside: the obstacle within `room` of the anchor
        if kind == "plane":
            depth = min(depth, min(float((mount - anchor) @ side) for mount in mounts) - 1.5 * radius)
        elif room > 0.1 * radius:
            size = min(size, 0.4 * room)
            depth = min(depth, size)
            extents = [min(extent, 0.8 * room) for extent in extents]
    table = f'[[contact.obstacles]]\nkind = "{kind}"\nname = "{name}"\n'
    if kind == "plane":
        return table + f"point = {_numbers(anchor + depth * side)}\nnormal = {_numbers(side)}\n"
    centre = anchor - (size - depth) * side
    if kind == "sphere":
        table += f"center = {_numbers(centre)}\nradius = {size!r}\n"
    elif kind == "cylinder":
        axis = _across(side, draw(_unit_vectors()))
        table += (f"start = {_numbers(centre - extents[0] * axis)}\nend = {_numbers(centre + extents[0] * axis)}\n"
                  f"radius = {size!r}\n")
    else:  # a block, one face towards the hose
        across = _across(side, draw(_unit_vectors()))
        table += (f"center = {_numbers(centre)}\nsize = {_numbers([2.0 * size, *extents])}\n"
                  f"axes = [{_numbers(side)}, {_numbers(across)}, {_numbers(np.cross(side, across))}]\n")
    hint = draw(st.sampled_from((None, None, "side", "opposite", "any")))
    if hint is not None:
        direction = {"side": side, "opposite": -side, "any": np.array(draw(_unit_vectors()))}[hint]
        table += f"hose_side = {_numbers(direction)}\n"
    return table


@st.composite
def contact_inputs(draw) -> FuzzInput:
    """A random problem (at most 2 m, twists within two turns), self-contact on or off, and up to three obstacles
    across its free shape (the problem placed without them), its straight start (along start.direction) or near the
    middle of the mounts, clear of the hose, touching it or through it; or the thesis problem with contact, mutated.

    The obstacles are named, and where the free placement succeeds a refusal must name one of them (or the hose's
    self-contact) and say what to change (run_input)."""
    if draw(st.integers(0, 3)) == 0:
        return FuzzInput("contact", {"problem.toml": draw(mutated(THESIS_WITH_CONTACT))},
                         ["solve", "problem.toml", "-o", "OUT", "-q"])
    data = draw(feasible_problem(largest_length=2000.0, largest_segments=16))
    data["end"]["twist"] = draw(st.floats(-720.0, 720.0))
    length, radius = data["hose"]["length"], 0.5 * data["hose"]["outer_diameter"]
    start, end = np.array(data["start"]["point"]), np.array(data["end"]["point"])
    direction = np.array(data["start"]["direction"]) / np.linalg.norm(data["start"]["direction"])
    gravity = np.array(data["environment"]["gravity"])
    up = -gravity / np.linalg.norm(gravity) if np.any(gravity) else None
    free = _free_centerline(data)
    self_contact = draw(st.booleans())
    lines = [f"[contact]\nself = {'true' if self_contact else 'false'}\n"]
    names = []
    for index in range(draw(st.integers(0 if self_contact else 1, 3))):
        where = draw(st.sampled_from(("free shape", "free shape", "straight start", "near")))
        if where == "free shape" and free is not None:
            anchor = free[draw(st.integers(1, len(free) - 2))]
        elif where == "near":
            anchor = 0.5 * (start + end) + draw(st.floats(0.05, 1.0)) * length * np.array(draw(_unit_vectors()))
        else:
            anchor = start + draw(st.floats(0.1, 1.0)) * length * direction
        names.append(f"obstacle {index + 1}")
        lines.append(draw(contact_obstacle(names[-1], anchor, length, radius, up, (start, end))))
    return FuzzInput("contact", {"problem.toml": toml_text(data, "\n".join(lines))},
                     ["solve", "problem.toml", "-o", "OUT", "-q"],
                     obstacles=tuple(names) if free is not None else ())


STRATEGIES = {
    "problem": problem_inputs, "iges": iges_inputs, "feasible": feasible_inputs, "sweep": sweep_inputs,
    "poses": pose_inputs, "mesh": mesh_inputs, "feasible_sweep": feasible_sweep_inputs, "cloud": cloud_inputs,
    "contact": contact_inputs,
}


# --- the oracle ---


class Hang(BaseException):
    """Raised by the watchdog when one input runs longer than its time limit (not an Exception: nothing catches it)."""


@contextmanager
def watchdog(seconds: int):
    """Raise Hang in the main thread after `seconds` (SIGALRM; 0 for none)."""

    def ring(signum, frame):
        raise Hang(f"still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, ring) if seconds else None
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        if previous is not None:
            signal.signal(signal.SIGALRM, previous)


def run_input(case: FuzzInput, folder: Path, timeout: int = 0) -> Outcome:
    """Write `case` into the empty `folder`, run its command in-process and judge what happened."""
    import time

    for name, content in case.files.items():
        (folder / name).write_bytes(content)
    out = folder / case.out.replace("INPUT", case.args[1])  # INPUT/inner: a folder under the input file
    args = [str(out) if a == "OUT" else str(folder / a) if a in case.files else a for a in case.args]
    before = _tree(folder)
    started = time.perf_counter()
    try:
        with watchdog(timeout):
            result = CliRunner().invoke(cli.app, args)
    except Hang as exc:
        return Outcome(case.kind, None, "hang", str(exc), seconds=time.perf_counter() - started)
    outcome = Outcome(case.kind, result.exit_code, output=result.output, seconds=time.perf_counter() - started)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        outcome.failure = "traceback"
        outcome.detail = "".join(traceback.format_exception(result.exception))
        return outcome
    if result.exit_code not in (0, 2, 3, 4):
        outcome.failure, outcome.detail = "exit_code", f"exit code {result.exit_code}"
        return outcome
    if result.exit_code != 0:
        left = sorted(str(p.relative_to(folder)) for p in _tree(folder) - before)
        if left:
            outcome.failure, outcome.detail = "partial_output", f"left behind: {left[:5]}"
        elif not any(line.startswith("error: ") for line in result.output.splitlines()) or "Traceback" in result.output:
            outcome.failure, outcome.detail = "unclear_error", result.output[:500]
        elif case.feasible and result.exit_code != 3:
            outcome.failure, outcome.detail = "refused_valid", result.output[:500]
        elif result.exit_code == 3 and "the solver failed: " not in result.output:
            outcome.failure, outcome.detail = "unclear_error", result.output[:500]
        elif result.exit_code == 3 and case.obstacles and not names_a_part_and_a_fix(result.output, case.obstacles):
            outcome.failure, outcome.detail = "unclear_error", result.output[:500]
        return outcome
    problems = _check_outputs(case.args[0], out)
    if problems:
        outcome.failure, outcome.detail = "bad_result", "; ".join(problems)
    return outcome


def names_a_part_and_a_fix(output: str, obstacles: tuple[str, ...]) -> bool:
    """Whether a contact placement's refusal names one of `obstacles` (quoted) or the hose's self-contact, and says
    what to change (one of FIXES)."""
    text = " ".join(output.split())  # the message as one line, wherever the terminal wrapped it
    named = any(f"'{name}'" in text for name in obstacles) or SELF_CONTACT.search(text) is not None
    return named and any(word in text.lower() for word in FIXES)


def _tree(folder: Path) -> set[Path]:
    return set(folder.rglob("*"))


def _check_outputs(command: str, out: Path) -> list[str]:
    """What is wrong with the files of a run that exited 0 (empty if nothing)."""
    if command == "solve":
        return check_result_json(out / "result.json")
    if command == "sweep":
        missing = [name for name in SWEEP_FILES if not (out / name).is_file()]
        if missing:
            return [f"missing {missing}"]
        document = json.loads((out / "sweep.json").read_text())
        problems = check_summary(document["assembly"], document["problem"]["hose"]["length"])
        return problems + check_shapes(out / "shapes.csv", document["problem"]["hose"]["length"])
    if command == "compare":
        missing = [name for name in ("report.html", "validation.json", "deviation.csv") if not (out / name).is_file()]
        return [f"missing {missing}"] if missing else []
    return [f"unknown command {command}"]


def check_summary(summary: dict, length: float) -> list[str]:
    """A placement summary is converged, stable and of exact length."""
    problems = []
    if summary.get("stable") is not True:
        problems.append(f"not stable (margin {summary.get('stability_margin_N_per_rad2')})")
    residual = summary.get("residual")
    # with contact the solver's contract is CONTACT_TOLERANCE: the barrier's stiffness (pressure / gap) lifts the
    # rounding floor (a 41 mm hose of EI 7.3 N mm^2 on a box stops at 1.2e-10 however long it is polished)
    loosest = CONTACT_TOLERANCE if summary.get("contact") else 1e-10
    if residual is None or not residual <= loosest:
        problems.append(f"residual {residual}")
    length_error = summary.get("length_error")
    if length_error is None or not abs(length_error) <= 1e-9:
        problems.append(f"length error {length_error}")
    if summary.get("length_mm") is not None and summary["length_mm"] != length:
        problems.append(f"length {summary['length_mm']} != {length}")
    return problems


def check_result_json(path: Path) -> list[str]:
    """result.json of a solve: every station finite, the ends on the mounts, the centreline of exact length."""
    if not path.is_file():
        return ["no result.json"]
    document = json.loads(path.read_text())
    hose = document["problem"]["hose"]
    problems = check_summary(document["summary"], hose["length"])
    gap = document["summary"].get("contact", {}).get("min_gap_mm")
    if gap is not None and not gap >= 0.0:  # the barrier keeps every gap positive: none may be negative
        problems.append(f"enters an obstacle or itself: smallest gap {gap} mm")
    stations = document["stations"]
    if any(v is None for name in stations for v in np.ravel(np.array(stations[name], dtype=object))):
        return problems + ["non-finite station values (null)"]
    centerline = np.array(stations["centerline"], dtype=float)
    scale = max(1.0, float(np.max(np.abs(centerline))))
    polyline = float(np.sum(np.linalg.norm(np.diff(centerline, axis=0), axis=1)))
    if abs(polyline - hose["length"]) > 1e-9 * hose["length"] + 1e-12 * scale * len(centerline):
        problems.append(f"centreline {polyline!r} mm long, hose {hose['length']!r} mm")
    for end, index in (("start", 0), ("end", -1)):
        gap = float(np.linalg.norm(centerline[index] - np.array(document["problem"][end]["point"])))
        if gap > 1e-8 * hose["length"] + 1e-12 * scale:
            problems.append(f"{end} station {gap:.3g} mm off its mount")
    return problems


def check_shapes(path: Path, length: float) -> list[str]:
    """shapes.csv of a sweep: every station finite, every pose's centreline of the hose's length (to its 8 digits)."""
    table = np.genfromtxt(path, delimiter=",", skip_header=1)
    table = table.reshape(-1, 5)
    if not np.all(np.isfinite(table)):
        return ["non-finite stations in shapes.csv"]
    problems = []
    for pose in np.unique(table[:, 0]):
        line = table[table[:, 0] == pose, 2:]
        polyline = float(np.sum(np.linalg.norm(np.diff(line, axis=0), axis=1)))
        tolerance = 1e-6 * length + 1e-7 * float(np.max(np.abs(line))) * len(line)
        if abs(polyline - length) > tolerance:
            problems.append(f"pose {pose:g}: centreline {polyline:.8g} mm long, hose {length:g} mm")
    return problems


def keep(case: FuzzInput, outcome: Outcome, folder: Path) -> None:
    """Save a failing input (its files, the command and what happened) into `folder` to reproduce it."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, content in case.files.items():
        (folder / name).write_bytes(content)
    (folder / "outcome.json").write_text(json.dumps({
        "kind": case.kind, "args": case.args, "out": case.out, "exit_code": outcome.exit_code,
        "failure": outcome.failure, "detail": outcome.detail, "output": outcome.output[-2000:],
        "seconds": outcome.seconds}, indent=1))


def fresh_folder(root: Path, name: str) -> Path:
    """An empty folder `root/name` (emptied if it exists)."""
    folder = root / name
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    return folder
