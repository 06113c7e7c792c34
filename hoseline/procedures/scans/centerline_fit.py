"""The centreline and radius of a scanned hose: short best-fit cylinders along the whole hose.

The thesis fitted a few short cylinders by hand; this does it along the whole scan:

1. Isolated outliers are dropped (mean distance to the nearest neighbours far above the
   typical one).
2. Each surface point's normal (local principal axes) and the nominal radius give two
   candidate axis points, p +- r n; the one in the denser crowd of candidates is kept (true
   axis points gather on a curve, wrong ones spread over a tube of twice the radius), which
   works with one-sided coverage.
3. The axis points are ordered along the hose by the longest path of their minimum
   spanning tree (gaps in the scan are bridged by its shortest edge across).
4. Along that guide, every `spacing` mm, the surface points within half a `section` of the
   station are fitted with a cylinder whose axis may bend (axis point, direction, curvature,
   radius) by robust least squares (soft-L1 loss, so remaining outliers count little).  Where the scan covers less
   than MIN_ARC_FOR_RADIUS_DEG of the circumference, the radius is fixed at the median of
   the well-covered sections and only the axis is fitted.  Stretches of the guide longer
   than a radius on which no point projects are reported as gaps and get no station;
   neither do stations with too few points or points on one side only (the ends).
5. The guide is rebuilt from the fitted axis and the cylinders fitted once more.

The station of each cylinder is the point of its axis in the station's cross-section (the
thesis' "midpoint of the axis of the cylinder").  Units: mm.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares
from scipy.sparse.csgraph import dijkstra, minimum_spanning_tree
from scipy.spatial import cKDTree, distance_matrix

from hoseline.procedures.scans.deviation import closest_on_polyline

MIN_ARC_FOR_RADIUS_DEG = 120.0  # below this coverage the radius and the axis cannot be told apart
MIN_SECTION_POINTS = 25
NEIGHBOURS = 16
GUIDE_POINTS = 1500  # the spanning tree is built on at most this many axis points


@dataclass
class CenterlineFit:
    """Result of fit_centerline (mm, degrees).

    points: (m, 3) fitted axis points, one per station, from the start end of the hose.
    tangents: (m, 3) fitted axis directions.
    s: (m,) arc length along the fitted centreline.
    radius: (m,) fitted radius per section; radius_fitted: False where it was fixed (low coverage).
    coverage_deg: (m,) arc of the circumference the section's points cover.
    point_count: (m,) surface points per section.  rms: (m,) fit residual per section.
    gaps: (from, to) arc-length ranges along the guide with no scan points (longer than a radius).
    outliers: points dropped as isolated.
    """

    points: np.ndarray
    tangents: np.ndarray
    s: np.ndarray
    radius: np.ndarray
    radius_fitted: np.ndarray
    coverage_deg: np.ndarray
    point_count: np.ndarray
    rms: np.ndarray
    gaps: list[tuple[float, float]] = field(default_factory=list)
    outliers: int = 0

    @property
    def radius_median(self) -> float:
        """Median of the fitted radii (fixed ones excluded), mm."""
        fitted = self.radius[self.radius_fitted]
        return float(np.median(fitted if fitted.size else self.radius))

    @property
    def radius_scatter(self) -> float:
        """Standard deviation of the fitted radii about their mean, mm (0 with fewer than two)."""
        fitted = self.radius[self.radius_fitted]
        return float(np.std(fitted, ddof=1)) if fitted.size > 1 else 0.0


def fit_centerline(
    points: np.ndarray,
    nominal_radius: float,
    *,
    section: float | None = None,
    spacing: float | None = None,
    start_hint: np.ndarray | None = None,
) -> CenterlineFit:
    """Fit short cylinders along a scanned hose surface.

    points: (n, 3) surface points, mm.  nominal_radius: outer radius of the hose, mm.
    section: length of each fitted cylinder, mm (default two diameters).
    spacing: distance between stations, mm (default one radius).
    start_hint: a point near the start of the hose (e.g. the start mount), to number the
    stations from that end.
    Raises ValueError when the points do not form a hose-like shape.
    """
    if not nominal_radius > 0.0:
        raise ValueError(f"nominal radius = {nominal_radius!r}: give the hose's outer radius in mm")
    section = 4.0 * nominal_radius if section is None else section
    spacing = nominal_radius if spacing is None else spacing
    points = np.asarray(points, dtype=float)
    clean = _drop_outliers(points)
    guide = _guide_from_axis_points(_axis_candidates(clean, nominal_radius), nominal_radius, spacing)
    if start_hint is not None and np.linalg.norm(guide[-1] - start_hint) < np.linalg.norm(guide[0] - start_hint):
        guide = guide[::-1]
    fit = _fit_sections(clean, guide, nominal_radius, section)
    if fit.points.shape[0] >= 4:  # second pass along the fitted axis
        guide = _resample(_smooth(fit.points, 2), spacing)
        fit = _fit_sections(clean, guide, nominal_radius, section)
    fit.outliers = points.shape[0] - clean.shape[0]
    return fit


def _drop_outliers(points: np.ndarray) -> np.ndarray:
    """Points whose mean distance to their nearest neighbours is not far above the typical one."""
    tree = cKDTree(points)
    distances, _ = tree.query(points, k=min(9, points.shape[0]))
    mean = distances[:, 1:].mean(axis=1)
    median = np.median(mean)
    spread = 1.4826 * np.median(np.abs(mean - median))
    return points[mean <= median + 6.0 * spread + 0.5 * median]


def _axis_candidates(points: np.ndarray, radius: float) -> np.ndarray:
    """One candidate axis point per surface point: p -+ r n on the side where the candidates crowd."""
    tree = cKDTree(points)
    _, neighbours = tree.query(points, k=min(NEIGHBOURS, points.shape[0]))
    local = points[neighbours] - points[neighbours].mean(axis=1, keepdims=True)
    _, vectors = np.linalg.eigh(np.einsum("nki,nkj->nij", local, local))
    normals = vectors[:, :, 0]  # smallest principal axis
    both = np.concatenate([points + radius * normals, points - radius * normals])
    crowd = cKDTree(both).query_ball_point(both, 0.4 * radius, return_length=True)
    n = points.shape[0]
    return np.where((crowd[:n] >= crowd[n:])[:, None], both[:n], both[n:])


def _guide_from_axis_points(axis_points: np.ndarray, radius: float, spacing: float) -> np.ndarray:
    """An ordered polyline through the axis points: the longest path of their minimum spanning tree."""
    cell = 0.5 * radius
    keys = np.floor(axis_points / cell).astype(np.int64)
    _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.reshape(-1)
    centres = np.zeros((counts.size, 3))
    np.add.at(centres, inverse, axis_points)
    centres /= counts[:, None]
    centres = centres[counts >= max(2, np.percentile(counts, 10))]  # cells of stray candidates
    if centres.shape[0] > GUIDE_POINTS:
        centres = centres[np.random.default_rng(0).choice(centres.shape[0], GUIDE_POINTS, replace=False)]
    if centres.shape[0] < 4:
        raise ValueError("the scan does not show a hose: too few points agree on an axis; check the radius and the units")
    tree = minimum_spanning_tree(distance_matrix(centres, centres))
    tree = tree + tree.T
    far = int(np.argmax(dijkstra(tree, indices=0)))
    lengths, predecessors = dijkstra(tree, indices=far, return_predecessors=True)
    node = int(np.argmax(lengths))
    path = [node]
    while predecessors[node] >= 0:
        node = int(predecessors[node])
        path.append(node)
    return _resample(_smooth(centres[path], 3), spacing)


def _smooth(polyline: np.ndarray, half_width: int) -> np.ndarray:
    """Moving average over 2*half_width+1 points, ends kept in place."""
    if polyline.shape[0] <= 2 * half_width + 1:
        return polyline
    kernel = np.ones(2 * half_width + 1) / (2 * half_width + 1)
    padded = np.concatenate([np.repeat(polyline[:1], half_width, 0), polyline, np.repeat(polyline[-1:], half_width, 0)])
    return np.column_stack([np.convolve(padded[:, k], kernel, mode="valid") for k in range(3)])


def _resample(polyline: np.ndarray, spacing: float) -> np.ndarray:
    """Points every `spacing` mm of arc length along a polyline (both ends included)."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(polyline, axis=0), axis=1))])
    stations = np.linspace(0.0, s[-1], max(2, int(round(s[-1] / spacing)) + 1))
    return np.column_stack([np.interp(stations, s, polyline[:, k]) for k in range(3)])


