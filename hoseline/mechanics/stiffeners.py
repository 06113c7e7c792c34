"""Off-axis spring stiffeners between adjacent segments: energy, exact gradient and Hessian blocks.

A spring j of a joint is anchored at a_j in the frame A of the segment before the node
and at b_j in the frame B of the segment after it, both relative to the shared node
(body coordinates, rows of the frames are the directors).  Its world vector is

    v = u_B - u_A,   u_A = A^T a_j,   u_B = B^T b_j,

which depends on the two frames only (the node cancels), so the springs fit the joint
structure of energy.py: same unknowns, same Hessian blocks, and since |v| = |Q b - a| with
Q = A B^T, the energy depends on the relative rotation only (grad_b = -grad_a, H_bb = H_aa).

Energy.  With L = |v| and the free length L0 = |b_j - a_j|, a joint spanning a length l of
hose (l = h inside, h/2 at a fitting) counts the deformation as that of a spring spanning a
whole segment, x = (L - L0) h / l, and stores (l / h) W(x), W(x) = int_0^x F; F is the
force table, piecewise linear with linear extrapolation.  So dE/dL = F(x) (the spring
force) and d2E/dL2 = F'(x) h / l.

Derivatives, with the perturbation d -> d + delta x d + 1/2 delta x (delta x d) of energy.py:
    dv = delta_B x u_B - delta_A x u_A + 1/2 [delta_B x (delta_B x u_B) - delta_A x (delta_A x u_A)],
n = v / L, J_A = [u_A]x, J_B = -[u_B]x (so the first-order dv = J_A delta_A + J_B delta_B), and
K = (F / L) (I - n n^T) + F' (h / l) n n^T:
    grad_A = J_A^T n F = -F (u_A x n)
    H_AB = J_A^T K J_B = [u_A]x K [u_B]x
    H_AA = J_A^T K J_A - F (sym(n u_A^T) - (n.u_A) I)
Verified against finite differences in tests/test_stiffeners.py.

Kernel data (see spring_set): a tuple (anchors, rest, table_x, table_f, table_w, span_ratio)
with anchors (2, m, 2, 3) for the two joint kinds FULL (l = h) and HALF (l = h/2).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# np.int64, not int: Numba compiles a kernel again for every int constant passed to it (a Literal[int] type each);
# an np.int64 is a plain int64, so every call site shares one compiled version
FULL, HALF = np.int64(0), np.int64(1)  # joint kinds: between two segments, between a segment and a fitting


def spring_set(anchors_full: np.ndarray, anchors_half: np.ndarray, deformation, force) -> tuple:
    """Pack springs for the kernels.

    anchors_full, anchors_half: (m, 2, 3) anchor points (mm) of the joints between two
    segments and between a segment and a fitting (see Stiffeners.anchors).
    deformation (mm), force (N): the force table, deformation strictly increasing.
    Returns the tuple the kernels take (stored energy at the breakpoints included).
    """
    anchors = np.ascontiguousarray(np.stack([anchors_full, anchors_half]), dtype=float)
    rest = np.linalg.norm(anchors[:, :, 1] - anchors[:, :, 0], axis=2)
    x = np.asarray(deformation, dtype=float)
    f = np.asarray(force, dtype=float)
    stored = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(x))])
    stored -= _table_energy(0.0, x, f, stored)  # W(0) = 0: the free spring stores nothing
    span_ratio = np.array([1.0, 2.0])  # h / l for FULL and HALF joints
    return anchors, rest, x, f, stored, span_ratio


@njit(cache=True)
def _table_segment(x, table_x):
    """Index i of the table interval [x_i, x_i+1] used at x (the end intervals extend outwards)."""
    n = table_x.shape[0]
    i = 0
    while i < n - 2 and x > table_x[i + 1]:
        i += 1
    return i


@njit(cache=True)
def _table_energy(x, table_x, table_f, table_w):
    """W(x) = W(x_i) + F(x_i)(x - x_i) + 1/2 slope (x - x_i)^2 on the interval of x."""
    i = _table_segment(x, table_x)
    slope = (table_f[i + 1] - table_f[i]) / (table_x[i + 1] - table_x[i])
    dx = x - table_x[i]
    return table_w[i] + table_f[i] * dx + 0.5 * slope * dx * dx


@njit(cache=True)
def _table_force(x, table_x, table_f):
    """F(x) and F'(x) of the piecewise-linear table with linear extrapolation."""
    i = _table_segment(x, table_x)
    slope = (table_f[i + 1] - table_f[i]) / (table_x[i + 1] - table_x[i])
    return table_f[i] + slope * (x - table_x[i]), slope


