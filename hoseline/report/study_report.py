"""Write everything a study produces into one output directory, all files or none.

    report.html          the self-contained interactive report
    envelope.stl         the union of the tubes of all sampled hoses (mm), for packaging
    summary.json         the study, nominal values, spreads, probabilities, first order, design ranking, notes
    samples.csv          one row per sample (failed ones with their reason); samples.npz the raw arrays
    envelope.csv         per station: P5/P50/P95 and extreme positions, distance from the nominal shape
    clearance_by_pose.csv  per pose of a sweep: clearance distribution per obstacle
    sensitivities.csv    derivatives of the quantities (placements and sweeps)
    station_sensitivities.csv  derivatives of the nominal hose's stations, per station and varied coordinate
    design.csv, design_grid.csv   the ranked candidates, and every candidate
    worst/QUANTITY/problem.toml   (and sweep.toml) the worst sample of each limit
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hoseline.io.atomic import staged_directory, write_text
from hoseline.io.obstacle_mesh import write_stl
from hoseline.io.study_results import remove_partial, write_study_data
from hoseline.procedures.sweep.envelope import Envelope, swept_envelope
from hoseline.procedures.variation.study import StudyOutcome
from hoseline.report.study_html import study_report_html


def sampled_envelope(outcome: StudyOutcome) -> Envelope | None:
    """The union of the tubes of every solved sample at every kept pose, meshed (None if none was solved)."""
    if not outcome.samples or not np.any(~outcome.samples["failed"]):
        return None
    shapes = outcome.samples["shapes"][~outcome.samples["failed"]]
    return swept_envelope(shapes.reshape((-1,) + shapes.shape[2:]), outcome.study.base.problem.hose.outer_radius)


def write_study_report(outcome: StudyOutcome, out_dir: str | Path, input_text: str, base_path: Path) -> Path:
    """Write the files of the module doc into `out_dir` (created), then drop its .partial batches.

    input_text: the study file as read, echoed in the report.  base_path: the study's problem or sweep
    file (a sweep's worst samples refer to its pose tables and meshes).  On any failure nothing is written.
    """
    out_dir = Path(out_dir)
    envelope = sampled_envelope(outcome)
    with staged_directory(out_dir) as staging:
        write_text(staging / "report.html", study_report_html(outcome, envelope, input_text))
        if envelope is not None:
            write_stl(staging / "envelope.stl", envelope.vertices, envelope.faces)
        write_study_data(outcome, staging, base_path)
    remove_partial(out_dir)
    return out_dir
