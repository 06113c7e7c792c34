"""Global sensitivity: Sobol' first-order and total indices of every quantity per tolerance, from a Saltelli design.

The first-order (tornado) contributions are those of the derivatives at the nominal hose; where the
response is not linear over the tolerances they are wrong (study.py says so).  Sobol' indices need no
linearity: the first-order index S_i is the share of a quantity's variance that tolerance i explains
alone, the total index ST_i the share it has a part in, interactions included (ST_i - S_i: with others).

Design (Saltelli et al. 2010): N rows of two independent matrices A and B of the unit hypercube (the
first and second half of the columns of a scrambled Sobol' sequence of twice the dimensions,
scipy.stats.qmc, as scipy.stats.sobol_indices draws them), then per tolerance the matrix A with that
tolerance's columns taken from B: N (tolerances + 2) hoses.  A tolerance is a group of columns (a
point's three axes, a direction's two), so its index is that of the tolerance as a whole, what the
tornado chart ranks.  The estimators are those of scipy.stats.sobol_indices (Saltelli 2010 table 2 (b)
for the first order, (f), Jansen's, for the total), written here because SciPy's takes its own design
of 2^m rows only and a row with a hose that could not be solved is left out; their 95 % intervals are
the bootstrap's (BCa over the rows, scipy.stats.bootstrap, seeded).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from hoseline.procedures.variation.statistics import CONFIDENCE

RESAMPLES = 999  # bootstrap resamples


def saltelli_design(groups: tuple[int, ...], count: int, seed: int) -> np.ndarray:
    """(count (len(groups) + 2), sum(groups)) points of the unit hypercube: the rows of A, of B, then of A with each
    group's columns (groups: columns per group, in order) from B.  count: N, a power of two keeps the balance."""
    from scipy.stats import qmc

    dimensions = sum(groups)
    both = qmc.Sobol(2 * dimensions, scramble=True, seed=seed).random(count)
    a, b = both[:, :dimensions], both[:, dimensions:]
    blocks = [a, b]
    first = 0
    for size in groups:
        mixed = a.copy()
        mixed[:, first:first + size] = b[:, first:first + size]
        blocks.append(mixed)
        first += size
    return np.vstack(blocks)


@dataclass(frozen=True)
class SobolIndices:
    """Sobol' indices of s quantities over g groups: first, total (s, g) and their 95 % intervals first_low,
    first_high, total_low, total_high (s, g); rows: base rows used (all hoses of the row solved), of count."""

    first: np.ndarray
    total: np.ndarray
    first_low: np.ndarray
    first_high: np.ndarray
    total_low: np.ndarray
    total_high: np.ndarray
    rows: int
    count: int


def sobol_indices(values: np.ndarray, count: int, groups: int, seed: int) -> SobolIndices:
    """The indices from the values (count (groups + 2), s) at saltelli_design's points (NaN: not solved)."""
    from scipy.stats import bootstrap

    values = np.asarray(values, dtype=float).reshape(count * (groups + 2), -1)
    blocks = values.reshape(groups + 2, count, -1)  # A, B, AB_1 .. AB_g
    usable = np.all(np.isfinite(blocks), axis=(0, 2))
    blocks = blocks[:, usable]
    rows = int(usable.sum())
    quantities = blocks.shape[2]
    if rows < 4:
        nan = np.full((quantities, groups), np.nan)
        return SobolIndices(nan, nan, nan, nan, nan, nan, rows, count)

    def indices(index: np.ndarray) -> np.ndarray:
        """(2, s, g) first and total indices of the rows `index` (Saltelli et al. 2010, table 2 (b) and (f))."""
        chosen = blocks[:, np.asarray(index, dtype=int)]  # (g + 2, n, s)
        chosen = chosen - np.mean(chosen[:2], axis=(0, 1))  # centred on the mean of A and B (Sobol' and Levitan)
        f_a, f_b, f_ab = chosen[0], chosen[1], chosen[2:]
        variance = np.var(np.concatenate([f_a, f_b]), axis=0)  # (s,)
        with np.errstate(divide="ignore", invalid="ignore"):
            first = np.mean(f_b * (f_ab - f_a), axis=1) / variance  # (g, s)
            total = 0.5 * np.mean((f_a - f_ab) ** 2, axis=1) / variance
        both = np.stack([first.T, total.T])
        return np.where(np.isfinite(both), both, 0.0)  # a quantity that does not vary: no share

    estimate = indices(np.arange(rows))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a quantity that does not vary: a degenerate bootstrap distribution
        interval = bootstrap((np.arange(rows),), lambda index: indices(index), confidence_level=CONFIDENCE,
                             n_resamples=RESAMPLES, method="BCa", vectorized=False, rng=seed).confidence_interval
    low, high = np.asarray(interval.low), np.asarray(interval.high)
    return SobolIndices(estimate[0], estimate[1], low[0], high[0], low[1], high[1], rows, count)
