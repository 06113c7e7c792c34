"""An independent reference for the tests: the Kirchhoff rod as a boundary-value problem of
ordinary differential equations, solved by SciPy's collocation solver (no hoseline code).

Unknowns along the arc length s (mm): the centreline x, the material frame as a unit
quaternion q (scalar last, as scipy.spatial.transform writes it; the rotation's columns are
the directors d1, d2, d3, d3 the tangent), the internal force n (N) and moment m (N*mm), both
exerted by the part beyond s on the part before it.  The textbook equations:

    x' = d3,   d_k' = (R u) x d_k  with  u = K^-1 R^T m   (K = EI1, EI2, GJ in N*mm^2),
    n' = -f  (f: weight per length, N/mm),   m' = -d3 x n.

The start is clamped (point and frame); the end either clamped (point and frame) or held at
its point with its tangent given and free to spin about it (zero moment about the tangent).
Frames and twists are scipy.spatial.transform Rotations, so which way a positive angle turns
is the right-hand rule by SciPy's definition, not hoseline's.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_bvp
from scipy.spatial.transform import Rotation


def _rotation_columns(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (3, 3, n) of quaternions q (4, n), scalar last."""
    x, y, z, w = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def _quaternion_rate(q: np.ndarray, u: np.ndarray) -> np.ndarray:
    """q' = 1/2 q (0, u) for the body-frame rate u (3, n); quaternions scalar last."""
    x, y, z, w = q
    ux, uy, uz = u
    return 0.5 * np.array([w * ux + y * uz - z * uy, w * uy + z * ux - x * uz, w * uz + x * uy - y * ux,
                           -x * ux - y * uy - z * uz])


def _product(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """p q for single quaternions, scalar last."""
    return np.concatenate([p[3] * q[:3] + q[3] * p[:3] + np.cross(p[:3], q[:3]), [p[3] * q[3] - p[:3] @ q[:3]]])


class KirchhoffRod:
    """A rod of stiffness (EI1, EI2, GJ) N*mm^2 and weight (3,) N/mm, clamped at the start (point mm,
    frame: a Rotation whose matrix has d1, d2, d3 as columns), its end at end_point (mm); its length
    is that of the mesh it is solved on."""

    def __init__(self, stiffness, start_point, start_frame: Rotation, end_point, weight=(0.0, 0.0, 0.0)):
        self.stiffness = np.asarray(stiffness, dtype=float)
        self.start_point = np.asarray(start_point, dtype=float)
        self.start_quat = start_frame.as_quat()
        self.end_point = np.asarray(end_point, dtype=float)
        self.weight = np.asarray(weight, dtype=float)

    def _rhs(self, _s, y):
        rotation = _rotation_columns(y[3:7])
        u = np.einsum("jin,jn->in", rotation, y[10:13]) / self.stiffness[:, None]  # K^-1 R^T m
        tangent = rotation[:, 2]
        return np.vstack([tangent, _quaternion_rate(y[3:7], u), np.repeat(-self.weight[:, None], y.shape[1], axis=1),
                          -np.cross(tangent, y[7:10], axis=0)])

    def solve(self, s, guess, *, end_frame: Rotation | None = None, end_tangent=None, tol=1e-6):
        """Equilibrium from `guess` (13, len(s)) on the mesh s (mm), with the end clamped in `end_frame`
        or, given `end_tangent` (unit, along the hose), free to spin about it.  Returns scipy's solution."""
        if end_frame is not None:
            inverse_end = end_frame.inv().as_quat()

            def end_conditions(yb):
                return _product(inverse_end, yb[3:7])[:3]  # zero when q(L) is the end frame (either sign)
        else:
            tangent = np.asarray(end_tangent, dtype=float)
            across = np.linalg.svd(tangent[None])[2][1:]  # two unit vectors normal to the tangent

            def end_conditions(yb):
                d3 = _rotation_columns(yb[3:7, None])[:, 2, 0]
                return np.concatenate([across @ d3, [yb[10:13] @ d3]])

        def bc(ya, yb):
            return np.concatenate([ya[:3] - self.start_point, ya[3:7] - self.start_quat, yb[:3] - self.end_point,
                                   end_conditions(yb)])

        guess = np.array(guess, dtype=float)
        if guess[3:7, 0] @ self.start_quat < 0.0:
            guess[3:7] *= -1.0
        solution = solve_bvp(self._rhs, bc, s, guess, tol=tol, max_nodes=100000)
        assert solution.success, solution.message
        return solution

    def twisted(self, solution, locked: Rotation, axis, degrees: float, from_deg: float = 0.0, step_deg: float = 15.0):
        """Continuation from `solution` (the end clamped in `locked` turned by from_deg) to the end frame
        turned by `degrees` about the unit `axis` (right-hand rule), in steps of at most step_deg;
        returns the last solution."""
        steps = max(1, math.ceil(abs(degrees - from_deg) / step_deg))
        for k in range(1, steps + 1):
            angle = math.radians(from_deg + (degrees - from_deg) * k / steps)
            turn = Rotation.from_rotvec(angle * np.asarray(axis, dtype=float))
            solution = self.solve(solution.x, solution.y, end_frame=turn * locked)
        return solution


def end_frame(solution) -> Rotation:
    """The frame at the end of a solution."""
    q = solution.y[3:7, -1]
    return Rotation.from_quat(q / np.linalg.norm(q))


def guess_from_result(result) -> tuple[np.ndarray, np.ndarray]:
    """Mesh and (13, N+1) initial guess from a hoseline Result: only a starting point for the solver."""
    frames = np.concatenate([result.start_frame[None], result.frames])  # rough: segment frames at the nodes
    quats = Rotation.from_matrix(np.transpose(frames, (0, 2, 1))).as_quat()
    for i in range(1, len(quats)):  # one continuous sign
        if quats[i] @ quats[i - 1] < 0.0:
            quats[i] = -quats[i]
    return result.s, np.vstack([result.centerline.T, quats.T, result.internal_force.T, result.internal_moment.T])
