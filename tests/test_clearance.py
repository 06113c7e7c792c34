"""Clearance: the exact segment-to-triangle distance and the tree search against brute force."""

import numpy as np
import pytest

from hoseline.procedures.clearance import TriangleIndex, brute_force_nearest
from hoseline.procedures.proximity import segment_triangle_distance


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


@pytest.mark.parametrize("seed", range(20))
def test_segment_triangle_distance_is_the_minimum_over_both(seed):
    rng = np.random.default_rng(100 + seed)
    p, q, a, b, c = (tuple(rng.normal(size=3) * 3.0) for _ in range(5))
    distance, x, y = segment_triangle_distance(p, q, a, b, c)
    # closest points lie on the segment and in the triangle, at the distance returned
    assert np.linalg.norm(np.subtract(x, y)) == pytest.approx(distance, abs=1e-12)
    # no sampled pair is nearer (samples of both: a lower bound check on the exact value)
    s = np.linspace(0.0, 1.0, 60)
    on_segment = np.asarray(p) + s[:, None] * np.subtract(q, p)
    u, v = np.meshgrid(s, s)
    keep = u + v <= 1.0
    on_triangle = np.asarray(a) + u[keep][:, None] * np.subtract(b, a) + v[keep][:, None] * np.subtract(c, a)
    sampled = np.min(np.linalg.norm(on_segment[:, None] - on_triangle[None], axis=2))
    assert distance <= sampled + 1e-12
    assert sampled - distance < 0.2


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
