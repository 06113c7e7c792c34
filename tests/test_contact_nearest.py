"""The smallest gap of the whole assembly to each obstacle (procedures/contact/nearest.py): an end fitting nearer an
obstacle than the hose, and a plane nearest at the start station, against hand-computed distances; where the
smallest gap to a mesh is, against every segment's."""

import numpy as np
import pytest
import trimesh

from hoseline.model.fittings import Fitting
from hoseline.model.hose import Hose
from hoseline.model.mounts import Mount
from hoseline.model.obstacles import Mesh, Plane, Sphere
from hoseline.model.problem import Problem, fitted_problem
from hoseline.procedures.contact.nearest import nearest_gaps
from hoseline.procedures.contact.placement import problem_contact_model
from hoseline.procedures.placement.sequence import solve

HOSE = Hose(length=300.0, outer_diameter=10.0, bending_stiffness=1e5, torsional_stiffness=1e5, segments=60)


def test_a_fitting_nearer_the_obstacle_than_the_hose_gives_the_smallest_gap_and_where():
    # a straight fitting of radius 10 mm along +y from the origin to its outlet at y = 40 mm; a ball of radius 5 mm
    # 30 mm off its axis at y = 20: the fitting's gap is 30 - 5 - 10 = 15 mm at 20 mm before the outlet
    ball = Sphere(np.array([30.0, 20.0, 0.0]), 5.0, "ball")
    problem = fitted_problem(HOSE, Mount(np.zeros(3), np.array([0.0, 1.0, 0.0])),
                             Mount(np.array([200.0, 140.0, 0.0]), np.array([-1.0, 0.0, 0.0])),
                             Fitting(40.0, outer_diameter=20.0), None, contact=(ball,))
    result = solve(problem, estimate_error=False)
    nodes = result.centerline
    hose_gap = float(np.min(np.linalg.norm(nodes - ball.centre, axis=1))) - 5.0 - 5.0
    assert hose_gap > 20.0  # the hose itself is further away
    (contact,) = result.contacts
    assert contact.min_gap == pytest.approx(15.0, abs=1e-9)
    assert contact.min_gap_on == "start fitting" and contact.min_gap_arc_length == pytest.approx(-20.0)
    summary = result.summary()["contact"]["obstacles"][0]
    assert summary["min_gap_mm"] == pytest.approx(15.0) and summary["min_gap_on"] == "start fitting"


def test_a_plane_nearest_at_the_held_start_station():
    # the start 3 mm above a floor (surface to surface), the hose rising away from it: the start station is nearest
    floor = Plane(np.array([0.0, 0.0, -8.0]), np.array([0.0, 0.0, 1.0]), "floor")
    problem = Problem(HOSE, Mount(np.zeros(3), np.array([0.0, 0.6, 0.8])),
                      Mount(np.array([0.0, 150.0, 200.0]), np.array([0.0, 1.0, 0.0])), contact=(floor,))
    result = solve(problem, estimate_error=False)
    assert np.all(result.centerline[1:, 2] > 1.0)
    (contact,) = result.contacts
    assert contact.min_gap == pytest.approx(3.0, abs=1e-9)
    assert contact.min_gap_on == "hose" and contact.min_gap_arc_length == pytest.approx(0.5 * HOSE.segment_length)


def test_the_nearest_segment_to_a_mesh_is_that_of_the_smallest_of_every_segments_gap():
    """The halving that finds where the smallest gap to a mesh is (its searches only within a hair of that gap)
    against the gap of every segment to the mesh, for a wiggly hose near a ball meshed with 1280 triangles."""
    ball = trimesh.creation.icosphere(subdivisions=3, radius=20.0)
    problem = Problem(HOSE, Mount(np.zeros(3), np.array([1.0, 0.0, 0.0])),
                      Mount(np.array([250.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])),
                      contact=(Mesh(ball.vertices + [130.0, 0.0, 27.0], ball.faces, "ball"),))
    model = problem_contact_model(problem)
    rng = np.random.default_rng(7)
    h = HOSE.length / HOSE.segments
    for lift in (0.0, 4.0, 40.0):
        nodes = np.column_stack([h * np.arange(HOSE.segments + 1), 2.0 * rng.standard_normal(HOSE.segments + 1),
                                 1.0 * rng.standard_normal(HOSE.segments + 1) - lift])
        every = model.mesh.segment_gaps(nodes[:-1], nodes[1:], model.hose_radius, np.inf)[0][0]
        nearest = nearest_gaps(problem, model, nodes)["ball"]
        lengths = np.linalg.norm(np.diff(nodes, axis=0), axis=1)
        k = int(np.argmin(every))
        assert nearest.gap == pytest.approx(float(every[k]), abs=1e-12) and nearest.on == "hose"
        assert nearest.arc_length == pytest.approx(float(np.sum(lengths[:k]) + 0.5 * lengths[k]), abs=1e-9)
