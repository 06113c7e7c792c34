"""From samples to answers: envelopes, probabilities of breaking a limit with confidence intervals, variances.

Probabilities are the fraction of solved samples beyond the limit, with the exact
(Clopper-Pearson) 95 % interval of a binomial proportion; failed samples are counted apart,
and the interval's upper end if every failed sample broke the limit is given beside it, with the
limit's process capability (Cpk, and the parts per million a normal quantity would put beyond it).  For
Latin hypercube and Sobol designs the binomial interval is conservative (such designs usually
estimate better than independent samples).

The variance of a quantity comes with its standard error, sqrt((m4 - s^4 (n - 3) / (n - 1)) / n)
(m4 the fourth central moment), so a first-order estimate can be judged against it: where they
differ by more than AGREEMENT standard errors the response is not linear over the tolerances
(near a fold, a fork of the equilibrium, or a limit of the linearisation) and the first-order
numbers must not be used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

from hoseline.procedures.variation.quantities import Limit

PERCENTILES = (5.0, 50.0, 95.0)
CONFIDENCE = 0.95
AGREEMENT = 3.0  # standard errors of the Monte Carlo variance within which a first-order variance agrees
NEGLIGIBLE = 1e-9  # standard deviations below this fraction of a quantity's natural scale are rounding


@dataclass(frozen=True)
class Probability:
    """P(the limit is broken): estimate and 95 % interval over the solved samples, and the interval's
    upper end counting every failed sample as broken.  broken, solved, failed: sample counts.

    cpk: the process capability of the (one-sided) limit, the mean's margin over three standard
    deviations of the solved samples (Cp needs two limits of one quantity: none here); ppm: the parts per
    million beyond the limit a normal quantity of that mean and standard deviation would give,
    1e6 Phi(-3 cpk) (beside the estimate counted, a check of how far from normal the tail is).  NaN with
    fewer than two solved samples.
    """

    limit: Limit
    broken: int
    solved: int
    failed: int
    estimate: float
    low: float
    high: float
    high_with_failed: float
    cpk: float = float("nan")
    ppm: float = float("nan")


def probability(limit: Limit, values: np.ndarray) -> Probability:
    """The probability that `limit` is broken, from the quantity's values of all samples (NaN: failed)."""
    values = np.asarray(values, dtype=float)
    solved = values[np.isfinite(values)]
    failed = values.size - solved.size
    broken = int(np.sum(limit.margin(solved) < 0.0))
    if solved.size == 0:
        return Probability(limit, 0, 0, failed, float("nan"), 0.0, 1.0, 1.0)
    from scipy.stats import binomtest  # here: scipy.stats takes a second to import, and a refused study file needs none

    interval = binomtest(broken, solved.size).proportion_ci(CONFIDENCE, method="exact")
    worst = binomtest(broken + failed, values.size).proportion_ci(CONFIDENCE, method="exact")
    cpk, ppm = capability(limit, solved)
    return Probability(limit, broken, int(solved.size), int(failed), broken / solved.size, float(interval.low),
                       float(interval.high), float(worst.high), cpk, ppm)


def capability(limit: Limit, solved: np.ndarray) -> tuple[float, float]:
    """(cpk, expected ppm beyond the limit if normal) of the solved values of the limited quantity (Probability)."""
    if solved.size < 2:
        return float("nan"), float("nan")
    sigma = float(np.std(solved, ddof=1))
    margin = float(limit.margin(np.mean(solved)))
    if sigma == 0.0:
        return math.copysign(math.inf, margin), 0.0 if margin >= 0.0 else 1e6
    cpk = margin / (3.0 * sigma)
    return cpk, 1e6 * float(ndtr(-3.0 * cpk))


@dataclass(frozen=True)
class Spread:
    """The distribution of one quantity over the solved samples: mean, standard deviation, variance
    and its standard error, the PERCENTILES, the extremes, and how many samples were solved; with the
    95 % confidence interval of the mean (Student's t) and of each percentile (distribution-free: the
    order statistics whose ranks bound the binomial count of samples below it; -inf or inf where too
    few samples lie beyond it to bound it)."""

    mean: float
    std: float
    variance: float
    variance_error: float
    percentiles: tuple[float, ...]
    minimum: float
    maximum: float
    solved: int
    mean_interval: tuple[float, float] = (float("nan"), float("nan"))
    percentile_intervals: tuple[tuple[float, float], ...] = ()


