"""Numbers in hoseline's data files (sweep, study, hysteresis CSV): 8 significant digits, round-off written as 0.

A number smaller than ROUND_OFF times the largest magnitude of its quantity (round-off such as
3e-45 where the exact value is 0) is written as 0; a number that is not finite as an empty cell.
"""

from __future__ import annotations

import numpy as np

ROUND_OFF = 1e-12  # relative to the quantity's largest magnitude: below it, a number is written as 0


def without_round_off(values) -> np.ndarray:
    """`values` (an array of one quantity, any shape), entries below ROUND_OFF times its largest magnitude set to 0."""
    values = np.asarray(values, dtype=float)
    finite = np.abs(values[np.isfinite(values)])
    scale = finite.max() if finite.size else 0.0
    return np.where(np.abs(values) < ROUND_OFF * scale, 0.0, values) + 0.0  # + 0.0: no -0 either


def cell(value) -> str:
    """One CSV cell: a float with 8 significant digits (empty when not finite), anything else as str()."""
    if isinstance(value, (float, np.floating)):
        return "" if not np.isfinite(value) else f"{value:.8g}"
    return str(value)