def _fit_sections(points: np.ndarray, guide: np.ndarray, radius: float, section: float) -> CenterlineFit:
    """A cylinder at every guide station; stations with too few points become gaps."""
    tangents = np.gradient(guide, axis=0)
    tangents /= np.linalg.norm(tangents, axis=1)[:, None]
    tree = cKDTree(points)
    reach = np.hypot(0.5 * section, 2.0 * radius)
    guide_s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(guide, axis=0), axis=1))])
    gaps = _coverage_gaps(points, guide, radius)
    fits = []
    for index, (centre, tangent) in enumerate(zip(guide, tangents)):
        if any(low <= guide_s[index] <= high for low, high in gaps):
            continue
        near = points[tree.query_ball_point(centre, reach)]
        along = (near - centre) @ tangent
        inside = np.abs(along) <= 0.5 * section
        near, along = near[inside], along[inside]
        if near.shape[0] >= MIN_SECTION_POINTS and min(np.sum(along < 0), np.sum(along > 0)) >= 0.25 * near.shape[0]:
            fits.append((index, _fit_cylinder(near, centre, tangent, radius)))
        # else: too few points, or points on one side of the station only (an end): no station
    fixed_radius = np.median([f["radius"] for _, f in fits if f["radius_fitted"]] or [radius])
    fits = [(i, _fit_cylinder(f["points"], f["axis_point"], f["tangent"], fixed_radius, False))
            if not f["radius_fitted"] else (i, f) for i, f in fits]
    if not fits:
        raise ValueError("no section of the scan has enough points for a cylinder: is it a hose, in mm?")
    axis_points = np.array([f["axis_point"] for _, f in fits])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(axis_points, axis=0), axis=1))])
    return CenterlineFit(
        points=axis_points,
        tangents=np.array([f["tangent"] for _, f in fits]),
        s=s,
        radius=np.array([f["radius"] for _, f in fits]),
        radius_fitted=np.array([f["radius_fitted"] for _, f in fits]),
        coverage_deg=np.array([f["coverage"] for _, f in fits]),
        point_count=np.array([f["points"].shape[0] for _, f in fits]),
        rms=np.array([f["rms"] for _, f in fits]),
        gaps=gaps,
    )


