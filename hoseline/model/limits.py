"""Physically sensible ranges of the inputs, from hose catalogues; the file readers refuse values outside them.

A number outside these ranges is a unit mistake (metres or micrometres for mm), a typo or a
damaged file, not a hose: it is refused at the boundary (problem, sweep and pose-table files,
IGES mounts, obstacle meshes) with a message naming the field and the range, so the solver
never sees 1e300 mm or an allocation sized by it.  Units: mm, N*mm^2, N/mm^2, kg/m, m/s^2, degrees.
"""

from __future__ import annotations

import math

# |coordinate| of mounts, pose translations, stage points and obstacle vertices: 100 m covers any
# vehicle, machine or plant a hose is routed through
COORDINATE_MM = 1e5

# hose length: catalogues sell assemblies from a few mm (micro hose) to 100 m reels
LENGTH_MM = (1.0, 1e5)

# outer diameter: 0.1 mm capillary tube to 2 m dredging hose
OUTER_DIAMETER_MM = (0.1, 2000.0)

# a rod model needs a slender hose: at least this many outer diameters long
SLENDERNESS = 4.0

# EI and GJ: a 1 mm rubber cord (E about 1 N/mm^2: EI about 0.05 N*mm^2) down to 1e-3; a 100 mm steel
# bar (EI about 1e12 N*mm^2) up
STIFFNESS_NMM2 = (1e-3, 1e12)

# Young's modulus: soft gels (1e-3 N/mm^2 = 1 kPa) to tungsten (4e5 N/mm^2)
YOUNGS_MODULUS_NMM2 = (1e-3, 1e6)

# EI over the solid section of the outer diameter, pi d^4 / 64: the Young's modulus a solid rod of that
# diameter would need.  Nothing at hose scale is stiffer than tungsten (4e5 N/mm^2); a lay-flat textile
# fire hose, the limpest hose, is about 3e-5 N/mm^2 (EI 10 N*mm^2 at 50 mm).  Outside: a unit mistake
EFFECTIVE_MODULUS_NMM2 = (1e-6, 1e6)

# GJ over the isotropic EI/(1 + nu), and EI2 over EI: catalogue hoses lie within 0.1-100 (the thesis'
# brake hose 25); beyond 1e-3-1e3 the section is a ribbon or a shaft, not a hose
STIFFNESS_RATIO = (1e-3, 1e3)

# mass per length: up to 1000 kg/m (the heaviest large-bore suction hoses, filled, are a few hundred)
MASS_PER_LENGTH_KG_M = 1e3

# braid strands: EA of one strand from a 0.1 mm polyester yarn (about 1e2 N) down to 1e-3, up to a 10 mm steel
# rope (about 1e7 N); strands per family up to 1000 (a 144-carrier braider with several ends per carrier); a
# slack strain beyond 1 (100 %) is no play of a braid but a unit mistake (percent for a fraction)
BRAID_STRAND_STIFFNESS_N = (1e-3, 1e7)
BRAID_STRANDS = 1000
BRAID_SLACK_STRAIN = 1.0

# |gravity|: up to 100 m/s^2 (10 g), more than any quasi-static load on a vehicle
GRAVITY_M_S2 = 100.0

# twist of the end fitting and rotation stages: ten turns either way
ANGLE_DEG = 3600.0

# segments of the model: 4 at least (the rod needs bending at both ends); 10 000 is finer than any
# hose needs (0.03 mm segments on the thesis hose)
SEGMENTS = (4, 10_000)

# clearance to an obstacle, mm: at most the coordinate range
CLEARANCE_MM = COORDINATE_MM

# intervals of one generated stage
STAGE_STEPS = 10_000

# |travel| of a pose, in its own unit (mm, degrees, s): beyond that it is no travel of a suspension
TRAVEL = 1e9

# a sweep's stations, poses x (segments + 1): each result array (M, N+1, 3) stays below 50 MB
# (1000 poses of a 100-segment hose are 101 000)
SWEEP_STATIONS = 2_000_000

# triangles of all obstacles together (a fine tessellation of a strut is 1e5)
OBSTACLE_TRIANGLES = 5_000_000


def within(value: float, bounds: tuple[float, float]) -> bool:
    """Whether `value` is a finite number in [low, high]."""
    return math.isfinite(value) and bounds[0] <= value <= bounds[1]


def coordinate_within(value: float) -> bool:
    """Whether `value` (mm) is a finite coordinate within +-COORDINATE_MM."""
    return math.isfinite(value) and abs(value) <= COORDINATE_MM
