"""The thesis brake hose (Thomas 2004, appendix A and C) placed at 0 and 180 degrees of twist.

The mounts are read from the thesis' IGES file (appendix A, named points A, B, C, D), the
round trip of the thesis in one command: mount points out of CAD, the hose solved, its
shape back to CAD.  Writes, under the output directory:
    twist_000/ and twist_180/: problem.toml (a problem file to copy), centerline.csv, result.json,
        and the exports asked for (all by default: hose.igs, hose.step, hose.stl, hose.ply,
        hose.glb, hose.cmd; see hoseline.io.exports)
    shapes.png: both shapes, curvature and twisting moment
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

from hoseline.io.adams_cmd import BeamSection
from hoseline.io.atomic import staged_directory, write_text
from hoseline.io.exports import FILE_NAMES, ExportedFile, write_exports
from hoseline.io.iges_mounts import mounts_from_iges
from hoseline.io.problem_file import problem_to_toml
from hoseline.io.results import write_results
from hoseline.model import Hose, Problem
from hoseline.procedures.placement.sequence import solve
from hoseline.procedures.placement.result import Result
from hoseline.report.plots import plot_shapes

# The thesis' appendix A: points A, B, C, D (entity 116); the hose leaves B along A->B and D along D->C.
THESIS_MOUNTS_IGES = Path(__file__).parents[1] / "data" / "mounts_thesis_appendix_a.igs"

# Goodyear5052 (thesis appendix C): E = 292.7985 N/mm^2 with I = 510.8053 mm^4,
# G = 96.12 N/mm^2 with the calibrated torsion constant 25540.26 mm^4 (25x the isotropic 2I).
YOUNGS_MODULUS_5052 = 292.7985  # N/mm^2
SHEAR_MODULUS_5052 = 96.12  # N/mm^2
GOODYEAR_5052 = Hose(
    length=330.6,  # mm, the thesis' dialogue example
    outer_diameter=10.1,  # mm
    bending_stiffness=YOUNGS_MODULUS_5052 * 510.8053,  # N*mm^2
    torsional_stiffness=SHEAR_MODULUS_5052 * 25540.26,  # N*mm^2
    mass_per_length=0.0,  # weightless, as in the thesis
    segments=100,
)

TWISTS_DEG = (0.0, 180.0)


def demo_problem(twist_deg: float, segments: int = GOODYEAR_5052.segments) -> Problem:
    """The brake hose from B to D with the end fitting twisted by `twist_deg` degrees; mounts from the IGES file."""
    start, end = mounts_from_iges(THESIS_MOUNTS_IGES)  # tip B with A behind it, tip D with C ahead of it
    return Problem(
        hose=replace(GOODYEAR_5052, segments=segments),
        start=start,
        end=end,
        end_twist_deg=twist_deg,
        name=f"thesis brake hose, twist {twist_deg:g} deg",
    )


def run_demo(
    out_dir: str | Path,
    *,
    progress: Callable[[str, float], None] | None = None,
    segments: int = GOODYEAR_5052.segments,
    formats: list[str] | None = None,
) -> tuple[list[str], list[Result], list[list[ExportedFile]]]:
    """Solve the demo at each twist and write all its files (only if every solve and export succeeded).

    out_dir: output directory.  progress: as for solve(), with the phase prefixed by
    the twist ("twist 180: place").  segments: rigid segments (fewer for quick tests).
    formats: export formats for each twist (hoseline.io.exports; default all, [] for none);
    the ADAMS model gets the thesis' E and G.
    Returns the labels, the results and the exported files of each twist, in the order of TWISTS_DEG.
    """
    formats = list(FILE_NAMES) if formats is None else formats
    section = BeamSection.from_hose(GOODYEAR_5052, YOUNGS_MODULUS_5052, SHEAR_MODULUS_5052)
    labels = [f"twist {twist:g}" for twist in TWISTS_DEG]
    results = [
        solve(demo_problem(twist, segments), progress=_prefixed(progress, label))
        for twist, label in zip(TWISTS_DEG, labels)
    ]

    exported = []
    with staged_directory(out_dir) as staging:
        for twist, result in zip(TWISTS_DEG, results):
            folder = staging / twist_folder(twist)
            write_results(result, folder)
            write_text(folder / "problem.toml", problem_to_toml(result.problem))
            exported.append(write_exports(result, folder, formats, section))
        plot_shapes(results, labels, staging / "shapes.png")
    return labels, results, exported


def twist_folder(twist_deg: float) -> str:
    """Name of the output folder of one twist: twist_000, twist_180."""
    return f"twist_{twist_deg:03.0f}"


def _prefixed(progress: Callable[[str, float], None] | None, label: str) -> Callable[[str, float], None] | None:
    """progress with `label` put in front of the phase name (None stays None)."""
    if progress is None:
        return None
    return lambda phase, fraction: progress(f"{label}: {phase}", fraction)
