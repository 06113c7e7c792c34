"""Validation demo: synthetic scans of the thesis brake hose, compared with the model, calibrated, and
the thesis' stiffener model followed through the twist.

The "real" hose is the thesis brake hose with weight (0.3 kg/m, gravity -z) and 25x torsion,
solved at 160 segments; its scans are made from that shape (synthetic_scan.py): at 0 deg
all round, three more at 0 deg left with a residual twist of -15, +15 and +30 deg (preset
and hysteresis after twisting and releasing), and at 180 deg from one side with a gap and
stray points.  The model starts from catalogue values (isotropic torsion, EI 20 % low) with
40 segments, is compared, calibrated on the 0 and 180 deg scans, and compared again.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from hoseline.io.atomic import staged_directory, write_text
from hoseline.io.problem_file import problem_to_toml
from hoseline.io.scans import write_ply
from hoseline.model import Hose, Mount, Problem
from hoseline.model.hose import isotropic_torsional_stiffness
from hoseline.model.stiffeners import thesis_preset
from hoseline.procedures.scans.calibration import Calibration, ScanCase, calibrate
from hoseline.procedures.scans.centerline_fit import fit_centerline
from hoseline.procedures.placement.sequence import solve
from hoseline.procedures.scans.scatter import ScatterEnvelope, scatter_envelope
from hoseline.procedures.scans.synthetic_scan import ScanDefects, synthetic_scan
from hoseline.procedures.placement.twist_path import TwistPath, follow_twist
from hoseline.procedures.scans.validation import Comparison, compare_scan
from hoseline.report.validation import write_validation_report

EI = 292.7985 * 510.8053  # N*mm^2, thesis appendix C
TRUE_FACTOR = 25.0
MASS = 0.3  # kg/m
GRAVITY = (0.0, 0.0, -9.81)
START = Mount([-13.0, 0.0, -11.25], [0.0, 1.0, 0.0])
END = Mount([-173.064, -7.0, -11.25], [1.0, 0.0, 0.0])
RESIDUAL_TWISTS_DEG = (-15.0, 15.0, 30.0)  # left in the hose by twisting and releasing (scatter scans)
ALL_ROUND = ScanDefects(noise=0.05, outlier_fraction=0.005)
ONE_SIDED = ScanDefects(noise=0.1, outlier_fraction=0.02, view=(0.2, 0.3, -1.0), gaps=((150.0, 170.0),))


def brake_hose(bending: float, factor: float, segments: int, mass: float = MASS, twist: float = 0.0,
               stiffeners=None) -> Problem:
    """The thesis brake hose between the appendix A mounts.

    bending: EI, N*mm^2.  factor: GJ over the isotropic EI / 1.5.  segments: of the model.
    mass: kg/m (under gravity -z when positive).  twist: end fitting, degrees.
    stiffeners: the thesis' springs (model/stiffeners.py) or None.
    """
    hose = Hose(length=330.6, outer_diameter=10.1, bending_stiffness=bending, segments=segments,
                torsional_stiffness=factor * isotropic_torsional_stiffness(bending), mass_per_length=mass,
                stiffeners=stiffeners)
    gravity = np.array(GRAVITY if mass > 0.0 else (0.0, 0.0, 0.0))
    return Problem(hose, START, END, twist, gravity, name="thesis brake hose")


@dataclass
class DemoOutcome:
    """What the demo computed: comparisons after calibration, the calibration, the scatter and the twist paths."""

    comparisons: list[Comparison]
    calibration: Calibration
    envelope: ScatterEnvelope
    twist_paths: list[TwistPath]


def run_validation_demo(out_dir: str | Path, *, truth_segments: int = 160, model_segments: int = 40,
                        twist_step_deg: float = 5.0) -> DemoOutcome:
    """Make the scans, compare, calibrate, follow the twist; write scans/, problem files and the report."""
    scans = {}
    for label, twist, defects in [("twist_000", 0.0, ALL_ROUND), ("twist_180", 180.0, ONE_SIDED)] + [
            (f"repeat_{k + 1}", residual, ALL_ROUND) for k, residual in enumerate(RESIDUAL_TWISTS_DEG)]:
        truth = solve(brake_hose(EI, TRUE_FACTOR, truth_segments, twist=twist))
        scans[label] = synthetic_scan(truth.s, truth.centerline, truth.problem.hose.outer_radius, defects,
                                      seed=len(scans))
    nominal = brake_hose(0.8 * EI, 1.0, model_segments)
    fits = {label: fit_centerline(points, nominal.hose.outer_radius, start_hint=START.point)
            for label, points in scans.items()}
    cases = [ScanCase(0.0, fits["twist_000"].points), ScanCase(180.0, fits["twist_180"].points)]
    calibration = calibrate(nominal, cases)
    calibrated = replace(nominal, hose=calibration.hose)
    comparisons = [
        compare_scan(solve(replace(calibrated, end_twist_deg=twist)), scans[label], label, fit=fits[label])
        for label, twist in (("twist_000", 0.0), ("twist_180", 180.0))
    ]
    envelope = scatter_envelope([fits[label].points for label in ("twist_000", "repeat_1", "repeat_2", "repeat_3")])
    twist_paths = stiffener_study(model_segments, twist_step_deg)
    with staged_directory(out_dir) as staging:
        for label, points in scans.items():
            (staging / "scans").mkdir(exist_ok=True)
            write_ply(staging / "scans" / f"{label}.ply", points)
        write_text(staging / "problem_nominal.toml", problem_to_toml(nominal))
        write_text(staging / "problem_calibrated.toml", problem_to_toml(calibrated))
        write_validation_report(staging / "report", comparisons, envelope=envelope, calibration=calibration,
                                twist_paths=twist_paths)
    return DemoOutcome(comparisons, calibration, envelope, twist_paths)


def stiffener_study(segments: int, step_deg: float) -> list[TwistPath]:
    """The weightless thesis hose twisted 0 -> 180 deg: isotropic, 25x torsion, and 25x with 16 and 8 springs.

    The stiffener models use the thesis preset's element count (40 for 330.6 mm).
    """
    preset = thesis_preset(330.6)
    twists = np.arange(0.0, 180.0 + 0.5 * step_deg, step_deg)
    variants = [
        ("isotropic", brake_hose(EI, 1.0, segments, mass=0.0)),
        ("25x torsion", brake_hose(EI, TRUE_FACTOR, segments, mass=0.0)),
        ("25x + 16 springs", brake_hose(EI, TRUE_FACTOR, preset.segments, mass=0.0, stiffeners=preset.stiffeners)),
        ("25x + 8 springs", brake_hose(EI, TRUE_FACTOR, preset.segments, mass=0.0,
                                       stiffeners=replace(preset.stiffeners, springs=8))),
    ]
    return [follow_twist(problem, twists, label) for label, problem in variants]
