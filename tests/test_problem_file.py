"""Problem files: valid ones load and round trip; invalid ones fail with a message naming field, value and fix."""

import math
import re

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



@pytest.mark.parametrize(
    "old, new, fragments",
    [
        ("length = 330.6", "length = 1e300", ["hose.length = 1e+300", "between 1 and 100000 mm"]),
        ("length = 330.6", "length = 0.5", ["hose.length = 0.5", "between 1 and 100000 mm"]),
        ("[-173.064, -7.0, -11.25]", "[1e15, -7.0, -11.25]", ["end.point = [1000000000000000.0, -7.0, -11.25]",
                                                              "within +-100000 mm"]),
        ("bending_stiffness = 149563.0", "bending_stiffness = 1e13", ["hose.bending_stiffness = 10000000000000.0", "1e+12 N*mm^2"]),
        ("bending_stiffness = 149563.0", "youngs_modulus = 1e-3",
         ["hose.torsional_stiffness = 2454930.0 gives 7.21e+06 times the isotropic GJ"]),
        ("outer_diameter = 10.1", "outer_diameter = 100.0", ["hose.outer_diameter = 100.0 mm is more than 1/4 of hose.length"]),
        ("outer_diameter = 10.1", "outer_diameter = 0.01", ["hose.outer_diameter = 0.01", "between 0.1 and 2000 mm"]),
        ("torsional_stiffness = 2454930.0", "torsional_stiffness = 1e11", ["1e+06 times the isotropic GJ", "0.001-1000"]),
        ("torsional_stiffness = 2454930.0", "torsion_factor = 1e4", ["hose.torsion_factor = 10000.0", "between 0.001 and 1000"]),
        ("segments = 10", "segments = 100000", ["hose.segments = 100000", "at most 10000"]),
        ("min_bend_radius = 50.0", "min_bend_radius = 1e9", ["hose.min_bend_radius = 1000000000.0", "at most 100000 mm"]),
        ("min_bend_radius = 50.0", "mass_per_length = 5000.0", ["hose.mass_per_length = 5000.0", "at most 1000 kg/m"]),
        ("twist = 180.0", "twist = 1e9", ["end.twist = 1000000000.0", "within +-3600 degrees"]),
        ("gravity = [0.0, 0.0, 0.0]", "gravity = [0.0, 0.0, -9810.0]", ["environment.gravity", "at most 100 m/s^2"]),
    ],
    ids=["length huge", "length tiny", "coordinate 1e15", "EI huge", "GJ lopsided from E", "diameter vs length",
         "diameter tiny", "GJ lopsided", "torsion factor", "segments", "bend radius", "mass", "twist", "gravity in mm/s^2"],
)
def test_values_outside_sensible_ranges_name_the_field_and_range(tmp_path, old, new, fragments):
    path = write(tmp_path / "bad.toml", bad_toml(old, new))
    with pytest.raises(ProblemFileError) as caught:
        load_problem(path)
    for fragment in fragments:
        assert fragment in str(caught.value)


def test_ranges_admit_their_bounds(thesis_dict):
    """The bounds themselves are sensible inputs: a 1 mm-thin, 90 m hose and a stiff, heavy one load."""
    data = thesis_dict
    data["hose"].update(length=9e4, outer_diameter=0.1, bending_stiffness=1e-3, torsional_stiffness=1e-3 / 1.5 * 1e3,
                        mass_per_length=1e3, segments=10_000, min_bend_radius=1e5)
    data["end"].update(point=[1e5, -1e5, -11.25], twist=-3600.0)
    data["start"]["point"] = [1e5 - 10.0, -1e5, -11.25]
    data["environment"]["gravity"] = [0.0, 0.0, -100.0]
    problem = problem_from_dict(data)
    assert problem.hose.segments == 10_000 and problem.end_twist_deg == -3600.0


def test_a_direction_with_huge_components_is_normalised_not_zeroed(thesis_dict):
    thesis_dict["end"]["direction"] = [1e308, 1e308, 0.0]
    direction = problem_from_dict(thesis_dict).end.direction
    np.testing.assert_allclose(direction, [math.sqrt(0.5), math.sqrt(0.5), 0.0])


def test_a_torsional_stiffness_computed_below_the_range_is_refused(thesis_dict):
    """EI = 1 N*mm^2 and torsion_factor 1e-3 are each in range; the GJ they give (6.7e-4 N*mm^2) is not."""
    del thesis_dict["hose"]["torsional_stiffness"]
    thesis_dict["hose"].update(bending_stiffness=1.0, torsion_factor=1e-3)
    with pytest.raises(ProblemFileError, match=r"hose.torsion_factor = 0.001 gives GJ = 0.000667 N\*mm\^2, outside"
                                               r".*give a larger torsion_factor"):
        problem_from_dict(thesis_dict)


def test_a_torsional_stiffness_computed_above_the_range_asks_for_a_smaller_factor(thesis_dict):
    """Found by the fuzz campaign: EI = 1e11 N*mm^2 with factor 15 gives GJ a rounding over 1e12 N*mm^2; the fix named
    is a smaller factor, not a larger one."""
    del thesis_dict["hose"]["torsional_stiffness"]
    thesis_dict["hose"].update(bending_stiffness=1e11, torsion_factor=15.000000000000004, outer_diameter=80.0)
    with pytest.raises(ProblemFileError, match=r"gives GJ = 1e\+12 N\*mm\^2, outside .*give a smaller torsion_factor"):
        problem_from_dict(thesis_dict)


@pytest.mark.parametrize("bending, diameter, modulus", [(1e11, 10.1, "1.96e+08"), (1e-3, 80.0, "4.97e-10")])
def test_a_bending_stiffness_no_material_of_that_diameter_has_is_refused(thesis_dict, bending, diameter, modulus):
    """EI and the diameter are each in range, but a solid rod of that diameter would need a Young's modulus beyond
    tungsten, or below a lay-flat fire hose: a unit mistake (the fuzz campaign's hoses that could not be placed)."""
    thesis_dict["hose"].update(bending_stiffness=bending, outer_diameter=diameter)
    with pytest.raises(ProblemFileError, match=rf"needs a solid rod of Young.s modulus {re.escape(modulus)} N/mm\^2 .*check the units"):
        problem_from_dict(thesis_dict)


@pytest.mark.parametrize("levels", [400, 100_000])
def test_deeply_nested_arrays_are_refused_naming_the_file(tmp_path, levels):
    """Fuzzing found `[[[[...]]]]` ending in RecursionError: in tomllib beyond ~500 levels, in the validation's
    message below that; the readers of problem, sweep and study files all refuse it as bad input."""
    from hoseline.io.study_file import StudyFileError, load_study
    from hoseline.io.sweep_file import SweepFileError, load_sweep

    path = write(tmp_path / "deep.toml", THESIS_TOML.replace("length = 330.6", "length = " + "[" * levels + "]" * levels))
    for load, error in ((load_problem, ProblemFileError), (load_sweep, SweepFileError), (load_study, StudyFileError)):
        with pytest.raises(error, match=f"{re.escape(str(path))}: arrays or tables nested more than 16 levels deep"):
            load(path)
