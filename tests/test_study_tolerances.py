"""Tolerances and designs: the distributions are what they say, the deviations land where they say."""

from __future__ import annotations

import math
from statistics import NormalDist

import numpy as np
import pytest

from hoseline.demos.thesis_hose import demo_problem
from hoseline.procedures.variation.designs import unit_design
from hoseline.procedures.variation.tolerances import (COORDINATES, INDEX, Tolerance, Variation, fitting_axes, perturbed,
                                                      tilt_axes)

DRAWS = 200_000

CASES = [
    Tolerance("end.point", "normal", (0.5, 1.0, 2.0)),
    Tolerance("end.point", "uniform", (0.5, 1.0, 2.0)),
    Tolerance("start.point", "sphere", (1.5,)),
    Tolerance("end.direction", "cone", (3.0,)),
    Tolerance("start.direction", "normal", (2.0,)),
    Tolerance("hose.length", "normal", (1.0,)),
    Tolerance("hose.length", "uniform", (-13.2, 6.6)),
    Tolerance("hose.bending_stiffness", "lognormal", (2.0,)),
    Tolerance("hose.torsion_factor", "loguniform", (1.5,)),
    Tolerance("hose.mass_per_length", "uniform", (0.8, 1.3)),
    Tolerance("end.twist", "uniform", (-5.0, 1.0)),
    Tolerance("hose.length", "triangular", (-6.0, -4.0, 2.0)),
    Tolerance("end.twist", "triangular", (0.0, 0.0, 3.0)),
    Tolerance("hose.length", "truncnormal", (-1.0, 2.0, -3.0, 4.0)),  # a process offset of -1 mm, cut asymmetrically
]


@pytest.mark.parametrize("tolerance", CASES, ids=lambda t: f"{t.parameter}-{t.distribution}")
def test_mean_and_covariance_match_draws(tolerance):
    """The closed-form mean and covariance (used by the first-order variance) against 2e5 draws: within 5
    standard errors of the sample moments (a wrong formula, e.g. the cone's E[theta^2] or the uniform factor's
    log moments, is off by far more)."""
    unit = np.random.default_rng(7).random((DRAWS, tolerance.dimensions))
    values = tolerance.values(unit)
    mean, covariance = tolerance.mean(), tolerance.covariance()
    scale = np.sqrt(np.diag(covariance))
    assert np.all(np.abs(values.mean(axis=0) - mean) <= 5.0 * scale / math.sqrt(DRAWS))
    sampled = np.cov(values.T).reshape(covariance.shape)
    # the standard error of a variance is about sqrt(2 / n) sigma^2 (4 x that for heavy-tailed ln factors)
    assert np.all(np.abs(sampled - covariance) <= 5.0 * 2.0 * math.sqrt(2.0 / DRAWS) * np.outer(scale, scale) + 1e-12)


def test_distributions_keep_their_bounds():
    """Sphere within its radius, cone within its angle, uniform ranges within their ends, lognormal 95 % within 1/f..f."""
    unit = np.random.default_rng(3).random((50_000, 3))
    assert np.max(np.linalg.norm(Tolerance("end.point", "sphere", (2.0,)).values(unit), axis=1)) <= 2.0
    assert np.max(np.linalg.norm(Tolerance("end.direction", "cone", (4.0,)).values(unit[:, :2]), axis=1)) <= 4.0
    length = Tolerance("hose.length", "uniform", (-4.0, 2.0)).values(unit[:, :1])
    assert length.min() >= -4.0 and length.max() <= 2.0
    triangle = Tolerance("hose.length", "triangular", (-6.0, -4.0, 2.0)).values(unit[:, :1])
    assert triangle.min() >= -6.0 and triangle.max() <= 2.0
    assert np.mean(triangle < -4.0) == pytest.approx(2.0 / 8.0, abs=0.01)  # the mode's quantile: (mode-low)/(high-low)
    cut = Tolerance("hose.length", "truncnormal", (-1.0, 2.0, -3.0, 4.0)).values(unit[:, :1])
    normal = NormalDist()  # the median in closed form: mean + sigma Phi^-1((Phi(alpha) + Phi(beta)) / 2)
    median = -1.0 + 2.0 * normal.inv_cdf(0.5 * (normal.cdf(-1.0) + normal.cdf(2.5)))
    assert cut.min() >= -3.0 and cut.max() <= 4.0 and np.median(cut) == pytest.approx(median, abs=0.02)
    factor = np.exp(Tolerance("hose.bending_stiffness", "lognormal", (2.0,)).values(unit[:, :1]))
    inside = np.mean((factor > 0.5) & (factor < 2.0))
    assert abs(inside - 0.95) < 0.005  # measured 0.9498


