"""The contact Newton step without a dense matrix: the banded rod plus a low-rank station term (compiled).

A station energy (contact.py) couples every segment before a station it touches (x_k = x_0 +
h sum_{i<k} d3_i), but only through the stations: its Hessian in the rotations is
    H = B + J_A^T H_AA J_A,
B banded (the rod's Hessian and the segment-load blocks of the second-order turn of the tangents,
contact.py), J_A (3a x n) the Jacobian of the a active stations (those of a pair below d_hat;
J_k has the blocks -h [t_i]x for i < k) and H_AA their station Hessian.  H_AA is block diagonal
over the groups of stations that pairs join (a floor: one station each; a wrap: a run of
stations; self-contact joins far ones), so its eigen-decomposition is per group:
H_AA = sum_e lambda_e v_e v_e^T.  With the columns u_e = sqrt|lambda_e| J_A^T v_e (U, n x r) and
sigma_e = sign lambda_e (zero eigenvalues dropped), H = B + U diag(sigma) U^T.

The KKT system [[H, Jc^T], [Jc, 0]] [p; -mu] = [-g; -c] is the Schur complement, on the z block,
of the bordered system
    M = [[B, W], [W^T, E]],  W = [Jc^T, U],  E = diag(0_m, -sigma)
(the extra unknowns z = sigma U^T p), which bordered.py's method solves: B = L D L^T (banded,
no pivoting), Y = L^-1 W, the (m + r) square Schur complement S = E - W^T B^-1 W (factored by
LAPACK's sytrf), one backward sweep for p: O(N (m + r)^2).  Inertia (Sylvester / Haynsworth):
In(M) = In(B) + In(S), and eliminating the z block first, In(M) = In(-diag sigma) + In(KKT); so
neg(KKT) = neg(D) + neg(S) - pos(sigma), and the unstable directions on the constraint tangent
space are neg(KKT) - m, as before.  Eliminating a border much stiffer than B (the barrier's
curvature, pressure / gap) loses digits to cancellation (a backward error of 1e-8 for the hose
at rest on a floor); one step of iterative refinement with the same factors restores 1e-15.

B alone may be singular or badly indefinite where H is fine (a hose pulled taut over a drum, held
by the contacts): the factor then has a tiny pivot, S is singular or the solve keeps a large
backward error, and the caller falls back to the dense solve (dense_step: LAPACK's symmetric
indefinite sytrf of the whole KKT matrix), counted in kkt_solves.

Written by hand (Numba): LAPACK has no banded LDL^T with inertia (banded.py), nor a bordered
solve with an indefinite low-rank border.
"""

from __future__ import annotations

from collections import Counter

import numpy as np
import scipy.linalg.lapack as lapack
from numba import njit

from hoseline.mechanics.banded import banded_matvec, count_negative, ldlt_banded
from hoseline.mechanics.contact import SEGMENT_SEGMENT, STATION_PLANE, STATION_TRIANGLE

DROPPED = 1e-13  # eigenvalues of a group's station Hessian below this fraction of its largest are rounding
BACKWARD_ERROR = 1e-9  # a banded solve with a larger relative residual is redone dense
ACCURATE = 1e-13  # a banded solve with a smaller relative residual needs no step of iterative refinement

kkt_solves = Counter()  # "banded" and "dense" (fall-backs) solves of this process, for the benchmarks


@njit(cache=True)
def _root(parent, k):
    while parent[k] != k:
        parent[k] = parent[parent[k]]
        k = parent[k]
    return k


