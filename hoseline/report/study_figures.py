"""The interactive figures of the study report (plotly): 3D envelope, distributions, tornado, spreads, heat map.

study_html.py puts them in one self-contained page.
"""

from __future__ import annotations

import numpy as np
import plotly.graph_objects as go
from plotly.subplots import make_subplots

from hoseline.procedures.sweep.envelope import Envelope
from hoseline.procedures.variation.study import StudyOutcome

SHOWN_SAMPLES = 60  # sampled hoses drawn as thin lines in the 3D view
NOMINAL_COLOUR = "#1f4e9c"
SAMPLE_COLOUR = "rgba(120, 120, 120, 0.35)"
WORST_COLOUR = "#d62828"
ENVELOPE_COLOUR = "#7fa7d9"
OBSTACLE_COLOUR = "#9a9a9a"
LIMIT_COLOUR = "#d62828"


def view_figure(outcome: StudyOutcome, envelope: Envelope | None) -> go.Figure:
    """3D: the envelope mesh of all sampled hoses, some samples, the nominal hose, the worst samples, obstacles."""
    figure = go.Figure()
    if envelope is not None:
        vertices, faces = envelope.vertices, envelope.faces
        figure.add_trace(go.Mesh3d(x=vertices[:, 0], y=vertices[:, 1], z=vertices[:, 2], i=faces[:, 0], j=faces[:, 1],
                                   k=faces[:, 2], color=ENVELOPE_COLOUR, opacity=0.25, name="envelope of all samples",
                                   showlegend=True, hoverinfo="skip"))
    shapes = outcome.samples.get("shapes")
    if shapes is not None:
        solved = np.nonzero(~outcome.samples["failed"])[0]
        for n, k in enumerate(solved[np.linspace(0, len(solved) - 1, min(SHOWN_SAMPLES, len(solved))).astype(int)]
                              if len(solved) else []):
            line = shapes[k, 0]
            figure.add_trace(go.Scatter3d(x=line[:, 0], y=line[:, 1], z=line[:, 2], mode="lines",
                                          line={"color": SAMPLE_COLOUR, "width": 2}, name="samples",
                                          legendgroup="samples", showlegend=n == 0, hoverinfo="skip"))
        for limit, k in zip(outcome.study.limits, outcome.worst):
            if k is None:
                continue
            line = shapes[k, 0]
            figure.add_trace(go.Scatter3d(x=line[:, 0], y=line[:, 1], z=line[:, 2], mode="lines",
                                          line={"color": WORST_COLOUR, "width": 4, "dash": "dash"},
                                          name=f"worst {limit.quantity.name} (sample {k})"))
    nominal = outcome.nominal_centerlines[outcome.study.base.shape_poses()[0]]
    figure.add_trace(go.Scatter3d(x=nominal[:, 0], y=nominal[:, 1], z=nominal[:, 2], mode="lines",
                                  line={"color": NOMINAL_COLOUR, "width": 6}, name="nominal hose"))
    sweep = outcome.study.base.sweep
    for obstacle in () if sweep is None else sweep.obstacles:
        v, f = obstacle.vertices, obstacle.faces
        figure.add_trace(go.Mesh3d(x=v[:, 0], y=v[:, 1], z=v[:, 2], i=f[:, 0], j=f[:, 1], k=f[:, 2],
                                   color=OBSTACLE_COLOUR, opacity=0.4, name=obstacle.name, showlegend=True))
    figure.update_layout(scene={"aspectmode": "data", "xaxis_title": "x [mm]", "yaxis_title": "y [mm]",
                                "zaxis_title": "z [mm]"}, height=640, margin={"l": 0, "r": 0, "t": 30, "b": 0},
                         legend={"x": 0.0, "y": 1.0})
    return figure


def distributions_figure(outcome: StudyOutcome) -> go.Figure:
    """A histogram of every quantity over the solved samples, with its limit (red) and nominal value (blue)."""
    quantities = outcome.study.quantities
    figure = make_subplots(rows=1, cols=len(quantities), subplot_titles=[f"{q.name} [{q.unit}]" for q in quantities])
    limits = {limit.quantity.name: limit.value for limit in outcome.study.limits}
    for k, quantity in enumerate(quantities, start=1):
        values = outcome.samples["values"][:, k - 1]
        figure.add_trace(go.Histogram(x=values[np.isfinite(values)], nbinsx=40, marker_color=ENVELOPE_COLOUR,
                                      showlegend=False, name=quantity.name), row=1, col=k)
        figure.add_vline(x=float(outcome.nominal[k - 1]), line_color=NOMINAL_COLOUR, row=1, col=k)
        if quantity.name in limits:
            figure.add_vline(x=limits[quantity.name], line_color=LIMIT_COLOUR, line_dash="dash", row=1, col=k)
    figure.update_layout(height=320, margin={"t": 40, "b": 30})
    return figure


