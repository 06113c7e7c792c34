"""Preset: the set a hose takes from being stored coiled, as a natural (stress-free) curvature.

The unloaded hose is not straight: it keeps a curvature of 1/R_set in a plane fixed to the
hose.  In the material frame (d1, d2, d3 = tangent) the natural Darboux vector is

    kappa0 = (1 / R_set) (-sin psi, cos psi, 0),

which bends the tangent towards  n = cos psi d1 + sin psi d2:  the centre of the set lies on
that side of the hose.  psi is measured at the start fitting, about the hose axis (right hand,
thumb along the start direction), from the start fitting's d1: the world axis least aligned
with the start direction, made perpendicular to it (mechanics.rotations.frame_from_tangent;
start direction +y: d1 = +x, d2 = -z).  The set is in the hose's material, so it turns with
the hose when the end fitting is twisted.

The discrete rod (mechanics/energy.py) takes the preset as one stress-free relative rotation per
joint, R0 = the rotation about kappa0 / |kappa0| by 2 atan(l |kappa0| / 2) (l the joint's
length: h inside, h/2 at the fittings), whose discrete Darboux vector is exactly kappa0.
Units: mm, 1/mm, degrees at the boundary; radians inside.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Preset:
    """A constant natural curvature of the hose.

    curvature: 1/mm, one over the radius of set (0: no set).  angle_deg: degrees, psi of the
    module doc (the side of the hose the set bends towards, from the start fitting's d1).
    """

    curvature: float
    angle_deg: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.curvature) and self.curvature >= 0.0):
            raise ValueError(f"preset curvature = {self.curvature!r}: must be zero or a positive finite number (1/mm)")
        if not math.isfinite(self.angle_deg):
            raise ValueError(f"preset angle = {self.angle_deg!r}: must be a finite number of degrees")

    @classmethod
    def from_components(cls, bend_1: float, bend_2: float) -> "Preset":
        """The preset whose natural curvature vector in the section is bend_1 d1 + bend_2 d2 (1/mm, towards the set)."""
        return cls(math.hypot(bend_1, bend_2), math.degrees(math.atan2(bend_2, bend_1)))

    @property
    def radius(self) -> float:
        """Radius of set, mm (inf for no set)."""
        return math.inf if self.curvature == 0.0 else 1.0 / self.curvature

    @property
    def components(self) -> tuple[float, float]:
        """The curvature towards d1 and towards d2, 1/mm (from_components' arguments)."""
        psi = math.radians(self.angle_deg)
        return self.curvature * math.cos(psi), self.curvature * math.sin(psi)

    def darboux(self) -> np.ndarray:
        """kappa0 (3,), 1/mm, in the material frame (module doc)."""
        psi = math.radians(self.angle_deg)
        return self.curvature * np.array([-math.sin(psi), math.cos(psi), 0.0])


def rest_rotations(darboux: np.ndarray, segment_length: float) -> np.ndarray:
    """Stress-free relative rotations R0 (N+1, 3, 3) of the joints of a rod of N segments.

    darboux: (N+1, 3) natural Darboux vectors per joint (1/mm, material frame: bending about d1,
    about d2, twist), the first and last at the fittings.  segment_length: h, mm; the joints at the
    fittings are h/2 long.  R0 = Q = A B^T of the joint in the stress-free shape (energy.py).
    """
    darboux = np.asarray(darboux, dtype=float)
    if darboux.ndim != 2 or darboux.shape[1] != 3 or darboux.shape[0] < 2:
        raise ValueError(f"preset curvatures: shape {darboux.shape}, expected (segments + 1, 3)")
    lengths = np.full(darboux.shape[0], segment_length)
    lengths[0] = lengths[-1] = 0.5 * segment_length
    magnitude = np.linalg.norm(darboux, axis=1)
    angle = 2.0 * np.arctan(0.5 * lengths * magnitude)
    axis = np.divide(darboux, magnitude[:, None], out=np.zeros_like(darboux), where=magnitude[:, None] > 0.0)
    from scipy.spatial.transform import Rotation  # here, not at the top: the command line starts without SciPy

    return Rotation.from_rotvec(axis * angle[:, None]).as_matrix()


def preset_rest_rotations(preset: Preset | None, segments: int, segment_length: float) -> np.ndarray | None:
    """rest_rotations of a constant preset for N = segments joints apart (mm), None without a set."""
    if preset is None or preset.curvature == 0.0:
        return None
    return rest_rotations(np.tile(preset.darboux(), (segments + 1, 1)), segment_length)


def stress_free_shape(
    rest: np.ndarray, start_point: np.ndarray, start_frame: np.ndarray, segment_length: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The unloaded shape of a preset rod held at its start only: (frames (N,3,3), nodes (N+1,3) mm, end frame).

    rest: (N+1, 3, 3) from rest_rotations.  start_point: mm.  start_frame: rows d1, d2, d3.
    Each joint's Q = A B^T equals its R0, so B = R0^T A.
    """
    count = rest.shape[0] - 1
    frames = np.empty((count, 3, 3))
    previous = np.asarray(start_frame, dtype=float)
    for j in range(count):
        frames[j] = previous = rest[j].T @ previous
    end_frame = rest[count].T @ previous
    nodes = np.vstack([start_point, start_point + segment_length * np.cumsum(frames[:, 2], axis=0)])
    return frames, nodes, end_frame
