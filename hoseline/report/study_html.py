"""The study report: one self-contained HTML page (plotly.js embedded, no network needed to open it).

Sections: verdict (probability of breaking each limit with its 95 % interval), notes, rare failures (FORM), 3D envelope,
distributions, first order beside Monte Carlo with the tornado chart and the station spreads, Sobol' indices,
worst-case corners,
clearance per pose (sweeps), the design search (ranked table, heat map), failures, the run, the input.
"""

from __future__ import annotations

import html

import plotly.io
from plotly.offline import get_plotlyjs

from hoseline.procedures.sweep.envelope import Envelope
from hoseline.procedures.variation.design_search import CLOCKING_TOLERANCE
from hoseline.procedures.variation.study import StudyOutcome
from hoseline.report.study_figures import (
    clearance_figure,
    design_figure,
    distributions_figure,
    spread_figure,
    tornado_figure,
    view_figure,
)
from hoseline.report.study_methods import rare_failure_section, sobol_section, worst_case_section
from hoseline.report.sweep_html import STYLE, _format, _performance_table

SAMPLES_LISTED = 20  # sample indexes shown per failure cause (summary.json lists them all)


def study_report_html(outcome: StudyOutcome, envelope: Envelope | None, input_text: str = "") -> str:
    """The whole page.  envelope: the envelope mesh of the samples, or None.  input_text: the study file."""
    study = outcome.study
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>hoseline study: {html.escape(study.name)}</title>",
        f"<style>{STYLE}</style>",
        f"<script>{get_plotlyjs()}</script>",
        "</head><body>",
        f"<h1>Study: {html.escape(study.name)}</h1>",
        _intro(outcome),
    ]
    if outcome.notes:
        parts += ["<h2>Notes</h2>", "<ul>" + "".join(f"<li>{html.escape(n)}</li>" for n in outcome.notes) + "</ul>"]
    if outcome.samples:
        parts += ["<h2>Limits</h2>", _probability_table(outcome), *rare_failure_section(outcome), "<h2>Envelope</h2>",
                  "<p>Blue surface: the union of the tubes of all sampled hoses (also envelope.stl"
                  + (f", meshed on a grid of {envelope.cell:.2g} mm" if envelope is not None else "")
                  + "). Grey: some samples. Dark blue: the nominal hose. Red dashed: the worst sample of each limit "
                  "(reproduced by worst/QUANTITY/problem.toml).</p>",
                  _figure(view_figure(outcome, envelope)),
                  "<h2>Distributions</h2>", "<p>Blue line: the nominal hose; red dashed: the limit.</p>",
                  _figure(distributions_figure(outcome)), _spread_table(outcome)]
        if outcome.first_order is not None:
            parts += ["<h2>First order beside Monte Carlo</h2>",
                      "<p>Sensitivities from the exact Hessian at the nominal equilibrium (implicit function theorem)"
                      + ("; for a sweep, at the pose where each quantity has its extreme over the sweep (the shape: "
                         "at the first pose)" if study.base.sweep is not None else "")
                      + "; the first-order variance is g<sup>T</sup> Cov g. Where it disagrees with the samples beyond "
                      "their sampling error the response is not linear (a fold or fork nearby, another pose taking "
                      "over the extreme, or tolerances too large).</p>",
                      _first_order_table(outcome),
                      "<h3>Which tolerance matters most (first order)</h3>", _figure(tornado_figure(outcome))]
        parts += sobol_section(outcome)
        parts += worst_case_section(outcome)
        parts += ["<h3>Spread along the hose</h3>", _figure(spread_figure(outcome))]
        if study.base.sweep is not None and study.base.obstacle_names:
            parts += ["<h2>Clearance per pose</h2>", _figure(clearance_figure(outcome))]
    if outcome.design is not None:
        parts += ["<h2>Design search</h2>", _design_table(outcome), _figure(design_figure(outcome))]
    if outcome.failures:
        parts += ["<h2>Failed samples</h2>", "<p>Grouped by cause (the reason with its numbers as #); every failed "
                  "sample and its whole reason are in samples.csv.</p>",
                  "<table><tr><th>cause</th><th>samples</th><th>which</th><th>for example</th></tr>"
                  + "".join(f"<tr><td>{html.escape(f.cause)}</td><td class=\"number\">{f.count}</td>"
                            f"<td>{_sample_list(f.samples)}</td><td>{html.escape(f.example)}</td></tr>"
                            for f in outcome.failures) + "</table>"]
    parts += ["<h2>Run</h2>", _performance_table(outcome.run), "<h2>Input</h2>",
              f"<pre>{html.escape(input_text)}</pre>" if input_text else "<p>(no input file)</p>", "</body></html>"]
    return "\n".join(parts)


