"""Check both peers on a case with a known answer: a cantilever under a transverse tip dead load.

Reference: Bisshopp & Drucker (1945), P L^2 / EI = 2 gives tip deflection 0.49346 L and
tip shortening 0.16064 L. The same elastica is also solved here by shooting, which
reproduces those numbers and allows a second comparison with an effective length
L - dl/2: both peers clamp the start by fixing the first element (PyElastica) or the
first edge (MuJoCo), and their first bending point sits half an element from the
mount, so the bending length is L - dl/2. That is an O(dl) discretisation error of the
peers, not a stiffness error; the second comparison separates the two.

Run: python bench/peers/check_peers.py   (prints the errors, writes nothing)
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

try:
    from . import common, mujoco_peer, pyelastica_peer
except ImportError:  # run as a script from bench/peers
    import common
    import mujoco_peer
    import pyelastica_peer


def elastica_tip(load_parameter: float) -> tuple[float, float]:
    """Tip deflection / L and tip shortening / L of a clamped elastica with tip dead load.

    theta(u) is the tangent angle from the undeformed axis, u = s / L, and
    theta'' = -alpha cos(theta) with theta(0) = 0, theta'(1) = 0, alpha = P L^2 / EI.
    Shooting on the unknown tip angle, integrating from the tip to the clamp.
    """

    def rhs(u, y):
        theta, dtheta, _, _ = y
        return [dtheta, -load_parameter * np.cos(theta), np.sin(theta), np.cos(theta)]

    def integrate(tip_angle):
        return solve_ivp(rhs, (1.0, 0.0), [tip_angle, 0.0, 0.0, 0.0], rtol=1e-11, atol=1e-12)

    tip_angle = brentq(lambda a: integrate(a).y[0, -1], 1e-9, np.pi / 2 - 1e-9, xtol=1e-13)
    sol = integrate(tip_angle).y[:, -1]
    # Integrated from u = 1 down to 0, so the integrals come out negated.
    return -sol[2], 1.0 + sol[3]


def elastica_tip_effective(load_parameter: float, segments: int) -> tuple[float, float]:
    """Same as elastica_tip, with the clamp moved half an element into the rod (bending length L - dl/2)."""
    ratio = 1.0 - 0.5 / segments
    deflection, shortening = elastica_tip(load_parameter * ratio**2)
    return ratio * deflection, ratio * shortening


def main(segments: int = 100) -> None:
    alpha = common.CANTILEVER_LOAD_PARAMETER
    exact = (common.CANTILEVER_TIP_DEFLECTION, common.CANTILEVER_TIP_SHORTENING)
    shooting = elastica_tip(alpha)
    effective = elastica_tip_effective(alpha, segments)
    print(f"Cantilever, P L^2/EI = {alpha:g}, {segments} elements (values / L)")
    print(f"  Bisshopp & Drucker      deflection {exact[0]:.5f}  shortening {exact[1]:.5f}")
    print(f"  shooting, length L      deflection {shooting[0]:.5f}  shortening {shooting[1]:.5f}")
    print(f"  shooting, length L-dl/2 deflection {effective[0]:.5f}  shortening {effective[1]:.5f}")
    for name, peer in (("PyElastica", pyelastica_peer), ("MuJoCo", mujoco_peer)):
        r = peer.cantilever(segments, alpha)
        got = (r["tip_deflection"], r["tip_shortening"])
        err = [100.0 * (g - e) / e for g, e in zip(got, exact)]
        err_eff = [100.0 * (g - e) / e for g, e in zip(got, effective)]
        print(
            f"  {name:10s} deflection {got[0]:.5f}  shortening {got[1]:.5f}  ({r['sim_steps']} steps)\n"
            f"             error vs B&D:      deflection {err[0]:+.3f} %  shortening {err[1]:+.3f} %\n"
            f"             error vs L-dl/2:   deflection {err_eff[0]:+.3f} %  shortening {err_eff[1]:+.3f} %"
        )


if __name__ == "__main__":
    main()