def tornado_figure(outcome: StudyOutcome) -> go.Figure:
    """Per smooth quantity, the standard deviation each tolerance alone gives it (first order), largest on top."""
    first = outcome.first_order
    names = [t.name for t in outcome.study.variation.tolerances]
    units = {q.name: q.unit for q in outcome.study.quantities}
    figure = make_subplots(rows=1, cols=len(first.names), subplot_titles=[f"{n} [{units[n]}]" for n in first.names],
                           horizontal_spacing=0.12)
    for k, name in enumerate(first.names, start=1):
        order = np.argsort(first.contributions[k - 1])
        figure.add_trace(go.Bar(x=first.contributions[k - 1][order], y=[names[i] for i in order], orientation="h",
                                marker_color=NOMINAL_COLOUR, showlegend=False), row=1, col=k)
        figure.update_yaxes(showticklabels=k == 1, row=1, col=k)
    figure.update_layout(height=80 + 30 * len(names), margin={"t": 40, "b": 30, "l": 10})
    return figure


def spread_figure(outcome: StudyOutcome) -> go.Figure:
    """RMS distance of each station from its mean position: Monte Carlo and first order, and the P95 deviation."""
    segments = outcome.nominal_centerlines.shape[1] - 1
    fraction = np.arange(segments + 1) / segments
    figure = go.Figure()
    figure.add_trace(go.Scatter(x=fraction, y=outcome.deviation["percentiles"][2], name="P95 distance from nominal",
                                line={"color": "#888", "dash": "dot"}))
    if outcome.first_order is not None:
        figure.add_trace(go.Scatter(x=fraction, y=outcome.first_order.station_spread_samples,
                                    name="RMS spread, samples", line={"color": NOMINAL_COLOUR}))
        figure.add_trace(go.Scatter(x=fraction, y=outcome.first_order.station_spread, name="RMS spread, first order",
                                    line={"color": WORST_COLOUR, "dash": "dash"}))
    figure.update_layout(xaxis_title="station, fraction of the length from the start fitting", yaxis_title="mm",
                         height=340, margin={"t": 20, "b": 40})
    return figure


def clearance_figure(outcome: StudyOutcome) -> go.Figure:
    """Per pose of the sweep: P5-P95 band, median and least clearance over the samples, per obstacle, and the limit."""
    sweep = outcome.study.base.sweep
    figure = go.Figure()
    poses = np.arange(sweep.pose_count)
    limits = {limit.quantity.name: limit.value for limit in outcome.study.limits}
    for o, obstacle in enumerate(sweep.obstacles):
        low, middle, high = outcome.clearance["percentiles"][o]
        figure.add_trace(go.Scatter(x=np.concatenate([poses, poses[::-1]]), y=np.concatenate([low, high[::-1]]),
                                    fill="toself", fillcolor="rgba(127, 167, 217, 0.4)", line={"width": 0},
                                    name=f"{obstacle.name}: P5-P95"))
        figure.add_trace(go.Scatter(x=poses, y=middle, name=f"{obstacle.name}: median", line={"color": NOMINAL_COLOUR}))
        figure.add_trace(go.Scatter(x=poses, y=outcome.clearance["minimum"][o], name=f"{obstacle.name}: least",
                                    line={"color": "#444", "dash": "dot"}))
        limit = limits.get(f"clearance:{obstacle.name}")
        if limit is not None:
            figure.add_hline(y=limit, line_color=LIMIT_COLOUR, line_dash="dash")
    figure.update_layout(xaxis_title="pose number", yaxis_title="clearance [mm]", height=360, margin={"t": 20, "b": 40})
    return figure


def design_figure(outcome: StudyOutcome) -> go.Figure:
    """Heat map of the margin of rank_by over length x clocking; candidates meeting every limit marked."""
    design = outcome.design
    grid = design.grid
    limit = design.limits[design.rank_index]
    margin = design.margins[:, :, design.rank_index]
    figure = go.Figure(go.Heatmap(x=list(grid.clockings), y=list(grid.lengths), z=margin, colorscale="RdBu",
                                  zmid=0.0, colorbar={"title": f"margin [{limit.quantity.unit}]"}))
    if design.ranking:
        figure.add_trace(go.Scatter(x=[grid.clockings[j] for _, j in design.ranking],
                                    y=[grid.lengths[i] for i, _ in design.ranking], mode="markers",
                                    marker={"symbol": "circle-open", "color": "black", "size": 9},
                                    name="meets every limit"))
    if design.refined:
        figure.add_trace(go.Scatter(x=[r.clocking for r in design.refined], y=[r.length for r in design.refined],
                                    mode="markers", marker={"symbol": "x-thin-open", "color": "black", "size": 11,
                                                            "line": {"width": 2}},
                                    text=[f"margin {r.margins[design.rank_index]:.4g}" for r in design.refined],
                                    name="optimiser's clocking per length"))
    best = design.table()[:1]
    if best:
        figure.add_trace(go.Scatter(x=[best[0]["clocking_deg"]], y=[best[0]["length_mm"]], mode="markers",
                                    marker={"symbol": "star", "color": "gold", "size": 16,
                                            "line": {"color": "black", "width": 1}}, name="best"))
    figure.update_layout(xaxis_title="clocking (twist at assembly) [deg]", yaxis_title="hose length [mm]",
                         title=f"margin of {limit.describe()}", height=460, margin={"t": 50, "b": 40})
    return figure
