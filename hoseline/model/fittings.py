"""End fittings: the rigid crimped pieces between a port and the flexible hose.

A catalogue hose assembly is the cut (free) hose plus a fitting at each end.  A fitting is
clamped at its port (the user's mount: the seal face centre, with the direction from the
port into the hose) and is rigid, so the flexible hose is an ordinary placement problem
between the two fitting outlets; this module only turns ports into outlets.

Geometry of one fitting, all in mm and degrees:

- straight (bend_angle = 0): a tube of `length` along the port direction; the outlet
  (where the flexible hose starts) is port + length * direction.
- elbow (0 < bend_angle < 180): a leg of `length` from the port along the port direction
  to the vertex (where the port axis meets the outlet axis; the "drop" of a 90 degree
  elbow), then a leg of `outlet_length` from the vertex along the outlet direction to the
  outlet.  The outlet direction is the port direction turned by bend_angle towards the
  clocking direction e.  The centreline rounds the vertex with an arc of `bend_radius`
  (0: a sharp corner), tangent to both legs.
- clocking: e is `reference` made normal to the port axis and then turned by
  `clocking_deg` about the port direction (right-hand rule).  `reference` is a world
  direction the user picks from the drawing (e.g. [0, 0, 1] when the drawing gives the
  elbow's angle from vertical); a sweep moves it with the port's body.

Overall length (the catalogue's ordering length): measured with the hose laid out straight,
along the hose axis, from the seal face of each fitting; for a bent fitting from the point
where its port axis meets the seal face (Gates' "C" dimension: "all bent and block couplings
are measured from the point at which the centre line of the coupling intersects the seal
face"; MIL-DTL-83796 fig. 2: "to the centre line of the 90 degree flange").  So a fitting
adds C = (outlet - port) . outlet_direction to the free length: `length` for a straight
fitting, outlet_length + length * cos(bend_angle) for an elbow (outlet_length for 90
degrees).  overall_length = free_length + C_start + C_end.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hoseline.model.mounts import Mount, unit_vector

MAX_BEND_DEG = 180.0  # an elbow turns the hose by less than a U-turn: its two legs would otherwise be parallel
ARC_SAMPLES_PER_90_DEG = 8  # centreline points on a bend, for exports and the clearance (chord error ~ r (1 - cos 5.6 deg))


@dataclass(frozen=True)
class Fitting:
    """One rigid end fitting, clamped at its port.

    length: mm, straight fitting: its rigid length from the port to the hose; elbow: from the
        port along the port axis to the vertex (where the port and outlet axes meet).
    bend_angle_deg: degrees, 0 for a straight fitting, an elbow's angle in (0, 180).
    outlet_length: mm, elbow only: from the vertex along the outlet axis to the hose.
    bend_radius: mm, elbow only: centreline radius of the bend (0: a sharp corner).
    clocking_deg: degrees, elbow only: turn of the elbow about the port direction (right-hand
        rule) from `reference`.
    reference: elbow only: a world direction; at clocking 0 the elbow bends towards its
        component normal to the port axis.
    outer_diameter: mm, the fitting's outer diameter for exports and clearance; None: the hose's.
    """

    length: float
    bend_angle_deg: float = 0.0
    outlet_length: float = 0.0
    bend_radius: float = 0.0
    clocking_deg: float = 0.0
    reference: np.ndarray | None = None
    outer_diameter: float | None = None

    def __post_init__(self) -> None:
        for name in ("length", "outlet_length", "bend_radius"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{name} = {value!r}: must be zero or positive (mm)")
        if self.outer_diameter is not None and not (math.isfinite(self.outer_diameter) and self.outer_diameter > 0.0):
            raise ValueError(f"outer_diameter = {self.outer_diameter!r}: must be positive (mm), or left out for the hose's")
        if not (math.isfinite(self.bend_angle_deg) and 0.0 <= self.bend_angle_deg < MAX_BEND_DEG):
            raise ValueError(f"bend_angle = {self.bend_angle_deg!r}: must lie in [0, 180) degrees (0 for a straight "
                             "fitting, 45 or 90 for the usual elbows)")
        if not math.isfinite(self.clocking_deg):
            raise ValueError(f"clocking = {self.clocking_deg!r}: must be a finite angle in degrees")
        if self.bend_angle_deg == 0.0:
            extra = [name for name, value in (("outlet_length", self.outlet_length), ("bend_radius", self.bend_radius),
                                              ("clocking", self.clocking_deg)) if value != 0.0]
            extra += ["reference"] if self.reference is not None else []
            if extra:
                raise ValueError(f"{', '.join(extra)} given for a straight fitting (bend_angle = 0): a straight fitting "
                                 f"has its length only; remove {', '.join(extra)} or give bend_angle")
            if self.length == 0.0:
                raise ValueError("length = 0.0: a straight fitting needs a positive length (mm); leave out the "
                                 "fitting table for a hose crimped at the port")
            return
        if self.reference is None:
            raise ValueError("an elbow needs reference = [x, y, z]: the world direction it bends towards at clocking 0 "
                             "(e.g. [0, 0, 1], with clocking the angle from it about the port axis)")
        object.__setattr__(self, "reference", unit_vector(self.reference, "reference"))
        tangent = self.tangent_length
        for name, leg in (("length", self.length), ("outlet_length", self.outlet_length)):
            if leg < tangent * (1.0 - 1e-12):
                raise ValueError(
                    f"{name} = {leg:g} mm is shorter than the bend's tangent length bend_radius * tan(bend_angle / 2) "
                    f"= {tangent:g} mm: give {name} >= {tangent:g} mm or a smaller bend_radius"
                )

    @property
    def bend_angle(self) -> float:
        """The bend in radians."""
        return math.radians(self.bend_angle_deg)

    @property
    def tangent_length(self) -> float:
        """mm from the vertex to where the bend's arc meets each leg (0 for a straight fitting)."""
        return self.bend_radius * math.tan(0.5 * self.bend_angle)

    @property
    def centreline_length(self) -> float:
        """mm along the fitting's centreline from the port to the outlet (legs and arc)."""
        return self.length + self.outlet_length - 2.0 * self.tangent_length + self.bend_radius * self.bend_angle

    @property
    def length_allowance(self) -> float:
        """mm the fitting adds to the free length in the catalogue's overall length: (outlet - port) . outlet direction."""
        return self.outlet_length + self.length * math.cos(self.bend_angle)

    def bend_direction(self, port: Mount) -> np.ndarray:
        """Unit vector normal to the port direction towards which the elbow bends (the clocked reference)."""
        axis = port.direction
        if self.reference is None:
            raise ValueError("a straight fitting does not bend")
        normal = self.reference - float(self.reference @ axis) * axis
        if np.linalg.norm(normal) < 1e-6:
            raise ValueError(f"reference = {self.reference.tolist()} is along the port direction {axis.tolist()}: "
                             "give a reference across the port axis")
        normal /= np.linalg.norm(normal)
        angle = math.radians(self.clocking_deg)
        return math.cos(angle) * normal + math.sin(angle) * np.cross(axis, normal)

    def outlet(self, port: Mount) -> Mount:
        """Where the flexible hose starts: the outlet point (mm) and direction (from the fitting into the hose)."""
        if self.bend_angle_deg == 0.0:
            return Mount(port.point + self.length * port.direction, port.direction)
        outlet_direction = math.cos(self.bend_angle) * port.direction + math.sin(self.bend_angle) * self.bend_direction(port)
        vertex = port.point + self.length * port.direction
        return Mount(vertex + self.outlet_length * outlet_direction, outlet_direction)

    def centreline(self, port: Mount) -> np.ndarray:
        """(K, 3) mm: points along the fitting's centreline from the port to the outlet (legs straight, the bend sampled)."""
        outlet = self.outlet(port)
        if self.bend_angle_deg == 0.0:
            return np.array([port.point, outlet.point])
        vertex = port.point + self.length * port.direction
        tangent = self.tangent_length
        if tangent == 0.0:
            return np.array([port.point, vertex, outlet.point])
        bend = self.bend_direction(port)
        centre = vertex - tangent * port.direction + self.bend_radius * bend
        samples = max(2, math.ceil(ARC_SAMPLES_PER_90_DEG * self.bend_angle_deg / 90.0))
        angles = np.linspace(0.0, self.bend_angle, samples + 1)
        arc = centre + self.bend_radius * (np.outer(np.sin(angles), port.direction) - np.outer(np.cos(angles), bend))
        return np.vstack([port.point, arc, outlet.point])

    def radius(self, hose_outer_diameter: float) -> float:
        """mm, the fitting's outer radius (the hose's when none is given)."""
        return 0.5 * (self.outer_diameter if self.outer_diameter is not None else hose_outer_diameter)


