"""Read and write problem files (TOML) with messages that name the field, the value and the fix.

The format, in the units of a hose catalogue (mm, N*mm^2, kg/m, degrees, m/s^2)::

    name = "optional text"
    [hose]
    length = 330.6                   # mm
    outer_diameter = 10.1            # mm
    bending_stiffness = 149563.0     # EI, N*mm^2 (or youngs_modulus, N/mm^2, with
                                     #   outer_diameter and optional inner_diameter, mm)
    torsional_stiffness = 2454930.0  # GJ, N*mm^2, optional (or torsion_factor)
    mass_per_length = 0.0            # kg/m, optional
    min_bend_radius = 50.0           # mm, optional, to the inside of the bend
    segments = 100                   # optional, >= 4
    [start]
    point = [-13.0, 0.0, -11.25]     # mm
    direction = [0.0, 1.0, 0.0]      # from the fitting into the hose
    [end]
    point = [-173.064, -7.0, -11.25]
    direction = [1.0, 0.0, 0.0]      # from the fitting into the hose
    twist = 180.0                    # degrees, optional
    [environment]
    gravity = [0.0, 0.0, -9.81]      # m/s^2, optional

Instead of the points and directions of [start] and [end], the mounts can come from
named points of an IGES file (CATIA and others); [end] then holds only the twist::

    [mounts]
    iges = "mounts.igs"                  # relative to the problem file
    start = { tip = "B", behind = "A" }  # default: the hose leaves B along A->B
    end = { tip = "D", ahead = "C" }     # default: the hose leaves D along D->C
    [end]
    twist = 180.0

Each fitting names its tip and one more point on its axis, either `behind` the tip (the
hose leaves the tip along behind->tip) or `ahead` of it on the hose side (the hose leaves
the tip along tip->ahead).

Exactly one of bending_stiffness / youngs_modulus.  At most one of
torsional_stiffness / torsion_factor; without either, torsion_factor = 1, the
isotropic GJ = EI / (1 + poisson_ratio) with poisson_ratio 0.5 unless given.
Real hoses are often much stiffer in torsion (the thesis calibrates 25x).
bending_stiffness_2 (N*mm^2, optional) is EI about the second section axis.

Clips (intermediate supports, model/clips.py), one [[clips]] table each, in order of arc length::

    [[clips]]
    type = "fixed"                   # fixed, rotating, sliding or ball
    arc_length = 150.0               # mm from the start fitting, on a station of the hose
                                     # (sliding: where the placement starts it; the solve finds it)
    point = [-60.0, 120.0, 10.0]     # mm
    direction = [-1.0, 0.3, 0.0]     # the hose's tangent through the clip (not for a ball clip)
    name = "bracket"                 # optional
    twist = 0.0                      # fixed clip only, optional: degrees turned from the torque-free roll
                                     # the placement locks it at, right-handed about direction (as [end] twist)

With [mounts], a clip may name IGES points instead of point and direction, as the fittings do:
tip = "E" with behind = "F" (the hose passes along F->E) or ahead = "F" (along E->F); a ball
clip names its tip only.

The thesis' off-axis stiffener springs (model/stiffeners.py), optional, either the chapter IV
preset (angle, table and segment count from hose.length; hose.segments left out or equal to
the preset's) or the springs given::

    [hose.stiffeners]
    springs = 16                     # 8 or 16 between adjacent segments, default 16
    preset = "thesis"                # or, instead of preset:
    angle_deg = 71.0                 # degrees from the section plane, (0, 90]
    table = [[0.0, 0.0], [0.2, 0.0], [0.21, 2500.0]]  # [deformation mm, force N], tension positive

A braided hose's strands as a stiffness term (model/braid.py, docs/model.md "The continuous
counterpart"), optional; not with [hose.stiffeners] (both model the braid) or [[clips]]::

    [hose.braid]
    angle_deg = 38.0                 # degrees, strands to the hose axis, [0, 89]
    strands = 12                     # per family (two families at +-angle_deg)
    strand_axial_stiffness = 1500.0  # EA of one strand, N
    slack_strain = 0.005             # optional, default 0: strain before a strand carries tension
    radius = 3.7                     # mm, optional, of the braid layer (default: the hose's outer radius)

End fittings (model/fittings.py): [fittings.start] and [fittings.end] make [start] and [end] the ports
(seal face centres) and put a rigid fitting between each port and the flexible hose; [hose] then takes
either length (the free, cut length) or overall_length (the catalogue's, fittings included)::

    [hose]
    overall_length = 400.0           # mm, instead of length
    [fittings.start]
    length = 30.0                    # mm, straight fitting from the port
    [fittings.end]
    bend_angle = 90.0                # degrees, an elbow
    length = 25.0                    # mm, port to the vertex (the drop)
    outlet_length = 30.0             # mm, vertex to the hose
    bend_radius = 12.0               # mm, optional (0: sharp corner)
    reference = [0.0, 0.0, 1.0]      # the elbow bends towards this at clocking 0
    clocking = 30.0                  # degrees about the port direction, optional
    outer_diameter = 14.0            # mm, optional (default: the hose's)

Contact (model/obstacles.py, docs/model.md "Contact"): analytic obstacles the hose touches without
entering (frictionless), and the hose kept out of itself::

    [contact]
    self = true                      # optional, default false
    placement = "bring_in"           # optional: the obstacles brought in after the free placement (default),
                                     # or "along_path": present all along the published sequence
    force_accuracy_percent = 0.5     # optional: `hoseline solve` refines the segments until each obstacle's
                                     # total force and the mount reactions are estimated within it (default 0.5
                                     # when [hose] gives no segments, else none: the count as given)
    [[contact.obstacles]]
    kind = "plane"                   # the hose stays on the side normal points to
    point = [0.0, 0.0, -40.0]        # mm
    normal = [0.0, 0.0, 1.0]
    name = "floor"                   # optional, default the kind (numbered when repeated)
    [[contact.obstacles]]
    kind = "sphere"
    center = [0.0, 50.0, 0.0]        # mm
    radius = 20.0                    # mm
    [[contact.obstacles]]
    kind = "cylinder"                # a capsule: rounded ends
    start = [0.0, 0.0, 0.0]          # mm, the axis from start to end
    end = [0.0, 100.0, 0.0]
    radius = 15.0                    # mm
    hose_side = [0.0, 0.0, 1.0]      # optional (not for a plane): the hose ends on this side of it (default: the
                                     # side of least penetration of the free hose)
    [[contact.obstacles]]
    kind = "box"                     # sharp edges and corners
    center = [0.0, -60.0, 0.0]       # mm
    size = [40.0, 20.0, 30.0]        # mm, edge lengths along axes
    axes = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]  # optional: directions of the edges (perpendicular)
    [[contact.obstacles]]
    kind = "mesh"                    # a surface: the hose stays on the side it starts on
    file = "bracket.stl"             # STL, OBJ, PLY or STEP, mm, relative to the problem file

These are not the [[obstacles]] of a sweep file (meshes the sweep measures clearance to, without
contact); a sweep file may hold [contact] too, kept out of at every pose, each obstacle fixed or moving
with a body (body = ..., io/sweep_file.py).
"""

from __future__ import annotations

import difflib
import json
import math
import tomllib
import typing
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import pydantic
from pydantic import AfterValidator, BaseModel, ConfigDict, Field, model_validator

