"""Shared by the validation tests: the thesis brake hose with weight, and synthetic scans of it."""

import numpy as np

from hoseline import Hose, Mount, Problem, solve
from hoseline.model.hose import isotropic_torsional_stiffness
from hoseline.procedures.scans.calibration import ScanCase
from hoseline.procedures.scans.centerline_fit import fit_centerline
from hoseline.procedures.scans.synthetic_scan import ScanDefects, synthetic_scan

EI = 149563.0  # N*mm^2
FACTOR = 25.0
RADIUS = 5.05  # mm
ONE_SIDED = ScanDefects(density=1.0, noise=0.1, outlier_fraction=0.02, view=(0.2, 0.3, -1.0), gaps=((150.0, 170.0),))
ALL_ROUND = ScanDefects(density=0.5, noise=0.05, outlier_fraction=0.0)


def brake_hose(bending=EI, factor=FACTOR, segments=40, twist=0.0, mass=0.3):
    """The thesis hose between the appendix A mounts, weighing `mass` kg/m under gravity -z."""
    hose = Hose(length=330.6, outer_diameter=2 * RADIUS, bending_stiffness=bending, segments=segments,
                torsional_stiffness=factor * isotropic_torsional_stiffness(bending), mass_per_length=mass)
    return Problem(hose, Mount([-13.0, 0.0, -11.25], [0.0, 1.0, 0.0]), Mount([-173.064, -7.0, -11.25], [1.0, 0.0, 0.0]),
                   twist, np.array([0.0, 0.0, -9.81]))


def scanned(twist, defects=ONE_SIDED, segments=80, seed=0):
    """(true result at `segments`, its synthetic scan)."""
    truth = solve(brake_hose(segments=segments, twist=twist))
    return truth, synthetic_scan(truth.s, truth.centerline, RADIUS, defects, seed=seed)


def scan_cases(truth_at, twists=(0.0, 180.0)):
    """ScanCases fitted to synthetic scans all round (ALL_ROUND) of truth_at(twist), a problem solved at each twist."""
    cases = []
    for seed, twist in enumerate(twists):
        truth = solve(truth_at(twist), estimate_error=False)
        points = synthetic_scan(truth.s, truth.centerline, RADIUS, ALL_ROUND, seed=seed)
        cases.append(ScanCase(twist, fit_centerline(points, RADIUS, start_hint=truth.centerline[0]).points))
    return cases
