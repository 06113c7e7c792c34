"""A Result's stability verdict when its margin was not computed (None: the studio's drag frames build such results):
`stable` is None, and result.json and the summary table say so instead of failing or calling it unstable."""

import json
from dataclasses import replace

from rich.console import Console
from validation_cases import brake_hose

from hoseline import solve
from hoseline.report.table import summary_table


def table_text(result) -> str:
    console = Console(width=200, record=True)
    console.print(summary_table([result], ["case"]))
    return console.export_text()


def test_a_result_without_its_margin_has_no_verdict_and_reports_say_so():
    placed = solve(brake_hose(segments=20), estimate_error=False)
    assert placed.stable is True and json.loads(json.dumps(placed.summary()))["stable"] is True
    unknown = replace(placed, stability_margin=None)
    assert unknown.stable is None
    summary = json.loads(json.dumps(unknown.summary()))
    assert summary["stable"] is None and summary["stability_margin_N_per_rad2"] is None
    row = next(line for line in table_text(unknown).splitlines() if "stability margin" in line)
    assert "n/a" in row and "UNSTABLE" not in row and "stable" not in row.replace("stability", "")
    negative = replace(placed, stability_margin=-1.0)
    assert negative.stable is False and "UNSTABLE" in table_text(negative)
