"""The braid of a hose as a continuous stiffness term: two families of tension-only strands at +-beta.

A braided hose's reinforcement is two families of strands wound in opposite senses at the braid
angle beta to the hose axis.  A strand carries tension only, and only once stretched beyond its
slack strain eps0 (the play of the braid on the liner).  Twisting the hose stretches one family
and slackens the other: a hose bent less than the slack bends stiffer once twisted beyond it (the
stretched family taut all round), while a hose bent beyond the slack feels twist only at second
order (docs/model.md, "The continuous counterpart").
The solver's term is mechanics/braid.py.  Units: mm, N, degrees at this boundary.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

LARGEST_ANGLE_DEG = 89.0  # beta beyond this: strands round the hose, which add nothing to bending or twist


@dataclass(frozen=True)
class Braid:
    """Two families of strands at +-angle_deg to the hose axis.

    angle_deg: beta, degrees from the hose axis, [0, 89].  strands: per family (the braid has
    2 x strands carriers).  strand_axial_stiffness: EA_s of one strand, N.  slack_strain: eps0,
    the strain a strand takes before it carries tension (dimensionless, >= 0).  radius: mm, of the
    braid layer; None for the hose's outer radius.
    """

    angle_deg: float
    strands: int
    strand_axial_stiffness: float
    slack_strain: float = 0.0
    radius: float | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.angle_deg) and 0.0 <= self.angle_deg <= LARGEST_ANGLE_DEG):
            raise ValueError(f"hose.braid.angle_deg = {self.angle_deg!r}: must lie in [0, {LARGEST_ANGLE_DEG:g}] "
                             "degrees from the hose axis")
        if int(self.strands) != self.strands or self.strands < 1:
            raise ValueError(f"hose.braid.strands = {self.strands!r}: must be a whole number >= 1 (per family)")
        if not (math.isfinite(self.strand_axial_stiffness) and self.strand_axial_stiffness > 0.0):
            raise ValueError(f"hose.braid.strand_axial_stiffness = {self.strand_axial_stiffness!r}: must be a "
                             "positive finite number (EA of one strand, N)")
        if not (math.isfinite(self.slack_strain) and self.slack_strain >= 0.0):
            raise ValueError(f"hose.braid.slack_strain = {self.slack_strain!r}: must be zero or a positive finite "
                             "number (strain, dimensionless)")
        if self.radius is not None and not (math.isfinite(self.radius) and self.radius > 0.0):
            raise ValueError(f"hose.braid.radius = {self.radius!r}: must be a positive finite number (mm)")

    @property
    def stiffness(self) -> float:
        """n EA_s, N: the axial stiffness of one family's strands together (what calibration fits)."""
        return self.strands * self.strand_axial_stiffness

    def layer_radius(self, outer_radius: float) -> float:
        """The braid's radius, mm: its own, or the hose's outer radius (mm) when none is given."""
        return outer_radius if self.radius is None else self.radius