from hoseline.model.hose import (
    DEFAULT_POISSON_RATIO,
    DEFAULT_SEGMENTS,
    Hose,
    bending_stiffness_from_modulus,
    isotropic_torsional_stiffness,
)
from hoseline.model import limits
from hoseline.model.braid import LARGEST_ANGLE_DEG as LARGEST_BRAID_ANGLE_DEG
from hoseline.model.braid import Braid
from hoseline.model.clips import Clip
from hoseline.model.fittings import EndFittings, Fitting
from hoseline.model.mounts import Mount
from hoseline.model.obstacles import Box, Cylinder, Mesh, Obstacle, Plane, Sphere
from hoseline.model.problem import DEFAULT_FORCE_ACCURACY, Problem, reaches
from hoseline.model.preset import Preset
from hoseline.model.stiffeners import PRESETS, SPRING_COUNTS, SpringTable, Stiffeners, thesis_preset


class ProblemFileError(ValueError):
    """A problem file (or dict) that cannot describe a hose placement; the message says what to fix."""


# unit (or meaning) of each key, for messages and the comments of a written problem file
_UNITS = {
    "length": "mm",
    "outer_diameter": "mm",
    "bending_stiffness": "EI, N*mm^2",
    "bending_stiffness_2": "EI about the second axis, N*mm^2",
    "torsional_stiffness": "GJ, N*mm^2",
    "torsion_factor": "GJ over the isotropic EI / (1 + poisson_ratio)",
    "poisson_ratio": "nu in the torsion factor's isotropic GJ",
    "mass_per_length": "kg/m",
    "min_bend_radius": "mm, to the inside of the bend",
    "segments": "rigid segments of the model",
    "point": "mm",
    "direction": "from the fitting into the hose",
    "twist": "degrees, end fitting about its direction",
    "gravity": "m/s^2",
    "iges": "IGES file with the named mount points, relative to the problem file",
    "tip": "label of the fitting tip point",
    "behind": "label of a point on the fitting axis behind the tip",
    "ahead": "label of a point on the fitting axis ahead of the tip",
    "type": "fixed, rotating or ball",
    "arc_length": "mm from the start fitting",
    "name": "free text",
    "clips.direction": "the hose's tangent through the clip",
    "clips.twist": "degrees, a fixed clip turned from its torque-free locked roll about its direction",
    "springs": "8 or 16 springs between adjacent segments",
    "angle_deg": "degrees, spring to the section plane",
    "table": "[deformation mm, force N] pairs, tension positive",
    "preset": "\"thesis\": chapter IV angle, table and segments",
    "braid.angle_deg": "degrees, strands to the hose axis",
    "strands": "strands per family (two families at +-angle_deg)",
    "strand_axial_stiffness": "EA of one strand, N",
    "slack_strain": "strain a strand takes before it carries tension",
    "braid.radius": "mm, of the braid layer",
    "preset_radius": "mm, radius of the set from storage (natural curvature)",
    "preset_angle_deg": "degrees, side of the set about the hose axis from the start fitting's d1",
    "overall_length": "mm, fittings included (catalogue length)",
    "bend_angle": "degrees, 0 for a straight fitting",
    "outlet_length": "mm, elbow vertex to the hose",
    "bend_radius": "mm, centreline radius of the elbow",
    "clocking": "degrees about the port direction from reference",
    "reference": "direction the elbow bends towards at clocking 0",
    "fittings.length": "mm, straight: port to hose; elbow: port to vertex",
    "fittings.outer_diameter": "mm, of the fitting",
    "self": "keep the hose out of itself",
    "kind": "plane, sphere, cylinder, box or mesh",
    "normal": "towards the side the hose stays on",
    "hose_side": "direction from the obstacle to the side the hose ends on",
    "contact.placement": "bring_in (obstacles after the free placement) or along_path",
    "contact.force_accuracy_percent": "percent, e.g. 0.5",
    "center": "mm",
    "radius": "mm",
    "obstacles.start": "mm, one end of the axis",
    "obstacles.end": "mm, the other end of the axis",
    "size": "mm, edge lengths along axes",
    "axes": "directions of the box's edges, perpendicular",
    "file": "STL, OBJ, PLY or STEP mesh (mm), relative to the problem file",
}


# --- field checks: each raises ValueError with the reason only; the location and value are added later ---


def _positive(unit: str):
    def check(value: float) -> float:
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"must be positive ({unit})")
        return value

    return AfterValidator(check)


def _in_range(bounds: tuple[float, float], unit: str, what: str):
    """A positive value within `bounds` (in `unit`); `what` says where the range comes from."""

    def check(value: float) -> float:
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"must be positive ({unit})")
        if not limits.within(value, bounds):
            raise ValueError(f"must lie between {bounds[0]:g} and {bounds[1]:g} {unit} ({what}); check the unit")
        return value

    return AfterValidator(check)


def _not_negative(unit: str, largest: float = math.inf):
    def check(value: float) -> float:
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f"must be zero or positive ({unit})")
        if value > largest:
            raise ValueError(f"must be at most {largest:g} {unit}; check the unit")
        return value

    return AfterValidator(check)


def _angle(value: float) -> float:
    if not (math.isfinite(value) and abs(value) <= limits.ANGLE_DEG):
        raise ValueError(f"must be a finite angle within +-{limits.ANGLE_DEG:g} degrees (ten turns)")
    return value


def _vector(value: list[float]) -> list[float]:
    if len(value) != 3:
        raise ValueError("must have exactly three components [x, y, z]")
    if not all(math.isfinite(v) for v in value):
        raise ValueError("components must be finite numbers")
    return value


def _point(value: list[float]) -> list[float]:
    _vector(value)
    if not all(limits.coordinate_within(v) for v in value):
        raise ValueError(
            f"coordinates must lie within +-{limits.COORDINATE_MM:g} mm (100 m); give the point in mm"
        )
    return value


def _direction(value: list[float]) -> list[float]:
    _vector(value)
    length = math.hypot(*value)
    if length < 1e-12:
        raise ValueError("a direction cannot be the zero vector; give the fitting axis, e.g. [1, 0, 0]")
    if not math.isfinite(length):
        raise ValueError("components too large to give a direction; give the fitting axis, e.g. [1, 0, 0]")
    return value


def _gravity(value: list[float]) -> list[float]:
    _vector(value)
    if not math.hypot(*value) <= limits.GRAVITY_M_S2:
        raise ValueError(f"must be at most {limits.GRAVITY_M_S2:g} m/s^2 long (10 g); give it in m/s^2, e.g. [0, 0, -9.81]")
    return value


def _poisson(value: float) -> float:
    if not (math.isfinite(value) and -1.0 < value <= 0.5):
        raise ValueError("must lie in (-1, 0.5]")
    return value


def _segments(value: int) -> int:
    low, high = limits.SEGMENTS
    if not low <= value <= high:
        raise ValueError(f"must be at least {low} and at most {high}")
    return value


Vector = Annotated[list[float], AfterValidator(_vector)]
Point = Annotated[list[float], AfterValidator(_point)]
Direction = Annotated[list[float], AfterValidator(_direction)]
Gravity = Annotated[list[float], AfterValidator(_gravity)]
Angle = Annotated[float, AfterValidator(_angle)]


_STIFFNESSES = "a 1 mm rubber cord to a 100 mm steel bar"


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)


MAX_NESTING = 16  # levels of tables and arrays within each other a file may hold (the validation recurses per level)
SPRING_FORCE_N = 1e7  # largest force of a stiffener table, N


def _spring_count(value: int) -> int:
    if value not in SPRING_COUNTS:
        raise ValueError("must be 8 or 16 (the thesis' geometries: equations 9-12 and 13-16)")
    return value


def _spring_angle(value: float) -> float:
    if not (math.isfinite(value) and 0.0 < value <= 90.0):
        raise ValueError("must lie in (0, 90] degrees from the section plane (90: along the hose)")
    return value


