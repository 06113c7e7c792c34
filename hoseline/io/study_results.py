"""Files of a study: the batches kept while it runs (to resume), and the tables and problem files it ends with.

While a study runs, every finished batch is written to OUT/.partial/STAGE/batch_NNNNN.npz
(atomically) beside a manifest holding the study's fingerprint; a study started again with the
same fingerprint skips the batches found there, one with another fingerprint starts afresh.  The
final files appear together when the study completes (report/study_report.py), and .partial is
removed then.

Tables (CSV, one header line, units in the column names) and summary.json are built here; the
worst sample of every limit is written as a problem file (a sweep file for a sweep study, its
pose tables and meshes referred to by absolute paths) that reproduces it with `hoseline solve`
or `hoseline sweep`.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import shutil
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np

from hoseline.io.atomic import write_bytes, write_text
from hoseline.io.problem_file import _toml_value, problem_to_dict, problem_to_toml
from hoseline.io.results import _json, _plain
from hoseline.io.csv_numbers import cell
from hoseline.procedures.variation.statistics import PERCENTILES
from hoseline.procedures.variation.study import Study, StudyOutcome
from hoseline.procedures.variation.tolerances import perturbed

PARTIAL = ".partial"
SWEEP_TABLES = ("bodies", "obstacles", "sweep")


def fingerprint(study_text: str, base_text: str, study: Study) -> str:
    """A hash of everything the samples depend on: the study and base files, the tolerances' sizes (measured values
    read from a file among them) and the obstacle meshes."""
    digest = hashlib.sha256()
    for text in (study_text, base_text):
        digest.update(text.encode("utf-8"))
    for tolerance in study.variation.tolerances:
        digest.update(np.array(tolerance.size, dtype=float).tobytes())
    sweep = study.base.sweep
    fixed = () if study.base.obstacles is None else study.base.obstacles.obstacles
    for obstacle in fixed if sweep is None else sweep.obstacles:
        digest.update(np.ascontiguousarray(obstacle.vertices, dtype=float).tobytes())
        digest.update(np.ascontiguousarray(obstacle.faces, dtype=np.int64).tobytes())
    for motion in () if sweep is None else sweep.motions:
        digest.update(np.array([np.concatenate([p.rotation.ravel(), p.position]) for p in motion.poses]).tobytes())
    return digest.hexdigest()


def _fingerprint_of(manifest: Path) -> str | None:
    """The study fingerprint a partial stage's manifest.json names; None when it names none or cannot be read."""
    try:
        data = json.loads(manifest.read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):  # ValueError: not JSON, or not UTF-8
        return None
    return data.get("fingerprint") if isinstance(data, dict) else None


class PartialStore:
    """The finished batches of one stage of a study, kept under OUT/.partial/STAGE (see the module doc)."""

    def __init__(self, out_dir: str | Path, stage: str, study_fingerprint: str) -> None:
        self.folder = Path(out_dir) / PARTIAL / stage
        manifest = self.folder / "manifest.json"
        if manifest.exists() and _fingerprint_of(manifest) != study_fingerprint:
            shutil.rmtree(self.folder)  # batches of another study (or of the same one changed, or a damaged manifest)
        self.folder.mkdir(parents=True, exist_ok=True)
        write_text(manifest, json.dumps({"fingerprint": study_fingerprint}))

    def finished(self) -> dict[int, dict[str, np.ndarray]]:
        """The batches written so far, by batch number."""
        out = {}
        for path in sorted(self.folder.glob("batch_*.npz")):
            with np.load(path, allow_pickle=False) as data:
                out[int(path.stem.split("_")[1])] = {key: data[key] for key in data.files}
        return out

    def save(self, batch: int, arrays: dict[str, np.ndarray]) -> None:
        """Write one batch atomically."""
        stream = io.BytesIO()
        np.savez(stream, **arrays)
        write_bytes(self.folder / f"batch_{batch:05d}.npz", stream.getvalue())


def remove_partial(out_dir: str | Path) -> None:
    """Remove OUT/.partial once the final files are in place."""
    shutil.rmtree(Path(out_dir) / PARTIAL, ignore_errors=True)


def _table(columns: dict[str, list | np.ndarray]) -> str:
    """CSV text of equally long columns (numbers to 8 significant digits, NaN as empty)."""
    stream = io.StringIO()
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow(columns)
    length = len(next(iter(columns.values()))) if columns else 0
    for k in range(length):
        writer.writerow(cell(values[k]) for values in columns.values())
    return stream.getvalue()


