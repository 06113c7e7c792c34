"""The probability of breaking a limit and the limit's process capability, against closed forms."""

from __future__ import annotations

from statistics import NormalDist

import numpy as np
import pytest

from hoseline.procedures.variation.quantities import Limit, quantities
from hoseline.procedures.variation.statistics import probability

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
