"""hoseline solve --hysteresis: the twist up and back down written to hysteresis.csv, the largest band in the summary."""

import csv
import re

import numpy as np
import pytest
from typer.testing import CliRunner

from hoseline import cli
from hoseline.io.problem_file import problem_to_toml
from test_hysteresis import thesis_problem

runner = CliRunner()


@pytest.fixture(scope="module")
def problem_file(tmp_path_factory):
    """The thesis brake hose of test_hysteresis with 30 segments: twisted up it folds between 600 and 610 deg, on
    the way down between 120 and 110 deg."""
    path = tmp_path_factory.mktemp("hysteresis") / "brake.toml"
    path.write_text(problem_to_toml(thesis_problem(30)), encoding="utf-8")
    return path


def solve_with_hysteresis(problem_file, out, largest, *options):
    """(output, rows of hysteresis.csv as float arrays keyed by column)."""
    result = runner.invoke(cli.app, ["solve", str(problem_file), "-o", str(out), "--hysteresis", largest, *options])
    assert result.exit_code == 0, result.output
    assert f"wrote {out / 'hysteresis.csv'}" in result.output
    with open(out / "hysteresis.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    columns = {key: np.array([float(row[key]) for row in rows]) for key in rows[0]}
    return result.output, columns


def test_a_fold_opens_a_band_and_the_summary_names_its_largest(problem_file, tmp_path):
    output, columns = solve_with_hysteresis(problem_file, tmp_path / "out", "720deg")
    np.testing.assert_allclose(columns["twist_deg"], np.arange(0.0, 721.0, 10.0))
    stations = np.column_stack([columns[f"band_station_{k}_mm"] for k in range(31)])
    np.testing.assert_allclose(columns["largest_band_mm"], stations.max(axis=1))
    assert np.all(stations[:, [0, -1]] < 1e-6)  # mm: both ways end at the same fittings
    widest = int(np.argmax(columns["largest_band_mm"]))
    assert columns["largest_band_mm"][widest] > 100.0  # mm: the snapped shape against the unsnapped one
    twists, widths = columns["twist_deg"], columns["largest_band_mm"]
    open_ = (twists >= 120.0) & (twists <= 600.0)  # between the fold down (110-120 deg) and the fold up (600-610 deg)
    assert np.all(widths[open_] > 100.0) and np.all(widths[~open_] < 1e-6)
    line = re.search(r"largest band ([0-9.e+-]+) mm at ([0-9.]+) deg twist", " ".join(output.split()))
    assert line is not None, output
    assert float(line.group(1)) == pytest.approx(columns["largest_band_mm"][widest], rel=1e-3)
    assert float(line.group(2)) == columns["twist_deg"][widest]


def test_without_a_fold_the_band_is_zero(problem_file, tmp_path):
    _, columns = solve_with_hysteresis(problem_file, tmp_path / "out", "360")
    np.testing.assert_allclose(columns["twist_deg"], np.arange(0.0, 361.0, 10.0))
    assert np.max(columns["largest_band_mm"]) < 1e-6  # mm: up and down along the same shapes


def test_a_largest_twist_off_the_ten_degree_grid_gets_even_steps(problem_file, tmp_path):
    _, columns = solve_with_hysteresis(problem_file, tmp_path / "out", "25")
    np.testing.assert_allclose(columns["twist_deg"], np.linspace(0.0, 25.0, 4))


@pytest.mark.parametrize("value", ["abc", "0", "nan", "1e6"])
def test_a_bad_largest_twist_exits_2_and_writes_nothing(problem_file, tmp_path, value):
    result = runner.invoke(cli.app, ["solve", str(problem_file), "-o", str(tmp_path / "out"), "--hysteresis", value])
    assert result.exit_code == 2
    assert "--hysteresis" in result.output and "degrees" in result.output
    assert not (tmp_path / "out").exists()


def test_a_problem_with_contact_is_refused(problem_file, tmp_path):
    touching = tmp_path / "self.toml"
    touching.write_text(problem_file.read_text(encoding="utf-8") + "\n[contact]\nself = true\n", encoding="utf-8")
    result = runner.invoke(cli.app, ["solve", str(touching), "-o", str(tmp_path / "out"), "--hysteresis", "90"])
    assert result.exit_code == 2 and "--hysteresis does not take contact yet" in result.output
    assert not (tmp_path / "out").exists()


def test_joint_friction_leaves_a_set_at_zero_twist_that_the_elastic_model_does_not(tmp_path):
    """The friction model from the command line, as tests/test_hysteresis.py checks it in Python: the 20-segment thesis
    hose twisted to 180 deg and back with a threshold of 2000 N*mm (the largest joint moment is about 3600) keeps a set
    back at 0 deg; with a threshold above every moment it is the elastic model (no band)."""
    path = tmp_path / "brake20.toml"
    path.write_text(problem_to_toml(thesis_problem(20)), encoding="utf-8")
    output, columns = solve_with_hysteresis(path, tmp_path / "friction", "180", "--friction-threshold", "2000")
    assert columns["twist_deg"][0] == 0.0 and columns["largest_band_mm"][0] > 10.0  # mm (measured 44 in Python)
    assert columns["largest_band_mm"][-1] < 1e-9  # the top of the path is one shape
    assert "joint friction 2000 N*mm" in " ".join(output.split())
    _, stiff = solve_with_hysteresis(path, tmp_path / "elastic", "180", "--friction-threshold", "1e9")
    assert np.max(stiff["largest_band_mm"]) < 1e-6


@pytest.mark.parametrize("options", [["--friction-threshold", "2000"], ["--hysteresis", "90", "--friction-threshold", "-5"]])
def test_a_friction_threshold_needs_hysteresis_and_a_positive_moment(problem_file, tmp_path, options):
    result = runner.invoke(cli.app, ["solve", str(problem_file), "-o", str(tmp_path / "out"), *options])
    assert result.exit_code == 2 and "--friction-threshold" in result.output
    assert not (tmp_path / "out").exists()
