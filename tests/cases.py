"""Problem files shared by the tests: the thesis brake hose and ways to get it wrong."""

from pathlib import Path

# The thesis brake hose (Goodyear5052) from B to D, 10 segments to keep solver tests fast.
THESIS_TOML = """\
name = "brake hose"
[hose]
length = 330.6
outer_diameter = 10.1
bending_stiffness = 149563.0
torsional_stiffness = 2454930.0
min_bend_radius = 50.0
segments = 10
[start]
point = [-13.0, 0.0, -11.25]
direction = [0.0, 1.0, 0.0]
[end]
point = [-173.064, -7.0, -11.25]
direction = [1.0, 0.0, 0.0]
twist = 180.0
[environment]
gravity = [0.0, 0.0, 0.0]
"""

# (case id, text in THESIS_TOML, replacement, fragments the error message must contain)
BAD_EDITS = [
    (
        "hose shorter than mount distance",
        "length = 330.6",
        "length = 100",
        ["hose.length = 100", "shorter than the mount distance 160.2", "use a hose longer than 160.2"],
    ),
    ("zero direction", "direction = [0.0, 1.0, 0.0]", "direction = [0, 0, 0]", ["start.direction = [0, 0, 0]", "zero vector"]),
    ("nan direction", "direction = [1.0, 0.0, 0.0]", "direction = [nan, 0.0, 0.0]", ["end.direction = [nan, 0.0, 0.0]", "finite"]),
    ("negative stiffness", "bending_stiffness = 149563.0", "bending_stiffness = -1", ["hose.bending_stiffness = -1", "must be positive"]),
    ("unknown key", "length = 330.6", "lenght = 330.6", ["unknown key 'hose.lenght'", "did you mean 'hose.length'"]),
    (
        "bending stiffness twice",
        "bending_stiffness = 149563.0",
        "bending_stiffness = 149563.0\nyoungs_modulus = 292.8",
        ["bending_stiffness", "youngs_modulus", "keep one"],
    ),
    ("no bending stiffness", "bending_stiffness = 149563.0", "", ["no bending stiffness", "bending_stiffness", "youngs_modulus"]),
    (
        "torsion twice",
        "torsional_stiffness = 2454930.0",
        "torsional_stiffness = 2454930.0\ntorsion_factor = 25.0",
        ["torsional_stiffness", "torsion_factor", "keep one"],
    ),
    ("too few segments", "segments = 10", "segments = 2", ["hose.segments = 2", "at least 4"]),
    ("text for a number", "outer_diameter = 10.1", 'outer_diameter = "10.1"', ['hose.outer_diameter = "10.1"', "must be a number"]),
    ("two-component point", "point = [-13.0, 0.0, -11.25]", "point = [-13.0, 0.0]", ["start.point", "three components"]),
    ("missing table", "[start]", "[begin]", ["unknown key 'begin'"]),
    ("toml syntax error", "[environment]", "[environment", ["not valid TOML", "line 16"]),
]


def bad_toml(old: str, new: str) -> str:
    """THESIS_TOML with the first `old` replaced by `new`."""
    assert old in THESIS_TOML, old
    return THESIS_TOML.replace(old, new, 1)


def write(path: Path, text: str) -> Path:
    """Write `text` to `path` and return the path."""
    path.write_text(text, encoding="utf-8")
    return path
