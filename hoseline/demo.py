"""The thesis brake hose (Thomas 2004, appendix A and C) placed at 0 and 180 degrees of twist.

Writes, under the output directory:
    twist_000/ and twist_180/: problem.toml (a problem file to copy), centerline.csv, result.json
    shapes.png: both shapes, curvature and twisting moment
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from hoseline.io.atomic import staged_directory, write_text
from hoseline.io.problem_file import problem_to_toml
from hoseline.io.results import write_results
from hoseline.model import Hose, Mount, Problem
from hoseline.procedures.placement import solve
from hoseline.procedures.result import Result
from hoseline.report.plots import plot_shapes

# Mount points in mm, from ../shared/data/mounts_thesis_appendix_a.igs (entities 116 labelled A-D).
# Hard-coded here; reading IGES comes in a later issue.  The hose leaves B along A->B and D along D->C.
A = (-13.0, -16.0, -11.25)
B = (-13.0, 0.0, -11.25)
C = (-160.0, -7.0, -11.25)
D = (-173.064, -7.0, -11.25)

# Goodyear5052 (thesis appendix C): E = 292.7985 N/mm^2 with I = 510.8053 mm^4,
# G = 96.12 N/mm^2 with the calibrated torsion constant 25540.26 mm^4 (25x the isotropic 2I).
GOODYEAR_5052 = Hose(
    length=330.6,  # mm, the thesis' dialogue example
    outer_diameter=10.1,  # mm
    bending_stiffness=292.7985 * 510.8053,  # N*mm^2
    torsional_stiffness=96.12 * 25540.26,  # N*mm^2
    mass_per_length=0.0,  # weightless, as in the thesis
    segments=100,
)

TWISTS_DEG = (0.0, 180.0)


def demo_problem(twist_deg: float, segments: int = GOODYEAR_5052.segments) -> Problem:
    """The brake hose from B to D with the end fitting twisted by `twist_deg` degrees."""
    return Problem(
        hose=replace(GOODYEAR_5052, segments=segments),
        start=Mount.from_points(A, B),  # tip B, direction A->B
        end=Mount(point=D, direction=np.subtract(C, D)),  # tip D, direction D->C (into the hose)
        end_twist_deg=twist_deg,
        name=f"thesis brake hose, twist {twist_deg:g} deg",
    )


def run_demo(
    out_dir: str | Path,
    *,
    progress: Callable[[str, float], None] | None = None,
    segments: int = GOODYEAR_5052.segments,
) -> tuple[list[str], list[Result]]:
    """Solve the demo at each twist and write all its files (only if every solve succeeded).

    out_dir: output directory.  progress: as for solve(), with the phase prefixed by
    the twist ("twist 180: place").  segments: rigid segments (fewer for quick tests).
    Returns the labels and the results, in the order of TWISTS_DEG.
    """
    labels = [f"twist {twist:g}" for twist in TWISTS_DEG]
    results = [
        solve(demo_problem(twist, segments), progress=_prefixed(progress, label))
        for twist, label in zip(TWISTS_DEG, labels)
    ]

    with staged_directory(out_dir) as staging:
        for twist, result in zip(TWISTS_DEG, results):
            folder = staging / f"twist_{twist:03.0f}"
            write_results(result, folder)
            write_text(folder / "problem.toml", problem_to_toml(result.problem))
        plot_shapes(results, labels, staging / "shapes.png")
    return labels, results


def _prefixed(progress: Callable[[str, float], None] | None, label: str) -> Callable[[str, float], None] | None:
    """progress with `label` put in front of the phase name (None stays None)."""
    if progress is None:
        return None
    return lambda phase, fraction: progress(f"{label}: {phase}", fraction)
