"""The thesis' off-axis spring stiffeners (Thomas 2004, chapters III and IV): geometry, force tables, preset.

Between every two adjacent hose elements, springs run on the hose surface at the spring
angle to the section plane (the thesis' "horizontal"), mimicking the braided strands of
the hose.  Each spring reaches from the centre of one element to the centre of the next
(one element length along the axis) and len_h = element / tan(angle) around it, so its
free length is element / sin(angle).  A piecewise-linear table gives its force against
its deformation (tension positive), extrapolated linearly.

Geometry (equations 9-16):
- 8 springs: four crossing pairs on the hose radius R, centred at 45, 135, 225 and 315 deg;
  each pair spans the chord len_h, i.e. the half angle ang_top = asin(len_h / 2 / R)
  (equations 9-12).
- 16 springs: a crossing pair on each side of an octagon whose side is len_h, so its
  circumradius is rad = len_h / (2 cos(b_angle)), b_angle = (180 - 45) / 2 deg
  (equations 13-16); the octagon is not tied to the hose radius.

Preset (chapter IV): the hose length is divided into an integer number of elements of
8.17-8.4122 mm; the spring angle follows equation 17 for elements up to 8.2454 mm and is
71 deg above; the deformation breakpoints follow equations 18-28 from the spring length
and the forces are those of Table 6 (0, 0, 0, 2500, 2501, 2503, 2504, 2600, 4000, 6000,
8000 N), for hose lengths 277.8-2474 mm.  Units: mm, N, degrees.

What the thesis' OCR does not settle (listed in docs/model.md, "Stiffener springs"; nothing is guessed):
- equation 26 prints "6.20050 x sp_len" without the square; the square is restored because
  only then it gives Table 6 (x9 = 2.01 mm at 8.6688 mm, against 2.02; without it 414 mm);
- equation 17 as printed gives 0.12-0.16 deg more than Table 6 at each of its five rows and
  80.36 deg at 8.4122 mm where the text says 80.21 deg: its coefficients are rounded (234.48
  +-0.005 alone moves the angle by 0.34 deg); used as printed;
- Table 6's 73 deg row: spring length 8.571 mm, but 8.2195 mm / sin 73 deg = 8.5951 mm (the
  other four rows agree with element / sin(angle) to 6e-4 mm); equations 20-28 fit 8.571;
- Table 11 (element 8.4122 mm "at 71 deg"): its spring length 8.70895 mm is 8.4122 / sin 75 deg;
  at 71 deg it would be 8.8969 mm.  The preset uses 71 deg, as the text says;
- Table 10's last row (every length of 277.8-2474 mm divisible into elements of 8.17-8.4122 mm)
  is reproduced; its other rows (656, 201, 52, 11 lengths left over for upper limits 8.3-8.41
  mm) are not (exact division leaves 544, 178, 30, 0): the search (steps of 0.00001 mm,
  "rounding off value" +-0.0002) is not described fully enough to repeat;
- the spring tables of Figures 13, 18, 22 and 24 (8 springs, early 16 springs, 52 deg) are not
  readable: Figure 22 shows 11 deformations and 14 forces, Figure 24 its deformations only,
  partly garbled; Figure 13 four numbers without their column.  The units of the tables are
  not stated beyond "Force values (Newton)" in Table 6: see table_read_as and the units
  study in docs/model.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

SPRING_COUNTS = (8, 16)
PRESETS = ("thesis",)  # the problem file's hose.stiffeners.preset values: "thesis" is thesis_preset()

# Chapter IV: element sizes, the range of the regression (equation 17) and the preset's hose lengths, mm
ELEMENT_MIN, ELEMENT_REGRESSION_MAX, ELEMENT_MAX = 8.17, 8.2454, 8.4122
PRESET_LENGTHS = (277.8, 2474.0)
ANGLE_ABOVE_REGRESSION_DEG = 71.0

# Table 6 (forces identical for all spring angles 71-75 deg; Figure 27 shows the same with opposite sign), N
THESIS_FORCES = (0.0, 0.0, 0.0, 2500.0, 2501.0, 2503.0, 2504.0, 2600.0, 4000.0, 6000.0, 8000.0)


@dataclass(frozen=True)
class SpringTable:
    """Force against deformation of one spring, piecewise linear with linear extrapolation.

    deformation: mm, strictly increasing; negative is compression, positive tension.
    force: N, one per deformation; positive pulls the two anchors together.
    """

    deformation: tuple[float, ...]
    force: tuple[float, ...]

    def __post_init__(self) -> None:
        x = np.asarray(self.deformation, dtype=float)
        y = np.asarray(self.force, dtype=float)
        if x.ndim != 1 or x.size < 2 or x.shape != y.shape:
            raise ValueError(
                f"spring table: {x.size} deformations and {y.size} forces: give at least two pairs of equal count"
            )
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            raise ValueError("spring table: deformations and forces must be finite numbers")
        if np.any(np.diff(x) <= 0.0):
            raise ValueError(f"spring table: deformations {list(x)} must be strictly increasing (mm)")
        object.__setattr__(self, "deformation", tuple(float(v) for v in x))
        object.__setattr__(self, "force", tuple(float(v) for v in y))

    def force_at(self, deformation) -> np.ndarray:
        """Force in N at deformations in mm, extrapolated linearly beyond the table."""
        x, y = np.asarray(self.deformation), np.asarray(self.force)
        d = np.asarray(deformation, dtype=float)
        inside = np.interp(d, x, y)
        low = y[0] + (y[1] - y[0]) / (x[1] - x[0]) * (d - x[0])
        high = y[-1] + (y[-1] - y[-2]) / (x[-1] - x[-2]) * (d - x[-1])
        return np.where(d < x[0], low, np.where(d > x[-1], high, inside))


@dataclass(frozen=True)
class Stiffeners:
    """Off-axis springs between adjacent hose elements.

    springs: 8 or 16 per pair of adjacent elements.
    angle_deg: spring angle to the section plane, degrees (90: along the axis).
    table: force-deformation table of each spring.
    """

    springs: int
    angle_deg: float
    table: SpringTable

    def __post_init__(self) -> None:
        if self.springs not in SPRING_COUNTS:
            raise ValueError(f"hose.stiffeners.springs = {self.springs!r}: the thesis geometry has 8 or 16 springs")
        if not (math.isfinite(self.angle_deg) and 0.0 < self.angle_deg <= 90.0):
            raise ValueError(f"hose.stiffeners.angle_deg = {self.angle_deg!r}: must lie in (0, 90] degrees")

    def chord(self, element_length: float) -> float:
        """len_h = element / tan(angle): how far round the hose a spring reaches, mm (equations 9 and 14)."""
        return element_length / math.tan(math.radians(self.angle_deg))

    def spring_circle_radius(self, hose_radius: float, element_length: float) -> float:
        """Radius of the circle the anchors lie on, mm: the hose radius (8 springs) or the octagon's (16)."""
        if self.springs == 8:
            return hose_radius
        b_angle = math.radians((180.0 - 360.0 / 8) / 2.0)  # equation 15
        return self.chord(element_length) / (2.0 * math.cos(b_angle))  # equation 16

    def anchors(self, hose_radius: float, element_length: float, axial_span: float) -> np.ndarray:
        """Anchor points of every spring in the frames of its two elements, relative to their shared node.

        hose_radius: mm.  element_length: mm, sets the chord and so the anchor angles.
        axial_span: mm between the two anchors along the axis (an element length; half of
        it where an element meets a fitting).
        Returns (springs, 2, 3): [j, 0] on the element before the node, [j, 1] on the one
        after it, as (x, y, z) in the element's frame (z along the hose).
        """
        chord = self.chord(element_length)
        radius = self.spring_circle_radius(hose_radius, element_length)
        if self.springs == 8:
            if chord > 2.0 * radius:
                raise ValueError(
                    f"hose.stiffeners.angle_deg = {self.angle_deg:g}: the chord {chord:.3g} mm exceeds the hose diameter "
                    f"{2 * radius:.3g} mm for elements of {element_length:.4g} mm; use a steeper spring angle"
                )
            half = math.asin(0.5 * chord / radius)  # ang_top, equation 9
            # final_ang = 45 deg - ang_top (equation 10) for each of the four pairs, measured from y towards x
            pairs = [(centre - half, centre + half) for centre in np.radians([45.0, 135.0, 225.0, 315.0])]
        else:
            step = 2.0 * math.pi / 8
            pairs = [(k * step, (k + 1) * step) for k in range(8)]
        out = np.empty((self.springs, 2, 3))
        for index, (first, second) in enumerate(pairs):
            for j, (on_a, on_b) in enumerate(((first, second), (second, first))):  # the crossing pair
                out[2 * index + j, 0] = (radius * math.sin(on_a), radius * math.cos(on_a), -0.5 * axial_span)
                out[2 * index + j, 1] = (radius * math.sin(on_b), radius * math.cos(on_b), 0.5 * axial_span)
        return out


