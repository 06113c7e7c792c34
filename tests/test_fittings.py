"""End fittings (model/fittings.py): the geometry, the overall/free length, the problem file, the
placement between the outlets, and the fittings in the exports and the clearance."""

import copy
import math
import tomllib

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from typer.testing import CliRunner

from hoseline import cli
from hoseline.io.problem_file import ProblemFileError, problem_from_dict, problem_to_dict, problem_to_toml
from hoseline.model.fittings import EndFittings, Fitting
from hoseline.model.hose import Hose
from hoseline.model.mounts import Mount
from hoseline.model.problem import Problem, fitted_problem
from hoseline.procedures.geometry.clearance import TriangleIndex, nearest_with_fittings
from hoseline.procedures.placement.sequence import solve

SEGMENTS = 32
HOSE = {"outer_diameter": 10.0, "bending_stiffness": 150000.0, "torsion_factor": 3.0, "segments": SEGMENTS}
ELBOW = {"length": 25.0, "bend_angle": 90.0, "outlet_length": 30.0, "bend_radius": 10.0, "reference": [0.0, 0.0, 1.0],
         "clocking": 20.0}


def fitted_file(**hose) -> dict:
    """A problem file (as a dict) with a straight start fitting and a clocked 90 degree elbow at the end."""
    return {
        "name": "fitted",
        "hose": HOSE | ({"overall_length": 420.0} if not hose else hose),
        "start": {"point": [0.0, 0.0, 0.0], "direction": [0.0, 1.0, 0.0]},
        "end": {"point": [-160.0, 10.0, 0.0], "direction": [1.0, 0.0, 0.0], "twist": 60.0},
        "fittings": {"start": {"length": 30.0}, "end": dict(ELBOW)},
    }


def quick(problem):
    return solve(problem, estimate_error=False)


# --- geometry ---


