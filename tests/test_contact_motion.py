"""Contact obstacles carried by a pose (mechanics/contact_motion.py): the moved model, and the check of a move."""

import numpy as np
import pytest
import trimesh

from hoseline.mechanics.bounding_volumes import build_tree, refit_boxes
from hoseline.mechanics.contact_motion import move_is_clear, moved_model, only
from hoseline.mechanics.newton import RodProperties
from hoseline.mechanics.rod import Clamps, RodState
from hoseline.model.motion import Pose, axis_angle_matrix
from hoseline.model.obstacles import Box, Cylinder, Mesh, Plane, Sphere
from hoseline.procedures.contact.model import contact_model

HOSE_RADIUS, SEGMENTS, H = 5.0, 30, 4.0
POSE = Pose(axis_angle_matrix(np.array([1.0, 2.0, 2.0]) / 3.0, 0.7), np.array([10.0, -5.0, 3.0]))


def carried_obstacle(obstacle, pose: Pose):
    """The obstacle built again where `pose` takes it (independent of contact_motion)."""
    if isinstance(obstacle, Plane):
        return Plane(pose.point(obstacle.point), pose.rotation @ obstacle.normal, obstacle.name)
    if isinstance(obstacle, Sphere):
        return Sphere(pose.point(obstacle.centre), obstacle.radius, obstacle.name)
    if isinstance(obstacle, Cylinder):
        return Cylinder(pose.point(obstacle.start), pose.point(obstacle.end), obstacle.radius, obstacle.name)
    if isinstance(obstacle, Box):
        return Box(pose.point(obstacle.center), obstacle.size, obstacle.axes @ pose.rotation.T, obstacle.name)
    return Mesh(pose.points(obstacle.vertices), obstacle.faces, obstacle.name)


def test_a_moved_model_is_the_model_of_the_moved_obstacles():
    """Every primitive where the pose puts it, and the meshes (a box, a ball of 1280 triangles, with a flat grid
    floor: flat edges) pair with the same stations and segments at the same gaps as meshes packed where they are."""
    ball = trimesh.creation.icosphere(subdivisions=3, radius=40.0)
    grid = trimesh.creation.box(extents=[200.0, 200.0, 2.0]).subdivide().subdivide()
    obstacles = [Plane([0.0, 0.0, -50.0], [0.0, 0.3, 1.0], "floor"), Sphere([0.0, 60.0, 0.0], 8.0, "ball"),
                 Cylinder([-30.0, 0.0, 0.0], [30.0, 10.0, 0.0], 6.0, "rod"),
                 Box([50.0, 0.0, 0.0], [30.0, 20.0, 10.0], name="box"), Mesh(ball.vertices, ball.faces, "sphere mesh"),
                 Mesh(grid.vertices + [0.0, 0.0, -80.0], grid.faces, "grid")]
    fixed = [None, POSE, POSE, POSE, POSE, POSE]
    model = contact_model(obstacles, HOSE_RADIUS, H, 1.0)
    moved = moved_model(model, fixed)
    rebuilt = contact_model([obstacles[0]] + [carried_obstacle(o, POSE) for o in obstacles[1:]], HOSE_RADIUS, H, 1.0)
    np.testing.assert_array_equal(moved.planes, model.planes)  # not moved
    for name in ("balls", "capsules"):
        np.testing.assert_allclose(getattr(moved, name), getattr(rebuilt, name), atol=1e-12)
    rng = np.random.default_rng(3)
    compared = 0
    for _ in range(40):
        local = np.cumsum(rng.normal(size=(SEGMENTS + 1, 3)) * H / np.sqrt(3.0), axis=0) + rng.normal(size=3) * 45.0
        nodes = POSE.points(local)
        found, expected = moved.pairs(nodes, 4.0), rebuilt.pairs(nodes, 4.0)
        mine = sorted(zip(found[0], found[1], [moved.owner(k, j) for k, j in zip(found[0], found[2])], found[3]))
        theirs = sorted(zip(expected[0], expected[1], [rebuilt.owner(k, j) for k, j in zip(expected[0], expected[2])],
                            expected[3]))
        assert [pair[:3] for pair in mine] == [pair[:3] for pair in theirs]
        np.testing.assert_allclose([pair[3] for pair in mine], [pair[3] for pair in theirs], atol=1e-9)
        compared += len(mine)
        np.testing.assert_allclose(moved.mesh.segment_gaps(nodes[:-1], nodes[1:], HOSE_RADIUS, np.inf)[0],
                                   rebuilt.mesh.segment_gaps(nodes[:-1], nodes[1:], HOSE_RADIUS, np.inf)[0], atol=1e-9)
    assert compared > 100  # the hoses met the obstacles