@njit(cache=True)
def station_groups(kinds, first, second, stations):
    """Group label of each station (stations,) joined by the pairs (-1: in no pair, or station 0, which is held)."""
    parent = np.arange(stations)
    active = np.zeros(stations, np.bool_)
    members = np.empty(4, np.int64)
    for p in range(kinds.shape[0]):
        if kinds[p] == STATION_PLANE or kinds[p] == STATION_TRIANGLE:
            members[0] = first[p]
            count = 1
        else:
            members[0], members[1] = first[p], first[p] + 1
            count = 2
            if kinds[p] == SEGMENT_SEGMENT:
                members[2], members[3] = second[p], second[p] + 1
                count = 4
        for a in range(count):
            active[members[a]] = True
            ra, r0 = _root(parent, members[a]), _root(parent, members[0])
            parent[ra] = r0
    label = -np.ones(stations, np.int64)
    groups = 0
    for k in range(1, stations):
        if active[k] and label[_root(parent, k)] < 0:
            label[_root(parent, k)] = groups
            groups += 1
    out = -np.ones(stations, np.int64)
    for k in range(1, stations):
        if active[k]:
            out[k] = label[_root(parent, k)]
    return out, groups


@njit(cache=True)
def rotation_gradient_and_band(frames, h, node_grad, index, band):
    """Add a station energy's gradient in the rotations and its segment-load blocks to the banded Hessian.

    frames (N, 3, 3); h: segment length, mm; node_grad (N+1, 3), N per station; index (N,): first
    rotation unknown of each segment; band: lower band storage (modified in place).  Returns the
    gradient (n,) of the station energy: h d3_i x G_i with G_i the summed station gradients beyond
    segment i (the same chain rule as contact.rotation_terms, without its dense station Hessian).
    """
    n_seg = frames.shape[0]
    grad = np.zeros(band.shape[0])
    beyond = np.zeros(3)
    for i in range(n_seg - 1, -1, -1):
        beyond += node_grad[i + 1]
        t = frames[i, 2]
        r = index[i]
        grad[r] = h * (t[1] * beyond[2] - t[2] * beyond[1])
        grad[r + 1] = h * (t[2] * beyond[0] - t[0] * beyond[2])
        grad[r + 2] = h * (t[0] * beyond[1] - t[1] * beyond[0])
        along = beyond[0] * t[0] + beyond[1] * t[1] + beyond[2] * t[2]
        for x in range(3):
            for y in range(x + 1):
                band[r + x, x - y] += h * (0.5 * (beyond[x] * t[y] + t[x] * beyond[y]) - (along if x == y else 0.0))
    return grad


