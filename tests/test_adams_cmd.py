"""The ADAMS/View command file: round trip, Z-X-Z angles, beam section, and the commands against the documentation.

hoseline has no ADAMS: the commands are checked against the ADAMS/View command language
documentation (commands and parameter names as ADAMS/View writes them), not run.
"""

import math
import re
from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from hoseline.demos.thesis_hose import GOODYEAR_5052, SHEAR_MODULUS_5052, YOUNGS_MODULUS_5052
from hoseline.io import adams_cmd
from hoseline.io.adams_cmd import (
    AdamsFileError,
    BeamSection,
    adams_cmd_text,
    body313_angles,
    body313_matrix,
    hose_from_adams,
    read_adams_cmd,
)

# ADAMS/View commands and the parameters hoseline writes, from the command language documentation
DOCUMENTED = {
    "defaults units": {"length", "angle", "force", "mass", "time", "coordinate_system_type", "orientation_type"},
    "model create": {"model_name"},
    "defaults coordinate_system": {"default_coordinate_system"},
    "part create rigid_body name_and_position": {"part_name", "adams_id", "location", "orientation", "relative_to"},
    "part create rigid_body mass_properties": {
        "part_name",
        "mass",
        "center_of_mass_marker",
        "inertia_marker",
        "ixx",
        "iyy",
        "izz",
        "ixy",
        "izx",
        "iyz",
    },
    "marker create": {"marker_name", "adams_id", "location", "orientation", "relative_to"},
    "geometry create shape cylinder": {
        "cylinder_name",
        "adams_id",
        "center_marker",
        "angle_extent",
        "length",
        "radius",
        "side_count_for_body",
        "segment_count_for_ends",
    },
    "force create element_like beam": {
        "beam_name",
        "adams_id",
        "i_marker_name",
        "j_marker_name",
        "length",
        "area_of_cross_section",
        "y_shear_area_ratio",
        "z_shear_area_ratio",
        "youngs_modulus",
        "shear_modulus",
        "ixx",
        "iyy",
        "izz",
        "damping_ratio",
    },
    "constraint create joint fixed": {"joint_name", "adams_id", "i_marker_name", "j_marker_name"},
    "force create body gravitational": {
        "gravity_field_name",
        "x_component_gravity",
        "y_component_gravity",
        "z_component_gravity",
    },
}
CREATES = {"model_name", "part_name", "marker_name", "cylinder_name", "beam_name", "joint_name", "gravity_field_name"}
REFERS = {
    "default_coordinate_system",
    "center_marker",
    "center_of_mass_marker",
    "inertia_marker",
    "i_marker_name",
    "j_marker_name",
}
ADAMS_NAME = re.compile(r"\.?[A-Za-z]\w*(\.[A-Za-z]\w*)*")


@pytest.fixture(scope="module")
def cmd_file(twisted_hose, tmp_path_factory):
    path = tmp_path_factory.mktemp("adams") / "hose.cmd"
    path.write_text(adams_cmd_text(twisted_hose))
    return path


def test_round_trip_gives_the_same_stations_and_frames(twisted_hose, cmd_file):
    stations, frames = hose_from_adams(read_adams_cmd(cmd_file))
    np.testing.assert_allclose(stations, twisted_hose.centerline, rtol=0, atol=1e-6)
    np.testing.assert_allclose(frames, twisted_hose.frames, rtol=0, atol=1e-9)


def test_thesis_z_x_z_example():
    """Thesis chapter II: a rod along (5, 2, 1) has the body Z-X-Z angles 111.8014 and 79.48 degrees.

    (The OCR text prints 79.84 once and 79.48 twice; equations 5 and 6 give 79.48.)
    """
    axis = np.array([5.0, 2.0, 1.0]) / math.sqrt(30.0)
    x_axis = np.cross([0.0, 0.0, 1.0], axis)
    x_axis /= np.linalg.norm(x_axis)
    psi, theta, phi = body313_angles(np.column_stack([x_axis, np.cross(axis, x_axis), axis]))
    assert psi == pytest.approx(111.8014, abs=1e-4)
    assert theta == pytest.approx(79.48, abs=1e-2)
    assert math.degrees(math.atan2(5.0, 2.0)) == pytest.approx(180.0 - psi, abs=1e-4)  # equation 5: -theta_1 + 180


@pytest.mark.parametrize("angles", [(30.0, 45.0, 60.0), (-170.0, 120.0, 10.0), (25.0, 0.0, 0.0), (-65.0, 180.0, 0.0)])
def test_euler_angles_round_trip_and_match_an_independent_convention(angles):
    matrix = body313_matrix(angles)
    np.testing.assert_allclose(matrix, Rotation.from_euler("ZXZ", angles, degrees=True).as_matrix(), atol=1e-12)
    np.testing.assert_allclose(body313_angles(matrix), angles, atol=1e-9)