def _spring_table(value: list[list[float]]) -> list[list[float]]:
    if len(value) < 2:
        raise ValueError("give at least two [deformation mm, force N] pairs")
    for index, pair in enumerate(value):
        if len(pair) != 2 or not all(math.isfinite(v) for v in pair):
            raise ValueError(f"pair {index} must be two finite numbers [deformation mm, force N]")
        if abs(pair[0]) > limits.LENGTH_MM[1] or abs(pair[1]) > SPRING_FORCE_N:
            raise ValueError(f"pair {index}: deformations lie within +-{limits.LENGTH_MM[1]:g} mm and forces within "
                             f"+-{SPRING_FORCE_N:g} N (a 100 mm steel rope breaks at about that); check the units")
        if index and pair[0] <= value[index - 1][0]:
            raise ValueError(f"pair {index}: deformation {pair[0]!r} mm must be above the one before it (strictly increasing)")
    return value


def _spring_preset(value: str) -> str:
    if value not in PRESETS:
        raise ValueError(f"unknown preset: use {', '.join(repr(name) for name in PRESETS)} (Thomas 2004, chapter IV)")
    return value


class StiffenersSection(_Section):
    """[hose.stiffeners]: the thesis' off-axis springs (model/stiffeners.py): preset, or angle and table (mm, N, degrees)."""

    springs: Annotated[int, AfterValidator(_spring_count)] = 16
    preset: Annotated[str, AfterValidator(_spring_preset)] | None = None
    angle_deg: Annotated[float, AfterValidator(_spring_angle)] | None = None
    table: Annotated[list[list[float]], AfterValidator(_spring_table)] | None = None

    @model_validator(mode="after")
    def _preset_or_angle_and_table(self) -> "StiffenersSection":
        explicit = [key for key in ("angle_deg", "table") if getattr(self, key) is not None]
        if self.preset is not None and explicit:
            raise ValueError(f"hose.stiffeners: preset and {' and '.join(explicit)} are given: keep preset = "
                             '"thesis" (its angle and table follow from the hose length) or give angle_deg and table')
        if self.preset is None and len(explicit) < 2:
            raise ValueError('hose.stiffeners: give preset = "thesis", or both angle_deg (degrees) and table '
                             "([deformation mm, force N] pairs)")
        return self


def _braid_strands(value: int) -> int:
    if not 1 <= value <= limits.BRAID_STRANDS:
        raise ValueError(f"must be a whole number of strands per family, 1 to {limits.BRAID_STRANDS}")
    return value


def _braid_angle(value: float) -> float:
    if not (math.isfinite(value) and 0.0 <= value <= LARGEST_BRAID_ANGLE_DEG):
        raise ValueError(f"must lie in [0, {LARGEST_BRAID_ANGLE_DEG:g}] degrees from the hose axis (braid angle; "
                         "a catalogue's 54.7 degrees is the neutral angle, measured from the axis too)")
    return value


def _braid_slack(value: float) -> float:
    if not (math.isfinite(value) and 0.0 <= value <= limits.BRAID_SLACK_STRAIN):
        raise ValueError(f"must lie in [0, {limits.BRAID_SLACK_STRAIN:g}]: a strain as a fraction (0.005 for 0.5 %)")
    return value


class BraidSection(_Section):
    """[hose.braid]: two families of tension-only strands at +-angle_deg to the hose axis (model/braid.py; mm, N, degrees)."""

    angle_deg: Annotated[float, AfterValidator(_braid_angle)]
    strands: Annotated[int, AfterValidator(_braid_strands)]
    strand_axial_stiffness: Annotated[float, _in_range(limits.BRAID_STRAND_STIFFNESS_N, "N",
                                                       "a fine yarn to a 10 mm steel rope")]
    slack_strain: Annotated[float, AfterValidator(_braid_slack)] = 0.0
    radius: Annotated[float, _in_range(limits.OUTER_DIAMETER_MM, "mm", "of the braid layer")] | None = None


class HoseSection(_Section):
    """[hose]: geometry, stiffness, weight and limits (mm, N*mm^2, N/mm^2, kg/m)."""

    length: Annotated[float, _in_range(limits.LENGTH_MM, "mm", "1 mm to 100 m")]
    outer_diameter: Annotated[float, _in_range(limits.OUTER_DIAMETER_MM, "mm", "capillary tube to dredging hose")]
    bending_stiffness: Annotated[float, _in_range(limits.STIFFNESS_NMM2, "N*mm^2", _STIFFNESSES)] | None = None
    bending_stiffness_2: Annotated[float, _in_range(limits.STIFFNESS_NMM2, "N*mm^2", _STIFFNESSES)] | None = None
    youngs_modulus: Annotated[float, _in_range(limits.YOUNGS_MODULUS_NMM2, "N/mm^2", "soft gel to tungsten")] | None = None
    inner_diameter: Annotated[float, _not_negative("mm")] | None = None
    torsional_stiffness: Annotated[float, _in_range(limits.STIFFNESS_NMM2, "N*mm^2", _STIFFNESSES)] | None = None
    torsion_factor: Annotated[float, _in_range(limits.STIFFNESS_RATIO, "times the isotropic GJ", "hoses lie within 0.1-100")] | None = None
    poisson_ratio: Annotated[float, AfterValidator(_poisson)] | None = None
    mass_per_length: Annotated[float, _not_negative("kg/m", limits.MASS_PER_LENGTH_KG_M)] = 0.0
    min_bend_radius: Annotated[float, _not_negative("mm", limits.LENGTH_MM[1])] | None = None
    segments: Annotated[int, AfterValidator(_segments)] = DEFAULT_SEGMENTS
    stiffeners: StiffenersSection | None = None
    braid: BraidSection | None = None
    preset_radius: Annotated[float, _in_range(limits.LENGTH_MM, "mm", "1 mm to 100 m")] | None = None
    preset_angle_deg: Annotated[float, AfterValidator(_angle)] | None = None

    @model_validator(mode="after")
    def _one_way_to_give_each_stiffness(self) -> "HoseSection":
        if self.bending_stiffness is not None and self.youngs_modulus is not None:
            raise ValueError(
                "hose: both bending_stiffness and youngs_modulus are given: keep one "
                "(bending_stiffness = EI in N*mm^2, or youngs_modulus = E in N/mm^2 with the diameters)"
            )
        if self.bending_stiffness is None and self.youngs_modulus is None:
            raise ValueError(
                "hose: no bending stiffness: give bending_stiffness (EI, N*mm^2) "
                "or youngs_modulus (E, N/mm^2, used with outer_diameter and inner_diameter)"
            )
        if self.youngs_modulus is None and self.inner_diameter is not None:
            raise ValueError("hose.inner_diameter is only used with youngs_modulus: remove it, bending_stiffness is given")
        if self.youngs_modulus is not None and self.bending_stiffness_2 is not None:
            raise ValueError(
                "hose.bending_stiffness_2 needs bending_stiffness: a section computed from youngs_modulus is round"
            )
        if self.inner_diameter is not None and self.inner_diameter >= self.outer_diameter:
            raise ValueError(
                f"hose.inner_diameter = {_show(self.inner_diameter)} mm is not smaller than "
                f"outer_diameter = {_show(self.outer_diameter)} mm: give the bore, smaller than the outside"
            )
        if self.torsional_stiffness is not None and self.torsion_factor is not None:
            raise ValueError(
                "hose: both torsional_stiffness and torsion_factor are given: keep one "
                "(torsional_stiffness = GJ in N*mm^2, or torsion_factor times the isotropic EI/(1+poisson_ratio))"
            )
        if self.torsional_stiffness is not None and self.poisson_ratio is not None:
            raise ValueError(
                "hose.poisson_ratio is only used with torsion_factor: remove it, torsional_stiffness is given"
            )
        if self.outer_diameter * limits.SLENDERNESS > self.length:
            raise ValueError(
                f"hose.outer_diameter = {_show(self.outer_diameter)} mm is more than 1/{limits.SLENDERNESS:g} of hose.length = "
                f"{_show(self.length)} mm: a rod model needs a hose at least {limits.SLENDERNESS:g} diameters long"
            )
        self._stiffnesses_in_range()
        return self

    def _stiffnesses_in_range(self) -> None:
        """Refuse an EI no solid rod of the outer diameter could have (a unit mistake), an EI computed from
        youngs_modulus outside the stiffness range, and lopsided stiffness ratios."""
        bending, torsional = self.stiffnesses()
        if self.bending_stiffness is not None:
            modulus = bending / (math.pi * self.outer_diameter**4 / 64.0)
            low, high = limits.EFFECTIVE_MODULUS_NMM2
            if not limits.within(modulus, limits.EFFECTIVE_MODULUS_NMM2):
                raise ValueError(
                    f"hose.bending_stiffness = {_show(self.bending_stiffness)} N*mm^2 with outer_diameter = "
                    f"{_show(self.outer_diameter)} mm needs a solid rod of Young's modulus {modulus:.3g} N/mm^2 "
                    f"(EI / (pi d^4 / 64)), outside {low:g}-{high:g} N/mm^2 (a lay-flat fire hose to tungsten): check "
                    "the units (EI in N*mm^2: 1 N*m^2 = 1e6 N*mm^2; the diameter in mm)"
                )
        low, high = limits.STIFFNESS_NMM2
        if not limits.within(bending, limits.STIFFNESS_NMM2):
            raise ValueError(
                f"hose.youngs_modulus = {_show(self.youngs_modulus)} N/mm^2 with outer_diameter = "
                f"{_show(self.outer_diameter)} mm gives EI = {bending:.3g} N*mm^2, outside {low:g}-{high:g} N*mm^2 "
                f"({_STIFFNESSES}): check the modulus and the diameters"
            )
        isotropic = isotropic_torsional_stiffness(bending)
        given = {"torsional_stiffness": self.torsional_stiffness} if self.torsional_stiffness is not None else {
            "torsion_factor": self.torsion_factor, "poisson_ratio": self.poisson_ratio}
        checks = [(given, torsional / isotropic, f"the isotropic GJ = EI / 1.5 = {isotropic:.6g} N*mm^2")]
        if self.bending_stiffness_2 is not None:
            checks.append(({"bending_stiffness_2": self.bending_stiffness_2}, self.bending_stiffness_2 / bending,
                           f"bending_stiffness = {bending:.6g} N*mm^2"))
        if not limits.within(torsional, limits.STIFFNESS_NMM2):
            named = ", ".join(f"hose.{key} = {_show(value)}" for key, value in given.items() if value is not None)
            raise ValueError(
                f"{named or 'the default torsion'} gives GJ = {torsional:.3g} N*mm^2, outside {low:g}-{high:g} N*mm^2 "
                f"({_STIFFNESSES}): give a {'smaller' if torsional > high else 'larger'} torsion_factor or "
                "torsional_stiffness"
            )
        low, high = limits.STIFFNESS_RATIO
        for keys, ratio, reference in checks:
            if not limits.within(ratio, limits.STIFFNESS_RATIO):
                named = ", ".join(f"hose.{key} = {_show(value)}" for key, value in keys.items() if value is not None)
                raise ValueError(
                    f"{named or 'the default torsion'} gives {ratio:.3g} times {reference}: give a value within "
                    f"{low:g}-{high:g} times it (catalogue hoses lie within 0.1-100)"
                )

    def stiffnesses(self) -> tuple[float, float]:
        """(EI, GJ) in N*mm^2 from whichever keys were given."""
        if self.bending_stiffness is not None:
            bending = self.bending_stiffness
        else:
            bending = bending_stiffness_from_modulus(self.youngs_modulus, self.outer_diameter, self.inner_diameter or 0.0)
        if self.torsional_stiffness is not None:
            return bending, self.torsional_stiffness
        factor = 1.0 if self.torsion_factor is None else self.torsion_factor
        nu = DEFAULT_POISSON_RATIO if self.poisson_ratio is None else self.poisson_ratio
        return bending, factor * isotropic_torsional_stiffness(bending, nu)


