"""A study from start to end: the nominal hose, the sensitivities, the samples (in rounds, to a requested precision:
precision.py), the worst-case corners, the Sobol' indices, the rare failures (FORM and importance sampling), the
design search, the outcome.

Batches go through a store (anything with finished() and save(k, arrays); io/study_results.py
keeps them as files so an interrupted study resumes): finished batches are not run again.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace
from typing import Protocol

import numpy as np

from hoseline.procedures.placement.continuation import PlacementError, Progress
from hoseline.procedures.variation.designs import balanced
from hoseline.procedures.variation.design_search import (FirstOrderCandidate, RefineTask, first_order_candidate, judge,
                                                        ranked_refinements, refine_length, refine_tasks)
from hoseline.procedures.variation.engine import Engine, Where, default_batch_size
from hoseline.procedures.variation.global_sensitivity import sobol_indices
from hoseline.procedures.variation.precision import PrecisionOutcome, next_total
from hoseline.procedures.variation.rare import RareEvent, RareTask, RareUnion, rare_event, standard_normal_deviations
from hoseline.procedures.variation.reliability import importance_estimate, importance_points, union_first_order
from hoseline.procedures.variation.scheduler import scheduler_address
from hoseline.procedures.variation.samples import StudyContext, nominal_context
from hoseline.procedures.variation.study import Study, StudyOutcome, merge_batches, summarize
from hoseline.procedures.variation.sweep_sensitivity import study_sensitivities
from hoseline.procedures.variation.worst_case import WorstCase, worst_cases


UNION_DRAWS = 100_000  # draws of the first-order union of the limits' half-spaces (no solve; 1 % at 1e-3)


class BatchStore(Protocol):
    """Where finished batches of one stage are kept."""

    def finished(self) -> dict[int, dict[str, np.ndarray]]: ...

    def save(self, batch: int, arrays: dict[str, np.ndarray]) -> None: ...


class MemoryStore:
    """A BatchStore in memory (nothing to resume from)."""

    def __init__(self) -> None:
        self.batches: dict[int, dict[str, np.ndarray]] = {}

    def finished(self) -> dict[int, dict[str, np.ndarray]]:
        return dict(self.batches)

    def save(self, batch: int, arrays: dict[str, np.ndarray]) -> None:
        self.batches[batch] = arrays


def run_study(study: Study, stores: Callable[[str], BatchStore] | None = None, *, where: Where = Where(),
              progress: Progress | None = None) -> StudyOutcome:
    """Run `study` and return its outcome.

    stores: stage name ("samples", "samples_R" (round R of sampling to a precision), "design", "optimise",
    "corners", "sobol", "form", "importance_K") -> its BatchStore (default: in memory).  where: where the
    batches run.  progress: callable(phase, fraction).  Raises PlacementError when the nominal hose
    cannot be solved, ClusterError at once (before any solving) when an existing cluster cannot be reached.
    """
    stores = stores or (lambda stage: MemoryStore())
    started = time.perf_counter()
    if where.scheduler is not None:
        where = replace(where, scheduler=scheduler_address(where.scheduler))
    with Engine(where) as engine:  # the cluster starts and warms while the nominal hose and sensitivities are solved
        context, nominal = nominal_context(study.base, warm=study.sampling.start == "nominal")
        notes = []
        sensitivities = None
        if study.sensitivities and study.variation.tolerances:
            try:
                sensitivities = study_sensitivities(study.base, study.base.problem, study.variation.varied)
            except (PlacementError, ValueError) as exc:
                notes.append(f"no sensitivities: {exc}")
            else:
                notes.extend(sensitivities.kinks)
        coordinates = study.coordinates()
        tick = time.perf_counter()
        timings = {"nominal": tick - started}
        engine.ready()
        timings["cluster"] = time.perf_counter() - tick
        tick = time.perf_counter()
        precision = None
        if study.sampling.precision is None or len(coordinates) == 0:
            samples = _stage(engine, "samples", context, coordinates, study.sampling.batch_size(), stores, progress)
        else:
            study, samples, precision = _sample_to_precision(engine, context, study, stores, progress)
            coordinates = study.coordinates()
        timings["samples"] = time.perf_counter() - tick
        design_samples = None
        if study.design is not None:
            grid = study.design
            problem = study.base.problem
            tick = time.perf_counter()
            cold = replace(context, warm=None)  # the candidates are too far apart for Newton from the nominal hose
            if grid.first_order:
                deviations = coordinates
                candidates = [FirstOrderCandidate(offset, deviations, study.variation.varied) for offset in
                              grid.offsets(problem.hose.length, problem.end_twist_deg, study.variation.width)]
                found = _stored_map(engine, first_order_candidate, cold, candidates, stores("design"), "design",
                                    progress)
                design_samples = merge_batches(found)
            else:
                deviations = coordinates[:grid.samples] if grid.samples else np.zeros((1, study.variation.width))
                rows = grid.coordinates(problem.hose.length, problem.end_twist_deg, deviations)
                design_samples = _stage(engine, "design", cold, rows, default_batch_size(len(rows)), stores, progress)
            timings["design"] = time.perf_counter() - tick
        corners = None
        if study.worst_case and sensitivities is not None:
            tick = time.perf_counter()
            corners = _worst_cases(engine, replace(context, warm=None), study, sensitivities, stores, progress)
            timings["corners"] = time.perf_counter() - tick
        sobol = None
        if study.global_sensitivity is not None:
            tick = time.perf_counter()
            rows = _stage(engine, "sobol", context, study.sobol_coordinates(), study.sampling.batch_size(), stores,
                          progress)
            sobol = sobol_indices(rows["values"], study.global_sensitivity.samples, len(study.variation.tolerances),
                                  study.global_sensitivity.seed)
            timings["sobol"] = time.perf_counter() - tick
        rare_events, rare_union = None, None
        if study.reliability is not None:
            tick = time.perf_counter()
            rare_events, rare_union = _rare_events(engine, replace(context, warm=None), study, stores, progress)
            timings["rare"] = time.perf_counter() - tick
        design = None
        if design_samples is not None:
            names = [q.name for q in study.quantities]
            design_limits = tuple(limit for limit in study.limits if limit.quantity.name != "deviation")
            design = judge(study.design, design_limits, names, design_samples)
            if grid.method == "optimise":
                tick = time.perf_counter()
                tasks = refine_tasks(design, names, problem.hose.length, problem.end_twist_deg, deviations,
                                     study.variation.varied)
                design.refined = ranked_refinements(tasks, _refine(engine, cold, tasks, stores, progress))
                timings["optimiser"] = time.perf_counter() - tick
        tick = time.perf_counter()
    timings["close"] = time.perf_counter() - tick
    outcome = summarize(study, samples, nominal.values(nominal.centerlines), nominal.centerlines, sensitivities)
    outcome.notes[:0] = notes
    outcome.design = design
    outcome.rare_events = rare_events or []
    outcome.rare_union = rare_union
    outcome.sobol = sobol
    outcome.worst_cases = corners or []
    outcome.precision = precision
    if precision is not None and not precision.reached:
        outcome.notes.append(f"sampling to a precision: {precision.describe()}")
    if study.worst_case and sensitivities is None:
        outcome.notes.append("no worst-case corners: they follow the sensitivities, which this study has not")
    if sobol is not None and outcome.first_order is not None:
        outcome.notes.extend(_sobol_notes(outcome))
    if sobol is not None and study.variation.correlations:
        outcome.notes.append("the Sobol' indices of correlated tolerances are those of their independent normal scores "
                             "in each correlation matrix's order (its Cholesky factor): the first tolerance of a "
                             "matrix carries what the others share with it, a later one only its own part")
    outcome.notes.extend(note for event in outcome.rare_events for note in event.notes())
    outcome.run = {
        "where": where.describe(),
        "samples": len(coordinates),
        "samples per second": len(coordinates) / timings["samples"] if len(coordinates) and timings["samples"] else None,
        "seconds, nominal hose and sensitivities": timings["nominal"],
        "seconds, waiting for the cluster (after the nominal hose)": timings["cluster"],
        "seconds, samples": timings["samples"],
        "seconds, worst-case corners": timings.get("corners"),
        "seconds, Sobol' indices": timings.get("sobol"),
        "seconds, design search": timings.get("design"),
        "seconds, rare failures (FORM and importance sampling)": timings.get("rare"),
        "seconds, design optimiser": timings.get("optimiser"),
        "seconds, closing the cluster": timings["close"],
        "seconds, whole study": time.perf_counter() - started,
    }
    return outcome


def _stage(engine: Engine, name: str, context: StudyContext, coordinates: np.ndarray, batch_size: int,
           stores: Callable[[str], BatchStore], progress: Progress | None, first: int = 0) -> dict[str, np.ndarray] | None:
    """Run one stage's batches (skipping those its store has) and return its merged samples (None if empty).
    first: the index of its first sample (a later round of sampling to a precision)."""
    if len(coordinates) == 0:
        return None
    store = stores(name)
    batches = store.finished()
    total = -(-len(coordinates) // batch_size)

    def keep(k: int, arrays: dict[str, np.ndarray]) -> None:
        store.save(k, arrays)
        batches[k] = arrays
        if progress is not None:
            progress(name, len(batches) / total)

    engine.run(context, coordinates, batch_size, keep, done=set(batches), first=first)
    return merge_batches(batches)


def _sample_to_precision(engine: Engine, context: StudyContext, study: Study, stores: Callable[[str], BatchStore],
                         progress: Progress | None) -> tuple[Study, dict[str, np.ndarray], PrecisionOutcome]:
    """The samples of rounds (stages "samples", "samples_1", ...) until [sampling.precision]'s statistic is known as
    well as asked or the cap is reached (precision.py): the study with the rounds drawn, the merged samples and how
    it ended."""
    precision = study.sampling.precision
    column = [q.name for q in study.quantities].index(precision.quantity)
    power_of_two = study.sampling.method == "sobol" and balanced("sobol", study.sampling.count)
    rounds = [study.sampling.count]
    parts = {}
    while True:
        study = replace(study, sampling=replace(study.sampling, count=sum(rounds), rounds=tuple(rounds)))
        first = sum(rounds[:-1])
        part = _stage(engine, "samples" if len(rounds) == 1 else f"samples_{len(rounds) - 1}", context,
                      study.coordinates()[first:], study.sampling.round_batch(rounds[-1]), stores, progress, first)
        parts[len(rounds) - 1] = part
        samples = merge_batches(parts)
        estimate, low, high = precision.interval(samples["values"][:, column])
        reached = (high - low) / 2.0 <= precision.half_width
        if reached or sum(rounds) >= precision.max_samples:
            return study, samples, PrecisionOutcome(precision, estimate, low, high, sum(rounds), tuple(rounds), reached)
        rounds.append(next_total(sum(rounds), (high - low) / 2.0, precision, power_of_two) - sum(rounds))


def _worst_cases(engine: Engine, context: StudyContext, study: Study, sensitivities, stores: Callable[[str], BatchStore],
                 progress: Progress | None) -> list[WorstCase]:
    """The worst-case corner of every smooth quantity from the sensitivities, each hose solved there (a stage)."""
    by_name = {q.name: q for q in study.quantities}
    cases = worst_cases(study.variation, tuple(by_name[name] for name in sensitivities.names), sensitivities.values,
                        sensitivities.derivatives)
    solved = _stage(engine, "corners", context, np.array([case.corner for case in cases]), 1, stores, progress)
    names = [q.name for q in study.quantities]
    for row, case in enumerate(cases):
        case.solved = float(solved["values"][row, names.index(case.quantity.name)])
        case.reason = str(solved["reason"][row])
    return cases


def _sobol_notes(outcome: StudyOutcome) -> list[str]:
    """Where the first order is flagged wrong, the Sobol' indices to use instead."""
    first = outcome.first_order
    return [f"the first-order contributions (tornado) of {name} are wrong here: its Sobol' indices are in the report "
            "and summary.json (their first-order and total shares need no linearity)"
            for name, check in zip(first.names, first.agreements) if not check.agrees]


