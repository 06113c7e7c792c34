"""Sampling to a requested precision: rounds until a statistic's 95 % interval is as narrow as asked, or the cap
(said so); on a quantity whose answer is known (the length deviation itself), then through the whole study."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest
from typer.testing import CliRunner

from hoseline.cli import app
from hoseline.demos.thesis_hose import demo_problem
from hoseline.io.problem_file import problem_to_toml
from hoseline.io.study_file import StudyFileError, load_study
from hoseline.procedures.variation.designs import round_design, unit_design
from hoseline.procedures.variation.precision import Precision, next_total
from hoseline.procedures.variation.run import MemoryStore, _sample_to_precision
from hoseline.procedures.variation.tolerances import INDEX

SIGMA = 2.0  # mm, the length tolerance of STUDY


class LengthEngine:
    """An Engine whose 'solve' reads every quantity as the sample's length deviation (mm): a quantity whose
    distribution is known, normal of SIGMA, without solving a hose.  Its context is the number of quantities."""

    def __init__(self) -> None:
        self.rounds: list[int] = []

    def run(self, context, coordinates, batch_size, on_batch, done=(), first=0) -> None:
        if 0 in done:  # one batch per round
            return
        self.rounds.append(len(coordinates))
        length = coordinates[:, INDEX["hose.length"]]
        on_batch(0, {"index": first + np.arange(len(coordinates)),
                     "values": np.repeat(length[:, None], context, axis=1)})


def _sample(study, stores: dict[str, MemoryStore] | None = None):
    """_sample_to_precision of `study` on the LengthEngine: (study, samples, outcome, the rounds' samples evaluated).
    stores: the stages' stores by name (kept by the caller to resume)."""
    engine = LengthEngine()
    stores = {} if stores is None else stores
    found = _sample_to_precision(engine, len(study.quantities), study, lambda s: stores.setdefault(s, MemoryStore()),
                                 None)
    return (*found, engine.rounds)


@pytest.mark.parametrize("statistic, half_width", [("mean", 0.05), ("P5", 0.1)])
def test_the_rounds_stop_once_the_interval_is_narrow_enough(tmp_path, statistic, half_width):
    """The mean of a normal length (sigma 2 mm) to +-0.05 mm needs (1.96 sigma / 0.05)^2 = 6147 samples, its P5 to
    +-0.1 mm 5.9e3 (the order statistics' interval, sqrt(p (1 - p)) / density per sqrt(n)): the study stops with
    the interval within what was asked, after 0.8 to 2 times the samples that needs (the interval is itself random:
    6493 samples for the P5 here), and the statistic is the normal's (0 mm; -1.645 sigma)."""
    study = _study(tmp_path, statistic, half_width, 100_000)
    study, samples, outcome, rounds = _sample(study)
    density = math.exp(-0.5 * 1.6449**2) / math.sqrt(2.0 * math.pi) / SIGMA
    per_root_n = 1.96 * (SIGMA if statistic == "mean" else math.sqrt(0.05 * 0.95) / density)
    needed = (per_root_n / half_width) ** 2
    assert outcome.reached and outcome.half_width <= half_width
    assert 0.8 * needed <= outcome.samples <= 2.0 * needed and outcome.samples == len(samples["index"]) == study.sampling.count
    assert tuple(rounds) == outcome.rounds == study.sampling.rounds and len(rounds) >= 2
    assert outcome.estimate == pytest.approx(0.0 if statistic == "mean" else -1.6449 * SIGMA, abs=2.0 * half_width)
    assert np.array_equal(samples["index"], np.arange(outcome.samples))
    # the merged samples are the study's own rows: the design drawn in rounds, the first round the plain design
    assert np.array_equal(samples["values"][:, 0], study.coordinates()[:, INDEX["hose.length"]])


def test_the_width_shrinks_as_one_over_the_square_root_of_the_samples(tmp_path):
    """Each round's interval of the mean, times sqrt(n), is the same 1.96 sigma to 5 % (the law the next round is
    sized by)."""
    study = _study(tmp_path, "mean", 0.02, 100_000)
    study, samples, outcome, rounds = _sample(study)
    precision = study.sampling.precision
    totals = np.cumsum(rounds)
    widths = [precision.interval(samples["values"][:n, 0]) for n in totals]
    scaled = [(high - low) / 2.0 * math.sqrt(n) for n, (_, low, high) in zip(totals, widths)]
    assert scaled == pytest.approx([1.96 * SIGMA] * len(scaled), rel=0.05)


def test_the_cap_stops_the_rounds_and_says_so(tmp_path):
    """With a cap below what the width needs, sampling stops at the cap, not reached, and the description says so."""
    study = _study(tmp_path, "mean", 0.01, 3000)
    _, samples, outcome, _ = _sample(study)
    assert not outcome.reached and outcome.samples == 3000 == len(samples["index"])
    assert outcome.half_width == pytest.approx(1.96 * SIGMA / math.sqrt(3000), rel=0.05)
    assert "NOT the 0.01 asked, the cap of max_samples = 3000 stopped it" in outcome.describe()


def test_an_interrupted_study_resumes_with_the_rounds_it_finished(tmp_path):
    """Run again over the same stores, the rounds are found finished: nothing is evaluated, the outcome is the same."""
    study = _study(tmp_path, "mean", 0.05, 100_000)
    stores: dict[str, MemoryStore] = {}
    _, samples, outcome, rounds = _sample(study, stores)
    assert sorted(stores) == ["samples"] + [f"samples_{r}" for r in range(1, len(rounds))]
    _, again, resumed, evaluated = _sample(study, stores)
    assert evaluated == [] and resumed == outcome and np.array_equal(again["values"], samples["values"])


def test_sobol_rounds_keep_a_power_of_two_and_continue_the_sequence():
    """The next total: 1.2 times the 1/sqrt(n) law's, between 1.5 and 4 times the samples so far, at most the cap; a
    Sobol' total stays a power of two, and its rounds are the rows of the one sequence; a Latin hypercube's first
    round is the plain design."""
    precision = Precision("bend_radius", "mean", 1.0, 10_000)
    assert next_total(256, 1.5, precision, True) == 1024 and next_total(256, 1.5, precision, False) == 692
    assert next_total(256, 10.0, precision, False) == 1024 and next_total(256, 1.01, precision, False) == 384
    assert next_total(4096, math.inf, precision, True) == 10_000
    assert np.array_equal(round_design("sobol", (64, 192), 3, 5), unit_design("sobol", 256, 3, 5))
    lhs = round_design("latin-hypercube", (64, 100), 3, 5)
    assert np.array_equal(lhs[:64], unit_design("latin-hypercube", 64, 3, 5)) and lhs.shape == (164, 3)


@pytest.mark.parametrize("precision, message", [
    ('{quantity = "bend_radios", half_width = 0.1, max_samples = 100}', 'sampling.precision.quantity = "bend_radios"'),
    ('{quantity = "bend_radius", statistic = "P100", half_width = 0.1, max_samples = 100}',
     'sampling.precision.statistic = "P100": give "mean" or a percentile'),
    ('{quantity = "bend_radius", half_width = -0.1, max_samples = 100}', "sampling.precision.half_width = -0.1"),
    ('{quantity = "bend_radius", half_width = 0.1, max_samples = 8}', "sampling.precision.max_samples = 8: less than"),
    ('{quantity = "bend_radius", half_width = 0.1}', "sampling.precision.max_samples"),
])
def test_bad_precision_is_refused_naming_the_field(tmp_path, precision, message):
    with pytest.raises(StudyFileError) as refused:
        _write(tmp_path, precision, "sobol")
        load_study(tmp_path / "study.toml")
    assert message in str(refused.value)


def test_a_study_to_a_precision_reports_the_width_and_the_samples(tmp_path):
    """The whole command: the mean bend radius of the thesis hose to +-0.15 mm from rounds of 8 solves (cap 64):
    summary.json and the report give the interval's half width, the samples and the rounds, and the samples are
    as many as the rows of samples.csv."""
    _write(tmp_path, '{quantity = "bend_radius", statistic = "mean", half_width = 0.15, max_samples = 64}',
           "latin-hypercube", samples=8, sigma=4.0)
    result = CliRunner().invoke(app, ["study", str(tmp_path / "study.toml"), "-o", str(tmp_path / "out"), "--workers",
                                      "0", "--quiet"])
    assert result.exit_code == 0, result.output
    summary = json.loads((tmp_path / "out" / "summary.json").read_text(encoding="utf-8"))
    precision = summary["precision"]
    assert precision["samples"] == summary["sampling"]["samples"] == sum(precision["rounds"]) > 8
    assert precision["half_width"] == pytest.approx((precision["ci95"][1] - precision["ci95"][0]) / 2.0)
    assert precision["reached"] == (precision["half_width"] <= 0.15)
    assert precision["estimate"] == pytest.approx(summary["quantities"]["bend_radius"]["mean"])
    rows = (tmp_path / "out" / "samples.csv").read_text(encoding="utf-8").strip().splitlines()
    assert len(rows) - 1 == precision["samples"]
    assert "Sampled to a precision" in (tmp_path / "out" / "report.html").read_text(encoding="utf-8")


def _write(folder, precision: str, method: str, samples: int = 16, sigma: float = SIGMA) -> None:
    """A study of the thesis hose's length tolerance (normal, sigma mm) sampled to `precision`."""
    (folder / "problem.toml").write_text(problem_to_toml(demo_problem(180.0, 30)), encoding="utf-8")
    (folder / "study.toml").write_text(
        f'base = "problem.toml"\nsensitivities = false\n[sampling]\nmethod = "{method}"\nsamples = {samples}\n'
        f"seed = 2\nprecision = {precision}\n"
        f'[[vary]]\nparameter = "hose.length"\ndistribution = "normal"\nsigma = {sigma}\n', encoding="utf-8")


def _study(folder, statistic: str, half_width: float, cap: int):
    """The Study of _write with a Monte Carlo first round of 256 samples."""
    _write(folder, f'{{quantity = "bend_radius", statistic = "{statistic}", half_width = {half_width}, '
                   f"max_samples = {cap}}}", "monte-carlo", samples=256)
    study = load_study(folder / "study.toml")[0]
    return replace(study, sampling=replace(study.sampling, count=256))
