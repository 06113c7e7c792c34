"""Potential energy of the discrete Kirchhoff rod, with its exact gradient and Hessian.

The rod (see docs/model.md) is N rigid segments of length h = L/N, each with a
material frame (rows d1, d2, d3; d3 the tangent).  Centreline nodes follow from the
frames, x_{i+1} = x_i + h d3_i, so the hose is exactly inextensible and unshearable.
Neighbouring frames are joined by elastic joints at the nodes; the first and last
joints tie segment 0 to the start fitting's frame and segment N-1 to the end fitting's
frame over half a segment (h/2), which keeps the clamps second-order accurate.

Joint energy.  For frames A and B let Q = A B^T (Q_kl = d_k^A . d_l^B) be the relative
rotation by angle phi about the axis e (same components in both frames).  The
discrete Darboux vector is  kappa = 2 tan(phi/2) e / l = 2 a / (c l)  with
a = axial(Q - Q^T) = 2 sin(phi) e,  c = 1 + tr Q = 4 cos^2(phi/2),  and
    E_joint = (l / 2) sum_k K_k kappa_k^2 = (2 / l) sum_k K_k a_k^2 / c^2,
K = (EI1, EI2, GJ).  2 tan(phi/2) = phi + O(phi^3), so E = K phi^2 / (2 l) to second
order, and the energy grows without bound as a joint approaches a full reversal, so
there is no spurious zero-energy state at large twist.

Segment terms.  Gravity and the end-position constraint (Lagrange multiplier mu, the
force of the end mount on the hose) are both linear in the tangents:
    E_segment_i = - w_i . d3_i,   w_i = h (mu + weight of the hose beyond segment i's centre),
so w_i / h is the internal force at the segment's centre.

Derivatives.  Every frame is perturbed by a small world rotation delta_i:
d -> exp(delta^) d = d + delta x d + 1/2 delta x (delta x d) + ...  The gradient and
Hessian below are those of E(delta) at delta = 0 (exact, no approximation), which is
what Newton's method on the rotation group needs.  Derivation in docs/model.md;
verified against finite differences in tests/test_energy_derivatives.py.

Stiffener springs.  Optionally (`springs`, see mechanics/stiffeners.py) the thesis' off-axis
springs add their energy, gradient and Hessian blocks to every joint; with springs None
(the default) Numba compiles that branch away, so the plain rod runs as before.

Preset (natural curvature).  Optionally (`rest`, see model/preset.py) every joint j has a
stress-free relative rotation R0_j (the Q of the joint in the hose's unloaded shape) and its
energy is that of the rotation left over, split evenly: with H the half of R0_j (R0_j = H H),
Q'' = H^T Q H^T = A'' B''^T with A'' = H^T A and B'' = H B, and the joint kernel is evaluated on
the turned frames A'', B''.  The turns act on the material side and a world rotation on the
other, so the kernel's gradient and Hessian with respect to delta_a and delta_b are exact for
the preset joint too.  The Darboux vector of Q'' is kappa - kappa0 to second order (the even
split cancels the commutator term of the Baker-Campbell-Hausdorff series, h/2 kappa0 x kappa,
that Q' = R0^T Q keeps: with it a set converged at order 1 only, measured; tests/test_preset.py);
the energy is zero exactly at the stress-free shape.  With rest None (the default) Numba
compiles the branch away.

Braid coupling.  Optionally (`braid`, see mechanics/braid.py) every joint adds l W_braid(kappa),
the energy of tension-only strands at +-beta, a function of the same Darboux vector kappa = 2 a / (c l):
its derivatives in u = (a, c) come from braid.joint_terms by the chain rule and join E_u and E_uu
(which then couple the components of a); the mapping to the rotations below is unchanged.  With
braid None (the default) Numba compiles that branch away.

Written by hand (Numba) because no library offers this rod; everything is a plain
loop over joints so the cost is linear in N.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from hoseline.mechanics.braid import joint_energy as braid_joint_energy
from hoseline.mechanics.braid import joint_terms as braid_joint_terms
from hoseline.mechanics.stiffeners import FULL, HALF, spring_energy, spring_terms_into

BANDWIDTH = 5  # half bandwidth of the Hessian: 3x3 blocks, neighbours only


@njit(cache=True)
def _rows(frame):
    # the three directors of a frame as 3-tuples (tuples stay in registers, small arrays do not;
    # one function for all three: a constant index argument would compile one specialisation each)
    return (
        (frame[0, 0], frame[0, 1], frame[0, 2]),
        (frame[1, 0], frame[1, 1], frame[1, 2]),
        (frame[2, 0], frame[2, 1], frame[2, 2]),
    )


@njit(cache=True)
def _dot(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]


@njit(cache=True)
def _combine(s0, u0, s1, u1, s2, u2):
    # s0 u0 + s1 u1 + s2 u2 for 3-tuples u
    return (
        s0 * u0[0] + s1 * u1[0] + s2 * u2[0],
        s0 * u0[1] + s1 * u1[1] + s2 * u2[1],
        s0 * u0[2] + s1 * u1[2] + s2 * u2[2],
    )


@njit(cache=True)
def joint_terms_into(frame_a, frame_b, stiffness, joint_length, grad_a, hess_aa, hess_ab, braid=None):
    """Energy (returned), gradient and Hessian blocks of one elastic joint, written into given arrays.

    frame_a, frame_b: 3x3 frames (rows = directors).  stiffness: (EI1, EI2, GJ) N*mm^2.
    joint_length: mm.  braid: the braid coupling's data (mechanics/braid.py) or None for none.
    grad_a (3,), hess_aa, hess_ab (3, 3): outputs; the second-order term is
    1/2 da.Haa.da + 1/2 db.Hbb.db + da.Hab.db (hess_ab is not symmetric), and grad_b = -grad_a,
    hess_bb = hess_aa because the energy depends on the relative rotation only.
    Written with scalars and 3-tuples: 3x3 products through BLAS and small temporary arrays
    cost more than the arithmetic (this runs N+1 times per Newton iteration).
    """
    a_0, a_1, a_2 = _rows(frame_a)
    b_0, b_1, b_2 = _rows(frame_b)
    # Q = A B^T, Q_kl = d_k^A . d_l^B
    q00, q01, q02 = _dot(a_0, b_0), _dot(a_0, b_1), _dot(a_0, b_2)
    q10, q11, q12 = _dot(a_1, b_0), _dot(a_1, b_1), _dot(a_1, b_2)
    q20, q21, q22 = _dot(a_2, b_0), _dot(a_2, b_1), _dot(a_2, b_2)
    a0 = q21 - q12
    a1 = q02 - q20
    a2 = q10 - q01
    trace = q00 + q11 + q22
    c = 1.0 + trace
    k0, k1, k2 = stiffness[0], stiffness[1], stiffness[2]
    scale = 2.0 / joint_length
    c2 = c * c
    energy = scale * (k0 * a0 * a0 + k1 * a1 * a1 + k2 * a2 * a2) / c2

    # first and second derivatives with respect to u = (a1, a2, a3, c); E_uu is diagonal in
    # (a1, a2, a3) plus the row and column of c
    f = 2.0 * scale / c2
    e_a0, e_a1, e_a2 = f * k0 * a0, f * k1 * a1, f * k2 * a2
    e_c = -2.0 * energy / c
    e_a0a0, e_a1a1, e_a2a2 = f * k0, f * k1, f * k2
    e_a0c, e_a1c, e_a2c = -2.0 * e_a0 / c, -2.0 * e_a1 / c, -2.0 * e_a2 / c
    e_cc = 6.0 * energy / c2
    e_a0a1 = e_a0a2 = e_a1a2 = 0.0  # the braid couples the components of kappa
    if braid is not None:
        (b_e, b_a0, b_a1, b_a2, b_c, b_a0a0, b_a1a1, b_a2a2, e_a0a1, e_a0a2, e_a1a2, b_a0c, b_a1c, b_a2c,
         b_cc) = braid_joint_terms(a0, a1, a2, c, joint_length, braid)
        energy += b_e
        e_a0, e_a1, e_a2, e_c = e_a0 + b_a0, e_a1 + b_a1, e_a2 + b_a2, e_c + b_c
        e_a0a0, e_a1a1, e_a2a2 = e_a0a0 + b_a0a0, e_a1a1 + b_a1a1, e_a2a2 + b_a2a2
        e_a0c, e_a1c, e_a2c, e_cc = e_a0c + b_a0c, e_a1c + b_a1c, e_a2c + b_a2c, e_cc + b_cc

    # b_u = du/d(delta_a) (du/d(delta_b) = -b_u).  dQ_kl/d(delta_a) = d_k^A x d_l^B summed
    # with the Levi-Civita identity:  d(a_m)/d(delta_a) = sum_x (Q_mx - delta_mx tr Q) d_x^A,
    # dc/d(delta_a) = sum_m a_m d_m^A.
    bu0 = _combine(q00 - trace, a_0, q01, a_1, q02, a_2)
    bu1 = _combine(q10, a_0, q11 - trace, a_1, q12, a_2)
    bu2 = _combine(q20, a_0, q21, a_1, q22 - trace, a_2)
    bu3 = _combine(a0, a_0, a1, a_1, a2, a_2)
    border = _combine(e_a0c, bu0, e_a1c, bu1, e_a2c, bu2)  # sum_m E_(a_m c) b_m

    # W = dE/dQ = [E_a]x + E_c I;  rows of W B, then T = A^T W B (columns) and s = <W, Q>
    wb0 = _combine(e_c, b_0, -e_a2, b_1, e_a1, b_2)
    wb1 = _combine(e_a2, b_0, e_c, b_1, -e_a0, b_2)
    wb2 = _combine(-e_a1, b_0, e_a0, b_1, e_c, b_2)
    t = (
        _combine(wb0[0], a_0, wb1[0], a_1, wb2[0], a_2),
        _combine(wb0[1], a_0, wb1[1], a_1, wb2[1], a_2),
        _combine(wb0[2], a_0, wb1[2], a_1, wb2[2], a_2),
    )  # t[y][x] = T_xy
    s = e_c * trace + e_a0 * a0 + e_a1 * a1 + e_a2 * a2

    for x in range(3):
        grad_a[x] = e_a0 * bu0[x] + e_a1 * bu1[x] + e_a2 * bu2[x] + e_c * bu3[x]
        for y in range(x + 1):
            # first = b^T E_uu b (symmetric)
            first = (
                e_a0a0 * bu0[x] * bu0[y] + e_a1a1 * bu1[x] * bu1[y] + e_a2a2 * bu2[x] * bu2[y]
                + e_cc * bu3[x] * bu3[y] + border[x] * bu3[y] + bu3[x] * border[y]
            )
            if braid is not None:
                first += (e_a0a1 * (bu0[x] * bu1[y] + bu1[x] * bu0[y]) + e_a0a2 * (bu0[x] * bu2[y] + bu2[x] * bu0[y])
                          + e_a1a2 * (bu1[x] * bu2[y] + bu2[x] * bu1[y]))
            hess_aa[x, y] = hess_aa[y, x] = first + 0.5 * (t[y][x] + t[x][y])
            hess_ab[x, y] = -first - t[x][y]
            hess_ab[y, x] = -first - t[y][x]
        hess_aa[x, x] -= s
        hess_ab[x, x] += s
    return energy


@njit(cache=True)
def rest_split_into(rest_rotation, frame_a, frame_b, turned_a, turned_b):
    """turned_a = H^T frame_a and turned_b = H frame_b, H the half of a joint's stress-free rotation R0 = H H (same
    axis, half the angle; R0 within half a turn), so that turned_a turned_b^T = H^T Q H^T (see the module doc)."""
    # R0 = I + sin(t) [k]x + (1 - cos t) [k]x^2: its axial vector sin(t) k and cos(t) = (tr R0 - 1) / 2; with
    # u = sin(t/2) k = axial / (2 cos(t/2)), H = I + [u]x + [u]x^2 / (1 + cos(t/2))
    cos_half = math.sqrt(max(0.25 * (1.0 + rest_rotation[0, 0] + rest_rotation[1, 1] + rest_rotation[2, 2]), 1e-300))
    scale = 0.25 / cos_half
    u0 = scale * (rest_rotation[2, 1] - rest_rotation[1, 2])
    u1 = scale * (rest_rotation[0, 2] - rest_rotation[2, 0])
    u2 = scale * (rest_rotation[1, 0] - rest_rotation[0, 1])
    w = 1.0 / (1.0 + cos_half)
    uu = u0 * u0 + u1 * u1 + u2 * u2
    h00, h11, h22 = 1.0 + w * (u0 * u0 - uu), 1.0 + w * (u1 * u1 - uu), 1.0 + w * (u2 * u2 - uu)
    h01, h10 = -u2 + w * u0 * u1, u2 + w * u0 * u1
    h02, h20 = u1 + w * u0 * u2, -u1 + w * u0 * u2
    h12, h21 = -u0 + w * u1 * u2, u0 + w * u1 * u2
    for x in range(3):
        a0, a1, a2 = frame_a[0, x], frame_a[1, x], frame_a[2, x]
        turned_a[0, x] = h00 * a0 + h10 * a1 + h20 * a2
        turned_a[1, x] = h01 * a0 + h11 * a1 + h21 * a2
        turned_a[2, x] = h02 * a0 + h12 * a1 + h22 * a2
        b0, b1, b2 = frame_b[0, x], frame_b[1, x], frame_b[2, x]
        turned_b[0, x] = h00 * b0 + h01 * b1 + h02 * b2
        turned_b[1, x] = h10 * b0 + h11 * b1 + h12 * b2
        turned_b[2, x] = h20 * b0 + h21 * b1 + h22 * b2


@njit(cache=True)
def _preset_joint_terms(frame_a, frame_b, stiffness, joint_length, rest, joint, turned_a, turned_b, grad_a, hess_aa,
                        hess_ab, braid):
    # joint_terms_into of joint `joint`, relative to its stress-free rotation rest[joint] when rest is given
    if rest is None:
        return joint_terms_into(frame_a, frame_b, stiffness, joint_length, grad_a, hess_aa, hess_ab, braid)
    rest_split_into(rest[joint], frame_a, frame_b, turned_a, turned_b)
    return joint_terms_into(turned_a, turned_b, stiffness, joint_length, grad_a, hess_aa, hess_ab, braid)


@njit(cache=True)
def _axial_and_c(frame_a, frame_b):
    # a = axial(Q - Q^T) and c = 1 + tr Q of Q = A B^T (see the module doc), without forming Q
    a_0, a_1, a_2 = _rows(frame_a)
    b_0, b_1, b_2 = _rows(frame_b)
    a0 = _dot(a_2, b_1) - _dot(a_1, b_2)
    a1 = _dot(a_0, b_2) - _dot(a_2, b_0)
    a2 = _dot(a_1, b_0) - _dot(a_0, b_1)
    c = 1.0 + _dot(a_0, b_0) + _dot(a_1, b_1) + _dot(a_2, b_2)
    return a0, a1, a2, c


@njit(cache=True)
def joint_energy(frame_a, frame_b, stiffness, joint_length, braid=None):
    """Energy of one joint only (N*mm); see joint_terms_into."""
    a0, a1, a2, c = _axial_and_c(frame_a, frame_b)
    energy = 2.0 / joint_length * (stiffness[0] * a0**2 + stiffness[1] * a1**2 + stiffness[2] * a2**2) / c**2
    if braid is not None:
        energy += braid_joint_energy(a0, a1, a2, c, joint_length, braid)
    return energy


@njit(cache=True)
def elastic_energy(frames, start_frame, end_frame, stiffness, h, end_clamped=True, springs=None, rest=None, braid=None):
    """Total elastic energy (N*mm) of the rod; the last joint only when the end is clamped.

    springs: stiffener springs (mechanics/stiffeners.py) or None.  rest: (N+1, 3, 3)
    stress-free joint rotations (model/preset.py) or None for a straight, untwisted hose.
    braid: the braid coupling (mechanics/braid.py) or None.
    """
    n = frames.shape[0]
    if rest is not None:
        turned_a, turned_b = np.empty((3, 3)), np.empty((3, 3))
        rest_split_into(rest[0], start_frame, frames[0], turned_a, turned_b)
        total = joint_energy(turned_a, turned_b, stiffness, 0.5 * h, braid)
        for i in range(n - 1):
            rest_split_into(rest[i + 1], frames[i], frames[i + 1], turned_a, turned_b)
            total += joint_energy(turned_a, turned_b, stiffness, h, braid)
        if end_clamped:
            rest_split_into(rest[n], frames[n - 1], end_frame, turned_a, turned_b)
            total += joint_energy(turned_a, turned_b, stiffness, 0.5 * h, braid)
        return total
    total = joint_energy(start_frame, frames[0], stiffness, 0.5 * h, braid)
    for i in range(n - 1):
        total += joint_energy(frames[i], frames[i + 1], stiffness, h, braid)
    if end_clamped:
        total += joint_energy(frames[n - 1], end_frame, stiffness, 0.5 * h, braid)
    if springs is not None:
        total += spring_energy(start_frame, frames[0], springs, HALF)
        for i in range(n - 1):
            total += spring_energy(frames[i], frames[i + 1], springs, FULL)
        if end_clamped:
            total += spring_energy(frames[n - 1], end_frame, springs, HALF)
    return total


@njit(cache=True)
def _add_diag_block(band, row0, block):
    # lower triangle of a symmetric diagonal block into band storage band[i, k] = H[i, i-k]
    for r in range(3):
        for c in range(r + 1):
            band[row0 + r, r - c] += block[r, c]


@njit(cache=True)
def _add_lower_block_transposed(band, row0, col0, block):
    # H[row0:row0+3, col0:col0+3] += block^T, with row0 > col0 (strictly below the diagonal blocks)
    for r in range(3):
        for c in range(3):
            band[row0 + r, row0 + r - col0 - c] += block[c, r]


@njit(cache=True)
def assemble(
    frames, start_frame, end_frame, stiffness, h, segment_loads, roll_free, grad, band, end_clamped=True, springs=None,
    rest=None, braid=None,
):
    """Elastic + segment energy of the rod, its gradient and its banded Hessian.

    frames: (N,3,3).  start_frame, end_frame: (3,3) fitting frames.  stiffness: (3,) N*mm^2.
    h: segment length, mm.  segment_loads: (N,3) vectors w_i in N*mm (see module doc).
    roll_free: when True one extra unknown, the roll of the end frame about its tangent, is
    appended after the 3N segment rotations.  end_clamped: False for a free tip (no end joint).
    springs: stiffener springs between the segments (mechanics/stiffeners.py), None for none.
    rest: (N+1, 3, 3) stress-free rotations of the joints (preset, model/preset.py), None for none.
    braid: the braid coupling added to every joint (mechanics/braid.py), None for none.
    grad: (n,) output, band: (n, BANDWIDTH+1) output (lower band, band[i, k] = H[i, i-k]);
    both are overwritten.  Returns (elastic_energy, segment_energy) in N*mm.
    """
    n_seg = frames.shape[0]
    grad[:] = 0.0
    band[:, :] = 0.0
    g = np.empty(3)
    haa = np.empty((3, 3))
    hab = np.empty((3, 3))
    if rest is None:  # the plain rod's calls stay as they are (a shared helper costs a third of this loop)
        energy = joint_terms_into(start_frame, frames[0], stiffness, 0.5 * h, g, haa, hab, braid)
    else:
        turned_a, turned_b = np.empty((3, 3)), np.empty((3, 3))
        rest_split_into(rest[0], start_frame, frames[0], turned_a, turned_b)
        energy = joint_terms_into(turned_a, turned_b, stiffness, 0.5 * h, g, haa, hab, braid)
    if springs is not None:
        energy += spring_terms_into(start_frame, frames[0], springs, HALF, g, haa, hab)
    for x in range(3):  # element by element: a slice assignment compiles Numba's shape-error messages (0.5 s)
        grad[x] -= g[x]
    _add_diag_block(band, 0, haa)
    for i in range(n_seg - 1):
        if rest is None:
            energy += joint_terms_into(frames[i], frames[i + 1], stiffness, h, g, haa, hab, braid)
        else:
            rest_split_into(rest[i + 1], frames[i], frames[i + 1], turned_a, turned_b)
            energy += joint_terms_into(turned_a, turned_b, stiffness, h, g, haa, hab, braid)
        if springs is not None:
            energy += spring_terms_into(frames[i], frames[i + 1], springs, FULL, g, haa, hab)
        for x in range(3):
            grad[3 * i + x] += g[x]
            grad[3 * i + 3 + x] -= g[x]
        _add_diag_block(band, 3 * i, haa)
        _add_diag_block(band, 3 * i + 3, haa)
        _add_lower_block_transposed(band, 3 * i + 3, 3 * i, hab)
    last = 3 * (n_seg - 1)
    if end_clamped:
        if rest is None:
            energy += joint_terms_into(frames[n_seg - 1], end_frame, stiffness, 0.5 * h, g, haa, hab, braid)
        else:
            rest_split_into(rest[n_seg], frames[n_seg - 1], end_frame, turned_a, turned_b)
            energy += joint_terms_into(turned_a, turned_b, stiffness, 0.5 * h, g, haa, hab, braid)
        if springs is not None:
            energy += spring_terms_into(frames[n_seg - 1], end_frame, springs, HALF, g, haa, hab)
        for x in range(3):
            grad[last + x] += g[x]
        _add_diag_block(band, last, haa)
    if roll_free and end_clamped:
        axis = end_frame[2]
        roll = 3 * n_seg
        grad[roll] = -(g[0] * axis[0] + g[1] * axis[1] + g[2] * axis[2])
        for x in range(3):
            for y in range(3):
                band[roll, 0] += axis[x] * haa[x, y] * axis[y]
        for c in range(3):  # H[segment N-1 rows, roll] = hab @ axis
            band[roll, roll - last - c] += hab[c, 0] * axis[0] + hab[c, 1] * axis[1] + hab[c, 2] * axis[2]

    segment_energy = 0.0
    for i in range(n_seg):
        d3 = frames[i, 2]
        w = segment_loads[i]
        segment_energy -= w[0] * d3[0] + w[1] * d3[1] + w[2] * d3[2]
        grad[3 * i] += w[1] * d3[2] - w[2] * d3[1]
        grad[3 * i + 1] += w[2] * d3[0] - w[0] * d3[2]
        grad[3 * i + 2] += w[0] * d3[1] - w[1] * d3[0]
        wd = w[0] * d3[0] + w[1] * d3[1] + w[2] * d3[2]
        for r in range(3):
            for c in range(r + 1):
                band[3 * i + r, r - c] += (wd if r == c else 0.0) - 0.5 * (w[r] * d3[c] + d3[r] * w[c])
    return energy, segment_energy


@njit(cache=True)
def joint_moments(frames, start_frame, end_frame, stiffness, h, end_clamped=True, springs=None, rest=None, braid=None):
    """Internal moment (world, N*mm) and discrete Darboux vector (material, 1/mm) at the N+1 nodes.

    The moment at node j is dE_joint/d(delta_B): the moment exerted by the part of the
    hose beyond the node on the part before it (springs included when given).  The Darboux
    vector components are (bending about d1, bending about d2, twist rate).  A free tip
    carries no moment.  rest: stress-free joint rotations (preset) or None; the moment is
    then that of the joint's deviation from them, the Darboux vector stays the geometric one.
    braid: the braid coupling (mechanics/braid.py) or None.
    """
    n_seg = frames.shape[0]
    g = np.empty(3)
    haa = np.empty((3, 3))
    hab = np.empty((3, 3))
    turned_a, turned_b = np.empty((3, 3)), np.empty((3, 3))
    moments = np.zeros((n_seg + 1, 3))
    darboux = np.zeros((n_seg + 1, 3))
    for j in range(n_seg + 1 if end_clamped else n_seg):
        if j == 0:
            fa, fb, length, kind = start_frame, frames[0], 0.5 * h, HALF
        elif j == n_seg:
            fa, fb, length, kind = frames[n_seg - 1], end_frame, 0.5 * h, HALF
        else:
            fa, fb, length, kind = frames[j - 1], frames[j], h, FULL
        _preset_joint_terms(fa, fb, stiffness, length, rest, j, turned_a, turned_b, g, haa, hab, braid)
        if springs is not None:
            spring_terms_into(fa, fb, springs, kind, g, haa, hab)
        for x in range(3):
            moments[j, x] = -g[x]
        a0, a1, a2, c = _axial_and_c(fa, fb)
        darboux[j, 0] = 2.0 * a0 / (c * length)
        darboux[j, 1] = 2.0 * a1 / (c * length)
        darboux[j, 2] = 2.0 * a2 / (c * length)
    return moments, darboux
