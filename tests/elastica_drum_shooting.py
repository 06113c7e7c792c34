"""Independent check for contact extent: a weightless planar elastica pulled over a frictionless drum,
solved as a boundary-value problem with a free boundary (scipy solve_bvp), not by hoseline's rod.

Symmetric set-up: the drum's axis is the y axis, the hose's centreline wraps it on the circle of
radius rho = R + r (x = -rho sin phi, z = rho cos phi); the mounts are at (-+half_span, height),
the hose leaving each fitting straight up (theta = pi/2, theta the tangent's angle from +x towards +z).
Left half, s from the start mount: free from s = 0 to the lift-off point s1, then on the circle to
the top (s = L/2), so the wrap's half angle is alpha = (L/2 - s1) / rho.  On the circle the
curvature is -1/rho (clockwise), the moment EI/rho constant, so the internal force there is a tension
T along the tangent and the drum pushes T/rho per length; at lift-off the moment (so the curvature)
is continuous, the shear jumps: a point force P along the drum's outward normal.  On the free part
(weightless) the internal force n (of the part beyond s on the part before it) is constant and
    x' = cos theta, z' = sin theta, EI theta'' = sin theta n_x - cos theta n_z.
The shape and the unknowns (n_x, n_z, s1) meet, at s = 0, the mount's point and theta = pi/2, and at s1 the
point (-rho sin alpha, rho cos alpha), theta = alpha, theta' = -1/rho.  Then T = n . t(s1), P = n . nu(s1) (nu
the outward normal; the solution is refused unless T > 0, P >= 0 and the free part clears the circle).
Units: mm, N.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_trapezoid, solve_bvp


@dataclass(frozen=True)
class DrumElastica:
    """The free-boundary solution.  wrap: the arc on the drum, mm (2 rho alpha).  lift_off: s1, mm of free hose from
    each mount to its lift-off point.  half_angle: alpha, rad.  tension: T on the wrap, N.  pressure: T/rho, the
    drum's push per length on the wrap, N/mm.  point_force: P, the drum's concentrated push at each lift-off
    point, N (along the outward normal there).  total: the drum's whole push on the hose, N (upward)."""

    wrap: float
    lift_off: float
    half_angle: float
    tension: float
    pressure: float
    point_force: float
    total: float


def solve_drum_elastica(length, bending_stiffness, drum_radius, hose_radius, half_span, height) -> DrumElastica:
    """The symmetric weightless elastica wrapped over a drum (see the module doc): drum_radius R and hose_radius r mm,
    the mounts at (-+half_span, height) mm, length mm, bending_stiffness N*mm^2."""
    rho = drum_radius + hose_radius

    # in units of rho (lengths) and EI / rho^2 (forces): the unknowns are all of order one
    def rhs(tau, y, p):
        # tau = s / s1 in [0, 1]; y = (x, z, theta, theta'); p = (n_x, n_z, s1)
        x, z, theta, kappa = y
        n_x, n_z, lift_off = p
        return lift_off * np.array([np.cos(theta), np.sin(theta), kappa, np.sin(theta) * n_x - np.cos(theta) * n_z])

    half = 0.5 * length / rho
    mount = np.array([-half_span, height]) / rho

    def ends(at_mount, at_lift_off, p):
        alpha = half - p[2]
        x, z, theta, kappa = at_lift_off
        return np.array([at_mount[0] - mount[0], at_mount[1] - mount[1], at_mount[2] - 0.5 * math.pi,
                         x + math.sin(alpha), z - math.cos(alpha), theta - alpha, kappa + 1.0])

    # the tension's boundary layers (length sqrt(EI / T)) make a single shot ill-conditioned: a collocation
    # solve (scipy solve_bvp) from a string pulled taut along the line from the mount to its tangent point on
    # the circle (direction beta, lift-off where the circle's tangent turns to beta), with a layer at each end
    # of the free part that turns the tangent from the mount's to beta and bends it to the circle's curvature
    distance = float(np.hypot(*mount))
    beta = math.atan2(-mount[1], -mount[0]) + math.asin(1.0 / distance)  # the taut string's direction
    lift_off = half - beta
    tau = np.linspace(0.0, 1.0, 801)
    s = lift_off * tau
    for tension in (10.0, 3.0, 30.0, 1.0):
        layer = 1.0 / math.sqrt(tension)
        theta = beta + (0.5 * math.pi - beta) * np.exp(-s / layer) + layer * (1.0 - np.exp(-(lift_off - s) / layer))
        kappa = -(0.5 * math.pi - beta) / layer * np.exp(-s / layer) - np.exp(-(lift_off - s) / layer)
        x = mount[0] + cumulative_trapezoid(np.cos(theta), s, initial=0.0)
        z = mount[1] + cumulative_trapezoid(np.sin(theta), s, initial=0.0)
        solved = solve_bvp(rhs, ends, tau, np.array([x, z, theta, kappa]),
                           p=[tension * math.cos(beta), tension * math.sin(beta), lift_off],
                           tol=1e-9, bc_tol=1e-12, max_nodes=100000)
        if solved.success and 0.0 < solved.p[2] < half:
            break
    else:
        raise RuntimeError("the drum elastica did not converge")
    free = solved.sol(np.linspace(0.0, 1.0, 2001))
    if np.min(np.hypot(free[0], free[1])) < 1.0 - 1e-9:
        raise RuntimeError("the drum elastica's free part enters the drum: not a contact solution")
    n_x, n_z, lift_off = solved.p * np.array([bending_stiffness / rho ** 2, bending_stiffness / rho ** 2, rho])
    alpha = (0.5 * length - lift_off) / rho
    t = np.array([math.cos(alpha), math.sin(alpha)])
    outward = np.array([-math.sin(alpha), math.cos(alpha)])
    force = np.array([n_x, n_z])
    tension, point = float(force @ t), float(force @ outward)
    if tension <= 0.0 or point < 0.0:
        raise RuntimeError("the drum elastica pulls on the drum: not a frictionless contact solution")
    # the drum's push: the distributed part (T/rho over the wrap, outward) plus the two point forces
    total = 2.0 * tension * math.sin(alpha) + 2.0 * point * math.cos(alpha)
    return DrumElastica(2.0 * rho * alpha, float(lift_off), alpha, tension, tension / rho, point, total)
