"""Contact with triangle meshes and boxes (mechanics/contact_mesh.py): derivatives, equilibria, scale, input."""

from dataclasses import replace

import numpy as np
import pytest
from test_contact_derivatives import assert_node_derivatives

from hoseline.mechanics.contact import (
    EDGE_AB,
    EDGE_AC,
    EDGE_BC,
    FACE,
    SEGMENT_CAPSULE,
    SEGMENT_EDGE,
    STATION_PLANE,
    STATION_TRIANGLE,
    VERTEX_A,
    VERTEX_B,
    VERTEX_C,
    node_terms,
    triangle_parameters,
)
from hoseline.mechanics.contact_mesh import pack_meshes
from hoseline.mechanics.rod import centerline

RADIUS, D_HAT, WEIGHT = 1.0, 3.0, 1.7
TRIANGLE = np.array([[0.0, 0.0, 0.0], [4.0, 0.5, 0.3], [1.0, 3.5, -0.4]]) + [1.3, -0.7, 0.4]  # off the origin (a wrong sign of a corner's coefficient shows)
NO_PLANES, NO_BALLS, NO_CAPSULES = np.zeros((0, 6)), np.zeros((0, 4)), np.zeros((0, 7))


def _terms(nodes, triangles, edges, kinds, first, second):
    return node_terms(nodes, RADIUS, WEIGHT, D_HAT, NO_PLANES, NO_BALLS, NO_CAPSULES, triangles, edges,
                      np.zeros(len(triangles), np.int64), kinds, first, second)


def _check_against_finite_differences(nodes, triangles, edges, kind, first, second):
    """Gradient against central differences of the energy, Hessian against central differences of the gradient."""
    pair = np.array([kind]), np.array([first]), np.array([second])
    assert_node_derivatives(lambda at: _terms(at, triangles, edges, *pair), nodes)


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
    offset = np.array([0.6, 1.1, -0.3])  # off the origin, where a wrong sign of a point's coefficient shows
    edge = np.array([[0.0, 0.0, 0.0], [5.0, 0.0, 0.0]]) + offset
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
        nodes = np.array([p, q]) + lift + jitter + offset
        _check_against_finite_differences(nodes, np.zeros((0, 3, 3)), edge[None], SEGMENT_EDGE, 0, 0)


def test_segment_edge_terms_are_those_of_a_capsule_of_no_radius_on_the_edge():
    """The written-out segment-edge terms (contact.segment_edge_terms) against the general envelope formulas of a
    segment-capsule pair whose capsule is the edge with radius 0, in every region and near parallel."""
    rng = np.random.default_rng(11)
    edge = np.array([[0.6, 1.1, -0.3], [5.6, 1.4, -0.1]])
    capsule = np.concatenate([edge.ravel(), [0.0]])[None]
    regions = set()
    for trial in range(400):
        along = edge[1] - edge[0]
        p = edge[0] + rng.uniform(-0.4, 1.4) * along + rng.normal(scale=1.5, size=3) + [0.0, 0.0, 2.5]
        q = p + (rng.uniform(0.5, 1.5) * along / 5.0 + 0.02 * rng.standard_normal(3) if trial % 4 == 0  # near parallel
                 else rng.normal(scale=2.0, size=3))
        nodes = np.array([p, q])
        pair = np.zeros(1, np.int64), np.zeros(1, np.int64)
        as_edge = node_terms(nodes, RADIUS, WEIGHT, 20.0, NO_PLANES, NO_BALLS, NO_CAPSULES, np.zeros((0, 3, 3)),
                             edge[None], np.zeros(0, np.int64), np.array([SEGMENT_EDGE]), *pair)
        as_capsule = node_terms(nodes, RADIUS, WEIGHT, 20.0, NO_PLANES, NO_BALLS, capsule, np.zeros((0, 3, 3)),
                                np.zeros((0, 2, 3)), np.zeros(0, np.int64), np.array([SEGMENT_CAPSULE]), *pair)
        if not 0.0 < as_edge[6][0] < 20.0:  # within the barrier's reach
            continue
        for mine, general in zip(as_edge, as_capsule):
            np.testing.assert_allclose(mine, general, rtol=1e-9, atol=1e-9 * np.max(np.abs(general)))
        s = np.dot(as_edge[4][0] - p, q - p) / np.dot(q - p, q - p)
        t = np.dot(as_edge[5][0] - edge[0], along) / np.dot(along, along)
        regions.add((bool(1e-9 < s < 1.0 - 1e-9), bool(1e-9 < t < 1.0 - 1e-9)))
    assert regions == {(True, True), (True, False), (False, True), (False, False)}


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


def _station_energy(mesh, station: np.ndarray) -> float:
    """The barrier energy (b summed, mm^2) of one station's pairs with `mesh` (RADIUS, D_HAT), no segment pairs."""
    from hoseline.mechanics.contact import barrier

    nodes = np.array([station + 1e4, station])  # the held station 0 far off; the segment's pairs cut off
    gaps = mesh.pairs(nodes, RADIUS, (np.full(2, D_HAT), np.full(1, -2.0 * RADIUS)))[3]
    return sum(barrier(gap, D_HAT)[0] for gap in gaps)


def _energy_steps(mesh, start: np.ndarray, direction: np.ndarray) -> list[float]:
    """The steps in the station's energy along start + t direction, t in [0, 1], that do not shrink with the step:
    each largest change between 100 samples narrowed by bisection to 1e-13 of the line."""
    samples = np.linspace(0.0, 1.0, 101)
    energies = [_station_energy(mesh, start + t * direction) for t in samples]
    if not np.all(np.isfinite(energies)):  # the line enters the mesh: left out
        return []
    changes = np.abs(np.diff(energies))
    steps = []
    for i in np.flatnonzero(changes > 10.0 * np.median(changes) + 1e-12):
        (low, e_low), (high, e_high) = (samples[i], energies[i]), (samples[i + 1], energies[i + 1])
        while high - low > 1e-13:
            middle = 0.5 * (low + high)
            e_middle = _station_energy(mesh, start + middle * direction)
            if abs(e_middle - e_low) > abs(e_high - e_middle):
                high, e_high = middle, e_middle
            else:
                low, e_low = middle, e_middle
        if abs(e_high - e_low) > 1e-9:
            steps.append(abs(e_high - e_low))
    return steps


