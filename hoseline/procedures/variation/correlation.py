"""Correlated tolerances: a Gaussian copula over tolerances of any kind and distribution.

A correlation names tolerances (of a study's Variation, by index) and a correlation matrix R between
them.  The sample's unit point u (the design's row: Monte Carlo, Latin hypercube or Sobol') is taken to
normal scores z = Phi^-1(u), correlated by the Cholesky factor L of R (z' = L z), and back to unit scores
u' = Phi(z'), which each tolerance's inverse distribution function turns into its deviation as before
(tolerances.Tolerance.values): each tolerance keeps its own distribution (its marginal), and their normal
scores have the correlation R.  A tolerance of several axes (a point's x, y, z; a direction's two tilts)
is correlated axis by axis with another of as many axes (x with x, ...); its distribution must then draw
each axis from its own unit score (normal and uniform points, normal tilts: Tolerance.per_axis).

The covariance the first-order variance needs between two correlated tolerances is that of their
marginals under the copula, E[(X - EX)(Y - EY)] with X = F^-1(Phi(z1)), Y = G^-1(Phi(z2)) and corr(z1, z2)
= rho, by Gauss-Hermite quadrature (QUADRATURE_NODES per axis): rho sigma_X sigma_Y for two normals, a
little less in magnitude for others (two uniforms: (6 / pi) arcsin(rho / 2) sigma_X sigma_Y).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.polynomial.hermite_e import hermegauss
from scipy.special import ndtr, ndtri

QUADRATURE_NODES = 64  # Gauss-Hermite nodes per axis of the induced covariance
SYMMETRY = 1e-9  # |R_ij - R_ji| above this is not symmetric
DEFINITE = 1e-9  # the smallest eigenvalue of R must exceed this (a singular R makes one tolerance a copy of others)
EDGE = 1e-12  # unit scores are kept this far inside (0, 1), as tolerances._EDGE


@dataclass(frozen=True)
class Correlation:
    """A correlation matrix between tolerances: tolerances (indexes into Variation.tolerances, two or more, each
    once), matrix (symmetric, unit diagonal, entries in [-1, 1], positive definite), in the same order.

    Raises ValueError naming "tolerances" or "matrix" and the fix.
    """

    tolerances: tuple[int, ...]
    matrix: tuple[tuple[float, ...], ...]

    def __post_init__(self) -> None:
        names = tuple(int(k) for k in self.tolerances)
        if len(names) < 2 or len(set(names)) != len(names):
            raise ValueError(f"tolerances = {list(names)}: name two tolerances or more, each once")
        object.__setattr__(self, "tolerances", names)
        count = len(names)
        rows = [list(row) for row in self.matrix]
        if len(rows) != count or any(len(row) != count for row in rows):
            raise ValueError(f"matrix must be {count} x {count}, one row and column per tolerance named, in their order")
        r = np.array(rows, dtype=float)
        if not np.all(np.isfinite(r)):
            raise ValueError("matrix: every entry must be a finite number")
        for i in range(count):
            if r[i, i] != 1.0:
                raise ValueError(f"matrix[{i}][{i}] = {r[i, i]:g}: the diagonal of a correlation matrix is 1; set it to 1")
        outside = np.argwhere(np.abs(r) > 1.0)
        if outside.size:
            i, j = outside[0]
            raise ValueError(f"matrix[{i}][{j}] = {r[i, j]:g}: a correlation lies in [-1, 1]")
        asymmetric = np.argwhere(np.abs(r - r.T) > SYMMETRY)
        if asymmetric.size:
            i, j = asymmetric[0]
            raise ValueError(f"matrix[{i}][{j}] = {r[i, j]:g} but matrix[{j}][{i}] = {r[j, i]:g}: a correlation matrix "
                             "is symmetric; make them equal")
        smallest = float(np.linalg.eigvalsh(r).min())
        if smallest <= DEFINITE:
            raise ValueError(f"matrix is not positive definite (smallest eigenvalue {smallest:.3g}): these correlations "
                             "cannot hold together (e.g. a with b and b with c strongly, a with c weakly or negatively); "
                             "weaken them, or name a tolerance that moves several parameters with shared_with instead "
                             "of a correlation of 1")
        object.__setattr__(self, "matrix", tuple(tuple(float(v) for v in row) for row in r))


def dimension_correlation(correlations: tuple[Correlation, ...], dimensions: tuple[int, ...]) -> np.ndarray:
    """(D, D) correlation of the normal scores of the unit hypercube's D = sum(dimensions) columns.

    dimensions: per tolerance, its columns (Tolerance.dimensions), in order; the tolerances of one Correlation
    must have as many each (checked by the Variation): axis i of one with axis i of another.
    """
    first = np.concatenate([[0], np.cumsum(dimensions)[:-1]]).astype(int)
    out = np.eye(int(sum(dimensions)))
    for correlation in correlations:
        for a, i in enumerate(correlation.tolerances):
            for b, j in enumerate(correlation.tolerances):
                if a != b:
                    for axis in range(dimensions[i]):
                        out[first[i] + axis, first[j] + axis] = correlation.matrix[a][b]
    return out


def correlated_unit(unit: np.ndarray, cholesky: np.ndarray) -> np.ndarray:
    """(n, D) unit scores of `unit` (n, D) in (0, 1) whose normal scores are correlated by `cholesky` (the lower
    Cholesky factor of dimension_correlation)."""
    scores = ndtri(np.clip(unit, EDGE, 1.0 - EDGE))
    return ndtr(scores @ cholesky.T)


def induced_covariance(first, second, rho: float) -> np.ndarray:
    """(k, k) covariance along their own axes of two tolerances of k axes each (Tolerance, per_axis) whose normal
    scores are correlated by rho axis by axis (diagonal: axis i with axis i, the others independent)."""
    nodes, weights = hermegauss(QUADRATURE_NODES)
    weights = weights / weights.sum()
    inner = np.sqrt(max(1.0 - rho * rho, 0.0))
    x = _marginal(first, nodes)  # (nodes, k)
    y = _marginal(second, (rho * nodes[:, None] + inner * nodes[None, :]).ravel()).reshape(len(nodes), len(nodes), -1)
    x = x - weights @ x
    y_mean = np.einsum("j,k,jka->a", weights, weights, y)
    return np.diag(np.einsum("j,k,ja,jka->a", weights, weights, x, y - y_mean))


def _marginal(tolerance, scores: np.ndarray) -> np.ndarray:
    """(len(scores), k) the tolerance's value along each of its own axes at the normal score `scores` of that
    axis (its axes drawn independently, each from its own unit score)."""
    unit = np.repeat(ndtr(scores)[:, None], tolerance.dimensions, axis=1)
    return tolerance.along_axes(unit).reshape(len(scores), -1)