def test_perturbed_problem_moves_what_the_coordinates_say():
    """Each coordinate changes the problem as documented: tips by mm, directions by the tilt angle, length
    in mm, EI and GJ by exp(ln factor) with the torsion factor kept, GJ alone by hose.torsion, twist in degrees."""
    problem = demo_problem(180.0)
    c = np.zeros(len(COORDINATES))
    c[INDEX["end.x"]], c[INDEX["start.z"]] = 0.7, -0.4
    c[INDEX["end.tilt_a"]], c[INDEX["end.tilt_b"]] = 3.0, 4.0  # 5 degrees in all
    c[INDEX["hose.length"]] = -2.5
    c[INDEX["hose.bending"]], c[INDEX["hose.torsion"]] = math.log(2.0), math.log(0.5)
    c[INDEX["end.twist"]] = -7.0
    moved = perturbed(problem, c)
    assert np.allclose(moved.end.point - problem.end.point, [0.7, 0.0, 0.0])
    assert np.allclose(moved.start.point - problem.start.point, [0.0, 0.0, -0.4])
    angle = math.degrees(math.acos(np.clip(moved.end.direction @ problem.end.direction, -1.0, 1.0)))
    assert angle == pytest.approx(5.0, rel=1e-9)
    # the tilt is about the axes a, b: the direction moves along b x d for a tilt about a, and so on
    turn = np.cross(np.array([3.0, 4.0]) @ tilt_axes(problem.end.direction), problem.end.direction)
    assert np.allclose(np.cross(problem.end.direction, moved.end.direction) / math.sin(math.radians(5.0)),
                       np.cross(problem.end.direction, turn) / np.linalg.norm(turn), atol=1e-9)
    assert moved.hose.length == pytest.approx(problem.hose.length - 2.5)
    assert moved.hose.bending_stiffness == pytest.approx(2.0 * problem.hose.bending_stiffness)
    assert moved.hose.torsion_factor == pytest.approx(0.5 * problem.hose.torsion_factor)
    assert moved.end_twist_deg == pytest.approx(173.0)


def test_tolerances_on_one_parameter_add_up():
    """A length tolerance and the change under pressure both move hose.length; their means and variances add."""
    both = Variation((Tolerance("hose.length", "normal", (1.0,)), Tolerance("hose.length", "uniform", (-4.0, 2.0))))
    assert both.dimensions == 2 and both.varied == (INDEX["hose.length"],)
    unit = np.array([[0.5, 0.0], [0.5, 1.0]])
    assert np.allclose(both.coordinates(unit)[:, INDEX["hose.length"]], [-4.0, 2.0], atol=1e-9)
    assert both.covariance()[INDEX["hose.length"], INDEX["hose.length"]] == pytest.approx(1.0 + 36.0 / 12.0)
    assert both.mean()[INDEX["hose.length"]] == pytest.approx(-1.0)


