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

NOISE_SIGMAS = 3.0  # the mean deviation noise can explain, in standard uncertainties of a scan station


@dataclass
class Comparison:
    """One scan against the model placed at the scan's twist.

    label: name in reports.  result: the placed model.  scan: (n, 3) scan points, mm.
    fit: the scan's fitted centreline.  deviation: scan stations against the model.
    thresholds: the acceptance limits.  reference: reference points against the model, or None.
    Passed when the deviation is within the limits and within what the scan's noise explains (noise_allowance).
    """

    label: str
    result: Result
    scan: np.ndarray
    fit: CenterlineFit
    deviation: Deviation
    thresholds: Thresholds
    reference: Deviation | None = None

    @property
    def within_limits(self) -> bool:
        """True when the scan stations' deviation is within the acceptance limits (mean, largest)."""
        return self.deviation.passes(self.thresholds)

    @property
    def noise_allowance(self) -> float:
        """The mean deviation (mm) that the scan's own noise and the model's discretisation can explain: the model's
        estimated discretisation error (its largest station error, Result.discretisation_error; 0 when not
        estimated) plus NOISE_SIGMAS times the mean standard uncertainty of the scan's stations (CenterlineFit.
        axis_sigma).  A station of an exact model is off by a Rayleigh distance of mean 1.25 sigma and standard
        deviation 0.65 sigma, so a mean of 3 sigma is out of reach of noise even for one independent station."""
        model = self.result.discretisation_error or 0.0
        return float(model + NOISE_SIGMAS * np.mean(self.fit.axis_sigma))

    @property
    def explained_by_noise(self) -> bool:
        """True when the mean deviation is within noise_allowance: the scan cannot tell the model from the truth."""
        return self.deviation.mean <= self.noise_allowance

    @property
    def passed(self) -> bool:
        """True when the deviation is within the limits and, unless the thresholds say otherwise, explained by the
        scan's noise (a hose 1 % short can pass the thesis' 6 mm and still be plainly off)."""
        return self.within_limits and (not self.thresholds.noise or self.explained_by_noise)

    @property
    def verdict(self) -> str:
        """PASS, or FAIL with the reason: "FAIL (limits)", "FAIL (noise)" or "FAIL (limits, noise)"."""
        if self.passed:
            return "PASS"
        reasons = ([] if self.within_limits else ["limits"]) + \
            (["noise"] if self.thresholds.noise and not self.explained_by_noise else [])
        return f"FAIL ({', '.join(reasons)})"

    def summary(self) -> dict:
        """Numbers for result files and tables (mm, degrees)."""
        return {
            "label": self.label,
            "twist_deg": self.result.problem.end_twist_deg,
            "deviation": self.deviation.summary(),
            "threshold_mean_mm": self.thresholds.mean,
            "threshold_max_mm": self.thresholds.max,
            "within_limits": self.within_limits,
            "noise_allowance_mm": self.noise_allowance,
            "explained_by_noise": self.explained_by_noise,
            "noise_check": self.thresholds.noise,
            "passed": self.passed,
            "station_sigma_mean_mm": float(np.mean(self.fit.axis_sigma)),
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
