"""Sweeps: rigid-motion invariance, the free-roll comparison, generated motions, clearance along the
sweep, the sweep file and the command line."""

import math
from functools import partial

import numpy as np
import pytest
import trimesh
from cases import THESIS_TOML, write
from sweep_cases import SEGMENTS, coarse_demo, small_sweep_result  # noqa: F401 (fixture)
from typer.testing import CliRunner

from hoseline import cli
from hoseline.commands import common
from hoseline.demos import sweep as sweep_demo
from hoseline.demos.thesis_hose import demo_problem
from hoseline.io.sweep_file import SweepFileError, load_sweep
from hoseline.model.motion import BodyMotion, Pose, Rotation, Stage, Translation, axis_angle_matrix, generated_motion
from hoseline.model.sweep import Obstacle, SweepProblem
from hoseline.procedures.sweep import quasi_static as sweep_procedure
from hoseline.procedures.geometry.clearance import TriangleIndex
from hoseline.procedures.placement.continuation import PlacementError
from hoseline.procedures.sweep.quasi_static import run_sweep
from hoseline.report.sweep_report import SWEEP_FILES

runner = CliRunner()


def rigid_motion(count):
    """Both bodies turned about a skew axis and shifted, together: poses k = 0..count-1."""
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    return tuple(Pose(axis_angle_matrix(axis, math.radians(12.0 * k)), np.array([5.0, -3.0, 8.0]) * k)
                 for k in range(count))


def test_moving_both_mounts_together_moves_the_shape_rigidly():
    problem = demo_problem(180.0, segments=SEGMENTS)
    poses = rigid_motion(4)
    motion = BodyMotion("frame", poses, np.arange(4.0), (Stage("step", "", 0, 4),))
    result = run_sweep(SweepProblem(problem, "frame", "frame", (motion,), compare_free_roll=False))
    for k, pose in enumerate(poses):
        np.testing.assert_allclose(result.centerlines[k], pose.points(result.assembly.centerline), atol=1e-6)
        np.testing.assert_allclose(result.bend_radius[k], result.assembly.curvature ** -1 - problem.hose.outer_radius,
                                   rtol=1e-6)
        np.testing.assert_allclose(result.twisting_moment[k], result.assembly.twisting_moment, atol=1e-6 * 1e3)
    assert result.snaps == []


def test_end_free_to_spin_separates_on_an_out_of_plane_motion():
    problem = demo_problem(0.0, segments=SEGMENTS)  # mounts and hose in the plane z = -11.25
    motion = generated_motion("knuckle", [Translation([0.0, 0.0, 1.0], (0.0, 30.0), 6, "jounce")])
    result = run_sweep(SweepProblem(problem, None, "knuckle", (motion,)))
    assert result.separation[0] < 1e-6  # same shape at design position
    assert result.separation[-1] > 1.0  # mm: the paper's error, clearly visible
    np.testing.assert_allclose(result.end_points[-1], problem.end.point + [0.0, 0.0, 30.0])
    np.testing.assert_allclose(result.single_plane_offset[-1], -30.0, atol=1e-9)


