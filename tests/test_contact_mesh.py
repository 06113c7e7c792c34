"""Contact with triangle meshes and boxes (mechanics/contact_mesh.py): derivatives, equilibria, scale, input."""

from dataclasses import replace

import numpy as np
import pytest

from hoseline.mechanics.contact import (
    EDGE_AB,
    EDGE_AC,
    EDGE_BC,
    FACE,
    SEGMENT_EDGE,
    STATION_TRIANGLE,
    VERTEX_A,
    VERTEX_B,
    VERTEX_C,
    node_terms,
    triangle_parameters,
)
from hoseline.mechanics.contact_mesh import pack_meshes

RADIUS, D_HAT, WEIGHT = 1.0, 3.0, 1.7
TRIANGLE = np.array([[0.0, 0.0, 0.0], [4.0, 0.5, 0.3], [1.0, 3.5, -0.4]])
NO_PLANES, NO_BALLS, NO_CAPSULES = np.zeros((0, 6)), np.zeros((0, 4)), np.zeros((0, 7))


def _terms(nodes, triangles, edges, kinds, first, second):
    return node_terms(nodes, RADIUS, WEIGHT, D_HAT, NO_PLANES, NO_BALLS, NO_CAPSULES, triangles, edges,
                      kinds, first, second)


def _check_against_finite_differences(nodes, triangles, edges, kind, first, second):
    """Gradient against central differences of the energy, Hessian against central differences of the gradient."""
    pair = np.array([kind]), np.array([first]), np.array([second])
    energy, grad, hess, *_ = _terms(nodes, triangles, edges, *pair)
    assert energy > 0.0
    step = 1e-6
    for k in range(nodes.shape[0]):
        for x in range(3):
            plus, minus = nodes.copy(), nodes.copy()
            plus[k, x] += step
            minus[k, x] -= step
            e_p, g_p, *_ = _terms(plus, triangles, edges, *pair)
            e_m, g_m, *_ = _terms(minus, triangles, edges, *pair)
            assert grad[k, x] == pytest.approx((e_p - e_m) / (2 * step), rel=1e-5, abs=1e-7)
            numeric = (g_p - g_m) / (2 * step)
            assert np.allclose(hess[:, k, :, x], numeric, rtol=1e-4, atol=1e-5), (k, x)


def _station_over(feature, rng):
    """A point whose nearest feature of TRIANGLE is `feature`, 1.2 to 2.5 mm from it (a gap in (0, d_hat))."""
    a, b, c = TRIANGLE
    normal = np.cross(b - a, c - a)
    normal /= np.linalg.norm(normal)
    u, v = rng.uniform(0.15, 0.35, size=2)
    inside = (1.0 - u - v) * a + u * b + v * c
    targets = {
        FACE: (inside, normal),
        EDGE_AB: (0.6 * a + 0.4 * b, np.cross(b - a, normal)),
        EDGE_AC: (0.3 * a + 0.7 * c, np.cross(normal, c - a)),
        EDGE_BC: (0.5 * b + 0.5 * c, np.cross(c - b, normal)),
        VERTEX_A: (a, -(b - a) - (c - a)),
        VERTEX_B: (b, (b - a) + (b - c)),
        VERTEX_C: (c, (c - a) + (c - b)),
    }
    point, outward = targets[feature]
    outward = outward / np.linalg.norm(outward)
    if feature != FACE:  # off the face's plane as well, as a station beside an edge would be
        outward = outward + rng.uniform(-0.5, 0.5) * normal
        outward /= np.linalg.norm(outward)
    return point + rng.uniform(2.2, 3.5) * outward


@pytest.mark.parametrize("feature", [FACE, EDGE_AB, EDGE_AC, EDGE_BC, VERTEX_A, VERTEX_B, VERTEX_C])
def test_station_triangle_gradient_and_hessian_in_every_region(feature):
    rng = np.random.default_rng(feature)
    for _ in range(5):
        station = _station_over(feature, rng)
        assert triangle_parameters(station, *TRIANGLE)[2] == feature
        nodes = np.array([station - [3.0, 0.2, 0.1], station])
        _check_against_finite_differences(nodes, TRIANGLE[None], np.zeros((0, 2, 3)), STATION_TRIANGLE, 1, 0)


@pytest.mark.parametrize("case", ["crossing", "end on edge", "over an edge end", "end to end"])
def test_segment_edge_gradient_and_hessian(case):
    rng = np.random.default_rng(len(case))
    edge = np.array([[0.0, 0.0, 0.0], [5.0, 0.0, 0.0]])
    for _ in range(5):
        lift = np.array([0.0, 0.0, rng.uniform(2.2, 3.5)])
        if case == "crossing":  # both closest points inside: s, t free
            p, q = np.array([2.0, -2.0, 0.0]), np.array([3.0, 2.0, 0.5])
        elif case == "end on edge":  # the segment's end nearest, inside the edge: t free
            p, q = np.array([2.5, 0.0, 0.0]), np.array([2.0, 1.0, 4.0])
        elif case == "over an edge end":  # inside the segment, at the edge's end: s free
            p, q = np.array([6.0, -2.0, 0.0]), np.array([5.5, 2.0, 0.2])
        else:  # both at ends
            p, q = np.array([6.0, 0.5, 0.0]), np.array([9.0, 1.0, 1.0])
        jitter = 0.1 * rng.standard_normal((2, 3))
        nodes = np.array([p, q]) + lift + jitter
        _check_against_finite_differences(nodes, np.zeros((0, 3, 3)), edge[None], SEGMENT_EDGE, 0, 0)


def test_flat_edges_are_left_out_and_ridges_kept():
    floor = np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]])
    two = pack_meshes([(floor, np.array([[0, 1, 2], [0, 2, 3]]))], [0])
    assert two.edges.shape[0] == 4  # the boundary, not the diagonal
    folded = floor.copy()
    folded[3, 2] = 0.5  # the second triangle tilted up about the diagonal: a valley, kept
    assert pack_meshes([(folded, np.array([[0, 1, 2], [0, 2, 3]]))], [0]).edges.shape[0] == 5
    sliver = np.vstack([floor, [[0.0, 0.0, 0.0]]])  # a zero-area triangle on the diagonal is left out
    with_sliver = pack_meshes([(sliver, np.array([[0, 1, 2], [0, 2, 3], [0, 4, 2]]))], [0])
    assert with_sliver.triangles.shape[0] == 2
