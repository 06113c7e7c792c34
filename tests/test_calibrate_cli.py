"""`hoseline calibrate`: a failed fit said loudly (--check exits 5), the torsion factor with the problem file's nu."""

import json
import tomllib
from dataclasses import replace

import pytest
from typer.testing import CliRunner
from validation_cases import EI, RADIUS, brake_hose

from hoseline import cli, solve
from hoseline.commands import common
from hoseline.io.problem_file import load_problem, problem_to_toml
from hoseline.io.scans import write_ply
from hoseline.procedures.scans.synthetic_scan import ScanDefects, synthetic_scan

runner = CliRunner()
SPARSE = ScanDefects(density=0.3, noise=0.1, outlier_fraction=0.0)  # all round, few points: fast to fit


def run(*args):
    result = runner.invoke(cli.app, [str(a) for a in args])
    return result.exit_code, result.output


def scans_of(truth, twists, tmp_path):
    """PLY scans of the problem `truth` placed at each twist (degrees)."""
    paths = []
    for seed, twist in enumerate(twists):
        result = solve(replace(truth, end_twist_deg=twist), estimate_error=False)
        points = synthetic_scan(result.s, result.centerline, RADIUS, SPARSE, seed=seed)
        paths.append(write_ply(tmp_path / f"scan_{twist:03.0f}.ply", points))
    return paths


def test_flipped_twists_warn_and_check_exits_5(tmp_path):
    """Scans at 90 and 180 deg given as -90 and -180: the calibrated model misses the limits, the
    warnings say so and suggest the other sign; the report is written all the same."""
    scans = scans_of(brake_hose(bending=120000.0, factor=18.0, segments=24), (90.0, 180.0), tmp_path)
    problem = tmp_path / "hose.toml"
    problem.write_text(problem_to_toml(brake_hose(segments=24)))
    code, output = run("calibrate", problem, *scans, "--twist", -90, "--twist", -180, "-o", tmp_path / "cal",
                       "--check", "--quiet")
    assert code == common.CHECK_FAILED, output
    assert "warning: " in output and "sign looks flipped" in output and "use twist = 90, 180" in output
    document = json.loads((tmp_path / "cal" / "validation.json").read_text())
    assert not document["passed"]
    assert any("sign looks flipped" in warning for warning in document["calibration"]["warnings"])
    assert "Warning:" in (tmp_path / "cal" / "report.html").read_text()


def test_calibrated_toml_writes_the_factor_with_the_problem_files_poisson_ratio(tmp_path):
    """A problem file with poisson_ratio = 0.3; the hose scanned has GJ = 25 EI / 1.3, a factor of 25 in
    the file's definition (28.8 relative to nu = 0.5).  The table, validation.json and calibrated.toml
    give the same factor with poisson_ratio = 0.3, and calibrated.toml reads back to the calibrated GJ."""
    scans = scans_of(brake_hose(segments=192, factor=25.0 * 1.5 / 1.3), (0.0, 180.0), tmp_path)  # nearly exact
    problem = tmp_path / "hose.toml"
    problem.write_text(problem_to_toml(brake_hose(bending=0.8 * EI, factor=12.0, segments=48), poisson_ratio=0.3))
    code, output = run("calibrate", problem, *scans, "--twist", 0, "--twist", 180, "-o", tmp_path / "cal", "--check")
    assert code == 0, output
    assert "warning" not in output and "GJ over EI / (1 + 0.3)" in output
    document = json.loads((tmp_path / "cal" / "validation.json").read_text())
    factor = {p["name"]: p for p in document["calibration"]["parameters"]}["torsion_factor"]
    assert document["calibration"]["poisson_ratio"] == 0.3
    assert factor["value"] == pytest.approx(25.0, rel=0.02) and factor["identifiable"]
    written = tomllib.loads((tmp_path / "cal" / "calibrated.toml").read_text())["hose"]
    assert written["poisson_ratio"] == 0.3 and "torsional_stiffness" not in written
    assert written["torsion_factor"] == pytest.approx(factor["value"], rel=1e-12)
    hose = load_problem(tmp_path / "cal" / "calibrated.toml").hose
    assert hose.torsional_stiffness == pytest.approx(factor["value"] * hose.bending_stiffness / 1.3, rel=1e-12)


def test_a_braid_parameter_without_a_braid_is_bad_input(tmp_path):
    """--fit braid_stiffness on a problem file without [hose.braid]: exit 2 naming what to add, before any solving."""
    problem = tmp_path / "hose.toml"
    problem.write_text(problem_to_toml(brake_hose(segments=24)))
    scan = write_ply(tmp_path / "scan.ply", [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    code, output = run("calibrate", problem, scan, "--twist", 0, "-o", tmp_path / "cal", "--fit", "braid_stiffness")
    assert code == common.BAD_INPUT, output
    assert "cannot fit braid_stiffness: give [hose.braid] in the problem file" in output
    assert not (tmp_path / "cal").exists()

