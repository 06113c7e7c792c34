"""Model against scan: the scan's centreline, its deviation from the model, pass or fail.

A Comparison bundles what a validation report shows for one scan: the placed model, the
scan points, the fitted centreline (radius per section), the deviation of every scan
station from the model centreline, optionally the thesis' reference-point form, and the
thresholds it is judged by.  Units: mm.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hoseline.procedures.scans.centerline_fit import CenterlineFit, fit_centerline
from hoseline.procedures.scans.deviation import Deviation, Thresholds, deviation
from hoseline.procedures.placement.result import Result


@dataclass
class Comparison:
    """One scan against the model placed at the scan's twist.

    label: name in reports.  result: the placed model.  scan: (n, 3) scan points, mm.
    fit: the scan's fitted centreline.  deviation: scan stations against the model.
    thresholds: the acceptance limits.  reference: reference points against the model, or None.
    """

    label: str
    result: Result
    scan: np.ndarray
    fit: CenterlineFit
    deviation: Deviation
    thresholds: Thresholds
    reference: Deviation | None = None

    @property
    def passed(self) -> bool:
        """True when the scan stations' deviation is within the thresholds."""
        return self.deviation.passes(self.thresholds)

    def summary(self) -> dict:
        """Numbers for result files and tables (mm, degrees)."""
        return {
            "label": self.label,
            "twist_deg": self.result.problem.end_twist_deg,
            "deviation": self.deviation.summary(),
            "threshold_mean_mm": self.thresholds.mean,
            "threshold_max_mm": self.thresholds.max,
            "passed": self.passed,
            "radius_median_mm": self.fit.radius_median,
            "radius_scatter_mm": self.fit.radius_scatter,
            "sections_with_radius_fixed": int(np.sum(~self.fit.radius_fitted)),
            "scan_points": int(self.scan.shape[0]),
            "outliers_dropped": int(self.fit.outliers),
            "gaps_mm": [list(gap) for gap in self.fit.gaps],
            "reference_points": None if self.reference is None else self.reference.summary(),
        }


def compare_scan(
    result: Result,
    scan: np.ndarray,
    label: str,
    *,
    thresholds: Thresholds | None = None,
    reference_points: np.ndarray | None = None,
    fit: CenterlineFit | None = None,
) -> Comparison:
    """Compare a placed model with a scan of the hose in the same mounts and twist.

    thresholds: default Thresholds.thesis(twist).  reference_points: (k, 3) points whose
    distance to the model is reported too (the thesis' form).  fit: an already fitted
    centreline of this scan (skips the fit).
    """
    if fit is None:
        fit = fit_centerline(scan, result.problem.hose.outer_radius, start_hint=result.problem.start.point)
    limits = thresholds or Thresholds.thesis(result.problem.end_twist_deg)
    reference = None if reference_points is None else deviation(result.centerline, reference_points)
    return Comparison(label, result, scan, fit, deviation(result.centerline, fit.points), limits, reference)