def test_a_90_degree_elbow_matches_the_hand_computation():
    port = Mount([10.0, 20.0, 30.0], [1.0, 0.0, 0.0])
    # reference across the axis after projection: [0.3, 1, 0] -> +y; clocked 90 degrees about +x -> +z
    elbow = Fitting(25.0, 90.0, 40.0, 10.0, 90.0, [0.3, 1.0, 0.0])
    outlet = elbow.outlet(port)
    np.testing.assert_allclose(outlet.point, [10.0 + 25.0, 20.0, 30.0 + 40.0], atol=1e-12)
    np.testing.assert_allclose(outlet.direction, [0.0, 0.0, 1.0], atol=1e-15)
    assert elbow.length_allowance == pytest.approx(40.0, abs=1e-12)  # catalogue: to the port axis
    assert elbow.centreline_length == pytest.approx(25.0 + 40.0 - 2 * 10.0 + math.pi / 2 * 10.0)
    line = elbow.centreline(port)
    np.testing.assert_allclose(line[0], port.point)
    np.testing.assert_allclose(line[-1], outlet.point, atol=1e-12)
    arc = line[1:-1]  # on the circle of radius 10 about the centre (25 - 10, 0, 10) from the port
    centre = port.point + [15.0, 0.0, 10.0]
    np.testing.assert_allclose(np.linalg.norm(arc - centre, axis=1), 10.0, atol=1e-12)
    np.testing.assert_allclose(arc[0], port.point + [15.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(arc[-1], port.point + [25.0, 0.0, 10.0], atol=1e-12)


@pytest.mark.parametrize("bend", [30.0, 45.0, 90.0, 135.0])
def test_the_length_allowance_is_the_outlet_offset_along_the_outlet(bend):
    port = Mount([1.0, -2.0, 3.0], [0.2, 1.0, -0.4])
    elbow = Fitting(28.0, bend, 33.0, 5.0, 17.0, [1.0, 0.0, 0.0])
    outlet = elbow.outlet(port)
    assert elbow.length_allowance == pytest.approx(float((outlet.point - port.point) @ outlet.direction), abs=1e-12)
    assert elbow.length_allowance == pytest.approx(33.0 + 28.0 * math.cos(math.radians(bend)), abs=1e-12)
    assert math.degrees(math.acos(np.clip(port.direction @ outlet.direction, -1, 1))) == pytest.approx(bend)
    # the sampled centreline is a chord polygon of the arc: a little shorter than the exact length
    polygon = np.sum(np.linalg.norm(np.diff(elbow.centreline(port), axis=0), axis=1))
    assert polygon == pytest.approx(elbow.centreline_length, rel=1e-3) and polygon <= elbow.centreline_length


def test_overall_and_free_lengths():
    straight, elbow = Fitting(30.0), Fitting(25.0, 90.0, 30.0, 10.0, 0.0, [0.0, 0.0, 1.0])
    ends = EndFittings(Mount([0, 0, 0], [0, 1, 0]), Mount([-160, 10, 0], [1, 0, 0]), straight, elbow)
    assert ends.length_allowance == pytest.approx(60.0)
    assert ends.overall_length(360.0) == pytest.approx(420.0)
    assert ends.free_length(ends.overall_length(333.3)) == pytest.approx(333.3)
    assert EndFittings(ends.start_port, ends.end_port, None, None).length_allowance == 0.0


def test_clocking_turns_the_outlet_about_the_port_axis():
    port = Mount([5.0, 6.0, 7.0], [1.0, 1.0, 0.0])
    base = Fitting(20.0, 60.0, 15.0, 4.0, 0.0, [0.0, 0.0, 1.0]).outlet(port)
    for clocking in (37.0, -90.0, 200.0):
        turned = Fitting(20.0, 60.0, 15.0, 4.0, clocking, [0.0, 0.0, 1.0]).outlet(port)
        spin = Rotation.from_rotvec(math.radians(clocking) * port.direction).as_matrix()
        np.testing.assert_allclose(turned.point, port.point + spin @ (base.point - port.point), atol=1e-12)
        np.testing.assert_allclose(turned.direction, spin @ base.direction, atol=1e-14)
    full_turn = Fitting(20.0, 60.0, 15.0, 4.0, 360.0, [0.0, 0.0, 1.0]).outlet(port)
    np.testing.assert_allclose(full_turn.point, base.point, atol=1e-12)


def test_a_rigid_motion_moves_the_fitting_with_the_port():
    rotation = Rotation.from_rotvec([0.4, -1.1, 0.7]).as_matrix()
    shift = np.array([100.0, -50.0, 12.0])
    port, reference = Mount([5.0, 6.0, 7.0], [0.0, 1.0, 0.3]), np.array([1.0, 0.0, 0.0])
    elbow = Fitting(20.0, 90.0, 15.0, 6.0, 33.0, reference)
    moved = Fitting(20.0, 90.0, 15.0, 6.0, 33.0, rotation @ reference)
    moved_port = Mount(rotation @ port.point + shift, rotation @ port.direction)
    np.testing.assert_allclose(moved.outlet(moved_port).point, rotation @ elbow.outlet(port).point + shift, atol=1e-12)
    np.testing.assert_allclose(moved.outlet(moved_port).direction, rotation @ elbow.outlet(port).direction, atol=1e-14)
    np.testing.assert_allclose(moved.centreline(moved_port), elbow.centreline(port) @ rotation.T + shift, atol=1e-12)


# --- placement ---


def test_a_straight_fitting_is_the_mount_moved_by_its_length():
    """The issue's test: straight fittings f0, f1 give the flexible shape of mounts moved by f along their
    directions with a hose of L - f0 - f1 (exact: the solver sees the same clamps)."""
    overall, f0, f1 = 420.0, 30.0, 45.0
    data = fitted_file(overall_length=overall)
    data["fittings"] = {"start": {"length": f0}, "end": {"length": f1}}
    fitted = problem_from_dict(data)
    start, end = Mount(data["start"]["point"], data["start"]["direction"]), Mount(data["end"]["point"], data["end"]["direction"])
    hose = Hose(overall - f0 - f1, 10.0, 150000.0, fitted.hose.torsional_stiffness, segments=SEGMENTS)
    moved = Problem(hose, Mount(start.point + f0 * start.direction, start.direction),
                    Mount(end.point + f1 * end.direction, end.direction), end_twist_deg=60.0)
    assert fitted.hose.length == pytest.approx(overall - f0 - f1, abs=1e-12)
    a, b = quick(fitted), quick(moved)
    assert np.max(np.abs(a.centerline - b.centerline)) <= 1e-9 * overall
    assert a.summary()["overall_length_mm"] == pytest.approx(overall)
    assert a.summary()["free_length_mm"] == pytest.approx(overall - f0 - f1)


def test_a_clocked_elbow_problem_turns_with_the_world():
    """Ports, reference and gravity turned and shifted together: the same shape, turned and shifted."""
    rotation = Rotation.from_rotvec([0.3, 0.9, -0.5]).as_matrix()
    shift = np.array([40.0, -25.0, 70.0])
    data = fitted_file()
    data["environment"] = {"gravity": [0.0, 0.0, -9.81]}
    data["hose"] = data["hose"] | {"mass_per_length": 0.3}
    turned = copy.deepcopy(data)
    for name in ("start", "end"):
        turned[name]["point"] = (rotation @ data[name]["point"] + shift).tolist()
        turned[name]["direction"] = (rotation @ data[name]["direction"]).tolist()
    turned["fittings"]["end"]["reference"] = (rotation @ ELBOW["reference"]).tolist()
    turned["environment"]["gravity"] = (rotation @ data["environment"]["gravity"]).tolist()
    a, b = quick(problem_from_dict(data)), quick(problem_from_dict(turned))
    assert np.max(np.linalg.norm(a.centerline @ rotation.T + shift - b.centerline, axis=1)) < 1e-6 * 420.0
    np.testing.assert_allclose(a.centerline[-1] @ rotation.T + shift, b.centerline[-1], atol=1e-9)


def test_the_problem_refuses_mounts_that_are_not_the_outlets():
    fitted = problem_from_dict(fitted_file())
    with pytest.raises(ValueError, match="not the outlet of its fitting"):
        Problem(fitted.hose, fitted.fittings.start_port, fitted.end, fittings=fitted.fittings)
    built = fitted_problem(fitted.hose, fitted.fittings.start_port, fitted.fittings.end_port, fitted.fittings.start,
                           fitted.fittings.end, end_twist_deg=60.0)
    np.testing.assert_allclose(built.end.point, fitted.end.point, atol=1e-12)


# --- problem file ---


def test_the_problem_file_round_trips_with_fittings():
    problem = problem_from_dict(fitted_file())
    assert problem.hose.length == pytest.approx(420.0 - 30.0 - 30.0)  # 90 degree elbow: its outlet leg only
    np.testing.assert_allclose(problem.start.point, [0.0, 30.0, 0.0])
    for again in (problem_from_dict(problem_to_dict(problem)), problem_from_dict(tomllib.loads(problem_to_toml(problem)))):
        assert again.hose == problem.hose
        for name in ("start", "end"):
            np.testing.assert_allclose(getattr(again, name).point, getattr(problem, name).point, atol=1e-12)
            np.testing.assert_allclose(getattr(again, name).direction, getattr(problem, name).direction, atol=1e-15)
        np.testing.assert_allclose(again.fittings.end_port.point, [-160.0, 10.0, 0.0])
        assert again.fittings.start.length == 30.0 and again.fittings.end.clocking_deg == 20.0
    # the written file gives the ports and the free length
    written = problem_to_dict(problem)
    assert written["start"]["point"] == [0.0, 0.0, 0.0] and written["hose"]["length"] == pytest.approx(360.0)
    assert "[fittings.end]" in problem_to_toml(problem)


def test_length_gives_the_free_length_directly():
    problem = problem_from_dict(fitted_file(length=360.0))
    assert problem.hose.length == 360.0
    assert problem.fittings.overall_length(problem.hose.length) == pytest.approx(420.0)


def _edit(path: str, value):
    def apply(data):
        *tables, key = path.split(".")
        target = data
        for table in tables:
            target = target[table]
        if value is None:
            del target[key]
        else:
            target[key] = value
        return data

    return apply


BAD = [
    ("both lengths", _edit("hose.length", 360.0), ["both length and overall_length", "keep one"]),
    ("overall within the fittings", _edit("hose.overall_length", 50.0),
     ["hose.overall_length = 50.0", "not longer than the 60 mm the fittings take up"]),
    ("free length short of the outlets", _edit("hose.overall_length", 200.0),
     ["leaves a free length of 140 mm", "between the fitting outlets", "overall_length above"]),
    ("bend over 180", _edit("fittings.end.bend_angle", 200.0), ["fittings.end: bend_angle = 200.0", "[0, 180)"]),
    ("elbow without reference", _edit("fittings.end.reference", None), ["fittings.end", "needs reference"]),
    ("clocked straight fitting", _edit("fittings.start.clocking", 30.0),
     ["fittings.start: clocking given for a straight fitting", "remove clocking"]),
    ("misspelt key", _edit("fittings.start.lenght", 3.0), ["unknown key 'fittings.start.lenght'", "did you mean"]),
    ("negative length", _edit("fittings.start.length", -5.0), ["fittings.start.length = -5.0", "zero or positive"]),
    ("reference along the port", _edit("fittings.end.reference", [-2.0, 0.0, 0.0]), ["along the port direction"]),
    ("bend radius too large", _edit("fittings.end.bend_radius", 40.0), ["tangent length", "smaller bend_radius"]),
]


@pytest.mark.parametrize("edit, fragments", [case[1:] for case in BAD], ids=[case[0] for case in BAD])
def test_bad_fittings_are_refused_naming_the_field(edit, fragments):
    with pytest.raises(ProblemFileError) as caught:
        problem_from_dict(edit(fitted_file()), source="p.toml")
    message = str(caught.value)
    assert message.startswith("p.toml: ")
    for fragment in fragments:
        assert fragment in message


# --- outputs ---


@pytest.fixture(scope="module")
def fitted_result():
    return quick(problem_from_dict(fitted_file()))


def test_solve_prints_both_lengths_and_writes_them(tmp_path):
    path = tmp_path / "fitted.toml"
    path.write_text(problem_to_toml(problem_from_dict(fitted_file())))
    result = CliRunner().invoke(cli.app, ["solve", str(path), "-o", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    assert "free length 360.00 mm, overall length 420.00 mm" in " ".join(result.output.split())
    text = (tmp_path / "out" / "result.json").read_text()
    assert '"overall_length_mm": 420.0' in text and '"free_length_mm": 360.0' in text


def test_step_holds_each_fitting_as_a_solid(fitted_result):
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps

    from hoseline.io.step_shape import fitting_shapes, step_bytes

    text = step_bytes(fitted_result).decode()
    for name in ("hose", "centerline", "fitting_start", "fitting_start_centerline", "fitting_end", "fitting_end_centerline"):
        assert f"PRODUCT('{name}'" in text
    assert text.count("MANIFOLD_SOLID_BREP") == 3
    fittings = fitted_result.problem.fittings
    for _, port, fitting in fittings.pieces():  # a round tube: pi r^2 times the centreline length (Pappus on the bend)
        solid, _ = fitting_shapes(port, fitting, 5.0)
        properties = GProp_GProps()
        BRepGProp.VolumeProperties_s(solid, properties)
        assert properties.Mass() == pytest.approx(math.pi * 25.0 * fitting.centreline_length, rel=1e-6)


def test_iges_holds_each_fitting_centreline(fitted_result):
    from OCP.IFSelect import IFSelect_ReturnStatus
    from OCP.IGESControl import IGESControl_Reader

    from hoseline.io.iges_shape import iges_bytes

    import tempfile, pathlib

    with tempfile.TemporaryDirectory() as folder:
        path = pathlib.Path(folder) / "hose.igs"
        path.write_bytes(iges_bytes(fitted_result))
        reader = IGESControl_Reader()
        assert reader.ReadFile(str(path)) == IFSelect_ReturnStatus.IFSelect_RetDone
    model = reader.IGESModel()
    polylines = {}
    for number in range(1, model.NbEntities() + 1):
        entity = model.Entity(number)
        if entity.TypeNumber() == 106:
            polylines[entity.ShortLabel().ToCString().strip()] = entity
    assert set(polylines) == {"POLYLINE", "FITSTART", "FITEND"}
    fittings = fitted_result.problem.fittings
    for label, port, fitting in (("FITSTART", fittings.start_port, fittings.start), ("FITEND", fittings.end_port, fittings.end)):
        line = polylines[label]
        corners = [line.Point(index).Coord() for index in range(1, line.NbPoints() + 1)]
        np.testing.assert_allclose(corners, fitting.centreline(port), atol=1e-6)


def test_adams_holds_each_fitting_as_a_part_fixed_at_its_port(fitted_result, tmp_path):
    from hoseline.io.adams_cmd import adams_cmd_text, hose_from_adams, read_adams_cmd

    path = tmp_path / "hose.cmd"
    path.write_text(adams_cmd_text(fitted_result))
    model = read_adams_cmd(path)
    stations, _ = hose_from_adams(model)  # the fitting parts carry no cylinder: the hose reads back alone
    np.testing.assert_allclose(stations, fitted_result.centerline, atol=1e-6)
    fittings = fitted_result.problem.fittings
    for name, port, fitting in fittings.pieces():
        part = f"fitted.fitting_{name}"  # the reader drops the leading dot
        assert part in model.parts
        np.testing.assert_allclose(model.markers[f"{part}.port"][0], port.point, atol=1e-6)
        np.testing.assert_allclose(model.markers[f"{part}.outlet"][0], fitting.outlet(port).point, atol=1e-6)
    text = path.read_text()
    assert "joint_name = .fitted.fix_fitting_start" in text and "j_marker_name = .fitted.ground.end_port" in text
    assert "j_marker_name = .fitted.fitting_start.outlet" in text  # the hose is held by the fitting


def test_the_clearance_includes_the_fittings(fitted_result):
    fittings = fitted_result.problem.fittings
    port, fitting = fittings.start_port, fittings.start
    # a triangle pointing a corner at the middle of the straight start fitting from 20 mm beside it
    side = np.array([1.0, 0.0, 0.0])
    middle = port.point + 0.5 * fitting.length * port.direction
    triangle = np.array([middle + 20.0 * side, middle + 30.0 * side + [0, 0, 5], middle + 30.0 * side + [0, 0, -5]])
    index = TriangleIndex(triangle, np.array([[0, 1, 2]]))
    hose_only = index.nearest(fitted_result.centerline, 5.0)
    pieces = tuple(None if f is None else (f.centreline(p), f.radius(10.0))
                   for p, f in ((fittings.start_port, fittings.start), (fittings.end_port, fittings.end)))
    found = nearest_with_fittings(index, fitted_result.centerline, 5.0, pieces)
    assert found.distance == pytest.approx(20.0 - 5.0, abs=1e-9)
    assert found.distance < hose_only.distance
    assert found.s == pytest.approx(-0.5 * fitting.length, abs=1e-9)  # on the start fitting, before the outlet


def test_a_sweep_carries_the_fitting_with_its_body_into_the_clearance():
    from dataclasses import replace

    from hoseline.io.sweep_file import sweep_from_dict
    from hoseline.model.sweep import Obstacle
    from hoseline.procedures.sweep.quasi_static import run_sweep

    data = fitted_file()
    data["end"]["body"] = "bracket"
    data["bodies"] = [{"name": "bracket", "stages": [{"name": "lift", "translate": [0.0, 12.0], "axis": [0, 0, 1],
                                                     "steps": 2}]}]
    sweep = sweep_from_dict(data)
    port, fitting = sweep.problem.fittings.end_port, sweep.problem.fittings.end
    middle = port.point + 0.5 * (fitting.length - fitting.tangent_length) * port.direction  # on the port leg
    side = np.array([0.0, -1.0, 0.0])
    corner = np.array([middle + 20.0 * side, middle + 30.0 * side + [5, 0, 0], middle + 30.0 * side + [-5, 0, 0]])
    sweep = replace(sweep, obstacles=(Obstacle("block", corner, np.array([[0, 1, 2]]), clearance=1.0),),
                    compare_free_roll=False)
    result = run_sweep(sweep)
    (found,) = result.clearances
    index = TriangleIndex(corner, np.array([[0, 1, 2]]))
    for k, lift in enumerate([0.0, 6.0, 12.0]):
        fitting_distance = math.hypot(20.0, lift) - 5.0  # the port leg moved up with the bracket
        hose_distance = index.nearest(result.centerlines[k], 5.0).distance
        assert found.distance[k] == pytest.approx(min(fitting_distance, hose_distance), abs=1e-9)
    assert found.distance[0] == pytest.approx(15.0, abs=1e-9)
    assert found.s[0] > sweep.problem.hose.length  # on the end fitting, beyond the flexible hose


def test_step_fittings_with_a_sharp_corner_and_a_too_tight_bend():
    from OCP.BRepCheck import BRepCheck_Analyzer

    from hoseline.io.step_shape import SweepError, fitting_shapes

    port = Mount([0.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    sharp, _ = fitting_shapes(port, Fitting(25.0, 45.0, 30.0, 0.0, 10.0, [1.0, 0.0, 0.0]), 5.0)
    assert BRepCheck_Analyzer(sharp).IsValid()
    with pytest.raises(SweepError, match="not above its outer radius 5 mm"):
        fitting_shapes(port, Fitting(25.0, 90.0, 30.0, 3.0, 0.0, [1.0, 0.0, 0.0]), 5.0)


def test_fittings_sit_on_ports_read_from_iges():
    from hoseline.demos.thesis_hose import THESIS_MOUNTS_IGES

    data = {"hose": HOSE | {"overall_length": 400.0}, "mounts": {"iges": str(THESIS_MOUNTS_IGES)},
            "end": {"twist": 0.0}, "fittings": {"start": {"length": 20.0}}}
    plain = problem_from_dict({**data, "hose": HOSE | {"length": 400.0}, "fittings": {}})
    fitted = problem_from_dict(data)
    np.testing.assert_allclose(fitted.fittings.start_port.point, plain.start.point)
    np.testing.assert_allclose(fitted.start.point, plain.start.point + 20.0 * plain.start.direction, atol=1e-12)
    np.testing.assert_allclose(fitted.end.point, plain.end.point)
    assert fitted.hose.length == pytest.approx(380.0) and plain.fittings is None