@pytest.mark.parametrize("shape", ["box", "subdivided box", "faceted tube", "tube with T-junctions"])
def test_a_station_s_barrier_energy_has_no_step_anywhere_near_a_mesh(shape):
    """Lines of stations past vertices, edges and faces of meshes with flat and sharp features: the summed barrier
    changes continuously.  Before, a triangle's vertex on a sharp edge was paired wherever the station was in its
    vertex region, also where a neighbour in its plane was nearer, and a pair appeared or left at a gap within
    d_hat: steps of about half a pair's energy on boxes and faceted struts, Newton stalled on them (a placement past
    a faceted strut failed "no descent step found")."""
    import trimesh

    if shape == "tube with T-junctions":  # each triangle cut alone until no edge is longer than 8 mm
        tube = trimesh.creation.cylinder(15.0, 60.0, sections=24)
        surface = trimesh.Trimesh(*trimesh.remesh.subdivide_to_size(tube.vertices, tube.faces, max_edge=8.0))
    elif shape == "faceted tube":
        surface = trimesh.creation.annulus(r_min=14.0, r_max=15.0, height=60.0, sections=24)
    else:
        surface = trimesh.creation.box(extents=[20.0, 20.0, 20.0])
        surface = surface.subdivide().subdivide() if shape == "subdivided box" else surface
    mesh = pack_meshes([(np.asarray(surface.vertices), np.asarray(surface.faces))], [0])
    rng = np.random.default_rng(11)
    steps, lines = [], 0
    for corner in rng.choice(len(surface.vertices), size=40):
        normal = surface.vertex_normals[corner]
        start = surface.vertices[corner] + normal * (RADIUS + rng.uniform(0.2, 0.8) * D_HAT) + rng.normal(size=3)
        direction = 2.0 * rng.normal(size=3)
        if np.isfinite(_station_energy(mesh, start)) and np.isfinite(_station_energy(mesh, start + direction)):
            lines += 1
            steps += _energy_steps(mesh, start, direction)
    assert lines > 20 and steps == []


def test_a_packing_is_kept_by_content_for_new_problems_with_the_same_mesh(monkeypatch):
    from hoseline.mechanics import contact_mesh

    monkeypatch.setattr(contact_mesh, "_PACKED", type(contact_mesh._PACKED)())
    vertices, faces = _grid_floor(4)
    first = pack_meshes([(vertices, faces)], [0])
    again = pack_meshes([(vertices.copy(), faces.copy())], [0])  # the same content, read again
    assert again.triangles is first.triangles and again.triangle_tree[0] is first.triangle_tree[0]
    assert again.leaf_lists is not first.leaf_lists  # each model keeps its own
    moved = vertices.copy()
    moved[7, 2] += 1e-9
    other_faces = faces[:, [0, 2, 1]]  # the same triangles, the other way round
    for changed in (pack_meshes([(moved, faces)], [0]), pack_meshes([(vertices, other_faces)], [0]),
                    pack_meshes([(vertices, faces)], [1]), pack_meshes([(vertices, faces), (vertices, faces)], [0, 1])):
        assert changed.triangles is not first.triangles
    fresh = contact_mesh._packed_meshes([(moved, faces)], [0])
    np.testing.assert_array_equal(pack_meshes([(moved, faces)], [0]).triangles, fresh.triangles)
    assert pack_meshes([(vertices, faces)], [0]).triangles is not first.triangles  # four others since: forgotten
    assert len(contact_mesh._PACKED) == contact_mesh.PACKED_KEPT


# --- equilibria: a mesh floor is the plane, a faceted drum the cylinder, a box edge carries its share ---

LENGTH, EI, MASS, HALF_SPAN, HEIGHT, HOSE_RADIUS = 1000.0, 2e4, 0.5, 420.0, 150.0, 5.0
HOSE_WEIGHT = MASS * 9.81e-3  # N/mm


def _follow(obstacle, problem, end, pressure, placed=None):
    """The problem placed without contact (end high, clear of the obstacle), then its end carried to `end` with
    contact on: (props, clamps, state, model, contact forces and gaps at the end)."""
    from hoseline.mechanics.contact_newton import evaluate_contact, minimum_gap
    from hoseline.procedures.contact.continuation import follow_contact
    from hoseline.procedures.contact.model import contact_model
    from hoseline.procedures.placement.sequence import place_only

    props, high, state, _ = placed or place_only(problem)
    model = contact_model([obstacle], HOSE_RADIUS, props.segment_length, pressure)
    assert minimum_gap(props, high, state, model) > 10.0

    def path(t):
        return replace(high, end_point=(1.0 - t) * high.end_point + t * np.asarray(end))

    state, _ = follow_contact("carry the end", path, props, state, model)
    system = evaluate_contact(props, path(1.0), state, model)
    return props, path(1.0), state, model, system, minimum_gap(props, path(1.0), state, model)


@pytest.fixture(scope="module")
def hanging_hose():
    from hoseline.model.hose import Hose
    from hoseline.model.mounts import Mount
    from hoseline.model.problem import Problem
    from hoseline.procedures.placement.sequence import place_only

    hose = Hose(length=LENGTH, outer_diameter=2 * HOSE_RADIUS, bending_stiffness=EI, torsional_stiffness=EI,
                mass_per_length=MASS, segments=100)
    down = np.array([0.0, 0.0, -1.0])
    problem = Problem(hose, Mount(np.array([-HALF_SPAN, 0.0, HEIGHT]), down), Mount(np.array([300.0, 0.0, 500.0]), down),
                      gravity=np.array([0.0, 0.0, -9.81]))
    return problem, place_only(problem)


def test_a_two_triangle_floor_gives_the_plane_s_equilibrium(hanging_hose):
    from hoseline.model.obstacles import Mesh, Plane
    from hoseline.procedures.contact.model import reference_pressure

    problem, placed = hanging_hose
    pressure = reference_pressure(HOSE_WEIGHT, EI, LENGTH)
    end = [HALF_SPAN, 0.0, HEIGHT]
    plane = _follow(Plane(np.zeros(3), np.array([0.0, 0.0, 1.0]), "floor"), problem, end, pressure, placed)
    # an irregular quadrilateral in the plane z = 0, split along a diagonal the hose lies across
    tiles = Mesh(np.array([[-700.0, -300.0, 0.0], [700.0, -250.0, 0.0], [650.0, 300.0, 0.0], [-600.0, 350.0, 0.0]]),
                 np.array([[0, 1, 2], [0, 2, 3]]), "floor")
    mesh = _follow(tiles, problem, end, pressure, placed)
    nodes = [centerline(result[2].frames, result[1].start_point, result[0].segment_length) for result in (plane, mesh)]
    assert np.max(np.abs(nodes[0] - nodes[1])) < 1e-8  # mm
    np.testing.assert_allclose(mesh[2].end_force, plane[2].end_force, rtol=1e-9, atol=1e-12)
    assert mesh[4].forces[:, 2].sum() == pytest.approx(plane[4].forces[:, 2].sum(), rel=1e-9)
    assert mesh[4].gaps.size == plane[4].gaps.size == 45  # the same stations touch
    assert 0.0 < mesh[5] < mesh[3].activation and mesh[5] == pytest.approx(plane[5], rel=1e-6)


