"""Calibration against synthetic scans of shapes that do not come from the solver: the Kirchhoff
BVP of reference_shapes.py (SciPy), so an error the model shares with its own finer solutions
does not cancel out."""

from dataclasses import replace

import numpy as np
import pytest
from reference_shapes import heavy_thesis_hose
from validation_cases import EI, FACTOR, ONE_SIDED, RADIUS, brake_hose

from hoseline import solve
from hoseline.procedures.scans.calibration import (RICHARDSON_SEGMENTS, ScanCase, _relative_std, calibrate,
                                                   scatter_inflation)
from hoseline.procedures.scans.centerline_fit import fit_centerline
from hoseline.procedures.scans.synthetic_scan import ScanDefects, synthetic_scan


@pytest.fixture(scope="module")
def cases():
    """Scans at 0 and 180 deg of the true hose (the BVP): one-sided, noisy, stray points, a gap."""
    shapes = heavy_thesis_hose((0.0, 180.0))
    s = np.linspace(0.0, 330.6, 331)
    out = []
    for seed, twist in enumerate((0.0, 180.0)):
        line = shapes[twist].sol(s)[:3].T
        points = synthetic_scan(s, line, RADIUS, ONE_SIDED, seed=seed)
        out.append(ScanCase(twist, fit_centerline(points, RADIUS, start_hint=line[0]).points))
    return out


def test_recovers_bending_stiffness_and_torsion_factor(cases):
    """An 80-segment model from EI -30 % and factor 12.  Measured: EI -0.044 %, factor +0.10 % (0.9 and 0.6 sigma);
    a 40-segment model: -0.001 % and -0.005 %.  Before the fit was corrected for the model's discretisation (-0.17 %
    and +0.96 % at 80 segments) and the cylinder fits measured offsets from the bent axis itself (one-sided scans
    moved the stations 0.025 mm away from the scanner), it gave -0.11 % and -0.39 %, and +0.28 % and -3.2 % with 40."""
    calibration = calibrate(brake_hose(bending=0.7 * EI, factor=12.0, segments=80), cases)
    fitted = {p.name: p for p in calibration.parameters}
    assert fitted["bending_stiffness"].value == pytest.approx(EI, rel=0.0015)
    assert fitted["torsion_factor"].value == pytest.approx(FACTOR, rel=0.003)
    assert all(p.identifiable for p in fitted.values())
    # the quoted sigma (scatter and what stays uncertain of the discretisation correction) holds the truth
    assert abs(fitted["bending_stiffness"].value - EI) < fitted["bending_stiffness"].std
    assert abs(fitted["torsion_factor"].value - FACTOR) < fitted["torsion_factor"].std
    for before, after in zip(calibration.before, calibration.after):
        assert after.mean < 0.13 and before.mean > 2.0  # mm, measured 0.035 / 0.041 after, 2.3 / 5.1 before
    assert calibration.warm_solves > 5 * calibration.cold_solves  # Newton from the last equilibria
    # every model evaluation, the finite-difference Jacobian's included, is one warm or cold solve
    assert calibration.evaluations == calibration.warm_solves + calibration.cold_solves


def _noisy_stations(result, rng, count=58, noise=0.05, window=1):
    """`count` stations along a result's centreline polyline, each moved by `noise` mm (standard
    deviation) in both directions across the hose; window > 1: the noise is the moving average of
    `window` independent draws (times sqrt(window)), so neighbouring stations share it as the
    overlapping sections of a fitted scan centreline do."""
    s = np.linspace(0.0, result.s[-1], count + 2)[1:-1]
    segment = np.minimum((s / result.s[1]).astype(int), len(result.frames) - 1)
    frames = result.frames[segment]
    on_line = result.centerline[segment] + (s - result.s[segment])[:, None] * frames[:, 2]
    draws = rng.normal(size=(count + window - 1, 2))
    shared = np.array([draws[i : i + window].sum(axis=0) for i in range(count)]) / np.sqrt(window)
    return on_line + noise * (shared[:, :1] * frames[:, 0] + shared[:, 1:] * frames[:, 1])


