"""Sensitivities of sweep studies against central differences of full sweeps; kinks said; first order against Monte Carlo."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from hoseline.demos.sweep import demo_sweep
from hoseline.model import Hose, Mount, Problem
from hoseline.model.motion import Rotation, generated_motion
from hoseline.model.sweep import SweepProblem
from hoseline.procedures.variation.engine import Where
from hoseline.procedures.variation.run import run_study
from hoseline.procedures.variation.samples import StudyBase
from hoseline.procedures.variation.sensitivity import step_sizes
from hoseline.procedures.variation.study import Sampling, Study
from hoseline.procedures.variation.sweep_sensitivity import sweep_sensitivities
from hoseline.procedures.variation.tolerances import COORDINATES, INDEX, Tolerance, Variation, perturbed

AGREEMENT = 1e-5  # relative; measured: see test_sweep_sensitivities_match_finite_differences_of_full_sweeps


def _sweep(twist: float, steps_per_degree: float = 0.1, segments: int = 16, weight: bool = True) -> SweepProblem:
    """The demo sweep (steer both ways, jounce and rebound, past the strut), coarse, the hose given weight
    (so the mass factor matters) unless `weight` is False, and twisted `twist` degrees at assembly."""
    sweep = demo_sweep(steps_per_degree=steps_per_degree, segments=segments)
    problem = replace(sweep.problem, end_twist_deg=twist)
    if weight:
        problem = replace(problem, hose=replace(problem.hose, mass_per_length=0.3), gravity=np.array([0.0, 0.0, -9.81]))
    return replace(sweep, problem=problem, compare_free_roll=False)


def _full(sweep: SweepProblem, deviation: np.ndarray) -> np.ndarray:
    """Quantities over the whole sweep (clearance to the strut, bend radius, end torque, twist rate) and the first
    pose's stations, by a full sweep of the perturbed hose (placement from the straight hose, every pose)."""
    base = StudyBase(sweep.problem, sweep)
    readings, _ = base.read(perturbed(sweep.problem, deviation))
    return np.concatenate([readings.smooth_values(), readings.centerlines[0].ravel()])


def test_sweep_sensitivities_match_finite_differences_of_full_sweeps():
    """Every coordinate (mounts, directions, length, EI, GJ, weight, clocking) against central differences of
    whole sweeps; the chain runs through the lock angle, the clamps carried to every pose and the active pose of
    each extreme (26 poses; the twist at assembly breaks the ties between mirror poses, so every extreme is
    smooth).  The steps are 1e-5 of the scale (3e-3 mm of a mount): the clearance to the strut, a cylinder of 64
    flat facets, is smooth only while the nearest points stay on their facets, and steps of 3e-4 of the scale
    (0.1 mm) already cross to the next one (their differences are off by 1 %).  Measured largest relative
    difference: 1.3e-6 over the quantities, 3.1e-7 over the stations."""
    sweep = _sweep(45.0)
    sensitivities = sweep_sensitivities(sweep, tuple(range(len(COORDINATES))))
    assert sensitivities.kinks == ()
    scale_steps = step_sizes(sweep.problem)
    worst = 0.0
    for j in range(len(COORDINATES)):
        e = np.zeros(len(COORDINATES))
        e[j] = 100.0 * scale_steps[j]
        reference = (_full(sweep, e) - _full(sweep, -e)) / (2.0 * e[j])
        quantities, stations = np.split(reference, [sensitivities.values.size])
        # relative to the derivative, or to the value per unit of the parameter's scale if that is larger
        scale = np.abs(quantities) + np.abs(sensitivities.values) / (scale_steps[j] / 1e-7)
        worst = max(worst, float(np.max(np.abs(sensitivities.derivatives[:, j] - quantities) / scale)))
        error = np.max(np.abs(sensitivities.station_derivatives[:, :, j].ravel() - stations))
        worst = max(worst, float(error / max(np.max(np.abs(stations)), 1e-12)))
    assert worst <= AGREEMENT, worst


