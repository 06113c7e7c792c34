"""The swept envelope: within about a cell of the exact union of the tubes, closed, and within its
budgets for layouts whose dense grid would not fit in memory."""

import numpy as np
import pytest
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from sweep_cases import small_sweep_result  # noqa: F401 (fixture)

from hoseline.procedures.geometry.clearance import TriangleIndex
from hoseline.procedures.sweep import envelope as envelope_module
from hoseline.procedures.sweep.envelope import swept_envelope


def tube_union_distance(points, centerlines, radius):
    """Signed distance (mm) from `points` to the union of the tubes around `centerlines` (brute force, numpy)."""
    starts = centerlines[:, :-1].reshape(-1, 3)
    steps = centerlines[:, 1:].reshape(-1, 3) - starts
    lengths2 = np.maximum(np.einsum("sk,sk->s", steps, steps), 1e-300)
    nearest = np.empty(len(points))
    for first in range(0, len(points), 256):
        p = points[first:first + 256, None, :] - starts
        t = np.clip(np.einsum("psk,sk->ps", p, steps) / lengths2, 0.0, 1.0)
        nearest[first:first + 256] = np.linalg.norm(p - t[..., None] * steps, axis=2).min(axis=1)
    return nearest - radius


def union_surface_points(centerlines, radius, count, seed=1):
    """Points on the surface of the union of the tubes: points on each tube not inside another."""
    rng = np.random.default_rng(seed)
    starts = centerlines[:, :-1].reshape(-1, 3)
    steps = centerlines[:, 1:].reshape(-1, 3) - starts
    pick = rng.integers(0, len(starts), count)
    axis = steps[pick] / np.linalg.norm(steps[pick], axis=1)[:, None]
    normal = np.cross(axis, rng.normal(size=(count, 3)))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    points = starts[pick] + rng.random(count)[:, None] * steps[pick] + radius * normal
    return points[tube_union_distance(points, centerlines, radius) > -1e-9]


def some(points, count=3000, seed=2):
    """At most `count` of `points`, picked at random (the brute-force distance is slow)."""
    return points[np.random.default_rng(seed).permutation(len(points))[:count]]


