"""Read study files (TOML): a problem or sweep file, the tolerances, the sampling, the limits, a design search.

    name = "brake hose as built"       # optional, default the file name
    base = "problem.toml"              # a problem file, or a sweep file ([[bodies]]), relative to this file
    sensitivities = true               # optional: derivatives and first-order variance
    worst_case = false                 # optional: each quantity at its worst corner of the tolerances (needs the
                                       #   sensitivities; unbounded distributions at +-3 standard deviations)

    [sampling]
    method = "sobol"                   # "monte-carlo", "latin-hypercube" or "sobol"
    samples = 1024
    seed = 1
    batch = 64                         # optional: samples per task
    start = "straight"                 # or "nominal": Newton from the nominal hose (placements; checked)
    precision = { quantity = "bend_radius", statistic = "P5", half_width = 0.1, max_samples = 16384 }
                                       # optional: rounds (samples the first) until the 95 % interval of the
                                       #   statistic ("mean" or "P<p>") is within +-half_width (the quantity's
                                       #   unit), or max_samples (then said so)

    [[vary]]                           # one per tolerance; several on one parameter add up
    parameter = "end.point"            # start.point, end.point: mm
    distribution = "sphere"            #   normal (sigma), uniform (tolerance: +-mm), sphere (radius)
    radius = 1.0                       #   sigma and tolerance: one number or one per axis [x, y, z], or with
                                       #   frame = "fitting" along the fitting's radial axes a, b and its axis
    [[vary]]
    parameter = "end.direction"        # start.direction, end.direction: degrees of cone
    distribution = "cone"              #   cone (angle: uniform within it), normal (sigma per axis)
    angle = 2.0
    [[vary]]
    parameter = "clips[0].point"       # a clip of the base, numbered from 0 in its order: clips[k].point (mm, as
    distribution = "sphere"            #   start.point) and clips[k].direction (degrees, as end.direction; not for
    radius = 0.5                       #   a ball clip)
    [[vary]]
    parameter = "hose.length"          # mm, or unit = "%" of the length
    distribution = "uniform"           #   normal (sigma), uniform (range = [low, high])
    range = [-4.0, 2.0]
    unit = "%"
    label = "length change under pressure"
    [[vary]]
    parameter = "hose.bending_stiffness"   # also hose.torsion_factor, hose.mass_per_length: factors
    distribution = "lognormal"         #   lognormal (factor: 95 % within [1/f, f]), loguniform (factor),
    factor = 2.0                       #   uniform (range = [low, high] of the factor)
    [[vary]]
    parameter = "end.twist"            # degrees: normal (sigma), uniform (range); offsets (length, twist)
    distribution = "normal"            #   also triangular (range and mode) and truncnormal (sigma, range and
    sigma = 3.0                        #   optionally mean: a process offset), as for hose.length
    [[vary]]
    parameter = "start.point"          # a shared contributor: the same deviation moves every parameter listed
    shared_with = ["end.point"]        #   (same kind and unit), e.g. the subframe both mounts sit on
    distribution = "normal"
    sigma = 0.5
    [[vary]]
    parameter = "hose.length"          # offsets and factors: measured values (at least 10, interpolated quantiles)
    distribution = "empirical"         #   values = [...] (the parameter's unit, or factors; unit = "%" too), or
    file = "lengths.csv"               #   file = a CSV relative to this file: one number per row, or a header and
    column = "deviation_mm"            #   column = the one to use
    label = "measured length"

    [[correlation]]                    # optional: a Gaussian copula between tolerances of any kind, named by label
    tolerances = ["measured length", "hose.bending_stiffness"]  # (or parameter of one [[vary]] alone); points
    matrix = [[1.0, 0.6], [0.6, 1.0]]  #   and directions axis by axis; symmetric, unit diagonal, in [-1, 1],
                                       #   positive definite

    [[obstacles]]                      # optional, a placement's base only (a sweep's are in the sweep file):
    name = "bracket"                   #   fixed obstacles the clearance is measured to (a quantity each,
    file = "bracket.stl"               #   clearance:NAME; the placement does not see them); as a sweep file's
    clearance = 5.0                    #   [[obstacles]] without body

    [limits]                           # each optional
    bend_radius = 35.0                 # mm, at least (default: the hose's min_bend_radius)
    clearance = 20.0                   # mm, at least, every obstacle (default: each obstacle's clearance)
    "clearance:strut" = 15.0           # one obstacle
    end_torque = 2000.0                # N*mm, at most
    twist_rate = 0.1                   # deg/mm, at most
    "force:end" = 50.0                 # N, at most: the force of a support on the hose (start, end, clips[k])
    "moment:clips[0]" = 900.0          # N*mm, at most: its moment (not for a ball clip)
    deviation = 10.0                   # mm from the nominal shape, at most

    [design]                           # optional: which length and clocking to choose
    lengths = [320.0, 345.0]           # mm, from and to, in catalogue steps of
    length_step = 5.0                  # mm
    clockings = [-90.0, 90.0]          # degrees of twist at assembly, from and to, in steps of
    clocking_step = 15.0               # degrees
    samples = 0                        # tolerance samples judged per candidate (0: the nominal hose)
    rank_by = "clearance:strut"        # optional: the limited quantity whose margin ranks the candidates
    rank_on = "nominal"                # or "p95_margin": by the 5th percentile of that margin over the
                                       #   tolerances, first order at each candidate (needs [[vary]])
    method = "grid"                    # or "optimise": per length, the best clocking between grid points

    [reliability]                      # optional: rare failures (FORM, SORM, importance sampling)
    method = "form"                    # or "sorm": FORM with Breitung's curvature correction
    importance_samples = 100           # samples around each design point checking it (0: none)
    limits = ["end_torque"]            # optional: which limits (default: every limit but the deviation)
    seed = 0                           # of the importance samples

    [sobol]                            # optional: Sobol' first-order and total indices per tolerance
    samples = 256                      # N base rows of the Saltelli design: N (tolerances + 2) hoses
    seed = 0

Errors name the field, the value and the fix, as for problem files.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import AfterValidator, ConfigDict, Field, model_validator

from hoseline.io.measured_values import read_measured_values
from hoseline.io.problem_file import ProblemFileError, _Section, _validated, load_problem, read_toml
from hoseline.io.sweep_file import ObstacleSection, _obstacle
from hoseline.procedures.variation.correlation import Correlation
from hoseline.procedures.variation.design_search import DesignGrid, default_rank_by
from hoseline.procedures.variation.fixed_obstacles import FixedObstacles
from hoseline.procedures.variation.precision import Precision
from hoseline.procedures.variation.quantities import CLEARANCE, Limit, quantities
from hoseline.procedures.variation.rare import Reliability
from hoseline.procedures.variation.samples import StudyBase
from hoseline.procedures.variation.study import GlobalSensitivity, Sampling, Study
from hoseline.procedures.variation.tolerances import (DISTRIBUTIONS, PARAMETERS, Tolerance, Variation, clip_index,
                                                      fitting_axes, parameter_kind)

MAX_SAMPLES = 10_000_000  # beyond this the stored samples would not fit in memory
MAX_CANDIDATES = 100_000
SIZE_KEYS = ("sigma", "tolerance", "radius", "angle", "range", "factor", "mode", "mean", "values", "file",
             "column")  # of [[vary]]


class StudyFileError(ProblemFileError):
    """A study file that cannot describe a study; the message names the field, the value and the fix."""


def _positive(value: float) -> float:
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError("must be a positive number")
    return value


def _pair(value: list[float]) -> list[float]:
    if len(value) != 2 or not all(math.isfinite(v) for v in value) or value[0] > value[1]:
        raise ValueError("must be [from, to], two finite numbers with from <= to")
    return value


Pair = Annotated[list[float], AfterValidator(_pair)]
Positive = Annotated[float, AfterValidator(_positive)]


class PrecisionSection(_Section):
    """[sampling.precision]: sample in rounds until a statistic's 95 % interval is this narrow."""

    quantity: str
    statistic: str = "mean"
    half_width: float
    max_samples: Annotated[int, Field(ge=1, le=MAX_SAMPLES)]


