"""The bad inputs of issue 9 (and what the fuzzer found): each refused with exit 2, its place named, nothing written."""

import pytest
from cases import THESIS_TOML, write
from typer.testing import CliRunner

from hoseline import cli
from hoseline.commands import common
from hoseline.procedures.placement import sequence
from hoseline.procedures.sweep import quasi_static

SWEEP_TOML = THESIS_TOML.replace("[end]\n", '[end]\nbody = "knuckle"\n') + """
[[bodies]]
name = "knuckle"
poses = "knuckle.csv"
"""
HEADER = "jounce [mm], x, y, z, qw, qx, qy, qz\n"


def run(*args):
    """Exit code and output of the CLI run in-process; a traceback fails the test."""
    result = CliRunner().invoke(cli.app, [str(a) for a in args], catch_exceptions=False)
    return result.exit_code, result.output


@pytest.fixture
def no_solving(monkeypatch):
    """Fail the test if the solver is reached: bad input must be refused before any solving."""

    def solve(*args, **options):
        raise AssertionError("the solver ran on input that should have been refused")

    monkeypatch.setattr(quasi_static, "run_sweep", solve)
    monkeypatch.setattr(sequence, "solve", solve)


@pytest.mark.parametrize(
    "rows, fragments",
    [
        ("0, 0, 0, 0, 1, 0, 0, 0\n1, 0, 0, 1e300, 1, 0, 0, 0\n", ["knuckle.csv line 3, column z", "1e+300", "100000 mm"]),
        ("0, 0, 0, 0, 1, 0, 0, 0\n1e300, 0, 0, 0, 1, 0, 0, 0\n", ["knuckle.csv line 3, column jounce [mm]", "1e+300"]),
        # pose 4 moves the end mount 2000 mm: refused before solving, naming the pose, both numbers and the fix
        ("0, 0, 0, 0, 1, 0, 0, 0\n5, 0, 0, 5, 1, 0, 0, 0\n10, 0, 0, 10, 1, 0, 0, 0\n15, 0, 0, 15, 1, 0, 0, 0\n"
         "2000, -2000, 0, 0, 1, 0, 0, 0\n",
         ["at pose 4 (jounce = 2000 mm)", "the mounts are 2160.",  "mm apart and the hose is 330.6 mm long",
          "use a hose longer than 2160."]),
    ],
    ids=["translation 1e300", "travel 1e300", "mounts 2160 mm apart at pose 4"],
)
def test_pose_tables_out_of_range_or_reach_exit_2_before_solving(tmp_path, no_solving, rows, fragments):
    write(tmp_path / "knuckle.csv", HEADER + rows)
    code, output = run("sweep", write(tmp_path / "sweep.toml", SWEEP_TOML), "-o", tmp_path / "out", "-q")
    assert code == common.BAD_INPUT, output
    for fragment in fragments:
        assert fragment in output
    assert not (tmp_path / "out").exists()


def test_a_generated_stage_out_of_reach_is_named_by_its_travel(tmp_path, no_solving):
    text = THESIS_TOML.replace("[end]\n", '[end]\nbody = "knuckle"\n') + """
[[bodies]]
name = "knuckle"
stages = [{ name = "jounce", translate = [0.0, 400.0], axis = [0, 0, 1], steps = 4 }]
"""
    code, output = run("sweep", write(tmp_path / "sweep.toml", text), "-o", tmp_path / "out", "-q")
    assert code == common.BAD_INPUT
    assert "at pose 3 (jounce = 300 mm) the mounts are 340.102 mm apart" in output  # |(160.064, 7, 300)| > 330.6
    assert not (tmp_path / "out").exists()


def test_an_output_folder_name_too_long_for_the_file_system_exits_2(tmp_path, no_solving):
    out = tmp_path / ("x" * 300)
    code, output = run("solve", write(tmp_path / "brake.toml", THESIS_TOML), "-o", out, "-q")
    assert code == common.BAD_INPUT
    assert "cannot write to" in output and "File name too long" in output and "shorter -o" in output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["brake.toml"]


@pytest.mark.parametrize("value", ["1e308", "1e15", "-100001"])
def test_coordinates_out_of_any_sensible_range_exit_2(tmp_path, no_solving, value):
    text = THESIS_TOML.replace("[-173.064, -7.0, -11.25]", f"[{value}, -7.0, -11.25]")
    code, output = run("solve", write(tmp_path / "brake.toml", text), "-o", tmp_path / "out", "-q")
    assert code == common.BAD_INPUT
    assert "end.point = [" in output and "within +-100000 mm" in output
    assert "mount distance" not in output  # not taken as a number and compared with the hose
    assert not (tmp_path / "out").exists()