def samples_csv(outcome: StudyOutcome) -> str:
    """One row per sample: index, status, reason, the varied deviations, the quantities, snap-throughs."""
    samples = outcome.samples
    columns: dict[str, list | np.ndarray] = {
        "sample": samples["index"],
        "status": np.where(samples["failed"], "failed", "solved"),
        "reason": samples["reason"],
    }
    variation = outcome.study.variation
    for k in variation.varied:
        columns[f"{variation.names[k]} [{variation.units[k]}]"] = outcome.coordinates[:, k]
    for k, quantity in enumerate(outcome.study.quantities):
        columns[f"{quantity.name} [{quantity.unit}]"] = samples["values"][:, k]
    columns["snap-throughs"] = samples["snaps"]
    return _table(columns)


def envelope_csv(outcome: StudyOutcome) -> str:
    """Per station at the first kept pose: the P5/P50/P95 and extreme positions (mm), and the distance from
    the nominal shape (P5/P50/P95 and maximum over all poses, mm)."""
    envelope = outcome.envelopes[0]
    segments = outcome.nominal_centerlines.shape[1] - 1
    columns: dict[str, np.ndarray] = {
        "station": np.arange(segments + 1),
        "s/L": np.arange(segments + 1) / segments,
    }
    for axis, name in enumerate("xyz"):
        columns[f"nominal {name} [mm]"] = outcome.nominal_centerlines[outcome.study.base.shape_poses()[0], :, axis]
        for p, values in zip(PERCENTILES, envelope["percentiles"]):
            columns[f"P{p:g} {name} [mm]"] = values[:, axis]
        columns[f"min {name} [mm]"] = envelope["minimum"][:, axis]
        columns[f"max {name} [mm]"] = envelope["maximum"][:, axis]
    for p, values in zip(PERCENTILES, outcome.deviation["percentiles"]):
        columns[f"deviation P{p:g} [mm]"] = values
    columns["deviation max [mm]"] = outcome.deviation["maximum"]
    return _table(columns)


def clearance_csv(outcome: StudyOutcome) -> str:
    """Per pose and obstacle: the P5/P50/P95 and the least clearance over the samples (mm)."""
    sweep = outcome.study.base.sweep
    columns: dict[str, list | np.ndarray] = {"pose": np.arange(sweep.pose_count), "travel": sweep.travel}
    for o, obstacle in enumerate(sweep.obstacles):
        for p, values in zip(PERCENTILES, outcome.clearance["percentiles"][o]):
            columns[f"{obstacle.name} P{p:g} [mm]"] = values
        columns[f"{obstacle.name} min [mm]"] = outcome.clearance["minimum"][o]
    return _table(columns)


def sensitivities_csv(outcome: StudyOutcome) -> str:
    """Per varied coordinate: the derivative of every smooth quantity (quantity unit per coordinate unit)."""
    derivatives, names = outcome.first_order.derivatives, outcome.first_order.names
    units = {q.name: q.unit for q in outcome.study.quantities}
    variation = outcome.study.variation
    varied = variation.varied
    columns: dict[str, list | np.ndarray] = {"coordinate": [variation.names[k] for k in varied],
                                             "unit": [variation.units[k] for k in varied]}
    for q, name in enumerate(names):
        columns[f"d {name} [{units[name]} per unit]"] = derivatives[q, list(varied)]
    return _table(columns)


def station_sensitivities_csv(outcome: StudyOutcome) -> str:
    """Per station of the nominal hose (of a sweep: at its first pose) and varied coordinate: the derivative of the
    station's position (mm per unit of the coordinate), one row each; its arc length along the nominal hose (mm)."""
    derivatives = outcome.first_order.station_derivatives
    variation = outcome.study.variation
    varied = list(variation.varied)
    stations = derivatives.shape[0]
    arc = np.linspace(0.0, outcome.study.base.problem.hose.length, stations)
    moved = derivatives[:, :, varied]  # (stations, 3, varied)
    columns: dict[str, list | np.ndarray] = {
        "station": np.repeat(np.arange(stations), len(varied)),
        "arc_length [mm]": np.repeat(arc, len(varied)),
        "coordinate": [variation.names[k] for k in varied] * stations,
        "unit": [variation.units[k] for k in varied] * stations,
    }
    for axis, name in enumerate("xyz"):
        columns[f"d{name} [mm per unit]"] = moved[:, axis, :].ravel()
    return _table(columns)


def design_csv(outcome: StudyOutcome) -> str:
    """The ranked candidates that meet every limit, with the margin of each limit (with the optimiser: one per
    length, and whether its clocking comes from the optimiser or the grid)."""
    rows = outcome.design.table()
    if not rows:
        return "rank,length_mm,clocking_deg\n"
    return _table({key: [row[key] for row in rows] for key in rows[0]})