class SamplingSection(_Section):
    """[sampling]: method, samples, seed, batch, start, precision."""

    method: Literal["monte-carlo", "latin-hypercube", "sobol"] = "sobol"
    samples: Annotated[int, Field(ge=0, le=MAX_SAMPLES)] = 256
    seed: Annotated[int, Field(ge=0)] = 0
    batch: Annotated[int, Field(ge=1)] | None = None
    start: Literal["straight", "nominal"] = "straight"
    precision: PrecisionSection | None = None


class VarySection(_Section):
    """[[vary]]: one tolerance."""

    parameter: str
    distribution: str
    sigma: float | list[float] | None = None
    tolerance: float | list[float] | None = None
    radius: float | None = None
    angle: float | None = None
    range: list[float] | None = None
    factor: float | None = None
    mode: float | None = None
    mean: float | None = None
    values: list[float] | None = None
    file: str | None = None
    column: str | None = None
    unit: Literal["mm", "%"] = "mm"
    label: str = ""
    shared_with: list[str] = Field(default_factory=list)
    frame: Literal["world", "fitting"] = "world"


class CorrelationSection(_Section):
    """[[correlation]]: a correlation matrix between tolerances named by their label or parameter."""

    tolerances: list[str]
    matrix: list[list[float]]


class DesignSection(_Section):
    """[design]: the grid of lengths and clockings."""

    lengths: Pair
    length_step: Positive
    clockings: Pair = Field(default_factory=lambda: [0.0, 0.0])
    clocking_step: Positive = 15.0
    samples: Annotated[int, Field(ge=0)] = 0
    rank_by: str | None = None
    rank_on: Literal["nominal", "p95_margin"] = "nominal"
    method: Literal["grid", "optimise"] = "grid"


