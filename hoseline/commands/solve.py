"""`hoseline solve problem.toml -o out/ [--export iges,step,...] [--hysteresis 720]`: place one hose, write its files."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import typer
from rich.console import Console

from hoseline.commands.common import (BAD_INPUT, OUT_HELP, QUIET_HELP, compile_solver, errors_to_exit_codes, fail,
                                      progress_bar, read_input)
from hoseline.io.export_names import FILE_NAMES, parse_formats

HYSTERESIS_STEP_DEG = 10.0  # largest twist step of --hysteresis, degrees

EXPORT_HELP = (
    "comma-separated CAD and model files to write beside the results: "
    + ", ".join(f"{name} ({file})" for name, file in FILE_NAMES.items())
    + "; all or none"
)


def solve_command(
    problem_file: Path = typer.Argument(..., help="TOML problem file (see README)"),
    out: Path = typer.Option(..., "-o", "--out", help=OUT_HELP),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
    export: str = typer.Option("none", "--export", "-e", help=EXPORT_HELP),
    accuracy: str = typer.Option(None, "--accuracy", help="largest station error wanted, mm (e.g. 0.01mm): the "
                                                          "segment count is raised until the estimate meets it"),
    hysteresis: str = typer.Option(None, "--hysteresis", metavar="MAX_DEG",
                                   help="also twist the placed hose from 0 to MAX_DEG degrees and back (steps of at "
                                        "most 10 deg) and write hysteresis.csv: the band between the two ways per "
                                        "station at each twist (elastic model, or with --friction-threshold)"),
    friction_threshold: float = typer.Option(None, "--friction-threshold", metavar="N_MM",
                                             help="with --hysteresis: the joints' internal-friction threshold, N*mm "
                                                  "(elastic-perfectly plastic joints whose set slides; docs/model.md, "
                                                  "Hysteresis); without it the elastic model"),
) -> None:
    """Place the hose of a problem file; write centerline.csv, result.json, the exports asked for (and
    hysteresis.csv with --hysteresis)."""
    from hoseline.io.atomic import staged_directory
    from hoseline.io.exports import write_exports
    from hoseline.io.problem_file import ProblemFileError, load_problem
    from hoseline.io.results import write_results
    from hoseline.procedures.placement.refinement import solve_to_accuracy
    from hoseline.procedures.placement.sequence import solve
    from hoseline.report.table import summary_table

    formats = export_formats(export)
    wanted = None if accuracy is None else accuracy_mm(accuracy)
    largest_twist = None if hysteresis is None else twist_deg(hysteresis)
    if friction_threshold is not None and (largest_twist is None or not (math.isfinite(friction_threshold)
                                                                         and friction_threshold > 0.0)):
        raise fail(f"--friction-threshold {friction_threshold:g}: give a positive moment in N*mm, together with "
                   "--hysteresis MAX_DEG (it sets the friction of the twist up and back)", BAD_INPUT)
    problem = read_input(load_problem, problem_file, "problem file", (ProblemFileError,))
    if largest_twist is not None and problem.has_contact:
        raise fail("--hysteresis does not take contact yet (the twist continuation does not keep the hose out of the "
                   "obstacles); remove [contact] or the option", BAD_INPUT)
    with errors_to_exit_codes(out):
        compile_solver(quiet, problem)
        with progress_bar(quiet) as progress:
            if wanted is None:
                result = solve(problem, progress=progress, force_accuracy=problem.force_accuracy)
            else:
                result = solve_to_accuracy(problem, wanted, progress=progress)
        band = None if largest_twist is None else twisted_band(problem, largest_twist, friction_threshold)
        with staged_directory(out) as staging:
            write_results(result, staging)
            exported = write_exports(result, staging, formats)
            if band is not None:
                from hoseline.io.hysteresis_csv import write_hysteresis

                write_hysteresis(band, staging)
    if not quiet:
        Console().print(summary_table([result], [problem.name]))
        if problem.fittings is not None:
            print_lengths(problem)
        print_contacts(result)
        if band is not None:
            print_hysteresis(band, largest_twist, friction_threshold)
        Console().print(f"wrote {out / 'centerline.csv'} and {out / 'result.json'}")
        if band is not None:
            from hoseline.io.hysteresis_csv import HYSTERESIS_FILE

            Console().print(f"wrote {out / HYSTERESIS_FILE}", soft_wrap=True)
        print_exports(out, exported)


def accuracy_mm(text: str) -> float:
    """The --accuracy value in mm ("0.01mm" or "0.01"), or exit 2 saying what to give."""
    value = _number(text, "mm")
    if not (math.isfinite(value) and value > 0.0):
        raise fail(f"--accuracy {text!r}: give a positive length in mm, e.g. 0.01mm", BAD_INPUT)
    return value


def twist_deg(text: str) -> float:
    """The --hysteresis value in degrees ("720deg" or "720"), or exit 2 saying what to give."""
    from hoseline.model import limits

    value = _number(text, "deg")
    if not (math.isfinite(value) and value != 0.0 and abs(value) <= limits.ANGLE_DEG):
        raise fail(f"--hysteresis {text!r}: give the largest twist in degrees, not zero and within "
                   f"+-{limits.ANGLE_DEG:g}, e.g. 720", BAD_INPUT)
    return value


def _number(text: str, unit: str) -> float:
    """The number of an option's text, with or without its unit ("0.01mm"), NaN when it is none."""
    try:
        return float(text.strip().lower().removesuffix(unit).strip())
    except ValueError:
        return math.nan


