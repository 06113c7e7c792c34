"""Tolerances: how one hose as built deviates from its drawing, as coordinates, and the problem they give.

Every deviation is a value of one of the canonical coordinates (user units):

    start.x, start.y, start.z, end.x, end.y, end.z     mm, the fitting tips moved
    start.tilt_a, start.tilt_b, end.tilt_a, end.tilt_b  degrees, the fitting direction turned about
                                                        its two section axes a, b (rows 0, 1 of
                                                        frame_from_tangent(direction))
    hose.length                                         mm added to the length
    hose.bending                                        ln of the factor on EI (and GJ with it: the
                                                        torsion factor stays)
    hose.torsion                                        ln of the factor on the torsion factor (GJ)
    hose.mass                                           ln of the factor on the mass per length
    end.twist                                           degrees added to the twist at assembly

and, after them, five per clip of the problem (coordinate_names(clips)), in the problem's order:

    clips[k].x, clips[k].y, clips[k].z                  mm, the clip point moved
    clips[k].tilt_a, clips[k].tilt_b                    degrees, the clip's direction turned about its
                                                        two section axes (a ball clip has none)

A Tolerance maps its own dimensions of a point u of the unit hypercube onto some coordinates
by the inverse distribution function, so one code serves Monte Carlo and space-filling designs
alike; several tolerances on one parameter add up (a length tolerance and the change under
pressure).  A tolerance shared with other parameters of its kind (`shared_with`: a shared
contributor, e.g. the subframe both mounts sit on) adds the same deviation to each of them, so
they move together: their deviations are correlated, and Variation.covariance has the cross
terms; tolerances of any kinds are correlated by a matrix over their normal scores (a Gaussian
copula, correlation.py), applied by Variation.coordinates to the design's unit points.  Each also knows the mean and covariance of what it adds, for the first-order variance
(sensitivity.py).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace

import numpy as np
from scipy.special import ndtri

from hoseline.mechanics.rotations import frame_from_tangent, rotation_matrix
from hoseline.model.clips import Clip
from hoseline.model.mounts import Mount
from hoseline.model.problem import Problem
from hoseline.procedures.variation.correlation import (Correlation, correlated_unit, dimension_correlation,
                                                       induced_covariance)

COORDINATES = (
    "start.x", "start.y", "start.z", "start.tilt_a", "start.tilt_b",
    "end.x", "end.y", "end.z", "end.tilt_a", "end.tilt_b",
    "hose.length", "hose.bending", "hose.torsion", "hose.mass", "end.twist",
)
COORDINATE_UNITS = ("mm",) * 3 + ("deg",) * 2 + ("mm",) * 3 + ("deg",) * 2 + ("mm", "ln", "ln", "ln", "deg")
INDEX = {name: k for k, name in enumerate(COORDINATES)}
CLIP_COORDINATES = ("x", "y", "z", "tilt_a", "tilt_b")  # per clip, after COORDINATES
CLIP_UNITS = ("mm",) * 3 + ("deg",) * 2
_CLIP_PARAMETER = re.compile(r"clips\[(\d+)\]\.(point|direction)")


def coordinate_names(clips: int = 0) -> tuple[str, ...]:
    """The canonical coordinates of a problem with `clips` clips: COORDINATES, then five per clip."""
    return COORDINATES + tuple(f"clips[{k}].{name}" for k in range(clips) for name in CLIP_COORDINATES)


def coordinate_units(clips: int = 0) -> tuple[str, ...]:
    """The units of coordinate_names(clips)."""
    return COORDINATE_UNITS + CLIP_UNITS * clips


def clip_index(parameter: str) -> int | None:
    """k of a parameter "clips[k].point" or "clips[k].direction", None for the other parameters."""
    match = _CLIP_PARAMETER.fullmatch(parameter)
    return None if match is None else int(match.group(1))


def parameter_kind(parameter: str) -> tuple[str, tuple[int, ...]]:
    """(kind, indexes of the canonical coordinates it moves) of a study parameter (PARAMETERS, or a clip's
    "clips[k].point" / "clips[k].direction"); ValueError for an unknown one."""
    if parameter in PARAMETERS:
        kind, names = PARAMETERS[parameter]
        return kind, tuple(INDEX[name] for name in names)
    match = _CLIP_PARAMETER.fullmatch(parameter)
    if match is None:
        raise ValueError(f"unknown parameter {parameter!r}: choose one of {', '.join(PARAMETERS)}, "
                         "clips[k].point or clips[k].direction")
    first = len(COORDINATES) + len(CLIP_COORDINATES) * int(match.group(1))
    return ("point", (first, first + 1, first + 2)) if match.group(2) == "point" else ("tilt", (first + 3, first + 4))

Z95 = 1.959963984540054  # the standard normal's 97.5 % point: lognormal `factor` holds 95 % of the hoses

# parameter of the study file -> (kind, canonical coordinates it moves)
PARAMETERS = {
    "start.point": ("point", ("start.x", "start.y", "start.z")),
    "end.point": ("point", ("end.x", "end.y", "end.z")),
    "start.direction": ("tilt", ("start.tilt_a", "start.tilt_b")),
    "end.direction": ("tilt", ("end.tilt_a", "end.tilt_b")),
    "hose.length": ("offset", ("hose.length",)),
    "hose.bending_stiffness": ("factor", ("hose.bending",)),
    "hose.torsion_factor": ("factor", ("hose.torsion",)),
    "hose.mass_per_length": ("factor", ("hose.mass",)),
    "end.twist": ("offset", ("end.twist",)),
}

# kind -> distribution -> its parameters, in the order Tolerance.size holds them
DISTRIBUTIONS = {
    "point": {"normal": ("sigma_x", "sigma_y", "sigma_z"), "uniform": ("tolerance_x", "tolerance_y", "tolerance_z"),
              "sphere": ("radius",)},
    "tilt": {"cone": ("angle",), "normal": ("sigma",)},
    "offset": {"normal": ("sigma",), "uniform": ("low", "high"), "triangular": ("low", "mode", "high"),
               "truncnormal": ("mean", "sigma", "low", "high"), "empirical": ("values",)},
    "factor": {"lognormal": ("factor",), "loguniform": ("factor",), "uniform": ("low", "high"), "empirical": ("values",)},
}
MIN_EMPIRICAL_VALUES = 10  # measured values an empirical distribution needs (fewer give its quantiles too coarsely)
PER_AXIS = {"point": ("normal", "uniform"), "tilt": ("normal",)}  # distributions drawing each axis from its own score

_EDGE = 1e-12  # unit points are kept this far inside (0, 1): the normal's inverse is infinite at the ends


@dataclass(frozen=True)
class Tolerance:
    """One varied parameter and its distribution.

    parameter: a key of PARAMETERS, e.g. "end.point", or a clip's "clips[k].point" or
    "clips[k].direction" (k from 0, in the problem's order).  distribution: a key of
    DISTRIBUTIONS[kind].  size: the distribution's parameters (DISTRIBUTIONS names them), user
    units: mm for points and length offsets, degrees for tilts and twists, factors (> 0,
    dimensionless) for stiffness and mass.  label: for reports, e.g. "length change under pressure".

    normal: sigma.  uniform: offsets in [low, high], or +-tolerance per axis for a point, or a
    factor in [low, high].  sphere: uniform in a ball of the radius.  cone: the direction
    uniform over the spherical cap of the half angle.  lognormal: 95 % of the factors within
    [1/factor, factor].  loguniform: ln(factor) uniform within +-ln(factor).  triangular (offsets):
    the density rising linearly from low to mode and falling to high.  truncnormal (offsets): a normal
    of the mean (a process offset) and sigma, cut to [low, high].  empirical (offsets, factors): size holds
    measured values (at least MIN_EMPIRICAL_VALUES; deviations in the parameter's unit, or factors), drawn by
    their interpolated quantiles (the unit score u at position u (n - 1) of the sorted values, NumPy's
    "linear" quantile; a factor's in its logarithm).

    shared_with: other parameters of the same kind and unit that the same deviation moves (a
    shared contributor: e.g. "end.point" and "clips[0].point" with "start.point" for a subframe
    carrying all three; "hose.mass_per_length" with "hose.bending_stiffness" for a hose batch).
    axes: for a point, the world directions (3 orthonormal rows) of the axes its sizes are given along
    (fitting_axes: a fitting's two radial axes and its axis); empty: the world axes x, y, z.
    """

    parameter: str
    distribution: str
    size: tuple[float, ...]
    label: str = ""
    shared_with: tuple[str, ...] = ()
    axes: tuple[tuple[float, ...], ...] = ()

    def __post_init__(self) -> None:
        kind = self.kind  # raises for an unknown parameter
        if self.distribution not in DISTRIBUTIONS[kind]:
            raise ValueError(f"{self.parameter}: distribution {self.distribution!r} does not apply; choose one of "
                             f"{', '.join(DISTRIBUTIONS[kind])}")
        names = DISTRIBUTIONS[kind][self.distribution]
        size = tuple(float(v) for v in self.size)
        if self.distribution == "empirical":
            size = _measured(self.parameter, kind, size)
        elif len(size) != len(names) or not all(math.isfinite(v) for v in size):
            raise ValueError(f"{self.parameter}: {self.distribution} needs {', '.join(names)}, finite numbers")
        elif self.distribution == "uniform" and kind in ("offset", "factor"):
            if not size[0] < size[1]:
                raise ValueError(f"{self.parameter}: uniform range [{size[0]:g}, {size[1]:g}] must have low < high")
            if kind == "factor" and size[0] <= 0.0:
                raise ValueError(f"{self.parameter}: a factor range must stay positive, got low = {size[0]:g}")
        elif self.distribution == "triangular":
            if not size[0] <= size[1] <= size[2] or not size[0] < size[2]:
                raise ValueError(f"{self.parameter}: triangular low = {size[0]:g}, mode = {size[1]:g}, high = "
                                 f"{size[2]:g}: need low <= mode <= high and low < high")
        elif self.distribution == "truncnormal":
            if not size[1] > 0.0 or not size[2] < size[3]:
                raise ValueError(f"{self.parameter}: truncnormal sigma = {size[1]:g}, range [{size[2]:g}, {size[3]:g}]: "
                                 "need sigma > 0 and low < high")
        elif self.distribution in ("lognormal", "loguniform"):
            if not size[0] > 1.0:
                raise ValueError(f"{self.parameter}: factor = {size[0]:g} must be above 1 (e.g. 2 for a factor of two)")
        elif self.distribution == "cone":
            if not 0.0 < size[0] < 90.0:
                raise ValueError(f"{self.parameter}: cone angle = {size[0]:g} must lie in (0, 90) degrees")
        elif any(v < 0.0 for v in size) or max(size) == 0.0:  # the spreads: sigma, +-tolerance, radius
            given = ", ".join(f"{name} = {value:g}" for name, value in zip(names, size))
            raise ValueError(f"{self.parameter}: {self.distribution} {given}: each must be zero or positive, and not "
                             "all zero (a tolerance of zero everywhere varies nothing: remove the entry)")
        object.__setattr__(self, "size", size)
        shared = tuple(self.shared_with)
        if len(set(shared) | {self.parameter}) != len(shared) + 1:
            raise ValueError(f"{self.parameter}: shared_with = {list(shared)} lists a parameter twice, or the parameter "
                             "itself")
        units = _units(self.parameter)
        for other in shared:
            other_kind = parameter_kind(other)[0]  # raises for an unknown parameter
            if other_kind != kind or _units(other) != units:
                raise ValueError(f"{self.parameter}: shared_with {other}: a shared deviation moves parameters of one "
                                 f"kind and unit ({kind}, {', '.join(sorted(set(units)))}), {other} is "
                                 f"{other_kind} in {', '.join(sorted(set(_units(other))))}")
        object.__setattr__(self, "shared_with", shared)
        axes = tuple(tuple(float(v) for v in row) for row in self.axes)
        if axes:
            matrix = np.array(axes)
            if kind != "point" or matrix.shape != (3, 3) or not np.allclose(matrix @ matrix.T, np.eye(3), atol=1e-9):
                raise ValueError(f"{self.parameter}: axes must be three orthonormal rows, and only for a point")
        object.__setattr__(self, "axes", axes)

    @property
    def parameters(self) -> tuple[str, ...]:
        """The parameter and those it is shared with."""
        return (self.parameter, *self.shared_with)

    @property
    def targets(self) -> tuple[tuple[int, ...], ...]:
        """Per parameter moved (parameters), the indexes into coordinate_names(clips) its deviation adds to."""
        return tuple(parameter_kind(parameter)[1] for parameter in self.parameters)

    @property
    def per_axis(self) -> bool:
        """Whether each of its axes is drawn from its own unit score alone (offsets, factors; normal and uniform
        points; normal tilts), so that it can be correlated axis by axis (correlation.py)."""
        return self.kind not in PER_AXIS or self.distribution in PER_AXIS[self.kind]

    @property
    def kind(self) -> str:
        """point, tilt, offset or factor."""
        return parameter_kind(self.parameter)[0]

    @property
    def coordinates(self) -> tuple[int, ...]:
        """Indexes into coordinate_names(clips) of what this tolerance moves."""
        return parameter_kind(self.parameter)[1]

    @property
    def dimensions(self) -> int:
        """How many dimensions of the unit hypercube it takes."""
        return {"point": 3, "tilt": 2}.get(self.kind, 1)

    @property
    def name(self) -> str:
        """The label, or parameter and distribution."""
        return self.label or f"{' + '.join(self.parameters)} ({self.distribution}{', shared' if self.shared_with else ''})"

    def values(self, unit: np.ndarray) -> np.ndarray:
        """(n, len(coordinates)) coordinate values of (n, dimensions) unit points in (0, 1) (in the world axes)."""
        values = self.along_axes(unit)
        return values @ np.array(self.axes) if self.axes else values

    def mean(self) -> np.ndarray:
        """(len(coordinates),) mean of what it adds (in the world axes)."""
        mean = self._mean_along_axes()
        return mean @ np.array(self.axes) if self.axes else mean

    def covariance(self) -> np.ndarray:
        """(k, k) covariance of what it adds (k = len(coordinates); in the world axes)."""
        covariance = self._covariance_along_axes()
        if not self.axes:
            return covariance
        axes = np.array(self.axes)
        return axes.T @ covariance @ axes

    def along_axes(self, unit: np.ndarray) -> np.ndarray:
        """values() along the tolerance's own axes."""
        u = np.clip(np.asarray(unit, dtype=float), _EDGE, 1.0 - _EDGE)
        size = np.array(self.size)
        if self.distribution == "normal":
            return size * ndtri(u) if self.kind == "point" else size[0] * ndtri(u)
        if self.distribution == "uniform":
            if self.kind == "point":
                return size * (2.0 * u - 1.0)
            low, high = size
            values = low + (high - low) * u
            return np.log(values) if self.kind == "factor" else values
        if self.distribution == "sphere":
            polar = 2.0 * u[:, 0] - 1.0
            azimuth = 2.0 * math.pi * u[:, 1]
            radius = size[0] * np.cbrt(u[:, 2])
            ring = np.sqrt(1.0 - polar**2)
            return radius[:, None] * np.column_stack([ring * np.cos(azimuth), ring * np.sin(azimuth), polar])
        if self.distribution == "cone":
            azimuth = 2.0 * math.pi * u[:, 0]
            angle = np.degrees(np.arccos(1.0 - u[:, 1] * (1.0 - math.cos(math.radians(size[0])))))
            return angle[:, None] * np.column_stack([np.cos(azimuth), np.sin(azimuth)])
        if self.distribution == "lognormal":
            return math.log(size[0]) / Z95 * ndtri(u)
        if self.distribution == "triangular":
            low, mode, high = size
            rising = u < (mode - low) / (high - low)
            return np.where(rising, low + np.sqrt(u * (high - low) * (mode - low)),
                            high - np.sqrt((1.0 - u) * (high - low) * (high - mode)))
        if self.distribution == "truncnormal":
            return _truncated(size).ppf(u)
        if self.distribution == "empirical":
            knots = self._empirical_knots()
            return np.interp(u * (knots.size - 1), np.arange(knots.size), knots)
        return math.log(size[0]) * (2.0 * u - 1.0)  # loguniform

    def _empirical_knots(self) -> np.ndarray:
        """The sorted measured values of an empirical tolerance (ln of them for a factor), between which its inverse
        distribution function interpolates: the unit score u lands at position u (n - 1) of the n knots."""
        values = np.array(self.size)
        return np.log(values) if self.kind == "factor" else values

    def _mean_along_axes(self) -> np.ndarray:
        """mean() along the tolerance's own axes."""
        if self.distribution == "uniform" and self.kind == "offset":
            return np.array([0.5 * sum(self.size)])
        if self.distribution == "uniform" and self.kind == "factor":
            low, high = self.size
            return np.array([(high * math.log(high) - high - low * math.log(low) + low) / (high - low)])
        if self.distribution == "triangular":
            return np.array([sum(self.size) / 3.0])
        if self.distribution == "truncnormal":
            return np.array([float(_truncated(self.size).mean())])
        if self.distribution == "empirical":
            knots = self._empirical_knots()
            return np.array([float(np.mean(0.5 * (knots[1:] + knots[:-1])))])  # the mean of each linear piece
        return np.zeros(len(self.coordinates))

    def _covariance_along_axes(self) -> np.ndarray:
        """covariance() along the tolerance's own axes: the components are uncorrelated there."""
        size = np.array(self.size)
        k = len(self.coordinates)
        if self.distribution == "normal":
            return np.diag(size**2) if self.kind == "point" else np.eye(k) * size[0] ** 2
        if self.distribution == "uniform":
            if self.kind == "point":
                return np.diag(size**2 / 3.0)
            low, high = size
            if self.kind == "offset":
                return np.array([[(high - low) ** 2 / 12.0]])
            second = _integral_log_squared(high) - _integral_log_squared(low)
            return np.array([[second / (high - low) - self.mean()[0] ** 2]])
        if self.distribution == "sphere":
            return np.eye(3) * size[0] ** 2 / 5.0
        if self.distribution == "cone":
            alpha = math.radians(size[0])
            # E[theta^2] for theta with density sin(theta) / (1 - cos(alpha)) on [0, alpha]
            second = (2.0 * alpha * math.sin(alpha) + (2.0 - alpha**2) * math.cos(alpha) - 2.0) / (1.0 - math.cos(alpha))
            return np.eye(2) * math.degrees(1.0) ** 2 * second / 2.0
        if self.distribution == "lognormal":
            return np.array([[(math.log(size[0]) / Z95) ** 2]])
        if self.distribution == "triangular":
            low, mode, high = size
            return np.array([[(low**2 + mode**2 + high**2 - low * mode - low * high - mode * high) / 18.0]])
        if self.distribution == "truncnormal":
            return np.array([[float(_truncated(self.size).var())]])
        if self.distribution == "empirical":
            a, b = self._empirical_knots()[:-1], self._empirical_knots()[1:]
            second = float(np.mean((a * a + a * b + b * b) / 3.0))  # E[X^2] of each linear piece, equally likely
            return np.array([[second - self.mean()[0] ** 2]])
        return np.array([[math.log(size[0]) ** 2 / 3.0]])  # loguniform


def _measured(parameter: str, kind: str, values: tuple[float, ...]) -> tuple[float, ...]:
    """The measured values of an empirical tolerance, checked (enough, finite, factors positive, not all equal)
    and sorted."""
    if len(values) < MIN_EMPIRICAL_VALUES or not all(math.isfinite(v) for v in values):
        raise ValueError(f"{parameter}: empirical needs at least {MIN_EMPIRICAL_VALUES} measured values, finite "
                         f"numbers; got {len(values)}" + ("" if all(math.isfinite(v) for v in values) else
                                                         " with some not finite"))
    if kind == "factor" and min(values) <= 0.0:
        raise ValueError(f"{parameter}: empirical factors must be positive (measured over nominal, e.g. 1.05), got "
                         f"{min(values):g}")
    if min(values) == max(values):
        raise ValueError(f"{parameter}: empirical values are all {values[0]:g}: they vary nothing; remove the entry")
    return tuple(sorted(values))


def _truncated(size: tuple[float, ...]):
    """scipy.stats' frozen truncated normal of a truncnormal tolerance's size (mean, sigma, low, high)."""
    from scipy.stats import truncnorm  # here: the workers, which never draw, need not import scipy.stats

    mean, sigma, low, high = size
    return truncnorm((low - mean) / sigma, (high - mean) / sigma, loc=mean, scale=sigma)


def _units(parameter: str) -> tuple[str, ...]:
    """The units of the coordinates a parameter moves."""
    clip = clip_index(parameter)
    units = coordinate_units(0 if clip is None else clip + 1)
    return tuple(units[k] for k in parameter_kind(parameter)[1])


def _integral_log_squared(x: float) -> float:
    """An antiderivative of ln(x)^2: x (ln^2 x - 2 ln x + 2)."""
    log = math.log(x)
    return x * (log * log - 2.0 * log + 2.0)


@dataclass(frozen=True)
class Variation:
    """All tolerances of a study, each with its own dimensions of the unit hypercube, in order.

    clips: the number of clips of the problem varied (its coordinates: coordinate_names(clips)).
    correlations: Gaussian copulas between tolerances (correlation.py), each tolerance in one at most; those
    of one correlation have as many axes each and draw each axis from its own score (Tolerance.per_axis).
    """

    tolerances: tuple[Tolerance, ...]
    clips: int = 0
    correlations: tuple[Correlation, ...] = ()

    def __post_init__(self) -> None:
        for tolerance in self.tolerances:
            for parameter in tolerance.parameters:
                k = clip_index(parameter)
                if k is not None and k >= self.clips:
                    raise ValueError(f"{parameter}: the problem has {self.clips} clip(s), numbered from 0")
        seen: set[int] = set()
        for correlation in self.correlations:
            members = correlation.tolerances
            if max(members) >= len(self.tolerances) or min(members) < 0:
                raise ValueError(f"tolerances {list(members)}: there are {len(self.tolerances)} tolerances")
            if seen & set(members):
                raise ValueError(f"tolerances: {self.tolerances[min(seen & set(members))].name} is in two correlations: "
                                 "give one matrix over all the tolerances correlated with it")
            seen |= set(members)
            for k in members:
                tolerance = self.tolerances[k]
                if not tolerance.per_axis:
                    raise ValueError(f"tolerances: {tolerance.name} (a {tolerance.distribution}) draws its axes together, "
                                     "they cannot be correlated axis by axis; use a normal or uniform distribution per "
                                     "axis, or shared_with")
                if tolerance.dimensions != self.tolerances[members[0]].dimensions:
                    raise ValueError(f"tolerances: {tolerance.name} has {tolerance.dimensions} axes, "
                                     f"{self.tolerances[members[0]].name} {self.tolerances[members[0]].dimensions}: "
                                     "tolerances are correlated axis by axis, so only with as many axes")

    @property
    def width(self) -> int:
        """How many canonical coordinates a deviation has: len(coordinate_names(clips))."""
        return len(COORDINATES) + len(CLIP_COORDINATES) * self.clips

    @property
    def names(self) -> tuple[str, ...]:
        """The canonical coordinates, coordinate_names(clips)."""
        return coordinate_names(self.clips)

    @property
    def units(self) -> tuple[str, ...]:
        """Their units, coordinate_units(clips)."""
        return coordinate_units(self.clips)

    @property
    def dimensions(self) -> int:
        """Dimensions of the unit hypercube (the design's columns)."""
        return sum(t.dimensions for t in self.tolerances)

    @property
    def varied(self) -> tuple[int, ...]:
        """Indexes of the canonical coordinates some tolerance moves, in COORDINATES order."""
        return tuple(sorted({k for t in self.tolerances for target in t.targets for k in target}))

    def coordinates(self, unit: np.ndarray) -> np.ndarray:
        """(n, width) deviations of the hoses at unit points (n, dimensions)."""
        unit = np.atleast_2d(np.asarray(unit, dtype=float))
        if self.correlations:
            unit = correlated_unit(unit, self.cholesky())
        out = np.zeros((unit.shape[0], self.width))
        column = 0
        for tolerance in self.tolerances:
            values = tolerance.values(unit[:, column:column + tolerance.dimensions]).reshape(unit.shape[0], -1)
            for target in tolerance.targets:
                out[:, list(target)] += values
            column += tolerance.dimensions
        return out

    def mean(self) -> np.ndarray:
        """(width,) mean deviation."""
        out = np.zeros(self.width)
        for tolerance in self.tolerances:
            for target in tolerance.targets:
                out[list(target)] += tolerance.mean()
        return out

    def cholesky(self) -> np.ndarray:
        """(dimensions, dimensions) lower Cholesky factor of the normal scores' correlation (correlation.py)."""
        return np.linalg.cholesky(dimension_correlation(self.correlations, tuple(t.dimensions for t in self.tolerances)))

    def covariance(self) -> np.ndarray:
        """(width, width) covariance of the deviations (a shared tolerance gives the same block between every two
        parameters it moves; two correlated ones their induced covariance between each of their parameters)."""
        out = np.zeros((self.width, self.width))
        for tolerance in self.tolerances:
            _add_block(out, tolerance, tolerance, tolerance.covariance())
        for correlation in self.correlations:
            for a, i in enumerate(correlation.tolerances):
                for b, j in enumerate(correlation.tolerances):
                    if a != b:
                        first, second = self.tolerances[i], self.tolerances[j]
                        own = induced_covariance(first, second, correlation.matrix[a][b])
                        _add_block(out, first, second, _world_axes(first).T @ own @ _world_axes(second))
        return out


def _world_axes(tolerance: Tolerance) -> np.ndarray:
    """(k, k) the tolerance's own axes as rows in the world axes (the identity when it has none given)."""
    return np.array(tolerance.axes) if tolerance.axes else np.eye(len(tolerance.coordinates))


def _add_block(out: np.ndarray, first: Tolerance, second: Tolerance, block: np.ndarray) -> None:
    """Add the covariance `block` between the deviations of two tolerances to `out` at every pair of their targets."""
    for one in first.targets:
        for other in second.targets:
            out[np.ix_(one, other)] += block


def tilt_axes(direction: np.ndarray) -> np.ndarray:
    """(2, 3) the axes a, b a fitting direction is tilted about (unit, perpendicular to it and each other)."""
    return frame_from_tangent(direction)[:2]


def fitting_axes(direction: np.ndarray) -> tuple[tuple[float, ...], ...]:
    """The axes of a point tolerance in a fitting's frame: its two radial axes a, b (tilt_axes) and its axis (the
    unit direction), as Tolerance.axes rows."""
    direction = np.asarray(direction, dtype=float)
    rows = np.vstack([tilt_axes(direction), direction / np.linalg.norm(direction)])
    return tuple(tuple(float(v) for v in row) for row in rows)


def _tilted(mount: Mount, offset: np.ndarray, tilt_deg: np.ndarray) -> Mount:
    """The mount moved by `offset` (mm) and its direction turned by `tilt_deg` about its tilt axes."""
    return Mount(mount.point + offset, _turned(mount.direction, tilt_deg))


def _turned(direction: np.ndarray, tilt_deg: np.ndarray) -> np.ndarray:
    """A unit direction turned by `tilt_deg` (degrees) about its two tilt axes."""
    if np.any(tilt_deg != 0.0):
        return rotation_matrix(np.radians(tilt_deg) @ tilt_axes(direction)) @ direction
    return direction


def _moved_clips(clips: tuple[Clip, ...], deviation: np.ndarray, stretch: float) -> tuple[Clip, ...]:
    """The clips moved by their coordinates in `deviation` (five per clip after COORDINATES; none: unmoved), their
    arc lengths times `stretch` (the hose's length over the nominal: a longer hose is longer all along, so each clip
    holds the same station)."""
    moved = []
    for k, clip in enumerate(clips):
        clip = replace(clip, arc_length=clip.arc_length * stretch)
        first = len(COORDINATES) + len(CLIP_COORDINATES) * k
        if deviation.size <= first:
            moved.append(clip)
            continue
        offset, tilt = deviation[first:first + 3], deviation[first + 3:first + 5]
        if clip.direction is None and np.any(tilt != 0.0):
            raise ValueError(f"clips[{k}].direction: a ball clip holds no direction to vary")
        direction = None if clip.direction is None else _turned(clip.direction, tilt)
        moved.append(replace(clip, point=clip.point + offset, direction=direction))
    return tuple(moved)


def perturbed(problem: Problem, deviation: np.ndarray) -> Problem:
    """The problem of a hose with the deviations `deviation` ((15,) or (15 + 5 clips,), user units) from `problem`.

    Raises ValueError when the hose no longer reaches its mounts or clips (the Problem's own check).
    """
    c = np.asarray(deviation, dtype=float)
    hose = problem.hose
    bending = math.exp(c[INDEX["hose.bending"]])
    second = None if hose.bending_stiffness_2 is None else hose.bending_stiffness_2 * bending
    hose = replace(
        hose,
        length=hose.length + c[INDEX["hose.length"]],
        bending_stiffness=hose.bending_stiffness * bending,
        bending_stiffness_2=second,
        torsional_stiffness=hose.torsional_stiffness * bending * math.exp(c[INDEX["hose.torsion"]]),
        mass_per_length=hose.mass_per_length * math.exp(c[INDEX["hose.mass"]]),
    )
    return replace(
        problem,
        hose=hose,
        start=_tilted(problem.start, c[0:3], c[3:5]),
        end=_tilted(problem.end, c[5:8], c[8:10]),
        end_twist_deg=problem.end_twist_deg + c[INDEX["end.twist"]],
        clips=_moved_clips(problem.clips, c, hose.length / problem.hose.length),
    )
