"""A placement problem: a hose between two mounts, a twist at assembly, gravity."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hoseline.model.hose import Hose
from hoseline.model.mounts import Mount, mount_distance


@dataclass(frozen=True)
class Problem:
    """Everything the solver needs, in user units.

    hose: the hose (mm, N*mm^2, kg/m).
    start, end: mounts (mm); directions from the fitting into the hose.
    end_twist_deg: degrees, rotation of the end fitting about end.direction
        (right-hand rule) applied after the torque-free lock angle.
    gravity: m/s^2 vector (e.g. [0, 0, -9.81]); zero for a weightless study.
    name: free text for reports.
    """

    hose: Hose
    start: Mount
    end: Mount
    end_twist_deg: float = 0.0
    gravity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    name: str = "hose"

    def __post_init__(self) -> None:
        g = np.asarray(self.gravity, dtype=float).reshape(-1)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise ValueError(f"environment.gravity = {list(g)}: must be three finite numbers in m/s^2")
        object.__setattr__(self, "gravity", g)
        if not np.isfinite(self.end_twist_deg):
            raise ValueError(f"end.twist = {self.end_twist_deg!r}: must be a finite angle in degrees")
        distance = mount_distance(self.start, self.end)
        if distance >= self.hose.length * (1.0 - 1e-9):
            raise ValueError(
                f"hose.length = {self.hose.length:g} mm is not longer than the mount distance "
                f"{distance:g} mm: an inextensible hose cannot reach; use a hose longer than {distance:g} mm"
            )
