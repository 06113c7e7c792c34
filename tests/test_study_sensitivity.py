"""Sensitivities from the exact Hessian against full placements, and the first-order variance against Monte Carlo."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from hoseline.demos.thesis_hose import demo_problem
from hoseline.model import Hose, Mount, Problem
from hoseline.procedures.placement.sequence import place_only
from hoseline.procedures.variation.engine import Where
from hoseline.procedures.variation.run import run_study
from hoseline.procedures.variation.samples import StudyBase, placement_readings
from hoseline.procedures.variation.sensitivity import placement_sensitivities, step_sizes
from hoseline.procedures.variation.study import Sampling, Study
from hoseline.procedures.variation.tolerances import COORDINATES, Tolerance, Variation, perturbed

# Measured largest relative difference over all 15 coordinates and all quantities and stations: 4.5e-7
# (central differences of full placements, Richardson-extrapolated from steps of 3e-4 and 1.5e-4 of the scale)
AGREEMENT = 2e-6


def _hose_with_weight(twist: float) -> Problem:
    """The thesis hose, 40 segments, given weight (so the mass factor matters), twisted `twist` degrees."""
    problem = demo_problem(twist, 40)
    return replace(problem, hose=replace(problem.hose, mass_per_length=0.3), gravity=np.array([0.0, 0.0, -9.81]))


def _readings(problem: Problem, deviation: np.ndarray) -> np.ndarray:
    """Quantities (bend radius, end torque, twist rate) and stations of a full placement of the perturbed hose."""
    hose = perturbed(problem, deviation)
    props, clamps, state, _ = place_only(hose)
    readings = placement_readings(hose, props, clamps, state)
    return np.concatenate([readings.smooth_values(), readings.centerlines[0].ravel()])


def test_sensitivities_match_finite_differences_of_full_placements():
    """d(quantity)/d(parameter) for every coordinate (mounts, directions, length, EI, GJ, weight, twist) against
    central differences of whole placements from the straight hose, which re-find the lock angle each time."""
    problem = _hose_with_weight(90.0)
    sensitivities = placement_sensitivities(problem, tuple(range(len(COORDINATES))))
    steps = 3000.0 * step_sizes(problem)  # 3e-4 of the scale: the truncation error is removed by Richardson

    def central(j: int, step: float) -> np.ndarray:
        e = np.zeros(len(COORDINATES))
        e[j] = step
        return (_readings(problem, e) - _readings(problem, -e)) / (2.0 * step)

    worst = 0.0
    for j in range(len(COORDINATES)):
        reference = (4.0 * central(j, steps[j] / 2.0) - central(j, steps[j])) / 3.0
        quantities, stations = np.split(reference, [sensitivities.values.size])
        ours = sensitivities.derivatives[:, j]
        # per quantity relative to its derivative, or to its value per unit of the parameter's scale if that is larger
        scale = np.abs(quantities) + np.abs(sensitivities.values) / (step_sizes(problem)[j] / 1e-7)
        worst = max(worst, float(np.max(np.abs(ours - quantities) / scale)))
        station_error = np.max(np.abs(sensitivities.station_derivatives[:, :, j].ravel() - stations))
        worst = max(worst, float(station_error / np.max(np.abs(stations))))
    assert worst <= AGREEMENT


def _thesis_tolerances(size: float) -> Variation:
    """Mount position, direction, length with the pressure change, stiffness and clocking, scaled by `size`."""
    return Variation((
        Tolerance("end.point", "sphere", (1.0 * size,)),
        Tolerance("end.direction", "cone", (2.0 * size,)),
        Tolerance("hose.length", "uniform", (-13.2 * size, 6.6 * size)),
        Tolerance("hose.bending_stiffness", "lognormal", (1.0 + size,)),
        Tolerance("end.twist", "normal", (3.0 * size,)),
    ))


def test_first_order_variance_agrees_with_monte_carlo_for_small_tolerances():
    """A tenth of the usual tolerances on the thesis hose: every quantity's and the shape's first-order variance
    lies within 3 standard errors of the 256-sample Sobol estimate (measured |z| <= 0.9; a first-order variance
    1.5 times too large gives |z| = 8.5)."""
    problem = demo_problem(90.0, 40)
    study = Study("small", StudyBase(problem), _thesis_tolerances(0.1), Sampling("sobol", 256, 1), ())
    outcome = run_study(study, where=Where(workers=0))
    first = outcome.first_order
    assert all(check.agrees for check in first.agreements + [first.shape]), [c.z for c in first.agreements]
    assert not any("DISAGREES" in note for note in outcome.notes)
    # and the estimates are not trivially equal: the spread is real
    assert all(check.monte_carlo_variance > 0.0 for check in first.agreements)


def test_a_fork_makes_first_order_and_monte_carlo_disagree_and_is_said():
    """A hose compressed between coaxial mounts bows out to the side a tiny misalignment decides: the response
    to the tolerance is not linear at all, the shape's first-order spread is a fraction of the sampled one,
    and the study says so."""
    hose = Hose(length=110.0, outer_diameter=4.0, bending_stiffness=1e4, torsional_stiffness=1e4 / 1.5, segments=30)
    problem = Problem(hose, Mount([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]), Mount([100.0, 0.0, 0.0], [-1.0, 0.0, 0.0]))
    variation = Variation((Tolerance("end.point", "normal", (0.05, 0.05, 0.05)),))
    study = Study("fork", StudyBase(problem), variation, Sampling("sobol", 64, 1), ())
    outcome = run_study(study, where=Where(workers=0))
    shape = outcome.first_order.shape
    assert not shape.agrees and shape.monte_carlo_variance > 100.0 * shape.first_order_variance
    assert any("DISAGREES" in note and "shape" in note for note in outcome.notes)
    # the hose really bows out both ways (the two sides of the fork): stations far apart on either side
    middle = outcome.samples["shapes"][:, 0, 15, 1:]
    angles = np.degrees(np.arctan2(middle[:, 1], middle[:, 0]))
    assert np.ptp(angles) > 180.0 and np.min(np.linalg.norm(middle, axis=1)) > 10.0
    assert math.isfinite(shape.z)


def test_without_the_lock_angle_the_sensitivities_are_wrong(monkeypatch):
    """The guard of the test above: dropping the lock angle's derivative (the roll found by the place phase)
    spoils the derivatives far beyond the tolerance (so the finite-difference test can fail)."""
    import hoseline.procedures.variation.sensitivity as sensitivity

    j = COORDINATES.index("end.tilt_a")
    problem = _hose_with_weight(90.0)
    right = placement_sensitivities(problem, (j,))
    monkeypatch.setattr(sensitivity, "_roll_tangent", lambda *arguments: (0.0, np.zeros(0)))
    wrong = placement_sensitivities(problem, (j,))
    difference = np.max(np.abs(wrong.station_derivatives[:, :, j] - right.station_derivatives[:, :, j]))
    assert difference > 1e3 * AGREEMENT * np.max(np.abs(right.station_derivatives[:, :, j]))


def test_tornado_of_a_weightless_hose():
    """A weightless hose's shape does not depend on EI when the torsion factor is kept (the energy only scales):
    a factor-two stiffness spread adds nothing to the bend radius or the twist rate, and dominates the end
    torque, which scales with EI, as do the mounts' forces and moments; the mount tolerance is what moves the
    shape."""
    problem = demo_problem(90.0, 40)
    variation = Variation((Tolerance("end.point", "sphere", (0.1,)), Tolerance("hose.bending_stiffness", "lognormal", (2.0,))))
    sensitivities = placement_sensitivities(problem, variation.varied)
    contributions = sensitivities.contributions(variation)  # rows: bend_radius, end_torque, twist_rate, reactions
    bend, torque, twist = contributions[:3]
    assert bend[1] < 1e-6 * bend[0] and twist[1] < 1e-6 * twist[0]
    assert torque[1] > 10.0 * torque[0]
    # the end torque is proportional to EI: d torque / d ln(EI) = torque
    assert sensitivities.derivatives[1, COORDINATES.index("hose.bending")] == pytest.approx(sensitivities.values[1], rel=1e-6)
    reactions = [k for k, name in enumerate(sensitivities.names) if name.startswith(("force:", "moment:"))]
    assert len(reactions) == 4
    assert np.allclose(sensitivities.derivatives[reactions, COORDINATES.index("hose.bending")],
                       sensitivities.values[reactions], rtol=1e-6)


def test_mounts_moved_together_move_the_weightless_hose_rigidly():
    """A deviation shared by both mounts of a weightless hose is a rigid translation: every sample's shape is the
    nominal one moved by it (the deviation quantity is its length, and its mean square 3 sigma^2 in closed form),
    the bend radius, end torque and twist rate do not change, and the first order says the same (a shared
    contribution of zero where the mounts moved apart would give a spread)."""
    sigma = 0.5
    problem = demo_problem(90.0, 30)
    together = Variation((Tolerance("start.point", "normal", (sigma,) * 3, shared_with=("end.point",)),))
    study = Study("subframe", StudyBase(problem), together, Sampling("sobol", 32, 4), ())
    outcome = run_study(study, where=Where(workers=0))
    values = outcome.samples["values"]
    names = [q.name for q in study.quantities]
    moved = np.linalg.norm(outcome.coordinates[:, 0:3], axis=1)
    assert np.allclose(outcome.coordinates[:, 0:3], outcome.coordinates[:, 5:8])
    assert np.allclose(values[:, names.index("deviation")], moved, rtol=1e-6, atol=1e-9)
    assert np.mean(moved**2) == pytest.approx(3.0 * sigma**2, rel=0.15)  # 32 draws
    for name in ("bend_radius", "end_torque", "twist_rate"):
        column = values[:, names.index(name)]
        assert np.ptp(column) <= 1e-6 * abs(outcome.nominal[names.index(name)])
    sensitivities = placement_sensitivities(problem, together.varied)
    contributions = sensitivities.contributions(together)[:, 0]  # bend_radius, end_torque, twist_rate
    apart = Variation((Tolerance("end.point", "normal", (sigma,) * 3),))
    assert np.all(contributions <= 1e-6 * sensitivities.contributions(apart)[:, 0])
