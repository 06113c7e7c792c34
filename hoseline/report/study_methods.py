"""Report tables of the study's methods beyond sampling: rare failures (FORM, SORM, importance sampling),
Sobol' indices beside the first-order shares of the tornado chart, and the worst-case corners beside the
first order and Monte Carlo."""

from __future__ import annotations

import html
import math

from hoseline.procedures.variation.study import StudyOutcome
from hoseline.report.sweep_html import _format

DESIGN_POINT_SHOWN = 1e-3  # of a coordinate's largest deviation at the design point: smaller ones are not listed


def rare_failure_section(outcome: StudyOutcome) -> list[str]:
    """The heading, explanation and table of the rare failures (empty without [reliability])."""
    if not outcome.rare_events:
        return []
    variation = outcome.study.variation
    rows = ["<table><tr><th>limit</th><th>beta</th><th>FORM P</th><th>SORM P</th><th>importance sampling P</th>"
            "<th>95 % interval</th><th>samples (failed)</th><th>solves</th><th>most probable failure point</th></tr>"]
    for event in outcome.rare_events:
        check = event.importance
        largest = max((abs(event.deviation[k]) for k in variation.varied), default=0.0)
        shown = ", ".join(f"{variation.names[k]} {event.deviation[k]:+.3g} {variation.units[k]}"
                          for k in variation.varied if abs(event.deviation[k]) > DESIGN_POINT_SHOWN * largest)
        point = html.escape(shown) if event.point.converged else f"not found: {html.escape(event.point.message)}"
        sorm = "" if event.sorm is None else _probability(event.sorm)
        rows.append(
            f"<tr><td>{html.escape(event.limit.describe())}</td><td class=\"number\">{_format(event.point.beta)}</td>"
            f"<td class=\"number\">{_probability(event.form)}</td><td class=\"number\">{sorm}</td>"
            + (f"<td class=\"number\">{_probability(check.estimate)}</td>"
               f"<td class=\"number\">[{check.low:.3g}, {check.high:.3g}]</td>"
               f"<td class=\"number\">{check.samples} ({check.failed})</td>" if check is not None
               else "<td></td><td></td><td></td>")
            + f"<td class=\"number\">{event.evaluations}</td><td>{point}</td></tr>")
    union = outcome.rare_union
    if union is not None:
        check = union.importance
        rows.append(f"<tr><td>any of these {len(union.limits)}</td><td></td><td class=\"number\">"
                    f"{_probability(union.form)}</td><td></td>"
                    + (f"<td class=\"number\">{_probability(check.estimate)}</td>"
                       f"<td class=\"number\">[{check.low:.3g}, {check.high:.3g}]</td>"
                       f"<td class=\"number\">{check.samples} ({check.failed})</td>" if check is not None
                       else "<td></td><td></td><td></td>")
                    + "<td></td><td>FORM: the union of the limits' tangent half-spaces; importance sampling: every "
                    "design point's samples pooled</td></tr>")
    rows.append("</table>")
    text = ("<p>FORM: the most probable failure point (the design point) is the hose with the tolerances nearest "
            "the nominal, in standard normal units, that breaks the limit; beta is its distance and Phi(-beta) the "
            "probability (exact for a limit linear in the standard normal coordinates). SORM corrects for the "
            "curvature of the failure surface there (Breitung). Importance sampling solves hoses drawn around the "
            "design point and weights them, an unbiased Monte Carlo check of both. Solves: placements (or sweeps) "
            "with their sensitivities that FORM and SORM took. Each design point is written as "
            "design_point/QUANTITY/problem.toml.</p>")
    return ["<h2>Rare failures</h2>", text, "\n".join(rows)]


