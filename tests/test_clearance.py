"""Clearance: the exact segment-to-triangle distance and the tree search against brute force."""

import math

import numpy as np
import pytest
from numba import njit
from scipy.optimize import minimize

from hoseline.procedures.geometry.clearance import TriangleIndex
from hoseline.mechanics.proximity import segment_triangle_distance


def brute_force_nearest(nodes, vertices, faces):
    """Centreline-to-mesh distance (mm) by testing every segment against every triangle."""
    return _brute_force(np.asarray(nodes, dtype=float), np.asarray(vertices, dtype=float)[np.asarray(faces)])


@njit  # no disk cache: Numba's would keep an old segment_triangle_distance (hoseline/compilation.py)
def _brute_force(nodes, triangles):
    best = math.inf
    for i in range(nodes.shape[0] - 1):
        p = (nodes[i, 0], nodes[i, 1], nodes[i, 2])
        q = (nodes[i + 1, 0], nodes[i + 1, 1], nodes[i + 1, 2])
        for t in range(triangles.shape[0]):
            a, b, c = triangles[t]
            d, _, _ = segment_triangle_distance(p, q, (a[0], a[1], a[2]), (b[0], b[1], b[2]), (c[0], c[1], c[2]))
            best = min(best, d)
    return best


def random_mesh(rng, count, centre, spread):
    vertices = centre + spread * rng.normal(size=(count, 3))
    faces = rng.integers(0, count, size=(2 * count, 3))
    return vertices, faces


def random_hose(rng, nodes=15, step=6.0):
    return np.cumsum(step * rng.normal(size=(nodes, 3)), axis=0)


@pytest.mark.parametrize("seed", range(12))
def test_tree_search_equals_brute_force(seed):
    rng = np.random.default_rng(seed)
    centre = rng.normal(size=3) * 40.0  # sometimes crossing the hose, sometimes far from it
    vertices, faces = random_mesh(rng, 200, centre, 15.0)
    index = TriangleIndex(vertices, faces)
    for _ in range(3):  # the hint from the last query must not change the answer
        nodes = random_hose(rng)
        found = index.nearest(nodes, outer_radius=2.0)
        assert found.distance + 2.0 == pytest.approx(brute_force_nearest(nodes, vertices, faces), abs=1e-9)
        assert np.linalg.norm(found.on_hose - found.on_obstacle) == pytest.approx(found.distance + 2.0, abs=1e-9)
        assert 0.0 <= found.s <= np.sum(np.linalg.norm(np.diff(nodes, axis=0), axis=1)) + 1e-9


def reference_distance(p, q, a, b, c):
    """Segment-triangle distance as the convex problem it is: min |p + s (q - p) - (a + u (b - a) + v (c - a))|
    over 0 <= s <= 1, u, v >= 0, u + v <= 1, solved by SLSQP (a method independent of the one under test)."""
    p, q, a, b, c = (np.asarray(x, dtype=float) for x in (p, q, a, b, c))
    axes = np.column_stack([q - p, a - b, a - c])

    def squared(x):
        gap = p - a + axes @ x
        return gap @ gap, 2.0 * axes.T @ gap

    simplex = {"type": "ineq", "fun": lambda x: 1.0 - x[1] - x[2], "jac": lambda x: np.array([0.0, -1.0, -1.0])}
    best = min(minimize(squared, start, jac=True, method="SLSQP", bounds=[(0.0, 1.0)] * 3, constraints=[simplex],
                        options={"ftol": 1e-16, "maxiter": 500}).fun
               for start in ([0.5, 1 / 3, 1 / 3], [0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]))
    return math.sqrt(max(best, 0.0))


def segment_near_triangle(rng, kind):
    """Random cases, and the awkward ones: segments parallel to the face (above it and in its plane),
    parallel to an edge, and aimed at a corner."""
    a, b, c = (rng.normal(size=3) * 3.0 for _ in range(3))
    if kind == "random":
        return tuple(rng.normal(size=3) * 3.0), tuple(rng.normal(size=3) * 3.0), tuple(a), tuple(b), tuple(c)
    normal = np.cross(b - a, c - a)
    height = rng.choice([0.0, 0.5, -2.0]) * normal / np.linalg.norm(normal)
    u, v = rng.uniform(-0.5, 1.2, 2), rng.uniform(-0.5, 1.2, 2)
    p = a + u[0] * (b - a) + v[0] * (c - a) + height
    q = {"parallel to the face": a + u[1] * (b - a) + v[1] * (c - a) + height,
         "parallel to an edge": p + rng.uniform(-2.0, 2.0) * (b - a),
         "aimed at a corner": p + rng.uniform(0.5, 2.0) * (a - p)}[kind]
    return tuple(p), tuple(q), tuple(a), tuple(b), tuple(c)


@pytest.mark.parametrize("kind", ["random", "parallel to the face", "parallel to an edge", "aimed at a corner"])
def test_segment_triangle_distance_is_exact(kind):
    rng = np.random.default_rng(len(kind))
    for _ in range(25):
        p, q, a, b, c = segment_near_triangle(rng, kind)
        distance, x, y = segment_triangle_distance(p, q, a, b, c)
        # closest points lie on the segment and in the triangle, at the distance returned
        assert np.linalg.norm(np.subtract(x, y)) == pytest.approx(distance, abs=1e-12)
        assert distance == pytest.approx(reference_distance(p, q, a, b, c), abs=1e-6)


def test_crossing_segment_has_zero_distance():
    distance, x, _ = segment_triangle_distance((0.2, 0.2, -1.0), (0.2, 0.2, 1.0), (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    assert distance == 0.0
    np.testing.assert_allclose(x, [0.2, 0.2, 0.0])


def test_degenerate_triangles_are_their_edges():
    distance, _, _ = segment_triangle_distance((0.0, 1.0, 0.0), (1.0, 1.0, 0.0), (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (2.0, 0.0, 0.0))
    assert distance == pytest.approx(1.0)


def test_step_obstacles_are_tessellated_by_opencascade(tmp_path):
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    from OCP.STEPControl import STEPControl_StepModelType, STEPControl_Writer

    from hoseline.io.obstacle_mesh import read_mesh

    writer = STEPControl_Writer()
    writer.Transfer(BRepPrimAPI_MakeBox(10.0, 20.0, 30.0).Shape(), STEPControl_StepModelType.STEPControl_AsIs)
    writer.Write(str(tmp_path / "box.step"))
    vertices, faces = read_mesh(tmp_path / "box.step")
    assert len(faces) == 12
    np.testing.assert_allclose(vertices.max(axis=0) - vertices.min(axis=0), [10.0, 20.0, 30.0])
    nodes = np.array([[5.0, 10.0, 40.0], [5.0, 10.0, 50.0]])  # 10 mm above the top face
    assert TriangleIndex(vertices, faces).nearest(nodes, 0.0).distance == pytest.approx(10.0)
