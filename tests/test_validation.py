"""Scans to centrelines, deviations, thresholds, the scatter of repeated scans and the twist path."""

import numpy as np
import pytest
from validation_cases import RADIUS, brake_hose, scanned

from hoseline import solve
from hoseline.procedures.scans.synthetic_scan import ScanDefects, synthetic_scan

from hoseline.procedures.scans.centerline_fit import fit_centerline
from hoseline.procedures.scans.deviation import Thresholds, closest_on_polyline, deviation
from hoseline.procedures.scans.scatter import scatter_envelope
from hoseline.procedures.placement.twist_path import follow_twist


def test_centerline_and_radius_from_a_one_sided_noisy_scan_with_a_gap():
    truth, points = scanned(180.0)
    fit = fit_centerline(points.tolist(), RADIUS, start_hint=truth.problem.start.point)  # any (n, 3) array-like
    error = deviation(truth.centerline, fit.points)
    assert error.max < 0.3 and error.mean < 0.12  # noise 0.1 mm, 2 % stray points, half the surface seen
    # measured: 0.103 / 0.040 mm above; radius 0.0091 mm off, scatter 0.021 mm
    assert abs(fit.radius_median - RADIUS) < 0.03 and fit.radius_scatter < 0.05
    assert np.all(fit.coverage_deg < 250.0)  # one-sided indeed
    assert fit.outliers > 0
    (low, high), = fit.gaps  # the 150-170 mm gap of the scan, along the fitted guide
    assert 10.0 < high - low < 25.0
    assert np.linalg.norm(fit.points[0] - truth.problem.start.point) < 15.0  # numbered from the start mount


@pytest.mark.parametrize("view", [None, (0.0, 0.0, -1.0)], ids=["all round", "one-sided"])
def test_the_stations_uncertainty_matches_their_scatter_over_noise_seeds(view):
    # the axis point's standard uncertainty from the fit's covariance (the --check noise allowance's sigma) against
    # the scatter of the stations of 8 scans of one hose (noise 0.3 mm): measured 8 % and 7 % below the scatter
    truth = solve(brake_hose(segments=160, twist=180.0), estimate_error=False)
    distances, sigmas = [], []
    for seed in range(8):
        points = synthetic_scan(truth.s, truth.centerline, RADIUS, ScanDefects(density=0.4, noise=0.3, view=view),
                                seed=seed)
        fit = fit_centerline(points, RADIUS, start_hint=truth.centerline[0])
        distances.append(deviation(truth.centerline, fit.points).distance)
        sigmas.append(fit.axis_sigma)
    distances, sigmas = np.concatenate(distances), np.concatenate(sigmas)
    scatter = np.sqrt(0.5 * np.mean(distances**2))  # per direction: a 2-D offset's mean square is 2 sigma^2
    assert scatter == pytest.approx(np.sqrt(np.mean(sigmas**2)), rel=0.2)


def test_closest_point_on_a_polyline_and_the_statistics():
    polyline = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [10.0, 10.0, 0.0]])
    points = np.array([[5.0, 2.0, 0.0], [12.0, 4.0, 0.0], [-3.0, 0.0, 4.0], [10.0, 15.0, 0.0]])
    distance, arc, closest = closest_on_polyline(points, polyline)
    np.testing.assert_allclose(distance, [2.0, 2.0, 5.0, 5.0])
    np.testing.assert_allclose(arc, [5.0, 14.0, 0.0, 20.0])
    np.testing.assert_allclose(closest[1], [10.0, 4.0, 0.0])
    result = deviation(polyline, points)
    assert result.mean == pytest.approx(3.5) and result.max == 5.0 and result.s_at_max == 0.0
    assert result.rms == pytest.approx(np.sqrt(np.mean(np.square([2, 2, 5, 5]))))
    assert result.passes(Thresholds(4.0)) and not result.passes(Thresholds(4.0, max=4.5))
    assert Thresholds.thesis(0.0).mean == 1.0 and Thresholds.thesis(180.0).mean == 6.0


def test_scatter_envelope_of_shifted_scans():
    line = np.column_stack([np.linspace(0.0, 100.0, 51), np.zeros(51), np.zeros(51)])
    scans = [line + [0.0, offset, 0.0] for offset in (-3.0, 0.0, 1.0, 2.0)]
    envelope = scatter_envelope(scans)
    np.testing.assert_allclose(envelope.spread, 5.0, atol=1e-9)
    np.testing.assert_allclose(envelope.mean[:, 1], 0.0, atol=1e-9)
    assert envelope.margin == pytest.approx(3.0) and envelope.max_spread == pytest.approx(5.0)
    with pytest.raises(ValueError, match="at least two"):
        scatter_envelope(scans[:1])


def test_twist_path_of_the_plain_model_is_smooth():
    path = follow_twist(brake_hose(segments=20, mass=0.0, twist=180.0), np.arange(0.0, 181.0, 30.0), "25x")
    assert path.smooth and not path.failure
    assert path.centerlines.shape == (7, 21, 3)
    np.testing.assert_allclose(path.centerlines[0, -1], [-173.064, -7.0, -11.25], atol=1e-6)
    assert np.all(path.steps > 1.0)  # it moves at every step, without jumps


def test_the_radius_is_measured_not_taken_from_the_nominal_one():
    """The fit starts from a nominal radius 20 % too large; the reported radius is the scan's.
    Measured: radius 0.0095 mm off, centreline within 0.114 mm (0.103 with the true nominal)."""
    truth, points = scanned(180.0)
    fit = fit_centerline(points, 1.2 * RADIUS, start_hint=truth.problem.start.point)
    assert abs(fit.radius_median - RADIUS) < 0.03
    assert np.all(np.abs(fit.radius[fit.radius_fitted] - RADIUS) < 0.21)  # every section: measured 0.075
    assert deviation(truth.centerline, fit.points).max < 0.36
