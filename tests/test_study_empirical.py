"""An empirical distribution from measured values: drawn by their interpolated quantiles, its moments those of the
draws, read from the study file as a list or a CSV file, and too few or bad values refused."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hoseline.demos.thesis_hose import demo_problem
from hoseline.io.problem_file import problem_to_toml
from hoseline.io.study_file import StudyFileError, load_study
from hoseline.procedures.variation.designs import unit_design
from hoseline.procedures.variation.tolerances import Tolerance
from hoseline.procedures.variation.worst_case import extreme

MEASURED = tuple(float(v) for v in np.round(np.random.default_rng(4).gamma(3.0, 0.6, 40) - 1.5, 3))  # skewed, mm


def test_sampled_quantiles_are_the_measured_values_quantiles():
    """2^14 Sobol' draws of an empirical length tolerance: their quantiles are the data's (np.quantile, linear) to
    0.01 mm; the extremes are the measured ones, never beyond."""
    tolerance = Tolerance("hose.length", "empirical", MEASURED)
    draws = tolerance.values(unit_design("sobol", 2**14, 1, 3))[:, 0]
    probabilities = [0.02, 0.1, 0.25, 0.5, 0.75, 0.9, 0.98]
    assert np.quantile(draws, probabilities) == pytest.approx(np.quantile(MEASURED, probabilities), abs=0.01)
    assert min(MEASURED) <= draws.min() and draws.max() <= max(MEASURED)


@pytest.mark.parametrize("parameter", ["hose.length", "hose.torsion_factor"])
def test_mean_and_variance_are_those_of_the_draws(parameter):
    """The closed-form mean and variance of the interpolated distribution (the first order's) against 2^16 draws;
    near the data's own mean and variance (the interpolation stays within the measured extremes: its variance is
    12 % below the data's here, 40 values)."""
    values = tuple(1.0 + 0.1 * v for v in MEASURED) if parameter == "hose.torsion_factor" else MEASURED
    tolerance = Tolerance(parameter, "empirical", values)
    draws = tolerance.values(unit_design("sobol", 2**16, 1, 8))[:, 0]
    assert tolerance.mean()[0] == pytest.approx(draws.mean(), abs=1e-3 * draws.std())
    assert tolerance.covariance()[0, 0] == pytest.approx(draws.var(), rel=1e-3)
    data = np.log(values) if parameter == "hose.torsion_factor" else np.array(values)
    assert tolerance.mean()[0] == pytest.approx(data.mean(), abs=0.1 * data.std())
    assert 0.8 * data.var(ddof=1) < tolerance.covariance()[0, 0] < data.var(ddof=1)


def test_the_worst_case_range_is_the_measured_extremes():
    """The corner of an empirical tolerance is its smallest or largest measured value."""
    tolerance = Tolerance("hose.length", "empirical", MEASURED)
    assert extreme(tolerance, np.array([1.0]))[0] == max(MEASURED)
    assert extreme(tolerance, np.array([-1.0]))[0] == min(MEASURED)


def test_a_study_file_reads_measured_values_from_a_list_or_a_csv_column(tmp_path):
    """values = [...] in the file, or file = a CSV with a header and column = its name (relative to the study file),
    give the same tolerance; unit = "%" scales the values by the base length."""
    rows = "\n".join(f"{k},{v}" for k, v in enumerate(MEASURED))
    (tmp_path / "lengths.csv").write_text(f"# hose lengths measured on batch 7\npart,deviation_mm\n{rows}\n",
                                          encoding="utf-8")
    listed = _load(tmp_path, f"values = {list(MEASURED)}\n").variation.tolerances[0]
    read = _load(tmp_path, 'file = "lengths.csv"\ncolumn = "deviation_mm"\n').variation.tolerances[0]
    assert listed == read and listed.size == tuple(sorted(MEASURED))
    percent = _load(tmp_path, f'values = {list(MEASURED)}\nunit = "%"\n').variation.tolerances[0]
    length = demo_problem(180.0, 30).hose.length
    assert percent.size == pytest.approx(tuple(v * length / 100.0 for v in sorted(MEASURED)))


@pytest.mark.parametrize("extra, message", [
    ("values = [0.1, 0.2, 0.3]", "vary[0] (hose.length): hose.length: empirical needs at least 10 measured values"),
    ("values = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]", "empirical values are all 0: they vary nothing"),
    ("values = [0.1, nan, 0.3, 0.1, 0.2, 0.3, 0.1, 0.2, 0.3, 0.4]", "finite numbers; got 10 with some not finite"),
    ('file = "missing.csv"', 'vary[0] (hose.length): file = "missing.csv": cannot read'),
    ('file = "bad.csv"', "bad.csv line 3: 'x' is not a finite number"),
    ('file = "two.csv"', 'two.csv: 2 columns: name the one to use with column = "..."'),
    ("values = [1.0]\nsigma = 1.0", "an empirical distribution takes values only: remove sigma"),
    ("", "an empirical distribution takes values only: give values"),
])
def test_bad_measured_values_are_refused_naming_the_field(tmp_path, extra, message):
    """Too few, equal, non-finite or unreadable values are refused naming the entry and the fix."""
    (tmp_path / "bad.csv").write_text("0.1\n0.2\nx\n", encoding="utf-8")
    (tmp_path / "two.csv").write_text("a,b\n1,2\n", encoding="utf-8")
    with pytest.raises(StudyFileError) as refused:
        _load(tmp_path, extra + "\n")
    assert message in str(refused.value)


def test_a_factor_is_interpolated_in_its_logarithm_and_must_be_positive():
    """Factors: the draws are ln of the measured factors' quantiles' interpolation in ln; zero is refused."""
    factors = tuple(math.exp(v / 10.0) for v in MEASURED)
    draws = Tolerance("hose.mass_per_length", "empirical", factors).values(np.array([[0.0], [1.0]]))[:, 0]
    assert draws == pytest.approx([math.log(min(factors)), math.log(max(factors))], abs=1e-9)
    with pytest.raises(ValueError, match="empirical factors must be positive"):
        Tolerance("hose.mass_per_length", "empirical", (0.0,) + factors)


def _load(folder, extra: str):
    """The Study of an empirical hose.length [[vary]] with `extra` keys, on the thesis hose."""
    (folder / "problem.toml").write_text(problem_to_toml(demo_problem(180.0, 30)), encoding="utf-8")
    text = f'base = "problem.toml"\n[[vary]]\nparameter = "hose.length"\ndistribution = "empirical"\n{extra}'
    (folder / "study.toml").write_text(text, encoding="utf-8")
    return load_study(folder / "study.toml")[0]


def test_changed_measurements_change_the_study_fingerprint(tmp_path):
    """A resumed study must not reuse samples drawn from other measurements: the CSV file is not in the study or base
    file's text, so its values enter the fingerprint."""
    from hoseline.io.study_results import fingerprint

    (tmp_path / "lengths.csv").write_text("\n".join(str(v) for v in MEASURED) + "\n", encoding="utf-8")
    before = fingerprint("same text", "same base", _load(tmp_path, 'file = "lengths.csv"\n'))
    (tmp_path / "lengths.csv").write_text("\n".join(str(v + 0.5) for v in MEASURED) + "\n", encoding="utf-8")
    assert fingerprint("same text", "same base", _load(tmp_path, 'file = "lengths.csv"\n')) != before