class ReliabilitySection(_Section):
    """[reliability]: FORM or SORM of the limits, checked by importance sampling."""

    method: Literal["form", "sorm"] = "form"
    importance_samples: Annotated[int, Field(ge=0, le=MAX_SAMPLES)] = 100
    limits: list[str] = Field(default_factory=list)
    seed: Annotated[int, Field(ge=0)] = 0


class SobolSection(_Section):
    """[sobol]: the Saltelli design of the Sobol' indices."""

    samples: Annotated[int, Field(ge=8, le=MAX_SAMPLES)] = 256
    seed: Annotated[int, Field(ge=0)] = 0


class StudyFile(_Section):
    """The whole study file."""

    model_config = ConfigDict(extra="forbid", strict=True)

    name: str = "study"
    base: str
    sensitivities: bool = True
    worst_case: bool = False
    sampling: SamplingSection = Field(default_factory=SamplingSection)
    vary: list[VarySection] = Field(default_factory=list)
    correlation: list[CorrelationSection] = Field(default_factory=list)
    obstacles: list[ObstacleSection] = Field(default_factory=list)
    limits: dict[str, float] = Field(default_factory=dict)
    design: DesignSection | None = None
    reliability: ReliabilitySection | None = None
    sobol: SobolSection | None = None

    @model_validator(mode="after")
    def _something_to_do(self) -> "StudyFile":
        if not self.vary and self.design is None:
            raise ValueError("nothing to study: give [[vary]] tolerances, a [design] search, or both")
        return self


def load_study(path: str | Path) -> tuple[Study, str, Path]:
    """Read a study file and its base file; returns the Study, the base file's text (for the fingerprint) and path.

    Raises StudyFileError naming the field, the value and the fix, and OSError when the study file
    itself cannot be read.
    """
    path = Path(path)
    data = read_toml(path, StudyFileError)
    spec = _validated(StudyFile, data, str(path), error=StudyFileError)
    base_path = path.parent / spec.base
    base, text = _base(base_path, str(path), spec.base)
    if spec.obstacles:
        base = _with_obstacles(base, spec.obstacles, path)
    tolerances = tuple(_tolerance(item, k, base, path) for k, item in enumerate(spec.vary))
    variation = Variation(tolerances, clips=len(base.problem.clips))
    if spec.correlation:
        variation = _correlated(variation, spec.correlation, spec.vary, str(path))
    if any(clip.kind == "sliding" for clip in base.problem.clips) and spec.sampling.start == "nominal":
        raise StudyFileError(f"{path}: sampling.start = \"nominal\" with a sliding clip in the base: the warm start "
                             "from the nominal hose does not carry sliding clips (the placement moves one to the "
                             "nearest station at its end); use start = \"straight\" (the published placement)")
    limits = _limits(spec.limits, base, str(path))
    precision = _precision(spec.sampling, base, str(path)) if spec.sampling.precision and spec.vary else None
    sampling = Sampling(spec.sampling.method, spec.sampling.samples if spec.vary else 0, spec.sampling.seed,
                        spec.sampling.batch, spec.sampling.start, precision)
    if spec.vary and sampling.count == 0:
        raise StudyFileError(f"{path}: sampling.samples = 0 with [[vary]] tolerances: give at least 1 sample")
    design = _design(spec.design, base, limits, sampling, str(path)) if spec.design else None
    reliability = _reliability(spec.reliability, base, variation, limits, str(path)) if spec.reliability else None
    if spec.sobol is not None and not spec.vary:
        raise StudyFileError(f"{path}: [sobol] needs [[vary]] tolerances: give some, or remove [sobol]")
    sobol = GlobalSensitivity(spec.sobol.samples, spec.sobol.seed) if spec.sobol is not None else None
    if spec.worst_case and not (spec.vary and spec.sensitivities):
        raise StudyFileError(f"{path}: worst_case = true needs [[vary]] tolerances and sensitivities = true (the corner "
                             "of each quantity follows its derivatives): give them, or remove worst_case")
    study = Study(spec.name, base, variation, sampling, limits, spec.sensitivities, design, reliability, sobol,
                  spec.worst_case)
    return study, text, base_path


