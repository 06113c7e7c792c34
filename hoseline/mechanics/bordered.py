"""The bordered (KKT) solve of banded.py for any number m of constraint rows (compiled).

For the rod with clips (mechanics/clipped.py) the border has m = 3 + 3c rows: the end position
and each clip's position.  Same method as banded.kkt_solve: with Y = L^-1 [J^T, grad] (one
forward sweep), S = J H^-1 J^T = Y_J^T D^-1 Y_J (m x m, dense), J H^-1 grad = Y_J^T D^-1 y_g,
and one backward sweep for the step.  The number of negative eigenvalues of H on the tangent
space {J v = 0} is neg(H) + pos(S) - r (Haynsworth / Gould), r the number of independent rows
(tangent_space_inertia).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hoseline.mechanics.banded import NEUTRAL


@njit(cache=True)
def positive_count(symmetric):
    """How many eigenvalues of a small symmetric matrix are clearly positive (above NEUTRAL x the largest)."""
    values = np.linalg.eigvalsh(symmetric)
    largest = max(abs(values[0]), abs(values[-1]))
    count = 0
    for v in values:
        if v > NEUTRAL * largest:
            count += 1
    return count


@njit(cache=True)
def tangent_space_inertia(schur, jac_t):
    """(pos, r): the positive eigenvalues of S = B^T H^-1 B - C on the border's independent rows, and
    how many independent rows there are, so that H has neg(H) + pos - r negative eigenvalues on the
    tangent space {J v = 0}.

    schur: S, (m, m) mm/N, or (m + s, m + s) when s unknowns that are not in the band were eliminated
    after the m constraint rows (the sliding clips' arc lengths, clipped_newton._step).  jac_t: (n, m)
    = J^T, mm/rad, the constraint rows over every unknown (with the s extra ones: (n + s, m)).
    Independent rows: the border's Gram matrix J J^T = U diag(g) U^T; a row combination with g
    below NEUTRAL x the largest (|J^T y| below 1e-5 of the longest) is a dependent constraint (a
    span between held stations pulled straight: the row along it vanishes) and is dropped, so the
    count is on the tangent space of the r independent constraints.  On those rows, in the basis
    W = U_r diag(g_r)^-1/2 in which they are orthonormal, W^T S W has the inertia of S (Sylvester;
    the extra unknowns keep their own basis) but eigenvalues that no longer scale with the lengths
    of the row combinations: one near zero there is a neutral direction of H, not a short
    combination of rows (a nearly straight span).
    """
    m, total = jac_t.shape[1], schur.shape[0]
    gram_values, gram_vectors = np.linalg.eigh(jac_t.T @ jac_t)  # ascending
    dependent = 0
    while dependent < m and gram_values[dependent] <= NEUTRAL * gram_values[m - 1]:
        dependent += 1
    basis = np.zeros((total, total - dependent))
    for column in range(m - dependent):  # a loop: Numba's broadcasting slice assignment compiles for 1.2 s
        length = np.sqrt(gram_values[dependent + column])
        for row in range(m):
            basis[row, column] = gram_vectors[row, dependent + column] / length
    for extra in range(total - m):
        basis[m + extra, m - dependent + extra] = 1.0
    return positive_count(basis.T @ schur @ basis), m - dependent


@njit(cache=True)
def kkt_solve_bordered(lower, diag, negative, jac_t, grad, constraint):
    """Newton step of [[H, J^T], [J, 0]] [p; -mu] = [-grad; -constraint] for a border of m rows.

    lower, diag, negative: LDL^T factor of H and its negative eigenvalues (banded.ldlt_banded).
    jac_t: (n, m) = J^T.  grad: (n,).
    constraint: (m,).  Returns (step (n,), mu (m,), unstable directions on the tangent space).
    """
    n, width = lower.shape
    p = width - 1
    m = jac_t.shape[1]
    forward = np.empty((n, m + 1))
    for i in range(n):
        for c in range(m + 1):
            value = jac_t[i, c] if c < m else grad[i]
            for k in range(min(p, i), 0, -1):
                value -= lower[i, k] * forward[i - k, c]
            forward[i, c] = value
    schur = np.zeros((m, m))
    rhs = np.zeros(m)
    for i in range(n):
        inv = 1.0 / diag[i]
        for a in range(m):
            scaled = forward[i, a] * inv
            rhs[a] += scaled * forward[i, m]
            for b in range(a + 1):
                schur[a, b] += scaled * forward[i, b]
    for a in range(m):
        rhs[a] -= constraint[a]
        for b in range(a):
            schur[b, a] = schur[a, b]
    mu = np.linalg.solve(schur, rhs)
    step = np.empty(n)
    for i in range(n - 1, -1, -1):
        value = -forward[i, m]
        for a in range(m):
            value += forward[i, a] * mu[a]
        value /= diag[i]
        for k in range(min(p, n - 1 - i), 0, -1):
            value -= lower[i + k, k] * step[i + k]
        step[i] = value
    positive, independent = tangent_space_inertia(schur, jac_t)
    unstable = negative + positive - independent
    return step, mu, unstable