@njit(cache=True)
def _world(frame, point, out):
    # out = frame^T point: body coordinates to world components
    for x in range(3):
        out[x] = frame[0, x] * point[0] + frame[1, x] * point[1] + frame[2, x] * point[2]


@njit(cache=True)
def _skew_sandwich(u, k, w, out, sign, m):
    # out += sign * [u]x K [w]x, with [u]x y = u x y; m: 3x3 work array for K [w]x
    for r in range(3):
        m[r, 0] = k[r, 1] * w[2] - k[r, 2] * w[1]
        m[r, 1] = k[r, 2] * w[0] - k[r, 0] * w[2]
        m[r, 2] = k[r, 0] * w[1] - k[r, 1] * w[0]
    for c in range(3):
        out[0, c] += sign * (u[1] * m[2, c] - u[2] * m[1, c])
        out[1, c] += sign * (u[2] * m[0, c] - u[0] * m[2, c])
        out[2, c] += sign * (u[0] * m[1, c] - u[1] * m[0, c])


@njit(cache=True)
def spring_terms_into(frame_a, frame_b, springs, kind, grad_a, hess_aa, hess_ab):
    """Add the springs of one joint to grad_a, hess_aa, hess_ab (as joint_terms_into defines them).

    frame_a, frame_b: 3x3 frames.  springs: the tuple of spring_set.  kind: FULL or HALF.
    Returns the spring energy, N*mm.
    """
    anchors, rest, table_x, table_f, table_w, span_ratio = springs
    ratio = span_ratio[kind]
    u_a = np.empty(3)
    u_b = np.empty(3)
    n = np.empty(3)
    k = np.empty((3, 3))
    work = np.empty((3, 3))
    energy = 0.0
    for j in range(anchors.shape[1]):
        _world(frame_a, anchors[kind, j, 0], u_a)
        _world(frame_b, anchors[kind, j, 1], u_b)
        length = 0.0
        for x in range(3):
            n[x] = u_b[x] - u_a[x]
            length += n[x] * n[x]
        length = math.sqrt(length)
        for x in range(3):
            n[x] /= length
        deformation = (length - rest[kind, j]) * ratio
        energy += _table_energy(deformation, table_x, table_f, table_w) / ratio
        force, stiffness = _table_force(deformation, table_x, table_f)
        stiffness *= ratio
        # grad_a = -F (u_a x n)
        grad_a[0] -= force * (u_a[1] * n[2] - u_a[2] * n[1])
        grad_a[1] -= force * (u_a[2] * n[0] - u_a[0] * n[2])
        grad_a[2] -= force * (u_a[0] * n[1] - u_a[1] * n[0])
        for r in range(3):
            for c in range(3):
                k[r, c] = (stiffness - force / length) * n[r] * n[c]
            k[r, r] += force / length
        _skew_sandwich(u_a, k, u_b, hess_ab, 1.0, work)
        _skew_sandwich(u_a, k, u_a, hess_aa, -1.0, work)
        nu = n[0] * u_a[0] + n[1] * u_a[1] + n[2] * u_a[2]
        for r in range(3):
            for c in range(3):
                hess_aa[r, c] -= 0.5 * force * (n[r] * u_a[c] + u_a[r] * n[c])
            hess_aa[r, r] += force * nu
    return energy


@njit(cache=True)
def spring_energy(frame_a, frame_b, springs, kind):
    """Energy of the springs of one joint only (N*mm); see spring_terms_into."""
    anchors, rest, table_x, table_f, table_w, span_ratio = springs
    ratio = span_ratio[kind]
    u_a = np.empty(3)
    u_b = np.empty(3)
    energy = 0.0
    for j in range(anchors.shape[1]):
        _world(frame_a, anchors[kind, j, 0], u_a)
        _world(frame_b, anchors[kind, j, 1], u_b)
        length = math.sqrt((u_b[0] - u_a[0]) ** 2 + (u_b[1] - u_a[1]) ** 2 + (u_b[2] - u_a[2]) ** 2)
        energy += _table_energy((length - rest[kind, j]) * ratio, table_x, table_f, table_w) / ratio
    return energy


def scaled_springs(springs: tuple, factor: float) -> tuple:
    """The same springs with every force (and so every stored energy) multiplied by `factor`."""
    anchors, rest, table_x, table_f, table_w, span_ratio = springs
    return anchors, rest, table_x, factor * table_f, factor * table_w, span_ratio
