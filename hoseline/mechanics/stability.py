"""Stability of an equilibrium: the smallest eigenvalues of the energy Hessian on the
tangent space of the clamps (rotations that keep the end point where it is).

Shift-invert subspace iteration around zero with the banded KKT factorisation of
banded.py, so the cost stays linear in N.  When the inertia says there are more
negative directions than the iteration found (far-negative eigenvalues), a dense
eigen-decomposition of the projected Hessian is used instead (rare, and only then).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from hoseline.mechanics.banded import banded_matvec, kkt_solve, ldlt_banded, ldlt_solve


def _band_to_dense(band: np.ndarray) -> np.ndarray:
    n, width = band.shape
    dense = np.zeros((n, n))
    for k in range(width):
        idx = np.arange(k, n)
        dense[idx, idx - k] = band[k:, k]
        dense[idx - k, idx] = band[k:, k]
    return dense


def _dense_pairs(band: np.ndarray, jac_t: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    basis = scipy.linalg.null_space(jac_t.T)
    reduced = basis.T @ _band_to_dense(band) @ basis
    values, vectors = scipy.linalg.eigh(reduced, subset_by_index=[0, count - 1])
    return values, basis @ vectors


def smallest_eigenpairs(band: np.ndarray, jac_t: np.ndarray, count: int = 1, tolerance: float = 1e-6):
    """The `count` algebraically smallest eigenvalues (N*mm/rad^2) and unit eigenvectors of the
    Hessian restricted to {v : J v = 0}.

    band: lower band storage of the Hessian; jac_t: (n, 3) transposed constraint Jacobian.
    tolerance: relative residual of the eigenpairs (the eigenvalues are then accurate to
    about its square).
    """
    n = band.shape[0]
    lower, diag, tiny = ldlt_banded(band, 0.0)
    negative = int(kkt_solve(lower, diag, jac_t, np.zeros(n), np.zeros(3))[2])
    if tiny or n < 40:
        return _dense_pairs(band, jac_t, count)
    h_inv_jt = ldlt_solve(lower, diag, jac_t)
    schur = jac_t.T @ h_inv_jt
    normal = jac_t.T @ jac_t

    def solve_projected(rhs: np.ndarray) -> np.ndarray:
        # [[H, J^T], [J, 0]] [w; y] = [rhs; 0]  ->  w = H^-1 (rhs - J^T y), J w = 0
        h_inv_rhs = ldlt_solve(lower, diag, rhs)
        y = np.linalg.solve(schur, jac_t.T @ h_inv_rhs)
        return h_inv_rhs - h_inv_jt @ y

    block = max(count, negative) + 3
    rng = np.random.default_rng(12345)
    vectors = solve_projected(rng.standard_normal((n, block)))
    values = np.full(block, np.inf)
    for _ in range(200):
        vectors, _ = np.linalg.qr(vectors)
        hv = banded_matvec(band, vectors)
        ritz_values, ritz_vectors = np.linalg.eigh(vectors.T @ hv)
        vectors = vectors @ ritz_vectors
        raw = hv @ ritz_vectors - vectors * ritz_values
        raw -= jac_t @ np.linalg.solve(normal, jac_t.T @ raw)  # only the part within the tangent space counts
        residual = np.linalg.norm(raw, axis=0)
        scale = max(abs(ritz_values[0]), 1e-30 * np.max(np.abs(band[:, 0])) + 1e-300)
        values = ritz_values
        if np.all(residual[:count] <= tolerance * max(scale, np.max(np.abs(ritz_values[:count])))):
            break
        vectors = solve_projected(vectors)
    found_negative = int(np.sum(values < 0.0))
    if found_negative < negative:
        return _dense_pairs(band, jac_t, max(count, negative))
    order = np.argsort(values)[: max(count, negative)]
    return values[order], vectors[:, order]
