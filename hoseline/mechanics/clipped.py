"""The rod with intermediate clips: energy, exact gradient, banded Hessian and constraints (compiled).

A clip holds station k (arc length k h, 1 <= k <= N-1) at a point p and, unless it is a ball
clip, holds the hose's direction there with a clip frame C (rows d1, d2, d3; d3 along the hose):

- position: three more constraint rows x_k - p = 0, with x_k = x_0 + h sum_{i<k} d3_i; their
  Jacobian is that of the end constraint restricted to the segments before k, and their
  multiplier mu_j is the force of the clip on the hose.  In the Lagrangian each segment i < k
  gains -h mu_j . d3_i, so the segment loads become
      w_i = h (mu_end + sum_{clips j with k_j > i} mu_j + weight of the hose beyond i's centre);
- direction (fixed and rotating clips): the ordinary joint at node k is replaced by two half
  joints (length h/2), segment k-1 to C and C to segment k, exactly as the end clamps tie the
  first and last segments to the fittings.  A fixed clip's frame is given; a rotating clip's
  frame may spin about its own d3: one more unknown, the roll, with zero torque about the axis
  at equilibrium (like the end's free roll);
- a ball clip keeps the ordinary joint: position rows only;
- a sliding clip (a guide ring) is a rotating clip whose arc length sigma is an unknown: the
  segments of the spans next to it take the lengths that put its node at sigma (each segment
  has its own length, `lengths`), and stretch_terms gives the Lagrangian's derivatives along
  sigma (they join the border: clipped_newton.py).

Unknown ordering.  The unknowns follow the chain: segment 0's three rotations, ..., then the
roll of a roll-free clip at node k between segment k-1's and segment k's rotations, ..., and
the end roll last.  A roll unknown couples only to its two neighbouring segments, and two
segments on either side of a framed clip do not couple at all, so the Hessian keeps half
bandwidth 5 (BANDWIDTH) and the banded LDL^T applies unchanged; the 3 + 3c constraint rows
are the border (mechanics/bordered.py).

Joint derivatives come from energy.joint_terms_into (and stiffeners.spring_terms_into); a body
with a roll unknown about the unit axis n sees the perturbation delta = theta n, so its
gradient is n . g and its Hessian entries are the blocks projected on n.  Verified against
finite differences in tests/test_clips.py.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from hoseline.mechanics.energy import (
    BANDWIDTH,
    _add_diag_block,
    _add_lower_block_transposed,
    _axial_and_c,
    joint_terms_into,
)
from hoseline.mechanics.stiffeners import FULL, HALF, spring_terms_into

# unknowns carried by a body of the chain; np.int64 for one compiled _body_basis (see stiffeners.FULL)
FIXED_BODY, ROLL_BODY, SEGMENT_BODY = np.int64(0), np.int64(1), np.int64(3)


@njit(cache=True)
def unknown_layout(n_seg, clip_nodes, clip_roll_free, end_roll_free):
    """Index of each segment's first rotation unknown (N,), of each clip's roll unknown (c,; -1 if
    none), of the end roll (-1 if none), and the number of unknowns (see the module doc)."""
    segment_index = np.empty(n_seg, np.int64)
    clip_roll_index = np.full(clip_nodes.shape[0], -1, np.int64)
    index = 0
    for i in range(n_seg):
        for j in range(clip_nodes.shape[0]):
            if clip_nodes[j] == i and clip_roll_free[j]:
                clip_roll_index[j] = index
                index += 1
        segment_index[i] = index
        index += 3
    end_roll_index = -1
    if end_roll_free:
        end_roll_index = index
        index += 1
    return segment_index, clip_roll_index, end_roll_index, index


@njit(cache=True)
def _band_add(band, row, col, value):
    # symmetric H[row, col] += value (and its mirror) into lower band storage band[i, k] = H[i, i-k]
    if row < col:
        row, col = col, row
    band[row, row - col] += value


@njit(cache=True)
def _projected(block, basis_a, p, basis_b, q):
    # basis_a[:, p] . block . basis_b[:, q]
    total = 0.0
    for x in range(3):
        for y in range(3):
            total += basis_a[x, p] * block[x, y] * basis_b[y, q]
    return total


@njit(cache=True)
def _body_basis(kind, axis):
    # columns: the world rotations that the body's unknowns stand for
    basis = np.zeros((3, 3))
    if kind == SEGMENT_BODY:
        for x in range(3):
            basis[x, x] = 1.0
    elif kind == ROLL_BODY:
        for x in range(3):
            basis[x, 0] = axis[x]
    return basis


@njit(cache=True)
def _add_joint(grad, band, g, haa, hab, index_a, kind_a, basis_a, index_b, kind_b, basis_b):
    # one joint between body a (before) and body b (after): gradient +g on a, -g on b; Hessian
    # blocks H_aa = H_bb = haa, H_ab = hab, all projected on the bodies' unknowns (kind = their count)
    if kind_a == SEGMENT_BODY and kind_b == SEGMENT_BODY:  # most joints: the blocks as they are
        for x in range(3):
            grad[index_a + x] += g[x]
            grad[index_b + x] -= g[x]
        _add_diag_block(band, index_a, haa)
        _add_diag_block(band, index_b, haa)
        _add_lower_block_transposed(band, index_b, index_a, hab)
        return
    for p in range(kind_a):
        grad[index_a + p] += g[0] * basis_a[0, p] + g[1] * basis_a[1, p] + g[2] * basis_a[2, p]
        for q in range(p + 1):
            _band_add(band, index_a + p, index_a + q, _projected(haa, basis_a, p, basis_a, q))
    for p in range(kind_b):
        grad[index_b + p] -= g[0] * basis_b[0, p] + g[1] * basis_b[1, p] + g[2] * basis_b[2, p]
        for q in range(p + 1):
            _band_add(band, index_b + p, index_b + q, _projected(haa, basis_b, p, basis_b, q))
    for p in range(kind_a):
        for q in range(kind_b):
            _band_add(band, index_b + q, index_a + p, _projected(hab, basis_a, p, basis_b, q))


@njit(cache=True)
def joint_into(frame_a, frame_b, stiffness, length, springs, kind, g, haa, hab):
    """Energy (N*mm, returned) of an elastic joint of `length` mm plus its stiffener springs of
    `kind` (if any), its gradient and Hessian blocks into g, haa, hab (see energy.joint_terms_into)."""
    energy = joint_terms_into(frame_a, frame_b, stiffness, length, g, haa, hab)
    if springs is not None:  # adds its terms to those of the joint
        energy += spring_terms_into(frame_a, frame_b, springs, kind, g, haa, hab)
    return energy


@njit(cache=True)
def _joint_length(lengths, node):
    # the length of the ordinary joint at a node: half of each segment it joins (h/2 at the fittings)
    if node == 0:
        return 0.5 * lengths[0]
    if node == lengths.shape[0]:
        return 0.5 * lengths[node - 1]
    return 0.5 * (lengths[node - 1] + lengths[node])


@njit(cache=True)
def clip_at_nodes(n_seg, clip_nodes):
    """(N+1,) index of the clip at each node, -1 where there is none."""
    at = np.full(n_seg + 1, -1, np.int64)
    for j in range(clip_nodes.shape[0]):
        at[clip_nodes[j]] = j
    return at


@njit(cache=True)
def clipped_system(
    frames, start_point, start_frame, end_point, end_frame, end_roll_free, clip_nodes, clip_points, clip_frames,
    clip_framed, clip_roll_free, stiffness, lengths, forces, line_weight, springs,
):
    """Energy, gradient, banded Hessian, constraints and their Jacobian of the clipped rod.

    frames: (N, 3, 3).  start_point, end_point: mm.  start_frame, end_frame: (3, 3), the end
    frame including its current roll.  end_roll_free: the end roll is an unknown.  clip_nodes:
    (c,) int node of each clip.  clip_points: (c, 3) mm.  clip_frames: (c, 3, 3) including their
    current roll (ignored where clip_framed is False: ball clips).  clip_roll_free: (c,) bool.
    stiffness: (EI1, EI2, GJ) N*mm^2.  lengths: (N,) mm, each segment's length (all L/N unless a
    sliding clip stretches the spans next to it).  forces: (1 + c, 3) N, the end force then the
    clip forces (the multipliers).  line_weight: (3,) N/mm.  springs: stiffener springs or None.
    Returns (energy N*mm: elastic + weight, grad (n,), band (n, BANDWIDTH + 1), jac_t (n, 3 + 3c),
    constraint (3 + 3c,) mm: x_N - end point then x_k - p per clip, largest |grad|, largest |constraint|).
    """
    n_seg = frames.shape[0]
    n_clips = clip_nodes.shape[0]
    segment_index, clip_roll_index, end_roll_index, n = unknown_layout(n_seg, clip_nodes, clip_roll_free, end_roll_free)
    grad = np.zeros(n)
    band = np.zeros((n, BANDWIDTH + 1))
    g = np.empty(3)
    haa = np.empty((3, 3))
    hab = np.empty((3, 3))
    segment_basis = _body_basis(SEGMENT_BODY, frames[0, 2])
    no_basis = np.zeros((3, 3))
    at_node = clip_at_nodes(n_seg, clip_nodes)
    energy = 0.0
    for node in range(n_seg + 1):
        # the body before the node and the body after it
        if node == 0:
            frame_a, index_a, kind_a, basis_a = start_frame, 0, FIXED_BODY, no_basis
        else:
            frame_a, index_a, kind_a, basis_a = frames[node - 1], segment_index[node - 1], SEGMENT_BODY, segment_basis
        if node == n_seg:
            frame_b = end_frame
            index_b, kind_b = (end_roll_index, ROLL_BODY) if end_roll_free else (0, FIXED_BODY)
            basis_b = _body_basis(kind_b, end_frame[2])
        else:
            frame_b, index_b, kind_b, basis_b = frames[node], segment_index[node], SEGMENT_BODY, segment_basis
        j = at_node[node]
        if j >= 0 and clip_framed[j]:
            clip = clip_frames[j]
            index_c, kind_c = (clip_roll_index[j], ROLL_BODY) if clip_roll_free[j] else (0, FIXED_BODY)
            basis_c = _body_basis(kind_c, clip[2])
            energy += joint_into(frame_a, clip, stiffness, 0.5 * lengths[node - 1], springs, HALF, g, haa, hab)
            _add_joint(grad, band, g, haa, hab, index_a, kind_a, basis_a, index_c, kind_c, basis_c)
            energy += joint_into(clip, frame_b, stiffness, 0.5 * lengths[node], springs, HALF, g, haa, hab)
            _add_joint(grad, band, g, haa, hab, index_c, kind_c, basis_c, index_b, kind_b, basis_b)
        else:
            end_joint = node == 0 or node == n_seg
            length = _joint_length(lengths, node)
            energy += joint_into(frame_a, frame_b, stiffness, length, springs, HALF if end_joint else FULL, g, haa, hab)
            _add_joint(grad, band, g, haa, hab, index_a, kind_a, basis_a, index_b, kind_b, basis_b)

    # segment terms -w_i . d3_i of the Lagrangian (weight and constraint forces; their gradient and
    # Hessian only: the energy returned is the plain one), the centreline and the weight potential
    jac_t = np.zeros((n, 3 + 3 * n_clips))
    constraint = np.zeros(3 + 3 * n_clips)
    tip = start_point.copy()
    weight_potential = 0.0
    w = np.empty(3)
    beyond_node = 0.0  # hose length beyond node i + 1, mm
    for i in range(n_seg):
        beyond_node += lengths[i]
    for i in range(n_seg):
        h = lengths[i]
        beyond_node -= h
        beyond = beyond_node + 0.5 * h
        for k in range(3):
            w[k] = h * (forces[0, k] + beyond * line_weight[k])
        for c in range(n_clips):
            if clip_nodes[c] > i:
                for k in range(3):
                    w[k] += h * forces[1 + c, k]
        d3 = frames[i, 2]
        r = segment_index[i]
        grad[r] += w[1] * d3[2] - w[2] * d3[1]
        grad[r + 1] += w[2] * d3[0] - w[0] * d3[2]
        grad[r + 2] += w[0] * d3[1] - w[1] * d3[0]
        wd = w[0] * d3[0] + w[1] * d3[1] + w[2] * d3[2]
        for x in range(3):
            for y in range(x + 1):
                band[r + x, x - y] += (wd if x == y else 0.0) - 0.5 * (w[x] * d3[y] + d3[x] * w[y])
        # J^T block of segment i is h [d3_i]x, in the end's columns and those of the clips beyond it
        for c in range(n_clips + 1):
            if c == 0 or clip_nodes[c - 1] > i:
                col = 3 * c
                jac_t[r, col + 1] = -h * d3[2]
                jac_t[r, col + 2] = h * d3[1]
                jac_t[r + 1, col] = h * d3[2]
                jac_t[r + 1, col + 2] = -h * d3[0]
                jac_t[r + 2, col] = -h * d3[1]
                jac_t[r + 2, col + 1] = h * d3[0]
        for k in range(3):
            weight_potential -= h * line_weight[k] * (tip[k] - start_point[k] + 0.5 * h * d3[k])
            tip[k] += h * d3[k]
        for c in range(n_clips):
            if clip_nodes[c] == i + 1:
                for k in range(3):
                    constraint[3 + 3 * c + k] = tip[k] - clip_points[c, k]
    for k in range(3):
        constraint[k] = tip[k] - end_point[k]
    grad_max = 0.0
    for value in grad:
        grad_max = max(grad_max, abs(value))
    gap = 0.0
    for value in constraint:
        gap = max(gap, abs(value))
    return energy + weight_potential, grad, band, jac_t, constraint, grad_max, gap


@njit(cache=True)
def clip_moments(frames, clip_nodes, clip_frames, clip_framed, stiffness, lengths, springs):
    """(c, 3) moment of each clip on the hose, N*mm (world, about the clip point): dE/d(delta_C) of
    the two half joints at the clip frame C; zero for a ball clip (it holds no direction).
    lengths: (N,) segment lengths, mm."""
    out = np.zeros((clip_nodes.shape[0], 3))
    g = np.empty(3)
    haa = np.empty((3, 3))
    hab = np.empty((3, 3))
    for j in range(clip_nodes.shape[0]):
        if not clip_framed[j]:
            continue
        k = clip_nodes[j]
        joint_into(frames[k - 1], clip_frames[j], stiffness, 0.5 * lengths[k - 1], springs, HALF, g, haa, hab)
        out[j] -= g
        joint_into(clip_frames[j], frames[k], stiffness, 0.5 * lengths[k], springs, HALF, g, haa, hab)
        out[j] += g
    return out


@njit(cache=True)
def joint_darboux(frame_a, frame_b, length):
    """Discrete Darboux vector (material components, 1/mm) of a joint of `length` mm: 2 a / (c l)."""
    a0, a1, a2, c = _axial_and_c(frame_a, frame_b)
    return np.array([2.0 * a0 / (c * length), 2.0 * a1 / (c * length), 2.0 * a2 / (c * length)])


@njit(cache=True)
def _add_projected(column, sign, g, index, kind, basis):
    # column[body's unknowns] += sign * basis^T g
    for p in range(kind):
        column[index + p] += sign * (g[0] * basis[0, p] + g[1] * basis[1, p] + g[2] * basis[2, p])


@njit(cache=True)
def _stretch_joint(grad_s, mixed, hess_ss, energy, g, length, length_rates, index_a, kind_a, basis_a, index_b,
                   kind_b, basis_b):
    # a joint's energy is e / length: its derivatives along the arc-length unknowns, which change the length
    # at the rates length_rates (s,) (mm per mm)
    for j in range(length_rates.shape[0]):
        rate = length_rates[j]
        if rate == 0.0:
            continue
        grad_s[j] -= energy * rate / length
        _add_projected(mixed[:, j], -rate / length, g, index_a, kind_a, basis_a)
        _add_projected(mixed[:, j], rate / length, g, index_b, kind_b, basis_b)
        for k in range(length_rates.shape[0]):
            hess_ss[j, k] += 2.0 * energy * rate * length_rates[k] / length**2


@njit(cache=True)
def stretch_terms(
    frames, start_point, start_frame, end_frame, end_roll_free, clip_nodes, clip_frames, clip_framed,
    clip_roll_free, stiffness, lengths, rates, forces, line_weight,
):
    """Derivatives of the clipped rod's Lagrangian along the arc lengths of its sliding clips (compiled).

    A sliding clip's arc length sigma is an unknown: the clip stays on its station and the
    segments of the two spans next to it (between the held stations before and after it) take
    the lengths that put the station at sigma, so segment i has length h_i(sigma) with constant
    rates dh_i/dsigma_j (rates, (N, s)).  Arguments as clipped_system (without springs), lengths
    (N,) mm the current h_i.  The Lagrangian L = sum_joints e_J / l_J + V_weight - sum mu . c
    depends on the h_i through the joint lengths l_J (half of each segment a joint spans), the
    node positions x_k = x_0 + sum_{i<k} h_i d3_i and the weight of each segment; with
    Lambda_i the hose length beyond node i and M_i the multipliers of the rows beyond segment i:
        dL/dh_i = -M_i . d3_i - q . (x_i - x_0) - (q . d3_i) Lambda_i   (plus -e_J/l_J dl_J/dh_i),
        d2L/dh_i dh_k = -q . d3_min(i,k)                                 (plus 2 e_J/l_J^3 ...).
    Returns (grad_s (s,) N, mixed (n, s) d2L/d(unknown) dsigma, hess_ss (s, s) N/mm,
    jac_s (3 + 3c, s) dc/dsigma, dimensionless).  Verified against finite differences in
    tests/test_clips_sliding.py.
    """
    n_seg = frames.shape[0]
    n_clips = clip_nodes.shape[0]
    n_slide = rates.shape[1]
    segment_index, clip_roll_index, end_roll_index, n = unknown_layout(n_seg, clip_nodes, clip_roll_free, end_roll_free)
    grad_s = np.zeros(n_slide)
    mixed = np.zeros((n, n_slide))
    hess_ss = np.zeros((n_slide, n_slide))
    jac_s = np.zeros((3 + 3 * n_clips, n_slide))
    g = np.empty(3)
    haa = np.empty((3, 3))
    hab = np.empty((3, 3))
    segment_basis = _body_basis(SEGMENT_BODY, frames[0, 2])
    no_basis = np.zeros((3, 3))
    at_node = clip_at_nodes(n_seg, clip_nodes)
    joint_rates = np.empty(n_slide)
    for node in range(n_seg + 1):
        if node == 0:
            frame_a, index_a, kind_a, basis_a = start_frame, 0, FIXED_BODY, no_basis
        else:
            frame_a, index_a, kind_a, basis_a = frames[node - 1], segment_index[node - 1], SEGMENT_BODY, segment_basis
        if node == n_seg:
            frame_b = end_frame
            index_b, kind_b = (end_roll_index, ROLL_BODY) if end_roll_free else (0, FIXED_BODY)
            basis_b = _body_basis(kind_b, end_frame[2])
        else:
            frame_b, index_b, kind_b, basis_b = frames[node], segment_index[node], SEGMENT_BODY, segment_basis
        j = at_node[node]
        if j >= 0 and clip_framed[j]:
            clip = clip_frames[j]
            index_c, kind_c = (clip_roll_index[j], ROLL_BODY) if clip_roll_free[j] else (0, FIXED_BODY)
            basis_c = _body_basis(kind_c, clip[2])
            for k in range(n_slide):
                joint_rates[k] = 0.5 * rates[node - 1, k]
            energy = joint_terms_into(frame_a, clip, stiffness, 0.5 * lengths[node - 1], g, haa, hab)
            _stretch_joint(grad_s, mixed, hess_ss, energy, g, 0.5 * lengths[node - 1], joint_rates, index_a, kind_a,
                           basis_a, index_c, kind_c, basis_c)
            for k in range(n_slide):
                joint_rates[k] = 0.5 * rates[node, k]
            energy = joint_terms_into(clip, frame_b, stiffness, 0.5 * lengths[node], g, haa, hab)
            _stretch_joint(grad_s, mixed, hess_ss, energy, g, 0.5 * lengths[node], joint_rates, index_c, kind_c,
                           basis_c, index_b, kind_b, basis_b)
        else:
            for k in range(n_slide):
                joint_rates[k] = 0.5 * ((rates[node - 1, k] if node > 0 else 0.0) + (rates[node, k] if node < n_seg else 0.0))
            length = _joint_length(lengths, node)
            energy = joint_terms_into(frame_a, frame_b, stiffness, length, g, haa, hab)
            _stretch_joint(grad_s, mixed, hess_ss, energy, g, length, joint_rates, index_a, kind_a, basis_a, index_b,
                           kind_b, basis_b)

    # segment terms: constraints and weight (see the docstring)
    rates_beyond = np.zeros(n_slide)  # sum of rates[m] over m > i
    for i in range(n_seg):
        for k in range(n_slide):
            rates_beyond[k] += rates[i, k]
    q = line_weight
    offset = np.zeros(3)  # x_i - x_0
    multipliers = np.empty(3)
    beyond = 0.0  # Lambda_i
    for i in range(n_seg):
        beyond += lengths[i]
    for i in range(n_seg):
        d3 = frames[i, 2]
        h = lengths[i]
        for k in range(n_slide):
            rates_beyond[k] -= rates[i, k]
        for x in range(3):
            multipliers[x] = forces[0, x]
        for c in range(n_clips):
            if clip_nodes[c] > i:
                for x in range(3):
                    multipliers[x] += forces[1 + c, x]
        qd = q[0] * d3[0] + q[1] * d3[1] + q[2] * d3[2]
        dl_dh = -(multipliers[0] * d3[0] + multipliers[1] * d3[1] + multipliers[2] * d3[2])
        dl_dh -= q[0] * offset[0] + q[1] * offset[1] + q[2] * offset[2] + qd * beyond
        # M_i x d3_i + Lambda_i q x d3_i (times rates[i]) and h_i q x d3_i (times the rates beyond i)
        a = np.empty(3)
        b = np.empty(3)
        for x in range(3):
            a[x] = multipliers[x] + beyond * q[x]
        cross_a = (a[1] * d3[2] - a[2] * d3[1], a[2] * d3[0] - a[0] * d3[2], a[0] * d3[1] - a[1] * d3[0])
        for x in range(3):
            b[x] = h * q[x]
        cross_b = (b[1] * d3[2] - b[2] * d3[1], b[2] * d3[0] - b[0] * d3[2], b[0] * d3[1] - b[1] * d3[0])
        r = segment_index[i]
        for k in range(n_slide):
            grad_s[k] += rates[i, k] * dl_dh
            for x in range(3):
                mixed[r + x, k] += rates[i, k] * cross_a[x] + rates_beyond[k] * cross_b[x]
            for l in range(n_slide):
                hess_ss[k, l] -= qd * (rates[i, k] * (rates_beyond[l] + rates[i, l]) + rates[i, l] * rates_beyond[k])
            for c in range(n_clips + 1):
                if c == 0 or clip_nodes[c - 1] > i:
                    for x in range(3):
                        jac_s[3 * c + x, k] += rates[i, k] * d3[x]
        for x in range(3):
            offset[x] += h * d3[x]
        beyond -= h
    return grad_s, mixed, hess_ss, jac_s