@pytest.mark.parametrize("window", [1, 5])
def test_quoted_uncertainty_covers_the_fits_over_noise_seeds(window):
    """Stations with noise on a 384-segment hose, fitted with 48 segments: independent noise (window 1) or shared by
    5 neighbours (an MA(5) process: 5 times the variance of a mean, as overlapping centreline sections give).  The
    fit is corrected for the 48-segment model's discretisation, and its quoted uncertainty (the scatter, inflated
    by the correlation along the hose, and (15 / 48)^2 of the correction) holds the truth over 16 seeds: measured RMS
    of the errors in sigma 0.51 and 0.74, within 1 sigma 94 % and 78 %, within 2 sigma all; inflation 1.10 and 4.89
    (exact 1 and 5).  Without the correction (the fit alone against its scatter) the errors were 7.4 and 4.0 sigma
    RMS: the discretisation's bias, which the scans' noise cannot hide."""
    results = [solve(brake_hose(segments=384, twist=twist), estimate_error=False) for twist in (0.0, 180.0)]
    truth = {"bending_stiffness": EI, "torsion_factor": FACTOR}
    z, inflations = [], []
    for seed in range(16):
        rng = np.random.default_rng(seed)
        cases = [ScanCase(r.problem.end_twist_deg, _noisy_stations(r, rng, window=window)) for r in results]
        calibration = calibrate(brake_hose(bending=0.7 * EI, factor=12.0, segments=48), cases)
        z += [(p.value - truth[p.name]) / p.std for p in calibration.parameters]
        inflations.append(calibration.scatter_inflation)
    z = np.abs(z)
    assert np.mean(inflations) == pytest.approx(window, rel=0.25)
    assert 0.4 < np.sqrt(np.mean(np.square(z))) < 1.3
    assert np.mean(z < 1.0) >= 0.68 and np.mean(z < 2.0) >= 0.95


TWO_VIEWS = (ScanDefects(density=0.4, noise=0.3, view=(0.0, 0.3, -1.0)),
             ScanDefects(density=0.4, noise=0.3, view=(0.2, -0.3, 1.0)))


def test_sigma_covers_the_truth_on_independent_scans_from_two_views():
    """The issue's case: scans of the Kirchhoff solution (no hoseline code) from two views at 0.3 mm noise, the default
    100-segment model.  Over 8 seeds the truth lies within 1 sigma in 12 and within 2 sigma in 15 of the 16 fits
    (EI, factor; RMS 0.90 sigma), the factor now on both sides of the truth (-0.23 to +0.60 %).  Before the correction for
    the discretisation the factor came out below the truth in every fit (measured -0.08 to -0.78 % at 100 segments),
    held by a sigma that added the whole correction as an uncertainty."""
    shapes = heavy_thesis_hose((0.0, 180.0))
    s = np.linspace(0.0, 330.6, 661)
    lines = {twist: shapes[twist].sol(s)[:3].T for twist in (0.0, 180.0)}
    truth = {"bending_stiffness": EI, "torsion_factor": FACTOR}
    z = []
    for seed in range(8):
        cases = [ScanCase(twist, fit_centerline(np.vstack([synthetic_scan(s, line, RADIUS, view, seed=10 * seed + k)
                                                           for k, view in enumerate(TWO_VIEWS)]),
                                                RADIUS, start_hint=line[0]).points)
                 for twist, line in lines.items()]
        calibration = calibrate(brake_hose(bending=1.3 * EI, factor=0.8 * FACTOR, segments=100), cases)
        z += [(p.value - truth[p.name]) / p.std for p in calibration.parameters]
    z = np.abs(z)
    assert np.mean(z < 1.0) >= 0.6 and np.mean(z < 2.0) >= 0.9


def test_scatter_inflation_of_a_moving_average_is_its_window():
    """MA(w) residuals (each the mean of w consecutive independent draws) have 1 + 2 sum rho_k = w."""
    rng = np.random.default_rng(7)
    draws = rng.normal(size=(20003, 3))
    for window in (1, 3, 5):
        moving = np.array([draws[i : i + window].mean(axis=0) for i in range(20000)])
        inflation = scatter_inflation([moving[:10000], moving[10000:]])
        assert inflation == pytest.approx(window, rel=0.1)


def test_the_discretisation_correction_removes_the_model_error():
    """Noise-free stations on a 192-segment hose, fitted with 24 segments: the error of the fit is the model's
    discretisation.  Measured before the correction: factor -9.0 %, EI +0.92 %.  The correction (4/3 of the change a
    48-segment model makes, as a Gauss-Newton step) takes most of it out; what is left (the 24-segment model's
    higher orders, and the 192-segment truth's own discretisation) lies within (15 / 24)^2 = 39 % of the correction
    (RICHARDSON_SEGMENTS): measured 31 % for EI."""
    results = [solve(brake_hose(segments=192, twist=twist), estimate_error=False) for twist in (0.0, 180.0)]
    truth = {"bending_stiffness": EI, "torsion_factor": FACTOR}
    rng = np.random.default_rng(0)
    cases = [ScanCase(r.problem.end_twist_deg, _noisy_stations(r, rng, noise=0.0)) for r in results]
    calibration = calibrate(brake_hose(bending=0.7 * EI, factor=12.0, segments=24), cases)
    fitted = {p.name: p for p in calibration.parameters}
    factor = fitted["torsion_factor"]
    assert (factor.value - factor.discretisation_correction - FACTOR) / FACTOR < -0.05  # the fit alone: -9.0 %
    for name, p in fitted.items():
        assert abs(p.value - truth[name]) < p.std
        assert abs(p.value - truth[name]) < (RICHARDSON_SEGMENTS / 24) ** 2 * abs(p.discretisation_correction)


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


