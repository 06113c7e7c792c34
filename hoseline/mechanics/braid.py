"""Braid coupling: tension-only strands at +-beta to the hose axis, their energy per length and its derivatives.

Two families of n strands each (axial stiffness EA_s, N) are wound on radius r at +-beta to the
hose axis.  A strand at angle theta round the section (from the outside of the bend) takes the strain

    eps+-(theta) = alpha kappa_b cos(theta) +- gamma tau,   alpha = r cos^2(beta),  gamma = r sin(beta) cos(beta),

from the bending curvature kappa_b = |(kappa_1, kappa_2)| and the twist rate tau = kappa_3, and
carries tension only beyond its slack strain eps0.  Per hose length the braid stores

    W(kappa) = C sum_+- I(alpha kappa_b, +-gamma tau - eps0),   C = n EA_s / (2 cos(beta)),
    I(a, b) = (1/2 pi) int (a cos(theta) + b)_+^2 d(theta)   (closed form in family_terms).

W is even in (kappa_1, kappa_2) and in tau, so the braid has no linear twist-bending term (docs/model.md); the
coupling is that a family stretched by twist and taut all round adds C alpha^2 = n EA_s r^2
cos^3(beta) / 2 to the bending stiffness.  With eps0 = 0 the two families together store exactly
the quadratic C (alpha^2 kappa_b^2 + 2 gamma^2 tau^2) / 2, half of the linear braid's energy.

The joint kernel (energy.joint_terms_into) adds l W(kappa) with kappa the joint's discrete Darboux
vector 2 a / (c l); joint_terms gives that energy and its derivatives with respect to u = (a, c).
Kernel data: braid = array([C N, alpha mm, gamma mm, eps0]) (braid_coefficients), None for no braid.
Units: mm, N, radians.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


def braid_coefficients(strands: int, strand_axial_stiffness: float, angle_deg: float, radius: float,
                       slack_strain: float) -> np.ndarray:
    """The kernel's braid data [C, alpha, gamma, eps0] of the module doc.

    strands: per family.  strand_axial_stiffness: EA_s, N.  angle_deg: beta, degrees from the hose
    axis.  radius: of the braid, mm.  slack_strain: eps0, dimensionless.
    """
    beta = math.radians(angle_deg)
    return np.array([
        strands * strand_axial_stiffness / (2.0 * math.cos(beta)),
        radius * math.cos(beta) ** 2,
        radius * math.sin(beta) * math.cos(beta),
        slack_strain,
    ])


@njit(cache=True)
def family_terms(a, b):
    """I(a, b) of one strand family (module doc) and what the chain rule to the Darboux vector needs.

    a >= 0: bending strain amplitude alpha kappa_b.  b: the family's twist strain beyond its slack.
    Returns (I, I_b, I_bb, I_a / a, I_aa - I_a / a, I_ab); the last two are zero unless the family is
    taut over part of the circumference only (|b| < a), so none divides by a = 0.  At a = b = 0 (a family
    exactly at its slack on a straight hose, where the second derivatives jump) it returns their limit
    along b = 0, taut on half the section: the two families of a braid without slack then sum to the
    derivatives of their exact quadratic b^2 + a^2 / 2.
    """
    if a == 0.0 and b == 0.0:
        return 0.0, 0.0, 1.0, 0.5, 0.0, 2.0 / math.pi
    if b <= -a:  # slack all round (and the straight hose at or below the slack strain)
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    if b >= a:  # taut all round: the linear strand
        return b * b + 0.5 * a * a, 2.0 * b, 2.0, 1.0, 0.0, 0.0
    # taut for |theta| < phi
    phi = math.acos(-b / a)
    sin_phi = math.sin(phi)
    cos_phi = -b / a
    value = (a * a * (phi + sin_phi * cos_phi) + 4.0 * a * b * sin_phi + 2.0 * b * b * phi) / (2.0 * math.pi)
    slope_b = 2.0 * (a * sin_phi + b * phi) / math.pi
    return (value, slope_b, 2.0 * phi / math.pi, (phi - sin_phi * cos_phi) / math.pi,
            2.0 * sin_phi * cos_phi / math.pi, 2.0 * sin_phi / math.pi)


@njit(cache=True)
def density_terms(k0, k1, k2, braid):
    """W (N), its gradient and Hessian in the Darboux vector (k0, k1 bending, k2 twist rate, 1/mm).

    Returns (W, w0, w1, w2, w00, w11, w22, w01, w02, w12), w_i = dW/dk_i, w_ij = d2W/dk_i dk_j.
    """
    coefficient, bend_arm, twist_arm, slack = braid[0], braid[1], braid[2], braid[3]
    bend = math.sqrt(k0 * k0 + k1 * k1)
    n0 = k0 / bend if bend > 0.0 else 0.0  # direction of the bending curvature (used only where bend > 0)
    n1 = k1 / bend if bend > 0.0 else 0.0
    a = bend_arm * bend
    w = w2 = w22 = 0.0
    ratio = excess = cross = 0.0  # sums over the families of I_a / a, I_aa - I_a / a and sign * I_ab
    for sign in (1.0, -1.0):
        value, slope_b, curve_b, family_ratio, family_excess, family_cross = family_terms(a, sign * twist_arm * k2 - slack)
        w += value
        w2 += sign * twist_arm * slope_b
        w22 += twist_arm * twist_arm * curve_b
        ratio += family_ratio
        excess += family_excess
        cross += sign * family_cross
    bend2 = bend_arm * bend_arm
    return (
        coefficient * w,
        coefficient * bend2 * ratio * k0,
        coefficient * bend2 * ratio * k1,
        coefficient * w2,
        coefficient * bend2 * (ratio + excess * n0 * n0),
        coefficient * bend2 * (ratio + excess * n1 * n1),
        coefficient * w22,
        coefficient * bend2 * excess * n0 * n1,
        coefficient * bend_arm * twist_arm * cross * n0,
        coefficient * bend_arm * twist_arm * cross * n1,
    )


@njit(cache=True)
def joint_terms(a0, a1, a2, c, joint_length, braid):
    """l W(kappa) of one joint, kappa = 2 a / (c l), and its derivatives in u = (a0, a1, a2, c).

    a = axial(Q - Q^T), c = 1 + tr Q of the joint's relative rotation Q (energy.py); joint_length: mm.
    Returns (E, E_a0, E_a1, E_a2, E_c, E_a0a0, E_a1a1, E_a2a2, E_a0a1, E_a0a2, E_a1a2, E_a0c, E_a1c, E_a2c,
    E_cc) in N*mm, by the chain rule: dkappa_i/da_j = p delta_ij, dkappa_i/dc = -kappa_i / c with p = 2 / (c l).
    """
    p = 2.0 / (c * joint_length)
    k0, k1, k2 = p * a0, p * a1, p * a2
    w, w0, w1, w2, w00, w11, w22, w01, w02, w12 = density_terms(k0, k1, k2, braid)
    l = joint_length
    # sum_j W_ij kappa_j + W_i (the chain rule's a-c terms) and sum_i W_i kappa_i
    m0 = w00 * k0 + w01 * k1 + w02 * k2
    m1 = w01 * k0 + w11 * k1 + w12 * k2
    m2 = w02 * k0 + w12 * k1 + w22 * k2
    first = w0 * k0 + w1 * k1 + w2 * k2
    second = m0 * k0 + m1 * k1 + m2 * k2
    lp2 = l * p * p
    ac = -l * p / c
    return (
        l * w,
        l * p * w0, l * p * w1, l * p * w2,
        -l * first / c,
        lp2 * w00, lp2 * w11, lp2 * w22, lp2 * w01, lp2 * w02, lp2 * w12,
        ac * (m0 + w0), ac * (m1 + w1), ac * (m2 + w2),
        l * (2.0 * first + second) / (c * c),
    )


@njit(cache=True)
def joint_energy(a0, a1, a2, c, joint_length, braid):
    """l W(kappa) of one joint only, N*mm (see joint_terms)."""
    p = 2.0 / (c * joint_length)
    return joint_length * density_terms(p * a0, p * a1, p * a2, braid)[0]
