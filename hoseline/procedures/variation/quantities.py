"""The quantities a study judges, and the limits they are judged against.

Every sample, placement or sweep, is read as a sequence of poses (one for a placement): per
pose the smallest inside bend radius, the largest twisting moment, the torque on the end
fitting about its axis and the clearance to each obstacle.  A quantity is the worst of these
over the poses:

    clearance:NAME  mm     smallest distance from the hose surface to obstacle NAME   (limit: at least)
    bend_radius     mm     smallest inside bend radius                                (limit: at least)
    end_torque      N*mm   largest torque on the end fitting about its axis           (limit: at most)
    twist_rate      deg/mm largest rate of twist, twisting moment / GJ                (limit: at most)
    force:SUPPORT   N      largest magnitude of the force of SUPPORT on the hose      (limit: at most)
    moment:SUPPORT  N*mm   largest magnitude of the moment of SUPPORT on the hose,    (limit: at most)
                           about its point (supports holding a direction only)
    deviation       mm     largest distance of a station from the nominal hose's      (limit: at most)
                           station of the same index (same fraction of the length), at the same pose

A SUPPORT is "start" or "end" (the mounts) or "clips[k]" (clip k of the problem, from 0); a ball clip holds
no direction and has no moment (reaction_supports).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

LOWER = "at least"
UPPER = "at most"

HEALTH = {
    "bend_radius": ("mm", LOWER, "smallest inside bend radius"),
    "end_torque": ("N*mm", UPPER, "largest torque on the end fitting about its axis"),
    "twist_rate": ("deg/mm", UPPER, "largest rate of twist (twisting moment / GJ)"),
}
DEVIATION = ("mm", UPPER, "largest distance from the nominal shape")
CLEARANCE = "clearance:"
FORCE = "force:"
MOMENT = "moment:"


@dataclass(frozen=True)
class Quantity:
    """A judged quantity: name (see the module doc), unit, sense (LOWER: a limit is a minimum), description."""

    name: str
    unit: str
    sense: str
    description: str


def quantities(obstacle_names: tuple[str, ...], force_supports: tuple[str, ...] = (),
               moment_supports: tuple[str, ...] = ()) -> tuple[Quantity, ...]:
    """The quantities of a study with these obstacles and supports (reaction_supports), in the order samples store
    them: clearances, bend radius, end torque, twist rate, forces, moments, deviation."""
    clearances = tuple(Quantity(f"{CLEARANCE}{name}", "mm", LOWER, f"smallest clearance to {name}") for name in obstacle_names)
    health = tuple(Quantity(name, *spec) for name, spec in HEALTH.items())
    forces = tuple(Quantity(f"{FORCE}{name}", "N", UPPER, f"largest force of the {name} support on the hose")
                   for name in force_supports)
    moments = tuple(Quantity(f"{MOMENT}{name}", "N*mm", UPPER, f"largest moment of the {name} support on the hose")
                    for name in moment_supports)
    return clearances + health + forces + moments + (Quantity("deviation", *DEVIATION),)


def reaction_supports(clips_hold_direction: tuple[bool, ...]) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(supports with a force, supports with a moment) of a hose with clips that hold a direction or not (a ball
    clip): the mounts and every clip; the mounts and the clips holding a direction."""
    clips = tuple(f"clips[{k}]" for k in range(len(clips_hold_direction)))
    framed = tuple(name for name, held in zip(clips, clips_hold_direction) if held)
    return ("start", "end") + clips, ("start", "end") + framed


def natural_scale(quantity: Quantity, length: float, stiffness: float) -> float:
    """A magnitude the quantity is naturally measured against: the hose length (mm), stiffness / length
    (N*mm), stiffness / length^2 (N), one radian over the length (deg/mm).  length: mm.  stiffness: the larger of
    EI and GJ, N*mm^2."""
    return {"mm": length, "N*mm": stiffness / length, "N": stiffness / length**2,
            "deg/mm": math.degrees(1.0) / length}[quantity.unit]


@dataclass(frozen=True)
class Limit:
    """A limit on a quantity: value in the quantity's unit; the sense is the quantity's."""

    quantity: Quantity
    value: float

    def margin(self, values: np.ndarray) -> np.ndarray:
        """How far inside the limit (positive) or beyond it (negative), in the quantity's unit; NaN stays NaN."""
        values = np.asarray(values, dtype=float)
        return values - self.value if self.quantity.sense == LOWER else self.value - values

    def describe(self) -> str:
        """E.g. 'bend_radius at least 35 mm'."""
        return f"{self.quantity.name} {self.quantity.sense} {self.value:g} {self.quantity.unit}"


@dataclass
class PoseReadings:
    """One hose through its poses (one pose for a placement), as the quantities read it.

    centerlines: (M, N+1, 3) mm.  bend_radius, twisting_moment: (M, N+1) mm and N*mm.
    end_moment: (M, 3) N*mm, the end mount's moment on the hose.  end_direction: (M, 3) unit.
    clearance: (O, M) mm, one row per obstacle.  torsional_stiffness: GJ, N*mm^2.
    forces: (M, R) N, the magnitude of each support's force on the hose (reaction_supports' first list);
    moments: (M, R') N*mm, of each support's moment (its second list).
    """

    centerlines: np.ndarray
    bend_radius: np.ndarray
    twisting_moment: np.ndarray
    end_moment: np.ndarray
    end_direction: np.ndarray
    clearance: np.ndarray
    torsional_stiffness: float
    forces: np.ndarray
    moments: np.ndarray

    def per_pose(self) -> dict[str, np.ndarray]:
        """(M,) per pose: bend_radius (smallest), end_torque, twisting_moment (largest |.|)."""
        return {
            "bend_radius": np.min(self.bend_radius, axis=1),
            "end_torque": np.abs(np.einsum("ij,ij->i", self.end_moment, self.end_direction)),
            "twisting_moment": np.max(np.abs(self.twisting_moment), axis=1),
        }

    def station_deviation(self, nominal: np.ndarray) -> np.ndarray:
        """(N+1,) mm: per station, the largest distance from the nominal centrelines `nominal` (M, N+1, 3) over the poses."""
        return np.max(np.linalg.norm(self.centerlines - nominal, axis=2), axis=0)

    def smooth_values(self) -> np.ndarray:
        """The quantities of quantities() but the deviation (which has no derivative at the nominal hose)."""
        pose = self.per_pose()
        twist = math.degrees(float(np.max(pose["twisting_moment"]))) / self.torsional_stiffness
        health = [float(np.min(pose["bend_radius"])), float(np.max(pose["end_torque"])), twist]
        return np.concatenate([np.min(self.clearance, axis=1), health, np.max(self.forces, axis=0),
                               np.max(self.moments, axis=0)])

    def values(self, nominal: np.ndarray) -> np.ndarray:
        """The quantities in the order of quantities(): clearances, bend_radius, end_torque, twist_rate, forces,
        moments, deviation."""
        return np.append(self.smooth_values(), np.max(self.station_deviation(nominal)))