def sobol_section(outcome: StudyOutcome) -> list[str]:
    """The heading, explanation and one table per quantity of the Sobol' indices (empty without [sobol]); a quantity
    whose first-order variance disagrees with the samples is flagged (its tornado shares are wrong)."""
    sobol = outcome.sobol
    if sobol is None:
        return []
    study = outcome.study
    labels = [t.name for t in study.variation.tolerances]
    first = outcome.first_order
    parts = ["<h3>Which tolerance matters most (Sobol' indices)</h3>",
             f"<p>From a Saltelli design of {sobol.count} base rows ({sobol.count * (len(labels) + 2)} hoses; "
             f"{sobol.rows} rows with every hose solved). First order S: the share of the quantity's variance the "
             "tolerance explains alone; total ST: the share it has a part in, with the others too. Beside them the "
             "first-order (tornado) share, (contribution / first-order standard deviation)<sup>2</sup>, which is "
             "right only where the response is linear over the tolerances. Brackets: 95 % bootstrap intervals.</p>"]
    for q, quantity in enumerate(study.quantities):
        flagged, shares = "", None
        if first is not None and quantity.name in first.names:
            k = first.names.index(quantity.name)
            total = float(first.contributions[k] @ first.contributions[k])
            shares = first.contributions[k] ** 2 / total if total > 0.0 else None
            if not first.agreements[k].agrees:
                flagged = (' <span class="bad">first order flagged wrong for this quantity: use the Sobol\' '
                           "indices, not the tornado chart</span>")
        rows = [f"<p><b>{html.escape(quantity.name)}</b>{flagged}</p>",
                "<table><tr><th>tolerance</th><th>first-order share (tornado)</th><th>S</th><th>ST</th></tr>"]
        for k, label in enumerate(labels):
            rows.append(f"<tr><td>{html.escape(label)}</td><td class=\"number\">"
                        f"{'' if shares is None else f'{shares[k]:.3f}'}</td>"
                        f"<td class=\"number\">{sobol.first[q, k]:.3f} [{sobol.first_low[q, k]:.3f}, "
                        f"{sobol.first_high[q, k]:.3f}]</td><td class=\"number\">{sobol.total[q, k]:.3f} "
                        f"[{sobol.total_low[q, k]:.3f}, {sobol.total_high[q, k]:.3f}]</td></tr>")
        rows.append("</table>")
        parts.append("\n".join(rows))
    return parts


def worst_case_section(outcome: StudyOutcome) -> list[str]:
    """The heading, explanation and table of the worst-case corners (empty without worst_case)."""
    if not outcome.worst_cases:
        return []
    variation = outcome.study.variation
    names = [q.name for q in outcome.study.quantities]
    first = outcome.first_order
    rows = ["<table><tr><th>quantity</th><th>nominal</th><th>worst case, first order</th><th>worst case, solved</th>"
            "<th>first order, 3 sigma</th><th>Monte Carlo extreme</th><th>corner</th></tr>"]
    for case in outcome.worst_cases:
        down = case.quantity.sense == "at least"
        spread = outcome.spreads[names.index(case.quantity.name)] if outcome.spreads else None
        sampled = "" if spread is None else _format(spread.minimum if down else spread.maximum)
        three = ""
        if first is not None and case.quantity.name in first.names:
            k = first.names.index(case.quantity.name)
            three = _format(float(first.mean[k] + (-3.0 if down else 3.0) * first.variance[k] ** 0.5))
        corner = ", ".join(f"{variation.names[k]} {case.corner[k]:+.3g} {variation.units[k]}" for k in variation.varied
                           if case.corner[k] != 0.0)
        solved = _format(case.solved) if not case.reason else f"not solved: {html.escape(case.reason)}"
        rows.append(f"<tr><td>{html.escape(case.quantity.name)} [{html.escape(case.quantity.unit)}]</td>"
                    f"<td class=\"number\">{_format(case.nominal)}</td><td class=\"number\">{_format(case.first_order)}</td>"
                    f"<td class=\"number\">{solved}</td><td class=\"number\">{three}</td>"
                    f"<td class=\"number\">{sampled}</td><td>{html.escape(corner)}</td></tr>")
    rows.append("</table>")
    text = ("<p>Each quantity at the corner of the tolerances that makes it worst to first order (every tolerance at "
            "the end of its range along the derivative: bounded ones at their bounds, normal and lognormal ones at "
            "3 standard deviations, a sphere or cone at its rim): the linear worst-case stack, and the hose solved "
            "at that corner (worst_case/QUANTITY/problem.toml). Beside them the first-order mean -/+ 3 standard "
            "deviations and the most extreme sample.</p>")
    return ["<h2>Worst case</h2>", text, "\n".join(rows)]


def _probability(value: float) -> str:
    """A probability to three significant digits ('-' when not a number)."""
    return f"{value:.3g}" if math.isfinite(value) else "-"
