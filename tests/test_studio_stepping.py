"""What the studio steps on: the clearance of every segment (against brute force) and the tracked
equilibrium carried through changes of fittings and properties (each step ends on an equilibrium)."""

from dataclasses import replace

import numpy as np
import pytest
from test_clearance import brute_force_nearest, random_hose, random_mesh

from hoseline.demos.thesis_hose import demo_problem
from hoseline.mechanics.newton import solve_equilibrium
from hoseline.mechanics.rotations import rotation_matrix
from hoseline.procedures.geometry.clearance import TriangleIndex
from hoseline.procedures.geometry.clearance_profile import clearance_profile
from hoseline.procedures.geometry.profile_nearest import profile_and_nearest
from hoseline.procedures.placement.continuation import PlacementError
from hoseline.procedures.placement.sequence import solve
from hoseline.procedures.placement.tracking import Fittings, Tracker, twisted


@pytest.mark.parametrize("seed", range(6))
def test_clearance_profile_is_the_brute_force_distance_of_each_segment_up_to_the_cutoff(seed):
    rng = np.random.default_rng(seed)
    vertices, faces = random_mesh(rng, 200, rng.normal(size=3) * 30.0, 15.0)
    index = TriangleIndex(vertices, faces)
    nodes = random_hose(rng)
    radius, cutoff = 2.0, 20.0
    profile = clearance_profile(index, nodes, radius, cutoff)
    expected = [min(brute_force_nearest(nodes[i:i + 2], vertices, faces) - radius, cutoff) for i in range(len(nodes) - 1)]
    assert np.allclose(profile, expected, atol=1e-9)
    assert profile.min() == pytest.approx(min(index.nearest(nodes, radius).distance, cutoff), abs=1e-9)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("cutoff", [0.5, 20.0, 1e3])
def test_the_nearest_approach_found_with_the_profile_is_the_whole_hoses(seed, cutoff):
    """profile_and_nearest searches only the segment the profile found nearest when it is within the cut-off, else the
    whole hose: the same distance, arc length and points as TriangleIndex.nearest, and the same profile."""
    rng = np.random.default_rng(seed)
    vertices, faces = random_mesh(rng, 200, rng.normal(size=3) * 30.0, 15.0)
    index = TriangleIndex(vertices, faces)
    nodes = random_hose(rng)
    radius = 2.0
    profile, found = profile_and_nearest(index, nodes, radius, cutoff)
    whole = index.nearest(nodes, radius)
    np.testing.assert_array_equal(profile, clearance_profile(index, nodes, radius, cutoff))
    assert (found.distance, found.s) == (whole.distance, whole.s)
    np.testing.assert_array_equal(found.on_hose, whole.on_hose)
    np.testing.assert_array_equal(found.on_obstacle, whole.on_obstacle)


@pytest.fixture(scope="module")
def placed():
    problem = demo_problem(180.0, segments=30)
    return problem, solve(problem)


def assert_equilibrium(tracker):
    """Newton from the tracked state stops at once: it is an equilibrium of the tracked hose and clamps."""
    state, report = solve_equilibrium(tracker.props, tracker.clamps, tracker.state, tolerance=1e-9)
    assert report.converged and report.iterations == 0 and report.unstable_directions == 0


def moved(problem, fittings, offset=(0.0, 0.0, 0.0), turn=(0.0, 0.0, 0.0)):
    """The problem and fittings with the end tip moved by `offset` (mm) and its frame turned by `turn` (rad)."""
    point = fittings.end_point + np.asarray(offset)
    frame = fittings.end_frame @ rotation_matrix(np.asarray(turn)).T
    from hoseline.model.mounts import Mount

    return replace(problem, end=Mount(point, -frame[2])), replace(fittings, end_point=point, end_frame=frame)


def test_moving_a_fitting_reaches_an_equilibrium_there_and_back_again(placed):
    problem, result = placed
    tracker = Tracker(problem, result)
    start = tracker.centerline
    for k in range(8):  # 2 mm and 3 degrees per step
        step = tracker.move(*moved(problem, tracker.fittings, (0.0, 0.0, 2.0), (0.0, np.radians(3.0), 0.0)))
        assert_equilibrium(tracker)
    assert np.allclose(tracker.centerline[-1], start[-1] + [0.0, 0.0, 16.0], atol=1e-9)
    assert step.iterations >= 1 and step.movement > 0.5
    for k in range(8):
        tracker.move(*moved(problem, tracker.fittings, (0.0, 0.0, -2.0), (0.0, np.radians(-3.0), 0.0)))
    assert np.max(np.abs(tracker.centerline - start)) < 1e-6 * problem.hose.length


def test_a_large_step_is_followed_by_continuation_and_ends_where_small_steps_end(placed):
    problem, result = placed
    small, large = Tracker(problem, result), Tracker(problem, result)
    for _ in range(10):
        small.move(*moved(problem, small.fittings, (0.0, -6.0, 4.0)))
    large.move(*moved(problem, large.fittings, (0.0, -60.0, 40.0)))
    assert np.max(np.abs(small.centerline - large.centerline)) < 1e-6 * problem.hose.length


