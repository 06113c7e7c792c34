"""Small probabilities of failure: FORM, SORM (Breitung) and importance sampling around the design point.

In standard normal space z (independent N(0, 1) coordinates, mapped to the tolerances' deviations by
the inverse distribution functions), a limit state g(z) is positive where the hose meets the limit and
negative where it breaks it.  FORM finds the most probable failure point (the design point): the point
of the surface g = 0 nearest the origin,

    z* = argmin |z|^2 / 2  subject to  g(z) = 0,

here by SciPy's SLSQP with the exact gradient of g (each evaluation one solve with its sensitivities),
within |z_i| <= 7 (beyond, the unit point Phi(z) is within 1e-12 of its ends, where the samples clip it),
stopped when |g| <= 1e-7 |g(0)| and z is parallel to grad g (1 - cos <= 1e-6), and takes
P(failure) = Phi(-beta), beta = |z*| signed by g(0) (negative when the nominal already breaks the limit).  SORM (Breitung 1984) corrects for the surface's curvature at z*:

    P = Phi(-beta) prod_i (1 + beta kappa_i)^(-1/2),

kappa_i the principal curvatures, the eigenvalues of the Hessian of g on the tangent plane over |grad g|
(positive where the failure domain curves away from the origin), the Hessian from central differences
of the exact gradient along an orthonormal basis of the tangent plane (2 (d - 1) evaluations).

Importance sampling checks either: z ~ N(z*, I), each sample weighted by phi(z) / phi(z - z*) =
exp(-z.z* + |z*|^2 / 2); the estimate is the weighted fraction of failures, its standard error the
standard deviation of the weighted indicator over sqrt(n).  Several limits at once (P of breaking any):
the samples of every design point pooled, each weighted by phi(z) over the mixture of the normals they
were drawn from (multiple importance sampling, the balance heuristic), and to first order the union of
the limits' tangent half-spaces, sampled the same way without solving anything (union_first_order).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr, ndtri

from hoseline.procedures.variation.statistics import CONFIDENCE

LimitState = Callable[[np.ndarray], tuple[float, np.ndarray]]  # z -> (g, dg/dz)
CURVATURE_STEP = 0.1  # standard deviations: the step of the central differences of the gradient for SORM
ALIGNED = 1e-6  # 1 - |cos| between z* and grad g at a design point (an angle of 1.4e-3 rad)
SURFACE = 1e-7  # of |g(0)|: |g| at a design point
MAX_ITERATIONS = 40
BOUND = 7.0  # standard deviations: the search stays within |z_i| <= BOUND, where Phi(z) is still resolved (1e-12)


@dataclass(frozen=True)
class DesignPoint:
    """FORM's answer: design_point (d,) z*, beta (signed: negative when g(0) < 0), gradient (d,) of g at z*,
    evaluations of the limit state, converged (z* on g = 0 and along grad g), message (why not)."""

    design_point: np.ndarray
    beta: float
    gradient: np.ndarray
    evaluations: int
    converged: bool
    message: str

    @property
    def probability(self) -> float:
        """FORM's P(failure) = Phi(-beta)."""
        return float(ndtr(-self.beta))


def design_point(limit_state: LimitState, dimensions: int) -> DesignPoint:
    """The most probable failure point of `limit_state` (z -> (g, dg/dz)) in `dimensions` standard normal
    coordinates, by SLSQP from the origin (the function is evaluated once per point, its values cached)."""
    from scipy.optimize import minimize  # here: reading a study file needs none of it

    cache: dict[bytes, tuple[float, np.ndarray]] = {}

    def evaluate(z: np.ndarray) -> tuple[float, np.ndarray]:
        key = np.asarray(z, dtype=float).tobytes()
        if key not in cache:
            g, gradient = limit_state(np.asarray(z, dtype=float))
            cache[key] = (float(g), np.asarray(gradient, dtype=float))
        return cache[key]

    origin = np.zeros(dimensions)
    g0, gradient0 = evaluate(origin)
    if not math.isfinite(g0) or not np.any(gradient0):
        return DesignPoint(origin, math.inf if g0 > 0 else -math.inf, gradient0, len(cache), False,
                           "the limit state does not change with the tolerances at the nominal hose")
    scale = abs(g0) if g0 != 0.0 else float(np.linalg.norm(gradient0))
    def misalignment(z: np.ndarray) -> float:
        g, gradient = evaluate(z)
        norm = float(np.linalg.norm(z) * np.linalg.norm(gradient))
        return 1.0 - abs(float(z @ gradient)) / norm if norm > 0.0 else 1.0

    def converged(z: np.ndarray) -> bool:
        return abs(evaluate(z)[0]) <= SURFACE * scale and misalignment(z) <= ALIGNED

    def stop(z: np.ndarray) -> None:
        if converged(z):
            raise StopIteration

    start = np.clip(-g0 * gradient0 / float(gradient0 @ gradient0), -BOUND, BOUND)  # that of the linearised g
    result = minimize(lambda z: 0.5 * float(z @ z), start, jac=lambda z: z, method="SLSQP", callback=stop,
                      bounds=[(-BOUND, BOUND)] * dimensions,
                      constraints=[{"type": "eq", "fun": lambda z: evaluate(z)[0] / scale,
                                    "jac": lambda z: evaluate(z)[1] / scale}],
                      options={"maxiter": MAX_ITERATIONS, "ftol": 1e-12})
    z = np.asarray(result.x, dtype=float)
    g, gradient = evaluate(z)
    beta = math.copysign(float(np.linalg.norm(z)), g0)
    done = bool(np.isfinite(g) and converged(z))
    message = "" if done else (f"SLSQP: {result.message}; |g| = {abs(g):.3g} at the last point, "
                               f"1 - cos(z, grad g) = {misalignment(z):.3g}"
                               + (f"; the search reached the bound |z| = {BOUND:g} of a tolerance: the failure is "
                                  f"further out, its probability far below Phi(-{BOUND:g}) = {ndtr(-BOUND):.1g}"
                                  if np.any(np.abs(z) >= BOUND - 1e-9) and g * g0 > 0.0 else ""))
    return DesignPoint(z, beta, gradient, len(cache), done, message)