def _grid_floor(cells, size=(800.0, 400.0), turn=0.0, shift=(0.0, 0.0)):
    """A floor in z = 0 of cells x cells rectangles (each split along a diagonal) covering `size` mm about the origin,
    turned by `turn` degrees about z and shifted by `shift` mm: (vertices, faces), 2 cells^2 triangles."""
    x, y = np.meshgrid(np.linspace(-size[0] / 2, size[0] / 2, cells + 1), np.linspace(-size[1] / 2, size[1] / 2, cells + 1),
                       indexing="ij")
    c, s = np.cos(np.radians(turn)), np.sin(np.radians(turn))
    vertices = np.column_stack([c * x.ravel() - s * y.ravel() + shift[0], s * x.ravel() + c * y.ravel() + shift[1],
                                np.zeros(x.size)])
    a = (np.arange(cells)[:, None] * (cells + 1) + np.arange(cells)[None, :]).ravel()
    return vertices, np.concatenate([np.column_stack([a, a + cells + 1, a + cells + 2]),
                                     np.column_stack([a, a + cells + 2, a + 1])])


def test_a_station_over_a_grid_floor_pairs_with_one_triangle_on_its_edges_and_vertices_too():
    # a station on a flat edge or vertex, or within rounding of one, is the triangles' there tie: one of them takes
    # it (before, a station within about 7e-5 mm of a flat edge paired with both: a double barrier)
    mesh = pack_meshes([_grid_floor(16)], [0])  # 50 x 25 mm cells
    offsets = (0.0, 1e-16, -1e-16, 5e-16, -5e-16, 2e-15, -2e-15, 1e-9, -1e-9, 1e-5, -1e-5, 1e-3, -1e-3)
    for x in (-350.0, -50.0, 0.0, 150.0, -37.5):  # vertices' x, and a diagonal's middle
        for y in (0.0, 25.0, -175.0, 12.5):
            for dx in offsets:
                for dy in offsets:
                    nodes = np.array([[-1000.0, 0.0, 100.0], [x + dx, y + dy, 5.001]])
                    kinds, _, _, gaps = mesh.pairs(nodes, 5.0, 1.0)
                    assert kinds.size == 1 and gaps[0] == pytest.approx(0.001, abs=1e-12), (x + dx, y + dy, gaps)


def test_a_station_over_a_flat_edge_or_vertex_has_the_plane_s_energy_gradient_and_hessian():
    # over a grid floor's diagonal or a vertex amid it (to rounding), the nearest triangle's closest feature is that
    # edge or vertex; the distance to the floor is the plane's, flat along it: measured as the edge's or vertex's,
    # its Hessian bent the barrier's push about the feature (a negative curvature of push / distance), and a heavy
    # hose on a plate lost its stability where it had none

    mesh = pack_meshes([_grid_floor(4)], [0])  # 200 x 100 mm cells
    plane = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 1.0]])
    for x, y in ((-100.0, -50.0), (0.0, 0.0), (50.0, 25.0), (50.0 + 1e-13, 25.0), (-50.0, -25.0 - 1e-13)):
        nodes = np.array([[-1000.0, 0.0, 100.0], [x, y, RADIUS + 0.4 * D_HAT]])
        kinds, first, second, _ = mesh.pairs(nodes, RADIUS, D_HAT)
        assert list(kinds) == [STATION_TRIANGLE]
        on_mesh = node_terms(nodes, RADIUS, WEIGHT, D_HAT, NO_PLANES, NO_BALLS, NO_CAPSULES, mesh.triangles,
                             mesh.edges, mesh.planar, kinds, first, second)
        on_plane = node_terms(nodes, RADIUS, WEIGHT, D_HAT, plane, NO_BALLS, NO_CAPSULES, mesh.triangles, mesh.edges,
                              mesh.planar, np.array([STATION_PLANE]), np.array([1]), np.array([0]))
        for mine, plane_s in zip(on_mesh[:3], on_plane[:3]):
            np.testing.assert_allclose(mine, plane_s, rtol=1e-9, atol=1e-9)


def test_a_segment_across_a_straight_ridge_cut_into_rows_pairs_with_one_of_its_edges_at_the_joint():
    # a roof of two rows: its ridge is two edges in a straight line, the joint at the origin; a segment across the
    # ridge at y from the joint pairs with one of them (before, with both within about 7e-5 mm on one side)
    vertices = np.array([[x, y, -abs(x) / 5.0] for y in (-10.0, 0.0, 10.0) for x in (-5.0, 0.0, 5.0)])
    faces = np.array([[a, a + 1, a + 4] for a in (0, 1, 3, 4)] + [[a, a + 4, a + 3] for a in (0, 1, 3, 4)])
    mesh = pack_meshes([(vertices, faces)], [0])
    for y in (0.0, 1e-16, -1e-16, 1e-8, -1e-8, 1e-5, -1e-5, 1e-3, -1e-3, 3.0, -3.0):
        kinds, _, _, gaps = mesh.pairs(np.array([[-3.0, y, 5.001], [3.0, y, 5.001]]), 5.0, 1.0)
        assert np.count_nonzero(kinds == SEGMENT_EDGE) == 1, y
        assert gaps[kinds == SEGMENT_EDGE][0] == pytest.approx(0.001, abs=1e-12)


HEAVY_HOSE = {"hose": {"length": 400.0, "outer_diameter": 10.0, "bending_stiffness": 500.0, "torsional_stiffness": 500.0,
                       "mass_per_length": 0.5, "segments": 30},
              "start": {"point": [-150.0, 0.0, 150.0], "direction": [1.0, 0.0, 0.0]},
              "end": {"point": [150.0, 0.0, 50.0], "direction": [-1.0, 0.0, 0.0]},
              "environment": {"gravity": [0.0, 0.0, -9.81]},
              "contact": {"obstacles": [{"kind": "plane", "point": [0, 0, 0], "normal": [0, 0, 1], "name": "floor"}]}}


@pytest.fixture(scope="module")
def lowered_onto_the_plane():
    from hoseline.io.problem_file import problem_from_dict
    from hoseline.procedures.placement.sequence import solve

    problem = problem_from_dict(HEAVY_HOSE)
    return problem, solve(problem, estimate_error=False)


@pytest.mark.parametrize("cells, turn, shift", [(16, 0.0, (0.0, 0.0)), (32, 0.0, (0.0, 0.0)), (16, 10.0, (3.7, 5.3)),
                                                (16, -np.degrees(np.arctan(0.5)), (0.0, 0.0))],
                         ids=["512-along-an-edge-line", "2048", "512-turned-and-shifted", "512-along-diagonals"])
