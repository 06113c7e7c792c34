"""Independent check for contact: a heavy planar elastica hanging between two mounts onto a
frictionless floor, solved by shooting (scipy solve_ivp + fsolve), not by hoseline's rod.

Symmetric set-up: mounts at x = -+half_span, height `height` (centreline) above the floor
z = 0, the hose leaving each fitting straight down; the hose's centreline rests at z = radius
on the floor.  On the floor the hose is straight and carries no moment and no shear; at the
touch-down point the curvature is zero (no point moment) while the shear may jump (a point
reaction).  Right half, sigma from the touch-down point (x_t = L/2 - s1, z = radius, theta = 0,
theta' = 0) to the mount (sigma = s1, theta = pi/2):
    x' = cos theta, z' = sin theta, EI theta'' = sin theta n_x - cos theta (n_z0 + w sigma),
with n the force of the part beyond sigma on the part before it (n' = (0, w), w the weight per
length).  The unknowns (s1, n_x, n_z0) meet x = half_span, z = height, theta = pi/2 at sigma = s1.
Units: mm, N.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.integrate import solve_ivp
from scipy.optimize import fsolve


@dataclass(frozen=True)
class FloorElastica:
    """The shooting solution.  lifted: s1, mm of hose off the floor on each side.  touchdown: x_t, mm
    (the touch-down points are at -+x_t).  horizontal: n_x, N.  reaction: the point reaction at each
    touch-down point, N (upward).  shape: sigma -> (x, z, theta, curvature) on the right suspended part."""

    lifted: float
    touchdown: float
    horizontal: float
    reaction: float
    shape: object


def solve_floor_elastica(length, bending_stiffness, weight, half_span, height, radius) -> FloorElastica:
    """Shooting solution of the symmetric heavy elastica on a floor (see the module doc); weight in N/mm."""

    def rhs(sigma, y, n_x, n_z0):
        x, z, theta, kappa = y
        return [math.cos(theta), math.sin(theta), kappa,
                (math.sin(theta) * n_x - math.cos(theta) * (n_z0 + weight * sigma)) / bending_stiffness]

    def wild(sigma, y, n_x, n_z0):  # a guess that curls the hose round: stop, its residual is large anyway
        return abs(y[2]) - 2.0 * math.pi

    wild.terminal = True

    def shoot(unknowns, dense=False):
        lifted, n_x, n_z0 = unknowns
        start = [0.5 * length - lifted, radius, 0.0, 0.0]
        return solve_ivp(rhs, (0.0, lifted), start, args=(n_x, n_z0), method="DOP853", rtol=1e-11, atol=1e-11,
                         dense_output=dense, events=wild)

    def residual(unknowns):
        if not 0.0 < unknowns[0] < 0.5 * length:  # no lifted length outside (0, L/2): steer fsolve back
            return [10.0, 10.0, 10.0]
        end = shoot(unknowns).y[:, -1]
        return [(end[0] - half_span) / length, (end[1] - height) / length, end[2] - 0.5 * math.pi]

    best = None
    for guess_lifted in (0.3 * length, 0.2 * length, 0.4 * length):
        for guess_nz in (-0.3 * weight * guess_lifted, -0.6 * weight * guess_lifted):
            solution, info, ok, _ = fsolve(residual, [guess_lifted, 0.0, guess_nz], full_output=True, xtol=1e-13)
            if ok == 1 and max(abs(v) for v in residual(solution)) < 1e-10 and 0.0 < solution[0] < 0.5 * length:
                best = solution
                break
        if best is not None:
            break
    if best is None:
        raise RuntimeError("shooting did not converge")
    lifted, n_x, n_z0 = best
    path = shoot(best, dense=True)
    return FloorElastica(float(lifted), 0.5 * length - float(lifted), float(n_x), float(-n_z0), path.sol)
