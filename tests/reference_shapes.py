"""Reference shapes from the independent Kirchhoff solver (kirchhoff_bvp.py), shared by the tests
and computed once per test session."""

import functools

import numpy as np
from kirchhoff_bvp import KirchhoffRod, end_frame, guess_from_result
from scipy.spatial.transform import Rotation
from validation_cases import EI, FACTOR, brake_hose

from hoseline import solve

MASS = 0.3  # kg/m, as brake_hose
GRAVITY = np.array([0.0, 0.0, -9.81])  # m/s^2


@functools.lru_cache(maxsize=None)
def heavy_thesis_hose(twists: tuple[float, ...]) -> dict:
    """The thesis hose of validation_cases (EI, factor 25, 0.3 kg/m under gravity -z) by the
    Kirchhoff BVP: {twist_deg: scipy solution}.  The end is first left free to spin (the
    torque-free lock), then its frame is turned about end.direction to each twist by
    continuation.  A coarse hoseline solve at 0 deg only provides the first guess."""
    problem = brake_hose(segments=40, twist=0.0)
    guess = solve(problem)
    start_frame = Rotation.from_matrix(guess.start_frame.T)  # round section: any frame with d3 = start.direction
    rod = KirchhoffRod([EI, EI, FACTOR * EI / 1.5], problem.start.point, start_frame, problem.end.point,
                       MASS * GRAVITY * 1e-3)
    placed = rod.solve(*guess_from_result(guess), end_tangent=-problem.end.direction)
    locked = end_frame(placed)
    shapes, last, last_twist = {}, placed, 0.0
    for twist in sorted(twists):
        last = rod.twisted(last, locked, problem.end.direction, twist, from_deg=last_twist)
        shapes[twist], last_twist = last, twist
    return shapes
