"""Rare failures of a hose: per limit, FORM's most probable failure point, SORM, and importance sampling there.

The limit state of a limit is its margin (statistics: positive inside the limit) as a function of the
standard normal coordinates z of the tolerances: z -> u = Phi(z), a point of the unit hypercube, ->
the deviations (tolerances.Variation.coordinates), -> the hose solved with them.  Its gradient is exact:
the sensitivities (sensitivity.py, sweep_sensitivity.py: the implicit function theorem with the exact
Hessian) of the hose with those deviations, per unit of each coordinate measured from that hose, turned
into derivatives along the study's coordinates (local_jacobian: the identity but for the directions,
whose tilt axes turn with them), times d(deviations)/dz (central differences of the distributions'
inverses, no solve).  One evaluation is one solve of the hose with its sensitivities.

rare_event runs FORM (and SORM) for one limit; it is a Dask task.  The importance samples are ordinary
study samples (samples.evaluate_batch) at deviations around the design point, run by run.py; pooled, they
also give the probability of breaking any of the limits (RareUnion).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

from hoseline.model.problem import Problem
from hoseline.procedures.variation.quantities import Limit
from hoseline.procedures.variation.reliability import (Curvatures, DesignPoint, ImportanceEstimate, LimitState,
                                                       curvatures, design_point)
from hoseline.procedures.variation.samples import SOLVER_FAILURES, StudyBase, StudyContext
from hoseline.procedures.variation.tolerances import (CLIP_COORDINATES, COORDINATES, INDEX, Variation, _turned,
                                                      perturbed, tilt_axes)

MAPPING_STEP = 1e-5  # standard deviations: central differences of the deviations along z
TILT_STEP = 1e-4  # degrees: central differences of a turned direction
RELATIVE = ("bend_radius", "end_torque", "twist_rate")  # positive by nature: their margins are taken as logarithms
TINY = 1e-12  # of the limit: the least value whose logarithm is taken


@dataclass(frozen=True)
class Reliability:
    """What the study file's [reliability] asks: method ("form" or "sorm": FORM with Breitung's correction),
    importance_samples around each design point (0: none), limits (quantity names; empty: every limit but
    the deviation, which has no derivative), seed of the importance samples."""

    method: str = "form"
    importance_samples: int = 100
    limits: tuple[str, ...] = ()
    seed: int = 0


def standard_normal_deviations(variation: Variation, z: np.ndarray) -> np.ndarray:
    """(n, width) deviations of standard normal points z (n, dimensions) (the unit point Phi(z))."""
    return variation.coordinates(ndtr(np.atleast_2d(z)))


def deviation_jacobian(variation: Variation, z: np.ndarray) -> np.ndarray:
    """(width, dimensions) d(deviations)/dz at the standard normal point z (dimensions,), central differences."""
    steps = MAPPING_STEP * np.eye(z.size)
    ahead = standard_normal_deviations(variation, z + steps)
    behind = standard_normal_deviations(variation, z - steps)
    return ((ahead - behind) / (2.0 * MAPPING_STEP)).T


def local_jacobian(problem: Problem, deviation: np.ndarray) -> np.ndarray:
    """(width, width) d(coordinates measured from the hose with `deviation`)/d(deviation): the identity (offsets,
    ln factors and arc-length stretch add up) but for every direction's two tilts, whose axes (tilt_axes of the
    turned direction) turn with it."""
    width = deviation.size
    out = np.eye(width)
    directions = [(INDEX["start.tilt_a"], problem.start.direction), (INDEX["end.tilt_a"], problem.end.direction)]
    for k, clip in enumerate(problem.clips):
        first = len(COORDINATES) + len(CLIP_COORDINATES) * k + 3
        if clip.direction is not None and first < width:
            directions.append((first, clip.direction))
    for first, direction in directions:
        tilt = deviation[first:first + 2]
        turned = _turned(direction, tilt)
        axes = tilt_axes(turned)
        moments = np.cross(axes, turned)  # d(direction) = (e_a a + e_b b) x direction, e in radians
        for j in range(2):
            step = TILT_STEP * np.eye(2)[j]
            change = (_turned(direction, tilt + step) - _turned(direction, tilt - step)) / (2.0 * TILT_STEP)
            out[first:first + 2, first + j] = np.degrees(moments @ change)
    return out


def limit_state(variation: Variation, margin: Callable[[np.ndarray], tuple[float, np.ndarray]]) -> LimitState:
    """z -> (g, dg/dz) of a margin given on the deviations: margin(deviation (width,)) -> (g, dg/d(deviation))."""

    def evaluate(z: np.ndarray) -> tuple[float, np.ndarray]:
        g, gradient = margin(standard_normal_deviations(variation, z)[0])
        return g, gradient @ deviation_jacobian(variation, z)

    return evaluate


def hose_margin(base: StudyBase, variation: Variation, limit: Limit) -> Callable[[np.ndarray], tuple[float, np.ndarray]]:
    """deviation -> (margin of `limit` of the hose with it, d(margin)/d(deviation)): one solve with sensitivities
    (NaN where the hose cannot be solved).

    The margin of a quantity positive by nature (RELATIVE: the bend radius, end torque, twist rate) is the logarithm
    of the value over the limit (or its inverse): the same surface g = 0, so the same design point and beta, but
    nearly linear where the quantity grows in proportion to a factor (the torque to the stiffness, lognormal), where
    the difference grows exponentially along z and the search would wander.  A clearance's is the difference (mm).
    """
    from hoseline.procedures.variation.sweep_sensitivity import study_sensitivities

    sign = 1.0 if limit.margin(1.0) > limit.margin(0.0) else -1.0  # d(margin)/d(quantity)
    relative = limit.quantity.name in RELATIVE and limit.value > 0.0

    def margin(deviation: np.ndarray) -> tuple[float, np.ndarray]:
        problem = perturbed(base.problem, deviation)
        try:
            found = study_sensitivities(base, problem, variation.varied)
        except SOLVER_FAILURES:  # the hose cannot be solved here: the search steps back
            return math.nan, np.full(deviation.size, math.nan)
        k = found.names.index(limit.quantity.name)
        value = float(found.values[k])
        gradient = sign * found.derivatives[k] @ local_jacobian(base.problem, deviation)
        if relative:
            value = max(value, TINY * limit.value)
            return sign * math.log(value / limit.value), gradient / value
        return float(limit.margin(value)), gradient

    return margin


@dataclass(frozen=True)
class RareTask:
    """One limit's FORM (and SORM when sorm) over the study's variation."""

    limit: Limit
    variation: Variation
    sorm: bool


def rare_event(context: StudyContext, task: RareTask) -> dict[str, np.ndarray]:
    """FORM (and SORM) of one limit (a Dask task); arrays for RareEvent.from_arrays."""
    g = limit_state(task.variation, hose_margin(context.base, task.variation, task.limit))
    point = design_point(g, task.variation.dimensions)
    found = curvatures(g, point) if task.sorm and point.converged else None
    return {"design_point": point.design_point, "beta": np.array(point.beta), "gradient": point.gradient,
            "evaluations": np.array(point.evaluations), "converged": np.array(point.converged),
            "message": np.array(point.message),
            "curvatures": found.curvatures if found is not None else np.zeros(0),
            "curvature_evaluations": np.array(found.evaluations if found is not None else 0)}


@dataclass
class RareEvent:
    """Rare failure of one limit: FORM's design point (point), SORM's curvatures (None: FORM only), the
    deviations of the design point (width,), and the importance-sampling check (None: not run)."""

    limit: Limit
    point: DesignPoint
    curvatures: Curvatures | None
    deviation: np.ndarray
    importance: ImportanceEstimate | None = None

    @staticmethod
    def from_arrays(limit: Limit, variation: Variation, arrays: dict[str, np.ndarray], sorm: bool) -> "RareEvent":
        """The RareEvent of rare_event's arrays."""
        point = DesignPoint(arrays["design_point"], float(arrays["beta"]), arrays["gradient"],
                            int(arrays["evaluations"]), bool(arrays["converged"]), str(arrays["message"]))
        found = Curvatures(arrays["curvatures"], int(arrays["curvature_evaluations"])) if sorm and point.converged else None
        deviation = (standard_normal_deviations(variation, point.design_point)[0] if np.all(np.isfinite(point.design_point))
                     else np.full(variation.width, np.nan))
        return RareEvent(limit, point, found, deviation)

    @property
    def form(self) -> float:
        """FORM's P(the limit is broken)."""
        return self.point.probability

    @property
    def sorm(self) -> float | None:
        """SORM's (Breitung) P, None when not asked (NaN where it does not apply)."""
        return None if self.curvatures is None else self.curvatures.breitung(self.point)

    @property
    def evaluations(self) -> int:
        """Solves with sensitivities spent on FORM and SORM."""
        return self.point.evaluations + (self.curvatures.evaluations if self.curvatures is not None else 0)

    def notes(self) -> list[str]:
        """What a reader must know: FORM not converged, SORM not applicable, the importance estimate away from them."""
        name = self.limit.describe()
        if not self.point.converged:
            return [f"FORM of {name}: no design point ({self.point.message}); its probability is not to be used"]
        notes = []
        if self.sorm is not None and not math.isfinite(self.sorm):
            notes.append(f"SORM of {name}: Breitung's formula does not apply here (the nominal hose breaks the limit, "
                         "or a curvature below -1/beta)")
        check = self.importance
        if check is not None and math.isfinite(check.estimate):
            for method, value in (("FORM", self.form), ("SORM", self.sorm)):
                if value is not None and math.isfinite(value) and not check.low <= value <= check.high:
                    notes.append(f"{method} of {name}: {value:.3g} outside the importance sampling's 95 % interval "
                                 f"[{check.low:.3g}, {check.high:.3g}] ({check.samples} samples): the limit-state surface "
                                 "is not flat near the design point (or there are several); trust the sampled estimate")
        return notes


@dataclass(frozen=True)
class RareUnion:
    """P(breaking any of several limits): limits, form (their tangent half-spaces' union, reliability.union_first_order)
    and importance (every design point's importance samples pooled, mixture weights; None without them)."""

    limits: tuple[Limit, ...]
    form: float
    importance: ImportanceEstimate | None