def element_count(length: float) -> int:
    """The thesis' element-size rule: a whole number of elements of 8.17-8.4122 mm for a hose of `length` mm.

    Prefers elements within the regression's range (up to 8.2454 mm, the largest such), else
    the smallest above it.  Raises ValueError outside the preset's 277.8-2474 mm.
    """
    low, high = PRESET_LENGTHS
    if not (low <= length <= high):
        raise ValueError(
            f"hose.length = {length:g} mm: the thesis stiffener preset covers {low:g}-{high:g} mm; "
            "give the stiffeners explicitly for other lengths"
        )
    counts = range(math.ceil(length / ELEMENT_MAX), math.floor(length / ELEMENT_MIN) + 1)
    in_regression = [n for n in counts if length / n <= ELEMENT_REGRESSION_MAX]
    if in_regression:
        return min(in_regression)
    if counts:
        return max(counts)
    raise ValueError(f"hose.length = {length:g} mm cannot be divided into elements of {ELEMENT_MIN}-{ELEMENT_MAX} mm")


def spring_angle_deg(element_length: float) -> float:
    """Spring angle for an element size, degrees: equation 17 up to 8.2454 mm, 71 deg above."""
    if element_length > ELEMENT_REGRESSION_MAX:
        return ANGLE_ABOVE_REGRESSION_DEG
    return -16446.9 + 3937.17 * element_length - 234.48 * element_length**2