class MountSection(_Section):
    """[start] and [end]: the fitting tip (mm) and the direction from the fitting into the hose."""

    point: Point
    direction: Direction


class EndSection(MountSection):
    """[end]: as [start], plus the twist of the end fitting at assembly (degrees)."""

    twist: Angle = 0.0


class EnvironmentSection(_Section):
    """[environment]: gravity vector in m/s^2."""

    gravity: Gravity = Field(default_factory=lambda: [0.0, 0.0, 0.0])


class FittingSection(_Section):
    """[mounts] start and end: labels of the fitting tip and of one more point on its axis."""

    tip: str
    behind: str | None = None
    ahead: str | None = None


class MountsSection(_Section):
    """[mounts]: the mounts from the named points (entity 116) of an IGES file."""

    iges: str
    start: FittingSection | None = None  # default: the thesis' B with A behind it
    end: FittingSection | None = None  # default: the thesis' D with C ahead of it


class ClipSection(_Section):
    """[[clips]]: one clip (model/clips.py checks the type, the direction and the placement)."""

    type: str
    arc_length: float
    point: Point
    direction: Direction | None = None
    name: str = ""
    twist: Angle = 0.0


class EndFittingSection(_Section):
    """[fittings.start] or [fittings.end]: one rigid end fitting (model/fittings.py checks the geometry)."""

    length: Annotated[float, _not_negative("mm", limits.LENGTH_MM[1])]
    bend_angle: float = 0.0
    outlet_length: Annotated[float, _not_negative("mm", limits.LENGTH_MM[1])] = 0.0
    bend_radius: Annotated[float, _not_negative("mm", limits.LENGTH_MM[1])] = 0.0
    clocking: Angle = 0.0
    reference: Direction | None = None
    outer_diameter: Annotated[float, _in_range(limits.OUTER_DIAMETER_MM, "mm", "capillary tube to dredging hose")] | None = None


class FittingsSection(_Section):
    """[fittings]: the fitting at each end (either may be left out)."""

    start: EndFittingSection | None = None
    end: EndFittingSection | None = None


class _OverallLength(_Section):
    overall_length: Annotated[float, _in_range(limits.LENGTH_MM, "mm", "1 mm to 100 m")]


CONTACT_KEYS = {"plane": ("point", "normal"), "sphere": ("center", "radius"), "cylinder": ("start", "end", "radius"),
                "box": ("center", "size"), "mesh": ("file",)}
CONTACT_OPTIONAL_KEYS = {"box": ("axes",)}


class ContactObstacleSection(_Section):
    """[[contact.obstacles]]: one obstacle; which keys a kind takes is checked by _contact_obstacle (mm)."""

    kind: str
    name: str | None = None
    point: Point | None = None
    normal: Direction | None = None
    center: Point | None = None
    start: Point | None = None
    end: Point | None = None
    radius: Annotated[float, _positive("mm")] | None = None
    size: Point | None = None
    axes: list[Direction] | None = None
    file: str | None = None
    hose_side: Direction | None = None


class ContactSection(_Section):
    """[contact]: self-contact, the obstacles the hose may touch, and how the placement meets them."""

    self_contact: bool = Field(False, alias="self")
    placement: str = "bring_in"
    force_accuracy_percent: float | None = None
    obstacles: list[ContactObstacleSection] = Field(default_factory=list)


