"""The probability of breaking a limit and the limit's process capability, against closed forms."""

from __future__ import annotations

from statistics import NormalDist

import numpy as np
import pytest

from hoseline.procedures.variation.quantities import Limit, quantities
from hoseline.procedures.variation.statistics import PERCENTILES, probability, spread

DRAWS = 400_000


@pytest.mark.parametrize("name, value, mean, sigma, cpk", [
    ("bend_radius", 34.0, 40.0, 2.0, 1.0),  # at least 34 mm: the mean 3 sigma inside, Cpk 1
    ("end_torque", 2500.0, 2000.0, 250.0, 2.0 / 3.0),  # at most 2500 N*mm: 2 sigma inside
])
def test_capability_of_a_normal_quantity(name, value, mean, sigma, cpk):
    """Normal values of a known mean and sigma: Cpk = margin of the mean / 3 sigma, the ppm if normal is
    1e6 Phi(-3 Cpk) (1350 ppm at Cpk 1), and the counted fraction beyond the limit agrees with it within its
    95 % interval; a missing 3 or a margin of the wrong sign is far off."""
    quantity = next(q for q in quantities(()) if q.name == name)
    values = np.random.default_rng(11).normal(mean, sigma, DRAWS)
    values[:10] = np.nan  # failed samples are left out of the capability
    result = probability(Limit(quantity, value), values)
    assert result.cpk == pytest.approx(cpk, rel=0.01)
    expected = 1e6 * NormalDist().cdf(-3.0 * cpk)
    assert result.ppm == pytest.approx(expected, rel=0.05)
    assert 1e6 * result.low <= expected <= 1e6 * result.high


def test_capability_without_spread_or_samples():
    quantity = quantities(())[0]
    inside = probability(Limit(quantity, 30.0), np.full(5, 35.0))
    assert inside.cpk == np.inf and inside.ppm == 0.0
    none = probability(Limit(quantity, 30.0), np.array([np.nan, 35.0]))
    assert np.isnan(none.cpk) and np.isnan(none.ppm)


def test_the_percentile_interval_ends_at_the_binomial_ranks_and_holds_the_true_percentile():
    """Uniform(0, 1) values: each percentile p's interval contains p, and its ends are the order statistics of
    ranks n p -+ z sqrt(n p (1 - p)) (the normal approximation of the binomial count below it, to 2 ranks);
    the mean's interval is 2 t sigma / sqrt(n) wide."""
    n = 4000
    values = np.random.default_rng(5).random(n)
    result = spread(values)
    z = NormalDist().inv_cdf(0.975)
    for p, (low, high) in zip(PERCENTILES, result.percentile_intervals):
        assert low <= p / 100.0 <= high
        centre, half = n * p / 100.0, z * np.sqrt(n * p / 100.0 * (1.0 - p / 100.0))
        assert abs(np.sum(values <= low) - (centre - half)) <= 2.0 and abs(np.sum(values <= high) - (centre + half)) <= 2.0
    low, high = result.mean_interval
    assert low <= 0.5 <= high and high - low == pytest.approx(2.0 * z * np.std(values, ddof=1) / np.sqrt(n), rel=1e-3)


def test_the_intervals_cover_the_true_values_95_percent_of_the_time():
    """2000 repetitions of 100 normal samples: the mean's interval and the P5 and P95 intervals hold the true
    values in 95 % of them or more (order statistics are conservative), the binomial error of 2000 runs being
    0.5 %; an interval half as wide covers about 70 %."""
    rng = np.random.default_rng(17)
    true = [NormalDist().inv_cdf(p / 100.0) for p in PERCENTILES]
    covered = np.zeros(1 + len(PERCENTILES))
    runs = 2000
    for _ in range(runs):
        result = spread(rng.normal(size=100))
        covered[0] += result.mean_interval[0] <= 0.0 <= result.mean_interval[1]
        covered[1:] += [low <= value <= high for value, (low, high) in zip(true, result.percentile_intervals)]
    assert np.all(covered / runs >= 0.94), covered / runs
    assert np.all(covered / runs <= 0.99), covered / runs
