"""`hoseline study`: the files it writes, the worst samples they reproduce, sweeps as the base, bad input."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
import trimesh
from typer.testing import CliRunner

from hoseline.cli import app
from hoseline.demos.thesis_hose import demo_problem
from hoseline.io.problem_file import load_problem, problem_to_toml
from hoseline.io.sweep_file import load_sweep
from hoseline.procedures.placement.sequence import solve
from hoseline.procedures.sweep.quasi_static import run_sweep

PLACEMENT_STUDY = """
name = "thesis hose as built"
base = "problem.toml"
[sampling]
method = "sobol"
samples = 16
seed = 3
[[vary]]
parameter = "end.point"
distribution = "normal"
sigma = [0.5, 0.5, 1.0]
[[vary]]
parameter = "hose.length"
distribution = "uniform"
range = [-4.0, 2.0]
unit = "%"
label = "length change under pressure"
[[vary]]
parameter = "hose.bending_stiffness"
distribution = "loguniform"
factor = 2.0
[limits]
bend_radius = 36.0
end_torque = 2500.0
"""

SWEEP_FILE = """
[hose]
length = 330.6
outer_diameter = 10.1
bending_stiffness = 149563.0
torsion_factor = 25.0
min_bend_radius = 30.0
segments = 30
[start]
point = [-13.0, 0.0, -11.25]
direction = [0.0, 1.0, 0.0]
[end]
point = [-173.064, -7.0, -11.25]
direction = [1.0, 0.0, 0.0]
body = "knuckle"
[[bodies]]
name = "knuckle"
stages = [{ name = "jounce", translate = [0.0, 20.0], axis = [0.0, 0.0, 1.0], steps = 4 }]
[[obstacles]]
name = "post"
file = "post.stl"
clearance = 10.0
[sweep]
compare_free_roll = false
"""

SWEEP_STUDY = """
base = "sweep.toml"
[sampling]
method = "latin-hypercube"
samples = 6
seed = 1
[[vary]]
parameter = "end.point"
distribution = "sphere"
radius = 2.0
[[vary]]
parameter = "end.twist"
distribution = "uniform"
range = [-10.0, 10.0]
"""


def _run(*args: str):
    return CliRunner().invoke(app, ["study", *args])


@pytest.fixture(scope="module")
def placement_study(tmp_path_factory):
    """The placement study run once (in process): its folder and output."""
    folder = tmp_path_factory.mktemp("placement")
    (folder / "problem.toml").write_text(problem_to_toml(demo_problem(180.0, 30)), encoding="utf-8")
    (folder / "study.toml").write_text(PLACEMENT_STUDY, encoding="utf-8")
    result = _run(str(folder / "study.toml"), "-o", str(folder / "out"), "--workers", "0")
    assert result.exit_code == 0, result.output
    return folder, result.output


def test_a_placement_study_writes_its_files(placement_study):
    folder, output = placement_study
    out = folder / "out"
    for name in ("report.html", "envelope.stl", "summary.json", "samples.csv", "samples.npz", "envelope.csv",
                 "sensitivities.csv"):
        assert (out / name).is_file(), name
    assert not (out / ".partial").exists()
    assert "16 samples" in output
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    rows = list(csv.DictReader((out / "samples.csv").open(encoding="utf-8")))
    assert len(rows) == 16 and all(row["status"] == "solved" for row in rows)
    # the probability is the fraction of samples beyond the limit, with an interval around it
    radii = np.array([float(row["bend_radius [mm]"]) for row in rows])
    bend = next(p for p in summary["probabilities"] if p["quantity"] == "bend_radius")
    assert bend["broken"] == int(np.sum(radii < 36.0))
    assert bend["ci95"][0] <= bend["probability"] <= bend["ci95"][1]
    # the envelope mesh is closed and wraps every sampled station at about the outer radius (5.05 mm)
    mesh = trimesh.load(out / "envelope.stl")
    assert mesh.is_watertight
    with np.load(out / "samples.npz") as data:
        stations = data["shapes"][:, 0].reshape(-1, 3)
    low, high = stations.min(axis=0), stations.max(axis=0)
    assert np.all(np.abs(mesh.bounds[0] - (low - 5.05)) < 2.6) and np.all(np.abs(mesh.bounds[1] - (high + 5.05)) < 2.6)
    html = (out / "report.html").read_text(encoding="utf-8")
    assert "First order beside Monte Carlo" in html and "Which tolerance matters most" in html


def test_the_worst_samples_are_problem_files_that_reproduce_them(placement_study):
    """worst/QUANTITY/problem.toml placed with `hoseline solve`'s solver gives the sample's value again."""
    folder, _ = placement_study
    out = folder / "out"
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    rows = list(csv.DictReader((out / "samples.csv").open(encoding="utf-8")))
    for entry in summary["probabilities"]:
        quantity, index = entry["quantity"], entry["worst_sample"]
        values = [float(row[[key for key in row if key.startswith(quantity + " [")][0]]) for row in rows]
        assert index == (int(np.argmin(values)) if quantity == "bend_radius" else int(np.argmax(values)))
        result = solve(load_problem(out / "worst" / quantity / "problem.toml"), estimate_error=False)
        reproduced = result.min_bend_radius if quantity == "bend_radius" else abs(
            float(result.end_moment @ result.problem.end.direction))
        assert reproduced == pytest.approx(values[index], rel=1e-6)


def test_sensitivity_table_lists_the_varied_coordinates(placement_study):
    folder, _ = placement_study
    rows = list(csv.DictReader((folder / "out" / "sensitivities.csv").open(encoding="utf-8")))
    assert [row["coordinate"] for row in rows] == ["end.x", "end.y", "end.z", "hose.length", "hose.bending"]


@pytest.fixture(scope="module")
def sweep_study(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sweep")
    post = trimesh.creation.cylinder(radius=10.0, height=200.0, sections=24)
    post.apply_translation((-90.0, 120.0, 0.0))
    post.export(folder / "post.stl")
    (folder / "sweep.toml").write_text(SWEEP_FILE, encoding="utf-8")
    (folder / "study.toml").write_text(SWEEP_STUDY, encoding="utf-8")
    result = _run(str(folder / "study.toml"), "-o", str(folder / "out"), "--workers", "0", "-q")
    assert result.exit_code == 0, result.output
    return folder


def test_a_sweep_study_judges_every_pose(sweep_study):
    """Per pose the clearance distribution; the limits from the sweep file (the post's clearance, the hose's
    bend radius); the worst sample as a sweep file that `hoseline sweep` reads and that reproduces it."""
    out = sweep_study / "out"
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert [p["limit"] for p in summary["probabilities"]] == ["clearance:post at least 10 mm", "bend_radius at least 30 mm"]
    rows = list(csv.DictReader((out / "clearance_by_pose.csv").open(encoding="utf-8")))
    assert len(rows) == 5
    with np.load(out / "samples.npz") as data:
        per_pose = data["clearance"][:, 0, :]
        values = data["values"]
    assert np.allclose([float(row["post min [mm]"]) for row in rows], per_pose.min(axis=0))
    assert np.allclose(values[:, 0], per_pose.min(axis=1))  # the quantity is the worst pose
    worst = summary["probabilities"][0]["worst_sample"]
    sweep = load_sweep(out / "worst" / "clearance_post" / "sweep.toml")
    again = run_sweep(sweep)
    assert again.clearances[0].distance.min() == pytest.approx(values[worst, 0], rel=1e-6)
    # the sensitivities of the sweep's quantities (its extremes over the poses), per varied coordinate
    rows = list(csv.DictReader((out / "sensitivities.csv").open(encoding="utf-8")))
    assert [row["coordinate"] for row in rows] == ["end.x", "end.y", "end.z", "end.twist"]
    assert "d clearance:post [mm per unit]" in rows[0] and "first_order" in summary


def test_a_rub_in_a_sweep_has_its_most_probable_failure_point_as_a_sweep_file(sweep_study, tmp_path):
    """[reliability] on a sweep: FORM's design point of the clearance to the post, written as
    design_point/clearance_post/sweep.toml, swept again by `hoseline sweep`'s code, has the limit's least clearance
    (the design point lies on the failure surface)."""
    (tmp_path / "post.stl").write_bytes((sweep_study / "post.stl").read_bytes())
    (tmp_path / "sweep.toml").write_text(SWEEP_FILE, encoding="utf-8")
    text = (SWEEP_STUDY.replace("samples = 6", "samples = 2") + '[limits]\n"clearance:post" = -1.6\n'
            '[reliability]\nlimits = ["clearance:post"]\nimportance_samples = 4\n')
    (tmp_path / "study.toml").write_text(text, encoding="utf-8")
    result = _run(str(tmp_path / "study.toml"), "-o", str(tmp_path / "out"), "--workers", "0", "-q")
    assert result.exit_code == 0, result.output
    summary = json.loads((tmp_path / "out" / "summary.json").read_text(encoding="utf-8"))
    rub = summary["rare_failures"][0]
    assert rub["converged"] and rub["quantity"] == "clearance:post"
    again = run_sweep(load_sweep(tmp_path / "out" / "design_point" / "clearance_post" / "sweep.toml"))
    assert again.clearances[0].distance.min() == pytest.approx(-1.6, abs=1e-6)


@pytest.mark.parametrize("old, new, message", [
    ('parameter = "hose.bending_stiffness"', 'parameter = "hose.bending_stiff"', 'vary[2].parameter'),
    ('distribution = "uniform"\nrange = [-4.0, 2.0]', 'distribution = "sphere"\nradius = 1.0', "does not apply"),
    ('distribution = "loguniform"', 'distribution = "weibull"', 'vary[2] (hose.bending_stiffness): distribution = '
                                                                '"weibull" does not apply'),
    ("sigma = [0.5, 0.5, 1.0]", "sigma = [0.5, 0.5, 1.0]\nradius = 2.0", "takes sigma only: remove radius"),
    ('distribution = "normal"\nsigma = [0.5, 0.5, 1.0]', 'distribution = "uniform"\ntolerance = [-0.5, 0.5, 1.0]',
     "vary[0] (end.point): end.point: uniform tolerance_x = -0.5, tolerance_y = 0.5, tolerance_z = 1: each must be "
     "zero or positive"),
    ('distribution = "normal"\nsigma = [0.5, 0.5, 1.0]', 'distribution = "uniform"\ntolerance = 0.0',
     "vary[0] (end.point): end.point: uniform tolerance_x = 0, tolerance_y = 0, tolerance_z = 0: each must be zero or "
     "positive, and not all zero"),
    ("sigma = [0.5, 0.5, 1.0]", "sigma = [0.5, -0.5, 1.0]", "sigma_y = -0.5"),
    ("sigma = [0.5, 0.5, 1.0]", 'sigma = [0.5, 0.5, 1.0]\nshared_with = ["start.pont"]',
     'vary[0].shared_with[0] = "start.pont": unknown'),
    ("sigma = [0.5, 0.5, 1.0]", 'sigma = [0.5, 0.5, 1.0]\nshared_with = ["hose.length"]',
     "vary[0] (end.point): end.point: shared_with hose.length: a shared deviation moves parameters of one kind"),
    ('distribution = "uniform"\nrange = [-4.0, 2.0]', 'distribution = "triangular"\nrange = [-4.0, 2.0]',
     "vary[1] (hose.length): a triangular distribution takes range and mode only: give mode"),
    ('distribution = "uniform"\nrange = [-4.0, 2.0]', 'distribution = "truncnormal"\nrange = [-4.0, 2.0]\nmode = 1.0',
     "a truncnormal distribution takes sigma and range (and optionally mean) only: remove mode; give sigma"),
    ('distribution = "loguniform"', 'distribution = "loguniform"\nframe = "fitting"',
     'vary[2] (hose.bending_stiffness): frame = "fitting" applies to points'),
    ("bend_radius = 36.0", "bendradius = 36.0", "limits.bendradius: unknown quantity"),
    ("end_torque = 2500.0", 'end_torque = 2500.0\n[reliability]\nlimits = ["deviation"]',
     'reliability.limits[0] = "deviation": not a limit FORM can judge; choose one of bend_radius, end_torque'),
    ("end_torque = 2500.0", 'end_torque = 2500.0\n[reliability]\nmethod = "mc"', "reliability.method"),
    ("end_torque = 2500.0", "end_torque = 2500.0\n[reliability]\nimportance_samples = -1", "reliability.importance_samples"),
    ("end_torque = 2500.0", "end_torque = 2500.0\n[sobol]\nsamples = 4", "sobol.samples"),
    ("end_torque = 2500.0", "end_torque = 2500.0\n[sobol]\nrows = 4", "sobol.rows"),
    ('base = "problem.toml"', 'base = "problem.toml"\nworst_case = true\nsensitivities = false',
     "worst_case = true needs [[vary]] tolerances and sensitivities = true"),
    ("end_torque = 2500.0", 'end_torque = 2500.0\n[[correlation]]\ntolerances = ["length change under pressure", '
     '"hose.bending_stiffness"]\nmatrix = [[1.0, 1.2], [1.2, 1.0]]', "correlation[0].matrix[0][1] = 1.2: a correlation "
     "lies in [-1, 1]"),
    ('distribution = "uniform"\nrange = [-4.0, 2.0]', 'distribution = "empirical"\nvalues = [1.0, 2.0]',
     "vary[1] (hose.length): hose.length: empirical needs at least 10 measured values"),
    ("seed = 3", 'seed = 3\nprecision = {quantity = "bend_radius", half_width = 0.0, max_samples = 64}',
     "sampling.precision.half_width = 0: must be a positive number"),
])
def test_bad_study_files_are_refused_naming_the_field(tmp_path, old, new, message):
    """Exit code 2, one line naming the field and the fix, nothing written."""
    assert old in PLACEMENT_STUDY
    (tmp_path / "problem.toml").write_text(problem_to_toml(demo_problem(180.0, 30)), encoding="utf-8")
    (tmp_path / "study.toml").write_text(PLACEMENT_STUDY.replace(old, new, 1), encoding="utf-8")
    result = _run(str(tmp_path / "study.toml"), "-o", str(tmp_path / "out"), "--workers", "0")
    assert result.exit_code == 2
    assert message in result.output.replace("\n", " ")
    assert not (tmp_path / "out").exists()


def test_triangular_and_truncated_normal_offsets_are_read_in_mm_or_percent(tmp_path):
    """The offset distributions' keys become the Tolerance's size (low, mode, high) and (mean, sigma, low, high),
    a percentage of the base length converted to mm throughout."""
    from hoseline.io.study_file import load_study

    text = PLACEMENT_STUDY.replace('distribution = "uniform"\nrange = [-4.0, 2.0]',
                                   'distribution = "triangular"\nrange = [-4.0, 2.0]\nmode = -1.0')
    text += '[[vary]]\nparameter = "end.twist"\ndistribution = "truncnormal"\nmean = 0.5\nsigma = 2.0\nrange = [-3.0, 5.0]\n'
    (tmp_path / "problem.toml").write_text(problem_to_toml(demo_problem(180.0, 30)), encoding="utf-8")
    (tmp_path / "study.toml").write_text(text, encoding="utf-8")
    study, _, _ = load_study(tmp_path / "study.toml")
    length = study.base.problem.hose.length
    triangle, cut = study.variation.tolerances[1], study.variation.tolerances[3]
    assert triangle.distribution == "triangular" and triangle.size == pytest.approx((-0.04 * length, -0.01 * length,
                                                                                     0.02 * length))
    assert cut.distribution == "truncnormal" and cut.size == (0.5, 2.0, -3.0, 5.0)


def test_a_point_tolerance_in_the_fittings_frame_takes_the_base_fittings_axes(tmp_path):
    from hoseline.io.study_file import load_study
    from hoseline.procedures.variation.tolerances import fitting_axes

    text = PLACEMENT_STUDY.replace("sigma = [0.5, 0.5, 1.0]", 'sigma = [0.5, 0.5, 1.0]\nframe = "fitting"')
    (tmp_path / "problem.toml").write_text(problem_to_toml(demo_problem(180.0, 30)), encoding="utf-8")
    (tmp_path / "study.toml").write_text(text, encoding="utf-8")
    study, _, _ = load_study(tmp_path / "study.toml")
    point = study.variation.tolerances[0]
    assert point.axes == fitting_axes(study.base.problem.end.direction) and point.size == (0.5, 0.5, 1.0)


def test_the_most_probable_failure_point_is_a_problem_file_on_the_limit(tmp_path):
    """[reliability]: FORM's design point of the end torque, written as design_point/end_torque/problem.toml, solved
    again by `hoseline solve`'s sequence, gives the limit's torque (the design point lies on the failure surface)."""
    text = PLACEMENT_STUDY.replace("samples = 16", "samples = 4") + "[reliability]\nimportance_samples = 8\n"
    (tmp_path / "problem.toml").write_text(problem_to_toml(demo_problem(180.0, 30)), encoding="utf-8")
    (tmp_path / "study.toml").write_text(text, encoding="utf-8")
    result = _run(str(tmp_path / "study.toml"), "-o", str(tmp_path / "out"), "--workers", "0")
    assert result.exit_code == 0, result.output
    assert "rare failures" in result.output
    summary = json.loads((tmp_path / "out" / "summary.json").read_text(encoding="utf-8"))
    torque = next(r for r in summary["rare_failures"] if r["quantity"] == "end_torque")
    assert torque["converged"] and torque["importance_sampling"]["samples"] == 8
    either = summary["rare_failures_any"]  # bend radius or end torque: at least the likelier of the two
    assert either["importance_sampling"]["samples"] == 16
    assert either["form_probability"] >= 0.99 * max(r["form_probability"] for r in summary["rare_failures"])
    placed = solve(load_problem(tmp_path / "out" / "design_point" / "end_torque" / "problem.toml"), estimate_error=False)
    assert abs(float(placed.end_moment @ placed.problem.end.direction)) == pytest.approx(2500.0, rel=1e-6)
    assert "Rare failures" in (tmp_path / "out" / "report.html").read_text(encoding="utf-8")


def test_a_missing_base_file_is_named(tmp_path):
    (tmp_path / "study.toml").write_text(PLACEMENT_STUDY.replace("problem.toml", "nowhere.toml"), encoding="utf-8")
    result = _run(str(tmp_path / "study.toml"), "-o", str(tmp_path / "out"))
    assert result.exit_code == 2 and 'base = "nowhere.toml": cannot read' in result.output.replace("\n", " ")


def test_help_lists_the_study_command():
    result = CliRunner().invoke(app, ["--help"])
    assert "study" in result.output
    assert Path(__file__).name  # keep pytest from treating this module as empty when filtered


DESIGN_SECTION = """
[design]
lengths = [325.0, 335.0]
length_step = 10.0
clockings = [-40.0, 40.0]
clocking_step = 40.0
rank_by = "bend_radius"
method = "optimise"
"""


def test_a_design_search_with_the_optimiser_writes_its_ranking(tmp_path):
    """[design] method = "optimise": one candidate per length in design.csv, with where its clocking comes from,
    the grid beside it in design_grid.csv, the optimiser's runs in summary.json; a misspelt method is refused."""
    (tmp_path / "problem.toml").write_text(problem_to_toml(demo_problem(0.0, 20)), encoding="utf-8")
    text = PLACEMENT_STUDY.replace("samples = 16", "samples = 4") + DESIGN_SECTION
    (tmp_path / "study.toml").write_text(text.replace("end_torque = 2500.0", "end_torque = 1e6"), encoding="utf-8")
    result = _run(str(tmp_path / "study.toml"), "-o", str(tmp_path / "out"), "--workers", "0", "-q")
    assert result.exit_code == 0, result.output
    out = tmp_path / "out"
    rows = list(csv.DictReader((out / "design.csv").open(encoding="utf-8")))
    grid = list(csv.DictReader((out / "design_grid.csv").open(encoding="utf-8")))
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert len(grid) == 6 and summary["design"]["method"] == "optimise"
    assert sorted(float(row["length_mm"]) for row in rows) == [325.0, 335.0]
    assert all(row["clocking from"] in ("optimiser", "grid") for row in rows)
    for row in rows:  # never worse than the grid's best cell of its length
        cells = [float(g["margin bend_radius [mm]"]) for g in grid if float(g["length_mm"]) == float(row["length_mm"])]
        assert float(row["margin bend_radius [mm]"]) >= max(cells) - 1e-9
    assert len(summary["design"]["optimiser"]) == 2
    assert "Optimiser:" in (out / "report.html").read_text(encoding="utf-8")
    (tmp_path / "study.toml").write_text(text.replace('"optimise"', '"optimize"'), encoding="utf-8")
    result = _run(str(tmp_path / "study.toml"), "-o", str(tmp_path / "out2"), "--workers", "0")
    assert result.exit_code == 2 and "design.method" in result.output.replace("\n", " ")