class ProblemFile(_Section):
    """The whole problem file ([mounts] is resolved into [start] and [end] before this model sees it)."""

    name: str = "hose"
    mounts: MountsSection | None = None
    hose: HoseSection
    start: MountSection
    end: EndSection
    environment: EnvironmentSection = Field(default_factory=EnvironmentSection)
    clips: list[ClipSection] = Field(default_factory=list)
    contact: ContactSection | None = None

    @model_validator(mode="after")
    def _hose_reaches(self) -> "ProblemFile":
        distance = math.dist(self.start.point, self.end.point)
        if not reaches(self.hose.length, distance):
            relation = "is shorter than" if self.hose.length < distance else "is not longer than"
            raise ValueError(
                f"hose.length = {_show(self.hose.length)} mm {relation} the mount distance {distance:g} mm: "
                f"use a hose longer than {distance:g} mm"
            )
        return self


# --- turning pydantic's errors into one line an engineer can act on ---


def _show(value: Any) -> str:
    """A value as the user wrote it in TOML."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_show(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(value) + "}"
    if isinstance(value, str):
        return json.dumps(value)
    return str(value)


def _path(loc: tuple) -> str:
    """A pydantic location as the user writes it: ('start', 'point', 1) -> start.point[1]."""
    text = ""
    for part in loc:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


def _inner_model(annotation) -> type[BaseModel] | None:
    """The model class in an annotation such as Model, list[Model] or Model | None (None if there is none)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for argument in typing.get_args(annotation):
        found = _inner_model(argument)
        if found is not None:
            return found
    return None


def _section_model(model: type[BaseModel], loc: tuple) -> type[BaseModel] | None:
    """The model class of the table at `loc` below `model` (None if `loc` is a plain value).

    List positions (ints, as in bodies[0]) stay in the model of the list's items.
    """
    for part in loc:
        if isinstance(part, int):
            continue
        field = model.model_fields.get(part)
        model = _inner_model(field.annotation) if field else None
        if model is None:
            return None
    return model


def _unknown_key(model: type[BaseModel], loc: tuple, prefix: tuple = ()) -> str:
    """Name the unknown key at `loc` below `model` (which sits at `prefix` in the file) and suggest
    the nearest known one (or list them)."""
    section = _section_model(model, loc[:-1])
    known = [field.alias or name for name, field in section.model_fields.items()] if section else []
    table = _path(prefix + loc[:-1])
    close = difflib.get_close_matches(str(loc[-1]), known, n=1, cutoff=0.6)
    hint = f"did you mean '{table + '.' if table else ''}{close[0]}'?" if close else "allowed keys: " + ", ".join(known)
    return f"unknown key '{_path(prefix + loc)}': {hint}"


_TYPE_REASONS = {
    "float_type": "must be a number",
    "int_type": "must be a whole number",
    "list_type": "must be a list of three numbers, e.g. [0.0, 1.0, 0.0]",
    "string_type": 'must be text in quotes, e.g. "front brake hose"',
    "bool_type": "must be true or false",
}


def _message(error: dict, model: type[BaseModel], prefix: tuple = ()) -> str:
    """One pydantic error of `model` (which sits at `prefix` in the file) as 'field = value: reason'."""
    loc, kind, value = tuple(error["loc"]), error["type"], error.get("input")
    path = _path(prefix + loc)
    if kind == "extra_forbidden":
        return _unknown_key(model, loc, prefix)
    if kind == "missing":
        if _section_model(model, loc):
            return f"missing table [{path}]"
        unit = _UNITS.get(str(loc[-1]))
        return f"missing key '{path}'" + (f" ({unit})" if unit else "")
    if kind == "model_type":
        return f"{path} = {_show(value)}: must be a table [{path}] with its keys below it"
    if kind == "value_error":
        reason = str(error["ctx"]["error"])
        if isinstance(value, dict):  # a rule across several keys: the message names them itself
            return reason
    else:
        reason = _TYPE_REASONS.get(kind, error["msg"])
    return f"{path} = {_show(value)}: {reason}"


def problem_from_dict(data: dict, source: str = "<dict>", base_dir: str | Path | None = None) -> Problem:
    """Validate a parsed problem file and build the Problem.

    data: the file's content as nested dicts (keys and units as in the module docstring).
    source: where the data came from, put in front of error messages (a file name).
    base_dir: directory that a relative [mounts] iges path is taken from (default: the current one).
    Raises ProblemFileError naming the field, the value and the fix.
    """
    if not isinstance(data, dict):
        raise ProblemFileError(f"{source}: expected tables [hose], [start] and [end], got {type(data).__name__}")
    if "mounts" in data:
        data = _with_mounts_from_iges(data, source, Path.cwd() if base_dir is None else Path(base_dir))
    elif isinstance(data.get("clips"), list) and any(isinstance(c, dict) and "tip" in c for c in data["clips"]):
        raise ProblemFileError(f"{source}: clips: a clip named by tip needs the IGES file of [mounts]; "
                               "give point and direction instead, or add [mounts]")
    data, fittings = _with_fittings_resolved(data, source)
    spec = _validated(ProblemFile, data, source)
    bending, torsional = spec.hose.stiffnesses()
    try:
        stiffeners, segments = _stiffeners(spec.hose)
        hose = Hose(
            length=spec.hose.length,
            outer_diameter=spec.hose.outer_diameter,
            bending_stiffness=bending,
            torsional_stiffness=torsional,
            mass_per_length=spec.hose.mass_per_length,
            min_bend_radius=spec.hose.min_bend_radius,
            segments=segments,
            bending_stiffness_2=spec.hose.bending_stiffness_2,
            stiffeners=stiffeners,
            preset=_preset(spec.hose),
            braid=_braid(spec.hose, bending),
        )
        if hose.preset is not None and spec.clips:
            raise ValueError("hose.preset_radius with [[clips]]: a preset hose with clips is not implemented yet; "
                             "remove preset_radius or the clips")
        if stiffeners is not None:  # the 8-spring chord must fit the hose: refused here, not in the solver
            stiffeners.anchors(hose.outer_radius, hose.segment_length, hose.segment_length)
        problem = Problem(
            hose=hose,
            start=Mount(point=spec.start.point, direction=spec.start.direction),
            end=Mount(point=spec.end.point, direction=spec.end.direction),
            end_twist_deg=spec.end.twist,
            gravity=spec.environment.gravity,
            name=spec.name,
            clips=tuple(_clip(index, clip) for index, clip in enumerate(spec.clips)),
            fittings=fittings,
            contact=_contact_obstacles(spec.contact, Path.cwd() if base_dir is None else Path(base_dir)),
            self_contact=spec.contact is not None and spec.contact.self_contact,
            contact_sides=() if spec.contact is None else tuple(table.hose_side for table in spec.contact.obstacles),
            contact_placement="bring_in" if spec.contact is None else spec.contact.placement,
            force_accuracy=_force_accuracy(spec, stiffeners),
        )
        if problem.contact:  # a mount or clip inside an obstacle: no placement exists; said before any solve
            from hoseline.procedures.contact.bring_in import mounts_inside  # the contact model: only with contact

            inside = mounts_inside(problem)
            if inside is not None:
                raise ValueError(f"[contact]: {inside}")
        return problem
    except ValueError as exc:  # the model's own checks; its messages name the field
        raise ProblemFileError(f"{source}: {exc}") from None


def _preset(section: HoseSection) -> Preset | None:
    """The hose's set from storage (model/preset.py), None without preset_radius."""
    if section.preset_radius is None:
        if section.preset_angle_deg is not None:
            raise ValueError(f"hose.preset_angle_deg = {section.preset_angle_deg!r} without preset_radius: "
                             "give preset_radius (mm, radius of the set) or remove preset_angle_deg")
        return None
    return Preset(1.0 / section.preset_radius, section.preset_angle_deg or 0.0)