def test_flipped_twist_signs_are_said_loudly():
    """The issue's case: a hose of EI 120 000 N*mm^2 and torsion factor 18 scanned at 0, 90 and 180 deg,
    the twists given with the wrong sign.  The fit runs both parameters to their bounds (measured:
    EI 1.5e7, factor 0.25) and leaves 10-53 mm of mean deviation; the refit with the signs flipped
    finds 0.10-0.12 mm and EI 1.201e5, factor 17.9, which is said, not used."""
    results = [solve(brake_hose(bending=120000.0, factor=18.0, segments=24, twist=twist), estimate_error=False)
               for twist in (0.0, 90.0, 180.0)]
    rng = np.random.default_rng(1)
    cases = [ScanCase(-r.problem.end_twist_deg, _noisy_stations(r, rng, noise=0.1)) for r in results]
    calibration = calibrate(brake_hose(bending=EI, factor=FACTOR, segments=24), cases)
    assert not any(p.identifiable for p in calibration.parameters)
    assert all(p.std is None and "at its bound" in p.note for p in calibration.parameters)
    assert sum("ran to its bound" in warning for warning in calibration.warnings) == 2
    assert sum("above its limit" in warning for warning in calibration.warnings) == 3
    (flipped,) = [warning for warning in calibration.warnings if "sign looks flipped" in warning]
    assert flipped.endswith("use twist = 0, 90, 180")
    assert calibration.after[2].mean > 6.0  # the fit itself is not replaced


def test_a_good_fit_has_no_warnings():
    results = [solve(brake_hose(bending=120000.0, factor=18.0, segments=24, twist=twist), estimate_error=False)
               for twist in (0.0, 180.0)]
    rng = np.random.default_rng(1)
    cases = [ScanCase(r.problem.end_twist_deg, _noisy_stations(r, rng, noise=0.1)) for r in results]
    calibration = calibrate(brake_hose(bending=EI, factor=FACTOR, segments=24), cases)
    assert calibration.warnings == []
    assert all(p.identifiable for p in calibration.parameters)


def test_weightless_problem_against_scans_of_a_heavy_hose():
    """The issue's case: the problem file says weightless, the scanned hose weighs 0.3 kg/m.  The
    torsion factor alone cannot absorb the sag (measured: 5.85, 8.1 mm mean deviation at 0 deg); the
    sensitivity to the fixed mass_per_length explains 98 % of the remaining misfit (predicted mass
    0.258 kg/m) and moves the factor far more than its sigma: not identified, and said."""
    results = [solve(brake_hose(segments=24, twist=twist, mass=0.3), estimate_error=False) for twist in (0.0, 180.0)]
    rng = np.random.default_rng(1)
    cases = [ScanCase(r.problem.end_twist_deg, _noisy_stations(r, rng, noise=0.1)) for r in results]
    calibration = calibrate(brake_hose(factor=12.0, segments=24, mass=0.0), cases)
    (factor,) = calibration.parameters
    assert not factor.identifiable and factor.std is None and "mass_per_length" in factor.note
    (confounded,) = [warning for warning in calibration.warnings if "not identified" in warning]
    assert confounded.startswith("torsion_factor not identified: the scans look heavier than the problem file says "
                                 "(mass_per_length = 0): freeing mass_per_length (to about 0.2")  # truth 0.3


def test_torsion_factor_follows_the_problem_files_poisson_ratio():
    """A hose of GJ = 25 EI / 1.3: with nu = 0.3 (as the problem file's poisson_ratio would give) the
    factor is 25; with the default nu = 0.5 the same GJ is 25 * 1.5 / 1.3 = 28.8."""
    truth = brake_hose(segments=192, factor=25.0 * 1.5 / 1.3)  # GJ = 25 EI / 1.3
    results = [solve(replace(truth, end_twist_deg=twist), estimate_error=False) for twist in (0.0, 180.0)]
    rng = np.random.default_rng(2)
    cases = [ScanCase(r.problem.end_twist_deg, _noisy_stations(r, rng)) for r in results]
    initial = brake_hose(bending=0.7 * EI, factor=12.0, segments=48)
    for nu, expected in ((0.3, 25.0), (0.5, 25.0 * 1.5 / 1.3)):
        calibration = calibrate(initial, cases, poisson_ratio=nu)
        fitted = {p.name: p for p in calibration.parameters}
        assert calibration.poisson_ratio == nu
        assert fitted["torsion_factor"].initial == pytest.approx(12.0 * (1.0 + nu) / 1.5)  # GJ = 12 EI / 1.5
        assert fitted["torsion_factor"].value == pytest.approx(expected, rel=0.01)
        assert calibration.hose.torsional_stiffness == pytest.approx(truth.hose.torsional_stiffness, rel=0.01)