@njit(cache=True)
def low_rank_columns(frames, h, node_hess, kinds, first, second, index, unknowns):
    """U (unknowns, r) and sigma (r,) with J_A^T H_AA J_A = U diag(sigma) U^T (see the module doc).

    node_hess (N+1, N+1, 3, 3): station Hessian of the pairs (contact.node_terms); kinds, first,
    second: the pairs; index (N,): first rotation unknown of each segment.
    """
    n_seg = frames.shape[0]
    label, groups = station_groups(kinds, first, second, n_seg + 1)
    # the eigen-decomposition of each group's block first, then the columns at their exact count
    sizes = np.zeros(groups, np.int64)
    for k in range(n_seg + 1):
        if label[k] >= 0:
            sizes[label[k]] += 1
    offsets = np.zeros(groups + 1, np.int64)  # of each group's eigenvectors in all_vectors
    starts = np.zeros(groups + 1, np.int64)  # of each group's stations in order
    for g in range(groups):
        offsets[g + 1] = offsets[g] + 9 * sizes[g] * sizes[g]
        starts[g + 1] = starts[g] + sizes[g]
    order = np.empty(starts[groups], np.int64)  # the active stations group by group, ascending in each
    filled = starts[:groups].copy()
    for k in range(n_seg + 1):
        if label[k] >= 0:
            order[filled[label[k]]] = k
            filled[label[k]] += 1
    all_vectors = np.empty(offsets[groups])
    all_values = np.empty(3 * np.sum(sizes))
    kept = np.zeros(3 * np.sum(sizes), np.bool_)
    rank = 0
    value_start = 0
    for g in range(groups):
        members = order[starts[g]:starts[g + 1]]
        size = members.shape[0]
        block = np.empty((3 * size, 3 * size))
        for a in range(size):
            for b in range(size):
                for x in range(3):
                    for y in range(3):
                        block[3 * a + x, 3 * b + y] = 0.5 * (node_hess[members[a], members[b], x, y]
                                                             + node_hess[members[b], members[a], y, x])
        values, vectors = np.linalg.eigh(block)
        largest = max(abs(values[0]), abs(values[-1]))
        all_vectors[offsets[g]:offsets[g + 1]] = vectors.ravel()
        for e in range(3 * size):
            all_values[value_start + e] = values[e]
            if abs(values[e]) > DROPPED * largest:
                kept[value_start + e] = True
                rank += 1
        value_start += 3 * size
    columns = np.zeros((unknowns, rank))
    signs = np.empty(rank)
    column = 0
    value_start = 0
    for g in range(groups):
        members = order[starts[g]:starts[g + 1]]
        size = members.shape[0]
        vectors = all_vectors[offsets[g]:offsets[g + 1]].reshape(3 * size, 3 * size)
        for e in range(3 * size):
            if not kept[value_start + e]:
                continue
            scale = h * np.sqrt(abs(all_values[value_start + e]))
            beyond = np.zeros(3)  # sum of v_k over the group's stations k > i
            top = size - 1
            for i in range(members[size - 1] - 1, -1, -1):
                if top >= 0 and members[top] == i + 1:
                    for x in range(3):
                        beyond[x] += vectors[3 * top + x, e]
                    top -= 1
                t = frames[i, 2]
                r = index[i]
                columns[r, column] = scale * (t[1] * beyond[2] - t[2] * beyond[1])
                columns[r + 1, column] = scale * (t[2] * beyond[0] - t[0] * beyond[2])
                columns[r + 2, column] = scale * (t[0] * beyond[1] - t[1] * beyond[0])
            signs[column] = 1.0 if all_values[value_start + e] > 0.0 else -1.0
            column += 1
        value_start += 3 * size
    return columns, signs


@njit(cache=True)
def _forward(lower, vector):
    # L^-1 vector for the unit lower banded factor
    n, width = lower.shape
    out = np.empty(n)
    for i in range(n):
        value = vector[i]
        for k in range(min(width - 1, i), 0, -1):
            value -= lower[i, k] * out[i - k]
        out[i] = value
    return out


@njit(cache=True)
def schur_complement(lower, diag, jac_t, columns, signs):
    """Y = L^-1 W (n, q) and S = E - W^T B^-1 W (q, q) for the border W = [Jc^T, U], E = diag(0_m, -sigma).

    lower, diag: the LDL^T factor of B (banded.ldlt_banded); jac_t (n, m) = Jc^T; columns (n, r) = U;
    signs (r,) = sigma.
    """
    n, width = lower.shape
    m = jac_t.shape[1]
    q = m + columns.shape[1]
    forward = np.empty((n, q))
    scaled = np.empty((q, n))  # (D^-1 Y)^T, for the product below
    for i in range(n):
        row = forward[i]
        for c in range(m):
            row[c] = jac_t[i, c]
        for c in range(m, q):
            row[c] = columns[i, c - m]
        for k in range(min(width - 1, i), 0, -1):  # row by row: contiguous, vectorised
            factor = lower[i, k]
            if factor != 0.0:
                for c in range(q):
                    row[c] -= factor * forward[i - k, c]
        inv = 1.0 / diag[i]
        for c in range(q):
            scaled[c, i] = row[c] * inv
    schur = -(scaled @ forward)  # E - W^T B^-1 W = E - Y^T D^-1 Y (BLAS)
    for a in range(m, q):
        schur[a, a] -= signs[a - m]
    return forward, schur


@njit(cache=True)
def border_rhs(lower, diag, forward, first_rows, last_rows):
    """y = L^-1 first_rows and the right-hand side last - W^T B^-1 first (q,) of the Schur complement system.

    [[B, W], [W^T, E]] [p; nu] = [first_rows; last_rows; 0]: nu solves S nu = that, then p = border_step.
    """
    y = _forward(lower, first_rows)
    rhs = -(forward.T @ (y / diag))
    for a in range(last_rows.shape[0]):
        rhs[a] += last_rows[a]
    return y, rhs