def twisted_band(problem, largest_twist_deg: float, friction_threshold: float | None):
    """The hysteresis band of --hysteresis (procedures/placement/hysteresis.py): the placed hose twisted to
    `largest_twist_deg` (degrees) and back in steps of hysteresis_step; friction_threshold: N*mm or None."""
    from hoseline.procedures.placement.hysteresis import hysteresis_band

    return hysteresis_band(problem, largest_twist_deg, hysteresis_step(largest_twist_deg), friction_threshold)


def hysteresis_step(largest_twist_deg: float) -> float:
    """The twist step, degrees: the largest that divides the largest twist into steps of at most HYSTERESIS_STEP_DEG."""
    return abs(largest_twist_deg) / math.ceil(abs(largest_twist_deg) / HYSTERESIS_STEP_DEG - 1e-9)


def print_hysteresis(band, largest_twist_deg: float, friction_threshold: float | None = None) -> None:
    """The summary line of the hysteresis band (procedures/placement/hysteresis.HysteresisBand): the largest band
    (mm) and the twist (degrees) where it is, or why the twist stopped early; friction_threshold: N*mm, or None
    for the elastic model."""
    console = Console()
    if band.failure:
        console.print(f"[yellow]hysteresis: the twist to {largest_twist_deg:g} deg and back stopped early: "
                      f"{band.failure}[/yellow]", soft_wrap=True)
    if band.width.size == 0:
        console.print("hysteresis: no twist was reached both ways; hysteresis.csv holds the header only")
        return
    widest = int(np.argmax(band.width))
    model = "elastic" if friction_threshold is None else f"joint friction {friction_threshold:g} N*mm"
    console.print(f"hysteresis (twisted to {largest_twist_deg:g} deg and back, {model}): largest band "
                  f"{band.width[widest]:.4g} mm "
                  f"at {band.twists_deg[widest]:g} deg twist", soft_wrap=True)


def export_formats(text: str) -> list[str]:
    """The --export list, or exit 2 naming the unknown format."""
    try:
        return parse_formats(text)
    except ValueError as exc:
        raise fail(f"--export {text}: {exc}", BAD_INPUT) from None


def print_lengths(problem) -> None:
    """The free (cut) length and the catalogue's overall length of a hose with end fittings, mm."""
    fittings = problem.fittings
    parts = " + ".join(f"{fitting.length_allowance:.2f} ({name})" for name, _, fitting in fittings.pieces())
    Console().print(f"free length {problem.hose.length:.2f} mm, overall length "
                    f"{fittings.overall_length(problem.hose.length):.2f} mm (the fittings add {parts} mm)")


def _where(contact) -> str:
    """Where an obstacle's smallest gap is, for the contact line: " (on the start fitting, s = -12.0 mm)"."""
    if not np.isfinite(contact.min_gap_arc_length):
        return ""
    return f" (on the {contact.min_gap_on}, s = {contact.min_gap_arc_length:.1f} mm)"


def print_contacts(result) -> None:
    """One line per obstacle of a placement with contact: the total force (N), the length the hose lies on and its
    distributed force, the point forces (N) at the touch-downs and point contacts (arc length, mm), the smallest gap;
    then the segment refinement for the forces' accuracy, if asked; then one per obstacle brought in after the free
    placement: how far (mm), the side the hose went to, and why."""
    for contact in result.contacts:
        what = "itself" if contact.name == "self" else f"{contact.name!r} ({contact.kind})"
        lying = [f"{arc.length:.1f} mm lying (s = {arc.start:.1f} to {arc.end:.1f} mm, "
                 f"{float(np.linalg.norm(arc.distributed_force)):.4g} N spread)" for arc in contact.carried]
        points = [f"{float(np.linalg.norm(t.force)):.4g} N at s = {t.arc_length:.1f} mm" for t in contact.touchdowns]
        carried = "; ".join(lying + ([f"point force(s) {', '.join(points)}"] if points else [])) or "not touching"
        Console().print(f"contact with {what}: force {float(np.linalg.norm(contact.total_force)):.4g} N, {carried}; "
                        f"smallest gap {contact.min_gap:.3g} mm{_where(contact)}", soft_wrap=True)
    refinement = result.force_refinement
    if refinement is not None:
        estimate = "not estimated" if refinement.estimated is None else f"estimated {100 * refinement.estimated:.2g} %"
        verdict = "" if refinement.met else f": not reached, {refinement.why}"
        Console().print(f"forces and reactions to {100 * refinement.asked:g} % (\\[contact] force_accuracy_percent): "
                        f"segments {' -> '.join(map(str, refinement.segments))}, {estimate}{verdict}", soft_wrap=True)
    for choice in result.obstacle_placement:
        if choice.rule != "clear":
            given_up = f", {choice.ways_failed} shorter way(s) given up" if choice.ways_failed else ""
            Console().print(f"{choice.name!r} brought in {choice.travel:.4g} mm, the hose pushed towards "
                            f"{np.round(choice.hose_side, 3).tolist()} ({choice.rule}{given_up}; the free hose "
                            f"{'entered' if choice.free_gap < 0.0 else 'touched'} it by {abs(choice.free_gap):.4g} mm)",
                            soft_wrap=True)


def print_exports(folder: Path, files) -> None:
    """One line per exported file (hoseline.io.exports.ExportedFile): path, size, time to make and write it."""
    for file in files:
        line = f"wrote {folder / file.name} ({file.size / 1024:.0f} KiB in {file.seconds:.2f} s)"
        Console().print(line, soft_wrap=True)
