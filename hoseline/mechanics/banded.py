"""Symmetric banded LDL^T factorisation with inertia, and the bordered (KKT) solve.

The rod's Hessian is symmetric with half bandwidth 5; the end-position constraint adds
a border of 3 dense rows.  We factor H = L D L^T without pivoting (cost O(n p^2)), read
the inertia of H from the signs of D (Sylvester's law, ldlt_banded), and eliminate the border with
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

# Let the compiler fuse a*b + c into one instruction (FMA) in the per-iteration kernels: a
# rounding difference only (one rounding instead of two); NaN and inf propagate as before.
FUSED_MULTIPLY_ADD = {"contract"}


NEUTRAL = 1e-10  # pivots and eigenvalues below this fraction of their scale count as zero


@njit(cache=True, fastmath=FUSED_MULTIPLY_ADD)
def ldlt_banded(band, shift):
    """Factor (H + shift*I) given in lower band storage band[i, k] = H[i, i-k].

    Returns (unit_lower, diagonal, negative, tiny) with unit_lower[i, k] = L[i, i-k] (k >= 1),
    negative the number of negative eigenvalues of H + shift*I (count_negative_pivots), and tiny True
    when a pivot was negligible against the matrix scale; such a pivot is replaced by the matrix
    scale, which keeps steps out of that (neutral) direction.
    """
    n, width = band.shape
    p = width - 1
    lower = np.zeros_like(band)
    diag = np.empty(n)
    inv_diag = np.empty(n)
    passed_on = np.zeros(n)  # passed_on[j]: the largest L[i, j]^2 |D[j]| taken off a later pivot
    scale = 0.0
    for i in range(n):
        scale = max(scale, abs(band[i, 0] + shift))
    tiny = False
    row = np.empty(p)  # row[j - first] = L[i, j] D[j] for the columns j of the current row i
    for i in range(n):
        # Row by row (Doolittle).  L keeps the envelope of H: row i of L starts where row i of H
        # does, so the rows of the block-tridiagonal Hessian that reach back only 3 or 4 columns
        # are cheaper than the full bandwidth.
        reach = min(p, i)
        while reach > 0 and band[i, reach] == 0.0:
            reach -= 1
        first = i - reach
        pivot = band[i, 0] + shift
        for j in range(first, i):
            # L[i, j] D[j] = H[i, j] - sum_m L[i, m] D[m] L[j, m], m from first to j-1
            value = band[i, i - j]
            for m in range(first, j):
                value -= row[m - first] * lower[j, j - m]
            row[j - first] = value
            factor = value * inv_diag[j]
            lower[i, i - j] = factor
            taken = value * factor
            pivot -= taken
            passed_on[j] = max(passed_on[j], abs(taken))
        diag[i] = pivot
        if abs(pivot) <= 1e-13 * scale:
            # an exactly neutral direction (a symmetry of the problem): count it as neither
            # stable nor unstable and do not move along it (a pivot of the matrix's own scale)
            tiny = True
            diag[i] = scale
        inv_diag[i] = 1.0 / diag[i]
    return lower, diag, count_negative_pivots(diag, passed_on, scale), tiny


@njit(cache=True)
def count_negative_pivots(diag, passed_on, scale):
    """The number of negative eigenvalues of a matrix factored as L D L^T (Sylvester's law: the
    negative pivots), with the neutral directions counted as neither.

    diag: the pivots D.  passed_on: per pivot, the largest term |L[i, j]^2 D[j]| its elimination took
    off a later pivot.  scale: the largest diagonal entry of the matrix (the unit of the pivots).
    A pivot that is zero to rounding (below NEUTRAL x scale) is a neutral direction (a symmetry of
    the mounts) and counts as neither, unless its elimination passed a term larger than the matrix
    scale on to a later pivot: without pivoting, a near-zero pivot that couples to the next rows
    is one half of an indefinite pair (a 2 x 2 block [[~0, b], [b, c]], eigenvalues about +-b) whose
    other half comes out about -b^2 / pivot, far above the scale.  The pair holds one negative
    eigenvalue whichever sign rounding gives the small pivot, so both signs count.  The scale is
    the matrix's, not the largest pivot's: such a grown pivot must not make the genuinely negative
    pivots of an ordinary size look neutral.
    """
    count = 0
    for i in range(diag.size):
        if diag[i] < -NEUTRAL * scale or (diag[i] < 0.0 and passed_on[i] > scale):
            count += 1
    return count


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
    x = np.empty((n, m))
    # each column's sum in a register, the columns of a row independent of one another, and
    # the row just solved added last: short chains of dependent operations
    for i in range(n):
        for j in range(m):
            value = rhs[i, j]
            for k in range(min(p, i), 0, -1):
                value -= lower[i, k] * x[i - k, j]
            x[i, j] = value
    for i in range(n - 1, -1, -1):
        inv = 1.0 / diag[i]
        for j in range(m):
            value = x[i, j] * inv
            for k in range(min(p, n - 1 - i), 0, -1):
                value -= lower[i + k, k] * x[i + k, j]
            x[i, j] = value
    return x


@njit(cache=True)
def count_negative(values):
    """How many eigenvalues are clearly negative (below -NEUTRAL times the largest magnitude).

    A symmetry of the problem (e.g. mounts on one axis, free to turn about it) gives an
    exactly zero eigenvalue; rounding must not turn that neutral direction into an unstable one.
    For eigenvalues only: the pivots of an LDL^T can grow far above the matrix scale (ldlt_banded
    counts its own).
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
    b = s / p
    for k in range(3):  # b = (s - mean I) / p, without compiling np.eye
        b[k, k] -= mean / p
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
def solve_3x3(m, rhs):
    """m^-1 rhs for a 3x3 matrix m and rhs of shape (3,) or (3, k), by Cramer's rule.

    For the 3x3 Schur complements of the border: a closed form, where a general solver
    costs more (and takes seconds to compile).
    """
    cofactor = np.empty((3, 3))  # cofactor[r, c] of entry (r, c)
    for r in range(3):
        r1, r2 = (r + 1) % 3, (r + 2) % 3
        for c in range(3):
            c1, c2 = (c + 1) % 3, (c + 2) % 3
            cofactor[r, c] = m[r1, c1] * m[r2, c2] - m[r1, c2] * m[r2, c1]
    det = m[0, 0] * cofactor[0, 0] + m[0, 1] * cofactor[0, 1] + m[0, 2] * cofactor[0, 2]
    columns = rhs.reshape(3, -1)
    out = np.empty_like(columns)
    for j in range(columns.shape[1]):
        for c in range(3):  # column c of m replaced by the right-hand side, expanded along that column
            out[c, j] = (
                columns[0, j] * cofactor[0, c] + columns[1, j] * cofactor[1, c] + columns[2, j] * cofactor[2, c]
            ) / det
    return out.reshape(rhs.shape)