@njit(cache=True)
def border_step(lower, diag, forward, y, nu):
    """p = B^-1 (first_rows - W nu) = L^-T D^-1 (y - Y nu) (one backward sweep)."""
    n, width = lower.shape
    right = (y - forward @ nu) / diag
    step = np.empty(n)
    for i in range(n - 1, -1, -1):
        value = right[i]
        for k in range(min(width - 1, n - 1 - i), 0, -1):
            value -= lower[i + k, k] * step[i + k]
        step[i] = value
    return step


@njit(cache=True)
def kkt_residual(band, columns, signs, jac_t, grad, constraint, step, mu):
    """Residuals of [[H, Jc^T], [Jc, 0]] [p; -mu] = [-grad; -constraint] (H = B + U diag(sigma) U^T) and the
    relative backward error: each block row's residual over the size of its terms (|H| |p| + |Jc^T| |mu| + |grad|,
    |Jc| |p| + |constraint|): a few eps for an accurate solve."""
    n, r, m = step.shape[0], columns.shape[1], jac_t.shape[1]
    product = banded_matvec(band, step)
    size = banded_matvec(np.abs(band), np.abs(step))
    along = np.zeros(r)  # U^T p and |U|^T |p|
    along_size = np.zeros(r)
    for i in range(n):
        for e in range(r):
            along[e] += columns[i, e] * step[i]
            along_size[e] += abs(columns[i, e] * step[i])
    first_rows = np.empty(n)
    for i in range(n):
        value, bound = product[i], size[i] + abs(grad[i])
        for e in range(r):
            value += columns[i, e] * signs[e] * along[e]
            bound += abs(columns[i, e]) * along_size[e]
        for a in range(m):
            value -= jac_t[i, a] * mu[a]
            bound += abs(jac_t[i, a] * mu[a])
        first_rows[i] = -grad[i] - value
        size[i] = bound
    last_rows = np.empty(m)
    last_size = np.empty(m)
    for a in range(m):
        value, bound = constraint[a], abs(constraint[a])
        for i in range(n):
            value += jac_t[i, a] * step[i]
            bound += abs(jac_t[i, a] * step[i])
        last_rows[a], last_size[a] = -value, bound
    error = max(np.max(np.abs(first_rows)) / max(np.max(size), 1e-300),
                np.max(np.abs(last_rows)) / max(np.max(last_size), 1e-300))
    return first_rows, last_rows, error


def banded_step(band, jac_t, columns, signs, grad, constraint):
    """(step, mu, unstable directions, pivots) of [[B + U diag(sigma) U^T, Jc^T], [Jc, 0]] [p; -mu] = [-grad;
    -constraint].  pivots: (B's diagonal, S's sytrf factor and pivot indices), whose log_abs_det is the KKT matrix's:
    det M = det B det S = det(-diag sigma) det KKT, |sigma_e| = 1 (worked out only where asked: at a converged state).

    band: B in lower band storage; jac_t (n, m) = Jc^T; columns (n, r) = U; signs (r,) = sigma.  None when the
    banded factor is not to be trusted: a tiny pivot of B, a singular Schur complement, a backward error above
    BACKWARD_ERROR after one step of iterative refinement (eliminating a border much stiffer than B, the
    barrier's curvature, loses digits to cancellation, which refinement with the same factors recovers;
    a first solve already within ACCURATE, a few hundred eps, is kept as it is).
    The Schur complement (m + r square) is factored by LAPACK's sytrf, which gives its inertia.
    """
    lower, diag, negative, tiny = ldlt_banded(band, 0.0)
    if tiny:
        return None
    forward, schur = schur_complement(lower, diag, jac_t, columns, signs)
    factor, pivots, info = lapack.dsytrf(schur, lower=1)
    if info != 0:
        return None

    def solve(first_rows, last_rows):
        y, rhs = border_rhs(lower, diag, forward, first_rows, last_rows)
        nu = lapack.dsytrs(factor, pivots, rhs, lower=1)[0]
        return border_step(lower, diag, forward, y, nu), nu

    m = jac_t.shape[1]
    step, nu = solve(-grad, -constraint)
    first_rows, last_rows, error = kkt_residual(band, columns, signs, jac_t, grad, constraint, step, -nu[:m])
    if error > ACCURATE:
        correction, nu_correction = solve(first_rows, last_rows)
        step, nu = step + correction, nu + nu_correction
        error = kkt_residual(band, columns, signs, jac_t, grad, constraint, step, -nu[:m])[2]
    mu = -nu[:m]
    if not (error <= BACKWARD_ERROR and np.all(np.isfinite(step)) and np.all(np.isfinite(mu))):
        return None
    unstable = negative + negative_pivots(factor, pivots) - int(np.sum(signs > 0.0)) - m
    if unstable < 0:  # an impossible inertia: a nearly singular B or S miscounted by rounding; the dense solve decides
        return None
    return step, mu, int(unstable), (diag, factor, pivots)


