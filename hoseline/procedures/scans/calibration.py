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
note; after it, parameters whose relative uncertainty exceeds UNIDENTIFIABLE_RELATIVE_STD are
reported as not identified by the scans, and so are those a fixed parameter would move by more
than their uncertainty if freed, when it would remove most of the remaining misfit
(_fixed_parameter_effects).

Discretisation.  The N-segment model's own error (_model_error, from one evaluation with twice the
segments) moves the fit; the Gauss-Newton step that removes it is added to the fitted values, so they
are the exact hose's (the plain rod and a set, whose order 2 the correction assumes: _order_two).  Uncertainty.  Two parts in quadrature: the scatter, s^2 (J^T J)^-1 of the
corrected fit's residuals times their variance inflation along the hose (scatter_inflation: n
stations carry the information of n / inflation independent ones), and (RICHARDSON_SEGMENTS / N)^2 of
the discretisation correction (where it is not made, the whole step).  Failures (a parameter at its bound, limits
missed, a flipped twist sign, a confounding fixed parameter) go to Calibration.warnings.
The braid (braid_stiffness = n EA_s, N, the strand count kept; braid_slack = eps0) is fitted from
the problem's [hose.braid] (it cannot start from no braid or no slack: both are scaled).  On the
thesis hose its torsional part and the torsion factor move the hose alike: fitted together, the
braid is reported as not identified (tests/test_braid_calibration.py).
Units: mm, N*mm^2, kg/m, N.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import least_squares

from hoseline.mechanics.newton import end_frame_of, node_positions, solve_equilibrium
from hoseline.mechanics.rod import RodState
from hoseline.model.braid import Braid
from hoseline.model.hose import DEFAULT_POISSON_RATIO, Hose, isotropic_torsional_stiffness
from hoseline.model.preset import Preset
from hoseline.model.problem import Problem
from hoseline.procedures.placement.continuation import PlacementError
from hoseline.procedures.scans.deviation import Deviation, Thresholds, closest_on_polyline, deviation
from hoseline.procedures.placement.path import PlacementPath
from hoseline.procedures.placement.sequence import rod_properties, solve
from hoseline.procedures.scans.parameters import BRAID_PARAMETERS, PARAMETERS

UNIDENTIFIABLE_RELATIVE_STD = 0.25
UNIDENTIFIABLE_ANGLE_STD_DEG = 15.0  # a preset angle less certain than this is not identified
PRESET_BOUND = 4.0 * math.pi  # the preset's x (rad): the set's turn over the hose's length (two coils), or its angle
LOG_BOUND = math.log(100.0)  # no parameter moves by more than 100x
# What stays uncertain of the discretisation correction, as a fraction of it: (RICHARDSON_SEGMENTS / N)^2 at N
# segments.  Measured on noise-free stations of a 384- and 768-segment hose: 0.35, 0.045, 0.011 at 24, 48, 96
# segments (the correction's higher orders fall faster than h^2); (15 / N)^2 is 0.39, 0.098, 0.024 (docs/validation.md).
RICHARDSON_SEGMENTS = 15.0
PRESET_ANGLE_STARTS = (0.0, 90.0, 180.0, 270.0)  # deg from the initial angle: the starts of a fit of the set's angle
AT_BOUND_LOG = 0.05  # a parameter within 5 % of its bound is reported as at the bound: the fit failed
FLIPPED_BETTER = 0.25  # the fit with the twists negated is "much better" below this fraction of the cost
FIXED_EXPLAINS = 0.5  # a fixed parameter that would remove this fraction of the misfit confounds the fit
PROBE_STEP = 1e-3  # relative step of a fixed parameter for its sensitivity
PROBE_SAG = 0.01  # weight per length probed on a weightless hose: w L^3 / EI


@dataclass(frozen=True)
class ScanCase:
    """One scan of the hose: the twist of the end fitting (degrees) and its centreline stations (n, 3), mm."""

    twist_deg: float
    points: np.ndarray


