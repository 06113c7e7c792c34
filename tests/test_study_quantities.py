"""The study's quantities beyond the hose's health: the mount and clip reactions and the clearance to a fixed
obstacle of a placement, their exact sensitivities, their limits; and the stations' derivatives written to
station_sensitivities.csv."""

from __future__ import annotations

import csv
import json
from dataclasses import replace

import numpy as np
import pytest
import trimesh
from typer.testing import CliRunner

from hoseline.cli import app
from hoseline.demos.thesis_hose import demo_problem
from hoseline.io.problem_file import problem_to_toml
from hoseline.model import Problem
from hoseline.model.sweep import Obstacle
from hoseline.procedures.placement.sequence import place_only
from hoseline.procedures.variation.fixed_obstacles import FixedObstacles
from hoseline.procedures.variation.samples import placement_readings
from hoseline.procedures.variation.sensitivity import placement_sensitivities, step_sizes
from hoseline.procedures.variation.tolerances import COORDINATES, INDEX, perturbed

LID_SIZE = (100.0, 80.0, 20.0)  # mm: a box above the hose's loop, tilted about x and y
LID_PLACE = {"angles": (0.3, 0.2, 0.0), "translate": (-70.0, 80.0, 75.0)}


def _lid() -> trimesh.Trimesh:
    return trimesh.creation.box(extents=LID_SIZE, transform=trimesh.transformations.compose_matrix(**LID_PLACE))


def _hose_with_weight() -> Problem:
    """The thesis hose, 40 segments, given weight (the mounts then carry it), twisted 90 degrees."""
    problem = demo_problem(90.0, 40)
    return replace(problem, hose=replace(problem.hose, mass_per_length=0.3), gravity=np.array([0.0, 0.0, -9.81]))


def test_reactions_and_the_clearance_to_a_fixed_obstacle_match_finite_differences_of_full_placements():
    """d(quantity)/d(parameter) of the clearance to a tilted box over the hose and of the force and moment of each
    mount, for every coordinate, against central differences of whole placements from the straight hose
    (Richardson-extrapolated), which re-find the lock angle each time.  The reactions' derivatives go through the
    Lagrange multipliers' tangent (the end force is one): with it left out the largest relative difference is 0.91.
    Measured: 2.0e-7."""
    problem = _hose_with_weight()
    lid = _lid()
    obstacles = FixedObstacles((Obstacle("lid", np.asarray(lid.vertices), np.asarray(lid.faces)),))
    sensitivities = placement_sensitivities(problem, tuple(range(len(COORDINATES))), obstacles)
    assert sensitivities.names == ("clearance:lid", "bend_radius", "end_torque", "twist_rate", "force:start",
                                   "force:end", "moment:start", "moment:end")
    steps = 3000.0 * step_sizes(problem)

    def read(deviation: np.ndarray) -> np.ndarray:
        hose = perturbed(problem, deviation)
        props, clamps, state, _ = place_only(hose)
        return placement_readings(hose, props, clamps, state, obstacles).smooth_values()

    def central(j: int, step: float) -> np.ndarray:
        e = np.zeros(len(COORDINATES))
        e[j] = step
        return (read(e) - read(-e)) / (2.0 * step)

    rows = [sensitivities.names.index(name) for name in ("clearance:lid", "force:start", "force:end", "moment:start",
                                                          "moment:end")]
    worst = 0.0
    for j in range(len(COORDINATES)):
        reference = (4.0 * central(j, steps[j] / 2.0) - central(j, steps[j])) / 3.0
        scale = np.abs(reference) + np.abs(sensitivities.values) / (step_sizes(problem)[j] / 1e-7)
        worst = max(worst, float(np.max((np.abs(sensitivities.derivatives[:, j] - reference) / scale)[rows])))
    assert worst <= 2e-6
    # the clearance is a real quantity here: the hose's loop moves towards the lid with the end mount's height
    assert 10.0 < sensitivities.values[0] < 50.0
    assert abs(sensitivities.derivatives[0, INDEX["end.z"]]) > 0.1


