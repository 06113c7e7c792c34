"""An independent second method: the planar elastica between the thesis mounts solved as a
boundary-value problem of ordinary differential equations (SciPy's collocation solver),
compared with the discrete rod."""

import numpy as np
from scipy.integrate import solve_bvp

from hoseline import Hose, Mount, Problem, solve

EI = 292.7985 * 510.8053
LENGTH = 330.6
START, END = np.array([-13.0, 0.0]), np.array([-173.064, -7.0])


def discrete(segments):
    hose = Hose(length=LENGTH, outer_diameter=10.1, bending_stiffness=EI, torsional_stiffness=96.12 * 25540.26, segments=segments)
    problem = Problem(hose, Mount([*START, -11.25], [0.0, 1.0, 0.0]), Mount([*END, -11.25], [1.0, 0.0, 0.0]))
    return solve(problem)


def elastica(guess):
    """x' = cos(theta), y' = sin(theta), theta' = M/EI, M' = Fx sin(theta) - Fy cos(theta);
    clamped: position and angle given at both ends; unknowns Fx, Fy (end force, N)."""
    s = guess.s
    tangent = np.diff(guess.centerline[:, :2], axis=0)
    theta_mid = np.unwrap(np.arctan2(tangent[:, 1], tangent[:, 0]))
    theta = np.interp(s, 0.5 * (s[1:] + s[:-1]), theta_mid)
    theta_end = np.pi if abs(theta_mid[-1] - np.pi) < 1.0 else -np.pi  # arrives heading -x
    theta[0], theta[-1] = np.pi / 2, theta_end
    moment = EI * np.gradient(theta, s)

    def rhs(_, y, p):
        fx, fy = p
        return np.vstack([np.cos(y[2]), np.sin(y[2]), y[3] / EI, fx * np.sin(y[2]) - fy * np.cos(y[2])])

    def bc(ya, yb, p):
        return np.array([ya[0] - START[0], ya[1] - START[1], ya[2] - np.pi / 2, yb[0] - END[0], yb[1] - END[1], yb[2] - theta_end])

    y0 = np.vstack([guess.centerline[:, 0], guess.centerline[:, 1], theta, moment])
    solution = solve_bvp(rhs, bc, s, y0, p=guess.end_force[:2], tol=1e-10, max_nodes=100000)
    assert solution.success, solution.message
    return solution


def test_discrete_rod_converges_to_the_elastica_solution():
    coarse, fine = discrete(50), discrete(100)
    reference = elastica(fine)
    errors = []
    for result in (coarse, fine):
        exact = reference.sol(result.s)[:2].T
        errors.append(np.max(np.linalg.norm(result.centerline[:, :2] - exact, axis=1)))
    assert errors[1] < 0.09  # mm, at 100 segments: measured 0.0296 (0.118 at 50)
    assert 3.9 < errors[0] / errors[1] < 4.1  # second order, against an independent solution: measured 3.98
    # the end force from the multiplier matches the elastica's end force: measured 1.05e-3 relative
    assert np.linalg.norm(fine.end_force[:2] - reference.p) < 3e-3 * np.linalg.norm(reference.p)
