"""Scans that cannot show the hose (found by fuzzing `hoseline compare`) are refused, exit 2, with a message naming
the file and what is wrong; no array is sized by such a scan beyond its cap."""

import numpy as np
import pytest
from typer.testing import CliRunner
from validation_cases import RADIUS, brake_hose

from hoseline import cli
from hoseline.commands import common
from hoseline.io.problem_file import problem_to_toml
from hoseline.io.scans import write_ply
from hoseline.procedures.scans import centerline_fit
from hoseline.procedures.scans.synthetic_scan import ScanDefects, synthetic_scan

runner = CliRunner()
START, END = np.array([-13.0, 0.0, -11.25]), np.array([-173.064, -7.0, -11.25])  # the brake hose's mounts


def hose_scan() -> np.ndarray:
    """An all-round scan (mm) of a tube of the brake hose's radius bowed between its mounts."""
    t = np.linspace(0.0, 1.0, 41)
    line = START + t[:, None] * (END - START) + np.outer(np.sin(np.pi * t), [0.0, 60.0, 0.0])
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(line, axis=0), axis=1))])
    return synthetic_scan(s, line, RADIUS, ScanDefects(density=0.5, noise=0.05, outlier_fraction=0.0))


def degenerate(kind: str) -> np.ndarray:
    rng = np.random.default_rng(1)
    if kind == "flat":  # a scatter on a plane through the mounts
        return np.column_stack([rng.uniform(-200, 0, 5000), rng.uniform(-50, 80, 5000), np.full(5000, -11.25)])
    if kind == "flattened hose":  # the hose's scan squashed onto z = 0, with the scanner's noise
        return hose_scan() * [1.0, 1.0, 0.0] + rng.normal(scale=0.1, size=(hose_scan().shape[0], 3))
    if kind == "collinear":
        return START + np.outer(rng.uniform(0.0, 1.0, 5000), END - START)
    if kind == "one point repeated":
        return np.repeat(START[None], 1000, axis=0)
    if kind == "far away":
        return hose_scan() + [1e4, 0.0, 0.0]
    if kind == "scaled down 1000x":  # a scan in metres
        return hose_scan() / 1000.0
    raise ValueError(kind)


@pytest.fixture(scope="module")
def problem_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("problem") / "hose.toml"
    path.write_text(problem_to_toml(brake_hose(segments=24)))
    return path


@pytest.mark.parametrize("kind, reason", [
    ("flat", "its points lie on a plane"),
    ("flattened hose", "its points lie on a plane"),
    ("collinear", "its points lie on a line"),
    ("one point repeated", "holds 1 distinct point(s)"),
    ("far away", "of its points lie within the hose's reach of the mounts"),
    ("scaled down 1000x", "distinct point(s) at a grid of"),
])
def test_a_scan_that_cannot_show_the_hose_is_refused_naming_the_file(tmp_path, problem_file, kind, reason):
    scan = write_ply(tmp_path / "scan.ply", degenerate(kind))
    out = tmp_path / "out"
    result = runner.invoke(cli.app, ["compare", str(problem_file), str(scan), "-o", str(out)])
    assert result.exit_code == common.BAD_INPUT, result.output
    message = " ".join(result.output.split())  # Rich wraps the line
    assert f"scan {scan}:" in message and reason in message
    assert not out.exists()


def test_a_scan_of_two_points_is_refused_naming_the_file(tmp_path, problem_file):
    scan = write_ply(tmp_path / "two.ply", np.array([START, END]))
    result = runner.invoke(cli.app, ["compare", str(problem_file), str(scan), "-o", str(tmp_path / "out")])
    assert result.exit_code == common.BAD_INPUT, result.output
    assert str(scan) in " ".join(result.output.split()) and "2 points" in result.output


def test_the_hose_scan_the_cases_are_made_from_is_fitted():
    """The degenerate clouds fail for what they are, not for the hose they are made from."""
    fit = centerline_fit.fit_centerline(hose_scan(), RADIUS, start_hint=START)
    assert fit.points.shape[0] > 30 and abs(fit.radius_median - RADIUS) < 0.1


def test_the_axis_a_fit_follows_is_capped_not_allocated():
    """A fit led astray (the fuzzed flat scan's cylinders put its axis 1.9e10 mm long) is refused before the
    second pass samples it (np.linspace of 139 GiB there), and so is a guide of too many stations."""
    astray = np.array([[0.0, 0.0, 0.0], [1e10, 0.0, 0.0], [1e10, 1e10, 0.0], [0.0, 1e10, 0.0], [0.0, 0.0, 1e10]])
    with pytest.raises(ValueError, match="the fitted axis is .* mm long"):
        centerline_fit._along_spline(astray, 0.5)
    with pytest.raises(ValueError, match="the guide along the scan is .* mm long"):
        centerline_fit._resample(astray, 0.5)
