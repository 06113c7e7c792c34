"""Mounts from IGES: the thesis' appendix A file, other labels, units and transformations, and damaged files."""

import io

import numpy as np
import pytest
from cases import THESIS_TOML, write
from OCP.collections import HArray2_double
from OCP.gp import gp_XYZ
from OCP.IGESBasic import IGESBasic_Name
from OCP.IGESControl import IGESControl_Writer
from OCP.IGESGeom import IGESGeom_Point, IGESGeom_TransformationMatrix
from OCP.TCollection import TCollection_HAsciiString
from typer.testing import CliRunner

from hoseline import cli
from hoseline.commands import common
from hoseline.demos.thesis_hose import THESIS_MOUNTS_IGES
from hoseline.io.iges_mounts import FittingLabels, IgesError, mounts_from_iges, read_named_points
from hoseline.io.problem_file import ProblemFileError, load_problem, problem_to_dict

A, B, C, D = (-13.0, -16.0, -11.25), (-13.0, 0.0, -11.25), (-160.0, -7.0, -11.25), (-173.064, -7.0, -11.25)


def thesis_lines() -> list[str]:
    """The appendix A file: line 1 S, 2-5 G, 6-15 D (labels B, D, C, A on lines 9, 11, 13, 15), 16-20 P, 21 T."""
    return THESIS_MOUNTS_IGES.read_text().splitlines()


def with_line(lines: list[str], number: int, text: str) -> list[str]:
    """`lines` with line `number` (1-based) replaced."""
    return lines[: number - 1] + [text] + lines[number:]


def parameter_line(lines: list[str], number: int, data: str) -> list[str]:
    """`lines` with the parameter data (columns 1-64) of line `number` replaced, the rest kept."""
    return with_line(lines, number, data.ljust(64) + lines[number - 1][64:])


def label_line(lines: list[str], number: int, label: str) -> list[str]:
    """`lines` with the label (columns 57-64) of directory line `number` replaced."""
    line = lines[number - 1]
    return with_line(lines, number, line[:56] + label.rjust(8) + line[64:])


def save(tmp_path, lines: list[str], name: str = "mounts.igs"):
    return write(tmp_path / name, "\n".join(lines) + "\n")


def assert_refused(error: type[Exception], call, path, fragments: list[str]) -> None:
    """call() raises `error` with a message that starts with `path` and holds every fragment."""
    with pytest.raises(error) as caught:
        call()
    message = str(caught.value)
    assert message.startswith(str(path)), message
    for fragment in fragments:
        assert fragment in message, message


def test_thesis_file_gives_the_four_points_and_the_thesis_mounts():
    points = read_named_points(THESIS_MOUNTS_IGES)
    assert sorted(points) == ["A", "B", "C", "D"]
    for label, expected in zip("ABCD", (A, B, C, D)):
        np.testing.assert_array_equal(points[label], [expected])
    start, end = mounts_from_iges(THESIS_MOUNTS_IGES)
    np.testing.assert_array_equal(start.point, B)
    np.testing.assert_allclose(start.direction, [0.0, 1.0, 0.0])  # along A -> B, into the hose
    np.testing.assert_array_equal(end.point, D)
    np.testing.assert_allclose(end.direction, [1.0, 0.0, 0.0])  # along D -> C, into the hose


def test_other_labels_and_sides():
    start, end = mounts_from_iges(
        THESIS_MOUNTS_IGES, FittingLabels(tip="A", ahead="B"), FittingLabels(tip="C", behind="D")
    )
    np.testing.assert_array_equal(start.point, A)
    np.testing.assert_allclose(start.direction, [0.0, 1.0, 0.0])  # A -> B
    np.testing.assert_array_equal(end.point, C)
    np.testing.assert_allclose(end.direction, [1.0, 0.0, 0.0])  # D -> C


def test_fitting_needs_exactly_one_axis_point():
    with pytest.raises(ValueError, match="exactly one of 'behind'"):
        FittingLabels(tip="B")
    with pytest.raises(ValueError, match="exactly one of 'behind'"):
        FittingLabels(tip="B", behind="A", ahead="C")