def test_a_heavy_hose_lowered_onto_a_grid_floor_rests_as_on_the_plane(lowered_onto_the_plane, cells, turn, shift):
    # the hose lies in y = 0 from a start at x = -150: with 50 x 25 mm cells on a grid line through vertices,
    # turned by -atan(1/2) along the cells' diagonals; the 512-triangle floor failed to place before
    from hoseline.model.obstacles import Mesh
    from hoseline.procedures.placement.sequence import solve

    problem, plane = lowered_onto_the_plane
    mesh = solve(replace(problem, contact=(Mesh(*_grid_floor(cells, turn=turn, shift=shift), "floor"),)),
                 estimate_error=False)
    assert np.max(np.abs(mesh.centerline - plane.centerline)) < 1e-7  # mm; measured 8.8e-9
    assert mesh.contacts[0].total_force[2] == pytest.approx(plane.contacts[0].total_force[2], rel=5e-7)  # 5.6e-8
    assert mesh.contacts[0].gap.size == plane.contacts[0].gap.size == 5 and mesh.stable
    assert mesh.contacts[0].min_gap == pytest.approx(plane.contacts[0].min_gap, rel=1e-6)


def _faceted_drum(facets, rows=1, radius=40.0, half_length=200.0):
    """A cylinder of `radius` about the y axis cut into `facets` flat sides (vertices on the circle) and `rows`
    rings: (vertices, faces), 2 facets rows triangles."""
    angles = 2.0 * np.pi * (np.arange(facets) + 0.5) / facets
    ys = np.linspace(-half_length, half_length, rows + 1)
    vertices = np.array([[radius * np.cos(a), y, radius * np.sin(a)] for y in ys for a in angles])
    faces = []
    for row in range(rows):
        for k in range(facets):
            a, b = row * facets + k, row * facets + (k + 1) % facets
            faces += [[a, b, b + facets], [a, b + facets, a + facets]]
    return vertices, np.array(faces)


@pytest.fixture(scope="module")
def pulled_over_a_drum():
    from hoseline.model.hose import Hose
    from hoseline.model.mounts import Mount
    from hoseline.model.obstacles import Cylinder
    from hoseline.model.problem import Problem
    from hoseline.procedures.contact.model import bend_length, reference_pressure
    from hoseline.procedures.placement.sequence import place_only

    hose = Hose(length=335.0, outer_diameter=2 * HOSE_RADIUS, bending_stiffness=1e5, torsional_stiffness=1e5,
                segments=100)
    up = np.array([0.0, 0.0, 1.0])
    problem = Problem(hose, Mount(np.array([-100.0, 0.0, -80.0]), up), Mount(np.array([60.0, 0.0, 150.0]), up))
    drum = Cylinder(np.array([0.0, -200.0, 0.0]), np.array([0.0, 200.0, 0.0]), 40.0, "drum")
    pressure = reference_pressure(0.0, 1e5, bend_length(335.0, [drum], HOSE_RADIUS))
    placed = place_only(problem)
    end = [100.0, 0.0, -80.0]
    return problem, placed, end, pressure, _follow(drum, problem, end, pressure, placed)


def _against_the_drum(faceted, round_drum):
    """(largest station distance mm, end force difference N) of two drum results."""
    nodes = [centerline(result[2].frames, result[1].start_point, result[0].segment_length) for result in (faceted, round_drum)]
    return float(np.max(np.abs(nodes[0] - nodes[1]))), float(np.linalg.norm(faceted[2].end_force - round_drum[2].end_force))


def test_a_faceted_drum_agrees_with_the_cylinder_within_its_faceting(pulled_over_a_drum):
    from hoseline.model.obstacles import Mesh

    problem, placed, end, pressure, round_drum = pulled_over_a_drum
    differences = []
    for facets in (64, 128):
        faceted = _follow(Mesh(*_faceted_drum(facets), "drum"), problem, end, pressure, placed)
        sagitta = 40.0 * (1.0 - np.cos(np.pi / facets))  # how far a facet's middle lies inside the circle
        assert 0.0 < faceted[5] < faceted[3].activation
        # the drum's push balances the mounts (the problem is symmetric: twice the end's vertical force)
        push = faceted[4].forces.sum(axis=0)
        assert push[2] == pytest.approx(-2.0 * faceted[2].end_force[2], rel=1e-6)
        distance, force = _against_the_drum(faceted, round_drum)
        assert distance < sagitta, (facets, distance, sagitta)  # measured 0.041 of 0.048, 0.011 of 0.012 mm
        differences.append(force)
    assert differences[1] < 0.25 * differences[0]  # 1.5 against 11.3 N of 570 N: converging as the facets shrink


def test_a_drum_of_100000_triangles_is_searched_not_looped_over(pulled_over_a_drum):
    import time

    from hoseline.model.obstacles import Mesh
    from hoseline.procedures.contact.model import contact_model

    problem, placed, end, pressure, round_drum = pulled_over_a_drum
    vertices, faces = _faceted_drum(500, rows=100)
    assert faces.shape[0] == 100_000
    drum = Mesh(vertices, faces, "drum")
    faceted = _follow(drum, problem, end, pressure, placed)
    distance, _ = _against_the_drum(faceted, round_drum)
    assert distance < 0.01 and 0.0 < faceted[5] < faceted[3].activation  # 500 facets: sagitta 0.0008 mm
    # one search of the pairs near the hose: the tree opens a few dozen boxes per station, where a loop over
    # all 100 000 triangles for each of 101 stations would take some 100 ms
    model = contact_model([drum], HOSE_RADIUS, faceted[0].segment_length, pressure)
    nodes = centerline(faceted[2].frames, faceted[1].start_point, faceted[0].segment_length)
    times = []
    for _ in range(5):
        begin = time.perf_counter()
        kinds = model.pairs(nodes, model.activation)[0]
        times.append(time.perf_counter() - begin)
    assert kinds.size > 0 and np.median(times) < 0.02, times


def test_pairs_found_through_the_tree_are_those_of_all_triangles():
    rng = np.random.default_rng(3)
    vertices, faces = _faceted_drum(24, rows=6)
    vertices = vertices + 0.5 * rng.standard_normal(vertices.shape)  # ridges and valleys in every direction
    mesh = pack_meshes([(vertices, faces)], [0])
    nodes = np.cumsum(np.vstack([[[-60.0, -30.0, 38.0]], 6.0 * rng.standard_normal((30, 3)) + [4.0, 2.0, 0.0]]), axis=0)

    def one_leaf(items):  # a tree of a single leaf holding every item: the search is a loop over all of them
        return (items.min(axis=(0, 1))[None], items.max(axis=(0, 1))[None], -np.ones((1, 2), np.int64),
                np.array([[0, items.shape[0]]]))

    looped = replace(mesh, triangle_tree=one_leaf(mesh.triangles), edge_tree=one_leaf(mesh.edges),
                     triangle_roots=np.zeros(1, np.int64), edge_roots=np.zeros(1, np.int64))
    for every_feature in (False, True):
        found = mesh.pairs(nodes, 2.0, 6.0, every_feature=every_feature)
        brute = looped.pairs(nodes, 2.0, 6.0, every_feature=every_feature)
        assert found[0].size > 20
        assert sorted(zip(*[a.tolist() for a in found[:3]])) == sorted(zip(*[a.tolist() for a in brute[:3]]))



