"""Symmetric banded LDL^T factorisation with inertia, and the bordered (KKT) solve.

The rod's Hessian is symmetric with half bandwidth 5; the end-position constraint adds
a border of 3 dense rows.  We factor H = L D L^T without pivoting (cost O(n p^2)), read
the inertia of H from the signs of D (Sylvester's law), and eliminate the border with
a 3x3 Schur complement S = J H^-1 J^T.  The inertia of the KKT matrix [[H, J^T], [J, 0]]
is In(H) + In(-S), so the number of negative eigenvalues of the Hessian restricted to
the constraint tangent space is  neg(H) + pos(S) - 3  (Haynsworth / Gould).

Written by hand because LAPACK offers no banded LDL^T with inertia (its banded
Cholesky refuses indefinite matrices, which a compressed hose produces); pivots that
are too small are reported so the caller can shift the matrix.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def ldlt_banded(band, shift):
    """Factor (H + shift*I) given in lower band storage band[i, k] = H[i, i-k].

    Returns (unit_lower, diagonal, tiny) with unit_lower[i, k] = L[i, i-k] (k >= 1) and
    tiny True when a pivot was negligible against the matrix scale; such a pivot is
    replaced by the matrix scale, which keeps steps out of that (neutral) direction.
    """
    n, width = band.shape
    p = width - 1
    lower = np.zeros_like(band)
    diag = np.empty(n)
    scale = 0.0
    for i in range(n):
        scale = max(scale, abs(band[i, 0] + shift))
    tiny = False
    for j in range(n):
        # L[j, m] for m < j within the band, times D[m]
        value = band[j, 0] + shift
        for k in range(1, min(p, j) + 1):
            m = j - k
            value -= lower[j, k] ** 2 * diag[m]
        diag[j] = value
        if abs(value) <= 1e-13 * scale:
            # an exactly neutral direction (a symmetry of the problem): count it as neither
            # stable nor unstable and do not move along it (a pivot of the matrix's own scale)
            tiny = True
            diag[j] = scale
        for i in range(j + 1, min(n, j + p + 1)):
            value = band[i, i - j]
            for k in range(i - j + 1, min(p, i) + 1):
                m = i - k
                # L[i, m] L[j, m] D[m], m < j
                if j - m <= p:
                    value -= lower[i, k] * lower[j, j - m] * diag[m]
            lower[i, i - j] = value / diag[j]
    return lower, diag, tiny


@njit(cache=True)
def ldlt_solve(lower, diag, rhs):
    """Solve L D L^T x = rhs for one right-hand side (n,) or several (n, m)."""
    if rhs.ndim == 1:
        return _ldlt_solve_columns(lower, diag, rhs.reshape(-1, 1)).reshape(-1)
    return _ldlt_solve_columns(lower, diag, rhs)


@njit(cache=True)
def _ldlt_solve_columns(lower, diag, rhs):
    n, width = lower.shape
    p = width - 1
    m = rhs.shape[1]
    x = np.ascontiguousarray(rhs).copy()
    for i in range(n):
        for k in range(1, min(p, i) + 1):
            factor = lower[i, k]
            for j in range(m):
                x[i, j] -= factor * x[i - k, j]
    for i in range(n):
        inv = 1.0 / diag[i]
        for j in range(m):
            x[i, j] *= inv
    for i in range(n - 1, -1, -1):
        for k in range(1, min(p, n - 1 - i) + 1):
            factor = lower[i + k, k]
            for j in range(m):
                x[i, j] -= factor * x[i + k, j]
    return x


NEUTRAL = 1e-10  # pivots and eigenvalues below this fraction of the largest count as zero


@njit(cache=True)
def count_negative(values):
    """How many entries are clearly negative (below -NEUTRAL times the largest magnitude).

    A symmetry of the problem (e.g. mounts on one axis, free to turn about it) gives an
    exactly zero eigenvalue; rounding must not turn that neutral direction into an unstable one.
    """
    largest = 0.0
    for v in values:
        largest = max(largest, abs(v))
    count = 0
    for v in values:
        if v < -NEUTRAL * largest:
            count += 1
    return count


@njit(cache=True)
def symmetric_3x3_positive_count(s):
    """How many eigenvalues of a symmetric 3x3 matrix are clearly positive (closed-form eigenvalues)."""
    p1 = s[0, 1] ** 2 + s[0, 2] ** 2 + s[1, 2] ** 2
    mean = (s[0, 0] + s[1, 1] + s[2, 2]) / 3.0
    p2 = (s[0, 0] - mean) ** 2 + (s[1, 1] - mean) ** 2 + (s[2, 2] - mean) ** 2 + 2.0 * p1
    if p2 <= 1e-300:
        return 3 if mean > 0.0 else 0
    p = np.sqrt(p2 / 6.0)
    b = (s - mean * np.eye(3)) / p
    det_half = 0.5 * (
        b[0, 0] * (b[1, 1] * b[2, 2] - b[1, 2] * b[2, 1])
        - b[0, 1] * (b[1, 0] * b[2, 2] - b[1, 2] * b[2, 0])
        + b[0, 2] * (b[1, 0] * b[2, 1] - b[1, 1] * b[2, 0])
    )
    phi = np.arccos(min(1.0, max(-1.0, det_half))) / 3.0
    largest = mean + 2.0 * p * np.cos(phi)
    smallest = mean + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0)
    middle = 3.0 * mean - largest - smallest
    zero = NEUTRAL * max(abs(largest), abs(smallest))
    return int(largest > zero) + int(middle > zero) + int(smallest > zero)


@njit(cache=True)
def _solve_3x3(m, rhs):
    # Cramer's rule for the 3x3 Schur complement
    det = (
        m[0, 0] * (m[1, 1] * m[2, 2] - m[1, 2] * m[2, 1])
        - m[0, 1] * (m[1, 0] * m[2, 2] - m[1, 2] * m[2, 0])
        + m[0, 2] * (m[1, 0] * m[2, 1] - m[1, 1] * m[2, 0])
    )
    out = np.empty(3)
    for col in range(3):
        mc = m.copy()
        mc[:, col] = rhs
        out[col] = (
            mc[0, 0] * (mc[1, 1] * mc[2, 2] - mc[1, 2] * mc[2, 1])
            - mc[0, 1] * (mc[1, 0] * mc[2, 2] - mc[1, 2] * mc[2, 0])
            + mc[0, 2] * (mc[1, 0] * mc[2, 1] - mc[1, 1] * mc[2, 0])
        ) / det
    return out


@njit(cache=True)
def kkt_solve(lower, diag, jac_t, grad, constraint):
    """Newton step of the bordered system  [[H, J^T], [J, 0]] [p; -mu] = [-grad; -constraint].

    lower, diag: LDL^T factor of H.  jac_t: (n, 3) = J^T.  grad: (n,).  constraint: (3,).
    Returns (step, mu, unstable_directions) where mu solves H p - J^T mu = -grad, J p = -constraint,
    and unstable_directions is the number of negative eigenvalues of H on the tangent space
    of the constraint.
    """
    n = grad.shape[0]
    # one solve with four columns costs hardly more than one (the column loops pipeline)
    columns = np.empty((n, 4))
    columns[:, :3] = jac_t
    columns[:, 3] = grad
    solved = _ldlt_solve_columns(lower, diag, columns)
    h_inv_jt = solved[:, :3]
    h_inv_g = solved[:, 3]
    schur = np.zeros((3, 3))
    rhs = np.zeros(3)
    for i in range(n):
        for a in range(3):
            rhs[a] += jac_t[i, a] * h_inv_g[i]
            for b in range(3):
                schur[a, b] += jac_t[i, a] * h_inv_jt[i, b]
    schur = 0.5 * (schur + schur.T)
    for a in range(3):
        rhs[a] -= constraint[a]
    mu = _solve_3x3(schur, rhs)
    step = np.empty(n)
    for i in range(n):
        step[i] = h_inv_jt[i, 0] * mu[0] + h_inv_jt[i, 1] * mu[1] + h_inv_jt[i, 2] * mu[2] - h_inv_g[i]
    unstable = count_negative(diag) + symmetric_3x3_positive_count(schur) - 3
    return step, mu, unstable


@njit(cache=True)
def banded_matvec(band, x):
    """y = H x for symmetric H in lower band storage; x of shape (n,) or (n, m)."""
    n, width = band.shape
    y = np.zeros_like(x)
    columns = x.reshape(n, -1)
    out = y.reshape(n, -1)
    for i in range(n):
        for j in range(columns.shape[1]):
            out[i, j] += band[i, 0] * columns[i, j]
        for k in range(1, min(width - 1, i) + 1):
            for j in range(columns.shape[1]):
                out[i, j] += band[i, k] * columns[i - k, j]
                out[i - k, j] += band[i, k] * columns[i, j]
    return y