@dataclass
class FittedParameter:
    """A calibrated parameter: initial and fitted value, standard uncertainty (None if not identified).

    std = hypot(std_scatter, std_discretisation), in the parameter's unit: the scans' scatter
    (stations correlated along the hose counted) and what stays uncertain of the discretisation
    correction ((RICHARDSON_SEGMENTS / N)^2 of it at N segments; the whole step where it is not made).
    discretisation_correction: what the value was moved by for the N-segment model's own error (4/3 of the change
    a model of twice the segments makes), so that it is the exact hose's; 0 where not made (_order_two).  note: why it is not identified.
    """

    name: str
    unit: str
    initial: float
    value: float
    std: float | None
    identifiable: bool
    note: str = ""
    std_scatter: float | None = None
    std_discretisation: float | None = None
    discretisation_correction: float | None = None


@dataclass
class Calibration:
    """What calibrate returns.

    parameters: the fitted parameters.  hose: the calibrated hose.
    before, after: one Deviation per scan case, with the initial and the calibrated hose.
    notes: parameters refused or not identified, and why.
    evaluations: model evaluations; warm_solves / cold_solves: how they were solved.
    warnings: how the fit failed (a parameter at its bound, the calibrated model outside the
        limits, a flipped twist sign, a fixed parameter that confounds the fitted ones).
    scatter_inflation: the variance inflation from residuals correlated along the hose.
    poisson_ratio: nu of the torsion factor's definition, GJ / (EI / (1 + nu)).
    """

    parameters: list[FittedParameter]
    hose: Hose
    before: list[Deviation]
    after: list[Deviation]
    notes: list[str] = field(default_factory=list)
    evaluations: int = 0
    warm_solves: int = 0
    cold_solves: int = 0
    warnings: list[str] = field(default_factory=list)
    scatter_inflation: float = 1.0
    poisson_ratio: float = DEFAULT_POISSON_RATIO


def hose_with(base: Hose, values: dict[str, float], poisson_ratio: float = DEFAULT_POISSON_RATIO) -> Hose:
    """`base` with some of PARAMETERS changed; GJ follows EI at the given (or base) torsion factor.

    poisson_ratio: nu of the torsion factor's definition, GJ / (EI / (1 + nu)) (the problem file's).
    """
    bending = values.get("bending_stiffness", base.bending_stiffness)
    factor = values.get("torsion_factor", current_value(base, "torsion_factor", poisson_ratio))
    second = None if base.bending_stiffness_2 is None else base.bending_stiffness_2 * bending / base.bending_stiffness
    return replace(
        base,
        bending_stiffness=bending,
        bending_stiffness_2=second,
        torsional_stiffness=factor * isotropic_torsional_stiffness(bending, poisson_ratio),
        mass_per_length=values.get("mass_per_length", base.mass_per_length),
        length=values.get("length", base.length),
        preset=_preset_with(base, values),
        braid=_braid_with(base, values),
    )


def _braid_with(base: Hose, values: dict[str, float]) -> Braid | None:
    """The base hose's braid with braid_stiffness (n EA_s, N; the strand count kept) and braid_slack (eps0)."""
    if base.braid is None:
        return None
    stiffness = values.get("braid_stiffness", base.braid.stiffness)
    return replace(base.braid, strand_axial_stiffness=stiffness / base.braid.strands,
                   slack_strain=values.get("braid_slack", base.braid.slack_strain))


def _preset_with(base: Hose, values: dict[str, float]) -> Preset | None:
    """The base hose's preset with preset_curvature (1/mm; a negative one turns the set round), preset_angle (deg)."""
    if "preset_curvature" not in values and "preset_angle" not in values:
        return base.preset
    curvature = values.get("preset_curvature", current_value(base, "preset_curvature"))
    angle = values.get("preset_angle", current_value(base, "preset_angle"))
    return Preset(abs(curvature), math.remainder(angle + (180.0 if curvature < 0.0 else 0.0), 360.0))


