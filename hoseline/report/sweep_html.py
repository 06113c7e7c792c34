"""The sweep report: one self-contained HTML page an engineer reads (no network needed to open it).

Sections: verdict, interactive 3D view with a slider through the poses, plots against
travel (a marker follows the slider), worst cases, snap-throughs, the free-roll
comparison, the run's figures (with the swept envelope's grid), and the input echoed.
plotly.js is embedded once, compressed (compressed_plotly.py).
"""

from __future__ import annotations

import html
import math

from hoseline.procedures.sweep.envelope import Envelope
from hoseline.procedures.sweep.result import SweepResult
from hoseline.report.compressed_plotly import figure_div, plotly_loader
from hoseline.report.sweep_figures import plots_figure, shown_poses, travel_axis, view_figure

VIEW_ID = "view3d"
PLOTS_ID = "plots"

STYLE = """
body { font-family: system-ui, sans-serif; margin: 1.5em auto; max-width: 1200px; color: #222; }
h1 { font-size: 1.5em; } h2 { font-size: 1.2em; margin-top: 1.6em; border-bottom: 1px solid #ccc; }
table { border-collapse: collapse; } td, th { padding: 0.25em 0.7em; border-bottom: 1px solid #ddd; text-align: left; }
td.number { text-align: right; font-variant-numeric: tabular-nums; }
.ok { color: #2a9d3c; font-weight: bold; } .bad { color: #d62828; font-weight: bold; }
pre { background: #f5f5f5; padding: 0.8em; overflow-x: auto; font-size: 0.85em; }
.subtitle { color: #666; margin-top: -0.6em; }
"""

# moves a vertical line on the plots to the pose the 3D view's slider shows
SLIDER_LINK = """
(function () {
  var view = document.getElementById("%(view)s"), plots = document.getElementById("%(plots)s");
  var xs = %(xs)s;
  function mark(index) {
    var x = xs[index];
    Plotly.relayout(plots, {shapes: [{type: "line", xref: "x", yref: "paper", x0: x, x1: x, y0: 0, y1: 1,
                                      line: {color: "#888", width: 1, dash: "dot"}}]});
  }
  view.on("plotly_sliderchange", function (event) { mark(event.slider.active); });
  view.on("plotly_animated", function () { mark(view.layout.sliders[0].active || 0); });
  mark(0);
})();
"""

VIEW_LEGEND = ("<p>Drag the slider to step through the poses. Blue: the hose with both ends clamped and the twist locked "
               "at assembly.{free} Green/red lines: the nearest approach to each obstacle (red below the required "
               "clearance); crosses: the worst approach over the whole sweep.{contact}</p>")
FREE_LEGEND = " Dashed orange: the same hose with its end fitting free to spin (the common modelling error)."
CONTACT_LEGEND = (" Brown: the obstacles of [contact], which the hose rests on and never enters; dots: where it presses "
                  "on them at the pose shown, coloured by the push (N).")


def sweep_report_html(result: SweepResult, input_text: str = "", performance: dict | None = None,
                      envelope: Envelope | None = None) -> str:
    """The whole report page as a string.

    input_text: the sweep file as read, echoed at the end.  performance: figures of the run
    (poses per second, ...) from SweepResult.performance(), shown as a small table.
    envelope: the swept envelope written beside the report, for its grid and size.
    """
    name = html.escape(result.sweep.problem.name)
    x, _ = travel_axis(result)
    link = SLIDER_LINK % {"view": VIEW_ID, "plots": PLOTS_ID, "xs": [float(x[k]) for k in shown_poses(result)]}
    free = FREE_LEGEND if result.free_centerlines is not None else ""
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{name}: hoseline sweep report</title>",
        f"<style>{STYLE}</style>",
        "</head><body>",
        f"<h1>{name}</h1>",
        '<p class="subtitle">hoseline sweep report</p>',
        _verdict(result),
        "<h2>3D view</h2>",
        VIEW_LEGEND.format(free=free, contact=CONTACT_LEGEND if result.contacts else ""),
        figure_div(VIEW_ID, view_figure(result)),
        "<h2>Along the sweep</h2>",
        figure_div(PLOTS_ID, plots_figure(result)),
        "<h2>Worst cases</h2>",
        _worst_table(result),
        "<h2>Snap-throughs</h2>",
        _snaps(result),
        "<h2>Run</h2>",
        _performance_table(performance or {}),
        _envelope_note(envelope, result.sweep.problem.hose.outer_radius),
        "<h2>Input</h2>",
        f"<pre>{html.escape(input_text)}</pre>" if input_text else "<p>(built-in demo: no input file)</p>",
        plotly_loader([VIEW_ID, PLOTS_ID], link),
        "</body></html>",
    ]
    return "\n".join(parts)


