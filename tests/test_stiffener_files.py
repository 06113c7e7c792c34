"""The stiffener springs in files: [hose.stiffeners] of the problem file, and the springs of the ADAMS .cmd export."""

import copy
import math
import tomllib
from dataclasses import replace

import numpy as np
import pytest
from test_adams_cmd import ADAMS_NAME, CREATES, DOCUMENTED, REFERS, commands

from hoseline import Hose, Mount, Problem, solve
from hoseline.io.adams_cmd import adams_cmd_text, hose_from_adams, read_adams_cmd, stiffeners_from_adams
from hoseline.io.problem_file import ProblemFileError, problem_from_dict, problem_to_toml
from hoseline.model.stiffeners import thesis_preset

THESIS = {
    "name": "thesis brake hose",
    "hose": {"length": 330.6, "outer_diameter": 10.1, "bending_stiffness": 149563.0, "torsional_stiffness": 2454930.0},
    "start": {"point": [-13.0, 0.0, -11.25], "direction": [0.0, 1.0, 0.0]},
    "end": {"point": [-173.064, -7.0, -11.25], "direction": [1.0, 0.0, 0.0], "twist": 30.0},
}
TABLE = [[-1.0, -0.5], [0.0, 0.0], [0.2, 0.0], [0.3, 40.0], [1.0, 60.0]]


def with_stiffeners(stiffeners: dict, **hose) -> dict:
    data = copy.deepcopy(THESIS)
    data["hose"] |= hose | {"stiffeners": stiffeners}
    return data


def test_the_preset_key_gives_the_thesis_preset_and_its_segments():
    problem = problem_from_dict(with_stiffeners({"preset": "thesis"}))
    preset = thesis_preset(330.6)
    assert problem.hose.stiffeners == preset.stiffeners and problem.hose.segments == preset.segments == 40
    eight = problem_from_dict(with_stiffeners({"preset": "thesis", "springs": 8}, segments=40))  # the same count: fine
    assert eight.hose.stiffeners == thesis_preset(330.6, 8).stiffeners


def test_explicit_springs_angle_and_table():
    problem = problem_from_dict(with_stiffeners({"springs": 8, "angle_deg": 75, "table": TABLE}, segments=50))
    stiffeners = problem.hose.stiffeners
    assert (stiffeners.springs, stiffeners.angle_deg, problem.hose.segments) == (8, 75.0, 50)
    assert stiffeners.table.deformation == (-1.0, 0.0, 0.2, 0.3, 1.0)
    assert stiffeners.table.force == (-0.5, 0.0, 0.0, 40.0, 60.0)
    assert problem_from_dict(copy.deepcopy(THESIS)).hose.stiffeners is None  # no table, no springs


@pytest.mark.parametrize("stiffeners", [{"preset": "thesis"}, {"springs": 8, "angle_deg": 75.0, "table": TABLE}])
def test_round_trip_through_the_written_problem_file(stiffeners):
    problem = problem_from_dict(with_stiffeners(stiffeners))
    text = problem_to_toml(problem)
    assert "[hose.stiffeners]" in text
    again = problem_from_dict(tomllib.loads(text))
    assert again.hose == problem.hose  # the same Stiffeners (a preset is written out explicitly), bit for bit


