"""A short bent cylinder fitted to the scan points near one station: robust least squares, exact Jacobian.

The axis is a parabola x(t) = point + t direction + t^2/2 (k1 e1 + k2 e2), so a bent hose does
not pull the axis towards the outside of the bend (a straight cylinder is pulled ~0.2 mm in a
42 mm bend).  The points may stand for several scan points each (voxel centroids with their
counts, voxel_cloud.py): their soft-L1 losses are weighted by the counts.  Units: mm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

NEAREST_NEWTON_STEPS = 2  # to each point's nearest point on the bent axis (BentCylinder.offsets)
MIN_ARC_FOR_RADIUS_DEG = 120.0  # below this coverage the radius and the axis cannot be told apart


@dataclass
class BentCylinder:
    """Residuals of points (n, 3) against a bent cylinder near a station (centre, unit tangent), mm.

    Unknowns x: the axis point's offset in the station's cross-section along e1, e2 (2), the
    tilt of the axis (2), its curvature (2) and, when radius is None, the radius (1).
    """

    points: np.ndarray
    centre: np.ndarray
    tangent: np.ndarray
    radius: float | None = None

    def __post_init__(self):
        e1 = np.cross(self.tangent, [1.0, 0.0, 0.0] if abs(self.tangent[0]) < 0.9 else [0.0, 1.0, 0.0])
        self.e1 = e1 / np.linalg.norm(e1)
        self.e2 = np.cross(self.tangent, self.e1)

    def axis(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """The axis point in the station's cross-section, the unit axis direction, and |tangent + tilt|."""
        point = self.centre + x[0] * self.e1 + x[1] * self.e2
        direction = self.tangent + x[2] * self.e1 + x[3] * self.e2
        length = float(np.linalg.norm(direction))
        return point, direction / length, length

    def offsets(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per point: its radial offset u from the bent axis (n, 3), its position t along the axis and p - point.

        t is the parameter of the point's nearest point on the bent axis c(t) = t d + t^2/2 b (relative to the axis
        point), so u is normal to the axis there: two Newton steps on (q - c(t)) . c'(t) = 0 from the projection
        t = q . d.  The projection alone measures the offset normal to the straight tangent, which narrows a
        curved tube's section in its bend plane by r (kappa t)^2 / 2 towards the section's ends; on a scan that
        sees one side only, a circle fitted to that narrowed section moves its axis away from the scanner (0.025 mm
        on the thesis hose, biasing a calibrated EI by -0.3 %).  With u normal to the axis the jacobian's terms of
        dt vanish (the envelope theorem), so it keeps its form."""
        point, direction, _ = self.axis(x)
        relative = self.points - point
        bend = x[4] * self.e1 + x[5] * self.e2
        t = relative @ direction
        for _ in range(NEAREST_NEWTON_STEPS):
            tangent = direction[None, :] + t[:, None] * bend[None, :]
            off = relative - np.outer(t, direction) - 0.5 * np.outer(t * t, bend)
            t = t + np.einsum("ij,ij->i", off, tangent) / (np.einsum("ij,ij->i", tangent, tangent) - off @ bend)
        return relative - np.outer(t, direction) - 0.5 * np.outer(t * t, bend), t, relative

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """|u| - radius per point, mm."""
        return np.linalg.norm(self.offsets(x)[0], axis=1) - (x[6] if self.radius is None else self.radius)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """d residuals / d x (n, 6 or 7), exact.

        With q = p - point, d the unit direction, t = q.d, b the bend vector and n = u/|u|:
        du = dq - dt d - t dd - t dt b, so d|u| = n.dq - dt (n.d + t n.b) - t n.dd.
        """
        radial, t, relative = self.offsets(x)
        _, direction, length = self.axis(x)
        unit = radial / np.linalg.norm(radial, axis=1)[:, None]
        along = unit @ direction + t * (unit @ (x[4] * self.e1 + x[5] * self.e2))
        columns = []
        for e in (self.e1, self.e2):  # the axis point moves along e: dq = -e, dt = -e.d
            columns.append(-(unit @ e) + (e @ direction) * along)
        for e in (self.e1, self.e2):  # the tilt: dd = (e - d (d.e)) / |tangent + tilt|, dt = q.dd
            turn = (e - direction * (direction @ e)) / length
            columns.append(-(relative @ turn) * along - t * (unit @ turn))
        for e in (self.e1, self.e2):  # the curvature: du = -t^2/2 e
            columns.append(-0.5 * t * t * (unit @ e))
        if self.radius is None:
            columns.append(-np.ones_like(t))
        return np.column_stack(columns)


def fit_cylinder(points, weights, centre, tangent, radius, free_radius=True) -> dict:
    """Robust bent cylinder through `points` (n, 3) near the station (centre, tangent); radius free or fixed.

    weights: (n,) scan points each entry stands for.  radius: the nominal (free) or the fixed
    radius, mm.  Returns the points and weights, the axis point in the station's cross-section,
    the unit axis direction there, the radius and whether it was fitted (not where the points
    cover less than MIN_ARC_FOR_RADIUS_DEG of the circumference, or the fit left 0.5-2 times the
    nominal), the covered arc (degrees), the weighted RMS residual (of voxel centroids: the
    scanner noise is averaged within each voxel) and the axis point's standard uncertainty (axis_sigma, mm).
    """
    weights = np.asarray(weights, dtype=float)
    cylinder = BentCylinder(points, centre, tangent, None if free_radius else radius)

    def weighted_soft_l1(z):
        """The soft-L1 loss of each residual times its weight: value, first and second derivative in z."""
        root = np.sqrt(1.0 + z)
        return np.vstack([weights * 2.0 * (root - 1.0), weights / root, -0.5 * weights / root**3])

    x0 = np.array([0.0] * 6 + ([radius] if free_radius else []))
    scale = np.array([radius] * 4 + [1.0 / radius] * 2 + ([radius] if free_radius else []))
    solution = least_squares(cylinder.residuals, x0, jac=cylinder.jacobian, loss=weighted_soft_l1,
                             f_scale=0.05 * radius, x_scale=scale)
    point, direction, _ = cylinder.axis(solution.x)
    radial = cylinder.offsets(solution.x)[0]
    angles = np.sort(np.arctan2(radial @ cylinder.e2, radial @ cylinder.e1))
    largest_gap = np.max(np.diff(np.concatenate([angles, angles[:1] + 2.0 * np.pi])))
    coverage = np.degrees(2.0 * np.pi - largest_gap)
    fitted_radius = solution.x[6] if free_radius else radius
    rms = float(np.sqrt(np.sum(weights * solution.fun**2) / np.sum(weights)))
    if free_radius and (coverage < MIN_ARC_FOR_RADIUS_DEG or not 0.5 * radius < fitted_radius < 2.0 * radius):
        free_radius = False  # refitted with the median radius of the well-covered sections
    return {
        "points": points,
        "weights": weights,
        "axis_point": point,
        "tangent": direction if direction @ tangent > 0 else -direction,
        "radius": float(fitted_radius),
        "radius_fitted": free_radius,
        "coverage": float(coverage),
        "rms": rms,
        "axis_sigma": _axis_sigma(cylinder.jacobian(solution.x), weights, rms),
    }


def _axis_sigma(jacobian: np.ndarray, weights: np.ndarray, rms: float) -> float:
    """The standard uncertainty (mm) of the fitted axis point in one direction of its cross-section: the square root
    of the mean of the two diagonal terms of its covariance, rms^2 (J^T W J)^-1, with the residuals' weighted RMS
    (mm) for the noise of one scan point and W the points each entry stands for (a voxel centroid averages its
    points' noise).  The least-squares covariance with every parameter free (tilt, curvature and radius too), so a
    one-sided section, whose axis is less determined, gets a larger one."""
    information = jacobian.T @ (weights[:, None] * jacobian)
    try:
        covariance = rms**2 * np.linalg.inv(information)
    except np.linalg.LinAlgError:
        return float("inf")
    return float(np.sqrt(max(0.5 * (covariance[0, 0] + covariance[1, 1]), 0.0)))
