"""Shared problem data and placement-path helpers for the benchmark peer solvers.

Units throughout: mm (length), N (force), s (time), rad (angles inside the helpers).

The problem is the thesis brake hose: a weightless Kirchhoff rod clamped at a start
mount P0 (leaving along t0) whose free end is driven quasi-statically to an end mount
P1 (arriving with tangent t1), first with a free roll about the end tangent
("place" phase), then twisted about the end mount direction with the roll locked
("twist" phase).

Orientation matrices are 3x3 with the material directors as COLUMNS:
``R[:, 0] = d1``, ``R[:, 1] = d2``, ``R[:, 2] = d3`` (d3 = hose tangent).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class HoseProblem:
    """Data of the brake-hose benchmark problem (mm, N)."""

    length: float = 330.6  # hose length L [mm]
    outer_radius: float = 5.05  # outer radius [mm]
    bending_stiffness: float = 149563.0  # EI [N mm^2], isotropic section
    torsional_stiffness: float = 2454930.0  # GJ [N mm^2]
    start_point: np.ndarray = field(default_factory=lambda: np.array([-13.0, 0.0, -11.25]))
    start_tangent: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0, 0.0]))
    end_point: np.ndarray = field(default_factory=lambda: np.array([-173.064, -7.0, -11.25]))
    # Direction of the end fitting, pointing from the fitting into the hose. The hose
    # arrives at the end point with tangent t1 = -end_mount_direction.
    end_mount_direction: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0, 0.0]))
    # Size of the lateral imperfection used to pick the buckling side [mm].
    perturbation_mm: float = 0.05

    @property
    def end_tangent(self) -> np.ndarray:
        """Tangent t1 with which the hose arrives at the end point (unit vector)."""
        return -unit(self.end_mount_direction)

    @property
    def section_inertia(self) -> float:
        """Second moment of area I = pi r^4 / 4 of the solid circular section [mm^4]."""
        return np.pi * self.outer_radius**4 / 4.0

    @property
    def equivalent_youngs_modulus(self) -> float:
        """E = EI / I for the solid circular section of the outer radius [N/mm^2]."""
        return self.bending_stiffness / self.section_inertia

    @property
    def equivalent_shear_modulus(self) -> float:
        """G = GJ / J with J = 2 I = pi r^4 / 2 [N/mm^2] (about 8x E: the hose is torsionally stiff)."""
        return self.torsional_stiffness / (2.0 * self.section_inertia)


BRAKE_HOSE = HoseProblem()


def unit(v: np.ndarray) -> np.ndarray:
    """Return v / |v|."""
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def rotation_matrix(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation by ``angle`` [rad] about ``axis`` (right-hand rule), Rodrigues formula."""
    k = unit(axis)
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * kx + (1.0 - np.cos(angle)) * (kx @ kx)