def _base(path: Path, source: str, given: str) -> tuple[StudyBase, str]:
    """The StudyBase of a problem or sweep file, and its text."""
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise StudyFileError(f"{source}: base = \"{given}\": cannot read {path}: {exc.strerror or exc}") from None
    try:
        if "bodies" in read_toml(path, ProblemFileError):
            from hoseline.io.sweep_file import load_sweep  # here: its meshes' library is for sweeps alone

            sweep = load_sweep(path)
            return StudyBase(sweep.problem, sweep), text
        return StudyBase(load_problem(path)), text
    except ProblemFileError as exc:
        raise StudyFileError(f"{source}: base = \"{given}\": {exc}") from None


def _with_obstacles(base: StudyBase, sections: list[ObstacleSection], path: Path) -> StudyBase:
    """The placement base with the fixed obstacles of [[obstacles]] (their meshes read, relative to the study file)."""
    source = str(path)
    if base.sweep is not None:
        raise StudyFileError(f"{source}: [[obstacles]] with a sweep file as the base: a sweep's obstacles are its "
                             "own; give them in the sweep file's [[obstacles]] and remove them here")
    for k, section in enumerate(sections):
        if section.body is not None:
            raise StudyFileError(f"{source}: obstacles[{k}].body = \"{section.body}\": a placement study's obstacles "
                                 "are fixed; remove body (or study a sweep file, whose obstacles move with bodies)")
    try:
        obstacles = tuple(_obstacle(section, path.parent, source) for section in sections)
    except ProblemFileError as exc:
        raise StudyFileError(str(exc)) from None
    names = [o.name for o in obstacles]
    for k, name in enumerate(names):
        if name in names[:k]:
            raise StudyFileError(f"{source}: obstacles[{k}].name = \"{name}\" is used by an earlier obstacle: give "
                                 "each obstacle its own name")
    return StudyBase(base.problem, obstacles=FixedObstacles(obstacles))


def _scalar(value, name: str) -> float:
    """One finite number (the scalar form of a per-axis key)."""
    if isinstance(value, list):
        raise ValueError(f"{name} must be one number here, not a list")
    return float(value)