STUDY = """
base = "problem.toml"
[sampling]
method = "sobol"
samples = 16
seed = 2
[[vary]]
parameter = "end.point"
distribution = "sphere"
radius = 1.0
[[vary]]
parameter = "hose.length"
distribution = "uniform"
range = [-2.0, 1.0]
unit = "%"
[[obstacles]]
name = "lid"
file = "lid.stl"
clearance = 15.0
[limits]
"force:end" = {force}
"moment:start" = 2000.0
"""


def _run(*args: str):
    return CliRunner().invoke(app, ["study", *args])


@pytest.fixture(scope="module")
def quantity_study(tmp_path_factory):
    """A placement study of the thesis hose with a lid to keep clear of and a limit on the end mount's force set
    between the samples' least and largest (so some hoses break it)."""
    folder = tmp_path_factory.mktemp("quantities")
    problem = _hose_with_weight()
    (folder / "problem.toml").write_text(problem_to_toml(problem), encoding="utf-8")
    _lid().export(folder / "lid.stl")
    (folder / "study.toml").write_text(STUDY.format(force=43.4), encoding="utf-8")
    result = _run(str(folder / "study.toml"), "-o", str(folder / "out"), "--workers", "0", "-q")
    assert result.exit_code == 0, result.output
    return folder, problem


def test_limits_on_reactions_and_on_a_fixed_obstacle_are_judged_like_the_others(quantity_study):
    """The limits: the file's on the end force and the start moment, and the lid's own clearance by default; each
    probability is the fraction of solved samples beyond its limit."""
    folder, _ = quantity_study
    out = folder / "out"
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    limits = [p["limit"] for p in summary["probabilities"]]
    assert limits == ["clearance:lid at least 15 mm", "force:end at most 43.4 N",
                      "moment:start at most 2000 N*mm"]
    with np.load(out / "samples.npz") as data:
        values = data["values"]
    names = list(summary["quantities"])
    force = values[:, names.index("force:end")]
    assert force.min() < 43.4 < force.max()  # the limit splits the samples
    probability = next(p for p in summary["probabilities"] if p["quantity"] == "force:end")
    assert probability["broken"] == int(np.sum(force > 43.4))
    rows = list(csv.DictReader((out / "sensitivities.csv").open(encoding="utf-8")))
    assert {"d clearance:lid [mm per unit]", "d force:end [N per unit]", "d moment:clips[0] [N*mm per unit]"} & set(
        rows[0]) == {"d clearance:lid [mm per unit]", "d force:end [N per unit]"}


def test_station_sensitivities_match_finite_differences_of_two_solves(quantity_study):
    """station_sensitivities.csv: per station and varied coordinate the derivative of its position, against the
    central difference of two placements from the straight hose at +-1e-4 of the scale (their truncation error is
    below 1e-6 of the derivative here)."""
    folder, problem = quantity_study
    rows = list(csv.DictReader((folder / "out" / "station_sensitivities.csv").open(encoding="utf-8")))
    stations = problem.hose.segments + 1
    assert len(rows) == stations * 4  # end.x, end.y, end.z, hose.length
    assert [row["coordinate"] for row in rows[:4]] == ["end.x", "end.y", "end.z", "hose.length"]
    assert float(rows[-1]["arc_length [mm]"]) == pytest.approx(problem.hose.length)
    for name in ("end.y", "hose.length"):
        j = INDEX[name]
        step = 1e-4 * problem.hose.length
        e = np.zeros(len(COORDINATES))
        e[j] = step
        shapes = []
        for sign in (1.0, -1.0):
            hose = perturbed(problem, sign * e)
            props, clamps, state, _ = place_only(hose)
            shapes.append(placement_readings(hose, props, clamps, state).centerlines[0])
        reference = (shapes[0] - shapes[1]) / (2.0 * step)
        written = np.array([[float(row[f"d{axis} [mm per unit]"]) for axis in "xyz"] for row in rows
                            if row["coordinate"] == name])
        assert np.max(np.abs(written - reference)) <= 1e-5 * np.max(np.abs(reference))


