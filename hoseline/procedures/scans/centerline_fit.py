"""The centreline and radius of a scanned hose: short best-fit cylinders along the whole hose.

The thesis fitted a few short cylinders by hand; this does it along the whole scan:

0. The cloud is reduced to a voxel grid of a tenth of the radius (voxel_cloud.py): the
   centroid of each occupied voxel, weighted by its point count, stands for its points, so a
   scan of millions of points costs about what one of 10^5 does.  Steps 1-3 and the first
   pass of step 4 only locate the hose and use a coarser grid (a quarter of the radius).
1. Isolated outliers are dropped (on the coarse grid: mean distance to the nearest
   neighbours far above the typical one).
2. Each surface point's normal (local principal axes) and the nominal radius give two
   candidate axis points, p +- r n; the one in the denser crowd of candidates is kept (true
   axis points gather on a curve, wrong ones spread over a tube of twice the radius), which
   works with one-sided coverage.
3. The axis points are ordered along the hose by the longest path of their minimum
   spanning tree (gaps in the scan are bridged by its shortest edge across).
4. Along that guide, every `spacing` mm, the surface points within half a `section` of the
   station are fitted with a cylinder whose axis may bend (cylinder_fit.py: axis point,
   direction, curvature, radius; robust least squares, so remaining outliers count little).
   Where the scan covers less than MIN_ARC_FOR_RADIUS_DEG of the circumference, the radius
   is fixed at the median of the well-covered sections and only the axis is fitted.
   Stretches of the guide longer than a radius on which no point projects are reported as
   gaps and get no station; neither do stations with too few points or points on one side
   only (the ends).
5. The guide is rebuilt along the fitted axis (a smoothing spline through the first pass'
   stations, continued a spacing beyond both ends), its stations placed whole spacings from
   the start hint, and the cylinders fitted once more.  So the stations lie where the hose
   is, not where the scan's points happen to end or the first pass happened to start.

The station of each cylinder is the point of its axis in the station's cross-section (the
thesis' "midpoint of the axis of the cylinder").  Units: mm.

The voxel grid moves the answer by about 0.001 mm against fits to every point (stations 0.0008 mm,
deviations 0.0002 mm at 1 and 5 million points: tests/test_large_scans.py, bench/bench_scans.py).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import make_smoothing_spline
from scipy.sparse.csgraph import dijkstra, minimum_spanning_tree
from scipy.spatial import cKDTree, distance_matrix

from hoseline.mechanics.blas_threads import one_blas_thread
from hoseline.procedures.scans.cloud_checks import check_count, check_spread
from hoseline.procedures.scans.cylinder_fit import fit_cylinder
from hoseline.procedures.scans.deviation import closest_on_polyline
from hoseline.procedures.scans.voxel_cloud import VoxelCloud, voxel_cloud

MIN_SECTION_POINTS = 25
NEIGHBOURS = 16
GUIDE_POINTS = 1500  # the spanning tree is built on at most this many axis points
VOXELS_PER_RADIUS = 10  # default voxel edge: a tenth of the radius
GUIDE_VOXELS_PER_RADIUS = 4  # the guide and the first pass of fits use a coarser grid: a quarter of the radius
CHUNK = 200_000  # points per block in the neighbour computations (bounds their memory)
MAX_STATIONS = 100_000  # stations along a guide (a 10 m hose at 0.1 mm): more is a scan the fit went astray on
AXIS_SAMPLES_PER_STATION = 10  # the second pass samples the fitted axis every tenth of a spacing


@dataclass
class CenterlineFit:
    """Result of fit_centerline (mm, degrees).

    points: (m, 3) fitted axis points, one per station, from the start end of the hose.
    tangents: (m, 3) fitted axis directions.
    s: (m,) arc length along the fitted centreline.
    radius: (m,) fitted radius per section; radius_fitted: False where it was fixed (low coverage).
    coverage_deg: (m,) arc of the circumference the section's points cover.
    point_count: (m,) surface points per section.  rms: (m,) fit residual per section (of the
    voxel centroids: the scanner's noise within a voxel is averaged out).  axis_sigma: (m,) the
    standard uncertainty of each station's axis point in one direction of its cross-section, from the
    scan's own noise (cylinder_fit._axis_sigma).
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
    axis_sigma: np.ndarray
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
    voxel: float | None = None,
    every_point: bool = False,
) -> CenterlineFit:
    """Fit short cylinders along a scanned hose surface.

    points: (n, 3) surface points, mm.  nominal_radius: outer radius of the hose, mm.
    section: length of each fitted cylinder, mm (default two diameters).
    spacing: distance between stations, mm (default one radius).
    start_hint: a point near the start of the hose (e.g. the start mount), to number the
    stations from that end.
    voxel: edge of the voxel grid for the final fits, mm (default a tenth of the radius; 0:
    every point, slow beyond ~10^5 points).  The outlier test, the guide and the first pass
    use a grid of at least a quarter of the radius.
    every_point: fit the final cylinders to every point that is not an outlier rather than
    to the voxel centroids (slow: the reference the voxel grid is measured against).
    Raises ValueError when the points do not form a hose-like shape (cloud_checks.py: too few distinct
    points, or on a line or a plane; or a guide or axis of more than MAX_STATIONS stations).
    """
    if not nominal_radius > 0.0:
        raise ValueError(f"nominal radius = {nominal_radius!r}: give the hose's outer radius in mm")
    section = 4.0 * nominal_radius if section is None else section
    spacing = nominal_radius if spacing is None else spacing
    voxel = nominal_radius / VOXELS_PER_RADIUS if voxel is None else voxel
    if not voxel >= 0.0:
        raise ValueError(f"voxel = {voxel!r}: give the voxel edge in mm, 0 or more")
    points = np.asarray(points, dtype=float)
    grid = voxel_cloud(points, voxel)
    coarse_edge = max(voxel, nominal_radius / GUIDE_VOXELS_PER_RADIUS)
    coarse = voxel_cloud(grid.points, coarse_edge, weights=grid.counts)
    check_count(coarse.points, nominal_radius, coarse_edge)
    kept_coarse = _not_isolated(coarse)
    kept = kept_coarse[coarse.inverse]
    clean, coarse = grid.subset(kept), coarse.subset(kept_coarse)
    check_spread(coarse.points, nominal_radius)
    guide = _guide_from_axis_points(_axis_candidates(coarse.points, nominal_radius), nominal_radius, spacing)
    if start_hint is not None and np.linalg.norm(guide[-1] - start_hint) < np.linalg.norm(guide[0] - start_hint):
        guide = guide[::-1]
    first = _fit_sections(coarse, guide, nominal_radius, section, _coverage_gaps(coarse.points, guide, nominal_radius))
    if first.points.shape[0] >= 5:  # second pass along the fitted axis, a spacing longer at both ends
        axis = _extend(_along_spline(first.points, spacing / AXIS_SAMPLES_PER_STATION), spacing)
        guide = _resample(axis, spacing, _phase(axis, start_hint, spacing))
    final = clean
    if every_point:
        surface = points[kept[grid.inverse]]
        final = VoxelCloud(surface, np.ones(surface.shape[0], dtype=np.int64))
    fit = _fit_sections(final, guide, nominal_radius, section, _coverage_gaps(coarse.points, guide, nominal_radius))
    fit.outliers = int(np.sum(grid.counts[~kept]))
    return fit


