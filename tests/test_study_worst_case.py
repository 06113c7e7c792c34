"""Worst-case corners: the linear stack in closed form for every distribution, and through the solver."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hoseline.procedures.variation.tolerances import INDEX, Z95, Tolerance, Variation, fitting_axes
from hoseline.procedures.variation.worst_case import corner


def test_the_corner_is_the_linear_stack_of_every_tolerance():
    """g.corner = the sum over tolerances of the largest g.c over each range: 3 sigma |g| per axis of a normal point
    (in the fitting's axes), R |g| for a sphere, angle |g| for a cone, the bounds of uniform, triangular and
    truncated ranges, 3 sigma of ln for a lognormal factor, a shared deviation once with its targets' summed
    derivative; and no point of the ranges (10^5 drawn in them) gives more."""
    axes = fitting_axes(np.array([0.0, 0.6, 0.8]))
    variation = Variation((
        Tolerance("end.point", "normal", (0.2, 0.2, 1.0), axes=axes),
        Tolerance("start.point", "sphere", (0.5,)),
        Tolerance("end.direction", "cone", (2.0,)),
        Tolerance("hose.length", "uniform", (-4.0, 2.0)),
        Tolerance("hose.length", "triangular", (-1.0, 0.0, 3.0)),
        Tolerance("end.twist", "truncnormal", (0.5, 2.0, -1.0, 10.0)),
        Tolerance("hose.bending_stiffness", "lognormal", (1.5,)),
        Tolerance("start.direction", "normal", (1.0,), shared_with=("end.direction",)),
    ))
    rng = np.random.default_rng(4)
    g = rng.normal(size=variation.width)
    g[INDEX["hose.length"]] = -0.7  # the length pushed down: uniform to -4, triangular to -1
    c = corner(variation, g)
    a = np.array(axes)
    end_point = 3.0 * np.abs(a @ g[5:8]) @ np.array([0.2, 0.2, 1.0])
    start_point = 0.5 * np.linalg.norm(g[0:3])
    cone = 2.0 * np.linalg.norm(g[8:10])
    length = 0.7 * (4.0 + 1.0)
    twist = abs(g[INDEX["end.twist"]]) * (min(10.0, 0.5 + 6.0) if g[INDEX["end.twist"]] > 0 else -max(-1.0, 0.5 - 6.0))
    bending = abs(g[INDEX["hose.bending"]]) * 3.0 * math.log(1.5) / Z95
    shared = 3.0 * np.sum(np.abs(g[3:5] + g[8:10]))
    assert g @ c == pytest.approx(end_point + start_point + cone + length + twist + bending + shared, rel=1e-12)
    # inside the ranges nothing beats it: bounded distributions over their support, normals within 3 sigma
    unit = rng.uniform(0.00135, 0.99865, size=(100_000, variation.dimensions))
    assert np.max(variation.coordinates(unit) @ g) <= g @ c


def test_a_tolerance_whose_derivative_is_rounding_stays_at_its_mean():
    variation = Variation((Tolerance("hose.length", "uniform", (-4.0, 2.0)),
                           Tolerance("hose.bending_stiffness", "uniform", (0.5, 3.0))))
    g = np.zeros(variation.width)
    g[INDEX["hose.length"]], g[INDEX["hose.bending"]] = 1.0, -1e-9
    c = corner(variation, g)
    assert c[INDEX["hose.length"]] == 2.0
    assert c[INDEX["hose.bending"]] == pytest.approx(variation.tolerances[1].mean()[0])


def test_through_the_solver_the_corner_is_worse_than_every_sample_and_its_problem_file_reproduces_it(tmp_path):
    """A tenth of the thesis tolerances, all bounded: per quantity the hose solved at its corner is worse than each
    of 256 samples, its change from nominal within 15 % of the first-order stack's, and
    worst_case/QUANTITY/problem.toml solved again gives it."""
    from hoseline.demos.thesis_hose import demo_problem
    from hoseline.io.problem_file import load_problem
    from hoseline.procedures.placement.sequence import solve
    from hoseline.procedures.variation.engine import Where
    from hoseline.procedures.variation.run import run_study
    from hoseline.procedures.variation.samples import StudyBase
    from hoseline.procedures.variation.study import Sampling, Study
    from hoseline.report.study_report import write_study_report

    variation = Variation((
        Tolerance("end.point", "sphere", (0.1,)),
        Tolerance("end.direction", "cone", (0.2,)),
        Tolerance("hose.length", "uniform", (-1.32, 0.66)),
        Tolerance("hose.bending_stiffness", "loguniform", (1.1,)),
        Tolerance("end.twist", "uniform", (-0.3, 0.3)),
    ))
    study = Study("corners", StudyBase(demo_problem(90.0, 24)), variation, Sampling("sobol", 256, 1), (),
                  worst_case=True)
    outcome = run_study(study, where=Where(workers=0))
    names = [q.name for q in study.quantities]
    assert [case.quantity.name for case in outcome.worst_cases] == ["bend_radius", "end_torque", "twist_rate",
                                                                     "force:start", "force:end", "moment:start",
                                                                     "moment:end"]
    base = tmp_path / "problem.toml"
    base.write_text("", encoding="utf-8")
    write_study_report(outcome, tmp_path / "out", "", base)
    for case in outcome.worst_cases:
        sampled = outcome.samples["values"][:, names.index(case.quantity.name)]
        down = case.quantity.sense == "at least"
        assert (case.solved < sampled.min()) if down else (case.solved > sampled.max()), case.quantity.name
        # the stack predicts the change from nominal to first order (measured: solved / first-order change 0.95 bend
        # radius, 1.11 end torque, 1.02 twist rate: the torque grows faster than linearly along the corner)
        assert (case.solved - case.nominal) / (case.first_order - case.nominal) == pytest.approx(1.0, abs=0.15)
        placed = solve(load_problem(tmp_path / "out" / "worst_case" / case.quantity.name.replace(":", "_") / "problem.toml"),
                       estimate_error=False)
        if case.quantity.name == "bend_radius":
            assert placed.min_bend_radius == pytest.approx(case.solved, rel=1e-6)
        if case.quantity.name == "end_torque":
            assert abs(float(placed.end_moment @ placed.problem.end.direction)) == pytest.approx(case.solved, rel=1e-6)