def test_units_transformations_and_name_properties(tmp_path):
    """A file in inches whose point is placed by a 124 matrix and named by a 406 form 15 property."""
    writer = IGESControl_Writer("IN", 0)
    point = IGESGeom_Point()
    point.Init(gp_XYZ(1.0, 0.0, 0.0), None)
    matrix = HArray2_double(1, 3, 1, 4)
    for row, values in enumerate(([0, -1, 0, 10], [1, 0, 0, 20], [0, 0, 1, 30]), start=1):
        for column, value in enumerate(values, start=1):
            matrix.SetValue(row, column, float(value))
    transformation = IGESGeom_TransformationMatrix()
    transformation.Init(matrix)
    point.InitTransf(transformation)
    name = IGESBasic_Name()
    name.Init(1, TCollection_HAsciiString("front fitting tip"))
    point.AddProperty(name)
    point.SetLabel(TCollection_HAsciiString("FRONTTIP"))
    writer.AddEntity(point)
    writer.ComputeModel()
    stream = io.BytesIO()
    assert writer.Write(stream)
    path = tmp_path / "inch.igs"
    path.write_bytes(stream.getvalue())
    points = read_named_points(path)
    np.testing.assert_allclose(points["front fitting tip"], [[254.0, 533.4, 762.0]])  # (10, 21, 30) in * 25.4


@pytest.mark.parametrize(
    "labels, fragments",
    [
        (
            (FittingLabels(tip="X", behind="A"), FittingLabels(tip="D", ahead="C")),
            ["no point labelled 'X'", "found: A, B, C, D"],
        ),
        (
            (FittingLabels(tip="B", behind="a"), FittingLabels(tip="D", ahead="C")),
            ["no point labelled 'a'", "found: A, B, C, D"],
        ),
    ],
)
def test_missing_label_lists_the_labels_found(labels, fragments):
    with pytest.raises(IgesError) as caught:
        mounts_from_iges(THESIS_MOUNTS_IGES, *labels)
    for fragment in fragments:
        assert fragment in str(caught.value)


def test_duplicated_label_is_refused_with_both_places(tmp_path):
    path = save(tmp_path, label_line(thesis_lines(), 11, "B"))  # the point D now also labelled B
    with pytest.raises(IgesError) as caught:
        mounts_from_iges(path)
    message = str(caught.value)
    assert "2 points are labelled 'B'" in message and "(-13, 0, -11.25); (-173.064, -7, -11.25)" in message
    assert "found: A, B (x2), C" in message


def test_coincident_points_are_refused(tmp_path):
    path = save(tmp_path, parameter_line(thesis_lines(), 19, "116,-173.064,-7.0,-11.25,0;"))  # C onto D
    with pytest.raises(IgesError, match="points D and C coincide at \\(-173.064, -7, -11.25\\)"):
        mounts_from_iges(path)


@pytest.mark.parametrize(
    "edit, fragments",
    [
        (
            lambda lines: parameter_line(lines, 18, "116,-173.0x4,-7.0,-11.25,0;"),
            ["line 18", "'-173.0x4' is not a number"],
        ),
        (lambda lines: parameter_line(lines, 18, "116,-173.064,-7.0,-11.25,0"), ["line 18", "do not end with ';'"]),
        (lambda lines: lines[:12], ["line 12", "without its terminate (T) record", "truncated"]),
        (lambda lines: lines[:19] + lines[20:], ["line 20", "counts 5 P lines, the file has 4"]),
        (lambda lines: with_line(lines, 10, lines[9][:40]), ["line 10", "40 characters", "80"]),
        (lambda lines: with_line(lines, 7, lines[6][:73] + "9" + lines[6][74:]), ["line 7", "sequence number"]),
        (
            lambda lines: with_line(lines, 10, lines[9][:8] + "      99" + lines[9][16:]),
            ["line 10", "parameter lines the file does not have"],
        ),
        (lambda lines: ["garbage"], ["line 1", "7 characters"]),
        (lambda lines: [], ["empty"]),
    ],
    ids=[
        "bad number",
        "no record end",
        "truncated",
        "lost line",
        "short line",
        "sequence",
        "bad pointer",
        "not iges",
        "empty",
    ],
)
def test_damaged_files_name_the_line(tmp_path, edit, fragments):
    path = save(tmp_path, edit(thesis_lines()))
    assert_refused(IgesError, lambda: read_named_points(path), path, fragments)


