"""Sampling to a requested precision: rounds of samples until a statistic's 95 % interval is narrow enough.

A Precision names a quantity, a statistic (its mean, or a percentile "P5"), the half width of the
statistic's 95 % confidence interval wanted (in the quantity's unit) and a cap on the samples.  After
each round the interval is taken over the solved samples so far (statistics.py: Student's t for the
mean, the order statistics for a percentile); while it is wider than asked, the next round brings the
total to what the 1/sqrt(n) law predicts the width needs (GROWTH_MARGIN more, between MIN_GROWTH and
MAX_GROWTH times the samples so far; a Sobol' design's total kept a power of two), up to the cap.  Where
the cap stops it, the outcome says so (reached: False).

The rounds are rows of one design (designs.round_design): Monte Carlo and Sobol' rows continue their
sequence, so n samples drawn in rounds are the first n of the design; a Latin hypercube is drawn
afresh for each round (each round stratified on its own).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from hoseline.procedures.variation.statistics import mean_interval, percentile_interval

GROWTH_MARGIN = 1.2  # the next round aims this much beyond the samples the 1/sqrt(n) law predicts
MIN_GROWTH = 1.5  # each round adds at least half the samples so far
MAX_GROWTH = 4.0  # and at most three times them (an unbounded or badly predicted width: grow steadily)
MIN_SOLVED = 4  # solved samples below which no interval is taken (infinitely wide)
_PERCENTILE = re.compile(r"P(\d+(?:\.\d+)?)")


@dataclass(frozen=True)
class Precision:
    """What [sampling.precision] asks: quantity (a quantity's name), statistic ("mean" or "P<p>", p in (0, 100)),
    half_width (> 0, the quantity's unit) of its 95 % interval, max_samples (the cap, >= the first round), unit (the
    quantity's, for reports).

    Raises ValueError naming statistic or half_width and the fix.
    """

    quantity: str
    statistic: str
    half_width: float
    max_samples: int
    unit: str = ""

    def __post_init__(self) -> None:
        if self.statistic != "mean":
            match = _PERCENTILE.fullmatch(self.statistic)
            if match is None or not 0.0 < float(match.group(1)) < 100.0:
                raise ValueError(f"statistic = \"{self.statistic}\": give \"mean\" or a percentile \"P<p>\" with p "
                                 "between 0 and 100, e.g. \"P5\"")
        if not (math.isfinite(self.half_width) and self.half_width > 0.0):
            raise ValueError(f"half_width = {self.half_width:g}: must be a positive number (the quantity's unit)")

    def interval(self, values: np.ndarray) -> tuple[float, float, float]:
        """(estimate, low, high) of the statistic over the finite entries of `values` (the solved samples), the
        interval CONFIDENCE; (NaN, -inf, inf) with fewer than MIN_SOLVED."""
        x = np.asarray(values, dtype=float)
        x = x[np.isfinite(x)]
        if x.size < MIN_SOLVED:
            return math.nan, -math.inf, math.inf
        if self.statistic == "mean":
            return (float(x.mean()), *mean_interval(x))
        p = float(self.statistic[1:])
        return (float(np.percentile(x, p)), *percentile_interval(np.sort(x), p))


@dataclass(frozen=True)
class PrecisionOutcome:
    """How sampling to a precision ended: the precision asked, the statistic's estimate and 95 % interval (low,
    high), its half width (high - low) / 2, the samples drawn, their rounds (samples each), and whether the
    width asked was reached (False: the cap stopped it)."""

    precision: Precision
    estimate: float
    low: float
    high: float
    samples: int
    rounds: tuple[int, ...]
    reached: bool

    @property
    def half_width(self) -> float:
        """Half the interval's width, the quantity's unit (inf while a percentile is not bounded)."""
        return (self.high - self.low) / 2.0

    def describe(self) -> str:
        """One sentence for notes and reports."""
        p = self.precision
        unit = p.unit
        said = (f"{p.statistic} of {p.quantity} = {self.estimate:.6g} {unit}, 95 % interval [{self.low:.6g}, "
                f"{self.high:.6g}]: half width {self.half_width:.3g} {unit} after {self.samples} samples in "
                f"{len(self.rounds)} round(s)")
        if self.reached:
            return f"{said}, within the {p.half_width:g} asked"
        return (f"{said}: NOT the {p.half_width:g} asked, the cap of max_samples = {p.max_samples} stopped it; "
                "raise max_samples, or accept the wider interval")


def next_total(samples: int, half_width: float, precision: Precision, power_of_two: bool) -> int:
    """The samples the next round brings the total to, from `samples` so far whose interval has `half_width`:
    the 1/sqrt(n) law's prediction times GROWTH_MARGIN, within [MIN_GROWTH, MAX_GROWTH] times `samples`, a power
    of two when `power_of_two` (a Sobol' design's balance), at most the cap."""
    ratio = half_width / precision.half_width
    growth = MAX_GROWTH if not math.isfinite(ratio) else min(max(GROWTH_MARGIN * ratio * ratio, MIN_GROWTH), MAX_GROWTH)
    total = math.ceil(samples * growth)
    if power_of_two:
        total = 1 << (total - 1).bit_length()
    return min(total, precision.max_samples)