def _tolerance(item: VarySection, k: int, base: StudyBase, source: Path) -> Tolerance:
    """The Tolerance of one [[vary]] entry (source: the study file; a file of measured values is relative to it)."""
    where = f"{source}: vary[{k}] ({item.parameter})"
    try:
        kind = parameter_kind(item.parameter)[0]
    except ValueError:
        raise StudyFileError(f"{source}: vary[{k}].parameter = \"{item.parameter}\": unknown; choose one of "
                             f"{', '.join(PARAMETERS)}, clips[k].point or clips[k].direction") from None
    for j, parameter in enumerate(item.shared_with):
        try:
            parameter_kind(parameter)
        except ValueError:
            raise StudyFileError(f"{source}: vary[{k}].shared_with[{j}] = \"{parameter}\": unknown; choose one of "
                                 f"{', '.join(PARAMETERS)}, clips[k].point or clips[k].direction") from None
    clips = base.problem.clips
    for parameter in (item.parameter, *item.shared_with):
        clip = clip_index(parameter)
        if clip is not None and clip >= len(clips):
            raise StudyFileError(f"{where}: {parameter}: the base has {len(clips)} clip(s), numbered from 0: give "
                                 f"clips[0] to clips[{len(clips) - 1}]" if clips else f"{where}: the base has no clips")
        if clip is not None and kind == "tilt" and not clips[clip].holds_direction:
            raise StudyFileError(f"{where}: clip {clip} is a ball clip: it holds the position only, vary "
                                 f"clips[{clip}].point")
    if item.distribution not in DISTRIBUTIONS[kind]:
        raise StudyFileError(f"{where}: distribution = \"{item.distribution}\" does not apply; choose one of "
                             f"{', '.join(DISTRIBUTIONS[kind])}")
    needed = {"normal": ("sigma",), "uniform": ("tolerance",) if kind == "point" else ("range",), "sphere": ("radius",),
              "cone": ("angle",), "lognormal": ("factor",), "loguniform": ("factor",), "triangular": ("range", "mode"),
              "truncnormal": ("sigma", "range"), "empirical": ("file",) if item.file is not None else ("values",)
              }[item.distribution]
    optional = {"truncnormal": ("mean",), "empirical": ("column",) if item.file is not None else ()}.get(item.distribution, ())
    given = [key for key in SIZE_KEYS if getattr(item, key) is not None]
    missing = [key for key in needed if key not in given]
    extra = [key for key in given if key not in needed + optional]
    if missing or extra:
        fix = "; ".join(part for part in (f"remove {', '.join(extra)}" if extra else "",
                                          f"give {', '.join(missing)}" if missing else "") if part)
        also = f" (and optionally {', '.join(optional)})" if optional else ""
        article = "an" if item.distribution[0] in "aeiou" else "a"
        raise StudyFileError(f"{where}: {article} {item.distribution} distribution takes {' and '.join(needed)}{also} only: {fix}")
    axes = ()
    if item.frame == "fitting":
        if kind != "point":
            raise StudyFileError(f"{where}: frame = \"fitting\" applies to points (start.point, end.point, "
                                 "clips[k].point): remove it")
        clip = clip_index(item.parameter)
        direction = {"start.point": base.problem.start.direction, "end.point": base.problem.end.direction}.get(
            item.parameter, None if clip is None else clips[clip].direction)
        if direction is None:
            raise StudyFileError(f"{where}: frame = \"fitting\": clip {clip} is a ball clip, it has no axis: use "
                                 "frame = \"world\"")
        axes = fitting_axes(direction)
    if item.unit == "%" and item.parameter != "hose.length":
        raise StudyFileError(f"{where}: unit = \"%\" applies to hose.length only: remove it")
    try:
        if kind == "point" and needed[0] in ("sigma", "tolerance"):
            value = getattr(item, needed[0])
            size = tuple(value) if isinstance(value, list) else (float(value),) * 3
            if len(size) != 3:
                raise ValueError(f"{needed[0]} must be one number or three [x, y, z]")
        elif item.distribution == "empirical":
            size = tuple(item.values) if item.file is None else _measured_file(source.parent / item.file, item, where)
        elif "range" in needed:
            if len(item.range) != 2:
                raise ValueError("range must be [low, high]")
            low, high = item.range
            if item.distribution == "triangular":
                size = (low, _scalar(item.mode, "mode"), high)
            elif item.distribution == "truncnormal":
                size = (_scalar(item.mean or 0.0, "mean"), _scalar(item.sigma, "sigma"), low, high)
            else:
                size = (low, high)
        else:
            size = (_scalar(getattr(item, needed[0]), needed[0]),)
        if item.unit == "%":
            size = tuple(v * base.problem.hose.length / 100.0 for v in size)
        if "hose.mass_per_length" in (item.parameter, *item.shared_with) and base.problem.hose.mass_per_length == 0.0:
            raise ValueError("the base hose is weightless (mass_per_length = 0): a factor changes nothing; give its "
                             "mass_per_length in the base file")
        return Tolerance(item.parameter, item.distribution, size, item.label, tuple(item.shared_with), axes)
    except ValueError as exc:
        raise StudyFileError(f"{where}: {exc}") from None