def current_value(hose: Hose, name: str, poisson_ratio: float = DEFAULT_POISSON_RATIO) -> float:
    """The value of one of PARAMETERS for a hose; the torsion factor is GJ / (EI / (1 + poisson_ratio))."""
    if name == "torsion_factor":
        return hose.torsional_stiffness / isotropic_torsional_stiffness(hose.bending_stiffness, poisson_ratio)
    if name in ("preset_curvature", "preset_angle"):
        preset = hose.preset or Preset(0.0)
        return preset.curvature if name == "preset_curvature" else preset.angle_deg
    if name in BRAID_PARAMETERS:  # 0 without a braid
        braid = hose.braid
        return 0.0 if braid is None else braid.stiffness if name == "braid_stiffness" else braid.slack_strain
    return float(getattr(hose, name))


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
        placed = solve(replace(problem, end_twist_deg=0.0), estimate_error=False)
        results = [placed if twist == 0.0 else solve(replace(problem, end_twist_deg=twist), estimate_error=False)
                   for twist in self.twists]
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
    braid = problem.hose.braid
    for name in (name for name in kept if name in BRAID_PARAMETERS):
        if braid is None or current_value(problem.hose, name) == 0.0:
            what = "[hose.braid]" if braid is None else "hose.braid.slack_strain > 0"
            raise ValueError(f"cannot fit {name}: give {what} in the problem file to start from (the fit scales the "
                             "initial value: it cannot start from zero)")
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
    poisson_ratio: float = DEFAULT_POISSON_RATIO,
    thresholds: list[Thresholds] | None = None,
) -> Calibration:
    """Least-squares fit of `fit` (names from PARAMETERS) so the model matches the scans.

    problem: the hose and mounts, with the initial values (its twist is ignored: each case
    has its own).  cases: scans of the same hose in the same mounts at various twists.
    max_evaluations: evaluations allowed to the least-squares iterations (each solves every
    case); the finite-difference Jacobian costs one more evaluation per fitted parameter and
    is not counted here (scipy's max_nfev).  poisson_ratio: nu in the torsion factor's
    definition, GJ / (EI / (1 + nu)) (the problem file's hose.poisson_ratio).  thresholds:
    the deviation limits per case (default: the thesis', Thresholds.thesis of its twist); a
    fit that leaves a case above them is warned about.

    Failures are said in Calibration.warnings: a parameter at its bound, a calibrated model
    still outside the limits (then the fit is tried again with every twist negated, and a
    much better fit there is reported as a flipped twist sign, not used), and a fixed
    parameter that explains the remaining misfit better than the fitted ones.
    """
    names, notes = identifiable_parameters(problem, list(fit))
    limits = thresholds if thresholds is not None else [Thresholds.thesis(case.twist_deg) for case in cases]
    if len(limits) != len(cases):
        raise ValueError(f"thresholds: {len(limits)} given for {len(cases)} scans; give one per scan")
    fitter = _Fitter(problem, cases, names, poisson_ratio)
    before = fitter.deviations(problem.hose)
    if not names:
        return Calibration([], problem.hose, before, before, notes, *fitter.solve_counts(), poisson_ratio=poisson_ratio)
    solution = fitter.fit(max_evaluations)
    fitter.deviations(fitter.hose_at(solution.x))  # the model's equilibria at the fit start the finer one
    model_error = _model_error(fitter, solution)
    # the N-segment model's discretisation moves the fit by a known amount: removed, not added as an uncertainty
    step = _discretisation_step(solution, model_error)
    corrects = _order_two(problem, names) and not any(fitter.at_bound(name, x) for name, x in zip(names, solution.x))
    correction = step if corrects else np.zeros_like(step)
    corrected = solution.x + correction
    hose = fitter.hose_at(corrected)
    after = fitter.deviations(hose)
    remaining = solution.fun + model_error + solution.jac @ correction  # the exact model's residuals, corrected fit
    # each residual vector is normal to the model centreline (closest point): two degrees of freedom per station
    inflation = scatter_inflation([row.reshape(-1, 3) for row in fitter.split(remaining)])
    scatter_std = math.sqrt(inflation) * _relative_std(solution.jac, remaining, 2 * fitter.station_count)
    discretisation_std = (min(1.0, (RICHARDSON_SEGMENTS / problem.hose.segments) ** 2) if corrects else 1.0) * np.abs(step)
    total_std = np.hypot(scatter_std, discretisation_std)
    warnings, confounded = [], {}
    for effect in _fixed_parameter_effects(fitter, solution, total_std, model_error):
        confounded.update({name: effect for name in effect.moves})
        warnings.append(effect.message(fitter, solution.x))
    parameters = []
    for name, x, x_fit, std, scatter, floor in zip(names, corrected, solution.x, total_std, scatter_std,
                                                   discretisation_std):
        value, std, scatter, floor = fitter.value(name, x), *(fitter.std(name, x, v) for v in (std, scatter, floor))
        moved = value - fitter.value(name, x_fit)
        if name in ("preset_curvature", "preset_angle"):  # as the hose holds them: a negative curvature turns the set
            value = current_value(hose, name)
        at_bound = fitter.at_bound(name, x)
        if at_bound:
            note = f"at its bound ({value:.4g}, 100x from the initial {fitter.initial[name]:.4g}): the fit failed"
            warnings.append(f"{name} ran to its bound, {value:.4g} (100x from the initial {fitter.initial[name]:.4g}): "
                            "the fit failed and the value is not a measurement")
        elif name in confounded:
            note = f"confounded with {confounded[name].name}, which the fit held fixed"
        elif not fitter.determined(name, value, std):
            note = ("not determined by these scans (uncertainty above "
                    f"{f'{UNIDENTIFIABLE_ANGLE_STD_DEG:g} deg' if name == 'preset_angle' else '25 %'})")
            notes.append(f"{name}: {note}; the value is not a measurement")
        else:
            note = ""
        identified = not note
        parameters.append(FittedParameter(name, PARAMETERS[name], fitter.initial[name], value,
                                          std if identified else None, identified, note,
                                          *(v if np.isfinite(v) else None for v in (scatter, floor)), moved))
    parameters = _angle_of_an_undetermined_set(parameters, notes)
    missed = [(case, d, limit) for case, d, limit in zip(cases, after, limits) if not d.passes(limit)]
    for case, d, limit in missed:
        warnings.append(f"after the fit the scan at {case.twist_deg + 0.0:g} deg still deviates by {d.mean:.3g} mm on "
                        f"average (largest {d.max:.3g} mm), above its limit of {_limit_text(limit)}: the calibrated "
                        "model does not describe this scan")
    at_bound = any(fitter.at_bound(name, x) for name, x in zip(names, solution.x))
    if (missed or at_bound) and any(c.twist_deg for c in cases):
        warnings += _flipped_twist_warning(fitter, solution, max_evaluations)
    return Calibration(parameters, hose, before, after, notes, *fitter.solve_counts(), warnings=warnings,
                       scatter_inflation=inflation, poisson_ratio=poisson_ratio)