def thesis_deformations(spring_length: float) -> tuple[float, ...]:
    """Deformation breakpoints x1..x11 (mm) of the spring table for a spring length in mm, equations 18-28.

    Fitted for spring lengths 8.5362-8.6688 mm; other lengths are extrapolated.
    """
    quadratic = 70.8547 * spring_length - 4.07276 * spring_length**2
    x3_to_x8 = [constant + quadratic for constant in (-307.974, -307.964, -307.954, -307.944, -307.934, -307.924)]
    x9 = -464.698 + 107.589 * spring_length - 6.20050 * spring_length**2
    x10 = 585.2 - 137.022 * spring_length + 8.04956 * spring_length**2
    x11 = -2192.54 + 507.583 * spring_length - 29.3037 * spring_length**2
    return (-8.0, 0.0, *x3_to_x8, x9, x10, x11)


FORCE_UNITS_N = {"N": 1.0, "mN": 1e-3}  # a table's force unit in newtons
DEFORMATION_UNITS_MM = {"mm": 1.0, "cm": 10.0, "m": 1e3}  # a table's deformation unit in millimetres
FREE_LENGTHS = ("anchors", "element")  # what a spring's free length is taken to be


def table_read_as(
    table: SpringTable, force_unit: str = "N", deformation_unit: str = "mm", free_length: str = "anchors",
    anchor_distance: float = 0.0, element_length: float = 0.0,
) -> SpringTable:
    """The same table read in other units or with another free length, in mm and N (the units study).

    force_unit: "N" or "mN", the unit the table's forces are taken to be in.
    deformation_unit: "mm", "cm" or "m", the unit of its deformations.
    free_length: "anchors", the spring is free at the distance of its anchors on the straight
    hose (element / sin(angle); the thesis' Figure 27 puts its table's zero there), or
    "element", free at the element length (so on the straight hose every spring is already
    stretched by anchor_distance - element_length, mm).
    anchor_distance, element_length: mm, needed for free_length = "element".
    """
    for name, value, allowed in (("force_unit", force_unit, FORCE_UNITS_N), ("deformation_unit", deformation_unit,
                                 DEFORMATION_UNITS_MM), ("free_length", free_length, FREE_LENGTHS)):
        if value not in allowed:
            raise ValueError(f"{name} = {value!r}: choose one of {', '.join(allowed)}")
    if free_length == "element" and not 0.0 < element_length <= anchor_distance:
        raise ValueError(f"free_length = 'element' needs the anchor distance ({anchor_distance!r} mm) and the element "
                         f"length ({element_length!r} mm), the element no longer than the anchor distance")
    prestretch = anchor_distance - element_length if free_length == "element" else 0.0
    deformation = np.asarray(table.deformation) * DEFORMATION_UNITS_MM[deformation_unit] - prestretch
    return SpringTable(tuple(deformation), tuple(np.asarray(table.force) * FORCE_UNITS_N[force_unit]))


@dataclass(frozen=True)
class StiffenerPreset:
    """The thesis preset for one hose length: elements, spring angle and table.

    segments: element count.  element_length, spring_length: mm.  stiffeners: the springs.
    """

    segments: int
    element_length: float
    spring_length: float
    stiffeners: Stiffeners


def thesis_preset(length: float, springs: int = 16) -> StiffenerPreset:
    """The chapter IV preset for a hose of `length` mm (277.8-2474 mm): equations 17-28 and Table 6."""
    segments = element_count(length)
    element = length / segments
    angle = spring_angle_deg(element)
    spring_length = element / math.sin(math.radians(angle))
    table = SpringTable(thesis_deformations(spring_length), THESIS_FORCES)
    return StiffenerPreset(segments, element, spring_length, Stiffeners(springs, angle, table))