@dataclass(frozen=True)
class EndFittings:
    """The ports as the user gave them and the fitting at each end (None: the hose is crimped at the port).

    start_port, end_port: mounts (mm; directions from the port into the hose, as Mount).
    start, end: Fitting or None.
    """

    start_port: Mount
    end_port: Mount
    start: Fitting | None = None
    end: Fitting | None = None

    def outlets(self) -> tuple[Mount, Mount]:
        """The mounts of the flexible hose: each fitting's outlet, or the port where there is no fitting."""
        return (self.start.outlet(self.start_port) if self.start else self.start_port,
                self.end.outlet(self.end_port) if self.end else self.end_port)

    @property
    def length_allowance(self) -> float:
        """mm the two fittings add to the free length in the catalogue's overall length."""
        return sum(fitting.length_allowance for fitting in (self.start, self.end) if fitting is not None)

    def overall_length(self, free_length: float) -> float:
        """The catalogue's overall length (mm) of a hose with `free_length` mm between the fittings."""
        return free_length + self.length_allowance

    def free_length(self, overall_length: float) -> float:
        """The free (cut) length (mm) of a hose ordered at `overall_length` mm."""
        return overall_length - self.length_allowance

    def pieces(self) -> list[tuple[str, Mount, Fitting]]:
        """[(which end, port, fitting)] for the ends that have a fitting."""
        return [(name, port, fitting) for name, port, fitting in
                (("start", self.start_port, self.start), ("end", self.end_port, self.end)) if fitting is not None]