def _correlated(variation: Variation, sections: list[CorrelationSection], vary: list[VarySection],
                source: str) -> Variation:
    """The variation with the correlations of [[correlation]]: each names tolerances by their label, or by their
    parameter when one [[vary]] alone has it."""
    correlations = []
    for k, section in enumerate(sections):
        members = []
        for j, name in enumerate(section.tolerances):
            found = [i for i, item in enumerate(vary) if item.label == name] or [
                i for i, item in enumerate(vary) if item.parameter == name and not item.label]
            if len(found) != 1:
                known = [item.label or item.parameter for item in vary]
                why = (f"{len(found)} [[vary]] entries have that parameter: give them labels and name the label"
                       if found else f"no [[vary]] entry has that label or parameter; choose one of {', '.join(known)}")
                raise StudyFileError(f"{source}: correlation[{k}].tolerances[{j}] = \"{name}\": {why}")
            members.append(found[0])
        try:
            correlations.append(Correlation(tuple(members), tuple(tuple(row) for row in section.matrix)))
            correlated = replace(variation, correlations=tuple(correlations))
        except ValueError as exc:
            raise StudyFileError(f"{source}: correlation[{k}].{exc}") from None
    return correlated


def _precision(section: SamplingSection, base: StudyBase, source: str) -> Precision:
    """The Precision of [sampling.precision]: a quantity of the study, a cap at least the first round."""
    given = section.precision
    names = [q.name for q in quantities(base.obstacle_names)]
    if given.quantity not in names:
        raise StudyFileError(f"{source}: sampling.precision.quantity = \"{given.quantity}\": unknown; choose one of "
                             f"{', '.join(names)}")
    if given.max_samples < section.samples:
        raise StudyFileError(f"{source}: sampling.precision.max_samples = {given.max_samples}: less than the first "
                             f"round's sampling.samples = {section.samples}; give at least that many")
    try:
        unit = next(q.unit for q in quantities(base.obstacle_names) if q.name == given.quantity)
        return Precision(given.quantity, given.statistic, given.half_width, given.max_samples, unit)
    except ValueError as exc:
        raise StudyFileError(f"{source}: sampling.precision.{exc}") from None


def _measured_file(path: Path, item: VarySection, where: str) -> tuple[float, ...]:
    """The measured values of an empirical [[vary]] entry's file (and column)."""
    try:
        return read_measured_values(path, item.column)
    except OSError as exc:
        raise StudyFileError(f"{where}: file = \"{item.file}\": cannot read {path}: {exc.strerror or exc}") from None
    except ValueError as exc:
        raise StudyFileError(f"{where}: file = \"{item.file}\": {exc}") from None


def _limits(given: dict[str, float], base: StudyBase, source: str) -> tuple[Limit, ...]:
    """The limits: the file's, over the defaults (the hose's minimum bend radius, each obstacle's clearance)."""
    known = {q.name: q for q in base.quantities}
    values: dict[str, float] = {}
    if base.problem.hose.min_bend_radius is not None:
        values["bend_radius"] = base.problem.hose.min_bend_radius
    obstacles = base.sweep.obstacles if base.sweep is not None else () if base.obstacles is None else base.obstacles.obstacles
    for obstacle in obstacles:
        values[f"{CLEARANCE}{obstacle.name}"] = obstacle.clearance
    for name, value in given.items():
        if not math.isfinite(value):
            raise StudyFileError(f"{source}: limits.{name} = {value!r}: must be a finite number")
        if name == "clearance":
            if not obstacles:
                raise StudyFileError(f"{source}: limits.clearance: the base has no obstacles; remove it, give "
                                     "[[obstacles]] (a placement) or use a sweep file with [[obstacles]] as the base")
            values.update({f"{CLEARANCE}{o.name}": value for o in obstacles})
        elif name in known:
            values[name] = value
        else:
            raise StudyFileError(f"{source}: limits.{name}: unknown quantity; choose one of "
                                 f"{', '.join(['clearance', *known])}")
    return tuple(Limit(known[name], values[name]) for name in known if name in values)