@njit(cache=True, fastmath=FUSED_MULTIPLY_ADD)
def kkt_solve(lower, diag, negative, jac_t, grad, constraint):
    """Newton step of the bordered system  [[H, J^T], [J, 0]] [p; -mu] = [-grad; -constraint].

    lower, diag, negative: LDL^T factor of H and its negative eigenvalues (ldlt_banded).
    jac_t: (n, 3) = J^T.  grad: (n,).  constraint: (3,).
    Returns (step, mu, unstable_directions) where mu solves H p - J^T mu = -grad, J p = -constraint,
    and unstable_directions is the number of negative eigenvalues of H on the tangent space
    of the constraint.

    With Y = L^-1 [J^T, grad] (one forward sweep, four columns), the Schur complement
    S = J H^-1 J^T = Y_J^T D^-1 Y_J and J H^-1 grad = Y_J^T D^-1 y_g need no backward sweep;
    only the step itself, H^-1 (J^T mu - grad) = L^-T D^-1 (Y_J mu - y_g), does.
    """
    n, width = lower.shape
    p = width - 1
    forward = np.empty((n, 4))
    s00 = s01 = s02 = s11 = s12 = s22 = 0.0
    r0 = r1 = r2 = 0.0
    for i in range(n):
        y0, y1, y2, y3 = jac_t[i, 0], jac_t[i, 1], jac_t[i, 2], grad[i]
        for k in range(min(p, i), 0, -1):  # the row just solved last: shorter chain of dependent operations
            factor = lower[i, k]
            y0 -= factor * forward[i - k, 0]
            y1 -= factor * forward[i - k, 1]
            y2 -= factor * forward[i - k, 2]
            y3 -= factor * forward[i - k, 3]
        forward[i, 0], forward[i, 1], forward[i, 2], forward[i, 3] = y0, y1, y2, y3
        # S and J H^-1 grad, row by row while the row is at hand
        inv = 1.0 / diag[i]
        w0, w1, w2 = y0 * inv, y1 * inv, y2 * inv
        s00 += w0 * y0
        s01 += w0 * y1
        s02 += w0 * y2
        s11 += w1 * y1
        s12 += w1 * y2
        s22 += w2 * y2
        r0 += w0 * y3
        r1 += w1 * y3
        r2 += w2 * y3
    schur = np.array([[s00, s01, s02], [s01, s11, s12], [s02, s12, s22]])
    rhs = np.array([r0 - constraint[0], r1 - constraint[1], r2 - constraint[2]])
    mu = solve_3x3(schur, rhs)
    step = np.empty(n)
    for i in range(n - 1, -1, -1):
        value = (forward[i, 0] * mu[0] + forward[i, 1] * mu[1] + forward[i, 2] * mu[2] - forward[i, 3]) / diag[i]
        for k in range(min(p, n - 1 - i), 0, -1):
            value -= lower[i + k, k] * step[i + k]
        step[i] = value
    unstable = negative + symmetric_3x3_positive_count(schur) - 3
    return step, mu, unstable


@njit(cache=True)
def banded_matvec(band, x):
    """y = H x for symmetric H in lower band storage; x of shape (n,) or (n, m)."""
    n, width = band.shape
    p = width - 1
    columns = np.ascontiguousarray(x).reshape(n, -1)
    out = np.empty_like(columns)
    for i in range(n):
        for j in range(columns.shape[1]):
            # row i of H: band[i, k] left of the diagonal, band[i + k, k] right of it
            value = band[i, 0] * columns[i, j]
            for k in range(1, min(p, i) + 1):
                value += band[i, k] * columns[i - k, j]
            for k in range(1, min(p, n - 1 - i) + 1):
                value += band[i + k, k] * columns[i + k, j]
            out[i, j] = value
    return out.reshape(x.shape)


def band_to_dense(band: np.ndarray) -> np.ndarray:
    """The full symmetric matrix (n, n) of a lower band (n, width), row k of the band holding the
    diagonals below it (for checks and small dense solves; the solver itself never forms it)."""
    n, width = band.shape
    dense = np.zeros((n, n))
    for k in range(width):
        idx = np.arange(k, n)
        dense[idx, idx - k] = band[k:, k]
        dense[idx - k, idx] = band[k:, k]
    return dense