def _braid(section: HoseSection, bending: float) -> Braid | None:
    """The Braid of [hose.braid] (None without it); refuses a braid a thousand times stiffer in bending than the hose."""
    spec = section.braid
    if spec is None:
        return None
    braid = Braid(spec.angle_deg, spec.strands, spec.strand_axial_stiffness, spec.slack_strain, spec.radius)
    radius = braid.layer_radius(0.5 * section.outer_diameter)
    taut = braid.stiffness * radius**2 * math.cos(math.radians(braid.angle_deg)) ** 3
    largest = limits.STIFFNESS_RATIO[1]
    if taut > largest * bending:
        raise ValueError(
            f"hose.braid.strand_axial_stiffness = {_show(spec.strand_axial_stiffness)} N with strands = {spec.strands} "
            f"gives a taut braid n EA_s r^2 cos^3(angle) = {taut:.3g} N*mm^2, more than {largest:g} times EI = "
            f"{bending:.6g} N*mm^2: give EA of one strand in N (per strand, not per family; N, not N*mm^2)")
    return braid


def _stiffeners(section: HoseSection) -> tuple[Stiffeners | None, int]:
    """The Stiffeners of [hose.stiffeners] (None without it) and the segment count (the preset's with preset)."""
    spec = section.stiffeners
    if spec is None:
        return None, section.segments
    if spec.preset is None:
        table = SpringTable(tuple(pair[0] for pair in spec.table), tuple(pair[1] for pair in spec.table))
        return Stiffeners(spec.springs, spec.angle_deg, table), section.segments
    preset = thesis_preset(section.length, spec.springs)
    if "segments" in section.model_fields_set and section.segments != preset.segments:
        raise ValueError(
            f"hose.segments = {section.segments}: the thesis stiffener preset divides {section.length:g} mm into "
            f"{preset.segments} elements of {preset.element_length:.4f} mm; remove hose.segments or set it to "
            f"{preset.segments}"
        )
    return preset.stiffeners, preset.segments


def _clip(index: int, section: ClipSection) -> Clip:
    """The Clip of a [[clips]] table; its errors name the table."""
    try:
        return Clip(section.type, section.point, section.arc_length, section.direction, section.name, section.twist)
    except ValueError as exc:
        raise ValueError(f"clips[{index}]: {exc}") from None


def _contact_obstacles(section: ContactSection | None, base_dir: Path) -> tuple[Obstacle, ...]:
    """The obstacles of [[contact.obstacles]], named by default after their kind (numbered when repeated); mesh files
    relative to base_dir."""
    if section is None:
        return ()
    kinds = [table.kind for table in section.obstacles]
    counters: dict[str, int] = {}
    obstacles = []
    for index, table in enumerate(section.obstacles):
        counters[table.kind] = counters.get(table.kind, 0) + 1
        default = table.kind if kinds.count(table.kind) == 1 else f"{table.kind} {counters[table.kind]}"
        obstacles.append(_contact_obstacle(index, table, table.name or default, base_dir))
    return tuple(obstacles)


def _contact_obstacle(index: int, table: ContactObstacleSection, name: str, base_dir: Path) -> Obstacle:
    """The Obstacle of one [[contact.obstacles]] table; its errors name the table and the key."""
    label = f"contact.obstacles[{index}]"
    if table.kind not in CONTACT_KEYS:
        raise ValueError(f"{label}.kind = {_show(table.kind)}: must be one of "
                         f"{', '.join(repr(kind) for kind in CONTACT_KEYS)}")
    keys = CONTACT_KEYS[table.kind]
    optional = CONTACT_OPTIONAL_KEYS.get(table.kind, ())
    given = [key for key in ("point", "normal", "center", "start", "end", "radius", "size", "axes", "file")
             if getattr(table, key) is not None]
    missing = [key for key in keys if key not in given]
    extra = [key for key in given if key not in keys + optional]
    if missing or extra:
        problem = f"missing {', '.join(missing)}" if missing else f"{', '.join(extra)} given"
        also = f" (optional: {', '.join(optional)})" if optional else ""
        raise ValueError(f"{label}: a {table.kind} takes {' and '.join(keys)}{also}: {problem}")
    try:
        if table.kind == "plane":
            return Plane(table.point, table.normal, name)
        if table.kind == "sphere":
            return Sphere(table.center, table.radius, name)
        if table.kind == "cylinder":
            return Cylinder(table.start, table.end, table.radius, name)
        if table.kind == "box":
            return Box(table.center, table.size, np.eye(3) if table.axes is None else table.axes, name)
        return _contact_mesh(label, table.file, name, base_dir)
    except ValueError as exc:
        raise ValueError(f"{label}: {exc}") from None


def _contact_mesh(label: str, file: str, name: str, base_dir: Path) -> Mesh:
    """The Mesh of a [[contact.obstacles]] table of kind "mesh", read from `file` (relative to base_dir)."""
    from hoseline.io.obstacle_mesh import ObstacleFileError, read_mesh  # trimesh takes 0.2-0.4 s to load: only for meshes

    path = (base_dir / file).resolve()
    try:
        vertices, faces = read_mesh(path)
    except ObstacleFileError as exc:
        raise ValueError(f"file = {_show(file)}: {exc}") from None
    except OSError as exc:
        raise ValueError(f"file = {_show(file)}: cannot read {path}: {exc.strerror or exc}; give the mesh file's path "
                         "relative to the problem file") from None
    return Mesh(vertices, faces, name, str(path))


def _contact_dict(problem: Problem) -> dict[str, Any]:
    """{"contact": {...}} in the file format, or {} without contact."""
    if not problem.has_contact:
        return {}
    tables = []
    for obstacle in problem.contact:
        if isinstance(obstacle, Plane):
            table = {"kind": "plane", "point": _floats(obstacle.point), "normal": _floats(obstacle.normal)}
        elif isinstance(obstacle, Sphere):
            table = {"kind": "sphere", "center": _floats(obstacle.centre), "radius": float(obstacle.radius)}
        elif isinstance(obstacle, Cylinder):
            table = {"kind": "cylinder", "start": _floats(obstacle.start), "end": _floats(obstacle.end),
                     "radius": float(obstacle.radius)}
        elif isinstance(obstacle, Box):
            table = {"kind": "box", "center": _floats(obstacle.center), "size": _floats(obstacle.size),
                     "axes": [_floats(axis) for axis in obstacle.axes]}
        else:
            table = {"kind": "mesh", "file": obstacle.file}
        side = problem.side_of(obstacle.name)
        tables.append(table | {"name": obstacle.name} | ({} if side is None else {"hose_side": _floats(side)}))
    accuracy = {} if problem.force_accuracy is None else {"force_accuracy_percent": 100.0 * problem.force_accuracy}
    return {"contact": {"self": bool(problem.self_contact), "placement": problem.contact_placement} | accuracy
            | {"obstacles": tables}}


def _force_accuracy(spec: ProblemFile, stiffeners) -> float | None:
    """[contact] force_accuracy_percent as a fraction; by default DEFAULT_FORCE_ACCURACY for obstacles on a hose whose
    file leaves the segment count to the solver (no hose.segments, no stiffener preset), else None."""
    if spec.contact is None:
        return None
    if spec.contact.force_accuracy_percent is not None:
        return spec.contact.force_accuracy_percent / 100.0
    given = "segments" in spec.hose.model_fields_set or stiffeners is not None
    return DEFAULT_FORCE_ACCURACY if spec.contact.obstacles and not given else None


