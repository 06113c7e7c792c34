"""Design search: which catalogue length and which clocking of the end fitting to choose.

The candidates are a grid of hose lengths (catalogue steps) and clockings (the twist of the end
fitting at assembly, degrees).  Each is solved like a sample (the placement, or the whole sweep)
and judged against every limit but the deviation (which measures a hose against the base design,
not a design against its requirements); with `samples` > 0 each is also judged over that many samples of
the study's tolerances (the same deviations for every candidate), a limit then counting as met
when its 5th percentile of margin (the margin 95 % of the hoses keep) is not negative.

The ranking: the candidates that meet every limit, best first by the margin of `rank_by`
(default: the smallest clearance, else the bend radius), ties broken by the smaller |clocking|
and then the shorter hose.  The grid of the margin of `rank_by` over length x clocking is the
heat map of the report.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hoseline.procedures.variation.quantities import CLEARANCE, Limit
from hoseline.procedures.variation.tolerances import INDEX

DESIGN_PERCENTILE = 5.0  # with tolerances, a limit is met when this percentile of its margin is not negative


@dataclass(frozen=True)
class DesignGrid:
    """The candidates: lengths (mm) x clockings (twist at assembly, degrees), absolute values; rank_by: the
    quantity whose margin ranks them (a limited one); samples: tolerance samples per candidate (0: nominal only)."""

    lengths: tuple[float, ...]
    clockings: tuple[float, ...]
    rank_by: str
    samples: int = 0

    def __post_init__(self) -> None:
        if not self.lengths or not self.clockings:
            raise ValueError("a design search needs at least one length and one clocking")

    def coordinates(self, nominal_length: float, nominal_twist: float, deviations: np.ndarray) -> np.ndarray:
        """(L * C * S, 15) the deviations of every candidate (lengths outermost, then clockings) and sample.

        deviations: (S, 15) tolerance deviations applied to every candidate (S = 1 row of zeros without).
        """
        rows = []
        for length in self.lengths:
            for clocking in self.clockings:
                offset = np.zeros(15)
                offset[INDEX["hose.length"]] = length - nominal_length
                offset[INDEX["end.twist"]] = clocking - nominal_twist
                rows.append(deviations + offset)
        return np.concatenate(rows)


@dataclass
class DesignOutcome:
    """The judged grid: margins (L, C, limits) mm or the quantity's unit (the 5th percentile with tolerances;
    NaN where the candidate failed), failed (L, C) how many of its samples failed, the reasons, and the ranking
    (indexes (i, j) into lengths x clockings of the candidates meeting every limit, best first)."""

    grid: DesignGrid
    limits: tuple[Limit, ...]
    margins: np.ndarray
    failed: np.ndarray
    reasons: list[str]
    ranking: list[tuple[int, int]]

    @property
    def rank_index(self) -> int:
        """Position of rank_by in limits."""
        return [limit.quantity.name for limit in self.limits].index(self.grid.rank_by)

    def table(self) -> list[dict]:
        """The ranked candidates as rows: rank, length_mm, clocking_deg, and the margin of every limit."""
        rows = []
        for rank, (i, j) in enumerate(self.ranking, start=1):
            row = {"rank": rank, "length_mm": self.grid.lengths[i], "clocking_deg": self.grid.clockings[j]}
            for k, limit in enumerate(self.limits):
                row[f"margin {limit.quantity.name} [{limit.quantity.unit}]"] = float(self.margins[i, j, k])
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
    """Judge the candidates from their samples (rows as grid.coordinates orders them)."""
    per = max(grid.samples, 1)
    shape = (len(grid.lengths), len(grid.clockings), per)
    values = samples["values"].reshape(shape + (-1,))
    failed = samples["failed"].reshape(shape)
    margins = np.full(shape[:2] + (len(limits),), np.nan)
    for k, limit in enumerate(limits):
        margin = limit.margin(values[..., names.index(limit.quantity.name)])
        with np.errstate(all="ignore"):
            judged = np.nanpercentile(margin, DESIGN_PERCENTILE, axis=2) if per > 1 else margin[..., 0]
        judged[failed.any(axis=2)] = np.nan  # a candidate some of whose hoses cannot be built is not met
        margins[..., k] = judged
    rank = [limit.quantity.name for limit in limits].index(grid.rank_by)
    feasible = [(i, j) for i in range(shape[0]) for j in range(shape[1])
                if np.all(np.isfinite(margins[i, j])) and np.all(margins[i, j] >= 0.0)]
    feasible.sort(key=lambda ij: (-margins[ij[0], ij[1], rank], abs(grid.clockings[ij[1]]), grid.lengths[ij[0]]))
    reasons = sorted({str(r) for r in samples["reason"][samples["failed"]]})
    return DesignOutcome(grid, limits, margins, failed.sum(axis=2), reasons, feasible)