def spread(values: np.ndarray) -> Spread:
    """The Spread of a quantity's values (NaN entries, the failed samples, left out)."""
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    n = x.size
    if n < 4:
        nan = float("nan")
        return Spread(nan, nan, nan, nan, (nan,) * len(PERCENTILES), nan, nan, n, (nan, nan), ((nan, nan),) * len(PERCENTILES))
    variance = float(np.var(x, ddof=1))
    m4 = float(np.mean((x - x.mean()) ** 4))
    error = float(np.sqrt(max(m4 - variance**2 * (n - 3) / (n - 1), 0.0) / n))
    ordered = np.sort(x)
    return Spread(float(x.mean()), float(np.sqrt(variance)), variance, error,
                  tuple(float(v) for v in np.percentile(x, PERCENTILES)), float(x.min()), float(x.max()), n,
                  mean_interval(x), tuple(percentile_interval(ordered, p) for p in PERCENTILES))


def mean_interval(x: np.ndarray) -> tuple[float, float]:
    """The CONFIDENCE interval of the mean of the finite values `x` (two or more), Student's t."""
    from scipy.stats import t  # here: scipy.stats takes a second to import, and a refused study file needs none

    n = x.size
    half = float(t.ppf(0.5 + CONFIDENCE / 2.0, n - 1) * np.sqrt(np.var(x, ddof=1) / n))
    return float(x.mean()) - half, float(x.mean()) + half


def percentile_interval(ordered: np.ndarray, p: float) -> tuple[float, float]:
    """The distribution-free CONFIDENCE interval of the p-th percentile (p in (0, 100)) of sorted finite values:
    the order statistics whose ranks bound the binomial count of samples below it (-inf or inf where too few
    samples lie beyond it to bound it)."""
    from scipy.stats import binom

    n = ordered.size
    # ranks l, u (from 1) with P(l <= B <= u - 1) >= CONFIDENCE, B ~ Binomial(n, p) the samples below the percentile
    low = int(binom.ppf((1.0 - CONFIDENCE) / 2.0, n, p / 100.0))
    high = int(binom.ppf(0.5 + CONFIDENCE / 2.0, n, p / 100.0)) + 1
    return (float(ordered[low - 1]) if low >= 1 else -math.inf, float(ordered[high - 1]) if high <= n else math.inf)


@dataclass(frozen=True)
class Agreement:
    """A first-order variance against the Monte Carlo one: z = (MC - first order) / standard error of MC."""

    first_order_variance: float
    monte_carlo_variance: float
    standard_error: float
    z: float

    @property
    def agrees(self) -> bool:
        """Within AGREEMENT standard errors."""
        return bool(abs(self.z) <= AGREEMENT)

    def verdict(self) -> str:
        """One sentence for reports."""
        if self.agrees:
            return f"agrees within sampling error (z = {self.z:+.1f})"
        return (f"DISAGREES (z = {self.z:+.1f}): the response is not linear over these tolerances (a fold, a fork "
                "of the equilibrium, or tolerances too large for a linearisation); use the Monte Carlo numbers")


def agreement(first_order_variance: float, monte_carlo_variance: float, standard_error: float,
              scale: float) -> Agreement:
    """Compare a first-order variance with a Monte Carlo variance and its standard error.

    scale: the quantity's natural magnitude (quantities.natural_scale); spreads below NEGLIGIBLE times
    it are rounding, and agree.
    """
    if max(first_order_variance, monte_carlo_variance) <= (NEGLIGIBLE * scale) ** 2:
        return Agreement(first_order_variance, monte_carlo_variance, standard_error, 0.0)
    z = (monte_carlo_variance - first_order_variance) / max(standard_error, (NEGLIGIBLE * scale) ** 2)
    return Agreement(first_order_variance, monte_carlo_variance, standard_error, float(z))


def station_envelope(shapes: np.ndarray) -> dict[str, np.ndarray]:
    """Per station and axis of sampled centrelines (S, N+1, 3), failed rows NaN: P5, P50, P95 (each (3, N+1, 3)
    stacked as 'percentiles'), 'minimum' and 'maximum' (N+1, 3) mm."""
    solved = shapes[np.all(np.isfinite(shapes), axis=(1, 2))]
    return {
        "percentiles": np.percentile(solved, PERCENTILES, axis=0),
        "minimum": solved.min(axis=0),
        "maximum": solved.max(axis=0),
    }


def worst_sample(limit: Limit, values: np.ndarray) -> int | None:
    """Index of the sample with the least margin to `limit` (None if none was solved)."""
    margin = limit.margin(values)
    if not np.any(np.isfinite(margin)):
        return None
    return int(np.nanargmin(margin))
