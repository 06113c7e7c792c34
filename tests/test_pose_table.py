"""Pose tables (CSV): quaternion conventions, and bad input named by line and column."""

import math

import numpy as np
import pytest

from hoseline.io.pose_table import PoseTableError, pose_table_text, read_pose_table
from hoseline.model.motion import Pose, interpolate, matrix_quaternion, quaternion_matrix

HALF = math.sqrt(0.5)


def write(tmp_path, text):
    path = tmp_path / "poses.csv"
    path.write_text(text, encoding="utf-8")
    return path


def test_quaternions_are_scalar_first_and_rotate_body_into_world():
    # a quarter turn about z: (w, x, y, z) = (cos 45, 0, 0, sin 45) takes x to y
    rotation = quaternion_matrix([HALF, 0.0, 0.0, HALF])
    np.testing.assert_allclose(rotation @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(matrix_quaternion(rotation), [HALF, 0.0, 0.0, HALF], atol=1e-15)


def test_quaternion_of_half_turns_and_near_half_turns():
    """matrix_quaternion's branches for a non-positive trace (turns of about 180 degrees about any axis)."""
    rng = np.random.default_rng(1)
    for angle in (math.pi, math.pi - 1e-3, 0.9 * math.pi, 2.2):
        for axis in (*np.eye(3), *rng.normal(size=(5, 3))):
            axis = axis / np.linalg.norm(axis)
            q = np.concatenate([[math.cos(0.5 * angle)], math.sin(0.5 * angle) * axis])
            np.testing.assert_allclose(quaternion_matrix(matrix_quaternion(quaternion_matrix(q))), quaternion_matrix(q),
                                       atol=1e-12)


def test_columns_are_found_by_name_scalar_first_or_last(tmp_path):
    first = read_pose_table(write(tmp_path, "jounce [mm], x, y, z, qw, qx, qy, qz\n0, 1, 2, 3, 0.7071067811865476, 0, 0, 0.7071067811865476\n"), "k")
    last = read_pose_table(write(tmp_path, "jounce [mm], x, y, z, qx, qy, qz, qw\n0, 1, 2, 3, 0, 0, 0.7071067811865476, 0.7071067811865476\n"), "k")
    for motion in (first, last):
        pose = motion.poses[0]
        np.testing.assert_allclose(pose.point([1.0, 0.0, 0.0]), [1.0, 3.0, 3.0], atol=1e-12)
        assert motion.stages[0].name == "jounce" and motion.stages[0].unit == "mm"


def test_round_trip(tmp_path):
    poses = [Pose(quaternion_matrix([1.0, 0.2, -0.1, 0.3]), np.array([1.0, -2.0, 3.5])), Pose()]
    motion = read_pose_table(write(tmp_path, pose_table_text("time [s]", [0.0, 0.5], poses)), "knuckle")
    for read, given in zip(motion.poses, poses):
        np.testing.assert_allclose(read.rotation, given.rotation, atol=1e-12)
        np.testing.assert_allclose(read.position, given.position, atol=1e-12)
    np.testing.assert_allclose(motion.travel, [0.0, 0.5])


def test_slerp_takes_the_short_way_and_the_midpoint():
    a = Pose()
    b = Pose(quaternion_matrix([math.cos(0.5), 0.0, 0.0, math.sin(0.5)]), np.array([2.0, 0.0, 0.0]))
    middle = interpolate(a, b, 0.5)
    np.testing.assert_allclose(middle.rotation, quaternion_matrix([math.cos(0.25), 0.0, 0.0, math.sin(0.25)]), atol=1e-12)
    np.testing.assert_allclose(middle.position, [1.0, 0.0, 0.0])
    flipped = Pose(quaternion_matrix(-matrix_quaternion(b.rotation)), b.position)  # same rotation, other sign
    np.testing.assert_allclose(interpolate(a, flipped, 0.5).rotation, middle.rotation, atol=1e-12)


HEADER = "travel, x, y, z, qw, qx, qy, qz\n"


@pytest.mark.parametrize(
    "text, fragments",
    [
        (HEADER + "0, 0, 0, 0, 1, 0, 0, 0\n1, 0, abc, 0, 1, 0, 0, 0\n", ["line 3, column y", "'abc' is not a number"]),
        (HEADER + "0, 0, 0, 0, 1, 0, 0\n", ["line 2", "7 values", "8 columns"]),
        (HEADER + "0, 0, 0, 0, 2, 0, 0, 0\n", ["line 2", "norm 2", "unit quaternion"]),
        (HEADER + "0, 0, 0, nan, 1, 0, 0, 0\n", ["line 2, column z", "not a finite number"]),
        ("travel, x, y, z, qx, qy, qz\n0, 0, 0, 0, 0, 0, 0\n", ["line 1", "missing qw"]),
        ("x, y, z, qw, qx, qy, qz\n0, 0, 0, 1, 0, 0, 0\n", ["line 1", "first column is 'x'", "travel"]),
        ("travel, x, y, z, qw, qx, qy, qz, roll\n", ["unknown roll"]),
        (HEADER, ["no poses"]),
        ("", ["empty"]),
    ],
    ids=["text", "short row", "not unit", "nan", "missing column", "no travel", "unknown column", "no rows", "empty"],
)
def test_bad_tables_name_line_and_column(tmp_path, text, fragments):
    with pytest.raises(PoseTableError) as error:
        read_pose_table(write(tmp_path, text), "knuckle")
    for fragment in fragments:
        assert fragment in str(error.value)


def test_a_table_that_is_not_utf8_is_refused_with_the_line(tmp_path):
    path = tmp_path / "poses.csv"
    path.write_bytes((HEADER + "0, 0, 0, 0, 1, 0, 0, 0\n# r\xe9f\xe9rence\n").encode("latin-1"))
    with pytest.raises(PoseTableError, match=r"line 3: not UTF-8 text"):
        read_pose_table(path, "knuckle")


@pytest.mark.parametrize(
    "row, fragment",
    [
        ("0, 0, 100001, 0, 1, 0, 0, 0", "line 2, column y: 100001 is outside +-100000 mm"),
        ("0, 0, 0, -1e300, 1, 0, 0, 0", "line 2, column z: -1e+300 is outside +-100000 mm"),
        ("2e9, 0, 0, 0, 1, 0, 0, 0", "line 2, column travel: 2e+09 is outside +-1e+09"),
    ],
    ids=["translation just out", "translation huge", "travel huge"],
)
def test_values_out_of_range_are_named_by_line_and_column(tmp_path, row, fragment):
    with pytest.raises(PoseTableError) as error:
        read_pose_table(write(tmp_path, HEADER + row + "\n"), "knuckle")
    assert fragment in str(error.value)


def test_translations_at_the_bound_are_read(tmp_path):
    motion = read_pose_table(write(tmp_path, HEADER + "0, 100000, -100000, 0, 1, 0, 0, 0\n"), "knuckle")
    np.testing.assert_array_equal(motion.poses[0].position, [1e5, -1e5, 0.0])