def _rare_events(engine: Engine, context: StudyContext, study: Study, stores: Callable[[str], BatchStore],
                 progress: Progress | None) -> tuple[list[RareEvent], RareUnion | None]:
    """FORM (and SORM) of every limit the study's [reliability] names (one task each, kept in the "form" store),
    then the importance samples around each design point (a stage of samples each); and, of two limits or more
    with a design point, the probability of breaking any of them."""
    options = study.reliability
    limits = study.reliability_limits()
    sorm = options.method == "sorm"
    tasks = [RareTask(limit, study.variation, sorm) for limit in limits]
    results = _stored_map(engine, rare_event, context, tasks, stores("form"), "rare failures (FORM)", progress)
    events = [RareEvent.from_arrays(limit, study.variation, results[k], sorm) for k, limit in enumerate(limits)]
    names = [q.name for q in study.quantities]
    columns = [names.index(limit.quantity.name) for limit in limits]
    drawn = []  # (event, its points, every limit's margin there)
    for k, event in enumerate(events):
        if options.importance_samples == 0 or not np.all(np.isfinite(event.point.design_point)):
            continue
        points = importance_points(event.point.design_point, options.importance_samples, options.seed + k)
        deviations = standard_normal_deviations(study.variation, points)
        samples = _stage(engine, f"importance_{k}", context, deviations, default_batch_size(len(points)), stores,
                         progress)
        margins = np.column_stack([limit.margin(samples["values"][:, q]) for limit, q in zip(limits, columns)])
        event.importance = importance_estimate(points, event.point.design_point, margins[:, k])
        if event.point.converged:
            drawn.append((event, points, margins))
    found = [event for event in events if event.point.converged]
    if len(found) < 2:
        return events, None
    form = union_first_order([event.point for event in found], UNION_DRAWS, options.seed)
    pooled = None
    if len(drawn) == len(found):
        centers = np.array([event.point.design_point for event, _, _ in drawn])
        chosen = [limits.index(event.limit) for event in found]
        pooled = importance_estimate(np.vstack([points for _, points, _ in drawn]), centers,
                                     np.vstack([margins for _, _, margins in drawn])[:, chosen].min(axis=1))
    return events, RareUnion(tuple(event.limit for event in found), form, pooled)


def _refine(engine: Engine, context: StudyContext, tasks: list[RefineTask], stores: Callable[[str], BatchStore],
            progress: Progress | None) -> list[dict[str, np.ndarray]]:
    """The optimiser's result of every task (one per length), kept in the "optimise" store like batches (so an
    interrupted study does not search the finished lengths again)."""
    if not tasks:
        return []
    results = _stored_map(engine, refine_length, context, tasks, stores("optimise"), "design optimiser", progress)
    return [results[k] for k in range(len(tasks))]


def _stored_map(engine: Engine, function, context: StudyContext, tasks: list, store: BatchStore, label: str,
                progress: Progress | None) -> dict[int, dict[str, np.ndarray]]:
    """{task index: arrays} of `function` over `tasks` on the engine, each result kept in `store` as it comes (so an
    interrupted study does not do the finished tasks again), progress reported under `label`."""
    results = store.finished()

    def keep(k: int, arrays: dict[str, np.ndarray]) -> None:
        store.save(k, arrays)
        results[k] = arrays
        if progress is not None:
            progress(label, len(results) / len(tasks))

    engine.map(function, context, tasks, keep, done=set(results))
    return results
