"""Calibration against synthetic scans made at a finer discretisation than the fit uses."""

import numpy as np
import pytest
from validation_cases import EI, FACTOR, RADIUS, brake_hose, scanned

from hoseline.procedures.scans.calibration import ScanCase, _relative_std, calibrate
from hoseline.procedures.scans.centerline_fit import fit_centerline


@pytest.fixture(scope="module")
def cases():
    """Scans at 0 and 180 deg of the true hose (80 segments): one-sided, noisy, stray points, a gap."""
    out = []
    for seed, twist in enumerate((0.0, 180.0)):
        truth, points = scanned(twist, seed=seed)
        out.append(ScanCase(twist, fit_centerline(points, RADIUS, start_hint=truth.problem.start.point).points))
    return out


def test_recovers_bending_stiffness_and_torsion_factor_within_5_percent(cases):
    calibration = calibrate(brake_hose(bending=0.7 * EI, factor=12.0, segments=40), cases)
    fitted = {p.name: p for p in calibration.parameters}
    assert fitted["bending_stiffness"].value == pytest.approx(EI, rel=0.05)
    assert fitted["torsion_factor"].value == pytest.approx(FACTOR, rel=0.05)
    assert all(p.identifiable and p.std is not None and p.std > 0.0 for p in fitted.values())
    for before, after in zip(calibration.before, calibration.after):
        assert after.mean < 0.5 < before.mean
    assert calibration.warm_solves > 5 * calibration.cold_solves  # Newton from the last equilibria
    # every model evaluation, the finite-difference Jacobian's included, is one warm or cold solve
    assert calibration.evaluations == calibration.warm_solves + calibration.cold_solves


def test_weightless_hose_refuses_bending_stiffness_and_still_fits_the_torsion_factor(cases):
    calibration = calibrate(brake_hose(factor=12.0, segments=24, mass=0.0), cases[1:], max_evaluations=8)
    assert [p.name for p in calibration.parameters] == ["torsion_factor"]
    assert any("bending_stiffness not fitted" in note and "EI scales out" in note for note in calibration.notes)


def test_bending_stiffness_and_weight_together_keep_only_the_stiffness(cases):
    calibration = calibrate(brake_hose(segments=24), cases[:1], ["bending_stiffness", "mass_per_length"],
                            max_evaluations=4)
    assert [p.name for p in calibration.parameters] == ["bending_stiffness"]
    assert any("mass_per_length not fitted" in note for note in calibration.notes)


def test_a_parameter_the_scans_do_not_see_is_reported_not_identified(cases):
    """At 0 deg the hose lies nearly in the mounts' plane: the torsion factor barely shapes it."""
    calibration = calibrate(brake_hose(factor=12.0, segments=24), cases[:1], ["torsion_factor"], max_evaluations=8)
    (factor,) = calibration.parameters
    assert not factor.identifiable and factor.std is None
    assert any("torsion_factor" in note and "not determined" in note for note in calibration.notes)


def test_uncertainty_counts_two_degrees_of_freedom_per_station():
    """Residuals are vectors from each station to its closest model point, normal to the model: their
    component along the hose is zero, so the residual variance is |r|^2 / (2 stations - parameters)."""
    rng = np.random.default_rng(3)
    stations, sigma = 5000, 0.1  # mm of scatter in each direction normal to the hose (here along x)
    residuals = np.zeros((stations, 3))
    residuals[:, 1:] = sigma * rng.normal(size=(stations, 2))
    jacobian = rng.normal(size=(3 * stations, 2)) * [1.0, 30.0]
    expected = sigma * np.sqrt(np.diag(np.linalg.inv(jacobian.T @ jacobian)))
    np.testing.assert_allclose(_relative_std(jacobian, residuals.ravel(), 2 * stations), expected, rtol=0.03)