def _not_isolated(cloud: VoxelCloud) -> np.ndarray:
    """Mask of the voxels whose mean distance to their nearest neighbours is not far above the typical one.

    Typical: the median over the scan's points (each voxel counts with its points), because a
    stray point keeps a voxel of its own while the surface's points share theirs: on a dense
    scan the stray voxels can outnumber the surface's.
    """
    tree = cKDTree(cloud.points)
    ranks = np.arange(2, min(9, cloud.points.shape[0]) + 1)  # the nearest neighbours but the point itself
    mean = np.concatenate([tree.query(cloud.points[start : start + CHUNK], k=ranks, workers=-1)[0].mean(axis=1)
                           for start in range(0, cloud.points.shape[0], CHUNK)])
    median = _weighted_median(mean, cloud.counts)
    spread = 1.4826 * _weighted_median(np.abs(mean - median), cloud.counts)
    return mean <= median + 6.0 * spread + 0.5 * median


def _weighted_median(values: np.ndarray, weights: np.ndarray) -> float:
    """The value below which half of the total weight lies."""
    order = np.argsort(values)
    cumulative = np.cumsum(weights[order])
    return float(values[order][np.searchsorted(cumulative, 0.5 * cumulative[-1])])


def _axis_candidates(points: np.ndarray, radius: float) -> np.ndarray:
    """One candidate axis point per surface point: p -+ r n on the side where the candidates crowd."""
    tree = cKDTree(points)
    normals = np.empty_like(points)
    for start in range(0, points.shape[0], CHUNK):
        _, neighbours = tree.query(points[start : start + CHUNK], k=min(NEIGHBOURS, points.shape[0]), workers=-1)
        local = points[neighbours] - points[neighbours].mean(axis=1, keepdims=True)
        scatter = np.einsum("nki,nkj->nij", local, local)
        normals[start : start + CHUNK] = np.linalg.eigh(scatter)[1][:, :, 0]  # smallest principal axis
    both = np.concatenate([points + radius * normals, points - radius * normals])
    crowd = cKDTree(both).query_ball_point(both, 0.4 * radius, return_length=True, workers=-1)
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


def _along_spline(points: np.ndarray, step: float) -> np.ndarray:
    """A polyline every ~`step` mm along the smoothing spline through ordered points (smoothing chosen by
    generalised cross-validation): it follows bends and gaps instead of cutting them with chords, so
    arc lengths along it hardly depend on where the points lie."""
    t = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    samples = _station_count(t[-1], step, MAX_STATIONS * AXIS_SAMPLES_PER_STATION, "the fitted axis")
    return make_smoothing_spline(t, points)(np.linspace(0.0, t[-1], samples))


