"""Independent check for the floor placement: a heavy planar elastica between two inclined mounts resting on a
frictionless floor, solved by shooting (scipy solve_ivp + fsolve), not by hoseline's rod; mounts at any heights
and clamp angles (tests/elastica_floor_shooting.py is the symmetric case with the fittings pointing straight down).

In the x-z plane, the floor z = 0, the hose's centreline resting at z = radius.  The hose leaves the start mount
(x_s, z_s) and arrives at the end mount (x_e, z_e) with x_s < x_e; between its two lifted parts it lies on the floor,
straight, with no moment and no shear, over [x_l, x_l + lying], lying = L - s_l - s_r.  At each touch-down point the
curvature is zero (no point moment) and the shear may jump (a point reaction).  Each lifted part is integrated from
its touch-down point outwards, sigma the arc length from it, theta its tangent angle (the left part mirrored, x -> -x,
so that both run to the right):
    x' = cos theta, z' = sin theta, EI theta'' = sin theta n_x - cos theta (n_z0 + w sigma),
with n_x the horizontal force of the lying part (the same on both sides) and n_z0 the shear at that touch-down
point.  Six unknowns (s_l, s_r, x_l, n_x, n_z0 left and right) meet the two mounts' positions and tangent angles.
Units: mm, N.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve


@dataclass(frozen=True)
class RestingElastica:
    """The shooting solution.  lifted: (s_l, s_r) mm.  touchdown: (x_l, x_r) mm.  horizontal: n_x, N.
    shears: (left, right) n_z0, N.  parts: the two lifted parts' dense solutions (sigma -> x, z, theta, curvature)."""

    length: float
    lifted: tuple[float, float]
    touchdown: tuple[float, float]
    horizontal: float
    shears: tuple[float, float]
    radius: float
    parts: tuple[object, object]

    def point(self, s: float) -> np.ndarray:
        """(x, z) mm of the centreline at arc length s (mm) from the start mount."""
        s_l, s_r = self.lifted
        if s <= s_l:  # the left part, mirrored back: sigma from its touch-down point
            x, z = self.parts[0].sol(s_l - s)[:2]
            return np.array([-x, z])
        if s >= self.length - s_r:
            return self.parts[1].sol(s - (self.length - s_r))[:2]
        return np.array([self.touchdown[0] + (s - s_l), self.radius])

    def curvature(self, s: float) -> float:
        """The centreline's curvature (1/mm, unsigned) at arc length s (mm) from the start mount."""
        s_l, s_r = self.lifted
        if s <= s_l:
            return abs(float(self.parts[0].sol(s_l - s)[3]))
        if s >= self.length - s_r:
            return abs(float(self.parts[1].sol(s - (self.length - s_r))[3]))
        return 0.0


def solve_resting_elastica(length, bending_stiffness, weight, start, start_angle, end, end_angle, radius,
                           guess) -> RestingElastica:
    """Shooting solution (see the module doc); weight in N/mm; start, end: (x, z) mm of the mounts; start_angle:
    the hose's tangent angle leaving the start mount, end_angle: arriving at the end mount (rad, from +x towards
    +z); guess: (s_l, s_r, x_l, n_x, n_z0 left, n_z0 right) to start fsolve from."""

    def rhs(sigma, y, n_x, n_z0):
        x, z, theta, kappa = y
        return [math.cos(theta), math.sin(theta), kappa,
                (math.sin(theta) * n_x - math.cos(theta) * (n_z0 + weight * sigma)) / bending_stiffness]

    def part(x0, lifted, n_x, n_z0, dense=False):
        return solve_ivp(rhs, (0.0, lifted), [x0, radius, 0.0, 0.0], args=(n_x, n_z0), method="DOP853",
                         rtol=1e-11, atol=1e-11, dense_output=dense)

    def residual(unknowns, dense=False):
        s_l, s_r, x_l, n_x, shear_l, shear_r = unknowns
        if not (0.0 < s_l and 0.0 < s_r and s_l + s_r < length):
            return [10.0] * 6
        left = part(-x_l, s_l, n_x, shear_l, dense)
        right = part(x_l + (length - s_l - s_r), s_r, n_x, shear_r, dense)
        xl, zl, tl = left.y[:3, -1]
        xr, zr, tr = right.y[:3, -1]
        # the left part, run outwards, reaches the start mount along -t_start = (-cos a, -sin a): mirrored, at -a
        return [(xl + start[0]) / length, (zl - start[1]) / length, tl + start_angle,
                (xr - end[0]) / length, (zr - end[1]) / length, tr - end_angle]

    solution, _, status, message = fsolve(residual, guess, xtol=1e-12, full_output=True)
    if status != 1 or max(abs(v) for v in residual(solution)) > 1e-10:
        raise RuntimeError(f"shooting did not converge: {message}, residual {residual(solution)}")
    s_l, s_r, x_l, n_x, shear_l, shear_r = solution
    left = part(-x_l, s_l, n_x, shear_l, True)
    right = part(x_l + (length - s_l - s_r), s_r, n_x, shear_r, True)
    return RestingElastica(length, (s_l, s_r), (x_l, x_l + length - s_l - s_r), n_x, (shear_l, shear_r), radius,
                           (left, right))