def dense_step(hess, jac_t, grad, constraint):
    """(step, mu, unstable directions, pivots) of the dense KKT system by LAPACK's sytrf (the reference and the
    fall-back); pivots as banded_step's (no banded part).

    The inertia of the KKT matrix is that of its D (1x1 and 2x2 blocks, Sylvester's law); the
    unstable directions on the constraint tangent space are neg(KKT) - m.  NaN, -1 and None when the
    solve fails.
    """
    n, m = jac_t.shape
    kkt = np.zeros((n + m, n + m))
    kkt[:n, :n] = hess
    kkt[:n, n:] = jac_t
    kkt[n:, :n] = jac_t.T
    factor, pivots, info = lapack.dsytrf(kkt, lower=1)
    if info < 0:
        raise ValueError(f"LAPACK dsytrf: argument {-info} is invalid")
    solution, info = lapack.dsytrs(factor, pivots, np.concatenate([-grad, -constraint]), lower=1)
    if info != 0 or not np.all(np.isfinite(solution)):
        return np.full(n, np.nan), np.full(m, np.nan), -1, None
    return solution[:n], -solution[n:], negative_pivots(factor, pivots) - m, (np.ones(0), factor, pivots)


def log_abs_det(banded_diagonal, factor, pivots):
    """log |det| of the KKT matrix from the pivots of its solve (banded_step's or dense_step's): the banded part's
    diagonal, and D of a sytrf factor (lower): its 1x1 blocks (a positive pivot index) and 2x2 blocks (a pair of equal
    negative indices, a c - b^2)."""
    diagonal = np.diagonal(factor)
    total = float(np.sum(np.log(np.abs(banded_diagonal))))
    if pivots.min() > 0:
        return total + float(np.sum(np.log(np.abs(diagonal))))
    pairs = np.flatnonzero(pivots < 0)[0::2]  # the first row of each 2x2 block
    blocks = diagonal[pairs] * diagonal[pairs + 1] - factor[pairs + 1, pairs] ** 2
    return total + float(np.sum(np.log(np.abs(diagonal[pivots > 0]))) + np.sum(np.log(np.abs(blocks))))


@njit(cache=True)
def negative_pivots(factor, pivots):
    """Negative eigenvalues of a matrix factored by sytrf (lower): those of D's 1x1 and 2x2 blocks (Sylvester's law)."""
    size = factor.shape[0]
    values = np.empty(size)
    k = 0
    while k < size:
        if pivots[k] > 0:
            values[k] = factor[k, k]
            k += 1
        else:
            a, b, c = factor[k, k], factor[k + 1, k], factor[k + 1, k + 1]
            middle, radius = 0.5 * (a + c), np.sqrt(0.25 * (a - c) ** 2 + b * b)
            values[k], values[k + 1] = middle - radius, middle + radius
            k += 2
    return count_negative(values)