@pytest.mark.parametrize(
    "stiffeners, hose, fragments",
    [
        ({"springs": 12, "preset": "thesis"}, {}, ["hose.stiffeners.springs = 12", "8 or 16"]),
        ({"preset": "Thesis"}, {}, ["hose.stiffeners.preset", "'thesis'"]),
        ({"preset": "thesis", "angle_deg": 71.0}, {}, ["hose.stiffeners", "preset and angle_deg", "keep"]),
        ({"angle_deg": 71.0}, {}, ["hose.stiffeners", "angle_deg", "table"]),
        ({"table": TABLE}, {}, ["hose.stiffeners", "angle_deg"]),
        ({"angle_deg": 0.0, "table": TABLE}, {}, ["hose.stiffeners.angle_deg = 0.0", "(0, 90]"]),
        ({"angle_deg": 71.0, "table": [[0.0, 1.0]]}, {}, ["hose.stiffeners.table", "at least two"]),
        ({"angle_deg": 71.0, "table": [[0.0, 1.0], [0.0, 2.0]]}, {}, ["hose.stiffeners.table", "pair 1", "increasing"]),
        ({"angle_deg": 71.0, "table": [[0.0, 1.0], [1.0]]}, {}, ["hose.stiffeners.table", "pair 1", "two finite"]),
        ({"angle_deg": 71.0, "table": [[0.0, 1.0], [1.0, "a"]]}, {}, ["hose.stiffeners.table[1][1]"]),
        ({"angle_deg": 71.0, "table": [[0.0, 1.0], [1.0, 1e308]]}, {}, ["hose.stiffeners.table", "pair 1", "units"]),
        ({"preset": "thesis", "count": 8}, {}, ["unknown key 'hose.stiffeners.count'"]),
        ({"preset": "thesis"}, {"segments": 100}, ["hose.segments = 100", "40 elements", "remove hose.segments"]),
        ({"preset": "thesis"}, {"length": 250.0}, ["hose.length = 250 mm", "277.8-2474", "explicitly"]),
        ({"springs": 8, "angle_deg": 10.0, "table": TABLE}, {}, ["hose.stiffeners.angle_deg = 10", "steeper"]),
    ],
)
def test_bad_stiffeners_are_refused_naming_the_field(stiffeners, hose, fragments):
    with pytest.raises(ProblemFileError) as caught:
        problem_from_dict(with_stiffeners(stiffeners, **hose), source="brake.toml")
    message = str(caught.value)
    assert message.startswith("brake.toml: ")
    for fragment in fragments:
        assert fragment in message, message


# --- the .cmd export ---


SPRING_COMMANDS = {
    "data_element create spline": {"spline_name", "adams_id", "x", "y", "linear_extrapolate"},
    "force create direct single_component_force": {
        "single_component_force_name", "adams_id", "type_of_freedom", "i_marker_name", "j_marker_name", "action_only",
        "function",
    },
}


@pytest.fixture(scope="module")
def stiff_hose():
    """The thesis hose with the preset's 8 springs, placed and twisted 30 degrees (a few seconds)."""
    preset = thesis_preset(330.6, springs=8)
    hose = Hose(length=330.6, outer_diameter=10.1, bending_stiffness=149563.0, torsional_stiffness=2454930.0,
                segments=preset.segments, stiffeners=preset.stiffeners)
    mounts = (Mount([-13.0, 0.0, -11.25], [0.0, 1.0, 0.0]), Mount([-173.064, -7.0, -11.25], [1.0, 0.0, 0.0]))
    return solve(Problem(hose, *mounts, end_twist_deg=30.0, name="stiff hose"))


@pytest.fixture(scope="module")
def spring_cmd(stiff_hose, tmp_path_factory):
    path = tmp_path_factory.mktemp("adams_springs") / "hose.cmd"
    path.write_text(adams_cmd_text(stiff_hose))
    return path


def test_springs_round_trip_through_the_cmd_file(stiff_hose, spring_cmd):
    model = read_adams_cmd(spring_cmd)
    back = stiffeners_from_adams(model)
    written = stiff_hose.problem.hose.stiffeners
    assert back.springs == written.springs == 8
    assert back.angle_deg == pytest.approx(written.angle_deg, abs=1e-9)
    np.testing.assert_allclose(back.table.deformation, written.table.deformation, rtol=0, atol=1e-12)
    assert back.table.force == written.table.force
    stations, _ = hose_from_adams(model)  # the spring markers do not disturb the hose parts
    np.testing.assert_allclose(stations, stiff_hose.centerline, atol=1e-6)