def test_mirror_poses_tying_for_the_extreme_are_a_kink_and_said():
    """The weightless hose untwisted: the jounce to +40 mm and the rebound to -40 mm give the same largest end
    torque on different (mirror) equilibria: the extreme over the sweep has a kink there, full sweeps see a
    derivative of nought along a mirror-odd tolerance where either pose alone has a large one; the
    sensitivities say so."""
    sweep = _sweep(0.0, weight=False)
    j = INDEX["end.z"]
    sensitivities = sweep_sensitivities(sweep, (j,))
    said = " ".join(sensitivities.kinks)
    assert "end_torque" in said and "twist_rate" in said and "kink" in said
    torque = sensitivities.names.index("end_torque")
    e = np.zeros(len(COORDINATES))
    e[j] = 1e-3
    full = (_full(sweep, e)[torque] - _full(sweep, -e)[torque]) / 2e-3
    one_sided = sensitivities.derivatives[torque, j]
    assert abs(one_sided) > 1e3 * abs(full)


def _short_sweep_study(size: float) -> Study:
    """64 Sobol samples of a 13-pose sweep of the twisted hose: end position and direction, length, EI and clocking
    tolerances, scaled by `size` (1: 0.2 mm, 0.4 deg, -1..+0.5 mm, EI factor 1.1, 0.5 deg of clocking)."""
    sweep = _sweep(45.0, steps_per_degree=0.05, segments=12)
    variation = Variation((Tolerance("end.point", "sphere", (0.2 * size,)), Tolerance("end.direction", "cone", (0.4 * size,)),
                           Tolerance("hose.length", "uniform", (-1.0 * size, 0.5 * size)),
                           Tolerance("hose.bending_stiffness", "lognormal", (1.0 + 0.1 * size,)),
                           Tolerance("end.twist", "normal", (0.5 * size,))))
    return Study("sweep", StudyBase(sweep.problem, sweep), variation, Sampling("sobol", 64, 1), ())


def test_first_order_agrees_with_monte_carlo_for_a_sweep_with_small_tolerances():
    """A tenth of those tolerances: the first-order variance of every quantity over the sweep and of the shape
    agrees with the samples of full sweeps within their sampling error (measured |z| <= 0.7, standard deviations
    within 5 %)."""
    outcome = run_study(_short_sweep_study(0.1), where=Where(workers=0))
    first = outcome.first_order
    assert first is not None and first.names[0] == "clearance:strut"
    assert all(check.agrees for check in first.agreements + [first.shape]), [c.z for c in first.agreements]
    for check in first.agreements:
        assert check.monte_carlo_variance > 0.0
        assert np.sqrt(check.monte_carlo_variance / check.first_order_variance) == pytest.approx(1.0, abs=0.1)
    assert not any("DISAGREES" in note or "placements only" in note for note in outcome.notes)


def test_a_sweep_whose_extreme_changes_pose_makes_first_order_and_monte_carlo_disagree_and_is_said():
    """Five times those tolerances: at the full steer the twisted hose's end torque grows faster and faster along
    a tolerance (388, 444, 506, 641 N*mm at 0, 1/4, 1/2 and 1 of one sample's deviation), overtakes the nominal
    largest torque (at full rebound, 523 N*mm) and makes it the extreme over the sweep: the response is far from
    linear, the samples' spread of the end torque is 2.7 times the first-order one, and the study says so."""
    outcome = run_study(_short_sweep_study(5.0), where=Where(workers=0))
    first = outcome.first_order
    torque = first.agreements[first.names.index("end_torque")]
    assert not torque.agrees and torque.monte_carlo_variance > 4.0 * torque.first_order_variance
    assert any("DISAGREES" in note and "end_torque" in note for note in outcome.notes)


def test_a_quantity_nought_at_every_pose_is_no_kink():
    """A hose that stays in a plane (an arch between coaxial mounts, the end fitting turned in that plane) has no
    end torque at any pose: every pose ties at nought, which is rounding, not a kink, and nothing is said."""
    hose = Hose(length=110.0, outer_diameter=4.0, bending_stiffness=1e4, torsional_stiffness=1e4 / 1.5, segments=24)
    tilt = np.radians(10.0)
    problem = Problem(hose, Mount([0.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
                      Mount([100.0, 0.0, 0.0], [-np.cos(tilt), np.sin(tilt), 0.0]))
    turn = generated_motion("end", [Rotation(np.array([0.0, 0.0, 1.0]), np.array([100.0, 0.0, 0.0]), (0.0, 8.0), 4, "turn")])
    sweep = SweepProblem(problem, None, "end", (turn,), (), compare_free_roll=False)
    sensitivities = sweep_sensitivities(sweep, (INDEX["hose.length"],))
    assert sensitivities.kinks == ()
    assert abs(sensitivities.values[sensitivities.names.index("end_torque")]) < 1e-9
