"""The broad phase of self-contact: every pair of segments closer than the reach is a candidate."""

import numpy as np
import pytest
from scipy.optimize import minimize

from hoseline.mechanics.self_pairs import near_segment_pairs


def segment_distance(p1, q1, p2, q2) -> float:
    """Distance between two segments by bounded minimisation over both parameters (independent of the kernels)."""
    def squared(st):
        s, t = st
        r = (p1 + s * (q1 - p1)) - (p2 + t * (q2 - p2))
        return float(r @ r)

    best = min((minimize(squared, start, bounds=[(0, 1), (0, 1)], method="L-BFGS-B").fun
                for start in ([0.5, 0.5], [0, 0], [0, 1], [1, 0], [1, 1])))
    return float(np.sqrt(max(best, 0.0)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_every_pair_closer_than_the_reach_is_a_candidate_and_the_exclusion_holds(seed):
    rng = np.random.default_rng(seed)
    steps = rng.normal(size=(60, 3))
    steps /= np.linalg.norm(steps, axis=1)[:, None]
    nodes = np.cumsum(np.vstack([np.zeros(3), 10.0 * steps]), axis=0)  # a random walk that crosses itself
    exclusion, reach = 3, 6.0
    first, second = near_segment_pairs(nodes, exclusion, reach)
    candidates = set(zip(first.tolist(), second.tolist()))
    assert all(j - i > exclusion for i, j in candidates)
    close = {(i, j) for i in range(60) for j in range(i + exclusion + 1, 60)
             if segment_distance(nodes[i], nodes[i + 1], nodes[j], nodes[j + 1]) < reach}
    assert close and close <= candidates  # every close pair found (the check can fail: there are close pairs)
    assert len(candidates) < 0.2 * 60 * 59 / 2  # and far fewer than all pairs


def test_a_hose_folded_onto_itself_grows_the_list():
    """Two parallel passes 1 mm apart: every segment of one is near several of the other (more than the first
    capacity of four per segment)."""
    x = np.linspace(0.0, 100.0, 101)
    out = np.column_stack([x, np.zeros_like(x), np.zeros_like(x)])
    back = np.column_stack([x[::-1], np.ones_like(x), np.zeros_like(x)])
    nodes = np.vstack([out, back])
    first, second = near_segment_pairs(nodes, 2, 5.0)
    assert len(first) > 4 * (len(nodes) - 1)
    assert len(set(zip(first.tolist(), second.tolist()))) == len(first)  # no pair twice