def test_refitted_boxes_of_unmoved_items_are_the_built_ones():
    corners = np.random.default_rng(0).normal(size=(500, 3, 3)) * 10.0
    order, lower, upper, children, ranges = build_tree(corners.min(axis=1), corners.max(axis=1),
                                                       corners.mean(axis=1), 4)
    refitted_lower, refitted_upper = np.zeros_like(lower), np.zeros_like(upper)
    refit_boxes(corners[order], refitted_lower, refitted_upper, children, ranges, 0, len(lower))
    np.testing.assert_array_equal(refitted_lower, lower)
    np.testing.assert_array_equal(refitted_upper, upper)


def straight_hose() -> tuple[RodProperties, Clamps, RodState]:
    """A straight hose along x from x = -60 mm, at z = 0."""
    frames = np.tile(np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]), (SEGMENTS, 1, 1))
    clamps = Clamps(np.array([-60.0, 0.0, 0.0]), frames[0], None, None, False, np.zeros(3))
    return RodProperties(np.full(3, 1e4), H, SEGMENTS), clamps, RodState(frames, np.zeros(3))


PLATE = Box([0.0, 0.0, 10.0], [40.0, 40.0, 1.0], name="plate")  # above the hose: 4.5 mm between the surfaces
BALL = Sphere([0.0, 0.0, 10.0], 3.0, "ball")  # 2 mm above the hose


@pytest.mark.parametrize("obstacle", [PLATE, BALL], ids=["thin plate", "small ball"])
def test_an_obstacle_jumping_across_the_hose_is_refused(obstacle):
    """Carried 20 mm down in one move it ends clear below the hose: the end alone looks fine, the move does not;
    carried 1.5 mm down it stays above the hose and is admitted."""
    props, clamps, state = straight_hose()
    model = contact_model([obstacle], HOSE_RADIUS, H, 1.0)
    down = Pose(np.eye(3), np.array([0.0, 0.0, -20.0]))
    nodes = np.array([[-60.0 + H * k, 0.0, 0.0] for k in range(SEGMENTS + 1)])
    assert moved_model(model, [down]).penetration(nodes) is None
    assert not move_is_clear(props, (clamps, state), (clamps, state), model, down)
    assert move_is_clear(props, (clamps, state), (clamps, state), model, Pose(np.eye(3), np.array([0.0, 0.0, -1.5])))


def test_a_hose_carried_along_with_the_obstacles_may_move_any_distance():
    """The hose touching the plate (gap 0.005 mm), both turned by 40 degrees and carried 300 mm: nothing moves
    relative to the plate, so the move is clear; the plate alone carried so would not be."""
    props, clamps, state = straight_hose()
    touching = Box([0.0, 0.0, 5.505], [40.0, 40.0, 1.0], name="plate")
    model = contact_model([touching], HOSE_RADIUS, H, 1.0)
    carry = Pose(axis_angle_matrix(np.array([0.0, 0.6, 0.8]), np.radians(40.0)), np.array([300.0, -100.0, 50.0]))
    along = Clamps(carry.point(clamps.start_point), carry.frame(clamps.start_frame), None, None, False, np.zeros(3))
    carried_along = RodState(carry.frame(state.frames), np.zeros(3))
    assert move_is_clear(props, (clamps, state), (along, carried_along), model, carry)
    assert not move_is_clear(props, (clamps, state), (clamps, state), model, carry)


def test_only_keeps_the_obstacles_asked_for():
    model = contact_model([PLATE, BALL, Plane([0.0, 0.0, -20.0], [0.0, 0.0, 1.0])], HOSE_RADIUS, H, 1.0,
                          self_contact=True)
    nodes = np.array([[-60.0 + H * k, 0.0, 0.0] for k in range(SEGMENTS + 1)])
    assert all(np.isfinite(gap) for gap in model.smallest_gaps(nodes).values())
    gaps = only(model, [1], self_contact=False).smallest_gaps(nodes)
    assert gaps == {"plate": np.inf, "ball": pytest.approx(2.0), "plane": np.inf}  # no "self"
    assert set(only(model, [], self_contact=True).smallest_gaps(nodes)) == {"plate", "ball", "plane", "self"}