def design_grid_csv(outcome: StudyOutcome) -> str:
    """Every candidate: length, clocking, failed samples, and the margin of each limit (empty: failed)."""
    design = outcome.design
    grid = design.grid
    columns: dict[str, list] = {"length_mm": [], "clocking_deg": [], "failed_samples": []}
    for limit in design.limits:
        columns[f"margin {limit.quantity.name} [{limit.quantity.unit}]"] = []
    for i, length in enumerate(grid.lengths):
        for j, clocking in enumerate(grid.clockings):
            columns["length_mm"].append(length)
            columns["clocking_deg"].append(clocking)
            columns["failed_samples"].append(int(design.failed[i, j]))
            for k, limit in enumerate(design.limits):
                columns[f"margin {limit.quantity.name} [{limit.quantity.unit}]"].append(float(design.margins[i, j, k]))
    return _table(columns)


def study_document(outcome: StudyOutcome) -> dict:
    """What summary.json holds: the study, the nominal hose, spreads, probabilities, first order, design, notes."""
    study = outcome.study
    names = [q.name for q in study.quantities]
    document = {
        "name": study.name,
        "base": "sweep" if study.base.sweep is not None else "placement",
        "problem": problem_to_dict(study.base.problem),
        "sampling": {"method": study.sampling.method, "samples": study.sampling.count, "seed": study.sampling.seed,
                     "batch": None if study.sampling.rounds else study.sampling.batch_size(), "rounds": [
                         {"samples": size, "batch": study.sampling.round_batch(size)} for size in study.sampling.rounds]},
        "tolerances": [{"parameter": t.parameter, "shared_with": list(t.shared_with), "distribution": t.distribution,
                        "size": list(t.size), "axes": [list(row) for row in t.axes] or "world", "label": t.name}
                       for t in study.variation.tolerances],
        "correlations": [{"tolerances": [study.variation.tolerances[k].name for k in c.tolerances],
                          "matrix": [list(row) for row in c.matrix]} for c in study.variation.correlations],
        "nominal": dict(zip(names, outcome.nominal)),
        "quantities": {
            q.name: {"unit": q.unit, "mean": s.mean, "mean_ci95": list(s.mean_interval), "std": s.std,
                     **{f"P{p:g}": v for p, v in zip(PERCENTILES, s.percentiles)},
                     **{f"P{p:g}_ci95": list(i) for p, i in zip(PERCENTILES, s.percentile_intervals)},
                     "min": s.minimum, "max": s.maximum, "solved": s.solved}
            for q, s in zip(study.quantities, outcome.spreads)
        },
        "probabilities": [
            {"limit": p.limit.describe(), "quantity": p.limit.quantity.name, "value": p.limit.value,
             "probability": p.estimate, "ci95": [p.low, p.high], "ci95_high_counting_failed": p.high_with_failed,
             "broken": p.broken, "solved": p.solved, "failed": p.failed, "cpk": p.cpk, "ppm_if_normal": p.ppm,
             "worst_sample": w}
            for p, w in zip(outcome.probabilities, outcome.worst)
        ],
        "failures": [{"cause": f.cause, "count": f.count, "samples": list(f.samples), "example": f.example}
                     for f in outcome.failures],
        "notes": outcome.notes,
        "run": outcome.run,
    }
    if outcome.precision is not None:
        reached = outcome.precision
        document["precision"] = {
            "quantity": reached.precision.quantity, "unit": reached.precision.unit, "statistic": reached.precision.statistic,
            "half_width_asked": reached.precision.half_width, "max_samples": reached.precision.max_samples,
            "estimate": reached.estimate, "ci95": [reached.low, reached.high], "half_width": reached.half_width,
            "samples": reached.samples, "rounds": list(reached.rounds), "reached": reached.reached}
    first = outcome.first_order
    if first is not None:
        document["first_order"] = {
            name: {"mean": first.mean[k], "variance": check.first_order_variance,
                   "monte_carlo_variance": check.monte_carlo_variance, "standard_error": check.standard_error,
                   "z": check.z, "agrees": check.agrees}
            for k, (name, check) in enumerate(zip(first.names, first.agreements))
        }
        document["first_order"]["shape (mean squared station spread, mm^2)"] = {
            "variance": first.shape.first_order_variance, "monte_carlo_variance": first.shape.monte_carlo_variance,
            "standard_error": first.shape.standard_error, "z": first.shape.z, "agrees": first.shape.agrees}
        document["contributions_std"] = {
            name: dict(zip([t.name for t in study.variation.tolerances], first.contributions[k]))
            for k, name in enumerate(first.names)
        }
    if outcome.worst_cases:
        variation = study.variation
        document["worst_case"] = {
            case.quantity.name: {
                "unit": case.quantity.unit, "worse": "down" if case.quantity.sense == "at least" else "up",
                "nominal": case.nominal, "first_order_worst": case.first_order, "solved_worst": case.solved,
                "reason": case.reason or None,
                "corner": {variation.names[k]: case.corner[k] for k in variation.varied}}
            for case in outcome.worst_cases}
    if outcome.sobol is not None:
        sobol = outcome.sobol
        labels = [t.name for t in study.variation.tolerances]
        document["sobol"] = {
            "base_rows": sobol.count, "rows_used": sobol.rows,
            "indices": {name: {label: {"first": sobol.first[q, k], "first_ci95": [sobol.first_low[q, k], sobol.first_high[q, k]],
                                       "total": sobol.total[q, k], "total_ci95": [sobol.total_low[q, k], sobol.total_high[q, k]]}
                               for k, label in enumerate(labels)}
                        for q, name in enumerate(names)}}
    if outcome.rare_events:
        document["rare_failures"] = [_rare_document(event, study) for event in outcome.rare_events]
    if outcome.rare_union is not None:
        union, check = outcome.rare_union, outcome.rare_union.importance
        document["rare_failures_any"] = {
            "limits": [limit.describe() for limit in union.limits], "form_probability": union.form,
            "importance_sampling": None if check is None else {
                "probability": check.estimate, "standard_error": check.standard_error, "ci95": [check.low, check.high],
                "samples": check.samples, "failed": check.failed, "ci95_high_counting_failed": check.high_with_failed}}
    if outcome.design is not None:
        design = outcome.design
        document["design"] = {"lengths_mm": list(design.grid.lengths), "clockings_deg": list(design.grid.clockings),
                              "rank_by": design.grid.rank_by, "rank_on": design.grid.rank_on,
                              "samples_per_candidate": design.grid.samples,
                              "method": design.grid.method, "ranking": design.table(),
                              "failure_reasons": design.reasons}
        if design.refined is not None:
            document["design"]["optimiser"] = [
                {"length_mm": r.length, "clocking_deg": r.clocking, "bracket_deg": list(r.bracket),
                 "evaluations": r.evaluations, "improved_on_grid": r.optimised} for r in design.refined]
    return _plain(document)