def test_spring_markers_sit_on_the_solver_anchors(stiff_hose, spring_cmd):
    """Each spring runs between the points the solver's spring joins (model/stiffeners.py anchors), at the solved shape."""
    model = read_adams_cmd(spring_cmd)
    hose = stiff_hose.problem.hose
    h = hose.segment_length
    anchors = hose.stiffeners.anchors(hose.outer_radius, h, h)
    forces = list(model.spline_forces.values())
    assert len(forces) == hose.stiffeners.springs * (hose.segments - 1)  # between adjacent parts, none at the fittings
    frames, nodes = stiff_hose.frames, stiff_hose.centerline
    for number, (i_marker, j_marker, spline) in enumerate(forces):
        joint, spring = divmod(number, hose.stiffeners.springs)
        expected_j = nodes[joint + 1] + frames[joint].T @ anchors[spring, 0]
        expected_i = nodes[joint + 1] + frames[joint + 1].T @ anchors[spring, 1]
        np.testing.assert_allclose(model.markers[j_marker][0], expected_j, atol=1e-9)
        np.testing.assert_allclose(model.markers[i_marker][0], expected_i, atol=1e-9)
        assert spline == "stiff_hose.spring_table"
    x, y = model.splines["stiff_hose.spring_table"]
    free = h / math.sin(math.radians(hose.stiffeners.angle_deg))  # the thesis' Figure 27: zero deformation there
    np.testing.assert_allclose(x, free + np.array(hose.stiffeners.table.deformation), atol=1e-12)
    assert np.all(y <= 0.0) and y[-1] == -8000.0  # tension pulls the markers together: negative in ADAMS


def test_spring_commands_are_documented_and_refer_to_what_exists(spring_cmd):
    documented = DOCUMENTED | SPRING_COMMANDS
    created = set()
    for line, command, parameters in commands(spring_cmd):
        assert set(parameters) <= documented[command], f"line {line}: {set(parameters) - documented[command]}"
        for key in REFERS & set(parameters):
            assert parameters[key][0].lstrip(".") in created, f"line {line}: {key} not created before"
        for key in (CREATES | {"spline_name", "single_component_force_name"}) & set(parameters):
            name = parameters[key][0]
            assert ADAMS_NAME.fullmatch(name) and name.lstrip(".") not in created, f"line {line}: {name}"
            created.add(name.lstrip("."))
            if key == "model_name":
                created.add(name.lstrip(".") + ".ground")  # every model has its ground part
        if command == "force create direct single_component_force":
            function = " ".join(parameters["function"])
            names = function[function.index("DM(") + 3:].replace(")", "").replace('"', "").split(", ")
            assert [name.lstrip(".") for name in names[:2]] == [parameters[k][0].lstrip(".") for k in
                                                                ("i_marker_name", "j_marker_name")]
            assert names[3].lstrip(".") in created  # the spline, written before
            assert parameters["type_of_freedom"] == ["translational"] and parameters["action_only"] == ["off"]


def test_a_hose_without_springs_writes_none(twisted_hose, tmp_path):
    path = tmp_path / "plain.cmd"
    path.write_text(adams_cmd_text(twisted_hose))
    assert stiffeners_from_adams(read_adams_cmd(path)) is None
    assert "single_component_force" not in path.read_text() and "spline" not in path.read_text()


def test_sixteen_springs_round_trip(stiff_hose, tmp_path):
    """The 16-spring octagon (equations 13-16) reads back too (the shape need not be an equilibrium for the file)."""
    sixteen = replace(stiff_hose.problem.hose.stiffeners, springs=16)
    result = replace(stiff_hose, problem=replace(stiff_hose.problem, hose=replace(stiff_hose.problem.hose,
                                                                                  stiffeners=sixteen)))
    path = tmp_path / "sixteen.cmd"
    path.write_text(adams_cmd_text(result))
    back = stiffeners_from_adams(read_adams_cmd(path))
    assert back.springs == 16 and back.angle_deg == pytest.approx(sixteen.angle_deg, abs=1e-9)