def rotation_angle_about(axis: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Signed angle [rad] that turns vector a into vector b about ``axis`` (both projected normal to it)."""
    k = unit(axis)
    a_p = a - np.dot(a, k) * k
    b_p = b - np.dot(b, k) * k
    return float(np.arctan2(np.dot(np.cross(a_p, b_p), k), np.dot(a_p, b_p)))


def start_frame(p: HoseProblem = BRAKE_HOSE) -> np.ndarray:
    """Material frame at the start mount (columns d1, d2, d3).

    d3 = t0; d1 = the world axis least aligned with t0, made perpendicular to t0;
    d2 = d3 x d1.
    """
    d3 = unit(p.start_tangent)
    axis = np.eye(3)[np.argmin(np.abs(d3))]
    d1 = unit(axis - np.dot(axis, d3) * d3)
    d2 = np.cross(d3, d1)
    return np.column_stack([d1, d2, d3])


def bend_axis(p: HoseProblem = BRAKE_HOSE) -> np.ndarray:
    """Axis n = t0 x t1 (unit) about which the end frame is turned during placement."""
    return unit(np.cross(p.start_tangent, p.end_tangent))


def bend_angle(p: HoseProblem = BRAKE_HOSE) -> float:
    """Angle theta = acos(t0 . t1) [rad] turned by the end frame during placement."""
    return float(np.arccos(np.clip(np.dot(unit(p.start_tangent), p.end_tangent), -1.0, 1.0)))


def straight_end_point(p: HoseProblem = BRAKE_HOSE) -> np.ndarray:
    """Free-end position Q0 = P0 + L t0 of the initial straight hose [mm]."""
    return p.start_point + p.length * unit(p.start_tangent)


def place_position(a: float, p: HoseProblem = BRAKE_HOSE) -> np.ndarray:
    """End position Q(a) = (1-a) Q0 + a P1 during the place phase, a in [0, 1] [mm]."""
    return (1.0 - a) * straight_end_point(p) + a * p.end_point


def place_orientation(a: float, p: HoseProblem = BRAKE_HOSE) -> np.ndarray:
    """Prescribed end frame R(a) = Rot(n, a theta) * start frame, a in [0, 1].

    Only its tangent column R(a)[:, 2] is imposed during placement: the roll about
    the tangent is free there.
    """
    return rotation_matrix(bend_axis(p), a * bend_angle(p)) @ start_frame(p)


def place_tangent(a: float, p: HoseProblem = BRAKE_HOSE) -> np.ndarray:
    """End tangent d3 imposed during the place phase (third column of R(a))."""
    return place_orientation(a, p)[:, 2]


def twist_rotation(b: float, twist_deg: float, p: HoseProblem = BRAKE_HOSE) -> np.ndarray:
    """Rotation of the locked end frame in the twist phase: Rot(end mount direction, b * twist).

    Apply as ``twist_rotation(b, ...) @ locked_frame``; b in [0, 1], twist in degrees.
    """
    return rotation_matrix(p.end_mount_direction, b * np.radians(twist_deg))


def twist_about_tangent(b: float, twist_deg: float) -> float:
    """The twist rotation expressed as a right-hand roll angle about the end tangent t1 [rad].

    t1 = -end mount direction, so a +phi rotation about the mount direction is a -phi roll about t1.
    """
    return -b * np.radians(twist_deg)


def perturbation_direction(p: HoseProblem = BRAKE_HOSE) -> np.ndarray:
    """Lateral direction n x t0 (in the bending plane) toward which the end rotation bends the hose first."""
    return unit(np.cross(bend_axis(p), p.start_tangent))


def perturbation_shape(s: np.ndarray, p: HoseProblem = BRAKE_HOSE) -> np.ndarray:
    """Lateral imperfection displacement [mm] at arc lengths s [mm]: amplitude * sin(pi s / L) * (n x t0).

    Returns an (len(s), 3) array. It vanishes at both ends so the boundary values are untouched.
    """
    amp = p.perturbation_mm * np.sin(np.pi * np.asarray(s) / p.length)
    return amp[:, None] * perturbation_direction(p)[None, :]


def lowest_bending_omega(p: HoseProblem, density: float) -> float:
    """First bending eigenfrequency [rad/s] of the straight clamped-free hose, 1.875^2 sqrt(EI / (rho A L^4)).

    ``density`` in t/mm^3. The peers scale their time step, damping and ramps with it.
    """
    area = np.pi * p.outer_radius**2
    return 1.8751**2 * np.sqrt(p.bending_stiffness / (density * area * p.length**4))


def max_node_shift(a: np.ndarray, b: np.ndarray) -> float:
    """Largest node displacement [mm] between two (M, 3) centerline snapshots."""
    return float(np.max(np.linalg.norm(a - b, axis=1)))


# Bisshopp & Drucker (1945) large-deflection cantilever with tip dead load, P L^2 / EI = 2:
CANTILEVER_LOAD_PARAMETER = 2.0
CANTILEVER_TIP_DEFLECTION = 0.49346  # transverse tip deflection / L
CANTILEVER_TIP_SHORTENING = 0.16064  # axial tip shortening / L


def outcome(centerline: np.ndarray, wall_start: float, steps: int, notes: str, rest_length: float) -> dict:
    """The dict every peer's run() returns; notes gain the centreline length (mm) against the rest length."""
    length = float(np.sum(np.linalg.norm(np.diff(centerline, axis=0), axis=1)))
    return {
        "centerline": centerline,
        "wall_time": time.perf_counter() - wall_start,
        "sim_steps": steps,
        "notes": f"{notes}; centerline length {length:.3f} mm (rest {rest_length} mm)",
    }


def cantilever_outcome(tip: np.ndarray, frame0: np.ndarray, steps: int, p: HoseProblem = BRAKE_HOSE) -> dict:
    """Tip deflection (along d1 of the start frame) and shortening, both as fractions of L.

    tip: tip position relative to the start point, mm.  frame0: start frame (directors as columns).
    """
    return {
        "tip_deflection": float(np.dot(tip, frame0[:, 0]) / p.length),
        "tip_shortening": float(1.0 - np.dot(tip, frame0[:, 2]) / p.length),
        "sim_steps": steps,
    }


def print_outcome(result: dict) -> None:
    """What a peer run as a script prints: wall time, steps, end nodes, notes."""
    centerline = result["centerline"]
    print(f"wall time {result['wall_time']:.2f} s, sim steps {result['sim_steps']}")
    print("start node", np.array2string(centerline[0], precision=4))
    print("end node  ", np.array2string(centerline[-1], precision=4))
    print(result["notes"])