def _with_fittings_resolved(data: dict, source: str) -> tuple[dict, EndFittings | None]:
    """`data` with [fittings] taken out, [start] and [end] moved to the fitting outlets and hose.overall_length
    turned into the free hose.length; and the EndFittings (None without [fittings])."""
    hose = data.get("hose")
    overall = hose.get("overall_length") if isinstance(hose, dict) else None
    if "fittings" not in data and overall is None:
        return data, None
    resolved = dict(data)
    spec = _validated(FittingsSection, resolved.pop("fittings", {}), source, ("fittings",))
    if isinstance(hose, dict) and "overall_length" in hose:
        if "length" in hose:
            raise ProblemFileError(f"{source}: hose: both length and overall_length are given: keep one (length = the "
                                   "free hose between the fittings, overall_length = the catalogue's, fittings included)")
        overall = _validated(_OverallLength, {"overall_length": hose["overall_length"]}, source, ("hose",)).overall_length
    ports = [_validated(section, data.get(name), source, (name,)) if name in data else None
             for name, section in (("start", MountSection), ("end", EndSection))]
    if None in ports:  # a missing [start] or [end]: the whole file's check names it
        _validated(ProblemFile, resolved, source)
    built = {}
    for name in ("start", "end"):
        section = getattr(spec, name)
        try:
            built[name] = None if section is None else Fitting(
                section.length, section.bend_angle, section.outlet_length, section.bend_radius, section.clocking,
                section.reference, section.outer_diameter)
        except ValueError as exc:
            raise ProblemFileError(f"{source}: fittings.{name}: {exc}") from None
    try:
        fittings = EndFittings(Mount(ports[0].point, ports[0].direction), Mount(ports[1].point, ports[1].direction),
                               built["start"], built["end"])
        outlets = fittings.outlets()
    except ValueError as exc:
        raise ProblemFileError(f"{source}: fittings: {exc}") from None
    if overall is not None:
        free = fittings.free_length(overall)
        if not free > 0.0:
            raise ProblemFileError(
                f"{source}: hose.overall_length = {_show(overall)} mm is not longer than the {fittings.length_allowance:g} "
                f"mm the fittings take up: give an overall_length above {fittings.length_allowance:g} mm, or shorter fittings")
        resolved["hose"] = {key: value for key, value in hose.items() if key != "overall_length"} | {"length": free}
    free = resolved["hose"].get("length") if isinstance(resolved.get("hose"), dict) else None
    gap = math.dist(outlets[0].point, outlets[1].point)
    if isinstance(free, (int, float)) and not reaches(free, gap):
        allowance = fittings.length_allowance
        given = (f"hose.overall_length = {_show(overall)} mm leaves a free length of {free:g} mm"
                 if overall is not None else f"hose.length = {_show(free)} mm (the free length)")
        raise ProblemFileError(
            f"{source}: {given}, not longer than the {gap:g} mm between the fitting outlets: give an overall_length "
            f"above {gap + allowance:g} mm (a length above {gap:g} mm), or shorter fittings")
    resolved["start"] = {"point": _floats(outlets[0].point), "direction": _floats(outlets[0].direction)}
    resolved["end"] = {**data["end"], "point": _floats(outlets[1].point), "direction": _floats(outlets[1].direction)}
    return resolved, fittings if fittings.pieces() else None


def _validated(
    model: type[BaseModel], data: Any, source: str, loc: tuple = (), error: type[ValueError] = ProblemFileError
) -> Any:
    """`model` validated from `data` (found at `loc` in the file), or `error` with the first problem."""
    try:
        return model.model_validate(data)
    except pydantic.ValidationError as exc:
        # an unknown key first: a misspelt key also shows up as a missing one
        errors = sorted(exc.errors(), key=lambda item: item["type"] != "extra_forbidden")
        more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
        raise error(f"{source}: {_message(errors[0], model, loc)}{more}") from None


def _with_mounts_from_iges(data: dict, source: str, base_dir: Path) -> dict:
    """`data` with [mounts] replaced by the [start] and [end] points and directions read from its IGES file."""
    from hoseline.io import iges_mounts  # imports OpenCASCADE (about a second): only when a file needs it

    mounts = _validated(MountsSection, data["mounts"], source, ("mounts",))
    end = data.get("end", {})
    given = ["start"] if "start" in data else []
    given += [f"end.{key}" for key in ("point", "direction") if isinstance(end, dict) and key in end]
    if given:
        raise ProblemFileError(
            f"{source}: {' and '.join(given)} given together with [mounts]: the mounts come from {mounts.iges}; "
            "remove " + ", ".join(given) + " (keep [end] twist), or remove [mounts]"
        )
    labels = {"start": iges_mounts.THESIS_START, "end": iges_mounts.THESIS_END}
    for name in labels:
        fitting = getattr(mounts, name)
        try:
            labels[name] = iges_mounts.FittingLabels(**fitting.model_dump()) if fitting else labels[name]
        except ValueError as exc:
            raise ProblemFileError(f"{source}: mounts.{name}: {exc}") from None
    path = base_dir / mounts.iges
    try:
        start, end_mount = iges_mounts.mounts_from_iges(path, labels["start"], labels["end"])
    except iges_mounts.IgesError as exc:
        raise ProblemFileError(f"{source}: mounts.iges: {exc}") from None
    except OSError as exc:
        reason = exc.strerror or exc
        raise ProblemFileError(f"{source}: mounts.iges = {_show(mounts.iges)}: cannot read {path}: {reason}") from None
    resolved = {key: value for key, value in data.items() if key != "mounts"}
    resolved["start"] = {"point": _floats(start.point), "direction": _floats(start.direction)}
    if isinstance(data.get("clips"), list):
        resolved["clips"] = _clips_from_iges(data["clips"], path, source)
    if isinstance(end, dict):
        resolved["end"] = {**end, "point": _floats(end_mount.point), "direction": _floats(end_mount.direction)}
    return resolved


def _clips_from_iges(clips: list, path: Path, source: str) -> list:
    """The [[clips]] tables with `tip` (and `behind` or `ahead`) replaced by the point and direction read
    from the IGES file of [mounts]; tables without `tip` are left as they are."""
    from hoseline.io import iges_mounts

    labels, where = [], []
    for index, clip in enumerate(clips):
        if not isinstance(clip, dict) or "tip" not in clip:
            continue
        given = [key for key in ("point", "direction") if key in clip]
        if given:
            raise ProblemFileError(f"{source}: clips[{index}]: {' and '.join(given)} given together with tip: "
                                   f"the clip comes from the IGES file; remove {', '.join(given)} or tip")
        axis = {key: clip[key] for key in ("behind", "ahead") if key in clip}
        try:
            labels.append(iges_mounts.FittingLabels(tip=clip["tip"], **axis) if axis else str(clip["tip"]))
        except ValueError as exc:
            raise ProblemFileError(f"{source}: clips[{index}]: {exc}") from None
        where.append(index)
    if not labels:
        return clips
    try:
        read = iges_mounts.clip_points_from_iges(path, labels)
    except iges_mounts.IgesError as exc:
        raise ProblemFileError(f"{source}: clips: {exc}") from None
    resolved = list(clips)
    for index, (point, direction) in zip(where, read):
        table = {key: value for key, value in clips[index].items() if key not in ("tip", "behind", "ahead")}
        table["point"] = _floats(point)
        if direction is not None:
            table["direction"] = _floats(direction)
        resolved[index] = table
    return resolved


def load_problem(path: str | Path) -> Problem:
    """Read a TOML problem file.

    path: the file; its stem is the problem name unless the file gives `name`.
    Raises ProblemFileError for invalid content (with the TOML line for syntax errors, and
    for a [mounts] IGES file that cannot give the mounts) and OSError (e.g.
    FileNotFoundError) when the problem file itself cannot be read.
    """
    path = Path(path)
    return problem_from_dict(read_toml(path, ProblemFileError), source=str(path), base_dir=path.parent)