def _angle_of_an_undetermined_set(parameters: list[FittedParameter], notes: list[str]) -> list[FittedParameter]:
    """The parameters with the preset's angle not identified where its curvature was fitted and is not: the side a
    set bends towards is no measurement when the set itself is not (its uncertainty says only how the scans' noise
    turns a curvature near zero).  Adds the reason to notes."""
    fitted = {parameter.name: parameter for parameter in parameters}
    curvature, angle = fitted.get("preset_curvature"), fitted.get("preset_angle")
    if curvature is None or angle is None or curvature.identifiable or not angle.identifiable:
        return parameters
    note = "not determined: it is the direction of the set, whose curvature these scans do not determine"
    notes.append(f"preset_angle: {note}; the value is not a measurement")
    return [replace(parameter, std=None, identifiable=False, note=note) if parameter is angle else parameter
            for parameter in parameters]


class _Fitter:
    """The residuals of the scans against the model, as a function of the log-parameters x.

    A parameter's value is its initial value times exp(x), except the preset's (value): there
    x is the change of the angle the set turns the hose through over its length (rad) or of the
    set's angle (rad).  Residuals are the vectors from each scan station to the closest point
    of the model centreline at the scan's twist, mm.
    """

    def __init__(self, problem: Problem, cases: list[ScanCase], names: list[str], poisson_ratio: float):
        self.problem, self.cases, self.names, self.poisson_ratio = problem, cases, names, poisson_ratio
        self.initial = {name: current_value(problem.hose, name, poisson_ratio) for name in names}
        self.model = WarmStartedModel(problem, [case.twist_deg for case in cases])
        self.station_count = sum(case.points.shape[0] for case in cases)

    def hose_at(self, x: np.ndarray, fixed: dict[str, float] | None = None) -> Hose:
        """The hose at log-parameters x, with some fixed parameters changed too (values in their units)."""
        values = {name: self.value(name, v) for name, v in zip(self.names, x)}
        return hose_with(self.problem.hose, values | (fixed or {}), self.poisson_ratio)

    def _step(self, name: str) -> float:
        # the preset's unit per unit of x (class doc): 1/mm per radian turned over the length, or degrees per radian
        return 1.0 / self.problem.hose.length if name == "preset_curvature" else math.degrees(1.0)

    def value(self, name: str, x: float) -> float:
        """The value of parameter `name` at its x, in its unit (PARAMETERS)."""
        if name in ("preset_curvature", "preset_angle"):
            return self.initial[name] + x * self._step(name)
        return self.initial[name] * math.exp(x)

    def std(self, name: str, x: float, std_x: float) -> float:
        """A standard uncertainty of x in the parameter's unit."""
        return std_x * (self._step(name) if name in ("preset_curvature", "preset_angle") else self.value(name, x))

    def determined(self, name: str, value: float, std: float) -> bool:
        """Whether the scans determine the parameter: within UNIDENTIFIABLE_RELATIVE_STD (the angle: _ANGLE_STD_DEG)."""
        if name == "preset_angle":
            return bool(np.isfinite(std) and std <= UNIDENTIFIABLE_ANGLE_STD_DEG)
        return bool(np.isfinite(std) and std <= UNIDENTIFIABLE_RELATIVE_STD * abs(value))

    def at_bound(self, name: str, x: float) -> bool:
        """Whether x ran to its bound (the fit failed)."""
        bound = PRESET_BOUND if name in ("preset_curvature", "preset_angle") else LOG_BOUND
        return bound - abs(x) < AT_BOUND_LOG

    def residuals(self, hose: Hose, model: WarmStartedModel | None = None) -> np.ndarray:
        """(3 stations,) residual vector components of every case, mm (1e3 for a hose the solver cannot place)."""
        try:
            lines = (model or self.model).centerlines(hose)
        except PlacementError:
            return np.full(3 * self.station_count, 1e3)  # an unsolvable hose: a very poor fit
        return np.concatenate([(case.points - closest_on_polyline(case.points, line)[2]).ravel()
                               for line, case in zip(lines, self.cases)])

    def split(self, vector: np.ndarray) -> list[np.ndarray]:
        """A residual vector cut into its cases."""
        return np.split(vector, np.cumsum([3 * case.points.shape[0] for case in self.cases])[:-1])

    def fit(self, max_evaluations: int):
        """scipy's least_squares result from x = 0 (the initial values), the best of PRESET_ANGLE_STARTS when the
        preset's angle is fitted: started on the wrong side of the hose, the set's fit can end in a local minimum
        (a set of R 500 mm towards 40 deg, started towards 220 deg: 43 mm of mean deviation left, against 0.15 mm
        from the other starts)."""
        bound = np.array([PRESET_BOUND if name in ("preset_curvature", "preset_angle") else LOG_BOUND
                          for name in self.names])
        starts = [np.zeros(len(self.names))]
        if "preset_angle" in self.names:
            for turn in PRESET_ANGLE_STARTS[1:]:
                start = np.zeros(len(self.names))
                start[self.names.index("preset_angle")] = math.radians(turn)
                starts.append(start)
        # diff_step is relative to |x| (1 at 0): the preset's x are radians, the others log-values
        fits = [least_squares(lambda x: self.residuals(self.hose_at(x)), start, bounds=(-bound, bound), x_scale=1.0,
                              diff_step=1e-4, max_nfev=max_evaluations) for start in starts]
        return min(fits, key=lambda solution: solution.cost)

    def deviations(self, hose: Hose) -> list[Deviation]:
        """Deviation of each case from the model of `hose`."""
        return [deviation(line, case.points) for line, case in zip(self.model.centerlines(hose), self.cases)]

    def solve_counts(self) -> tuple[int, int, int]:
        """(evaluations, warm solves, cold solves) of the model so far."""
        return self.model.warm_solves + self.model.cold_solves, self.model.warm_solves, self.model.cold_solves