def _envelope_note(envelope: Envelope | None, radius: float) -> str:
    """One paragraph: the envelope's file, its grid and what that means for its accuracy (radius: the hose's, mm)."""
    if envelope is None:
        return ""
    coarsened = "" if not envelope.coarsened else \
        f" (coarsened from {envelope.requested_cell:.3g} mm to stay within the memory and size budgets)"
    widened = "" if envelope.radius <= radius else \
        f"; the hose, thinner than a cell, is meshed {envelope.radius:.3g} mm in radius instead of {radius:.3g} mm"
    return (f"<p>Swept envelope: <code>envelope.stl</code>, {len(envelope.faces)} triangles on a grid of "
            f"{envelope.cell:.3g} mm{coarsened}; its surface is within about one cell of the exact union of the "
            f"hose's tube over the poses{widened}.</p>")


def _verdict(result: SweepResult) -> str:
    """One paragraph: poses, clearance verdict per obstacle, bend radius verdict."""
    names = dict.fromkeys(stage.name for stage in result.sweep.stages)  # in order, each once
    lines = [f"<p>{result.pose_count} poses ({', '.join(html.escape(name) for name in names)}), "
             f"hose {result.sweep.problem.hose.length:g} mm with {result.sweep.problem.hose.segments} segments.</p><ul>"]
    for clearance in result.clearances:
        name = html.escape(clearance.obstacle.name)
        required = clearance.obstacle.clearance
        first = clearance.first_violation
        worst = clearance.worst
        if first is None:
            lines.append(f'<li><span class="ok">clear of {name}</span>: least {clearance.distance[worst]:.1f} mm '
                         f"(required {required:g} mm) at {html.escape(result.travel_label(worst))}</li>")
        else:
            lines.append(f'<li><span class="bad">too close to {name}</span> from {html.escape(result.travel_label(first))} '
                         f"on: least {clearance.distance[worst]:.1f} mm (required {required:g} mm) at "
                         f"{html.escape(result.travel_label(worst))}, s = {clearance.s[worst]:.0f} mm along the hose</li>")
    margin = result.bend_radius_margin
    if margin is not None:
        worst = int(margin.argmin())
        verdict = '<span class="ok">bend radius within the minimum</span>' if margin[worst] >= 0 else \
            '<span class="bad">bent tighter than the minimum bend radius</span>'
        lines.append(f"<li>{verdict}: smallest {result.min_bend_radius[worst]:.1f} mm at "
                     f"{html.escape(result.travel_label(worst))}</li>")
    if result.separation is not None:
        worst = int(result.separation.argmax())
        lines.append(f"<li>modelling the end as free to spin would misplace the hose by up to "
                     f"{result.separation[worst]:.1f} mm (at {html.escape(result.travel_label(worst))})</li>")
    lines.append(f"<li>{len(result.snaps)} snap-through(s)</li></ul>")
    return "\n".join(lines)


def _worst_table(result: SweepResult) -> str:
    rows = ["<table><tr><th>quantity</th><th>worst</th><th>limit</th><th>pose</th><th>where along the hose</th></tr>"]
    for row in result.worst_cases():
        status = "" if row["ok"] is None else (' class="ok"' if row["ok"] else ' class="bad"')
        limit = "" if row["limit"] is None else f"{row['limit']:.4g} {row['unit']}"
        where = "" if row["s"] is None else f"s = {row['s']:.1f} mm"
        rows.append(f"<tr><td>{html.escape(row['quantity'])}</td><td class=\"number\"><span{status}>"
                    f"{row['value']:.4g} {row['unit']}</span></td><td>{limit}</td>"
                    f"<td>{html.escape(row['travel'])} (#{row['pose']})</td><td>{where}</td></tr>")
    rows.append("</table>")
    return "\n".join(rows)


def _snaps(result: SweepResult) -> str:
    if not result.snaps:
        return "<p>None: the equilibrium stayed stable and moved smoothly from pose to pose.</p>"
    items = [f"<li>at {html.escape(result.travel_label(snap.pose))} (#{snap.pose}): the hose jumped "
             f"{snap.jump:.1f} mm. {html.escape(' '.join(snap.events))}</li>" for snap in result.snaps]
    return "<ul>" + "\n".join(items) + "</ul>"


def _performance_table(performance: dict) -> str:
    rows = [f"<tr><td>{html.escape(key)}</td><td class=\"number\">{_format(value)}</td></tr>"
            for key, value in performance.items()]
    return "<table>" + "\n".join(rows) + "</table>"


def _format(value) -> str:
    if isinstance(value, float):
        return "-" if not math.isfinite(value) else f"{value:.4g}"
    return html.escape(str(value))