def read_toml(path: Path, error: type[ValueError]) -> dict:
    """The parsed TOML file, with `name` defaulting to the file's stem.

    error: the exception class raised (with the path and the TOML line) for invalid content;
    OSError propagates when the file cannot be read.
    """
    with path.open("rb") as stream:
        try:
            data = tomllib.load(stream)
        except tomllib.TOMLDecodeError as exc:
            raise error(f"{path}: not valid TOML: {exc}") from None
        except UnicodeDecodeError:
            raise error(f"{path}: not UTF-8 text: save the file as UTF-8") from None
        except RecursionError:  # the parser recurses once per level of arrays or inline tables within each other
            data = None
    if data is None or _nesting(data) > MAX_NESTING:
        raise error(f"{path}: arrays or tables nested more than {MAX_NESTING} levels deep (a hoseline file nests a few: "
                    "a table of points in an array of tables): not a hoseline file, or a damaged one")
    data.setdefault("name", path.stem)
    return data


def _nesting(data: dict) -> int:
    """How many levels of tables and arrays `data` holds within each other (a flat table: 1), counted without
    recursion."""
    deepest, pending = 0, [(data, 1)]
    while pending:
        value, level = pending.pop()
        deepest = max(deepest, level)
        if level <= MAX_NESTING:  # deeper is refused whatever lies below
            items = value.values() if isinstance(value, dict) else value
            pending.extend((item, level + 1) for item in items if isinstance(item, (dict, list)))
    return deepest


def problem_to_dict(problem: Problem, poisson_ratio: float | None = None) -> dict:
    """The problem in the file format, with EI and GJ explicit (for result.json and problem.toml).

    problem_from_dict(problem_to_dict(p)) rebuilds p.  poisson_ratio: given, the torsion is
    written as torsion_factor = GJ / (EI / (1 + poisson_ratio)) with that poisson_ratio instead
    of GJ (as `calibrate` reports the factor).
    """
    hose = problem.hose
    torsion = {"torsional_stiffness": float(hose.torsional_stiffness)} if poisson_ratio is None else {
        "torsion_factor": float(hose.torsional_stiffness / isotropic_torsional_stiffness(hose.bending_stiffness,
                                                                                         poisson_ratio)),
        "poisson_ratio": float(poisson_ratio)}
    hose_dict: dict[str, Any] = {
        "length": float(hose.length),
        "outer_diameter": float(hose.outer_diameter),
        "bending_stiffness": float(hose.bending_stiffness),
        **torsion,
        "mass_per_length": float(hose.mass_per_length),
        "segments": int(hose.segments),
    }
    if hose.bending_stiffness_2 is not None:
        hose_dict["bending_stiffness_2"] = float(hose.bending_stiffness_2)
    if hose.min_bend_radius is not None:
        hose_dict["min_bend_radius"] = float(hose.min_bend_radius)
    if hose.preset is not None and hose.preset.curvature > 0.0:
        hose_dict["preset_radius"] = float(hose.preset.radius)
        hose_dict["preset_angle_deg"] = float(hose.preset.angle_deg)
    if hose.braid is not None:
        braid = hose.braid
        hose_dict["braid"] = {
            "angle_deg": float(braid.angle_deg),
            "strands": int(braid.strands),
            "strand_axial_stiffness": float(braid.strand_axial_stiffness),
            "slack_strain": float(braid.slack_strain),
        } | ({} if braid.radius is None else {"radius": float(braid.radius)})
    if hose.stiffeners is not None:  # written out explicitly (a preset's angle and table included)
        stiffeners = hose.stiffeners
        hose_dict["stiffeners"] = {
            "springs": int(stiffeners.springs),
            "angle_deg": float(stiffeners.angle_deg),
            "table": [[float(x), float(f)] for x, f in zip(stiffeners.table.deformation, stiffeners.table.force)],
        }
    # with fittings, [start] and [end] are the ports and hose.length the free length
    start, end = (problem.fittings.start_port, problem.fittings.end_port) if problem.fittings else (problem.start, problem.end)
    return {
        "name": problem.name,
        "hose": hose_dict,
        "start": {"point": _floats(start.point), "direction": _floats(start.direction)},
        "end": {
            "point": _floats(end.point),
            "direction": _floats(end.direction),
            "twist": float(problem.end_twist_deg),
        },
        "environment": {"gravity": _floats(problem.gravity)},
    } | ({"clips": [_clip_dict(clip) for clip in problem.clips]} if problem.clips else {}) | _fittings_dict(problem) \
      | _contact_dict(problem)


def _fittings_dict(problem: Problem) -> dict[str, Any]:
    """{"fittings": {"start": ..., "end": ...}} in the file format, or {} without fittings."""
    if problem.fittings is None:
        return {}
    tables = {}
    for name, _, fitting in problem.fittings.pieces():
        table: dict[str, Any] = {"length": float(fitting.length)}
        if fitting.bend_angle_deg:
            table |= {"bend_angle": float(fitting.bend_angle_deg), "outlet_length": float(fitting.outlet_length),
                      "bend_radius": float(fitting.bend_radius), "clocking": float(fitting.clocking_deg),
                      "reference": _floats(fitting.reference)}
        if fitting.outer_diameter is not None:
            table["outer_diameter"] = float(fitting.outer_diameter)
        tables[name] = table
    return {"fittings": tables}


def _clip_dict(clip: Clip) -> dict[str, Any]:
    out: dict[str, Any] = {"type": clip.kind, "arc_length": float(clip.arc_length), "point": _floats(clip.point)}
    if clip.direction is not None:
        out["direction"] = _floats(clip.direction)
    return out | ({"name": clip.name} if clip.name else {}) | ({"twist": float(clip.twist_deg)} if clip.twist_deg else {})


def _floats(vector: np.ndarray) -> list[float]:
    return [float(v) for v in vector]


def problem_to_toml(problem: Problem, poisson_ratio: float | None = None) -> str:
    """The problem as a commented TOML problem file that load_problem reads back.

    poisson_ratio: given, the torsion is written as torsion_factor with it (problem_to_dict)."""
    lines = []
    for key, value in problem_to_dict(problem, poisson_ratio).items():
        tables = [value] if isinstance(value, dict) else value if isinstance(value, list) and key == "clips" else None
        headers = [f"[{key}]" if isinstance(value, dict) else f"[[{key}]]"] * len(tables or [])
        if key == "fittings":  # a table of tables: [fittings.start], [fittings.end]
            headers, tables = [f"[{key}.{end}]" for end in value], list(value.values())
        if tables is not None:
            for header, table in zip(headers, tables):
                lines.append(f"\n{header}")
                nested = {name: item for name, item in table.items() if isinstance(item, dict)}
                arrays = {name: item for name, item in table.items()  # tables inside this one: [[contact.obstacles]]
                          if isinstance(item, list) and item and all(isinstance(entry, dict) for entry in item)}
                for name, item in table.items():
                    if name not in nested and name not in arrays:
                        text = f"{name} = {_toml_value(item)}"
                        lines.append(f"{text:<45} # {_UNITS.get(f'{key}.{name}', _UNITS.get(name))}")
                for name, inner in nested.items():  # a table inside this one: [hose.stiffeners], [hose.braid]
                    lines.append(f"\n[{key}.{name}]")
                    for inner_name, item in inner.items():
                        text = f"{inner_name} = {_toml_value(item)}"
                        lines.append(f"{text:<45} # {_UNITS.get(f'{name}.{inner_name}', _UNITS.get(inner_name))}")
                for name, entries in arrays.items():
                    for entry in entries:
                        lines.append(f"\n[[{key}.{name}]]")
                        for inner_name, item in entry.items():
                            text = f"{inner_name} = {_toml_value(item)}"
                            lines.append(f"{text:<45} # {_UNITS.get(f'{name}.{inner_name}', _UNITS.get(inner_name))}")
        else:
            lines.append(f"{key} = {_toml_value(value)}")
    return "\n".join(lines) + "\n"


def _toml_value(value: Any) -> str:
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)  # a JSON string is a valid TOML basic string
    return repr(value)  # int, or float in the shortest form that reads back exactly