def test_bad_tolerances_are_refused_with_the_fix():
    with pytest.raises(ValueError, match="cone angle"):
        Tolerance("end.direction", "cone", (120.0,))
    with pytest.raises(ValueError, match="does not apply"):
        Tolerance("hose.length", "sphere", (1.0,))
    with pytest.raises(ValueError, match="above 1"):
        Tolerance("hose.bending_stiffness", "lognormal", (0.5,))
    with pytest.raises(ValueError, match="tolerance_y = -1, tolerance_z = 0: each must be zero or positive"):
        Tolerance("end.point", "uniform", (1.0, -1.0, 0.0))
    with pytest.raises(ValueError, match="not all zero"):
        Tolerance("clips[0].point", "uniform", (0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="need low <= mode <= high"):
        Tolerance("hose.length", "triangular", (-1.0, 2.0, 1.0))
    with pytest.raises(ValueError, match="need sigma > 0 and low < high"):
        Tolerance("hose.length", "truncnormal", (0.0, 1.0, 2.0, -2.0))
    with pytest.raises(ValueError, match="radius = -1"):
        Tolerance("start.point", "sphere", (-1.0,))


@pytest.mark.parametrize("method", ["monte-carlo", "latin-hypercube", "sobol"])
def test_designs_depend_on_the_seed_alone(method):
    """The same seed gives the same points; another seed others; Latin hypercube rows are stratified."""
    first, again = unit_design(method, 64, 5, 11), unit_design(method, 64, 5, 11)
    assert np.array_equal(first, again)
    assert not np.array_equal(first, unit_design(method, 64, 5, 12))
    assert np.all((first > 0.0) & (first < 1.0))
    if method == "latin-hypercube":
        assert all(sorted(np.floor(first[:, k] * 64).astype(int)) == list(range(64)) for k in range(5))


def test_a_shared_contributor_moves_its_parameters_together_with_the_closed_form_variance():
    """A subframe deviation (sigma) shared by both mounts and the end mount's own (tau), per axis: the mounts' gap
    end.x - start.x varies by tau alone (the shared part cancels), their sum by 4 sigma^2 + tau^2; without sharing
    the gap would vary by 2 sigma^2 + tau^2.  The covariance gives these exactly, and 2^16 Sobol draws agree."""
    sigma, tau = 0.5, 0.3
    shared = Variation((Tolerance("start.point", "normal", (sigma,) * 3, shared_with=("end.point",)),
                        Tolerance("end.point", "normal", (tau,) * 3)))
    gap = np.zeros(len(COORDINATES))
    gap[INDEX["end.x"]], gap[INDEX["start.x"]] = 1.0, -1.0
    total = np.abs(gap)
    covariance = shared.covariance()
    assert gap @ covariance @ gap == pytest.approx(tau**2, rel=1e-12)
    assert total @ covariance @ total == pytest.approx(4.0 * sigma**2 + tau**2, rel=1e-12)
    draws = shared.coordinates(unit_design("sobol", 2**16, shared.dimensions, 3))
    assert np.var(draws @ gap) == pytest.approx(tau**2, rel=0.02)
    assert np.var(draws @ total) == pytest.approx(4.0 * sigma**2 + tau**2, rel=0.02)
    assert np.allclose(np.cov(draws, rowvar=False), covariance, atol=0.02 * sigma**2)
    independent = Variation((Tolerance("start.point", "normal", (sigma,) * 3), Tolerance("end.point", "normal", (sigma,) * 3),
                             Tolerance("end.point", "normal", (tau,) * 3)))
    assert gap @ independent.covariance() @ gap == pytest.approx(2.0 * sigma**2 + tau**2, rel=1e-12)
    assert shared.varied == tuple(sorted([INDEX[n] for n in ("start.x", "start.y", "start.z", "end.x", "end.y", "end.z")]))


def test_a_shared_contributor_of_another_kind_or_unit_is_refused():
    with pytest.raises(ValueError, match="shared_with hose.mass_per_length: a shared deviation moves parameters of one"):
        Tolerance("end.point", "normal", (1.0,) * 3, shared_with=("hose.mass_per_length",))
    with pytest.raises(ValueError, match="shared_with end.twist"):  # both offsets, but mm and degrees
        Tolerance("hose.length", "normal", (1.0,), shared_with=("end.twist",))
    with pytest.raises(ValueError, match="lists a parameter twice"):
        Tolerance("end.point", "sphere", (1.0,), shared_with=("start.point", "start.point"))
    with pytest.raises(ValueError, match="unknown parameter"):
        Tolerance("end.point", "sphere", (1.0,), shared_with=("end.pint",))
    with pytest.raises(ValueError, match=r"clips\[0\].point: the problem has 0 clip"):
        Variation((Tolerance("end.point", "sphere", (1.0,), shared_with=("clips[0].point",)),))


def test_a_point_tolerance_in_the_fittings_frame_is_radial_and_axial():
    """sigma = [0.2, 0.2, 1.0] along a fitting's radial axes and its axis d: the world covariance is
    0.04 (I - d d^T) + 1.0 d d^T in closed form, and 2^16 draws move the point by 1.0 along d and 0.2 across."""
    direction = np.array([1.0, 2.0, -2.0]) / 3.0
    tolerance = Tolerance("end.point", "normal", (0.2, 0.2, 1.0), axes=fitting_axes(direction))
    along = np.outer(direction, direction)
    assert np.allclose(tolerance.covariance(), 0.04 * (np.eye(3) - along) + along, atol=1e-12)
    draws = tolerance.values(unit_design("sobol", 2**16, 3, 2))
    axial = draws @ direction
    radial = draws - axial[:, None] * direction
    assert np.std(axial) == pytest.approx(1.0, rel=0.01)
    assert np.sqrt(np.mean(np.sum(radial**2, axis=1)) / 2.0) == pytest.approx(0.2, rel=0.01)
    with pytest.raises(ValueError, match="only for a point"):
        Tolerance("hose.length", "normal", (1.0,), axes=fitting_axes(direction))