@pytest.mark.parametrize("rows", [4, 60])  # 192 triangles: walked in one call; 2880: through leaf lists
def test_a_hose_cutting_into_a_mesh_gets_one_pair_inside_and_a_clear_hose_all_of_its_pairs(rows):
    """stop_inside (the contact Newton's evaluations): a hose cutting into a mesh gets the first pair found at a gap of
    zero or less alone, one of the pairs of every feature; a clear hose the same pairs as without it, to the bit."""
    mesh = pack_meshes([_faceted_drum(24, rows=rows)], [0])
    xs = np.arange(-60.0, 61.0, 1.0)
    through = np.column_stack([xs, np.full_like(xs, 3.0), np.full_like(xs, 30.0)])  # crosses the drum's wall twice
    over = through + [0.0, 0.0, 13.0]  # 1.3 mm over the top facets
    stopped = mesh.pairs(through, 2.0, 6.0, stop_inside=True)
    every = mesh.pairs(through, 2.0, 6.0, every_feature=True)
    assert np.min(every[3]) <= 0.0 and every[0].size > 100
    assert stopped[0].size == 1 and stopped[3][0] <= 0.0
    assert (stopped[0][0], stopped[1][0], stopped[2][0], stopped[3][0]) in set(zip(*[a.tolist() for a in every]))
    listed, clear = mesh.pairs(over, 2.0, 6.0), mesh.pairs(over, 2.0, 6.0, stop_inside=True)
    assert np.min(listed[3]) > 0.0 and listed[0].size > 20
    assert all(np.array_equal(a, b) for a, b in zip(listed, clear))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_one_walk_down_both_trees_finds_the_leaves_of_a_walk_per_segment(seed):
    from hoseline.mechanics.bounding_volumes import LEAF_SIZE, build_tree, chain_tree, leaf_within, leaves_within

    rng = np.random.default_rng(seed)
    corners = rng.uniform(-50.0, 50.0, (3000, 1, 3)) + rng.normal(scale=2.0, size=(3000, 3, 3))
    order, lower, upper, children, ranges = build_tree(corners.min(axis=1), corners.max(axis=1), corners.mean(axis=1),
                                                       LEAF_SIZE)
    count = int(rng.integers(1, 60))  # any chain length, not only powers of two
    starts = np.cumsum(rng.normal(scale=4.0, size=(count, 3)), axis=0)
    ends = starts + rng.normal(scale=3.0, size=(count, 3)) * (seed != 0)  # seed 0: stations (points)
    reaches = rng.uniform(-2.0, 8.0, count)  # none within a negative reach
    segments, leaves = leaves_within(starts, ends, reaches, chain_tree(starts, ends, reaches), lower, upper, children,
                                     ranges, 0)
    found = sorted(zip(segments.tolist(), leaves.tolist()))
    every_leaf = np.flatnonzero(children[:, 0] < 0)
    expected = sorted((i, int(leaf)) for i in range(count) for leaf in every_leaf
                      if leaf_within(tuple(starts[i]), tuple(ends[i]), lower[leaf], upper[leaf], reaches[i]))
    assert len(expected) > 10 and found == expected


def test_a_station_pairs_with_the_nearest_triangle_of_each_patch_within_its_cutoff():
    """Against trimesh's closest points: a fine wavy drum (every triangle its own patch, hundreds within a station's
    cutoff) and a grid floor (one patch of 800 triangles), each station's pairs are one per patch within the
    cutoff, at the smallest gap of that patch's triangles."""
    import trimesh

    drum_vertices, drum_faces = _faceted_drum(96, rows=40, radius=20.0, half_length=20.0)
    wave = 0.2 * np.sin(drum_vertices[:, 1]) * np.cos(3.0 * np.arctan2(drum_vertices[:, 2], drum_vertices[:, 0]))
    drum_vertices = drum_vertices * (1.0 + wave / 20.0)[:, None]
    floor_vertices, floor_faces = _grid_floor(20, size=(60.0, 60.0))
    floor_vertices = floor_vertices - [0.0, 0.0, 22.0]
    parts = [(drum_vertices, drum_faces), (floor_vertices, floor_faces)]
    mesh = pack_meshes(parts, [0, 1])
    radius, cutoff = 3.0, 1.5
    angles = np.linspace(0.3, 1.2 * np.pi, 12)
    nodes = np.column_stack([24.0 * np.cos(angles), np.linspace(-8.0, 8.0, 12), -24.0 * np.sin(angles)])
    nodes = np.vstack([nodes, [[0.0, 0.0, -18.5], [5.0, 3.0, -18.6]]])  # two stations over the floor (and the drum)
    kinds, first, second, gaps = mesh.pairs(nodes, radius, cutoff)
    station_pairs = kinds == STATION_TRIANGLE
    found = {(int(k), int(mesh.patches[t])): gap for k, t, gap in zip(first[station_pairs], second[station_pairs],
                                                                       gaps[station_pairs])}
    expected = {}
    for vertices, faces in parts:  # the packed triangles, by their corners, with their patches
        corners = vertices[faces]
        packed = {tuple(np.round(t.ravel(), 9)): patch for t, patch in zip(mesh.triangles, mesh.patches)}
        patch_of = np.array([packed[tuple(np.round(c.ravel(), 9))] for c in corners])
        for k in range(1, len(nodes)):
            points = trimesh.triangles.closest_point(corners, np.repeat(nodes[k][None], len(corners), axis=0))
            gap = np.linalg.norm(points - nodes[k], axis=1) - radius
            for patch in np.unique(patch_of[gap < cutoff]):
                expected[(k, int(patch))] = float(np.min(gap[patch_of == patch]))
    assert found.keys() == expected.keys()
    assert max(abs(found[key] - expected[key]) for key in found) < 1e-9
    per_station = np.bincount(first[station_pairs])
    assert per_station.max() > 100 and len(expected) > 500  # many patches per station: the table's probing is met


def test_mesh_pairs_come_in_the_order_of_their_stations_and_segments():
    rng = np.random.default_rng(5)
    vertices, faces = _faceted_drum(24, rows=6)
    mesh = pack_meshes([(vertices, faces), (vertices + [0.0, 0.0, 30.0], faces)], [0, 1])
    nodes = np.cumsum(np.vstack([[[-60.0, -30.0, 38.0]], 6.0 * rng.standard_normal((30, 3)) + [4.0, 2.0, 0.0]]), axis=0)
    kinds, first, second, _ = mesh.pairs(nodes, 2.0, 6.0)
    for kind in (STATION_TRIANGLE, SEGMENT_EDGE):
        assert np.all(np.diff(first[kinds == kind]) >= 0) and np.any(kinds == kind)