def test_euler_angles_of_random_frames_rebuild_them():
    for matrix in Rotation.random(200, random_state=1).as_matrix():
        np.testing.assert_allclose(body313_matrix(body313_angles(matrix)), matrix, atol=1e-12)


def test_beam_section_of_the_thesis_hose():
    section = BeamSection.from_hose(GOODYEAR_5052, YOUNGS_MODULUS_5052, SHEAR_MODULUS_5052)
    assert section.ixx == pytest.approx(25540.26, rel=1e-9)  # appendix C
    assert section.iyy == section.izz == pytest.approx(510.8053, rel=1e-7)
    assert section.area == pytest.approx(math.pi * 5.05**2)
    default = BeamSection.from_hose(GOODYEAR_5052)  # E from EI and pi r^4 / 4, G = E / 3
    assert default.youngs_modulus == pytest.approx(YOUNGS_MODULUS_5052, rel=1e-7)
    assert default.shear_modulus == pytest.approx(default.youngs_modulus / 3.0)
    assert default.shear_modulus * default.ixx == pytest.approx(GOODYEAR_5052.torsional_stiffness)
    second = BeamSection.from_hose(replace(GOODYEAR_5052, bending_stiffness_2=2.0 * GOODYEAR_5052.bending_stiffness))
    assert second.izz == pytest.approx(2.0 * second.iyy)


def commands(path):
    """(line, command, parameters) of every command of a .cmd file."""
    return [(line, " ".join(words), parameters) for line, words, parameters in adams_cmd._commands(path.read_text())]


def test_commands_and_parameters_are_documented(cmd_file):
    for line, command, parameters in commands(cmd_file):
        assert command in DOCUMENTED, f"line {line}: {command!r} is not a documented command"
        assert set(parameters) <= DOCUMENTED[command], f"line {line}: {set(parameters) - DOCUMENTED[command]}"
        for key, values in parameters.items():
            assert values, f"line {line}: {key} has no value"
            if key in ("location", "orientation"):
                assert len(values) == 3
            if key == "orientation":
                assert all(value.endswith("d") for value in values)  # degrees, explicitly


def test_layout_continuations_and_comments(cmd_file):
    lines = cmd_file.read_text().splitlines()
    for number, (line, following) in enumerate(zip(lines, lines[1:] + ["!"]), start=1):
        if line.startswith("!"):
            continue
        continued = line.endswith("  &")
        assert continued == (following.startswith("   ") and "=" in following), f"line {number}: {line!r}"


def test_names_ids_and_references(cmd_file):
    created, ids = set(), {}
    for line, command, parameters in commands(cmd_file):
        for key in REFERS & set(parameters):
            name = parameters[key][0]
            assert ADAMS_NAME.fullmatch(name) and name.lstrip(".") in created, (
                f"line {line}: {key} = {name} not created before"
            )
        for key in CREATES & set(parameters):
            name = parameters[key][0]
            assert ADAMS_NAME.fullmatch(name), f"line {line}: {name!r} is not an ADAMS name"
            assert name.lstrip(".") not in created, f"line {line}: {name} created twice"
            created.add(name.lstrip("."))
            if key == "model_name":
                created.add(name.lstrip(".") + ".ground")  # every model has its ground part
        if "adams_id" in parameters:
            kind = command.split()[0]  # ids count per kind of object: part, marker, geometry, force, constraint
            assert parameters["adams_id"][0] not in ids.setdefault(kind, set()), f"line {line}: adams_id repeated"
            ids[kind].add(parameters["adams_id"][0])


