"""The command line: exit codes, nothing written on errors, the files written on success."""

import csv
import json
from functools import partial

import numpy as np
import pytest
from cases import BAD_EDITS, THESIS_TOML, bad_toml, write
from typer.testing import CliRunner

from hoseline import cli
from hoseline.commands import common
from hoseline.demos import thesis_hose as demo
from hoseline.io.problem_file import load_problem, problem_to_dict
from hoseline.procedures.placement import sequence as placement

runner = CliRunner()


def run(*args):
    """Run the CLI in-process; return (exit code, all it printed)."""
    result = runner.invoke(cli.app, [str(a) for a in args])
    return result.exit_code, result.output


@pytest.mark.parametrize("old, new, fragments", [case[1:] for case in BAD_EDITS], ids=[case[0] for case in BAD_EDITS])
def test_bad_problem_file_exits_2_and_writes_nothing(tmp_path, old, new, fragments):
    problem = write(tmp_path / "bad.toml", bad_toml(old, new))
    code, output = run("solve", problem, "-o", tmp_path / "out")
    assert code == common.BAD_INPUT
    assert not (tmp_path / "out").exists()
    assert output.startswith("error: ")
    for fragment in fragments:
        assert fragment in output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]  # no staging left behind either


def test_missing_problem_file_exits_2(tmp_path):
    code, output = run("solve", tmp_path / "nope.toml", "-o", tmp_path / "out")
    assert code == common.BAD_INPUT
    assert "cannot read problem file" in output and "nope.toml" in output
    assert not (tmp_path / "out").exists()


def test_solver_failure_exits_3_and_writes_nothing(tmp_path, monkeypatch):
    def fail(problem, **options):
        raise placement.PlacementError("continuation stalled at twist fraction 0.5")

    monkeypatch.setattr(placement, "solve", fail)
    code, output = run("solve", write(tmp_path / "brake.toml", THESIS_TOML), "-o", tmp_path / "out", "--quiet")
    assert code == common.SOLVER_FAILED
    assert "the solver failed: continuation stalled at twist fraction 0.5" in output
    assert not (tmp_path / "out").exists()


def test_unwritable_output_exits_2_before_solving(tmp_path, monkeypatch):
    def fail(problem, **options):
        raise AssertionError("solved although the output cannot be written")

    monkeypatch.setattr(placement, "solve", fail)
    blocker = write(tmp_path / "out", "a file where the output directory should go")
    for out in (blocker, blocker / "inner"):
        code, output = run("solve", write(tmp_path / "brake.toml", THESIS_TOML), "-o", out, "--quiet")
        assert code == common.BAD_INPUT, output
        assert "cannot write to" in output and "is a file, not a directory" in output


@pytest.mark.parametrize("command", ["solve", "demo", "sweep", "compare", "calibrate", "validation-demo"])
def test_every_command_has_help(command):
    code, output = run(command, "--help")
    assert code == 0 and "--out" in output
    if command == "sweep":
        assert "[[bodies]]" in output  # not eaten as console markup


def test_solve_writes_centerline_and_result(tmp_path):
    problem_path = write(tmp_path / "brake.toml", THESIS_TOML)
    out = tmp_path / "out"
    code, output = run("solve", problem_path, "-o", out)
    assert code == 0, output
    assert "stability margin" in output

    with open(out / "centerline.csv", newline="") as stream:
        rows = list(csv.reader(stream))
    assert rows[0] == ["s", "x", "y", "z"]
    table = np.array(rows[1:], dtype=float)
    assert table.shape == (11, 4)  # 10 segments: 11 stations
    np.testing.assert_allclose(table[[0, -1], 0], [0.0, 330.6])
    np.testing.assert_allclose(table[0, 1:], [-13.0, 0.0, -11.25], atol=1e-6)
    np.testing.assert_allclose(table[-1, 1:], [-173.064, -7.0, -11.25], atol=1e-6)

    document = json.loads((out / "result.json").read_text())
    assert document["problem"] == problem_to_dict(load_problem(problem_path))
    assert document["summary"]["segments"] == 10
    for name in ("s", "centerline", "curvature", "twist_rate", "bending_moment", "twisting_moment", "internal_force"):
        assert len(document["stations"][name]) == 11, name
    np.testing.assert_allclose(document["stations"]["centerline"], table[:, 1:], rtol=1e-9, atol=1e-9)


def test_quiet_prints_nothing(tmp_path):
    code, output = run("solve", write(tmp_path / "brake.toml", THESIS_TOML), "-o", tmp_path / "out", "--quiet")
    assert code == 0
    assert output == ""


def test_demo_writes_both_twists_the_exports_and_the_picture(tmp_path, monkeypatch):
    monkeypatch.setattr(demo, "run_demo", partial(demo.run_demo, segments=10))
    out = tmp_path / "demo"
    code, output = run("demo", "-o", out)
    assert code == 0, output
    assert "twist 180" in output
    exports = ("hose.igs", "hose.step", "hose.stl", "hose.ply", "hose.glb", "hose.cmd")
    for twist in ("000", "180"):
        for name in ("problem.toml", "centerline.csv", "result.json") + exports:
            assert (out / f"twist_{twist}" / name).is_file()
    assert output.count("hose.step (") == 2  # each export reported with its size and time
    assert (out / "shapes.png").read_bytes().startswith(b"\x89PNG")
    copied = load_problem(out / "twist_180" / "problem.toml")
    assert problem_to_dict(copied) == problem_to_dict(demo.demo_problem(180.0, segments=10))


def test_demo_mounts_come_from_the_thesis_iges_file():
    problem = demo.demo_problem(0.0)
    np.testing.assert_allclose(problem.start.point, [-13.0, 0.0, -11.25])  # B
    np.testing.assert_allclose(problem.start.direction, [0.0, 1.0, 0.0])  # A -> B
    np.testing.assert_allclose(problem.end.point, [-173.064, -7.0, -11.25])  # D
    np.testing.assert_allclose(problem.end.direction, [1.0, 0.0, 0.0])  # D -> C
    assert problem.hose.bending_stiffness == pytest.approx(149563.0, rel=1e-6)
    assert problem.hose.torsional_stiffness == pytest.approx(2454930.0, rel=1e-6)


def test_the_command_line_starts_without_the_heavy_libraries():
    """`hoseline --help` and every command start fast (issue 9: <= 0.5 s) because the heavy libraries load only where
    they are used; a module-level import of one of them anywhere on the way to the commands breaks that unseen."""
    import subprocess
    import sys

    heavy = ["scipy", "numba", "OCP", "plotly", "matplotlib", "trimesh", "skimage", "dask", "distributed", "uvicorn",
             "starlette"]
    code = ("import sys, hoseline.cli; hoseline.cli.app; "
            f"print(','.join(m for m in {heavy!r} if m in sys.modules))")
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert loaded == "", f"importing the command line loads {loaded}"