def _rare_document(event, study: Study) -> dict:
    """summary.json's entry of one rare failure (rare.RareEvent)."""
    point, check = event.point, event.importance
    names = study.variation.names
    return {
        "limit": event.limit.describe(), "quantity": event.limit.quantity.name,
        "beta": point.beta, "form_probability": event.form, "sorm_probability": event.sorm,
        "curvatures": None if event.curvatures is None else list(event.curvatures.curvatures),
        "converged": point.converged, "message": point.message, "solves_with_sensitivities": event.evaluations,
        "design_point_standard_normal": list(point.design_point),
        "design_point_deviations": {names[k]: event.deviation[k] for k in study.variation.varied},
        "importance_sampling": None if check is None else {
            "probability": check.estimate, "standard_error": check.standard_error, "ci95": [check.low, check.high],
            "coefficient_of_variation": check.coefficient_of_variation, "samples": check.samples,
            "failed": check.failed, "ci95_high_counting_failed": check.high_with_failed},
    }


def write_study_data(outcome: StudyOutcome, folder: Path, base_path: Path) -> None:
    """The tables, summary.json, samples.npz and the worst samples' problem files into `folder` (it exists)."""
    write_text(folder / "summary.json", _json(study_document(outcome)) + "\n")
    if outcome.samples:
        write_text(folder / "samples.csv", samples_csv(outcome))
        stream = io.BytesIO()
        np.savez_compressed(stream, coordinates=outcome.coordinates,
                            **{k: v for k, v in outcome.samples.items() if k != "reason"})
        write_bytes(folder / "samples.npz", stream.getvalue())
        if outcome.envelopes:
            write_text(folder / "envelope.csv", envelope_csv(outcome))
        if outcome.study.base.sweep is not None and outcome.study.base.obstacle_names and outcome.envelopes:
            write_text(folder / "clearance_by_pose.csv", clearance_csv(outcome))
        _write_worst(outcome, folder, base_path)
    _write_design_points(outcome, folder, base_path)
    _write_corners(outcome, folder, base_path)
    if outcome.first_order is not None:
        write_text(folder / "sensitivities.csv", sensitivities_csv(outcome))
        write_text(folder / "station_sensitivities.csv", station_sensitivities_csv(outcome))
    if outcome.design is not None:
        write_text(folder / "design.csv", design_csv(outcome))
        write_text(folder / "design_grid.csv", design_grid_csv(outcome))


