"""Design search: which catalogue length and which clocking of the end fitting to choose.

The candidates are a grid of hose lengths (catalogue steps) and clockings (the twist of the end
fitting at assembly, degrees).  Each is solved like a sample (the placement, or the whole sweep)
and judged against every limit but the deviation (which measures a hose against the base design,
not a design against its requirements); with `samples` > 0 each is also judged over that many samples of
the study's tolerances (the same deviations for every candidate), a limit then counting as met
when its 5th percentile of margin (the margin 95 % of the hoses keep) is not negative.

With rank_on = "p95_margin" each candidate is judged over the tolerances to first order instead: its
sensitivities are computed at the candidate (one nominal solve and one banded solve per varied
coordinate, sensitivity.py), every quantity is linearised there, Q(c) = Q0 + dQ/dc . c, and evaluated
at every tolerance sample of the study (the same deviations for every candidate, no solve), and a
limit's judged margin is the 5th percentile of its linearised margin over them (the margin 95 % of the
hoses keep): exact for the linearisation whatever the distributions (uniform, lognormal, ...), and
as cheap as a nominal candidate plus its sensitivities.  A candidate whose margin is large but
sensitive to the tolerances then ranks below one with a smaller, steadier margin.  Where the first
order is poor (a fold, a kink over a sweep's poses) judge with sampled candidates (`samples`) instead.

The ranking: the candidates that meet every limit, best first by the margin of `rank_by`
(default: the smallest clearance, else the bend radius), ties broken by the smaller |clocking|
and then the shorter hose.  The grid of the margin of `rank_by` over length x clocking is the
heat map of the report.

With method "optimise" the grid is refined: lengths are discrete (catalogue steps) and stay so,
the clocking is continuous.  For every length with a grid cell meeting every limit, the margin of
`rank_by` is maximised over the clocking subject to every limit (each judged margin >= 0, a
constraint) within the bracket of its best such cell (from the clocking on its left to the one on
its right, both grid points), by COBYQA (scipy.optimize.minimize, method "COBYQA": a derivative-free
trust-region method on quadratic models of the objective and of each constraint, bounds kept at
every evaluation; a failed candidate is NaN, which COBYQA treats as beyond a barrier), from the grid
cell, to CLOCKING_TOLERANCE.  Every clocking evaluated is checked against every limit, and the
answer is the best of them that meets every limit (the grid cell when none beats it), so the answer
meets every limit whatever the optimiser's last point is; the table says which.  Why a constrained
optimiser: the best clocking is often where another limit becomes active (the end torque grows as
the bend relaxes), and maximising the ranked margin alone walks past it into a design that breaks
that limit.  Why this and not a global optimiser over both (e.g. differential evolution with an
integral length): the margin over the clocking is an extreme over the poses (a kink where the
active pose changes) and can have several humps; the grid, which the heat map needs anyway, finds
the hump, and the local search only polishes inside a bracket every point of which is between two
candidates the grid judged; it is deterministic (the same numbers each run, as the samples are)
and costs about a dozen solves per length, where an evolutionary search costs hundreds of whole
sweeps and its answer depends on its seed.  A derivative-free method because the margins have
kinks (the active pose, the 5th percentile over tolerance samples) where gradients mislead.  Each
length is one task (on Dask when there is a cluster).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import Bounds, NonlinearConstraint, minimize

from hoseline.procedures.variation.quantities import CLEARANCE, Limit
from hoseline.procedures.variation.samples import SOLVER_FAILURES, StudyContext, evaluate_batch, failure_cause
from hoseline.procedures.variation.sweep_sensitivity import study_sensitivities
from hoseline.procedures.variation.tolerances import INDEX, perturbed

DESIGN_PERCENTILE = 5.0  # with tolerances, a limit is met when this percentile of its margin is not negative
METHODS = ("grid", "optimise")
RANK_ON = ("nominal", "p95_margin")  # judged at the nominal hose (or over sampled tolerances), or to first order
CLOCKING_TOLERANCE = 0.01  # degrees: the optimiser's final trust-region radius on the clocking
MAX_EVALUATIONS = 40  # candidates solved by the optimiser per length at most


@dataclass(frozen=True)
class DesignGrid:
    """The candidates: lengths (mm) x clockings (twist at assembly, degrees), absolute values; rank_by: the
    quantity whose margin ranks them (a limited one); samples: tolerance samples solved per candidate (0: nominal
    only); rank_on: "nominal" (as samples says) or "p95_margin" (each limit's 5th percentile of margin over the
    study's tolerance samples to first order at the candidate; samples must then be 0)."""

    lengths: tuple[float, ...]
    clockings: tuple[float, ...]
    rank_by: str
    samples: int = 0
    method: str = "grid"
    rank_on: str = "nominal"

    def __post_init__(self) -> None:
        if not self.lengths or not self.clockings:
            raise ValueError("a design search needs at least one length and one clocking")
        if self.method not in METHODS:
            raise ValueError(f"design method {self.method!r}: choose one of {', '.join(METHODS)}")
        if self.rank_on not in RANK_ON:
            raise ValueError(f"design rank_on {self.rank_on!r}: choose one of {', '.join(RANK_ON)}")
        if self.rank_on == "p95_margin" and self.samples:
            raise ValueError(f"design samples = {self.samples} with rank_on = \"p95_margin\": both judge the 5th "
                             "percentile of margin, by solved samples or to first order; give samples = 0 or "
                             "rank_on = \"nominal\"")

    @property
    def first_order(self) -> bool:
        """Whether the candidates are judged to first order over the tolerances (rank_on "p95_margin")."""
        return self.rank_on == "p95_margin"

    def offsets(self, nominal_length: float, nominal_twist: float, width: int) -> list[np.ndarray]:
        """(width,) per candidate (lengths outermost, then clockings): its length (mm) and clocking (deg) from the
        base's, as a deviation (width: tolerances.Variation.width)."""
        return [candidate_rows(length - nominal_length, clocking - nominal_twist, np.zeros((1, width)))[0]
                for length in self.lengths for clocking in self.clockings]

    def coordinates(self, nominal_length: float, nominal_twist: float, deviations: np.ndarray) -> np.ndarray:
        """(L * C * S, width) the deviations of every candidate (lengths outermost, then clockings) and sample.

        deviations: (S, width) tolerance deviations applied to every candidate (S = 1 row of zeros without;
        width: tolerances.Variation.width).
        """
        return np.concatenate([candidate_rows(length - nominal_length, clocking - nominal_twist, deviations)
                               for length in self.lengths for clocking in self.clockings])


def candidate_rows(length_offset: float, clocking_offset: float, deviations: np.ndarray) -> np.ndarray:
    """(S, width) the deviations of one candidate: its length (mm) and clocking (deg) from the base's, plus each of
    the tolerance deviations (S, width)."""
    offset = np.zeros(deviations.shape[1])
    offset[INDEX["hose.length"]] = length_offset
    offset[INDEX["end.twist"]] = clocking_offset
    return deviations + offset


@dataclass(frozen=True)
class FirstOrderCandidate:
    """One candidate judged to first order: offset (width,) its length and clocking from the base's as a deviation;
    deviations (S, width) the study's tolerance samples; varied: the coordinates the tolerances move."""

    offset: np.ndarray
    deviations: np.ndarray
    varied: tuple[int, ...]


def first_order_candidate(context: StudyContext, candidate: FirstOrderCandidate) -> dict[str, np.ndarray]:
    """The quantities of a candidate linearised at it and evaluated at every tolerance sample (a Dask task): arrays
    as evaluate_batch's for judge (values (S, quantities), the deviation NaN: it has no derivative; failed (S,),
    reason (S,)); every sample failed with the reason when the candidate cannot be solved or differentiated."""
    count = len(candidate.deviations)
    names = [q.name for q in context.base.quantities]
    out = {"values": np.full((count, len(names)), np.nan), "failed": np.zeros(count, dtype=bool),
           "reason": np.full(count, "", dtype=object)}
    try:
        found = study_sensitivities(context.base, perturbed(context.base.problem, candidate.offset), candidate.varied)
    except SOLVER_FAILURES as exc:
        out["failed"][:] = True
        out["reason"][:] = f"{type(exc).__name__}: {exc}"
    else:
        columns = [names.index(name) for name in found.names]
        out["values"][:, columns] = found.values + candidate.deviations @ found.derivatives.T
    out["reason"] = out["reason"].astype(str)
    return out


def candidate_arrays(context: StudyContext, offset: np.ndarray, deviations: np.ndarray, first_order: bool,
                     varied: tuple[int, ...]) -> dict[str, np.ndarray]:
    """The arrays judge and candidate_margins read for one candidate (offset (width,) its length and clocking as a
    deviation): its hoses solved at each of `deviations` (S, width), or its first-order linearisation evaluated
    there (first_order; varied: the coordinates the tolerances move)."""
    if first_order:
        return first_order_candidate(context, FirstOrderCandidate(offset, deviations, varied))
    rows = deviations + offset
    return evaluate_batch(context, np.arange(len(rows)), rows)


def candidate_margins(limits: tuple[Limit, ...], names: list[str], values: np.ndarray, failed: np.ndarray) -> np.ndarray:
    """(..., limits) the judged margin of each limit of candidates whose samples have `values` (..., S, quantities)
    and `failed` (..., S): the margin itself for one sample, its DESIGN_PERCENTILE over several; NaN where a
    sample of the candidate failed (a candidate some of whose hoses cannot be built meets no limit)."""
    margins = np.full(values.shape[:-2] + (len(limits),), np.nan)
    for k, limit in enumerate(limits):
        margin = limit.margin(values[..., names.index(limit.quantity.name)])
        with np.errstate(all="ignore"):
            judged = np.nanpercentile(margin, DESIGN_PERCENTILE, axis=-1) if margin.shape[-1] > 1 else margin[..., 0]
        judged = np.where(failed.any(axis=-1), np.nan, judged)
        margins[..., k] = judged
    return margins


def meets_every_limit(margins: np.ndarray) -> bool:
    """Whether a candidate's margins (limits,) are all known and not negative."""
    return bool(np.all(np.isfinite(margins)) and np.all(margins >= 0.0))


@dataclass
class Refined:
    """The best clocking of one length by the optimiser: length (mm), clocking (deg), margins (limits,),
    evaluations (candidates solved by the optimiser), optimised (False: the refined clocking did not meet every
    limit or did not beat the grid cell, which stands), bracket (deg) searched."""

    length: float
    clocking: float
    margins: np.ndarray
    evaluations: int
    optimised: bool
    bracket: tuple[float, float]


@dataclass
class DesignOutcome:
    """The judged grid: margins (L, C, limits) mm or the quantity's unit (the 5th percentile with tolerances;
    NaN where the candidate failed), failed (L, C) how many of its samples failed, the causes of the failures
    (samples.failure_cause), and the ranking
    (indexes (i, j) into lengths x clockings of the candidates meeting every limit, best first).  With the
    optimiser, refined: one per length that has a grid cell meeting every limit, ranked best first (the
    table is then theirs)."""

    grid: DesignGrid
    limits: tuple[Limit, ...]
    margins: np.ndarray
    failed: np.ndarray
    reasons: list[str]
    ranking: list[tuple[int, int]]
    refined: list[Refined] | None = None

    @property
    def rank_index(self) -> int:
        """Position of rank_by in limits."""
        return [limit.quantity.name for limit in self.limits].index(self.grid.rank_by)

    def table(self) -> list[dict]:
        """The ranked candidates as rows: rank, length_mm, clocking_deg, and the margin of every limit (with the
        optimiser: its candidates, one per length, and where each clocking comes from)."""
        if self.refined is not None:
            candidates = [(r.length, r.clocking, r.margins, "optimiser" if r.optimised else "grid") for r in self.refined]
        else:
            candidates = [(self.grid.lengths[i], self.grid.clockings[j], self.margins[i, j], None)
                          for i, j in self.ranking]
        rows = []
        for rank, (length, clocking, margins, source) in enumerate(candidates, start=1):
            row = {"rank": rank, "length_mm": length, "clocking_deg": clocking}
            for k, limit in enumerate(self.limits):
                row[f"margin {limit.quantity.name} [{limit.quantity.unit}]"] = float(margins[k])
            if source is not None:
                row["clocking from"] = source
            rows.append(row)
        return rows


def default_rank_by(limits: tuple[Limit, ...]) -> str:
    """The first limited clearance, else the bend radius, else the first limited quantity."""
    limited = [limit.quantity.name for limit in limits]
    for name in limited:
        if name.startswith(CLEARANCE):
            return name
    return "bend_radius" if "bend_radius" in limited else limited[0]


def judge(grid: DesignGrid, limits: tuple[Limit, ...], names: list[str], samples: dict[str, np.ndarray]) -> DesignOutcome:
    """Judge the candidates from their samples (rows as grid.coordinates orders them: candidate after candidate,
    the same number of rows each; to first order, first_order_candidate's rows)."""
    per = len(samples["failed"]) // (len(grid.lengths) * len(grid.clockings))
    shape = (len(grid.lengths), len(grid.clockings), per)
    failed = samples["failed"].reshape(shape)
    margins = candidate_margins(limits, names, samples["values"].reshape(shape + (-1,)), failed)
    rank = [limit.quantity.name for limit in limits].index(grid.rank_by)
    feasible = [(i, j) for i in range(shape[0]) for j in range(shape[1]) if meets_every_limit(margins[i, j])]
    feasible.sort(key=lambda ij: (-margins[ij[0], ij[1], rank], abs(grid.clockings[ij[1]]), grid.lengths[ij[0]]))
    reasons = sorted({failure_cause(str(r)) for r in samples["reason"][samples["failed"]]})
    return DesignOutcome(grid, limits, margins, failed.sum(axis=2), reasons, feasible)


@dataclass(frozen=True)
class RefineTask:
    """What the optimiser needs for one length: length (mm), the bracket of clockings (deg) and the grid's best
    clocking in it with its margins, the base's length (mm) and twist (deg), the tolerance deviations (S, width)
    judged per candidate, the limits, the quantities' names and the position of rank_by in the limits; first_order:
    candidates judged to first order over the deviations (varied: the coordinates the tolerances move)."""

    length: float
    bracket: tuple[float, float]
    start: float
    start_margins: np.ndarray
    nominal_length: float
    nominal_twist: float
    deviations: np.ndarray
    limits: tuple[Limit, ...]
    names: tuple[str, ...]
    rank: int
    first_order: bool = False
    varied: tuple[int, ...] = ()


def refine_tasks(outcome: DesignOutcome, names: list[str], nominal_length: float, nominal_twist: float,
                 deviations: np.ndarray, varied: tuple[int, ...] = ()) -> list[RefineTask]:
    """One task per length with a grid cell meeting every limit: its best cell's bracket."""
    grid = outcome.grid
    clockings = grid.clockings
    tasks = []
    for i, length in enumerate(grid.lengths):
        cells = [j for ii, j in outcome.ranking if ii == i]  # ranked best first
        if not cells:
            continue
        j = cells[0]
        bracket = (clockings[max(j - 1, 0)], clockings[min(j + 1, len(clockings) - 1)])
        tasks.append(RefineTask(length, bracket, clockings[j], outcome.margins[i, j], nominal_length, nominal_twist,
                                deviations, outcome.limits, tuple(names), outcome.rank_index, grid.first_order, varied))
    return tasks


def refine_length(context: StudyContext, task: RefineTask) -> dict[str, np.ndarray]:
    """Maximise the margin of rank_by over the clocking within the task's bracket for its length, every limit a
    constraint (a Dask task).

    Returns arrays: clocking (1,) deg, margins (limits,), evaluations (1,), optimised (1,) bool (False: the grid's
    clocking stands, no clocking evaluated both meeting every limit and beating it).
    """
    seen: dict[float, np.ndarray] = {}

    def margins(clocking: float) -> np.ndarray:
        if clocking not in seen:
            offset = candidate_rows(task.length - task.nominal_length, clocking - task.nominal_twist,
                                    np.zeros((1, task.deviations.shape[1])))[0]
            out = candidate_arrays(context, offset, task.deviations, task.first_order, task.varied)
            seen[clocking] = candidate_margins(task.limits, list(task.names), out["values"], out["failed"])
        return seen[clocking]

    low, high = task.bracket
    if high > low:
        minimize(lambda x: -margins(float(x[0]))[task.rank], np.array([task.start]), method="COBYQA",
                 bounds=Bounds([low], [high]),
                 constraints=NonlinearConstraint(lambda x: margins(float(x[0])), 0.0, np.inf),
                 options={"initial_tr_radius": 0.25 * (high - low), "final_tr_radius": CLOCKING_TOLERANCE,
                          "maxfev": MAX_EVALUATIONS})
    best, found, optimised = task.start, task.start_margins, False
    for clocking, candidate in seen.items():
        if meets_every_limit(candidate) and candidate[task.rank] > found[task.rank]:
            best, found, optimised = clocking, candidate, True
    return {"clocking": np.array([best]), "margins": np.asarray(found, dtype=float),
            "evaluations": np.array([len(seen)]), "optimised": np.array([optimised])}


def ranked_refinements(tasks: list[RefineTask], results: list[dict[str, np.ndarray]]) -> list[Refined]:
    """The optimiser's candidates (one per task, results in task order), best first as the grid ranks."""
    refined = [Refined(t.length, float(r["clocking"][0]), r["margins"], int(r["evaluations"][0]),
                       bool(r["optimised"][0]), t.bracket) for t, r in zip(tasks, results)]
    rank = tasks[0].rank if tasks else 0
    refined.sort(key=lambda c: (-c.margins[rank], abs(c.clocking), c.length))
    return refined
