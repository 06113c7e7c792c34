"""Five placements with independent references (the Kirchhoff BVP of kirchhoff_bvp.py, no hoseline code beyond a
first guess), for the accuracy tests: the error estimate against the true station error, and --accuracy.

Each case is placed as hoseline places it: the end free to spin about its axis (the torque-free lock), then its
frame turned about end.direction to the twist by continuation."""

import functools
from dataclasses import replace

import numpy as np
from kirchhoff_bvp import KirchhoffRod, end_frame, guess_from_result
from scipy.spatial.transform import Rotation
from validation_cases import brake_hose

from hoseline import Hose, Mount, Problem, solve
from hoseline.model.hose import isotropic_torsional_stiffness

REFERENCE_TOLERANCE = 1e-8  # solve_bvp's relative residual: station errors far below the discrete ones measured


def _non_coplanar(twist: float) -> Problem:
    """The thesis hose between mounts 60 mm apart in height, the end direction tilted out of the start's plane."""
    base = brake_hose(segments=40, twist=twist)
    end = Mount(base.end.point + np.array([0.0, 0.0, 60.0]), np.array([1.0, 0.0, 0.4]))
    return replace(base, end=end)


def _weightless_u_bend(twist: float) -> Problem:
    """A weightless isotropic hose in a U between opposed mounts (twisting it turns the U out of its plane)."""
    hose = Hose(length=400.0, outer_diameter=10.0, bending_stiffness=2e5,
                torsional_stiffness=isotropic_torsional_stiffness(2e5), segments=40)
    return Problem(hose, Mount([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]), Mount([0.0, 120.0, 0.0], [1.0, 0.0, 0.0]), twist)


CASES = {  # name: (problem at a twist, twist deg)
    "thesis 0 deg": (lambda twist: brake_hose(segments=40, twist=twist), 0.0),
    "thesis 180 deg": (lambda twist: brake_hose(segments=40, twist=twist), 180.0),
    "thesis 90 deg": (lambda twist: brake_hose(segments=40, twist=twist), 90.0),
    "non-coplanar 45 deg": (_non_coplanar, 45.0),
    "weightless U 120 deg": (_weightless_u_bend, 120.0),
}


def problem_of(name: str, segments: int) -> Problem:
    """The case's problem at `segments` segments."""
    make, twist = CASES[name]
    problem = make(twist)
    return replace(problem, hose=replace(problem.hose, segments=segments))


@functools.lru_cache(maxsize=None)
def reference(name: str):
    """scipy's solution of the case by the Kirchhoff BVP (centreline rows 0-2 of .sol(s))."""
    make, twist = CASES[name]
    problem = make(twist)
    guess = solve(replace(problem, end_twist_deg=0.0, hose=replace(problem.hose, segments=80)), estimate_error=False)
    hose = problem.hose
    start_frame = Rotation.from_matrix(guess.start_frame.T)
    weight = hose.mass_per_length * np.asarray(problem.gravity) * 1e-3  # kg/m * m/s^2 -> N/mm
    rod = KirchhoffRod(hose.stiffness_vector, problem.start.point, start_frame, problem.end.point, weight)
    placed = rod.solve(*guess_from_result(guess), end_tangent=-problem.end.direction)
    if twist == 0.0:
        return rod.solve(placed.x, placed.y, end_tangent=-problem.end.direction, tol=REFERENCE_TOLERANCE)
    locked = end_frame(placed)
    twisted = rod.twisted(placed, locked, problem.end.direction, twist)
    turn = Rotation.from_rotvec(np.radians(twist) * np.asarray(problem.end.direction, dtype=float))
    return rod.solve(twisted.x, twisted.y, end_frame=turn * locked, tol=REFERENCE_TOLERANCE)  # refined at the end


def true_error(name: str, result) -> float:
    """The largest station error (mm) of a placement of the case against its reference."""
    exact = reference(name).sol(result.s)[:3].T
    return float(np.max(np.linalg.norm(result.centerline - exact, axis=1)))
