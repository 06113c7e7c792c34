"""Fit a hose's stiffness (and optionally its weight and a length correction) to scans.

The model is solved at the twist of each scan; the residuals are the vectors from every
scan station to the closest point of the model centreline; scipy's least_squares adjusts
the parameters (in logarithms, so every parameter is a relative change).  Each evaluation
re-solves the equilibria by Newton's method from the previous ones (warm start: the placed
state with its free end roll, then each twisted state), falling back to a full placement
only when Newton does not reach a stable equilibrium.

Identifiability.  Without weight (mass_per_length or gravity zero) the shape depends on the
stiffness ratios only: EI scales out, so only the torsion factor (GJ over the isotropic
EI/(1 + nu)) can be fitted.  With weight the shape depends on the weight per EI, so EI and
mass_per_length cannot both be fitted.  Such parameters are refused before the fit with a
note; after it, parameters whose relative uncertainty (from the Jacobian) exceeds
UNIDENTIFIABLE_RELATIVE_STD are reported as not identified by the scans.  Units: mm, N*mm^2, kg/m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import least_squares

from hoseline.mechanics.newton import end_frame_of, node_positions, solve_equilibrium
from hoseline.mechanics.rod import RodState
from hoseline.model.hose import Hose, isotropic_torsional_stiffness
from hoseline.model.problem import Problem
from hoseline.procedures.placement.continuation import PlacementError
from hoseline.procedures.scans.deviation import Deviation, closest_on_polyline, deviation
from hoseline.procedures.placement.sequence import PlacementPath, rod_properties, solve
from hoseline.procedures.scans.parameters import PARAMETERS

UNIDENTIFIABLE_RELATIVE_STD = 0.25
LOG_BOUND = math.log(100.0)  # no parameter moves by more than 100x


@dataclass(frozen=True)
class ScanCase:
    """One scan of the hose: the twist of the end fitting (degrees) and its centreline stations (n, 3), mm."""

    twist_deg: float
    points: np.ndarray


@dataclass
class FittedParameter:
    """A calibrated parameter: initial and fitted value, standard uncertainty (None if not identified)."""

    name: str
    unit: str
    initial: float
    value: float
    std: float | None
    identifiable: bool
    note: str = ""


@dataclass
class Calibration:
    """What calibrate returns.

    parameters: the fitted parameters.  hose: the calibrated hose.
    before, after: one Deviation per scan case, with the initial and the calibrated hose.
    notes: parameters refused or not identified, and why.
    evaluations: model evaluations; warm_solves / cold_solves: how they were solved.
    """

    parameters: list[FittedParameter]
    hose: Hose
    before: list[Deviation]
    after: list[Deviation]
    notes: list[str] = field(default_factory=list)
    evaluations: int = 0
    warm_solves: int = 0
    cold_solves: int = 0


def hose_with(base: Hose, values: dict[str, float]) -> Hose:
    """`base` with some of PARAMETERS changed; GJ follows EI at the given (or base) torsion factor."""
    bending = values.get("bending_stiffness", base.bending_stiffness)
    factor = values.get("torsion_factor", base.torsion_factor)
    second = None if base.bending_stiffness_2 is None else base.bending_stiffness_2 * bending / base.bending_stiffness
    return replace(
        base,
        bending_stiffness=bending,
        bending_stiffness_2=second,
        torsional_stiffness=factor * isotropic_torsional_stiffness(bending),
        mass_per_length=values.get("mass_per_length", base.mass_per_length),
        length=values.get("length", base.length),
    )


def current_value(hose: Hose, name: str) -> float:
    """The value of one of PARAMETERS for a hose."""
    return hose.torsion_factor if name == "torsion_factor" else float(getattr(hose, name))


class WarmStartedModel:
    """Centrelines of one problem's hose at several twists, re-solved from the last equilibria."""

    def __init__(self, problem: Problem, twists_deg: list[float]):
        self.problem = problem
        self.twists = list(twists_deg)
        self.place_state: RodState | None = None
        self.twisted_states: list[RodState] = []
        self.warm_solves = 0
        self.cold_solves = 0

    def centerlines(self, hose: Hose) -> list[np.ndarray]:
        """Model centrelines (N+1, 3), one per twist, for `hose` (raises PlacementError if unsolvable)."""
        problem = replace(self.problem, hose=hose)
        if self.place_state is not None:
            lines = self._warm(problem)
            if lines is not None:
                self.warm_solves += 1
                return lines
        self.cold_solves += 1
        return self._cold(problem)

    def _cold(self, problem: Problem) -> list[np.ndarray]:
        """Full placements by continuation; their states start the next warm solve."""
        placed = solve(replace(problem, end_twist_deg=0.0))
        results = [placed if twist == 0.0 else solve(replace(problem, end_twist_deg=twist)) for twist in self.twists]
        self.place_state = RodState(placed.frames, placed.end_force, math.radians(placed.lock_angle_deg))
        self.twisted_states = [RodState(r.frames, r.end_force) for r in results]
        return [r.centerline for r in results]

    def _warm(self, problem: Problem) -> list[np.ndarray] | None:
        """Newton from the last states: the placed hose (end roll free), then each twist; None if any fails."""
        props = rod_properties(problem)
        path = PlacementPath(problem)
        placed_clamps = path.place(1.0)
        placed, report = solve_equilibrium(props, placed_clamps, self.place_state)
        if not (report.converged and report.unstable_directions == 0):
            return None
        locked = end_frame_of(placed_clamps, placed)
        states, lines = [], []
        for twist, previous in zip(self.twists, self.twisted_states):
            clamps = path.twisted(locked, twist)
            state, report = solve_equilibrium(props, clamps, previous)
            if not (report.converged and report.unstable_directions == 0):
                return None
            states.append(state)
            lines.append(node_positions(props, clamps, state))
        self.place_state, self.twisted_states = placed, states
        return lines


