"""Report tables of the study's methods beyond sampling: rare failures (FORM, SORM, importance sampling)."""

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
    rows.append("</table>")
    text = ("<p>FORM: the most probable failure point (the design point) is the hose with the tolerances nearest "
            "the nominal, in standard normal units, that breaks the limit; beta is its distance and Phi(-beta) the "
            "probability (exact for a limit linear in the standard normal coordinates). SORM corrects for the "
            "curvature of the failure surface there (Breitung). Importance sampling solves hoses drawn around the "
            "design point and weights them, an unbiased Monte Carlo check of both. Solves: placements (or sweeps) "
            "with their sensitivities that FORM and SORM took. Each design point is written as "
            "design_point/QUANTITY/problem.toml.</p>")
    return ["<h2>Rare failures</h2>", text, "\n".join(rows)]


def _probability(value: float) -> str:
    """A probability to three significant digits ('-' when not a number)."""
    return f"{value:.3g}" if math.isfinite(value) else "-"