def scatter_inflation(residuals: list[np.ndarray]) -> float:
    """Variance inflation 1 + 2 sum_k rho_k from the correlation of residuals along the hose.

    residuals: per scan, (n, 3) residual vectors of its stations in order along the hose, mm.
    Neighbouring stations of a fitted scan centreline share scan points (sections two diameters
    long, one radius apart), so their errors are correlated and n stations carry the
    information of n / inflation independent ones.  rho_k is the lag-k autocorrelation of the
    residual vectors pooled over the scans, summed while positive (the initial positive
    sequence); an unwanted smooth misfit (model error) also correlates, and inflates too.
    """
    total = sum(float(np.sum(r * r)) for r in residuals)
    if total == 0.0:
        return 1.0
    inflation = 1.0
    for lag in range(1, max(r.shape[0] for r in residuals) // 2):
        rho = sum(float(np.sum(r[lag:] * r[:-lag])) for r in residuals if r.shape[0] > lag) / total
        if rho <= 0.0:
            break
        inflation += 2.0 * rho
    return inflation


def _model_error(fitter: _Fitter, solution) -> np.ndarray:
    """The N-segment model's own error in the residuals at the fit, estimated as 4/3 of their change
    with a model of twice the segments (the model converges at order 2, so the N-segment one is off
    by 4/3 of its distance to the 2N one), mm.  Call it right after an evaluation at the fit: the
    model's last equilibria start the finer one."""
    fine_problem = replace(fitter.problem, hose=replace(fitter.problem.hose, segments=2 * fitter.problem.hose.segments))
    fine_model = WarmStartedModel(fine_problem, [case.twist_deg for case in fitter.cases])
    if fitter.model.place_state is not None:  # Newton from the fit's equilibria, each segment cut in two halves
        fine_model.place_state = replace(fitter.model.place_state,
                                         frames=np.repeat(fitter.model.place_state.frames, 2, axis=0))
        fine_model.twisted_states = [replace(state, frames=np.repeat(state.frames, 2, axis=0))
                                     for state in fitter.model.twisted_states]
    fine = fitter.residuals(replace(fitter.hose_at(solution.x), segments=fine_problem.hose.segments), fine_model)
    return 4.0 / 3.0 * (fine - solution.fun)


def _order_two(problem: Problem, names: list[str]) -> bool:
    """Whether the model's shape converges at order 2 in the segment length, as the discretisation correction
    assumes: the plain rod (observed orders 1.98-2.01, docs/model.md) and a set (2.05-2.10 since its stress-free
    rotation is split evenly over each joint, tests/test_preset.py).  The springs' and the braid's order is not
    measured: their fits are not corrected, and the whole step is their uncertainty, as before.  names: the
    fitted parameters (the braid's imply a braid)."""
    hose = problem.hose
    return hose.stiffeners is None and hose.braid is None and not any(name.startswith("braid_") for name in names)


def _discretisation_step(solution, model_error: np.ndarray) -> np.ndarray:
    """The change of each parameter's x that the N-segment model's discretisation costs the fit: the Gauss-Newton
    step that removing the model error (mm) from the residuals takes from it.  Added to the fit, it gives the
    parameters the exact (continuum) hose would be fitted with; (RICHARDSON_SEGMENTS / N)^2 of it stays uncertain."""
    step, *_ = np.linalg.lstsq(solution.jac, -model_error, rcond=1e-8)
    return step


@dataclass
class _FixedEffect:
    """What freeing one fixed parameter would do, to first order, from the fit.

    name: the fixed parameter; value: its value, change: its predicted change, in its unit.
    explained: the fraction of the remaining squared residual it would remove.  shifts: the
    change of each fitted parameter's x.  moves: the fitted parameters it moves by more than
    their uncertainty.
    """

    name: str
    value: float
    change: float
    explained: float
    shifts: np.ndarray
    moves: list[str]

    def message(self, fitter: _Fitter, x: np.ndarray) -> str:
        """The warning: which fitted parameters are not identified, and what the scans look like."""
        more, less = _LOOKS.get(self.name, (f"to have a larger {self.name}", f"to have a smaller {self.name}"))
        moved = ", ".join(f"{name} from {fitter.value(name, v):.4g} to about {fitter.value(name, v + shift):.4g}"
                          for name, v, shift in zip(fitter.names, x, self.shifts) if name in self.moves)
        return (f"{' and '.join(self.moves)} not identified: the scans look {more if self.change > 0 else less} than "
                f"the problem file says ({self.name} = {self.value:.4g}): freeing {self.name} (to about "
                f"{self.value + self.change:.3g}) would explain {self.explained:.0%} of the remaining misfit and move "
                f"{moved}; correct {self.name} in the problem file, or fit it too")


_LOOKS = {"mass_per_length": ("heavier", "lighter"), "length": ("longer", "shorter"),
          "bending_stiffness": ("stiffer in bending", "softer in bending"),
          "torsion_factor": ("stiffer in torsion", "softer in torsion"),
          "braid_stiffness": ("to have a stiffer braid", "to have a softer braid"),
          "braid_slack": ("to have a slacker braid", "to have a tighter braid")}


def _fixed_parameter_effects(fitter: _Fitter, solution, total_std: np.ndarray,
                             model_error: np.ndarray) -> list[_FixedEffect]:
    """The fixed parameters that would explain much of the remaining misfit and move a fitted one.

    For each parameter of PARAMETERS not fitted (and not scaled out by a weightless hose), one
    more model evaluation gives the residual's sensitivity to it; its part orthogonal to the
    fitted parameters' sensitivities predicts, to first order, what freeing it would gain
    (the fraction of the squared residual it removes) and how far the fitted ones would move.
    Reported when it would remove more than FIXED_EXPLAINS of the misfit, more misfit than the
    model's own discretisation error (`model_error`, mm, outside what the fitted parameters
    absorb) amounts to, and move a fitted parameter by more than its uncertainty.
    """
    problem, hose = fitter.problem, fitter.hose_at(solution.x)
    gravity = float(np.linalg.norm(problem.gravity))
    weightless = hose.mass_per_length == 0.0 or gravity == 0.0
    residual, jacobian = solution.fun, solution.jac
    absorbed, *_ = np.linalg.lstsq(jacobian, model_error, rcond=1e-8)
    unexplained_model_error = float(np.sum((model_error - jacobian @ absorbed) ** 2))
    effects = []
    for name in PARAMETERS:
        if name in fitter.names or (name == "bending_stiffness" and weightless):
            continue
        value = current_value(hose, name, fitter.poisson_ratio)
        if value != 0.0:
            step = PROBE_STEP * value
        elif name == "mass_per_length" and gravity > 0.0:
            # no weight yet: w L^3 / EI = PROBE_SAG moves the hose by hundredths of a mm, within the linear range
            step = PROBE_SAG * hose.bending_stiffness / (hose.length**3 * gravity * 1e-3)
        else:
            continue
        try:
            column = (fitter.residuals(fitter.hose_at(solution.x, {name: value + step})) - residual) / step
        except ValueError:  # a value the problem refuses, e.g. a length that moves clips off their stations
            continue
        along, *_ = np.linalg.lstsq(jacobian, column, rcond=1e-8)
        orthogonal = column - jacobian @ along
        norm2 = float(orthogonal @ orthogonal)
        if norm2 <= (1e-6 * float(column @ column)) or not residual.any():
            continue  # moves the model as the fitted parameters do: nothing to tell apart
        change = -float(orthogonal @ residual) / norm2
        removed = float(orthogonal @ residual) ** 2 / norm2
        explained = removed / float(residual @ residual)
        shifts = -along * change
        moves = [fitted for fitted, shift, std in zip(fitter.names, shifts, total_std) if abs(shift) > std]
        if explained > FIXED_EXPLAINS and removed > unexplained_model_error and moves:
            effects.append(_FixedEffect(name, value, change, explained, shifts, moves))
    return effects


def _flipped_twist_warning(fitter: _Fitter, solution, max_evaluations: int) -> list[str]:
    """The fit again with every twist negated: a warning if it is much better (the fit is not replaced)."""
    cases = [ScanCase(-case.twist_deg, case.points) for case in fitter.cases]
    flipped = _Fitter(fitter.problem, cases, fitter.names, fitter.poisson_ratio)
    other = flipped.fit(max_evaluations)
    if not other.cost < FLIPPED_BETTER * solution.cost:
        return []
    means = [d.mean for d in flipped.deviations(flipped.hose_at(other.x))]
    first = [d.mean for d in fitter.deviations(fitter.hose_at(solution.x))]
    values = ", ".join(f"{name} {fitter.value(name, x):.4g}" for name, x in zip(fitter.names, other.x))
    twists = ", ".join(f"{case.twist_deg + 0.0:g}" for case in cases)  # + 0.0: no "-0"
    return [f"the twists' sign looks flipped: with the twists negated the fit ends at mean deviations "
            f"{', '.join(f'{m:.3g}' for m in means)} mm instead of {', '.join(f'{m:.3g}' for m in first)} mm "
            f"({values}); check the sign convention (degrees about the end fitting's direction, right-handed) "
            f"and use twist = {twists}"]


def _limit_text(limit: Thresholds) -> str:
    """'1 mm mean' or '1 mm mean, 3 mm largest'."""
    return f"{limit.mean:g} mm mean" + ("" if limit.max is None else f", {limit.max:g} mm largest")


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