def _sample_list(samples: tuple[int, ...]) -> str:
    """The sample indexes of a failure cause, the first SAMPLES_LISTED of them."""
    listed = ", ".join(str(k) for k in samples[:SAMPLES_LISTED])
    return listed + (f", ... ({len(samples) - SAMPLES_LISTED} more)" if len(samples) > SAMPLES_LISTED else "")


def _figure(figure) -> str:
    return plotly.io.to_html(figure, include_plotlyjs=False, full_html=False)


def _intro(outcome: StudyOutcome) -> str:
    study = outcome.study
    hose = study.base.problem.hose
    kind = (f"a sweep of {study.base.pose_count} poses" if study.base.sweep is not None else "the placement")
    tolerances = "".join(f"<li>{html.escape(t.name)}: {html.escape(t.distribution)} {_size(t)}</li>"
                         for t in study.variation.tolerances)
    text = (f"<p>{outcome.count} samples ({html.escape(study.sampling.method)}, seed {study.sampling.seed}) of "
            f"{kind} of a {hose.length:g} mm hose ({hose.segments} segments).</p>")
    if outcome.precision is not None:
        status = "ok" if outcome.precision.reached else "bad"
        text += (f'<p>Sampled to a precision: <span class="{status}">{html.escape(outcome.precision.describe())}'
                 "</span>.</p>")
    correlations = "".join(
        f"<li>{html.escape(', '.join(study.variation.tolerances[k].name for k in c.tolerances))}: correlation matrix "
        f"{html.escape(str([list(row) for row in c.matrix]))} (of their normal scores, a Gaussian copula)</li>"
        for c in study.variation.correlations)
    return text + (f"<ul>{tolerances}{correlations}</ul>" if tolerances else "")


def _size(tolerance) -> str:
    """A tolerance's size for the report: its numbers, or for measured values their count and range."""
    size = tolerance.size
    if tolerance.distribution == "empirical":
        return f"{len(size)} measured values from {size[0]:g} to {size[-1]:g}"
    return ", ".join(f"{v:g}" for v in size)


def _probability_table(outcome: StudyOutcome) -> str:
    rows = ["<table><tr><th>limit</th><th>nominal</th><th>P(broken)</th><th>95 % interval</th>"
            "<th>upper end if failed samples broke it</th><th>broken / solved</th><th>Cpk</th>"
            "<th>ppm if normal</th><th>worst sample</th></tr>"]
    names = [q.name for q in outcome.study.quantities]
    for p, worst in zip(outcome.probabilities, outcome.worst):
        nominal = outcome.nominal[names.index(p.limit.quantity.name)]
        status = ' class="ok"' if p.broken == 0 else ' class="bad"'
        rows.append(f"<tr><td>{html.escape(p.limit.describe())}</td><td class=\"number\">{_format(float(nominal))}</td>"
                    f"<td class=\"number\"><span{status}>{p.estimate:.4g}</span></td>"
                    f"<td class=\"number\">[{p.low:.3g}, {p.high:.3g}]</td><td class=\"number\">{p.high_with_failed:.3g}</td>"
                    f"<td class=\"number\">{p.broken} / {p.solved}</td><td class=\"number\">{p.cpk:.3g}</td>"
                    f"<td class=\"number\">{p.ppm:.3g}</td><td class=\"number\">{_format(worst)}</td></tr>")
    rows.append("</table>")
    return "\n".join(rows)