def test_the_smallest_gap_to_a_mesh_is_that_of_the_nearest_triangle_of_every_segment():
    """MeshArrays.smallest_gaps (every segment below a first bound, then the segments of the lowest box bounds searched
    first, their gap the bound of the search of the others) against segment_gaps with no bound (the nearest triangle
    of every segment), for a hose touching the drum, near it, and far from it; with `within`, the same where the gap
    is below it, else inf; with `beyond`, a lower bound where that is at least `beyond` (close to the gap far off),
    else the gap; and per-segment bounds of segment_gaps: the exact gap below each segment's own bound, the bound
    where the mesh is farther."""
    rng = np.random.default_rng(4)
    vertices, faces = _faceted_drum(24, rows=6)
    mesh = pack_meshes([(vertices, faces)], [0])
    nodes = np.cumsum(np.vstack([[[-60.0, -30.0, 38.0]], 6.0 * rng.standard_normal((30, 3)) + [4.0, 2.0, 0.0]]), axis=0)
    for lift in (0.0, 3.0, 300.0):
        moved = nodes + [0.0, 0.0, lift]
        every = mesh.segment_gaps(moved[:-1], moved[1:], 1.0, np.inf)[0]
        assert mesh.smallest_gaps(moved[:-1], moved[1:], 1.0, 0.01) == pytest.approx(np.min(every, axis=1), abs=1e-12)
        smallest = float(np.min(every))
        for within in (0.5 * smallest, 2.0 * smallest):
            expected = smallest if smallest < within else np.inf
            assert mesh.smallest_gaps(moved[:-1], moved[1:], 1.0, 0.01, within)[0] == pytest.approx(expected, abs=1e-12)
        bounded = mesh.smallest_gaps(moved[:-1], moved[1:], 1.0, 0.01, beyond=1.0)[0]  # a lower bound where >= 1 mm
        assert bounded <= smallest + 1e-12 and (bounded >= 1.0 or bounded == pytest.approx(smallest, abs=1e-12))
        if lift == 300.0:  # far off: the bound, near the gap
            assert 1.0 <= bounded < smallest and bounded > 0.8 * smallest
        bounds = np.linspace(0.0, 2.0 * float(np.max(every)), moved.shape[0] - 1)
        bounded, nearest = mesh.segment_gaps(moved[:-1], moved[1:], 1.0, bounds)
        below = every[0] < bounds
        assert np.all(nearest[0][below] >= 0) and np.allclose(bounded[0][below], every[0][below], atol=1e-12)
        assert np.all(nearest[0][~below] < 0) and np.all(bounded[0][~below] == bounds[~below])

BOX_BASE = {"hose": {"length": 600.0, "outer_diameter": 10.0, "bending_stiffness": 2e4, "mass_per_length": 0.5,
                     "segments": 60},
            "start": {"point": [-200.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0]},
            "end": {"point": [200.0, 0.0, 0.0], "direction": [1.0, 0.0, 0.0]},
            "environment": {"gravity": [0.0, 0.0, -9.81]}}
BLOCK = {"kind": "box", "center": [-150.0, 0.0, -260.0], "size": [300.0, 100.0, 400.0], "name": "block"}


def test_a_heavy_hose_hangs_over_a_box_edge_clear_of_it_and_in_balance():
    from hoseline.io.problem_file import problem_from_dict
    from hoseline.procedures.contact.model import DEFAULT_ACTIVATION
    from hoseline.procedures.placement.sequence import solve

    free = solve(problem_from_dict(BOX_BASE), estimate_error=False)
    inside = (free.centerline[:, 0] < HOSE_RADIUS) & (free.centerline[:, 2] < -60.0 + HOSE_RADIUS)
    assert np.any(inside)  # without contact the hose sags into the block
    result = solve(problem_from_dict(BOX_BASE | {"contact": {"obstacles": [BLOCK]}}), estimate_error=False)
    block, = result.contacts
    assert block.kind == "box" and 0.0 < block.min_gap < DEFAULT_ACTIVATION
    # it rests on the block's edge (x = 0, z = -60), pushed away from the edge through the hose's axis
    np.testing.assert_allclose(block.surface_point[:, [0, 2]], [[0.0, -60.0]] * block.gap.size, atol=1e-9)
    away = block.point - block.surface_point
    np.testing.assert_allclose(np.cross(away, block.force), 0.0, atol=1e-9 * np.abs(block.force).max())
    assert np.all(np.einsum("ij,ij->i", away, block.force) > 0.0)
    # mounts, block and weight balance
    weight = np.array([0.0, 0.0, -MASS * 9.81e-3 * 600.0])
    np.testing.assert_allclose(result.start_force + result.end_force + block.total_force + weight, 0.0,
                               atol=1e-9 * np.linalg.norm(weight))
    assert block.total_force[2] > 0.1 * np.linalg.norm(weight) and result.stable
    assert result.summary()["contact"]["obstacles"][0]["kind"] == "box"


# --- input ---


def _problem_with(tmp_path, obstacle):
    from hoseline.io.problem_file import problem_from_dict

    return problem_from_dict(BOX_BASE | {"contact": {"obstacles": [obstacle]}}, "p.toml", tmp_path)


