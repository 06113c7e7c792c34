"""Scans of real size: the voxel grid keeps the answer of every point; stations stay put; the grid; the Jacobian."""

from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial import cKDTree
from validation_cases import RADIUS, scanned

from hoseline.procedures.scans.centerline_fit import fit_centerline
from hoseline.procedures.scans.cylinder_fit import BentCylinder
from hoseline.procedures.scans.deviation import deviation
from hoseline.procedures.scans.synthetic_scan import ScanDefects
from hoseline.procedures.scans.voxel_cloud import voxel_cloud

# 139 000 points of a one-sided scan with a 20 mm gap, 0.05 mm noise, 0.5 % stray points
DENSE = ScanDefects(density=28.0, noise=0.05, outlier_fraction=0.005, view=(0.2, 0.3, -1.0), gaps=((150.0, 170.0),))


def paired(a, b):
    """Distances from each station of a to the nearest station of b, mm."""
    return cKDTree(b).query(a)[0]


def test_the_voxel_grid_keeps_the_answer_of_every_point():
    truth, points = scanned(180.0, DENSE)
    assert 130_000 < points.shape[0] < 150_000
    hint = truth.problem.start.point
    fast = fit_centerline(points, RADIUS, start_hint=hint)
    full = fit_centerline(points, RADIUS, start_hint=hint, every_point=True)  # same guide, every point in the fits
    assert fast.points.shape == full.points.shape
    # the counts carry every point; voxels across a section's ends go in or out whole (measured 0.4 %)
    np.testing.assert_allclose(fast.point_count, full.point_count, rtol=0.012)
    # measured: stations 0.0008 mm apart (0.0011 mm on a 216 000-point scan)
    assert np.max(np.linalg.norm(fast.points - full.points, axis=1)) < 0.003
    # measured: mean deviation 0.00002 mm and largest 0.00008 mm apart (up to 0.0007 mm on other scans)
    fast_deviation, full_deviation = deviation(truth.centerline, fast.points), deviation(truth.centerline, full.points)
    assert abs(fast_deviation.mean - full_deviation.mean) < 0.001
    assert abs(fast_deviation.max - full_deviation.max) < 0.001
    # the centroid of a voxel of edge a = r/10 lies ~a^2/(24 r) = 0.002 mm inside the surface (measured 0.0016)
    assert -0.005 < fast.radius_median - full.radius_median < 0.0
    assert fast.outliers == full.outliers > 0


def test_stations_lie_whole_spacings_from_the_start_mount_whatever_the_sample():
    truth, first = scanned(180.0, seed=0)
    _, second = scanned(180.0, seed=1)
    hint = truth.problem.start.point
    a, b = (fit_centerline(points, RADIUS, start_hint=hint) for points in (first, second))
    # two scans of the same shape (0.1 mm noise): stations at the same places along the hose, measured
    # 0.071 mm apart at most (placed from wherever the first pass started, as before: 1.14 mm)
    assert np.max(paired(a.points, b.points)) < 0.2
    s_hint = (a.points[0] - hint) @ a.tangents[0]  # the first station's distance from the mount, along the hose
    assert s_hint / RADIUS == pytest.approx(round(s_hint / RADIUS), abs=0.01)  # measured 1.0007


def test_voxel_cloud_centroids_counts_and_inverse():
    rng = np.random.default_rng(3)
    points = rng.uniform(-2.0, 3.0, size=(20_000, 3))
    grid = voxel_cloud(points, 0.7)
    cells = np.floor((points - points.min(axis=0)) / 0.7)
    _, inverse, counts = np.unique(cells, axis=0, return_inverse=True, return_counts=True)
    np.testing.assert_array_equal(np.sort(grid.counts), np.sort(counts))
    np.testing.assert_array_equal(grid.counts[grid.inverse], counts[inverse.ravel()])
    for voxel in (0, 17, grid.inverse[5]):
        np.testing.assert_allclose(grid.points[voxel], points[grid.inverse == voxel].mean(axis=0), atol=1e-12)
    weights = rng.integers(1, 5, size=points.shape[0])
    weighted = voxel_cloud(points, 0.7, weights=weights)
    members = weighted.inverse == 17
    np.testing.assert_allclose(weighted.points[17], np.average(points[members], axis=0, weights=weights[members]))
    assert weighted.counts[17] == weights[members].sum()
    same = voxel_cloud(points, 0.0)
    np.testing.assert_array_equal(same.points, points)
    assert np.all(same.counts == 1)
    with pytest.raises(ValueError, match="check that it is in mm"):
        voxel_cloud(np.array([[0.0, 0.0, 0.0], [1e9, 1e9, 1e9]]), 0.5)


@pytest.mark.parametrize("radius", [None, 5.0])
def test_bent_cylinder_jacobian_is_exact(radius):
    rng = np.random.default_rng(4)
    t = rng.uniform(-10.0, 10.0, 400)
    angle = rng.uniform(0.0, 2.0 * np.pi, 400)
    points = np.column_stack([5.0 * np.cos(angle), 5.0 * np.sin(angle) + 0.01 * t**2, t]) + rng.normal(0, 0.1, (400, 3))
    tangent = np.array([0.1, 0.05, 1.0]) / np.linalg.norm([0.1, 0.05, 1.0])
    cylinder = BentCylinder(points, np.array([0.3, -0.2, 0.1]), tangent, radius)
    x = np.array([0.2, -0.1, 0.05, -0.03, 0.02, -0.01, 5.1][: 7 if radius is None else 6])
    numeric = np.empty((400, x.size))
    for k in range(x.size):
        step = np.zeros(x.size)
        step[k] = 1e-6
        numeric[:, k] = (cylinder.residuals(x + step) - cylinder.residuals(x - step)) / 2e-6
    np.testing.assert_allclose(cylinder.jacobian(x), numeric, rtol=1e-6, atol=1e-7)


def test_stray_points_are_dropped_even_where_they_outnumber_the_surface_voxels():
    truth, points = scanned(0.0, replace(DENSE, outlier_fraction=0.1))  # 13 800 stray voxels, 4 200 of the surface
    strays = int(round(0.1 * points.shape[0] / 1.1))
    fit = fit_centerline(points, RADIUS, start_hint=truth.problem.start.point)
    assert 0.98 * strays < fit.outliers <= strays  # measured: 99.6 % of them
    assert deviation(truth.centerline, fit.points).max < 0.3  # measured 0.10 mm (as without the strays)