def _spread_table(outcome: StudyOutcome) -> str:
    rows = ["<p>Each estimate with its 95 % confidence interval below it (the mean's by Student's t, the "
            "percentiles' by order statistics, distribution-free).</p>"
            "<table><tr><th>quantity</th><th>nominal</th><th>mean</th><th>std</th><th>P5</th><th>P50</th><th>P95</th>"
            "<th>min</th><th>max</th></tr>"]
    for q, s, nominal in zip(outcome.study.quantities, outcome.spreads, outcome.nominal):
        cells = [_format(float(nominal)), _with_interval(s.mean, s.mean_interval), _format(s.std),
                 *(_with_interval(v, i) for v, i in zip(s.percentiles, s.percentile_intervals)),
                 _format(s.minimum), _format(s.maximum)]
        rows.append(f"<tr><td>{html.escape(q.name)} [{html.escape(q.unit)}]</td>"
                    + "".join(f'<td class="number">{cell}</td>' for cell in cells) + "</tr>")
    rows.append("</table>")
    return "\n".join(rows)


def _with_interval(value: float, interval: tuple[float, float]) -> str:
    """A value with its confidence interval on the line below."""
    low, high = interval
    return f"{_format(float(value))}<br><small>[{_format(float(low))}, {_format(float(high))}]</small>"


def _first_order_table(outcome: StudyOutcome) -> str:
    first = outcome.first_order
    rows = ["<table><tr><th>quantity</th><th>std, first order</th><th>std, Monte Carlo</th><th>z</th><th>verdict</th></tr>"]
    checks = list(zip(first.names, first.agreements)) + [("shape: RMS station spread [mm]", first.shape)]
    for name, check in checks:
        verdict = '<span class="ok">agrees</span>' if check.agrees else '<span class="bad">disagrees</span>'
        rows.append(f"<tr><td>{html.escape(name)}</td><td class=\"number\">{check.first_order_variance ** 0.5:.4g}</td>"
                    f"<td class=\"number\">{check.monte_carlo_variance ** 0.5:.4g}</td>"
                    f"<td class=\"number\">{check.z:+.1f}</td><td>{verdict}</td></tr>")
    rows.append("</table>")
    return "\n".join(rows)


def _design_table(outcome: StudyOutcome) -> str:
    design = outcome.design
    grid = design.grid
    intro = (f"<p>{len(grid.lengths)} lengths x {len(grid.clockings)} clockings"
             + (f", each over {grid.samples} tolerance samples (margins: 5th percentile)" if grid.samples else "")
             + (", each over the study's tolerance samples to first order at the candidate (margins: 5th percentile "
                "of the linearised margin)" if grid.first_order else "")
             + f"; ranked by the margin of {html.escape(grid.rank_by)}. {len(design.ranking)} grid candidates meet "
             "every limit.</p>")
    if design.refined is not None:
        optimised = sum(r.optimised for r in design.refined)
        intro += (f"<p>Optimiser: for each of the {len(design.refined)} lengths with a grid candidate meeting every "
                  f"limit, the margin of {html.escape(grid.rank_by)} maximised over the clocking between the grid points "
                  f"either side of its best candidate, every limit a constraint (COBYQA, to {CLOCKING_TOLERANCE:g} deg); "
                  f"{optimised} improved on the grid, the others keep the grid's clocking (column \"clocking from\"). "
                  f"{sum(r.evaluations for r in design.refined)} candidates solved. The table ranks these; the heat map "
                  "shows the grid, the optimiser's candidates as crosses.</p>")
    rows = design.table()[:20]
    if not rows:
        return intro + '<p class="bad">No candidate meets every limit.</p>'
    head = "".join(f"<th>{html.escape(key)}</th>" for key in rows[0])
    body = "".join("<tr>" + "".join(f'<td class="number">{_format(v)}</td>' for v in row.values()) + "</tr>"
                   for row in rows)
    return intro + f"<table><tr>{head}</tr>{body}</table>"