def _extend(polyline: np.ndarray, length: float) -> np.ndarray:
    """The polyline continued straight by `length` mm beyond both ends (stations there are kept only
    where the scan has points on both sides)."""
    before = polyline[0] - length * (polyline[1] - polyline[0]) / np.linalg.norm(polyline[1] - polyline[0])
    after = polyline[-1] + length * (polyline[-1] - polyline[-2]) / np.linalg.norm(polyline[-1] - polyline[-2])
    return np.vstack([before, polyline, after])


def _phase(polyline: np.ndarray, start_hint: np.ndarray | None, spacing: float) -> float:
    """Arc length along the polyline of its first station, mm, so that the stations lie whole spacings
    from the start hint (measured along the polyline, extended straight from its start): they then do
    not depend on where the scan's points happen to end.  0 without a hint."""
    if start_hint is None:
        return 0.0
    direction = (polyline[1] - polyline[0]) / np.linalg.norm(polyline[1] - polyline[0])
    return float((np.asarray(start_hint, dtype=float) - polyline[0]) @ direction % spacing)


def _resample(polyline: np.ndarray, spacing: float, first: float = 0.0) -> np.ndarray:
    """Points every `spacing` mm of arc length along a polyline from arc length `first` (both ends if it is short)."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(polyline, axis=0), axis=1))])
    _station_count(s[-1] - first, spacing, MAX_STATIONS, "the guide along the scan")
    stations = np.arange(first, s[-1], spacing)
    if stations.size < 2:
        stations = np.array([0.0, s[-1]])
    return np.column_stack([np.interp(stations, s, polyline[:, k]) for k in range(3)])


def _station_count(length: float, step: float, largest: int, what: str) -> int:
    """Points every `step` mm along `length` mm, both ends included; ValueError naming `what` when more than
    `largest` (or the length is not finite): the scan led the fit astray."""
    count = length / step + 1.0
    if not count <= largest:
        raise ValueError(f"{what} is {length:.4g} mm long: {count:.4g} points {step:.3g} mm apart, more than {largest}; "
                         "the scan does not show one hose of this radius (check the radius and that the scan is in mm)")
    return int(np.ceil(length / step)) + 1


def _fit_sections(cloud: VoxelCloud, guide: np.ndarray, radius: float, section: float,
                  gaps: list[tuple[float, float]]) -> CenterlineFit:
    """A cylinder at every guide station outside the gaps, fitted to the count-weighted points near it."""
    tangents = np.gradient(guide, axis=0)
    tangents /= np.linalg.norm(tangents, axis=1)[:, None]
    tree = cKDTree(cloud.points)
    reach = np.hypot(0.5 * section, 2.0 * radius)
    guide_s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(guide, axis=0), axis=1))])
    fits = []
    # The fits are small dense problems: OpenBLAS threads only add waiting (a 4000 x 7 SVD took
    # 62 ms with its threads on this 2-core machine under load, 0.7 ms with one).
    with one_blas_thread():
        for index, (centre, tangent) in enumerate(zip(guide, tangents)):
            if any(low <= guide_s[index] <= high for low, high in gaps):
                continue
            near = np.asarray(tree.query_ball_point(centre, reach), dtype=np.int64)
            along = (cloud.points[near] - centre) @ tangent
            inside = np.abs(along) <= 0.5 * section
            near, along = near[inside], along[inside]
            counts = cloud.counts[near]
            total = counts.sum()
            if total >= MIN_SECTION_POINTS and min(counts[along < 0].sum(), counts[along > 0].sum()) >= 0.25 * total:
                fit = fit_cylinder(cloud.points[near], counts, centre, tangent, radius)
                if np.linalg.norm(fit["axis_point"] - centre) <= reach:  # else an axis away from its points: astray
                    fits.append((index, fit))
            # else: too few points, or points on one side of the station only (an end): no station
        fixed_radius = np.median([f["radius"] for _, f in fits if f["radius_fitted"]] or [radius])
        fits = [(i, fit_cylinder(f["points"], f["weights"], f["axis_point"], f["tangent"], fixed_radius, False))
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
        point_count=np.array([int(f["weights"].sum()) for _, f in fits]),
        rms=np.array([f["rms"] for _, f in fits]),
        axis_sigma=np.array([f["axis_sigma"] for _, f in fits]),
        gaps=gaps,
    )


def _coverage_gaps(points: np.ndarray, guide: np.ndarray, radius: float) -> list[tuple[float, float]]:
    """(from, to) arc lengths along the guide, mm, longer than a radius, on which no scan point projects."""
    along = np.sort(closest_on_polyline(points, guide)[1])
    steps = np.diff(along)
    return [(float(along[i]), float(along[i + 1])) for i in np.flatnonzero(steps > radius)]
