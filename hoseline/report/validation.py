"""The validation report: deviation along the hose, 3D overlay of model and scan, and the tables.

report.html is self-contained (the PNG is embedded, the interactive 3D overlay carries
plotly's JavaScript inline), so it opens offline and can be mailed.  deviation.png holds
the same plots; deviation.csv the per-station numbers; validation.json everything else.
"""

from __future__ import annotations

import base64
import csv
import html
import io
import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import plotly.graph_objects as go
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from hoseline.io.atomic import staged_directory, write_bytes, write_text
from hoseline.procedures.scans.calibration import Calibration
from hoseline.procedures.scans.scatter import ScatterEnvelope
from hoseline.procedures.placement.twist_path import TwistPath
from hoseline.procedures.scans.validation import Comparison
from hoseline.report.plots import VIEWS, finish_view, png_bytes

OVERLAY_POINTS = 20000  # scan points drawn in the 3D overlay, at most (all scans together)


def write_validation_report(
    out_dir: str | Path,
    comparisons: Sequence[Comparison],
    *,
    envelope: ScatterEnvelope | None = None,
    calibration: Calibration | None = None,
    twist_paths: Sequence[TwistPath] = (),
    extra_files: dict[str, str] | None = None,
) -> Path:
    """Write report.html, deviation.png, deviation.csv and validation.json into `out_dir` (all or none).

    comparisons: one per scan.  envelope: scatter of repeated scans.  calibration: a fit of
    the hose to the scans.  twist_paths: model variants followed through a twist.
    extra_files: more text files to write with them, {file name: text}.
    """
    png = deviation_png(comparisons, envelope)
    twist_png = twist_paths_png(twist_paths) if twist_paths else None
    document = _document(comparisons, envelope, calibration, twist_paths)
    with staged_directory(out_dir) as staging:
        write_bytes(staging / "deviation.png", png)
        if twist_png is not None:
            write_bytes(staging / "twist_paths.png", twist_png)
        write_text(staging / "deviation.csv", deviation_csv(comparisons))
        write_text(staging / "validation.json", json.dumps(document, indent=1) + "\n")
        write_text(staging / "report.html", _html(comparisons, envelope, calibration, twist_paths, png, twist_png))
        for name, text in (extra_files or {}).items():
            write_text(staging / name, text)
    return Path(out_dir)


