"""Points of the unit hypercube to sample at: Monte Carlo, Latin hypercube or Sobol (scipy.stats.qmc).

The whole design is drawn once, up front, from the seed alone; sample i is row i.  So the
numbers do not depend on how the samples are later split into batches or spread over workers,
and a resumed study draws the same points again.
"""

from __future__ import annotations

import warnings

import numpy as np

METHODS = ("monte-carlo", "latin-hypercube", "sobol")


def unit_design(method: str, count: int, dimensions: int, seed: int) -> np.ndarray:
    """(count, dimensions) points in (0, 1).

    method: one of METHODS.  count: samples (Sobol is balanced for powers of two; other counts
    work, with a warning from SciPy that is silenced here and said in the study's notes).
    seed: any non-negative integer.
    """
    if method not in METHODS:
        raise ValueError(f"sampling method {method!r}: choose one of {', '.join(METHODS)}")
    if count < 1 or dimensions < 1:
        raise ValueError(f"a design needs at least one sample and one dimension, got {count} x {dimensions}")
    if method == "monte-carlo":
        return np.random.default_rng(seed).random((count, dimensions))
    from scipy.stats import qmc  # here: scipy.stats takes a second to import, and a refused study file needs none
    if method == "latin-hypercube":
        return qmc.LatinHypercube(d=dimensions, rng=seed).random(count)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # "balance properties ... require n = 2^m"
        return qmc.Sobol(d=dimensions, scramble=True, rng=seed).random(count)


def balanced(method: str, count: int) -> bool:
    """False for a Sobol design whose count is not a power of two (its balance is lost)."""
    return method != "sobol" or (count & (count - 1)) == 0