def test_a_mesh_file_is_read_relative_to_the_problem_file_and_written_back(tmp_path):
    import tomllib

    from hoseline.io.obstacle_mesh import write_stl
    from hoseline.io.problem_file import problem_from_dict, problem_to_dict, problem_to_toml

    vertices, faces = _faceted_drum(12)
    (tmp_path / "parts").mkdir()
    write_stl(tmp_path / "parts" / "drum.stl", vertices + [0.0, 0.0, -200.0], faces)
    problem = _problem_with(tmp_path, {"kind": "mesh", "file": "parts/drum.stl", "name": "drum"})
    drum, = problem.contact
    assert drum.kind == "mesh" and drum.faces.shape == (24, 3)
    again = problem_from_dict(tomllib.loads(problem_to_toml(problem)))
    assert problem_to_dict(again) == problem_to_dict(problem)
    box = _problem_with(tmp_path, dict(BLOCK, axes=[[0.0, 2.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])).contact[0]
    np.testing.assert_allclose(box.axes[0], [0.0, 1.0, 0.0])


@pytest.mark.parametrize("obstacle, expected", [
    ({"kind": "mesh", "file": "missing.stl"},
     'contact.obstacles[0]: file = "missing.stl": cannot read'),
    ({"kind": "mesh", "file": "nan.obj"}, "has vertices that are not finite numbers"),
    ({"kind": "mesh", "file": "line.stl"}, "every triangle has zero area"),
    ({"kind": "mesh"}, "contact.obstacles[0]: a mesh takes file: missing file"),
    ({"kind": "mesh", "file": "nan.obj", "radius": 2.0}, "a mesh takes file: radius given"),
    (dict(BLOCK, size=[300.0, 0.0, 400.0]), "contact.obstacles[0]: obstacle 'block' size = [300.0, 0.0, 400.0]: "
                                            "must be three positive edge lengths in mm"),
    (dict(BLOCK, axes=[[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), "must be perpendicular"),
    ({"kind": "box", "center": [0.0, 0.0, 0.0]}, "a box takes center and size (optional: axes): missing size"),
])
def test_bad_mesh_and_box_tables_are_refused_naming_the_field(tmp_path, obstacle, expected):
    from hoseline.io.obstacle_mesh import write_stl
    from hoseline.io.problem_file import ProblemFileError

    (tmp_path / "nan.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 nan 0\nf 1 2 3\nf 1 2 4\n")
    write_stl(tmp_path / "line.stl", np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]), np.array([[0, 1, 2]]))
    with pytest.raises(ProblemFileError) as error:
        _problem_with(tmp_path, obstacle)
    assert expected in str(error.value)


def test_a_straight_start_through_a_mesh_is_refused_naming_it(tmp_path):
    from hoseline.io.obstacle_mesh import write_stl
    from hoseline.io.problem_file import problem_from_dict
    from hoseline.procedures.placement.continuation import PlacementError
    from hoseline.procedures.placement.sequence import solve

    # a thin plate across the straight hose (from the start along x): no station inside it, a segment through it
    write_stl(tmp_path / "plate.stl", np.array([[103.0, -50.0, -50.0], [103.0, 50.0, -50.0], [103.0, 0.0, 50.0]]),
              np.array([[0, 1, 2]]))
    problem = problem_from_dict(BOX_BASE | {"contact": {"placement": "along_path",
                                                        "obstacles": [{"kind": "mesh", "file": "plate.stl",
                                                                       "name": "plate"}]}}, "p.toml", tmp_path)
    with pytest.raises(PlacementError) as error:
        solve(problem, estimate_error=False)
    assert "'plate'" in str(error.value) and "straight hose" in str(error.value) and "segment" in str(error.value)


def test_the_step_filter_refuses_a_step_through_a_thin_plate_that_ends_clear_of_it():
    from hoseline.mechanics.contact_newton import step_filter
    from hoseline.mechanics.newton import apply_step
    from hoseline.model.hose import Hose
    from hoseline.model.mounts import Mount
    from hoseline.model.obstacles import Mesh
    from hoseline.model.problem import Problem
    from hoseline.procedures.contact.model import contact_model
    from hoseline.procedures.placement.sequence import place_only

    hose = Hose(length=300.0, outer_diameter=2 * HOSE_RADIUS, bending_stiffness=1e5, torsional_stiffness=1e5, segments=30)
    along = np.array([1.0, 0.0, 0.0])
    props, clamps, state, _ = place_only(Problem(hose, Mount(np.zeros(3), along), Mount(np.array([299.0, 0.0, 0.0]), along)))
    nodes = centerline(state.frames, clamps.start_point, props.segment_length)
    middle = (nodes[:, 0] > 90.0) & (nodes[:, 0] < 210.0)
    height = float(np.max(nodes[middle, 2])) + HOSE_RADIUS + 3.5  # a plate 3.5 mm above the hose's middle
    plate = Mesh(np.array([[100.0, -50.0, height], [200.0, -50.0, height], [150.0, 50.0, height]]),
                 np.array([[0, 1, 2]]), "plate")
    model = contact_model([plate], HOSE_RADIUS, props.segment_length, 1.0)
    for turn, admitted in ((0.2, False), (0.005, True)):  # every segment turned up: the hose swings up about its start
        step = np.zeros(3 * props.segments)
        step[1::3] = -turn
        trial = apply_step(props, clamps, state, step, np.zeros(3))
        moved = centerline(trial.frames, clamps.start_point, props.segment_length)
        assert model.penetration(moved) is None  # clear at the end of the step: 30 mm above the plate, or below it
        assert step_filter(props, clamps, state, step, model).admits(props, clamps, trial, model, 1.0) == admitted


def test_the_step_filter_decides_as_with_every_station_s_gap_sought_at_once():
    """StepFilter seeks the stations' mesh gaps at each trial, only within what its move can close, and keeps them
    for the trials after: the same decisions as a new filter at each trial, and as one holding every station's gap
    within the whole step's reach (what it sought before), for random steps of a hose lying 0.5 mm over a floor
    (one triangle, its edges far: only the stations' paths guard its face), each tried at fractions growing and
    shrinking; and a swing down is refused exactly where its end comes within a tenth of its gap (a
    station out of reach, whose whole step cannot bring it within d_hat, is not watched)."""
    from hoseline.mechanics.contact_newton import SAFE_FRACTION, step_filter
    from hoseline.mechanics.newton import RodProperties, apply_step
    from hoseline.mechanics.rod import Clamps, RodState
    from hoseline.mechanics.rotations import frame_from_tangent
    from hoseline.model.obstacles import Mesh
    from hoseline.procedures.contact.model import contact_model

    n_seg, h, radius = 40, 2.0, 1.0
    frames = np.array([frame_from_tangent(np.array([1.0, 0.0, 0.0]))] * n_seg)
    props = RodProperties(np.array([1e4, 1e4, 1e4]), h, n_seg)
    start = np.array([-40.0, 0.0, radius + 0.5])
    clamps = Clamps(start, frames[0].copy(), start + [80.0, 0.0, 0.0], frames[-1].copy(), False, np.zeros(3))
    state = RodState(frames, np.zeros(3))
    floor = Mesh(np.array([[-1000.0, -1000.0, 0.0], [1000.0, -1000.0, 0.0], [0.0, 1000.0, 0.0]]), np.array([[0, 1, 2]]),
                 "floor")
    model = contact_model([floor], radius, h, 1.0)
    rng = np.random.default_rng(21)
    steps = [size * rng.standard_normal(3 * n_seg) for size in (1e-3, 3e-3, 1e-2, 3e-2, 0.1) for _ in range(4)]
    drops = (0.3, 0.48, 0.6, 0.8, 1.2)
    for drop in drops:  # the hose swung down about its start: its end drops by `drop` mm
        steps.append(np.zeros(3 * n_seg))
        steps[-1][1::3] = drop / (n_seg * h)
    decisions = set()
    for number, step in enumerate(steps):
        kept = step_filter(props, clamps, state, step, model)
        eager = step_filter(props, clamps, state, step, model)
        nodes, reach, _ = eager.swept
        every = model.mesh.station_gaps(nodes, radius, reach)
        every[every >= reach] = np.inf
        eager._station_gaps = reach, every  # every station's gap within its reach, as the filter once held
        for fraction in (0.25, 1.0, 0.5, 0.125, 1.0):  # a trial may reach farther than the last one
            alpha = fraction * kept.limit
            trial = apply_step(props, clamps, state, alpha * step, np.zeros(3))
            fresh = step_filter(props, clamps, state, step, model).admits(props, clamps, trial, model, alpha)
            assert kept.admits(props, clamps, trial, model, alpha) == fresh
            assert eager.admits(props, clamps, trial, model, alpha) == fresh
            if number >= len(steps) - len(drops):  # a swing is refused where its end comes within a tenth of its
                drop = drops[number - len(steps)]  # gap, unless the whole step cannot bring it within d_hat
                assert fresh == (alpha * drop < (1.0 - SAFE_FRACTION) * 0.5 or drop + model.activation <= 0.5)
            decisions.add(fresh)
    assert decisions == {True, False}


@pytest.mark.parametrize("obstacle", ["mesh", "plane"])
def test_the_contact_newton_takes_no_step_its_filter_refuses(obstacle, monkeypatch):
    """The contact Newton evaluates a trial before its step filter where there are meshes (the cheaper test first)
    and after it where there are none, and takes a step only where both agree: a hose bowed up between two clamps
    and loaded by its weight, a floor 50 mm below, converges in a few steps, and not at all with a filter that
    refuses every step."""
    from hoseline.mechanics.contact_newton import StepFilter, solve_with_contact
    from hoseline.mechanics.newton import RodProperties
    from hoseline.mechanics.rod import Clamps, RodState
    from hoseline.mechanics.rotations import frame_from_tangent
    from hoseline.model.obstacles import Mesh, Plane
    from hoseline.procedures.contact.model import contact_model

    n_seg, h, radius = 30, 10.0, 2.0
    angles = 0.4 * np.cos(np.pi * (np.arange(n_seg) + 0.5) / n_seg)
    frames = np.array([frame_from_tangent(np.array([np.cos(a), 0.0, np.sin(a)])) for a in angles])
    level = frame_from_tangent(np.array([1.0, 0.0, 0.0]))
    props = RodProperties(np.array([1e5, 1e5, 1e5]), h, n_seg)
    clamps = Clamps(np.zeros(3), level, np.array([h * np.sum(np.cos(angles)), 0.0, 0.0]), level.copy(), False,
                    np.array([0.0, 0.0, -2e-3]))
    state = RodState(frames, np.zeros(3))
    floor = (Mesh(np.array([[-500.0, -500.0, -50.0], [900.0, -500.0, -50.0], [200.0, 900.0, -50.0]]),
                  np.array([[0, 1, 2]]), "floor") if obstacle == "mesh"
             else Plane(np.array([0.0, 0.0, -50.0]), np.array([0.0, 0.0, 1.0]), "floor"))
    model = contact_model([floor], radius, h, 1e-2)
    assert (model.mesh.count == 1) == (obstacle == "mesh")
    _, report = solve_with_contact(props, clamps, state, model)
    assert report.converged and report.iterations >= 2
    monkeypatch.setattr(StepFilter, "admits", lambda *arguments: False)
    _, report = solve_with_contact(props, clamps, state, model)
    assert not report.converged and report.message == "no acceptable step found"


def test_the_step_filter_s_kept_station_gaps_are_those_sought_anew():
    """StepFilter._gaps_below answers from the gaps it last sought where the bounds are within theirs, else seeks
    them again: the exact gaps below any sequence of bounds, growing and shrinking, and inf beyond them."""
    from hoseline.mechanics.contact_newton import motion_filter
    from hoseline.model.obstacles import Mesh
    from hoseline.procedures.contact.model import contact_model

    vertices, faces = _faceted_drum(64, rows=8)
    model = contact_model([Mesh(vertices, faces, "drum")], 1.0, 2.0, 1.0)
    rng = np.random.default_rng(3)
    nodes = np.column_stack([np.linspace(-60.0, 60.0, 31), np.zeros(31), np.full(31, 43.0)])  # over the drum
    watch = motion_filter(nodes, np.full(30, 0.05), 0.0, 2.0, model)
    exact = model.mesh.station_gaps(nodes, 1.0, np.full(31, np.inf))
    for scale in (0.5, 5.0, 1.0, 20.0, 2.0, 0.1):
        bounds = scale * rng.uniform(0.5, 1.5, 31)
        expected = np.where(exact < bounds, exact, np.inf)
        np.testing.assert_array_equal(watch._gaps_below(model, bounds), expected)


def test_plane_and_triangle_pairs_in_one_call_are_the_sum_of_each_alone_and_leave_the_obstacles_as_they_were():
    """Station-plane and station-triangle pairs share node_terms' arrays for a station's direction and curvature: one
    call with both gives what two calls give, each alone, and leaves the planes and triangles untouched (the plane's
    row once stood in for that array, and a triangle pair after it overwrote the plane's normal)."""
    nodes = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.3], [2.0, 0.0, 0.3]])
    planes = np.array([[0.0, 0.0, -1.0, 0.0, 0.0, 1.0]])
    triangles = np.array([[[0.0, -5.0, 1.5], [5.0, -5.0, 1.5], [0.0, 5.0, 1.5]]])
    kept = planes.copy(), triangles.copy()

    def terms(kinds, first):
        return node_terms(nodes, 1.0, 1.0, 0.5, planes, np.zeros((0, 4)), np.zeros((0, 7)), triangles,
                          np.zeros((0, 2, 3)), np.zeros(1, np.int64), np.array(kinds), np.array(first),
                          np.zeros(len(kinds), np.int64))

    both = terms([STATION_PLANE, STATION_TRIANGLE, STATION_PLANE], [1, 2, 2])
    np.testing.assert_array_equal(planes, kept[0])
    np.testing.assert_array_equal(triangles, kept[1])
    alone = [terms([kind], [station]) for kind, station in ((STATION_PLANE, 1), (STATION_TRIANGLE, 2),
                                                            (STATION_PLANE, 2))]
    assert both[0] == pytest.approx(sum(part[0] for part in alone), rel=1e-14)
    for k in (1, 2):  # gradient, Hessian
        np.testing.assert_allclose(both[k], sum(part[k] for part in alone), rtol=1e-14, atol=0.0)
    for k in (3, 4, 5, 6):  # forces, points on the hose and on the other body, gaps: one row per pair
        np.testing.assert_allclose(both[k], np.concatenate([part[k] for part in alone]), rtol=1e-14, atol=0.0)