# --- the problem file's [mounts] table ---

# the thesis problem file with its mounts taken from the IGES file in the folder cad/
IGES_TOML = THESIS_TOML.replace(
    "[start]\npoint = [-13.0, 0.0, -11.25]\ndirection = [0.0, 1.0, 0.0]\n", '[mounts]\niges = "cad/mounts.igs"\n'
).replace("point = [-173.064, -7.0, -11.25]\ndirection = [1.0, 0.0, 0.0]\n", "")


@pytest.fixture
def iges_problem(tmp_path):
    """A problem file taking its mounts from the thesis' IGES file, in a folder beside it."""
    (tmp_path / "cad").mkdir()
    (tmp_path / "cad" / "mounts.igs").write_bytes(THESIS_MOUNTS_IGES.read_bytes())
    return write(tmp_path / "brake.toml", IGES_TOML)


def test_problem_file_mounts_from_iges_equal_the_typed_ones(tmp_path, iges_problem):
    typed = load_problem(write(tmp_path / "typed.toml", THESIS_TOML))
    assert problem_to_dict(load_problem(iges_problem)) == problem_to_dict(typed)


def test_problem_file_mounts_with_other_labels(iges_problem):
    text = IGES_TOML.replace('iges = "cad/mounts.igs"', 'iges = "cad/mounts.igs"\nstart = { tip = "A", ahead = "B" }')
    problem = load_problem(write(iges_problem, text))
    np.testing.assert_array_equal(problem.start.point, A)
    np.testing.assert_allclose(problem.start.direction, [0.0, 1.0, 0.0])


@pytest.mark.parametrize(
    "old, new, fragments",
    [
        (
            "[end]\n",
            "[start]\npoint = [0.0, 0.0, 0.0]\ndirection = [0.0, 1.0, 0.0]\n[end]\n",
            ["start given together with [mounts]", "remove start"],
        ),
        (
            "twist = 180.0",
            "twist = 180.0\npoint = [0.0, 0.0, 0.0]",
            ["end.point given together with [mounts]", "keep [end] twist"],
        ),
        ('"cad/mounts.igs"', '"cad/nope.igs"', ['mounts.iges = "cad/nope.igs": cannot read', "nope.igs"]),
        (
            'iges = "cad/mounts.igs"',
            'iges = "cad/mounts.igs"\nend = { tip = "E", ahead = "C" }',
            ["mounts.iges:", "no point labelled 'E'", "A, B, C, D"],
        ),
        (
            'iges = "cad/mounts.igs"',
            'iges = "cad/mounts.igs"\nstart = { tip = "B" }',
            ["mounts.start:", "exactly one of 'behind'"],
        ),
        (
            'iges = "cad/mounts.igs"',
            'igs = "cad/mounts.igs"',
            ["unknown key 'mounts.igs'", "did you mean 'mounts.iges'"],
        ),
        (
            'iges = "cad/mounts.igs"',
            'iges = "cad/mounts.igs"\nstart = { tip = "B", behnd = "A" }',
            ["unknown key 'mounts.start.behnd'", "did you mean 'mounts.start.behind'"],
        ),
    ],
    ids=[
        "start twice",
        "end point twice",
        "no iges file",
        "unknown label",
        "no axis point",
        "misspelt iges",
        "misspelt behind",
    ],
)
def test_problem_file_mounts_errors(iges_problem, old, new, fragments):
    assert old in IGES_TOML
    write(iges_problem, IGES_TOML.replace(old, new, 1))
    assert_refused(ProblemFileError, lambda: load_problem(iges_problem), iges_problem, fragments)


def test_cli_refuses_a_damaged_iges_file_and_writes_nothing(tmp_path, iges_problem):
    save(tmp_path / "cad", parameter_line(thesis_lines(), 18, "116,-173.0x4,-7.0,-11.25,0;"))
    result = CliRunner().invoke(cli.app, ["solve", str(iges_problem), "-o", str(tmp_path / "out")])
    assert result.exit_code == common.BAD_INPUT
    assert "line 18" in result.output and "'-173.0x4' is not a number" in result.output
    assert not (tmp_path / "out").exists()
