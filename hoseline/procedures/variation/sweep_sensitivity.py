"""Sensitivities of a sweep study: derivatives of the quantities over the whole sweep at the nominal hose.

A sweep is a sequence of equilibria with both fittings clamped: at pose k the clamps are the
placement's final clamps (start frame, end frame locked at the lock angle and twisted) carried
by the bodies' poses (sweep.quasi_static).  A tolerance moves every pose's equilibrium through
the rod (length, EI, GJ, weight), the mount points, and the placement's clamps, the lock angle
included.  So, per parameter p, the chain is the placement's (sensitivity.perturbed_finals: the
roll-free equilibrium differentiated first, the lock angle's derivative entering the final
clamps), then the final clamps carried to pose k, then the implicit function theorem at pose k's
equilibrium with its exact Hessian (one banded solve per parameter and pose):

    [H_k  J_k^T] [ dx_k/dp  ]     [dg_k/dp]
    [J_k   0   ] [-dmu_k/dp ] = - [dc_k/dp]

A quantity of the sweep is an extreme over the poses (the least clearance to an obstacle, the
smallest bend radius, the largest end torque and twisting moment): its derivative is that of its
active pose (and, within the pose, of its active station or nearest point), evaluated as a central
difference of that pose's readings along the tangent, as for placements.  Where two poses tie for
the extreme, or the nearest point to an obstacle jumps between two places along the hose, the
quantity has a kink and only one-sided derivatives: first order is then not a good estimate,
which the comparison with the Monte Carlo variance shows (study.py).  The shape (the stations'
derivatives) is that of the first pose, where the study's envelope is compared.

The equilibria are those the sweep itself reached (run_sweep(equilibria=...)): whatever branch the
published sweep followed, snap-throughs included, is the one differentiated.  Compared with central
differences of full sweeps in tests/test_study_sweep_sensitivity.py.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from hoseline.mechanics.newton import apply_step, evaluate
from hoseline.mechanics.rod import Clamps, RodState
from hoseline.model.problem import Problem
from hoseline.model.sweep import SweepProblem
from hoseline.procedures.geometry.clearance import TriangleIndex
from hoseline.procedures.sweep.quasi_static import _fitting_lines, _nearest, run_sweep
from hoseline.procedures.variation.nominal import EQUILIBRIUM, PerturbedPlacement, nominal_placement
from hoseline.procedures.variation.quantities import PoseReadings, Quantity, natural_scale
from hoseline.procedures.variation.samples import StudyBase, placement_readings
from hoseline.procedures.variation.sensitivity import (Sensitivities, _tangent, perturbed_finals,
                                                      placement_sensitivities, step_sizes)
from hoseline.procedures.variation.statistics import NEGLIGIBLE
from hoseline.procedures.variation.tolerances import COORDINATES

TIE = 1e-6  # relative: two poses this close in a quantity tie for its extreme
SAME_EQUILIBRIUM = 1e-6  # of the length: tied poses whose stations are this close are one equilibrium visited twice


def pose_clamps(sweep: SweepProblem, index: int, placed: Clamps) -> Clamps:
    """The clamps at sweep pose `index` of a hose whose placement ended under `placed` (its final clamps):
    both fittings carried by their bodies' poses, as the sweep carries them (quasi_static._Tracker.clamps)."""
    start, end = sweep.pose(sweep.start_body, index), sweep.pose(sweep.end_body, index)
    return Clamps(start.point(placed.start_point), start.frame(placed.start_frame), end.point(placed.end_point),
                  end.frame(placed.end_frame), False, placed.line_weight)


class _PoseReader:
    """Reads one pose of a sweep (health and clearance to every obstacle) for any state of the hose."""

    def __init__(self, sweep: SweepProblem) -> None:
        self.sweep = sweep
        self.indexes = [TriangleIndex(o.vertices, o.faces) for o in sweep.obstacles]

    def read(self, problem: Problem, props, clamps: Clamps, state: RodState, index: int) -> PoseReadings:
        """PoseReadings of one pose (M = 1), the clearance to every obstacle at its pose `index`."""
        readings = placement_readings(problem, props, clamps, state)
        nodes = readings.centerlines[0]
        fittings = _fitting_lines(replace(self.sweep, problem=problem), index)  # as the sweep measures: fittings too
        readings.clearance = np.array([
            [_nearest(tree, self.sweep.pose(obstacle.body, index), nodes, problem.hose.outer_radius, fittings).distance]
            for obstacle, tree in zip(self.sweep.obstacles, self.indexes)
        ]).reshape(-1, 1)
        return readings


def per_pose_values(readings: PoseReadings) -> np.ndarray:
    """(q, M) per smooth quantity (PoseReadings.smooth_values order) its value at every pose, signed so that the
    quantity over the sweep is the minimum over the poses (the largest torque and twisting moment negated)."""
    pose = readings.per_pose()
    return np.vstack([readings.clearance, pose["bend_radius"], -pose["end_torque"], -pose["twisting_moment"],
                      -readings.forces.T, -readings.moments.T])