def test_beams_and_joints_are_placed_as_adams_requires(twisted_hose, cmd_file):
    model = read_adams_cmd(cmd_file)
    h = twisted_hose.problem.hose.segment_length
    beams = [parameters for _, command, parameters in commands(cmd_file) if command == "force create element_like beam"]
    joints = [parameters for _, command, parameters in commands(cmd_file) if command == "constraint create joint fixed"]
    assert len(beams) == twisted_hose.problem.hose.segments - 1 and len(joints) == 2
    for beam in beams:
        i_position, i_axes = model.markers[beam["i_marker_name"][0].lstrip(".")]
        j_position, j_axes = model.markers[beam["j_marker_name"][0].lstrip(".")]
        along = j_axes.T @ (i_position - j_position)  # I in the J marker's frame
        assert 0.99 * h < along[0] <= h  # I lies ahead of J along J's x axis (the beam's axis), about one length
        assert float(beam["length"][0]) == pytest.approx(h)
        assert np.dot(i_axes[:, 0], j_axes[:, 0]) > math.cos(math.radians(30))  # nearly aligned: a small pre-bend
    for joint in joints:
        i_pose, j_pose = (model.markers[joint[key][0].lstrip(".")] for key in ("i_marker_name", "j_marker_name"))
        np.testing.assert_allclose(i_pose[0], j_pose[0], atol=1e-9)
        np.testing.assert_allclose(i_pose[1], j_pose[1], atol=1e-12)
    start, end = (model.markers[joint["i_marker_name"][0].lstrip(".")][0] for joint in joints)
    np.testing.assert_allclose([start, end], twisted_hose.centerline[[0, -1]], atol=1e-9)  # at the fitting tips


def test_mass_and_gravity_are_written_when_the_problem_has_them(twisted_hose):
    heavy = replace(
        twisted_hose,
        problem=replace(
            twisted_hose.problem,
            hose=replace(twisted_hose.problem.hose, mass_per_length=0.2),
            gravity=np.array([0.0, 0.0, -9.81]),
        ),
    )
    text = adams_cmd_text(heavy)
    assert text.count("part create rigid_body mass_properties") == heavy.problem.hose.segments
    assert f"mass = {0.2e-3 * heavy.problem.hose.segment_length:.15g}" in text  # kg/m * mm
    assert "z_component_gravity = -9810.0" in text  # mm/s^2
    assert "mass_properties" not in adams_cmd_text(twisted_hose) and "gravitational" not in adams_cmd_text(twisted_hose)


SNIPPET = """\
! as ADAMS/View writes it, in metres and radians, with a marker placed relative to another part
defaults units  &
   length = meter  &
   angle = rad
defaults coordinate_system  &
   default_coordinate_system = .m.ground
part create rigid_body name_and_position  &
   part_name = .m.p1  &
   location = 1.0, 0.0, 0.0  &
   orientation = 1.5707963267948966, 0.0, 0.0   ! 90 degrees about z
defaults coordinate_system  &
   default_coordinate_system = .m.p1
marker create  &
   marker_name = .m.p1.cm  &
   location = 0.0, 0.0, 0.0
marker create  &
   marker_name = .m.p1.tip  &
   location = 0.5, 0.0, 0.0  &
   orientation = 0.0d, 90.0d, 0.0d
marker create  &
   marker_name = .m.p1.probe  &
   relative_to = .m.ground  &
   location = 0.0, 0.002, 0.0
"""


def test_reader_applies_units_and_reference_frames(tmp_path):
    path = tmp_path / "m.cmd"
    path.write_text(SNIPPET)
    model = read_adams_cmd(path)
    position, rotation = model.parts["m.p1"]
    np.testing.assert_allclose(position, [1000.0, 0.0, 0.0])
    np.testing.assert_allclose(rotation, body313_matrix([90.0, 0.0, 0.0]), atol=1e-12)
    np.testing.assert_allclose(model.markers["m.p1.tip"][0], [1000.0, 500.0, 0.0], atol=1e-9)  # x of p1 is world y
    np.testing.assert_allclose(model.markers["m.p1.tip"][1], body313_matrix([90.0, 90.0, 0.0]), atol=1e-12)
    np.testing.assert_allclose(model.markers["m.p1.probe"][0], [0.0, 2.0, 0.0], atol=1e-12)


@pytest.mark.parametrize(
    "old, new, fragments",
    [
        ("angle = rad", "angle = rad  &\n   orientation_type = body123", ["line 2", "only body313"]),
        ("length = meter", "length = furlong", ["line 2", "length = furlong"]),
        (
            "default_coordinate_system = .m.p1",
            "default_coordinate_system = .m.p9",
            ["line 13", "'m.p9' is not defined"],
        ),
        ("location = 0.5, 0.0, 0.0", "location = 0.5, 0.0", ["line 16", "location has 2 values, expected 3"]),
        ("orientation = 0.0d, 90.0d, 0.0d", "orientation = 0.0d, (90deg), 0.0d", ["line 16", "not a plain angle"]),
    ],
)
def test_reader_errors_name_the_line(tmp_path, old, new, fragments):
    path = tmp_path / "bad.cmd"
    path.write_text(SNIPPET.replace(old, new))
    with pytest.raises(AdamsFileError) as caught:
        read_adams_cmd(path)
    for fragment in fragments:
        assert fragment in str(caught.value)