def check_closed(envelope):
    mesh = trimesh.Trimesh(envelope.vertices, envelope.faces, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0.0
    return mesh


def test_envelope_is_within_a_fraction_of_a_cell_of_the_exact_tube_union(small_sweep_result):
    result = small_sweep_result
    radius = result.sweep.problem.hose.outer_radius
    envelope = swept_envelope(result.centerlines, radius)
    assert envelope.cell == 0.5 * radius and not envelope.coarsened and envelope.radius == radius
    assert on_grid_lines(envelope.vertices, envelope.cell) > 0.6
    check_closed(envelope)
    cell = envelope.cell
    # the mesh lies on the union: measured max 0.26 cell at the vertices, 0.43 cell at the facet centres
    # (where tubes of two poses cross, the facets cut the crease), medians 0.003 and 0.05 cell
    on_vertices = np.abs(tube_union_distance(some(envelope.vertices), result.centerlines, radius)) / cell
    centres = np.abs(tube_union_distance(some(envelope.vertices[envelope.faces].mean(axis=1)), result.centerlines,
                                         radius)) / cell
    assert on_vertices.max() < 0.8 and np.median(on_vertices) < 0.01
    assert centres.max() < 1.3 and np.median(centres) < 0.15
    # and covers all of it: points on the union's surface are near the mesh (measured 0.41 cell at most)
    index = TriangleIndex(envelope.vertices, envelope.faces)
    surface = union_surface_points(result.centerlines, radius, 4000)
    assert len(surface) > 200
    gaps = [index.nearest(np.array([p, p]), 0.0).distance for p in surface]
    assert max(gaps) < 1.25 * cell
    # a finer grid encloses nearly the same volume (measured 0.8 % more at a quarter of the radius)
    finer = check_closed(swept_envelope(result.centerlines, radius, cell=radius / 4))
    assert abs(check_closed(envelope).volume / finer.volume - 1.0) < 0.025


def test_a_tight_budget_coarsens_the_cell_and_reports_the_cell_used(small_sweep_result, monkeypatch):
    result = small_sweep_result
    radius = result.sweep.problem.hose.outer_radius
    monkeypatch.setattr(envelope_module, "NODE_BUDGET", 100_000)
    envelope = swept_envelope(result.centerlines, radius)
    assert envelope.coarsened and envelope.nodes <= 100_000
    check_closed(envelope)
    # the cell reported is the grid's: two of each vertex's three coordinates lie on its lines
    assert on_grid_lines(envelope.vertices, envelope.cell) > 0.6
    assert on_grid_lines(envelope.vertices, envelope.requested_cell) < 0.2
    # the hose (5.05 mm) is thinner than the cell (measured 6.07 mm): widened to it, and meshed accurately
    assert envelope.radius == envelope.cell
    on_vertices = np.abs(tube_union_distance(some(envelope.vertices), result.centerlines, envelope.radius))
    assert on_vertices.max() < 0.8 * envelope.cell and np.median(on_vertices) < 0.01 * envelope.cell  # 0.25, 0.003


def on_grid_lines(vertices, cell):
    """The smallest fraction, over the three axes, of vertex coordinates on the lines of a grid of
    `cell` (mm), whatever the grid's origin: those sharing the most frequent remainder modulo the cell."""
    fractions = []
    for axis in range(3):
        remainder = np.round(np.mod(vertices[:, axis] / cell, 1.0) * 1e4).astype(int) % 10000
        fractions.append(np.bincount(remainder).max() / len(vertices))
    return min(fractions)


def sagging_hoses(length, span, poses, rise, segments=100):
    """(poses, segments + 1, 3) mm: a hose of `length` sagging between fixed mounts `span` apart
    along x, its middle lifted by `rise` (mm) over the poses and swung sideways (a synthetic sweep)."""
    s = np.linspace(0.0, 1.0, segments + 1)
    bow = np.sin(np.pi * s)
    sag = 0.5 * np.sqrt(length**2 - span**2)
    return np.array([np.column_stack([span * s, 0.5 * sag * fraction * bow, (rise * fraction - sag) * bow])
                     for fraction in np.linspace(0.0, 1.0, poses)])


def stray_pieces(mesh):
    """Extents (mm, the diagonal of the bounding box) of the mesh's connected pieces other than the largest."""
    adjacency = coo_matrix((np.ones(len(mesh.face_adjacency)), mesh.face_adjacency.T), shape=(len(mesh.faces),) * 2)
    _, label = connected_components(adjacency, directed=False)
    largest = np.argmax(np.bincount(label))
    corners = [mesh.vertices[mesh.faces[label == piece]].reshape(-1, 3) for piece in set(label) - {largest}]
    return [np.linalg.norm(c.max(axis=0) - c.min(axis=0)) for c in corners]


@pytest.mark.parametrize("length, span, rise, radius", [(3000.0, 2000.0, 1000.0, 3.0), (5000.0, 4990.0, 200.0, 1.0)],
                         ids=["3 m hose moving 1 m", "mounts 5 m apart, thin cable"])
def test_envelope_of_a_large_layout_stays_within_the_budgets_in_one_piece(length, span, rise, radius):
    centerlines = sagging_hoses(length, span, 30, rise)
    low, high = centerlines.reshape(-1, 3).min(axis=0), centerlines.reshape(-1, 3).max(axis=0)
    dense_nodes = np.prod((high - low + 3.0 * radius) / (0.5 * radius))
    assert dense_nodes > 3e8  # a dense grid of half the radius: more than 15 GB at the former 56 bytes per node
    envelope = swept_envelope(centerlines, radius)
    assert envelope.coarsened and envelope.nodes <= envelope_module.NODE_BUDGET
    assert len(envelope.faces) <= envelope_module.TRIANGLE_BUDGET
    # the poses share the mounts: one piece, not broken up (where two tubes nearly touch, marching cubes
    # may leave a speck within a cell: measured 4 of 8 triangles, 1.2 mm across, at a 2.9 mm cell)
    assert all(extent < envelope.cell for extent in stray_pieces(check_closed(envelope)))
    # a tube thinner than a cell is widened (by less than a cell), and meshed as accurately as at the demo's grid
    assert radius <= envelope.radius < radius + envelope.cell
    on_vertices = np.abs(tube_union_distance(some(envelope.vertices), centerlines, envelope.radius)) / envelope.cell
    assert on_vertices.max() < 0.8
    np.testing.assert_allclose(envelope.vertices.min(axis=0), low - envelope.radius, atol=envelope.cell)
    np.testing.assert_allclose(envelope.vertices.max(axis=0), high + envelope.radius, atol=envelope.cell)
