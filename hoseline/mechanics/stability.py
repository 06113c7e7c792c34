"""Stability of an equilibrium: the smallest eigenvalues of the energy Hessian on the
tangent space of the clamps (rotations that keep the end point where it is).

Shift-invert subspace iteration around zero with the banded KKT factorisation of
banded.py, so the cost stays linear in N.  When the inertia says there are more
negative directions than the iteration found (far-negative eigenvalues), a dense
eigen-decomposition of the projected Hessian is used instead (rare, and only then).
"""

from __future__ import annotations

import functools

import numpy as np
from numba import njit

from hoseline.mechanics.banded import band_to_dense, banded_matvec, kkt_solve, ldlt_banded, ldlt_solve
from hoseline.mechanics.bordered import kkt_solve_bordered


def _dense_pairs(band: np.ndarray, jac_t: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    import scipy.linalg  # here, not at the top: only small or far-unstable systems need it (0.1 s to load)

    basis = scipy.linalg.null_space(jac_t.T)
    reduced = basis.T @ band_to_dense(band) @ basis
    values, vectors = scipy.linalg.eigh(reduced, subset_by_index=[0, count - 1])
    return values, basis @ vectors


def smallest_eigenpairs(band: np.ndarray, jac_t: np.ndarray, count: int = 1, tolerance: float = 1e-6):
    """The `count` algebraically smallest eigenvalues (N*mm/rad^2) and unit eigenvectors of the
    Hessian restricted to {v : J v = 0}.

    band: lower band storage of the Hessian; jac_t: (n, m) transposed constraint Jacobian (m = 3, or 3 + 3c with clips).
    tolerance: relative residual of the eigenpairs (the eigenvalues are then accurate to
    about its square).
    """
    n, m = jac_t.shape
    lower, diag, negative_in_h, tiny = ldlt_banded(band, 0.0)
    solve = kkt_solve if m == 3 else kkt_solve_bordered  # a border of 3 + 3c rows with clips
    negative = int(solve(lower, diag, negative_in_h, jac_t, np.zeros(n), np.zeros(m))[2])
    if tiny or n < 40:
        return _dense_pairs(band, jac_t, count)
    block = max(count, negative) + 3
    # the m x m border matrices, inverted here once (NumPy): the compiled iteration needs no
    # linear solver of its own (Numba's LAPACK glue would add 3 s to the first run's compiling)
    h_inv_jt = ldlt_solve(lower, diag, jac_t)
    schur_inverse = np.linalg.inv(jac_t.T @ h_inv_jt)
    normal_inverse = np.linalg.inv(jac_t.T @ jac_t)
    start = _start_block(n, block).copy()
    values, vectors = _subspace_iteration(
        band, jac_t, lower, diag, h_inv_jt, schur_inverse, normal_inverse, start, count, tolerance
    )
    found_negative = int(np.sum(values < 0.0))
    if found_negative < negative:
        return _dense_pairs(band, jac_t, max(count, negative))
    order = np.argsort(values)[: max(count, negative)]
    return values[order], vectors[:, order]


@functools.lru_cache(maxsize=16)
def _start_block(n: int, block: int) -> np.ndarray:
    """Fixed random start vectors (n, block) of the subspace iteration, the same for every call
    (kept: drawing them costs more than a copy; callers copy before use)."""
    return np.random.default_rng(12345).standard_normal((n, block))


@njit(cache=True)
def _solve_projected(lower, diag, jac_t, h_inv_jt, schur_inverse, rhs):
    # [[H, J^T], [J, 0]] [w; y] = [rhs; 0]  ->  w = H^-1 (rhs - J^T y), J w = 0
    h_inv_rhs = ldlt_solve(lower, diag, rhs)
    y = schur_inverse @ (jac_t.T @ h_inv_rhs)
    return h_inv_rhs - h_inv_jt @ y


@njit(cache=True)
def _subspace_iteration(band, jac_t, lower, diag, h_inv_jt, schur_inverse, normal_inverse, start, count, tolerance):
    """Shift-invert subspace iteration around zero on the constraint tangent space, from the
    columns of `start`; returns the Ritz values and vectors of the last iteration (unsorted).

    h_inv_jt = H^-1 J^T; schur_inverse = (J H^-1 J^T)^-1; normal_inverse = (J J^T)^-1.
    Compiled: a handful of iterations on (n, block) arrays, where Python's per-call cost of
    every small NumPy operation would dominate.  The sums and largest values are written as loops (the
    same arithmetic in the same order): Numba's np.sum along an axis and np.max compiled for 2.2 s.
    """
    vectors = _solve_projected(lower, diag, jac_t, h_inv_jt, schur_inverse, start)
    values = np.full(start.shape[1], np.inf)
    band_scale = 0.0
    for row in range(band.shape[0]):
        band_scale = max(band_scale, abs(band[row, 0]))
    residual = np.empty(start.shape[1])
    for _ in range(200):
        vectors = np.ascontiguousarray(np.linalg.qr(vectors)[0])  # C order for banded_matvec
        hv = banded_matvec(band, vectors)
        ritz_values, ritz_vectors = np.linalg.eigh(vectors.T @ hv)
        vectors = vectors @ ritz_vectors
        raw = hv @ ritz_vectors - vectors * ritz_values
        raw -= jac_t @ (normal_inverse @ (jac_t.T @ raw))  # only the part within the tangent space counts
        for column in range(raw.shape[1]):  # the norm of each column
            squares = 0.0
            for row in range(raw.shape[0]):
                squares += raw[row, column] ** 2
            residual[column] = np.sqrt(squares)
        scale = max(abs(ritz_values[0]), 1e-30 * band_scale + 1e-300)
        values = ritz_values
        largest = 0.0
        for column in range(count):
            largest = max(largest, abs(ritz_values[column]))
        if np.all(residual[:count] <= tolerance * max(scale, largest)):
            break
        vectors = _solve_projected(lower, diag, jac_t, h_inv_jt, schur_inverse, vectors)
    return values, vectors