def _write_hose(problem, study, folder: Path, kind: str, quantity_name: str, header: str, base_path: Path) -> None:
    """KIND/QUANTITY/problem.toml (and sweep.toml for a sweep study) in `folder`: the hose `problem` with a header
    comment saying what it is.  Without a force accuracy: the study solved the hose at its segment count, and the
    file is to give what the study found."""
    target = folder / kind / quantity_name.replace(":", "_")
    target.mkdir(parents=True, exist_ok=True)
    write_text(target / "problem.toml", header + problem_to_toml(replace(problem, force_accuracy=None)))
    if study.base.sweep is not None:
        write_text(target / "sweep.toml", header + sweep_toml(problem, base_path))


def _write_worst(outcome: StudyOutcome, folder: Path, base_path: Path) -> None:
    """worst/QUANTITY/problem.toml (and sweep.toml for a sweep) for the worst sample of every limit."""
    study = outcome.study
    for limit, index in zip(study.limits, outcome.worst):
        if index is not None:
            _write_hose(study.sample_problem(index), study, folder, "worst", limit.quantity.name,
                        f"# sample {index} of study '{study.name}': the worst {limit.quantity.name}\n", base_path)


def _write_design_points(outcome: StudyOutcome, folder: Path, base_path: Path) -> None:
    """design_point/QUANTITY/problem.toml (and sweep.toml for a sweep): the most probable failure point of every
    limit FORM judged (the hose with the deviations that break it first)."""
    study = outcome.study
    for event in outcome.rare_events:
        if event.point.converged:
            _write_hose(perturbed(study.base.problem, event.deviation), study, folder, "design_point",
                        event.limit.quantity.name,
                        f"# the most probable failure point of {event.limit.describe()} in study '{study.name}': "
                        f"beta {event.point.beta:.4g}, FORM P {event.form:.3g}\n", base_path)


def _write_corners(outcome: StudyOutcome, folder: Path, base_path: Path) -> None:
    """worst_case/QUANTITY/problem.toml (and sweep.toml for a sweep): the hose at each quantity's worst-case corner."""
    study = outcome.study
    for case in outcome.worst_cases:
        _write_hose(perturbed(study.base.problem, case.corner), study, folder, "worst_case", case.quantity.name,
                    f"# the worst-case corner of {case.quantity.name} in study '{study.name}': first order "
                    f"{case.first_order:.6g}, solved {case.solved:.6g} {case.quantity.unit}\n", base_path)


def sweep_toml(problem, base_path: Path) -> str:
    """A sweep file: the base sweep file's motion and obstacles (paths made absolute) around `problem`."""
    original = tomllib.loads(base_path.read_text(encoding="utf-8"))
    data = problem_to_dict(problem)
    for role in ("start", "end"):
        if isinstance(original.get(role), dict) and "body" in original[role]:
            data[role]["body"] = original[role]["body"]
    for body in original.get("bodies", []):
        if "poses" in body:
            body["poses"] = str((base_path.parent / body["poses"]).resolve())
    for obstacle in original.get("obstacles", []):
        obstacle["file"] = str((base_path.parent / obstacle["file"]).resolve())
    data.update({key: original[key] for key in SWEEP_TABLES if key in original})
    return _toml(data)


def _toml(data: dict) -> str:
    """TOML text of nested dicts: plain keys first, then tables, then arrays of tables."""
    lines = [f"{key} = {_inline(value)}" for key, value in data.items() if not isinstance(value, (dict, list))
             or (isinstance(value, list) and not (value and isinstance(value[0], dict)))]
    for key, value in data.items():
        if isinstance(value, dict):
            lines.append(f"\n[{key}]")
            lines.extend(f"{name} = {_inline(item)}" for name, item in value.items())
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            for item in value:
                lines.append(f"\n[[{key}]]")
                lines.extend(f"{name} = {_inline(entry)}" for name, entry in item.items())
    return "\n".join(lines) + "\n"


def _inline(value) -> str:
    """A TOML value on one line (inline tables for dicts inside arrays)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{key} = {_inline(item)}" for key, item in value.items()) + " }"
    if isinstance(value, list):
        return "[" + ", ".join(_inline(item) for item in value) + "]"
    return _toml_value(value)
