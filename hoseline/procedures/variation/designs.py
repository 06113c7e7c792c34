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


def round_design(method: str, rounds: tuple[int, ...], dimensions: int, seed: int) -> np.ndarray:
    """(sum(rounds), dimensions) points in (0, 1) drawn in rounds of rounds[r] samples (precision.py).

    Monte Carlo and Sobol' rows continue their sequence: the rows of unit_design(method, sum(rounds)), so the
    first round is the design of its samples alone and a round never changes an earlier one.  A Latin
    hypercube is drawn afresh for each round (the first from the seed, round r from the seed and r), each
    round stratified on its own.
    """
    if method != "latin-hypercube":
        return unit_design(method, sum(rounds), dimensions, seed)
    from scipy.stats import qmc

    first = unit_design(method, rounds[0], dimensions, seed)
    later = [qmc.LatinHypercube(d=dimensions, rng=np.random.default_rng([seed, r])).random(count)
             for r, count in enumerate(rounds[1:], start=1)]
    return np.vstack([first, *later])


def balanced(method: str, count: int) -> bool:
    """False for a Sobol design whose count is not a power of two (its balance is lost)."""
    return method != "sobol" or (count & (count - 1)) == 0