def _design(section: DesignSection, base: StudyBase, limits: tuple[Limit, ...], sampling: Sampling,
            source: str) -> DesignGrid:
    """The DesignGrid of [design]."""
    if not limits:
        raise StudyFileError(f"{source}: [design] needs limits to judge the candidates: give [limits] (or a "
                             "min_bend_radius in the base's [hose])")
    lengths = _steps(section.lengths, section.length_step)
    clockings = _steps(section.clockings, section.clocking_step)
    if len(lengths) * len(clockings) * max(section.samples, 1) > MAX_CANDIDATES:
        raise StudyFileError(f"{source}: [design]: {len(lengths)} lengths x {len(clockings)} clockings x "
                             f"{max(section.samples, 1)} samples is more than {MAX_CANDIDATES} solves: use larger steps")
    if section.samples > sampling.count:
        raise StudyFileError(f"{source}: design.samples = {section.samples}: the study draws only {sampling.count} "
                             "tolerance samples ([sampling] samples, with [[vary]]); use at most that many")
    limits = tuple(limit for limit in limits if limit.quantity.name != "deviation")  # not judged by the search
    if not limits:
        raise StudyFileError(f"{source}: [design] needs a limit other than the deviation to judge the candidates")
    names = [limit.quantity.name for limit in limits]
    rank_by = section.rank_by or default_rank_by(limits)
    if rank_by not in names:
        raise StudyFileError(f"{source}: design.rank_by = \"{rank_by}\": not a limited quantity; choose one of "
                             f"{', '.join(names)}")
    if section.rank_on == "p95_margin":
        if sampling.count == 0:
            raise StudyFileError(f"{source}: design.rank_on = \"p95_margin\" needs [[vary]] tolerances (the margins are "
                                 "judged over their samples): give some, or rank_on = \"nominal\"")
        if section.samples:
            raise StudyFileError(f"{source}: design.samples = {section.samples} with rank_on = \"p95_margin\": both judge "
                                 "the 5th percentile of margin (by solved samples, or to first order): give samples = 0 "
                                 "or remove rank_on")
        uncovered = _uncovered_sensitivities(base)
        if uncovered:
            raise StudyFileError(f"{source}: design.rank_on = \"p95_margin\": the base has {uncovered}, whose "
                                 "sensitivities are not covered (docs/variation.md); judge the candidates by samples "
                                 "(design.samples) instead")
    return DesignGrid(lengths, clockings, rank_by, section.samples, section.method, section.rank_on)


def _reliability(section: ReliabilitySection, base: StudyBase, variation: Variation, limits: tuple[Limit, ...],
                 source: str) -> Reliability:
    """The Reliability of [reliability]: FORM needs tolerances, limits with derivatives, and a base whose
    sensitivities are covered."""
    if not variation.tolerances:
        raise StudyFileError(f"{source}: [reliability] needs [[vary]] tolerances: give some, or remove [reliability]")
    uncovered = _uncovered_sensitivities(base)
    if uncovered:
        raise StudyFileError(f"{source}: [reliability]: the base has {uncovered}, whose sensitivities FORM needs are "
                             "not covered (docs/variation.md); remove [reliability] and judge the limits by sampling")
    smooth = [limit.quantity.name for limit in limits if limit.quantity.name != "deviation"]
    if not smooth:
        raise StudyFileError(f"{source}: [reliability] needs a limit other than the deviation (which has no "
                             "derivative): give one in [limits]")
    for k, name in enumerate(section.limits):
        if name not in smooth:
            raise StudyFileError(f"{source}: reliability.limits[{k}] = \"{name}\": not a limit FORM can judge; choose "
                                 f"one of {', '.join(smooth)} (given in [limits]; the deviation has no derivative)")
    return Reliability(section.method, section.importance_samples, tuple(section.limits), section.seed)


def _uncovered_sensitivities(base: StudyBase) -> str | None:
    """What in the base the sensitivities do not cover (stiffener springs, a sliding clip, clips in a sweep), or
    None."""
    problem = base.problem
    return ("stiffener springs" if problem.hose.stiffeners is not None else
            "a sliding clip" if any(clip.kind == "sliding" for clip in problem.clips) else
            "clips in a sweep" if base.sweep is not None and problem.clips else None)


def _steps(pair: list[float], step: float) -> tuple[float, ...]:
    """From pair[0] to pair[1] (included when on a step) in steps of `step`."""
    count = int(math.floor((pair[1] - pair[0]) / step + 1e-9)) + 1
    return tuple(float(v) for v in pair[0] + step * np.arange(count))