def _coverage_gaps(points: np.ndarray, guide: np.ndarray, radius: float) -> list[tuple[float, float]]:
    """(from, to) arc lengths along the guide, mm, longer than a radius, on which no scan point projects."""
    along = np.sort(closest_on_polyline(points, guide)[1])
    steps = np.diff(along)
    return [(float(along[i]), float(along[i + 1])) for i in np.flatnonzero(steps > radius)]


def _fit_cylinder(points, centre, tangent, radius, free_radius=True) -> dict:
    """Robust bent cylinder through `points` near the station (centre, tangent); radius free or fixed.

    The axis is a parabola x(t) = point + t direction + t^2/2 (k1 e1 + k2 e2), so a bent hose
    does not pull the axis towards the outside of the bend.  Unknowns: the axis point's
    offset in the station's cross-section (2), the tilt of the axis (2), its curvature (2)
    and, if free, the radius.  Returns the axis point in the station's cross-section, the
    unit axis direction there, the radius, the covered arc and the RMS residual.
    """
    e1 = np.cross(tangent, [1.0, 0.0, 0.0] if abs(tangent[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(tangent, e1)

    def axis(x):
        point = centre + x[0] * e1 + x[1] * e2
        direction = tangent + x[2] * e1 + x[3] * e2
        return point, direction / np.linalg.norm(direction)

    def radial_offsets(x):
        point, direction = axis(x)
        relative = points - point
        t = relative @ direction
        return relative - np.outer(t, direction) - 0.5 * np.outer(t * t, x[4] * e1 + x[5] * e2)

    def residuals(x):
        return np.linalg.norm(radial_offsets(x), axis=1) - (x[6] if free_radius else radius)

    x0 = np.array([0.0] * 6 + ([radius] if free_radius else []))
    scale = np.array([radius] * 4 + [1.0 / radius] * 2 + ([radius] if free_radius else []))
    solution = least_squares(residuals, x0, loss="soft_l1", f_scale=0.05 * radius, x_scale=scale)
    point, direction = axis(solution.x)
    radial = radial_offsets(solution.x)
    angles = np.sort(np.arctan2(radial @ e2, radial @ e1))
    largest_gap = np.max(np.diff(np.concatenate([angles, angles[:1] + 2.0 * np.pi])))
    coverage = np.degrees(2.0 * np.pi - largest_gap)
    fitted_radius = solution.x[6] if free_radius else radius
    if free_radius and (coverage < MIN_ARC_FOR_RADIUS_DEG or not 0.5 * radius < fitted_radius < 2.0 * radius):
        free_radius = False  # refitted with the median radius of the well-covered sections
    return {
        "points": points,
        "axis_point": point,
        "tangent": direction if direction @ tangent > 0 else -direction,
        "radius": float(fitted_radius),
        "radius_fitted": free_radius,
        "coverage": float(coverage),
        "rms": float(np.sqrt(np.mean(solution.fun**2))),
    }
