"""Write everything a sweep produces into one output directory, all files or none.

    report.html   the self-contained interactive report
    view.png      the hose through the sweep, worst-clearance pose highlighted
    curves.png    clearance, bend radius, twisting moment, free-roll separation against travel
    envelope.stl  the swept envelope of the hose (mm), for packaging studies
    poses.csv, shapes.csv, sweep.json   the numbers (io/sweep_results.py)
    obstacle_<name>.stl   each obstacle made in code (the demo's strut), as the clearance was measured
"""

from __future__ import annotations

from pathlib import Path

from hoseline.io.atomic import staged_directory, write_text
from hoseline.io.sweep_results import write_sweep_data
from hoseline.procedures.sweep.envelope import swept_envelope
from hoseline.procedures.sweep.result import SweepResult
from hoseline.report.sweep_html import sweep_report_html
from hoseline.report.sweep_png import plot_sweep_curves, plot_sweep_view

SWEEP_FILES = ("report.html", "view.png", "curves.png", "envelope.stl", "poses.csv", "shapes.csv", "sweep.json")


def write_sweep_report(result: SweepResult, out_dir: str | Path, input_text: str = "") -> Path:
    """Write the files of SWEEP_FILES (and the obstacles made in code) into `out_dir` (created);
    on any failure nothing is written.

    input_text: the sweep file as read, echoed in the report.  Returns out_dir.
    """
    out_dir = Path(out_dir)
    envelope = swept_envelope(result.centerlines, result.sweep.problem.hose.outer_radius)
    with staged_directory(out_dir) as staging:
        write_text(staging / "report.html", sweep_report_html(result, input_text, result.performance(), envelope))
        plot_sweep_view(result, staging / "view.png")
        plot_sweep_curves(result, staging / "curves.png")
        write_sweep_data(result, staging, envelope)
    return out_dir
