"""Sensitivities without sampling: derivatives of the quantities with respect to every tolerance at the nominal hose.

At an equilibrium the Lagrangian's gradient g(x, mu; p) and the end-position constraint
c(x; p) vanish.  Differentiating along a parameter p (implicit function theorem):

    [H  J^T] [ dx/dp  ]     [dg/dp]
    [J   0 ] [-dmu/dp ] = - [dc/dp]

with H the exact Hessian of the Lagrangian and J the constraint Jacobian, the same bordered
system Newton's method factors (banded LDL^T and a 3x3 Schur complement, mechanics/banded.py):
one banded solve per parameter.  dg/dp and dc/dp are central differences of the exact gradient
and constraint at the fixed equilibrium (semi-analytic: the gradient is linear in EI, GJ and the
weight; the mounts enter the clamps; the length enters the segment length), with steps of 1e-7
of the parameter's scale (step_sizes).

The placement is two equilibria in a row: at the end of the place phase the end fitting is free
to roll and the roll found (the lock angle) is then clamped and twisted.  A tolerance moves the
lock angle too, so the first equilibrium is differentiated first (its unknowns include the roll),
and the roll's derivative enters the final clamps: end frame = locked(p) turned by the twist.
Clips the same way: in the place phase every framed clip is free to roll too; a fixed clip is then
locked at its roll, whose derivative enters its frame in the final clamps, while a rotating clip's
roll stays an unknown (the bordered system then has three rows more per clip, mechanics/bordered.py).

The quantities are then differentiated by the chain rule along the tangent of the equilibrium
path, evaluated as a central difference of the readings at x +- eps dx/dp, p +- eps (the minimum
bend radius is taken at its active station, the non-smooth minimum being smooth where it is
attained).  Compared with central differences of full placements in tests/test_study_sensitivity.py.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hoseline.mechanics.banded import kkt_solve, ldlt_banded
from hoseline.mechanics.bordered import kkt_solve_bordered
from hoseline.mechanics.clipped import unknown_layout
from hoseline.mechanics.newton import apply_step, evaluate
from hoseline.mechanics.rod import Clamps
from hoseline.model.problem import Problem
from hoseline.procedures.variation.fixed_obstacles import FixedObstacles
from hoseline.procedures.variation.nominal import PerturbedPlacement, nominal_placement, rolled
from hoseline.procedures.variation.samples import StudyBase, placement_readings
from hoseline.procedures.variation.tolerances import COORDINATES, Variation, coordinate_units

RELATIVE_STEP = 1e-7  # central-difference step, of the parameter's scale (mm: the hose length; deg: 100 deg; ln: 10)


@dataclass
class Sensitivities:
    """Derivatives at the nominal hose, per unit of each canonical coordinate (tolerances.coordinate_names).

    names: the quantities differentiated (quantities() without the deviation).  values: (q,) at
    the nominal hose.  derivatives: (q, width), width = 15 + 5 per clip (Variation.width).  stations: (N+1, 3)
    mm, the nominal centreline; station_derivatives: (N+1, 3, width) mm per unit.  Columns of coordinates no
    tolerance moves are zero.
    kinks: notes on quantities whose derivative is one-sided (a sweep's extreme reached at two poses).
    """

    names: tuple[str, ...]
    values: np.ndarray
    derivatives: np.ndarray
    stations: np.ndarray
    station_derivatives: np.ndarray
    kinks: tuple[str, ...] = ()

    def first_order(self, variation: Variation) -> tuple[np.ndarray, np.ndarray]:
        """First-order (mean, variance) of every quantity under the tolerances: Q0 + g.E[c], g^T Cov(c) g."""
        covariance = variation.covariance()
        mean = self.values + self.derivatives @ variation.mean()
        variance = np.einsum("qi,ij,qj->q", self.derivatives, covariance, self.derivatives)
        return mean, variance

    def station_spread(self, variation: Variation) -> np.ndarray:
        """(N+1,) first-order RMS distance of each station from its mean position, mm."""
        covariance = variation.covariance()
        return np.sqrt(np.einsum("nai,ij,naj->n", self.station_derivatives, covariance, self.station_derivatives))

    def contributions(self, variation: Variation) -> np.ndarray:
        """(q, tolerances): the standard deviation each tolerance alone gives each quantity (the tornado chart)."""
        out = np.zeros((len(self.names), len(variation.tolerances)))
        for k, tolerance in enumerate(variation.tolerances):
            g = sum(self.derivatives[:, list(target)] for target in tolerance.targets)  # one deviation, every target
            out[:, k] = np.sqrt(np.einsum("qi,ij,qj->q", g, tolerance.covariance(), g))
        return out


def step_sizes(problem: Problem) -> np.ndarray:
    """(width,) central-difference steps of the coordinates (15 and five per clip), user units."""
    scale = {"mm": problem.hose.length, "deg": 100.0, "ln": 10.0}
    return np.array([RELATIVE_STEP * scale[unit] for unit in coordinate_units(len(problem.clips))])


def _tangent(system, dgrad: np.ndarray, dconstraint: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(dx/dp, dmu/dp) from the bordered system of `system` (exact Hessian) and the parameter derivatives
    (three border rows for the end; three more per clip)."""
    lower, diag, negative, _ = ldlt_banded(system.band, 0.0)
    solve = kkt_solve if system.jac_t.shape[1] == 3 else kkt_solve_bordered
    step, mu, _ = solve(lower, diag, negative, system.jac_t, dgrad, dconstraint)
    return step, mu


def placement_sensitivities(problem: Problem, varied: tuple[int, ...],
                            obstacles: FixedObstacles | None = None) -> Sensitivities:
    """Derivatives of the placement quantities and stations of `problem` with respect to the coordinates `varied`;
    obstacles: fixed obstacles whose clearances are quantities too.

    Raises PlacementError when the nominal hose cannot be placed, ValueError for stiffener springs
    (not covered: they are phased in after the lock) (nominal.nominal_placement).
    """
    nominal = nominal_placement(problem)
    props, final, state, free_state = nominal.props, nominal.final, nominal.state, nominal.free_state
    free_clamps = PerturbedPlacement(problem, np.zeros(len(COORDINATES))).free()
    free_system = evaluate(props, free_clamps, free_state)
    final_system = evaluate(props, final, state)
    readings = placement_readings(problem, props, final, state, obstacles)
    values = readings.smooth_values()
    steps = step_sizes(problem)
    derivatives = np.zeros((values.size, steps.size))
    station_derivatives = np.zeros(readings.centerlines[0].shape + (steps.size,))
    for j in varied:
        sides, finals = perturbed_finals(problem, free_clamps, free_system, free_state, j, steps[j])
        moved = [evaluate(side.props, clamps, state) for side, clamps in zip(sides, finals)]
        dx, dmu = _tangent(final_system, (moved[0].grad - moved[1].grad) / (2 * steps[j]),
                           (moved[0].constraint - moved[1].constraint) / (2 * steps[j]))
        read = [
            placement_readings(side.problem, side.props, clamps, apply_step(side.props, clamps, state, sign * steps[j] * dx,
                                                                            sign * steps[j] * dmu), obstacles)
            for side, clamps, sign in zip(sides, finals, (1.0, -1.0))
        ]
        derivatives[:, j] = (read[0].smooth_values() - read[1].smooth_values()) / (2 * steps[j])
        station_derivatives[:, :, j] = (read[0].centerlines[0] - read[1].centerlines[0]) / (2 * steps[j])
    return Sensitivities(
        names=tuple(q.name for q in StudyBase(problem, obstacles=obstacles).quantities if q.name != "deviation"),
        values=values,
        derivatives=derivatives,
        stations=readings.centerlines[0],
        station_derivatives=station_derivatives,
    )


def perturbed_finals(problem: Problem, free_clamps: Clamps, free_system, free_state, j: int, step: float):
    """The hoses at coordinate j +- step (user units) and their final placement clamps, the lock angles (of the
    end fitting and of fixed clips) moved to first order: ((side +, side -), (clamps +, clamps -)).
    free_clamps, free_system: the nominal roll-free equilibrium's clamps and system (evaluate), free_state
    its state."""
    eps = step * np.eye(step_sizes(problem).size)[j]
    sides = (PerturbedPlacement(problem, eps), PerturbedPlacement(problem, -eps))
    free = [evaluate(side.props, side.free(), free_state) for side in sides]
    roll_step, clip_roll_step = _roll_tangent(free_clamps, len(free_state.frames), free_system, free, step)
    rolls = [rolled(free_state.roll + sign * step * roll_step, free_state.clip_rolls + sign * step * clip_roll_step)
             for sign in (1.0, -1.0)]
    return sides, [side.final(r) for side, r in zip(sides, rolls)]


def _roll_tangent(free_clamps: Clamps, segments: int, free_system, sides, step: float) -> tuple[float, np.ndarray]:
    """(droll/dp, dclip_rolls/dp) of the roll-free equilibrium (rad per unit) from the systems at p +- step: the
    end roll's and the clips' roll unknowns of its tangent (zero for a clip without one)."""
    dx, _ = _tangent(free_system, (sides[0].grad - sides[1].grad) / (2 * step),
                     (sides[0].constraint - sides[1].constraint) / (2 * step))
    if not free_clamps.clips:
        return float(dx[-1]), np.zeros(0)
    nodes = np.array([hold.node for hold in free_clamps.clips], dtype=np.int64)
    roll_free = np.array([hold.roll_free for hold in free_clamps.clips])
    _, clip_roll_index, end_roll_index, _ = unknown_layout(segments, nodes, roll_free, True)
    return float(dx[end_roll_index]), np.where(clip_roll_index >= 0, dx[np.maximum(clip_roll_index, 0)], 0.0)