def deviation_csv(comparisons: Sequence[Comparison]) -> str:
    """Per scan station: scan label, x, y, z of the station, radius, closest model arc length, deviation (mm)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["scan", "x", "y", "z", "radius", "s_model", "deviation"])
    for c in comparisons:
        for point, radius, s, d in zip(c.fit.points, c.fit.radius, c.deviation.s_model, c.deviation.distance):
            writer.writerow([c.label, *(f"{v:.6g}" for v in (*point, radius, s, d))])
    return buffer.getvalue()


def deviation_png(comparisons: Sequence[Comparison], envelope: ScatterEnvelope | None = None) -> bytes:
    """PNG: deviation along the hose per scan with its threshold, the scatter envelope, and three views."""
    figure = Figure(figsize=(16, 10), layout="constrained")
    FigureCanvasAgg(figure)
    along = figure.add_subplot(2, 2, 1)
    for c in comparisons:
        line = along.plot(c.deviation.s_model, c.deviation.distance, ".-", label=f"{c.label}: mean {c.deviation.mean:.2f} mm")[0]
        along.axhline(c.thresholds.mean, color=line.get_color(), linestyle="--", linewidth=0.8)
    along.set(title="deviation of the scan centreline from the model (dashed: mean limit)",
              xlabel="s along the model [mm]", ylabel="deviation [mm]")
    along.grid(True, alpha=0.3)
    along.legend()
    scatter_axes = figure.add_subplot(2, 2, 2)
    if envelope is not None:
        scatter_axes.plot(envelope.s, envelope.radius, label=f"envelope radius (margin {envelope.margin:.2f} mm)")
        scatter_axes.plot(envelope.s, envelope.spread, label=f"spread (max {envelope.max_spread:.2f} mm)")
        scatter_axes.legend()
    else:
        scatter_axes.text(0.5, 0.5, "one scan per mounting: no scatter envelope", ha="center", transform=scatter_axes.transAxes)
    scatter_axes.set(title="scatter of repeated scans (preset, hysteresis)", xlabel="s [mm]", ylabel="distance [mm]")
    scatter_axes.grid(True, alpha=0.3)
    for index, (title, i, j) in enumerate(VIEWS[:2]):
        axes = figure.add_subplot(2, 2, 3 + index)
        for c in comparisons:
            model = axes.plot(c.result.centerline[:, i], c.result.centerline[:, j], label=f"model {c.label}")[0]
            axes.plot(c.fit.points[:, i], c.fit.points[:, j], "o", markersize=3, color=model.get_color(),
                      markerfacecolor="none", label=f"scan centreline {c.label}")
        finish_view(axes, title, i, j)
        axes.legend(fontsize="small")
    return png_bytes(figure)


def twist_paths_png(paths: Sequence[TwistPath]) -> bytes:
    """PNG: the final shapes of each model variant in two views, and the movement per twist step."""
    figure = Figure(figsize=(16, 5.5), layout="constrained")
    FigureCanvasAgg(figure)
    for index, (title, i, j) in enumerate(VIEWS[:2]):
        axes = figure.add_subplot(1, 3, 1 + index)
        for path in paths:
            final = path.centerlines[-1]
            axes.plot(final[:, i], final[:, j], label=f"{path.label} at {path.twists_deg[-1]:g} deg")
        finish_view(axes, title, i, j)
        axes.legend(fontsize="small")
    steps = figure.add_subplot(1, 3, 3)
    for path in paths:
        steps.plot(path.twists_deg[1:], path.steps, ".-", label=f"{path.label} ({'smooth' if path.smooth else 'NOT smooth'})")
    steps.set(title="largest station movement per twist step", xlabel="twist [deg]", ylabel="movement [mm]")
    steps.grid(True, alpha=0.3)
    steps.legend(fontsize="small")
    return png_bytes(figure)


def overlay_figure(comparisons: Sequence[Comparison]) -> go.Figure:
    """Interactive 3D: model centrelines, scan points (thinned), scan stations coloured by deviation."""
    figure = go.Figure()
    rng = np.random.default_rng(0)
    share = max(1, OVERLAY_POINTS // max(1, len(comparisons)))
    largest = max([float(np.max(c.deviation.distance)) for c in comparisons] + [1e-9])
    for index, c in enumerate(comparisons):
        model = c.result.centerline
        figure.add_trace(go.Scatter3d(x=model[:, 0], y=model[:, 1], z=model[:, 2], mode="lines",
                                      line={"width": 6}, name=f"model {c.label}"))
        shown = c.scan if c.scan.shape[0] <= share else c.scan[rng.choice(c.scan.shape[0], share, replace=False)]
        figure.add_trace(go.Scatter3d(x=shown[:, 0], y=shown[:, 1], z=shown[:, 2], mode="markers",
                                      marker={"size": 1, "opacity": 0.35}, name=f"scan points {c.label}"))
        stations = c.fit.points
        figure.add_trace(go.Scatter3d(
            x=stations[:, 0], y=stations[:, 1], z=stations[:, 2], mode="markers", name=f"scan centreline {c.label}",
            marker={"size": 3, "color": c.deviation.distance, "colorscale": "Turbo", "cmin": 0.0, "cmax": largest,
                    "showscale": index == 0, "colorbar": {"title": "deviation [mm]"}},
            text=[f"deviation {d:.2f} mm at s = {s:.1f} mm" for d, s in zip(c.deviation.distance, c.deviation.s_model)],
        ))
    figure.update_layout(scene={"aspectmode": "data", "xaxis_title": "x [mm]", "yaxis_title": "y [mm]",
                                "zaxis_title": "z [mm]"}, height=700, margin={"l": 0, "r": 0, "t": 30, "b": 0},
                         legend={"itemsizing": "constant", "x": 0.0, "y": 1.0})
    return figure


def _document(comparisons, envelope, calibration, twist_paths) -> dict:
    """validation.json: summaries of every part of the report (mm, degrees, N*mm^2, kg/m)."""
    return {
        "comparisons": [c.summary() for c in comparisons],
        "passed": all(c.passed for c in comparisons),
        "scatter": None if envelope is None else envelope.summary(),
        "calibration": None if calibration is None else {
            "parameters": [vars(p) for p in calibration.parameters],
            "before": [d.summary() for d in calibration.before],
            "after": [d.summary() for d in calibration.after],
            "notes": calibration.notes,
            "warnings": calibration.warnings,
            "scatter_inflation": calibration.scatter_inflation,
            "poisson_ratio": calibration.poisson_ratio,
            "evaluations": calibration.evaluations,
            "warm_solves": calibration.warm_solves,
            "cold_solves": calibration.cold_solves,
        },
        "twist_paths": [{"label": p.label, "smooth": p.smooth, "jumps_deg_mm": p.jumps, "failure": p.failure,
                         "median_step_mm": float(np.median(p.steps)) if p.steps.size else None}
                        for p in twist_paths],
    }


def _table(head: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    cells = "".join(f"<th>{html.escape(str(h))}</th>" for h in head)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(v))}</td>" for v in row) + "</tr>" for row in rows)
    return f"<table><tr>{cells}</tr>{body}</table>"


def _html(comparisons, envelope, calibration, twist_paths, png: bytes, twist_png: bytes | None) -> str:
    """The self-contained report page."""
    name = comparisons[0].result.problem.name if comparisons else "hose"
    parts = [f"<h1>hoseline validation: {html.escape(name)}</h1>", "<h2>Deviation of the scan from the model</h2>",
             _table(["scan", "twist [deg]", "stations", "mean [mm]", "RMS [mm]", "max [mm]", "at s [mm]",
                     "mean limit [mm]", "noise allows [mm]", "verdict", "radius [mm]", "outliers", "gaps [mm]"],
                    [[c.label, f"{c.result.problem.end_twist_deg:g}", c.deviation.distance.size, f"{c.deviation.mean:.3f}",
                      f"{c.deviation.rms:.3f}", f"{c.deviation.max:.3f}", f"{c.deviation.s_at_max:.1f}",
                      f"{c.thresholds.mean:g}", f"{c.noise_allowance:.3f}", c.verdict,
                      f"{c.fit.radius_median:.3f} ± {c.fit.radius_scatter:.3f}", c.fit.outliers,
                      "; ".join(f"{a:.0f}-{b:.0f}" for a, b in c.fit.gaps) or "none"] for c in comparisons])]
    references = [c for c in comparisons if c.reference is not None]
    if references:
        parts += ["<h2>Reference points (shortest distance to the model centreline)</h2>",
                  _table(["scan", "point", "x", "y", "z", "deviation [mm]", "at s [mm]"],
                         [[c.label, k + 1, *(f"{v:.3f}" for v in p), f"{d:.3f}", f"{s:.1f}"]
                          for c in references for k, (p, d, s) in enumerate(zip(c.reference.points, c.reference.distance,
                                                                                 c.reference.s_model))])]
    parts += [f'<img alt="deviation plots" src="data:image/png;base64,{base64.b64encode(png).decode()}">',
              "<h2>3D overlay (drag to turn, scroll to zoom)</h2>",
              overlay_figure(comparisons).to_html(full_html=False, include_plotlyjs=True)]
    if envelope is not None:
        parts += ["<h2>Scatter of repeated scans</h2>",
                  _table(["scans", "max spread [mm]", "at s [mm]", "clearance margin around the mean shape [mm]"],
                         [[envelope.scans, f"{envelope.max_spread:.2f}", f"{envelope.s_at_max_spread:.1f}",
                           f"{envelope.margin:.2f}"]])]
    if calibration is not None:
        parts += ["<h2>Calibration</h2>",
                  _table(["parameter", "unit", "initial", "fitted", "± (1 sigma)", "identified"],
                         [[p.name, p.unit, f"{p.initial:.6g}", f"{p.value:.6g}",
                           "n/a" if p.std is None else f"{p.std:.3g}", "yes" if p.identifiable else "NO"]
                          for p in calibration.parameters]),
                  _table(["scan", "mean before [mm]", "max before [mm]", "mean after [mm]", "max after [mm]"],
                         [[c.label, f"{b.mean:.3f}", f"{b.max:.3f}", f"{a.mean:.3f}", f"{a.max:.3f}"]
                          for c, b, a in zip(comparisons, calibration.before, calibration.after)])]
        parts += [f"<p><strong>Warning:</strong> {html.escape(warning)}</p>" for warning in calibration.warnings]
        parts += [f"<p>{html.escape(note)}</p>" for note in calibration.notes]
    if twist_paths:
        parts += ["<h2>Models along the twist</h2>",
                  _table(["model", "smooth", "jumps (twist deg: mm)", "median step [mm]", "failure"],
                         [[p.label, "yes" if p.smooth else "NO", "; ".join(f"{t:g}: {m:.1f}" for t, m in p.jumps) or "none",
                           f"{np.median(p.steps):.2f}" if p.steps.size else "n/a", p.failure or "none"]
                          for p in twist_paths]),
                  f'<img alt="twist paths" src="data:image/png;base64,{base64.b64encode(twist_png).decode()}">']
    style = ("body{font-family:sans-serif;margin:2em;max-width:1400px}table{border-collapse:collapse;margin:1em 0}"
             "td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}img{max-width:100%}")
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>hoseline validation</title>"
            f"<style>{style}</style></head><body>{''.join(parts)}</body></html>\n")