def test_changing_length_and_stiffness_reaches_the_equilibrium_of_the_new_hose(placed):
    problem, result = placed
    tracker = Tracker(problem, result)
    hose = replace(problem.hose, length=380.0, bending_stiffness=2 * problem.hose.bending_stiffness)
    tracker.move(replace(problem, hose=hose), tracker.fittings)
    assert tracker.props.length == pytest.approx(380.0)
    assert_equilibrium(tracker)
    assert np.sum(np.linalg.norm(np.diff(tracker.centerline, axis=0), axis=1)) == pytest.approx(380.0, abs=1e-9)


def test_a_twist_turns_the_end_fitting_about_its_direction_and_a_step_that_fails_changes_nothing(placed):
    problem, result = placed
    frame = result.end_frame
    turned = twisted(frame, 90.0)
    assert np.allclose(turned[2], frame[2]) and np.isclose(turned[0] @ frame[0], 0.0, atol=1e-12)
    assert np.allclose(twisted(turned, -90.0), frame)
    tracker = Tracker(problem, result)
    before = tracker.centerline
    far = Fittings(tracker.fittings.start_point, tracker.fittings.start_frame,
                   tracker.fittings.start_point + [problem.hose.length, 0.0, 0.0], tracker.fittings.end_frame)
    with pytest.raises(PlacementError):  # the hose cannot reach: no equilibrium is followed there
        tracker.move(problem, far)
    assert np.array_equal(tracker.centerline, before)


def test_a_large_twist_in_one_step_is_followed_as_in_small_steps(placed):
    problem, result = placed
    small, large = Tracker(problem, result), Tracker(problem, result)
    for _ in range(15):
        small.move(problem, replace(small.fittings, end_frame=twisted(small.fittings.end_frame, 10.0)))
    step = large.move(problem, replace(large.fittings, end_frame=twisted(large.fittings.end_frame, 150.0)))
    assert step.iterations > 10  # Newton alone cannot: the step was followed by continuation
    assert np.max(np.abs(small.centerline - large.centerline)) < 1e-6 * problem.hose.length


def test_the_session_turns_a_twist_of_more_than_half_a_turn_the_way_it_goes(placed):
    from hoseline.studio.messages import Target
    from hoseline.studio.session import Session

    problem, _ = placed
    problem = replace(problem, end_twist_deg=0.0)
    by_slider, typed = Session(problem), Session(problem)
    for twist in range(15, 271, 15):
        by_slider.apply(Target(type="set", seq=1, twist=float(twist)))
    typed.apply(Target(type="set", seq=1, twist=270.0))
    assert np.max(np.abs(by_slider.tracker.centerline - typed.tracker.centerline)) < 1e-6 * problem.hose.length
    far = typed.tracker.centerline
    with pytest.raises(Exception):  # too short a hose: refused, and nothing changes
        typed.apply(Target(type="set", seq=2, twist=0.0, hose={"length": 100.0}))
    assert np.array_equal(typed.tracker.centerline, far) and typed.problem.end_twist_deg == 270.0


@pytest.mark.parametrize("kind", ["fixed", "rotating", "sliding", "ball"])
def test_the_tracker_holds_the_clips_as_the_placement_left_them(kind):
    """A placement with a clip, taken over by the tracker: an equilibrium of its clamps (Newton stops at once),
    the stations where the placement has them; a clip moved and back gives the same shape."""
    from hoseline.model.clips import Clip
    problem = demo_problem(180.0, segments=30)
    shape, h = solve(problem, estimate_error=False).centerline, problem.hose.segment_length
    tangent = (shape[16] - shape[14]) / np.linalg.norm(shape[16] - shape[14])
    clip = Clip(kind, shape[15] + [0.0, 0.0, 3.0], 15 * h, None if kind == "ball" else tangent)
    clipped = replace(problem, clips=(clip,))
    placed = solve(clipped, estimate_error=False)
    tracker = Tracker(clipped, placed)
    assert np.max(np.abs(tracker.centerline - placed.centerline)) < 1e-9 * problem.hose.length
    _, report = solve_equilibrium(tracker.props, tracker.clamps, tracker.state)
    assert report.converged and report.iterations == 0
    fittings = tracker.fittings
    start = tracker.centerline
    tracker.move(clipped, replace(fittings, clip_points=fittings.clip_points + [0.0, 0.0, 6.0]))
    node = tracker.clamps.clips[0].node
    assert np.allclose(tracker.centerline[node], fittings.clip_points[0] + [0.0, 0.0, 6.0], atol=1e-9)
    tracker.move(clipped, fittings)
    assert np.max(np.abs(tracker.centerline - start)) < 1e-6 * problem.hose.length


def test_a_sweep_pose_moves_a_clip_with_its_body(tmp_path):
    from test_sweep import SWEEP_TOML, sweep_folder

    from hoseline.io.sweep_file import load_sweep
    from hoseline.studio.messages import Target
    from hoseline.studio.session import Session
    clip = '\n[[clips]]\ntype = "rotating"\narc_length = 165.3\npoint = [-80.0, 40.0, -11.25]\ndirection = [-1.0, -0.3, 0.0]\n' \
           'body = "knuckle"\n'
    session = Session(sweep=load_sweep(sweep_folder(tmp_path, SWEEP_TOML + clip)))
    session.apply(Target(type="set", seq=1, pose=2))  # the knuckle lifted 20 mm
    held = session.fittings_at_zero_twist().clip_points[0]
    np.testing.assert_allclose(held, [-80.0, 40.0, 8.75], atol=1e-12)
    assert np.allclose(session.tracker.centerline[session.tracker.clamps.clips[0].node], held, atol=1e-9)