def kinks(smooth: tuple[Quantity, ...], readings: PoseReadings, length: float,
          stiffness: float) -> tuple[np.ndarray, list[str]]:
    """The active pose of every smooth quantity (where its extreme over the sweep is), and a note for each
    quantity whose extreme is reached at two poses with different equilibria (within TIE of each other): a
    kink, where the derivative is one-sided.  A pose visited twice (the sweep going there and back) with the
    same equilibrium is no kink, nor is a quantity that is nought (within statistics.NEGLIGIBLE of its natural
    scale, e.g. the end torque of a hose that stays in a plane).  length: of the hose, mm; stiffness: the larger
    of EI and GJ, N*mm^2."""
    values = per_pose_values(readings)
    active = np.argmin(values, axis=1)
    notes = []
    for q, quantity in enumerate(smooth):
        name = quantity.name
        best = values[q, active[q]]
        if abs(best) <= NEGLIGIBLE * natural_scale(quantity, length, stiffness):
            continue
        tied = np.nonzero(values[q] - best <= TIE * abs(best))[0]
        shapes = readings.centerlines[tied]
        apart = np.max(np.linalg.norm(shapes - shapes[0], axis=2), axis=1)
        other = tied[apart > SAME_EQUILIBRIUM * length]
        if other.size:
            notes.append(f"{name}: its extreme over the sweep is reached at poses {active[q]} and {other[0]} (different "
                         f"equilibria, within {TIE:g} of each other): a kink, where its derivative is one-sided (pose "
                         f"{active[q]}'s is given); the first-order numbers of {name} are not valid")
    return active, notes


def sweep_sensitivities(sweep: SweepProblem, varied: tuple[int, ...]) -> Sensitivities:
    """Derivatives of the sweep quantities (per obstacle clearance, bend radius, end torque, twist rate: the
    extremes over all poses) and of the first pose's stations with respect to the coordinates `varied`.

    Raises PlacementError when the nominal hose cannot be placed or swept, ValueError for clips, for stiffener
    springs (nominal.nominal_placement) or when the sweep's equilibria are not those of the placement's clamps.
    """
    problem = sweep.problem
    if problem.clips:
        raise ValueError("the clips are not covered (the pose clamps carried here hold the two fittings only)")
    nominal = nominal_placement(problem)
    equilibria: list[tuple[Clamps, RodState]] = []
    run_sweep(replace(sweep, compare_free_roll=False), equilibria=equilibria, judge_assembly=False)
    reader = _PoseReader(sweep)
    props = nominal.props
    per_pose = [reader.read(problem, props, clamps, state, k) for k, (clamps, state) in enumerate(equilibria)]
    whole = PoseReadings(*(np.concatenate([getattr(r, name) for r in per_pose], axis=axis) for name, axis in
                           (("centerlines", 0), ("bend_radius", 0), ("twisting_moment", 0), ("end_moment", 0),
                            ("end_direction", 0), ("clearance", 1))), problem.hose.torsional_stiffness,
                         *(np.concatenate([getattr(r, name) for r in per_pose]) for name in ("forces", "moments")))
    values = whole.smooth_values()
    smooth = tuple(q for q in StudyBase(problem, sweep).quantities if q.name != "deviation")
    names = tuple(q.name for q in smooth)
    hose = problem.hose
    active, notes = kinks(smooth, whole, hose.length, max(hose.bending_stiffness, hose.torsional_stiffness))
    needed = sorted(set(active.tolist()) | {0})
    systems = {}
    for k in needed:
        clamps, state = equilibria[k]
        rebuilt = pose_clamps(sweep, k, nominal.final)
        system = evaluate(props, rebuilt, state)
        if system.residual > EQUILIBRIUM or not np.allclose(rebuilt.end_frame, clamps.end_frame, atol=1e-9):
            raise ValueError(f"pose {k} of the sweep is not an equilibrium under the placement's clamps carried to it "
                             f"(residual {system.residual:.2e}): the sweep's assembly differs from the placement")
        systems[k] = system
    free_clamps = PerturbedPlacement(problem, np.zeros(len(COORDINATES))).free()
    free_system = evaluate(props, free_clamps, nominal.free_state)
    derivatives = np.zeros((values.size, len(COORDINATES)))
    station_derivatives = np.zeros(whole.centerlines[0].shape + (len(COORDINATES),))
    steps = step_sizes(problem)
    for j in varied:
        h = steps[j]
        sides, finals = perturbed_finals(problem, free_clamps, free_system, nominal.free_state, j, h)
        for k in needed:
            state = equilibria[k][1]
            clamps = [pose_clamps(sweep, k, final) for final in finals]
            moved = [evaluate(side.props, c, state) for side, c in zip(sides, clamps)]
            dx, dmu = _tangent(systems[k], (moved[0].grad - moved[1].grad) / (2 * h),
                               (moved[0].constraint - moved[1].constraint) / (2 * h))
            read = [reader.read(side.problem, side.props, c, apply_step(side.props, c, state, sign * h * dx,
                                                                        sign * h * dmu), k)
                    for side, c, sign in zip(sides, clamps, (1.0, -1.0))]
            slope = (read[0].smooth_values() - read[1].smooth_values()) / (2 * h)
            derivatives[active == k, j] = slope[active == k]
            if k == 0:
                station_derivatives[:, :, j] = (read[0].centerlines[0] - read[1].centerlines[0]) / (2 * h)
    return Sensitivities(names, values, derivatives, whole.centerlines[0], station_derivatives, tuple(notes))



def study_sensitivities(base: StudyBase, problem: Problem, varied: tuple[int, ...]) -> Sensitivities:
    """The sensitivities of `problem`'s hose (the base's or a deviated one) in the base's setting: its placement
    (with the base's fixed obstacles) or its sweep (sensitivity.placement_sensitivities, sweep_sensitivities)."""
    if base.sweep is None:
        return placement_sensitivities(problem, varied, base.obstacles)
    return sweep_sensitivities(replace(base.sweep, problem=problem), varied)