@dataclass(frozen=True)
class Curvatures:
    """SORM at a design point: curvatures (d - 1,) of the limit-state surface, evaluations spent on them."""

    curvatures: np.ndarray
    evaluations: int

    def breitung(self, point: DesignPoint) -> float:
        """Breitung's P(failure) = Phi(-beta) prod (1 + beta kappa)^(-1/2); NaN where it does not apply (a factor
        1 + beta kappa <= 0, or the nominal hose already breaking the limit)."""
        factors = 1.0 + point.beta * self.curvatures
        if point.beta <= 0.0 or np.any(factors <= 0.0):
            return float("nan")
        return point.probability / float(np.sqrt(np.prod(factors)))


def curvatures(limit_state: LimitState, point: DesignPoint, step: float = CURVATURE_STEP) -> Curvatures:
    """The principal curvatures of g = 0 at `point`, from central differences of the gradient (step in standard
    deviations) along an orthonormal basis of the tangent plane."""
    from scipy.linalg import null_space

    gradient = point.gradient
    norm = float(np.linalg.norm(gradient))
    basis = null_space(gradient[None, :])  # (d, d - 1) orthonormal, perpendicular to grad g
    columns = []
    for k in range(basis.shape[1]):
        ahead = limit_state(point.design_point + step * basis[:, k])[1]
        behind = limit_state(point.design_point - step * basis[:, k])[1]
        columns.append(basis.T @ (ahead - behind) / (2.0 * step))
    hessian = np.array(columns).reshape(basis.shape[1], basis.shape[1])
    if not np.all(np.isfinite(hessian)):  # a hose beside the design point could not be solved
        return Curvatures(np.full(basis.shape[1], np.nan), 2 * basis.shape[1])
    return Curvatures(np.linalg.eigvalsh(0.5 * (hessian + hessian.T)) / norm, 2 * basis.shape[1])


@dataclass(frozen=True)
class ImportanceEstimate:
    """Importance sampling around a design point: estimate, standard_error, 95 % interval (low, high) (the
    normal approximation, low clipped at 0), samples used (solved), failed (not solved: left out),
    high_with_failed (the upper end if every failed sample broke the limit)."""

    estimate: float
    standard_error: float
    low: float
    high: float
    samples: int
    failed: int
    high_with_failed: float

    @property
    def coefficient_of_variation(self) -> float:
        """standard_error / estimate (inf for an estimate of 0)."""
        return self.standard_error / self.estimate if self.estimate > 0.0 else math.inf


def importance_points(center: np.ndarray, count: int, seed: int) -> np.ndarray:
    """(count, d) standard normal points z ~ N(center, I) (seeded: the same every run)."""
    return center + np.random.default_rng(seed).standard_normal((count, center.size))


def mixture_weights(points: np.ndarray, centers: np.ndarray) -> np.ndarray:
    """(n,) phi(z) / q(z) at `points` (n, d) drawn in equal numbers from N(c, I) of each of `centers` (k, d): the
    mixture q = mean_k phi(z - c_k) (the balance heuristic of multiple importance sampling; k = 1: one center)."""
    centers = np.atleast_2d(centers)
    exponents = points @ centers.T - 0.5 * np.sum(centers**2, axis=1)  # ln phi(z - c) - ln phi(z)
    largest = np.max(exponents, axis=1)
    return 1.0 / (np.exp(largest) * np.mean(np.exp(exponents - largest[:, None]), axis=1))


def importance_estimate(points: np.ndarray, centers: np.ndarray, margins: np.ndarray) -> ImportanceEstimate:
    """P(g < 0) from margins (n,) (g at each point; NaN: not solved) at `points` (n, d) drawn in equal numbers from
    N(c, I) of each of `centers` (k, d), or (d,) for one."""
    weights = mixture_weights(points, centers)
    solved = np.isfinite(margins)
    n = int(solved.sum())
    if n < 2:
        nan = float("nan")
        return ImportanceEstimate(nan, nan, nan, nan, n, int((~solved).sum()), nan)
    terms = np.where(margins[solved] < 0.0, weights[solved], 0.0)
    estimate = float(terms.mean())
    error = float(terms.std(ddof=1) / math.sqrt(n))
    half = float(ndtri(0.5 + CONFIDENCE / 2.0)) * error
    with_failed = float((np.sum(terms) + np.sum(weights[~solved])) / len(margins))
    return ImportanceEstimate(estimate, error, max(estimate - half, 0.0), estimate + half, n, int((~solved).sum()),
                              max(with_failed, 0.0) + half)


def union_first_order(points: list[DesignPoint], count: int, seed: int) -> float:
    """P(breaking any of the limits) to first order: the union of the half-spaces grad g_k . (z - z*_k) < 0 (each
    limit linearised at its design point), by `count` draws from the mixture of N(z*_k, I), no solve."""
    centers = np.array([p.design_point for p in points])
    each = count // len(points)
    shifted = importance_points(np.zeros(centers.shape[1]), each * len(points), seed) + np.repeat(centers, each, axis=0)
    broken = np.any([(shifted - p.design_point) @ p.gradient < 0.0 for p in points], axis=0)
    return float(np.mean(np.where(broken, mixture_weights(shifted, centers), 0.0)))