def identifiable_parameters(problem: Problem, fit: list[str]) -> tuple[list[str], list[str]]:
    """The parameters of `fit` that scans can determine, and notes on those that were dropped."""
    unknown = [name for name in fit if name not in PARAMETERS]
    if unknown:
        raise ValueError(f"cannot fit {', '.join(unknown)}: choose from {', '.join(PARAMETERS)}")
    kept, notes = list(dict.fromkeys(fit)), []
    weightless = problem.hose.mass_per_length == 0.0 or not np.any(problem.gravity)
    if weightless:
        for name in ("bending_stiffness", "mass_per_length"):
            if name in kept:
                kept.remove(name)
                notes.append(
                    f"{name} not fitted: without weight the shape depends on stiffness ratios only (EI scales out); "
                    "give mass_per_length > 0 and gravity to fit it, the torsion factor is a ratio and can be fitted"
                )
    elif "bending_stiffness" in kept and "mass_per_length" in kept:
        kept.remove("mass_per_length")
        notes.append("mass_per_length not fitted: with EI it shapes the hose only as their ratio (weight per EI); "
                     "fit one of them and give the other")
    return kept, notes


def calibrate(
    problem: Problem,
    cases: list[ScanCase],
    fit: list[str] = ("bending_stiffness", "torsion_factor"),
    *,
    max_evaluations: int = 60,
) -> Calibration:
    """Least-squares fit of `fit` (names from PARAMETERS) so the model matches the scans.

    problem: the hose and mounts, with the initial values (its twist is ignored: each case
    has its own).  cases: scans of the same hose in the same mounts at various twists.
    max_evaluations: evaluations allowed to the least-squares iterations (each solves every
    case); the finite-difference Jacobian costs one more evaluation per fitted parameter and
    is not counted here (scipy's max_nfev).
    """
    names, notes = identifiable_parameters(problem, list(fit))
    model = WarmStartedModel(problem, [case.twist_deg for case in cases])
    initial = {name: current_value(problem.hose, name) for name in names}

    def hose_at(x: np.ndarray) -> Hose:
        return hose_with(problem.hose, {name: initial[name] * math.exp(v) for name, v in zip(names, x)})

    before = [deviation(line, case.points) for line, case in zip(model.centerlines(problem.hose), cases)]
    if not names:
        return Calibration([], problem.hose, before, before, notes, 1, model.warm_solves, model.cold_solves)
    station_count = sum(case.points.shape[0] for case in cases)

    def residuals(x: np.ndarray) -> np.ndarray:
        try:
            lines = model.centerlines(hose_at(x))
        except PlacementError:
            return np.full(3 * station_count, 1e3)  # an unsolvable hose: a very poor fit
        return np.concatenate([(case.points - closest_on_polyline(case.points, line)[2]).ravel()
                               for line, case in zip(lines, cases)])

    solution = least_squares(residuals, np.zeros(len(names)), bounds=(-LOG_BOUND, LOG_BOUND), x_scale=1.0,
                             diff_step=1e-4, max_nfev=max_evaluations)
    # each residual vector is normal to the model centreline (closest point): two degrees of freedom per station
    relative_std = _relative_std(solution.jac, solution.fun, 2 * station_count)
    parameters = []
    for name, x, std in zip(names, solution.x, relative_std):
        value = initial[name] * math.exp(x)
        identified = bool(np.isfinite(std) and std <= UNIDENTIFIABLE_RELATIVE_STD)
        note = "" if identified else "not determined by these scans (relative uncertainty above 25 %)"
        if not identified:
            notes.append(f"{name}: {note}; the value is not a measurement")
        parameters.append(FittedParameter(name, PARAMETERS[name], initial[name], value,
                                          value * std if identified else None, identified, note))
    hose = hose_at(solution.x)
    after = [deviation(line, case.points) for line, case in zip(model.centerlines(hose), cases)]
    return Calibration(parameters, hose, before, after, notes, model.warm_solves + model.cold_solves,
                       model.warm_solves, model.cold_solves)


def _relative_std(jacobian: np.ndarray, residuals: np.ndarray, observations: int) -> np.ndarray:
    """Standard uncertainty of each log-parameter from s^2 (J^T J)^-1 (infinite where J is singular).

    observations: independent components among the residuals; s^2 = |r|^2 / (observations - parameters).
    """
    count = jacobian.shape[1]
    dof = max(observations - count, 1)
    variance = float(residuals @ residuals) / dof
    _, singular, vt = np.linalg.svd(jacobian, full_matrices=False)
    if singular[0] == 0.0:
        return np.full(count, np.inf)
    inverse = np.where(singular > 1e-8 * singular[0], 1.0 / np.maximum(singular, 1e-300) ** 2, np.inf)
    with np.errstate(invalid="ignore"):
        covariance_diagonal = np.array([np.sum(np.where(vt[:, j] ** 2 > 0, vt[:, j] ** 2 * inverse, 0.0))
                                        for j in range(count)])
    return np.sqrt(variance * covariance_diagonal)