@pytest.mark.parametrize("extra, message", [
    ('[[obstacles]]\nname = "lid"\nfile = "lid.stl"\nbody = "knuckle"\n', "obstacles[1].body"),
    ('[[obstacles]]\nname = "lid"\nfile = "lid.stl"\n', 'obstacles[1].name = "lid" is used by an earlier obstacle'),
    ('[[obstacles]]\nname = "bracket"\nfile = "missing.stl"\n', "cannot read"),
])
def test_bad_obstacles_are_refused_naming_the_field(tmp_path, extra, message):
    (tmp_path / "problem.toml").write_text(problem_to_toml(demo_problem(90.0, 20)), encoding="utf-8")
    _lid().export(tmp_path / "lid.stl")
    text = STUDY.format(force=50.0).replace("[limits]", extra + "[limits]")
    (tmp_path / "study.toml").write_text(text, encoding="utf-8")
    result = _run(str(tmp_path / "study.toml"), "-o", str(tmp_path / "out"), "--workers", "0", "-q")
    assert result.exit_code == 2 and message in result.output, result.output


def test_a_limit_on_a_ball_clips_moment_is_refused(tmp_path):
    """A ball clip holds no direction: it has a force but no moment, and a limit on its moment names the quantities
    there are."""
    from hoseline.model.clips import Clip

    problem = demo_problem(90.0, 20)
    problem = replace(problem, clips=(Clip("ball", np.array([-69.5, 91.4, 48.0]), problem.hose.length / 2.0),))
    (tmp_path / "problem.toml").write_text(problem_to_toml(problem), encoding="utf-8")
    text = STUDY.split("[[obstacles]]")[0] + '[limits]\n"moment:clips[0]" = 100.0\n'
    (tmp_path / "study.toml").write_text(text, encoding="utf-8")
    result = _run(str(tmp_path / "study.toml"), "-o", str(tmp_path / "out"), "--workers", "0", "-q")
    assert result.exit_code == 2 and "force:clips[0]" in result.output and "moment:end" in result.output, result.output


def test_a_design_ranked_on_the_p95_margin_from_a_study_file(quantity_study, tmp_path):
    """[design] rank_on = "p95_margin" read from the file: the candidates' margins are the first-order 5th
    percentiles (below the nominal ones for a limit the tolerances move), the report and summary.json say so; with
    solved samples per candidate too it is refused naming the fields."""
    folder, _ = quantity_study
    for name in ("problem.toml", "lid.stl"):
        (tmp_path / name).write_bytes((folder / name).read_bytes())
    design = '[design]\nlengths = [330.6, 335.6]\nlength_step = 5.0\nrank_by = "force:end"\nrank_on = "{}"\n'
    for rank_on in ("nominal", "p95_margin"):
        text = STUDY.format(force=60.0) + design.format(rank_on)
        (tmp_path / "study.toml").write_text(text, encoding="utf-8")
        result = _run(str(tmp_path / "study.toml"), "-o", str(tmp_path / rank_on), "--workers", "0", "-q")
        assert result.exit_code == 0, result.output
    judged = {}
    for rank_on in ("nominal", "p95_margin"):
        summary = json.loads((tmp_path / rank_on / "summary.json").read_text(encoding="utf-8"))
        assert summary["design"]["rank_on"] == rank_on
        judged[rank_on] = {row["length_mm"]: row["margin force:end [N]"] for row in summary["design"]["ranking"]}
    assert len(judged["p95_margin"]) == 2 and all(judged["p95_margin"][k] < judged["nominal"][k] for k in judged["nominal"])
    assert "to first order at the candidate" in (tmp_path / "p95_margin" / "report.html").read_text(encoding="utf-8")
    (tmp_path / "study.toml").write_text(STUDY.format(force=60.0) + design.format("p95_margin") + "samples = 4\n",
                                         encoding="utf-8")
    result = _run(str(tmp_path / "study.toml"), "-o", str(tmp_path / "refused"), "--workers", "0", "-q")
    assert result.exit_code == 2 and "design.samples = 4 with rank_on" in result.output, result.output
