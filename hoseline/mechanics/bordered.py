"""The bordered (KKT) solve of banded.py for any number m of constraint rows (compiled).

For the rod with clips (mechanics/clipped.py) the border has m = 3 + 3c rows: the end position
and each clip's position.  Same method as banded.kkt_solve: with Y = L^-1 [J^T, grad] (one
forward sweep), S = J H^-1 J^T = Y_J^T D^-1 Y_J (m x m, dense), J H^-1 grad = Y_J^T D^-1 y_g,
and one backward sweep for the step.  The number of negative eigenvalues of H on the tangent
space {J v = 0} is neg(H) + pos(S) - m (Haynsworth / Gould), neg(H) counted by banded.ldlt_banded.
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
    unstable = negative + positive_count(schur) - m
    return step, mu, unstable
