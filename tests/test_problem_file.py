"""Problem files: valid ones load and round trip; invalid ones fail with a message naming field, value and fix."""

import math

import numpy as np
import pytest
from cases import BAD_EDITS, THESIS_TOML, bad_toml, write

from hoseline.io.problem_file import (
    ProblemFileError,
    load_problem,
    problem_from_dict,
    problem_to_dict,
    problem_to_toml,
)

THESIS_EI = 292.7985 * 510.8053  # N*mm^2, E * I of Goodyear5052


def test_thesis_file_loads(tmp_path):
    problem = load_problem(write(tmp_path / "brake.toml", THESIS_TOML))
    assert problem.name == "brake hose"
    assert problem.hose.length == 330.6
    assert problem.hose.bending_stiffness == 149563.0
    assert problem.hose.torsional_stiffness == 2454930.0
    assert problem.hose.min_bend_radius == 50.0
    assert problem.hose.segments == 10
    np.testing.assert_array_equal(problem.end.point, [-173.064, -7.0, -11.25])
    np.testing.assert_array_equal(problem.end.direction, [1.0, 0.0, 0.0])
    assert problem.end_twist_deg == 180.0


def test_name_defaults_to_file_stem_and_optional_keys_to_defaults(tmp_path):
    text = THESIS_TOML.replace('name = "brake hose"\n', "").replace("twist = 180.0\n", "")
    text = text.replace("[environment]\ngravity = [0.0, 0.0, 0.0]\n", "").replace("segments = 10\n", "")
    problem = load_problem(write(tmp_path / "front_left.toml", text))
    assert problem.name == "front_left"
    assert problem.end_twist_deg == 0.0
    assert problem.hose.segments == 100
    assert problem.hose.mass_per_length == 0.0
    np.testing.assert_array_equal(problem.gravity, [0.0, 0.0, 0.0])


def test_round_trip_through_dict_and_toml(tmp_path):
    problem = load_problem(write(tmp_path / "brake.toml", THESIS_TOML.replace("[0.0, 0.0, 0.0]", "[0.0, 0.0, -9.81]")))
    echo = problem_to_dict(problem)
    assert problem_to_dict(problem_from_dict(echo)) == echo
    again = load_problem(write(tmp_path / "echo.toml", problem_to_toml(problem)))
    assert problem_to_dict(again) == echo
    assert echo["environment"]["gravity"] == [0.0, 0.0, -9.81]


@pytest.fixture
def thesis_dict(tmp_path):
    """The thesis problem in the problem-file format, as a dict to edit."""
    return problem_to_dict(load_problem(write(tmp_path / "brake.toml", THESIS_TOML)))


def test_youngs_modulus_and_diameters_give_annular_ei(thesis_dict):
    data = thesis_dict
    del data["hose"]["bending_stiffness"]
    data["hose"]["youngs_modulus"] = 292.7985
    solid = problem_from_dict(data).hose.bending_stiffness
    assert solid == pytest.approx(THESIS_EI, rel=1e-6)  # I = pi r^4 / 4 with r = 5.05 mm
    data["hose"]["inner_diameter"] = 4.0
    annular = problem_from_dict(data).hose.bending_stiffness
    assert annular == pytest.approx(292.7985 * math.pi * (10.1**4 - 4.0**4) / 64, rel=1e-12)


def test_torsion_factor_scales_the_isotropic_gj(thesis_dict):
    data = thesis_dict
    del data["hose"]["torsional_stiffness"]
    assert problem_from_dict(data).hose.torsional_stiffness == pytest.approx(149563.0 / 1.5)  # default: isotropic, nu 0.5
    data["hose"]["torsion_factor"] = 25.0
    assert problem_from_dict(data).hose.torsional_stiffness == pytest.approx(25.0 * 149563.0 / 1.5)
    data["hose"]["poisson_ratio"] = 0.3
    assert problem_from_dict(data).hose.torsional_stiffness == pytest.approx(25.0 * 149563.0 / 1.3)


@pytest.mark.parametrize("old, new, fragments", [case[1:] for case in BAD_EDITS], ids=[case[0] for case in BAD_EDITS])
def test_bad_input_names_field_value_and_fix(tmp_path, old, new, fragments):
    path = write(tmp_path / "bad.toml", bad_toml(old, new))
    with pytest.raises(ProblemFileError) as caught:
        load_problem(path)
    message = str(caught.value)
    assert message.startswith(str(path))
    for fragment in fragments:
        assert fragment in message


def test_problem_file_error_is_a_value_error():
    with pytest.raises(ValueError, match="missing table \\[hose\\]"):
        problem_from_dict({"start": {}, "end": {}})


def test_missing_file_raises_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_problem(tmp_path / "nope.toml")