def test_generated_stages_share_named_coordinates():
    steer = partial(Rotation, [0.0, 0.0, 1.0], [10.0, 0.0, 0.0], name="steer")
    motion = generated_motion("knuckle", [steer((0.0, 20.0), 2), Translation([0, 0, 1], (0.0, 5.0), 1, "jounce"),
                                          steer((20.0, 0.0), 2)])
    np.testing.assert_allclose(motion.travel, [0.0, 10.0, 20.0, 5.0, 10.0, 0.0])
    assert [(s.name, s.first, s.count) for s in motion.stages] == [("steer", 0, 3), ("jounce", 3, 1), ("steer", 4, 2)]
    last = motion.poses[-1]  # steer back at 0 with the jounce kept
    np.testing.assert_allclose(last.rotation, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(last.position, [0.0, 0.0, 5.0], atol=1e-12)
    turned = motion.poses[2]  # 20 degrees about the axis through (10, 0, 0): that point stays
    np.testing.assert_allclose(turned.point([10.0, 0.0, 0.0]), [10.0, 0.0, 0.0], atol=1e-12)
    with pytest.raises(ValueError, match="appears twice"):
        generated_motion("k", [steer((0.0, 1.0), 1), Rotation([1, 0, 0], [0, 0, 0], (0.0, 1.0), 1, "steer")])


def test_demo_sweep_clearance_health_and_report_numbers(small_sweep_result):
    result = small_sweep_result
    clearance = result.clearances[0]
    # the strut is a cylinder: check the nearest distance against the analytic one at every pose
    centre = np.array([-60.0, 175.0])
    radial = np.linalg.norm(result.centerlines[:, :, :2] - centre, axis=2) - 25.0
    np.testing.assert_allclose(clearance.distance, radial.min(axis=1) - 5.05, atol=0.35)  # 64 facets: chord 0.3 mm
    assert clearance.first_violation is not None and clearance.distance.min() < 25.4
    assert result.min_bend_radius.min() > 0.0
    rows = {row["quantity"]: row for row in result.worst_cases()}
    assert rows["clearance to strut"]["ok"] is False
    assert rows["clearance to strut"]["pose"] == clearance.worst
    assert result.iterations[1:].max() <= 8
    # the free-roll answer coincides at design position and swings far off once the knuckle moves
    assert result.separation[0] < 1e-6 and result.separation.max() > 25.4


def test_rotating_obstacle_is_measured_where_its_body_is():
    problem = demo_problem(0.0, segments=SEGMENTS)
    box = trimesh.creation.box(extents=[10.0, 10.0, 10.0])
    box.apply_translation([-90.0, 150.0, -11.25])
    turned = Pose(axis_angle_matrix(np.array([0.6, 0.0, 0.8]), math.radians(40.0)), np.array([30.0, -60.0, 5.0]))
    motion = BodyMotion("knuckle", (Pose(), turned), np.array([0.0, 1.0]), (Stage("shift", "mm", 0, 2),))
    fixed = Obstacle("box", box.vertices, box.faces)
    moving = Obstacle("box on knuckle", box.vertices, box.faces, body="knuckle")
    result = run_sweep(SweepProblem(problem, None, None, (motion,), (fixed, moving), compare_free_roll=False))
    near_fixed, near_moving = result.clearances
    np.testing.assert_allclose(near_fixed.distance[0], near_moving.distance[0])
    # at pose 1 the box is where the pose puts it (R v + p): measure that box directly, in world coordinates
    there = TriangleIndex(turned.points(box.vertices), box.faces).nearest(result.centerlines[1], problem.hose.outer_radius)
    assert near_moving.distance[1] == pytest.approx(there.distance, abs=1e-9)
    assert abs(near_moving.distance[1] - near_fixed.distance[1]) > 1.0  # the motion matters
    np.testing.assert_allclose(near_moving.on_obstacle[1], there.on_obstacle, atol=1e-9)
    np.testing.assert_allclose(near_moving.on_hose[1], there.on_hose, atol=1e-9)


SWEEP_TOML = THESIS_TOML.replace("[end]\n", '[end]\nbody = "knuckle"\n') + """
[[bodies]]
name = "knuckle"
poses = "knuckle.csv"

[[obstacles]]
file = "strut.stl"
clearance = 20.0
"""

KNUCKLE_CSV = "jounce [mm], x, y, z, qw, qx, qy, qz\n0, 0, 0, 0, 1, 0, 0, 0\n10, 0, 0, 10, 1, 0, 0, 0\n20, 0, 0, 20, 1, 0, 0, 0\n"


def sweep_folder(tmp_path, toml=SWEEP_TOML, csv=KNUCKLE_CSV):
    write(tmp_path / "knuckle.csv", csv)
    strut = trimesh.creation.cylinder(radius=25.0, height=300.0, sections=32)
    strut.apply_translation([-60.0, 175.0, 0.0])
    strut.export(tmp_path / "strut.stl")
    return write(tmp_path / "sweep.toml", toml)


def test_sweep_file_reads_tables_and_meshes(tmp_path):
    sweep = load_sweep(sweep_folder(tmp_path))
    assert sweep.end_body == "knuckle" and sweep.start_body is None
    assert sweep.pose_count == 3 and sweep.stages[0].name == "jounce"
    assert sweep.obstacles[0].name == "strut" and sweep.obstacles[0].clearance == 20.0
    np.testing.assert_allclose(sweep.pose("knuckle", 2).position, [0.0, 0.0, 20.0])


@pytest.mark.parametrize(
    "old, new, fragments",
    [
        ('poses = "knuckle.csv"', 'poses = "nope.csv"', ["body 'knuckle'", "nope.csv", "cannot read"]),
        ('body = "knuckle"', 'body = "wheel"', ["end.body = 'wheel'", "no such body"]),
        ('clearance = 20.0', "clearance = -1.0", ["obstacles[0].clearance = -1.0", "zero or positive"]),
        ('clearance = 20.0', "clearence = 1.0", ["unknown key 'obstacles[0].clearence'", "did you mean 'obstacles[0].clearance'"]),
        ('poses = "knuckle.csv"', 'stages = [{ rotate = [0, 10], axis = [0, 0, 1] }]', ["needs point"]),
        ('file = "strut.stl"', 'file = "knuckle.csv"', ["obstacle 'knuckle'", "cannot be read as a mesh"]),
    ],
    ids=["missing table", "unknown body", "negative clearance", "misspelt key", "rotation without point", "not a mesh"],
)
def test_bad_sweep_files_name_the_field(tmp_path, old, new, fragments):
    assert old in SWEEP_TOML
    with pytest.raises(SweepFileError) as error:
        load_sweep(sweep_folder(tmp_path, SWEEP_TOML.replace(old, new)))
    for fragment in fragments:
        assert fragment in str(error.value)


def test_bad_pose_table_is_named_by_line(tmp_path):
    with pytest.raises(SweepFileError, match=r"knuckle.csv line 3, column z: 'x' is not a number"):
        load_sweep(sweep_folder(tmp_path, csv=KNUCKLE_CSV.replace("10, 0, 0, 10,", "10, 0, 0, x,")))


def run(*args):
    result = runner.invoke(cli.app, [str(a) for a in args])
    return result.exit_code, result.output


def test_cli_sweep_writes_all_files_together(tmp_path):
    out = tmp_path / "out"
    code, output = run("sweep", sweep_folder(tmp_path), "-o", out, "--quiet")
    assert code == 0, output
    assert output == ""
    assert sorted(p.name for p in out.iterdir()) == sorted(SWEEP_FILES)
    html = (out / "report.html").read_text(encoding="utf-8")
    assert "name = &quot;brake hose&quot;" in html  # the input echoed
    assert (out / "view.png").read_bytes().startswith(b"\x89PNG")
    assert trimesh.load(out / "envelope.stl").is_watertight
    assert (out / "poses.csv").read_text().count("\n") == 4  # header and 3 poses


def test_cli_sweep_bad_input_exits_2_and_writes_nothing(tmp_path):
    code, output = run("sweep", sweep_folder(tmp_path, SWEEP_TOML.replace("knuckle.csv", "nope.csv")), "-o", tmp_path / "out")
    assert code == common.BAD_INPUT and "cannot read" in output
    code, output = run("sweep", "-o", tmp_path / "out")
    assert code == common.BAD_INPUT and "--demo" in output
    assert not (tmp_path / "out").exists()


def test_cli_sweep_solver_failure_exits_3_and_writes_nothing(tmp_path, monkeypatch):
    def fail(sweep, **options):
        raise PlacementError("step to pose 2 failed")

    monkeypatch.setattr(sweep_procedure, "run_sweep", fail)
    code, output = run("sweep", sweep_folder(tmp_path), "-o", tmp_path / "out", "-q")
    assert code == common.SOLVER_FAILED and "step to pose 2 failed" in output
    assert not (tmp_path / "out").exists()


def test_cli_sweep_demo_with_progress(tmp_path, monkeypatch):
    monkeypatch.setattr(sweep_demo, "demo_sweep", coarse_demo)
    code, output = run("sweep", "--demo", "-o", tmp_path / "demo")
    assert code == 0, output
    assert "clearance to strut" in output and (tmp_path / "demo" / "report.html").is_file()


def test_jump_check_sends_big_moves_through_continuation(monkeypatch):
    """With the jump limit at zero every pose goes through continuation.follow: same answer."""
    sweep = coarse_demo()
    motion = sweep.motions[0]
    short = BodyMotion(motion.name, motion.poses[:4], motion.travel[:4], (Stage("steer", "deg", 0, 4),))
    sweep = SweepProblem(sweep.problem, None, "knuckle", (short,), compare_free_roll=False)
    fast = run_sweep(sweep)
    monkeypatch.setattr(sweep_procedure, "JUMP_FACTOR", 0.0)
    careful = run_sweep(sweep)
    np.testing.assert_allclose(careful.centerlines, fast.centerlines, atol=1e-6)
    assert careful.iterations[1:].sum() > fast.iterations[1:].sum()


def test_twisting_the_end_body_of_a_u_bend_snaps_and_is_reported():
    """Turning the end fitting's body about the fitting axis twists a planar U-bend until it
    loses stability and jumps out of its plane: the sweep must see it and say where and how far."""
    from hoseline import Hose, Mount, Problem

    hose = Hose(length=400.0, outer_diameter=10.0, bending_stiffness=1.5e5, torsional_stiffness=2.5e6, segments=30)
    problem = Problem(hose, Mount([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]), Mount([0.0, 100.0, 0.0], [1.0, 0.0, 0.0]))
    twist = Rotation([1.0, 0.0, 0.0], [0.0, 100.0, 0.0], (0.0, 360.0), 24, name="twist")
    result = run_sweep(SweepProblem(problem, None, "fitting", (generated_motion("fitting", [twist]),), compare_free_roll=False))
    assert result.snaps, "the loss of stability was not reported"
    snap = result.snaps[0]
    assert 0 < snap.pose < 25 and snap.jump > 1.0
    assert any("stability lost" in event for event in snap.events)
    # the jump stands out from the ordinary pose-to-pose movement
    steps = [np.max(np.linalg.norm(b - a, axis=1)) for a, b in zip(result.centerlines[:-1], result.centerlines[1:])]
    assert snap.jump > 2.0 * np.median(steps)


def test_a_sweep_judges_its_assembly_once_and_a_study_sample_not_at_all():
    """`hoseline sweep` reports the assembly's uniqueness verdict and error estimate (the thesis hose at 180 deg: not
    unique, its mirror image); a study's sweep sample (judge_assembly=False) reads the poses only, so it skips both and
    says so, and its poses are the same."""
    problem = demo_problem(180.0, segments=SEGMENTS)
    motion = BodyMotion("frame", rigid_motion(3), np.arange(3.0), (Stage("step", "", 0, 3),))
    sweep = SweepProblem(problem, "frame", "frame", (motion,), compare_free_roll=False)
    judged, sample = run_sweep(sweep), run_sweep(sweep, judge_assembly=False)
    assert judged.assembly.unique is False and judged.assembly.discretisation_error > 0.0
    assert sample.assembly.unique is None and sample.assembly.discretisation_error is None
    assert "not asked for" in sample.assembly.summary()["uniqueness_not_checked"]
    np.testing.assert_array_equal(sample.centerlines, judged.centerlines)
