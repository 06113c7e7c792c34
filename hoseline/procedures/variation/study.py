"""A variation study: what is varied, how it is sampled, what is judged; and the outcome read off its samples.

The study's samples are rows of deviations (tolerances.COORDINATES) drawn from the design
once (designs.unit_design), so the outcome depends on the study alone, not on where or in how
many pieces it ran.  summarize() turns the merged samples into spreads, probabilities with
confidence intervals, envelopes and the worst samples, and sets the first-order estimates from
the sensitivities beside the Monte Carlo ones.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hoseline.model.problem import Problem
from hoseline.procedures.variation.designs import balanced, round_design
from hoseline.procedures.variation.design_search import DesignGrid, DesignOutcome
from hoseline.procedures.variation.engine import default_batch_size
from hoseline.procedures.variation.quantities import Limit, Quantity, natural_scale
from hoseline.procedures.variation.global_sensitivity import SobolIndices, saltelli_design
from hoseline.procedures.variation.precision import Precision, PrecisionOutcome
from hoseline.procedures.variation.rare import RareEvent, RareUnion, Reliability
from hoseline.procedures.variation.samples import StudyBase, failure_cause
from hoseline.procedures.variation.sensitivity import Sensitivities
from hoseline.procedures.variation.statistics import (
    PERCENTILES,
    Agreement,
    Probability,
    Spread,
    agreement,
    probability,
    spread,
    station_envelope,
    worst_sample,
)
from hoseline.procedures.variation.tolerances import Variation, perturbed
from hoseline.procedures.variation.worst_case import WorstCase


STARTS = ("straight", "nominal")
OTHER_BRANCH = 1e-4  # of the length: a warm-started sample this far from the published sequence's is on another branch


@dataclass(frozen=True)
class Sampling:
    """How the tolerances are sampled: method (designs.METHODS), count, seed, batch (samples per task; None:
    default), start: "straight" (every placement sample by the published sequence from the straight hose) or
    "nominal" (by Newton from the nominal hose's equilibria, checked on a subset: samples.py).
    precision: sample in rounds until a statistic is known this well (precision.py; count is then the first
    round's); rounds: the samples of each round drawn (run.py sets it and count to their sum; () : one round)."""

    method: str = "sobol"
    count: int = 256
    seed: int = 0
    batch: int | None = None
    start: str = "straight"
    precision: Precision | None = None
    rounds: tuple[int, ...] = ()

    def batch_size(self) -> int:
        """Samples per task."""
        return self.round_batch(self.count)

    def round_batch(self, samples: int) -> int:
        """Samples per task of a round of `samples` (each round of sampling to a precision is a stage of its own)."""
        return self.batch or default_batch_size(samples)


@dataclass(frozen=True)
class GlobalSensitivity:
    """What [sobol] asks: samples, the N base rows of the Saltelli design (N (tolerances + 2) hoses), and its seed."""

    samples: int = 256
    seed: int = 0


@dataclass(frozen=True)
class Study:
    """A study: name, the base (placement or sweep), the tolerances, the sampling, the limits,
    whether to compute the sensitivities, and an optional design search; reliability: FORM of the limits;
    global_sensitivity: Sobol' indices; worst_case: the worst-case corners (they need the sensitivities)."""

    name: str
    base: StudyBase
    variation: Variation
    sampling: Sampling
    limits: tuple[Limit, ...]
    sensitivities: bool = True
    design: DesignGrid | None = None
    reliability: Reliability | None = None
    global_sensitivity: GlobalSensitivity | None = None
    worst_case: bool = False

    @property
    def quantities(self) -> tuple[Quantity, ...]:
        """The judged quantities, in the order the samples store them."""
        return self.base.quantities

    def reliability_limits(self) -> tuple[Limit, ...]:
        """The limits whose rare failure [reliability] asks for (none without it): those it names, else every limit
        but the deviation's (no derivative)."""
        if self.reliability is None:
            return ()
        names = self.reliability.limits
        return tuple(limit for limit in self.limits if (limit.quantity.name in names if names
                                                        else limit.quantity.name != "deviation"))

    def coordinates(self) -> np.ndarray:
        """(count, width) the deviations of every sample (empty without tolerances)."""
        if not self.variation.tolerances or self.sampling.count == 0:
            return np.zeros((0, self.variation.width))
        sampling = self.sampling
        unit = round_design(sampling.method, sampling.rounds or (sampling.count,), self.variation.dimensions, sampling.seed)
        return self.variation.coordinates(unit)

    def sobol_coordinates(self) -> np.ndarray:
        """(N (tolerances + 2), width) the deviations of the Saltelli design of [sobol] (global_sensitivity.py)."""
        settings = self.global_sensitivity
        groups = tuple(t.dimensions for t in self.variation.tolerances)
        return self.variation.coordinates(saltelli_design(groups, settings.samples, settings.seed))

    def sample_problem(self, index: int) -> Problem:
        """The problem of sample `index` (to reproduce it)."""
        return perturbed(self.base.problem, self.coordinates()[index])


@dataclass
class FirstOrder:
    """First-order estimates beside Monte Carlo: per smooth quantity its mean and variance from the
    sensitivities and the agreement with the samples; the same for the shape as a whole (the mean over
    stations of the squared distance from the mean shape, mm^2); per station the RMS spread both ways (mm)."""

    names: tuple[str, ...]
    mean: np.ndarray
    variance: np.ndarray
    agreements: list[Agreement]
    shape: Agreement
    station_spread: np.ndarray
    station_spread_samples: np.ndarray
    contributions: np.ndarray  # (quantities, tolerances) standard deviations each tolerance alone gives
    derivatives: np.ndarray  # (quantities, 15) per unit of each coordinate (Sensitivities.derivatives)
    station_derivatives: np.ndarray  # (N+1, 3, 15) mm per unit of each coordinate (Sensitivities.station_derivatives)


@dataclass(frozen=True)
class FailureCause:
    """Failed samples with one cause: cause (the reason with its numbers as "#", samples.failure_cause), count,
    samples (their indexes, ascending), example (the first one's whole reason)."""

    cause: str
    count: int
    samples: tuple[int, ...]
    example: str


def failure_causes(reasons: np.ndarray, failed: np.ndarray) -> list[FailureCause]:
    """The failed samples grouped by cause, the most frequent first (ties: the first sample first).

    reasons: (n,) text per sample; failed: (n,) bool.
    """
    groups: dict[str, list[int]] = {}
    for index in np.flatnonzero(failed):
        groups.setdefault(failure_cause(str(reasons[index])), []).append(int(index))
    causes = [FailureCause(cause, len(indexes), tuple(indexes), str(reasons[indexes[0]]))
              for cause, indexes in groups.items()]
    return sorted(causes, key=lambda c: (-c.count, c.samples[0]))


@dataclass
class StudyOutcome:
    """Everything a study found.

    samples: the merged batch arrays (samples.evaluate_batch), rows in sample order; coordinates:
    (n, width) their deviations (tolerances.Variation.width).  nominal: (q,) the nominal hose's quantities; nominal_centerlines
    (M, N+1, 3).  spreads: one per quantity.  probabilities, worst: per limit (worst: sample index).
    envelopes: per kept pose (base.shape_poses()) the station envelope (statistics.station_envelope).
    deviation: per station P5/P50/P95 (3, N+1) and the maximum (N+1,) of the distance from nominal, mm.
    clearance: per obstacle and pose, P5/P50/P95 (O, 3, M) and minimum (O, M), mm.
    failures: the failed samples grouped by cause (FailureCause, most frequent first).  first_order: None without sensitivities.  design: None without search.
    rare_events: per limit of [reliability], FORM/SORM and the importance-sampling check (rare.RareEvent);
    rare_union: the probability of breaking any of them (two or more with a design point; else None).
    sobol: Sobol' indices of every quantity (quantities order) per tolerance, None without [sobol].
    worst_cases: per smooth quantity its worst-case corner, first-order and solved (worst_case.WorstCase).
    precision: how sampling to a precision ended (None without [sampling.precision]).
    notes: what a reader must know (unbalanced design, disagreement, failures).  run: figures of the run.
    """

    study: Study
    samples: dict[str, np.ndarray]
    coordinates: np.ndarray
    nominal: np.ndarray
    nominal_centerlines: np.ndarray
    spreads: list[Spread]
    probabilities: list[Probability]
    worst: list[int | None]
    envelopes: list[dict[str, np.ndarray]]
    deviation: dict[str, np.ndarray]
    clearance: dict[str, np.ndarray]
    failures: list[FailureCause]
    first_order: FirstOrder | None = None
    design: DesignOutcome | None = None
    rare_events: list[RareEvent] = field(default_factory=list)
    rare_union: RareUnion | None = None
    sobol: SobolIndices | None = None
    worst_cases: list[WorstCase] = field(default_factory=list)
    precision: PrecisionOutcome | None = None
    notes: list[str] = field(default_factory=list)
    run: dict = field(default_factory=dict)

    @property
    def count(self) -> int:
        """Samples in the study."""
        return int(self.coordinates.shape[0])


def merge_batches(batches: dict[int, dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """The batches' arrays stacked in batch order (so rows are in sample order)."""
    order = sorted(batches)
    return {key: np.concatenate([batches[k][key] for k in order]) for key in batches[order[0]]}


def summarize(study: Study, samples: dict[str, np.ndarray] | None, nominal: np.ndarray, nominal_centerlines: np.ndarray,
              sensitivities: Sensitivities | None) -> StudyOutcome:
    """The outcome of a study from its merged samples (None: no tolerances, a design search alone), the nominal
    quantities and centrelines, and (optionally) the sensitivities."""
    coordinates = study.coordinates()
    if samples is None:
        return StudyOutcome(study, {}, coordinates, nominal, nominal_centerlines, [], [], [], [], {}, {}, [])
    if not np.array_equal(samples["index"], np.arange(len(coordinates))):
        raise ValueError("the samples do not cover the study: some batches are missing or repeated")
    values = samples["values"]
    names = [q.name for q in study.quantities]
    spreads = [spread(values[:, k]) for k in range(len(names))]
    probabilities = [probability(limit, values[:, names.index(limit.quantity.name)]) for limit in study.limits]
    worst = [worst_sample(limit, values[:, names.index(limit.quantity.name)]) for limit in study.limits]
    solved = ~samples["failed"]
    envelopes = [station_envelope(samples["shapes"][:, k]) for k in range(samples["shapes"].shape[1])] if solved.any() else []
    deviation = samples["station_deviation"][solved]
    clearance = samples["clearance"][solved]
    outcome = StudyOutcome(
        study=study,
        samples=samples,
        coordinates=coordinates,
        nominal=nominal,
        nominal_centerlines=nominal_centerlines,
        spreads=spreads,
        probabilities=probabilities,
        worst=worst,
        envelopes=envelopes,
        deviation={"percentiles": np.percentile(deviation, PERCENTILES, axis=0) if solved.any() else None,
                   "maximum": deviation.max(axis=0) if solved.any() else None},
        clearance={"percentiles": np.moveaxis(np.percentile(clearance, PERCENTILES, axis=0), 0, 1)
                   if solved.any() else None, "minimum": clearance.min(axis=0) if solved.any() else None},
        failures=failure_causes(samples["reason"], samples["failed"]),
    )
    if not balanced(study.sampling.method, study.sampling.count):
        outcome.notes.append(f"a Sobol design of {study.sampling.count} samples is not a power of two: its balance "
                             "is lost (the estimates are still unbiased, but less precise than they could be)")
    failed = int(samples["failed"].sum())
    if failed:
        outcome.notes.append(f"{failed} of {len(coordinates)} samples failed ({len(outcome.failures)} cause(s)); they "
                             "are listed in samples.csv with their reasons and left out of the spreads (the probabilities give an upper end "
                             "counting them as broken)")
    outcome.notes.extend(_warm_start_notes(samples, study.base.problem.hose.length))
    if sensitivities is not None and solved.sum() >= 4:
        outcome.first_order = _first_order(study, sensitivities, samples, names)
        first = outcome.first_order
        for name, check in zip(first.names + ("the shape (mean squared station spread)",), first.agreements + [first.shape]):
            if not check.agrees:
                outcome.notes.append(f"first-order variance of {name} {check.verdict()}")
    return outcome


def _warm_start_notes(samples: dict[str, np.ndarray], length: float) -> list[str]:
    """What the warm start did: how many samples it reached, and how far the checked ones were from the published
    sequence's answers (another branch when more than OTHER_BRANCH of the length)."""
    warm = samples["warm"]
    if not warm.any():
        return []
    checked = samples["branch_distance"][np.isfinite(samples["branch_distance"])]
    notes = [f"warm start: {int(warm.sum())} samples by Newton from the nominal hose, "
             f"{int((~warm & ~samples['failed']).sum())} placed from the straight hose (Newton did not reach a stable "
             f"equilibrium); {checked.size} checked against the published sequence: largest distance "
             f"{checked.max() if checked.size else float('nan'):.3g} mm"]
    other = int(np.sum(checked > OTHER_BRANCH * length))
    if other:
        notes.append(f"warm start reached another branch than the published sequence on {other} of {checked.size} "
                     'checked samples: run the study with [sampling] start = "straight"')
    return notes


def _first_order(study: Study, sensitivities: Sensitivities, samples: dict[str, np.ndarray], names: list[str]) -> FirstOrder:
    """The first-order estimates and their agreement with the samples."""
    mean, variance = sensitivities.first_order(study.variation)
    hose = study.base.problem.hose
    stiffness = max(hose.bending_stiffness, hose.torsional_stiffness)
    checks = []
    for k, name in enumerate(sensitivities.names):
        quantity = study.quantities[names.index(name)]
        sampled = spread(samples["values"][:, names.index(name)])
        scale = natural_scale(quantity, hose.length, stiffness)
        checks.append(agreement(variance[k], sampled.variance, sampled.variance_error, scale))
    shapes = samples["shapes"][:, 0][~samples["failed"]]
    linear = sensitivities.station_spread(study.variation)
    # the shape as a whole: per sample, the mean over stations of the squared distance from the mean shape
    count = len(shapes)
    squared = np.mean(np.sum((shapes - shapes.mean(axis=0)) ** 2, axis=2), axis=1) * count / (count - 1)
    shape = agreement(float(np.mean(linear**2)), float(np.mean(squared)), float(np.std(squared, ddof=1) / np.sqrt(count)),
                      hose.length)
    return FirstOrder(sensitivities.names, mean, variance, checks, shape, linear,
                      np.sqrt(np.sum(np.var(shapes, axis=0, ddof=1), axis=1)), sensitivities.contributions(study.variation),
                      sensitivities.derivatives, sensitivities.station_derivatives)