def test_iges_points_out_of_range_are_named_by_label(tmp_path, no_solving):
    from fuzz_cases import IGES_FILE, IGES_PROBLEM

    iges = IGES_FILE.read_text().replace("116,-173.064,-7.0,-11.25,0;", "116,-1.73E15,-7.0,-11.25,0;")
    write(tmp_path / "mounts.igs", iges)
    code, output = run("solve", write(tmp_path / "problem.toml", IGES_PROBLEM.decode()), "-o", tmp_path / "out", "-q")
    assert code == common.BAD_INPUT, output
    assert "mounts.iges" in output and "point D at (-1.73e+15, -7, -11.25) mm lies outside +-100000 mm" in output


def test_a_mesh_whose_text_is_not_utf8_is_refused_as_such(tmp_path, no_solving):
    """A damaged ASCII STL made trimesh reach for an optional module; the message said only that it was missing."""
    from fuzz_cases import SWEEP_TOML as WITH_MESH
    from fuzz_cases import strut_mesh

    stl = strut_mesh("stl")
    write(tmp_path / "knuckle.csv", HEADER + "0, 0, 0, 0, 1, 0, 0, 0\n")
    (tmp_path / "strut.stl").write_bytes(stl[:30] + b"\xff\xfe" + stl[30:])
    code, output = run("sweep", write(tmp_path / "sweep.toml", WITH_MESH.replace("{ext}", "stl")), "-o", tmp_path / "out")
    assert code == common.BAD_INPUT
    assert "strut.stl: cannot be read as a mesh: its text is neither ASCII nor UTF-8" in output
    assert not (tmp_path / "out").exists()


def test_a_division_by_zero_in_the_compiled_newton_is_a_failed_solve_not_a_traceback(monkeypatch):
    """The long fuzz run met a nearly weightless-stiff, heavy 11.8 m hose whose Newton kernel divided
    by zero; the solve must report non-convergence so that the placement fails with where and why."""
    import numpy as np

    from hoseline.demos.thesis_hose import demo_problem
    from hoseline.mechanics import newton
    from hoseline.mechanics.rod import RodState
    from hoseline.procedures.placement.path import PlacementPath
    from hoseline.procedures.placement.sequence import rod_properties

    def divides_by_zero(*args):
        raise ZeroDivisionError("division by zero")

    problem = demo_problem(0.0)
    props = rod_properties(problem)
    clamps = PlacementPath(problem).place(0.5)
    state = RodState(np.repeat(clamps.start_frame[None], props.segments, axis=0), np.zeros(3))
    monkeypatch.setattr(newton, "_track_kernel", divides_by_zero)
    same, report = newton.solve_equilibrium(props, clamps, state)
    assert not report.converged and "division by zero" in report.message and same is state


def test_neutral_margin_is_relative_to_the_weight_of_a_heavy_soft_hose():
    """A stability margin at rounding level must be judged against the terms it is made of: for a
    heavy hose of tiny EI those are weight terms (|q| L), not EI/L^2, which would call rounding noise
    of 1e-12 N 'unstable' (seen in the long fuzz run)."""
    import numpy as np

    from hoseline.mechanics.rod import Clamps, RodState
    from hoseline.procedures.placement.stations import NEUTRAL_MARGIN, neutral_scale

    class Props:
        largest_stiffness, length = 0.17, 1000.0  # N*mm^2, mm

    state = RodState(frames=np.zeros((4, 3, 3)), end_force=np.array([0.0, 0.0, -2.0]))
    heavy = Clamps(np.zeros(3), np.eye(3), None, None, False, line_weight=np.array([0.0, 0.0, -0.05]))  # N/mm
    assert neutral_scale(Props, heavy, state) == pytest.approx(0.05 * 1000.0)
    assert NEUTRAL_MARGIN * neutral_scale(Props, heavy, state) > 3e-12 > NEUTRAL_MARGIN * 0.17 / 1000.0**2


def test_a_mesh_whose_vertices_are_not_3d_points_is_refused_by_the_reader():
    """An OBJ with a damaged line (found by the fuzz campaign) that trimesh reads as 2D vertices:
    refused by read_mesh, not a traceback in the clearance tree."""
    from pathlib import Path

    from hoseline.io.obstacle_mesh import ObstacleFileError, read_mesh

    # 26: read unprocessed (trimesh would drop non-finite triangles silently), its vertices not merged
    with pytest.raises(ObstacleFileError, match=r"vertices of shape \(26, 2\).*export the mesh again"):
        read_mesh(Path(__file__).parent / "data" / "fuzz_damaged_vertex.obj")
