"""The hose: geometry, stiffness, weight and the limits a catalogue gives.

Units are those of a hose catalogue: lengths in mm, stiffness in N*mm^2,
mass per length in kg/m.  Everything here is plain data; the checks that give
user-facing messages live in :mod:`hoseline.io.problem_file`, but the
constructors below refuse values no hose can have, so the solver never sees them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hoseline.model.braid import Braid
from hoseline.model.preset import Preset
from hoseline.model.stiffeners import Stiffeners

DEFAULT_SEGMENTS = 100
MIN_SEGMENTS = 4
DEFAULT_POISSON_RATIO = 0.5


def isotropic_torsional_stiffness(bending_stiffness: float, poisson_ratio: float = DEFAULT_POISSON_RATIO) -> float:
    """Torsional stiffness GJ of an isotropic round section with the given EI.

    For a circular (or annular) section J = 2 I and G = E / (2 (1 + nu)), so
    GJ = EI / (1 + nu).

    bending_stiffness: EI in N*mm^2.  poisson_ratio: nu, dimensionless.
    Returns N*mm^2.
    """
    return bending_stiffness / (1.0 + poisson_ratio)


def bending_stiffness_from_modulus(youngs_modulus: float, outer_diameter: float, inner_diameter: float = 0.0) -> float:
    """EI of an annular section: E * pi * (Do^4 - Di^4) / 64.

    youngs_modulus: N/mm^2 (MPa).  outer_diameter, inner_diameter: mm.
    Returns N*mm^2.
    """
    return youngs_modulus * math.pi * (outer_diameter**4 - inner_diameter**4) / 64.0


@dataclass(frozen=True)
class Hose:
    """A hose of exact length with its section properties.

    length: mm, centreline length between the two fitting tips.
    outer_diameter: mm.
    bending_stiffness: EI in N*mm^2 about the section's first axis (d1).
    torsional_stiffness: GJ in N*mm^2.
    mass_per_length: kg/m (as catalogues give it); 0 for a weightless hose.
    min_bend_radius: mm, catalogue minimum, measured to the inside of the bend; None if unknown.
    segments: number of rigid segments of the discrete rod (>= 4).
    bending_stiffness_2: EI in N*mm^2 about the second axis (d2); None means equal to bending_stiffness.
    stiffeners: the thesis' off-axis springs between adjacent segments (model/stiffeners.py),
        added to the elastic joints; None (default) for the plain rod.
    preset: the set from storage, a natural curvature (model/preset.py); None (default) for a
        hose that is straight when unloaded.
    braid: the braid's tension-only strands as a stiffness term (model/braid.py), added to the
        elastic joints; None (default) for none.
    """

    length: float
    outer_diameter: float
    bending_stiffness: float
    torsional_stiffness: float
    mass_per_length: float = 0.0
    min_bend_radius: float | None = None
    segments: int = DEFAULT_SEGMENTS
    bending_stiffness_2: float | None = None
    stiffeners: Stiffeners | None = None
    preset: Preset | None = None
    braid: Braid | None = None

    def __post_init__(self) -> None:
        for name in ("length", "outer_diameter", "bending_stiffness", "torsional_stiffness"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"hose.{name} = {value!r}: must be a positive finite number")
        if self.bending_stiffness_2 is not None and not (
            math.isfinite(self.bending_stiffness_2) and self.bending_stiffness_2 > 0.0
        ):
            raise ValueError(f"hose.bending_stiffness_2 = {self.bending_stiffness_2!r}: must be a positive finite number")
        if not (math.isfinite(self.mass_per_length) and self.mass_per_length >= 0.0):
            raise ValueError(f"hose.mass_per_length = {self.mass_per_length!r}: must be zero or positive (kg/m)")
        if self.min_bend_radius is not None and not (math.isfinite(self.min_bend_radius) and self.min_bend_radius >= 0):
            raise ValueError(f"hose.min_bend_radius = {self.min_bend_radius!r}: must be zero or positive (mm)")
        if int(self.segments) != self.segments or self.segments < MIN_SEGMENTS:
            raise ValueError(f"hose.segments = {self.segments!r}: must be a whole number >= {MIN_SEGMENTS}")
        if self.stiffeners is not None and not isinstance(self.stiffeners, Stiffeners):
            raise ValueError(f"hose.stiffeners = {self.stiffeners!r}: must be a Stiffeners or None")
        if self.preset is not None and not isinstance(self.preset, Preset):
            raise ValueError(f"hose.preset = {self.preset!r}: must be a Preset or None")
        if self.preset is not None and self.stiffeners is not None:
            raise ValueError("hose.preset with hose.stiffeners: the stiffener springs have no preset; give one of them")
        if self.braid is not None and not isinstance(self.braid, Braid):
            raise ValueError(f"hose.braid = {self.braid!r}: must be a Braid or None")
        if self.braid is not None and self.stiffeners is not None:
            raise ValueError("[hose.braid] with [hose.stiffeners]: both model the braid (the springs discretely); "
                             "give one of them")
        if self.braid is not None and self.braid.radius is not None and self.braid.radius > self.outer_radius:
            raise ValueError(f"hose.braid.radius = {self.braid.radius!r} mm is outside the hose (outer radius "
                             f"{self.outer_radius:g} mm): give the braid's mean radius, at most the outer radius")

    @property
    def outer_radius(self) -> float:
        """Outer radius in mm."""
        return 0.5 * self.outer_diameter

    @property
    def segment_length(self) -> float:
        """Length of one rigid segment in mm."""
        return self.length / self.segments

    @property
    def stiffness_vector(self) -> np.ndarray:
        """(EI1, EI2, GJ) in N*mm^2, in the material frame (d1, d2, d3)."""
        second = self.bending_stiffness if self.bending_stiffness_2 is None else self.bending_stiffness_2
        return np.array([self.bending_stiffness, second, self.torsional_stiffness], dtype=float)

    @property
    def torsion_factor(self) -> float:
        """GJ divided by the isotropic value EI/(1+nu) with nu = 0.5."""
        return self.torsional_stiffness / isotropic_torsional_stiffness(self.bending_stiffness)

    def line_weight(self, gravity_m_per_s2: float) -> float:
        """Weight per length in N/mm for a gravity magnitude in m/s^2 (kg/m * m/s^2 = N/m = 1e-3 N/mm)."""
        return self.mass_per_length * gravity_m_per_s2 * 1e-3
