"""Worst-case (corner) analysis: each quantity at the corner of the tolerances that makes it worst.

A tolerance's worst-case range is its support when bounded (uniform, triangular, sphere, cone,
loguniform; an empirical one's measured extremes), WORST_CASE_SIGMAS standard deviations either side of the mean when not (normal,
lognormal in ln of the factor; a truncated normal within both).  To first order a quantity Q0 + g.c is
worst where each tolerance takes the point of its range furthest along -g (a minimum: bend radius,
clearance) or +g (a maximum: torque, twist rate): the corner of a box, the point of a ball or cone along
the gradient.  Summed over the tolerances (a shared one once, with the sum of its targets' derivatives),
that is the classical worst-case stack; the hose is then solved at that corner, which gives the worst
value without the linearisation (the corner itself is still the first order's choice).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hoseline.procedures.variation.quantities import LOWER, Quantity
from hoseline.procedures.variation.tolerances import Z95, Tolerance, Variation

WORST_CASE_SIGMAS = 3.0  # the range of an unbounded distribution: this many standard deviations either side
NEGLIGIBLE = 1e-6  # of the largest tolerance's push: a smaller one is rounding (measured 4e-9: the central differences
#                     of the sensitivities, steps of 1e-7 of the scale, resolve a derivative to about 1e-9 of the value)


def extreme(tolerance: Tolerance, direction: np.ndarray) -> np.ndarray:
    """(len(coordinates),) the deviation within the tolerance's worst-case range furthest along `direction` (world
    axes, one per coordinate it moves); where the direction is zero the tolerance stays at its mean."""
    axes = np.array(tolerance.axes) if tolerance.axes else np.eye(len(tolerance.coordinates))
    along = axes @ np.asarray(direction, dtype=float)  # the direction in the tolerance's own axes
    sign = np.sign(along)
    size = np.array(tolerance.size)
    kind, name = tolerance.kind, tolerance.distribution
    if kind in ("point", "tilt"):
        if name in ("sphere", "cone"):
            norm = float(np.linalg.norm(along))
            own = size[0] * along / norm if norm > 0.0 else np.zeros_like(along)
        else:  # normal (sigma per axis, or one for a tilt), uniform (+-tolerance per axis)
            reach = WORST_CASE_SIGMAS * size if name == "normal" else size
            own = sign * (reach if kind == "point" else reach[0])
        return own @ axes
    low, high = _range(tolerance)
    if sign[0] == 0.0:
        return tolerance.mean()
    return np.array([high if sign[0] > 0.0 else low])


def _range(tolerance: Tolerance) -> tuple[float, float]:
    """(low, high) worst-case range of an offset (user units) or a factor (ln of it)."""
    size = tolerance.size
    name = tolerance.distribution
    if name == "normal":
        return -WORST_CASE_SIGMAS * size[0], WORST_CASE_SIGMAS * size[0]
    if name == "uniform":
        return (math.log(size[0]), math.log(size[1])) if tolerance.kind == "factor" else (size[0], size[1])
    if name == "triangular":
        return size[0], size[2]
    if name == "truncnormal":
        mean, sigma, low, high = size
        return max(low, mean - WORST_CASE_SIGMAS * sigma), min(high, mean + WORST_CASE_SIGMAS * sigma)
    if name == "lognormal":
        spread = WORST_CASE_SIGMAS * math.log(size[0]) / Z95
        return -spread, spread
    if name == "empirical":  # the measured extremes
        return (math.log(size[0]), math.log(size[-1])) if tolerance.kind == "factor" else (size[0], size[-1])
    return -math.log(size[0]), math.log(size[0])  # loguniform


def corner(variation: Variation, gradient: np.ndarray) -> np.ndarray:
    """(width,) the deviations that push a quantity of derivative `gradient` (width,) furthest up, to first order.

    A tolerance whose push is below NEGLIGIBLE of the largest one's stays at its mean: its derivative is rounding
    (the EI of a weightless hose scales every load and moves no bend radius: 3.6e-9 mm per unit of ln EI, 4.5e-9 of
    the end point's push), its sign no choice of corner."""
    values, pushes = [], []
    for tolerance in variation.tolerances:
        direction = sum(gradient[list(target)] for target in tolerance.targets)  # one deviation, every target
        value = extreme(tolerance, direction)
        values.append(value)
        pushes.append(abs(float(direction @ (value - tolerance.mean()))))
    out = np.zeros(variation.width)
    largest = max(pushes, default=0.0)
    for tolerance, value, push in zip(variation.tolerances, values, pushes):
        for target in tolerance.targets:
            out[list(target)] += value if push > NEGLIGIBLE * largest else tolerance.mean()
    return out


@dataclass
class WorstCase:
    """One quantity's worst case: the quantity, its nominal value, the corner (width,) deviations, the first-order
    worst value there (the linear stack), the solved value there (NaN when the hose could not be solved, reason
    why)."""

    quantity: Quantity
    nominal: float
    corner: np.ndarray
    first_order: float
    solved: float = math.nan
    reason: str = ""


def worst_cases(variation: Variation, quantities: tuple[Quantity, ...], values: np.ndarray,
                derivatives: np.ndarray) -> list[WorstCase]:
    """The corner of each quantity (values (q,) nominal, derivatives (q, width)) toward its worse side (down for a
    minimum-limited quantity, up for a maximum-limited one)."""
    out = []
    for quantity, value, gradient in zip(quantities, values, derivatives):
        worse = -gradient if quantity.sense == LOWER else gradient
        deviation = corner(variation, worse)
        out.append(WorstCase(quantity, float(value), deviation, float(value + gradient @ deviation)))
    return out
