"""Contact barrier terms (mechanics/contact.py): gradients and Hessians against finite differences."""

import numpy as np
import pytest

from hoseline.mechanics.contact import (
    SEGMENT_BALL,
    SEGMENT_CAPSULE,
    SEGMENT_SEGMENT,
    STATION_PLANE,
    barrier,
    node_terms,
    pair_gaps,
    rotation_terms,
)
from hoseline.mechanics.rod import centerline
from hoseline.mechanics.rotations import frame_from_tangent, rotate_frames

D_HAT = 0.5
RADIUS = 1.0
NO_TRIANGLES, NO_EDGES = np.zeros((0, 3, 3)), np.zeros((0, 2, 3))  # mesh pairs: tests/test_contact_mesh.py


def test_barrier_derivatives_and_smoothness():
    for d in (1e-3, 0.05, 0.3, 0.49):
        b, b1, b2 = barrier(d, D_HAT)
        step = 1e-6 * d
        assert b1 == pytest.approx((barrier(d + step, D_HAT)[0] - barrier(d - step, D_HAT)[0]) / (2 * step), rel=1e-6)
        assert b2 == pytest.approx((barrier(d + step, D_HAT)[1] - barrier(d - step, D_HAT)[1]) / (2 * step), rel=1e-6)
    # C2 at d_hat: value, slope and curvature all vanish there
    assert max(abs(v) for v in barrier(D_HAT * (1 - 1e-7), D_HAT)) < 1e-6
    assert barrier(D_HAT, D_HAT) == (0.0, 0.0, 0.0)


def _hose(segments=12, seed=0):
    # a wavy hose near the obstacles below, start at the origin
    rng = np.random.default_rng(seed)
    tangents = np.array([[1.0, 0.3 * np.sin(0.7 * i), 0.2 * np.cos(0.5 * i)] for i in range(segments)])
    tangents += 0.05 * rng.standard_normal(tangents.shape)
    frames = np.array([frame_from_tangent(t) for t in tangents])
    return frames, 2.0


def _obstacles():
    planes = np.array([[0.0, 0.0, -1.2, 0.0, 0.0, 1.0]])  # floor just below the hose
    balls = np.array([[10.0, 1.0, 2.2, 1.0]])
    capsules = np.array([[4.0, -3.0, -0.8, 4.5, 3.0, -1.0, 0.9]])
    return planes, balls, capsules


def _energy(frames, h, planes, balls, capsules, NO_TRIANGLES, NO_EDGES, kinds, first, second):
    nodes = centerline(frames, np.zeros(3), h)
    return node_terms(nodes, RADIUS, 1.7, D_HAT * 3, planes, balls, capsules, NO_TRIANGLES, NO_EDGES,
                      np.zeros(0, np.int64), kinds, first, second)


@pytest.mark.parametrize("kind", [STATION_PLANE, SEGMENT_BALL, SEGMENT_CAPSULE, SEGMENT_SEGMENT])
def test_node_gradient_and_hessian_against_finite_differences(kind):
    frames, h = _hose()
    planes, balls, capsules = _obstacles()
    nodes = centerline(frames, np.zeros(3), h)
    kinds, first, second, gaps = pair_gaps(nodes, RADIUS, planes, balls, capsules, 2, 3 * D_HAT)
    chosen = (kinds == kind) & (gaps > 0.05)
    if kind == SEGMENT_SEGMENT:  # a self-contact pair: a loop brought next to the start
        nodes = nodes.copy()
        nodes[8] = nodes[1] + np.array([0.3, 2.6, 0.1])
        nodes[9] = nodes[2] + np.array([-0.2, 2.4, 0.4])
        kinds, first, second = np.array([kind]), np.array([1]), np.array([8])
    else:
        kinds, first, second = kinds[chosen], first[chosen], second[chosen]
    assert kinds.size > 0
    weight, d_hat = 1.7, 3 * D_HAT

    def terms(at):
        return node_terms(at, RADIUS, weight, d_hat, planes, balls, capsules, NO_TRIANGLES, NO_EDGES,
                          np.zeros(0, np.int64), kinds, first, second)

    assert_node_derivatives(terms, nodes, relative=True)


def assert_node_derivatives(terms, nodes, relative: bool = False) -> None:
    """The node gradient of terms(nodes) (contact.node_terms' energy, gradient, Hessian, ...) against central
    differences of its energy, its node Hessian against central differences of the gradient; the absolute
    tolerances scaled by the energy and the Hessian's size when `relative`."""
    energy, grad, hess, *_ = terms(nodes)
    assert energy > 0.0
    grad_atol = 1e-7 * (1 + abs(energy)) if relative else 1e-7
    hess_atol = 1e-5 * (1 + np.max(np.abs(hess))) if relative else 1e-5
    step = 1e-6
    for k in range(nodes.shape[0]):
        for x in range(3):
            plus, minus = nodes.copy(), nodes.copy()
            plus[k, x] += step
            minus[k, x] -= step
            e_p, g_p, *_ = terms(plus)
            e_m, g_m, *_ = terms(minus)
            assert grad[k, x] == pytest.approx((e_p - e_m) / (2 * step), rel=1e-5, abs=grad_atol)
            np.testing.assert_allclose(hess[:, k, :, x], (g_p - g_m) / (2 * step), rtol=1e-4, atol=hess_atol,
                                       err_msg=f"station {k}, axis {x}")


def test_rotation_gradient_and_hessian_against_finite_differences():
    frames, h = _hose()
    planes, balls, capsules = _obstacles()
    nodes = centerline(frames, np.zeros(3), h)
    kinds, first, second, gaps = pair_gaps(nodes, RADIUS, planes, balls, capsules, 2, 3 * D_HAT)
    kinds, first, second = kinds[gaps > 0.05], first[gaps > 0.05], second[gaps > 0.05]
    assert {STATION_PLANE, SEGMENT_BALL, SEGMENT_CAPSULE} <= set(kinds.tolist())

    def terms(fr):
        energy, g, hn, *_ = _energy(fr, h, planes, balls, capsules, NO_TRIANGLES, NO_EDGES, kinds, first, second)
        grad, hess = rotation_terms(fr, h, g, hn)
        return energy, grad, hess

    energy, grad, hess = terms(frames)
    n = 3 * frames.shape[0]
    step = 1e-6
    numeric_grad = np.zeros(n)
    numeric_hess = np.zeros((n, n))
    for a in range(n):
        delta = np.zeros(n)
        delta[a] = step
        e_p, g_p, _ = terms(rotate_frames(frames, delta.reshape(-1, 3)))
        e_m, g_m, _ = terms(rotate_frames(frames, -delta.reshape(-1, 3)))
        numeric_grad[a] = (e_p - e_m) / (2 * step)
        numeric_hess[:, a] = (g_p - g_m) / (2 * step)
    np.testing.assert_allclose(grad, numeric_grad, rtol=1e-5, atol=1e-7 * np.max(np.abs(grad)))
    # the gradient is taken at delta = 0 of each perturbed state: its derivative is the Hessian's
    # symmetric part plus half the commutator of the rotations, as in tests/test_energy_derivatives.py
    symmetric = 0.5 * (numeric_hess + numeric_hess.T)
    np.testing.assert_allclose(hess, symmetric, rtol=1e-4, atol=1e-5 * np.max(np.abs(hess)))
