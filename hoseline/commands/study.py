"""`hoseline study study.toml -o OUT`: a variation or design study of a hose, on Dask; the report and the tables.

Exit codes: 0 done, 2 bad input (study file, its base file, paths, an unreachable scheduler), 3 the
nominal hose cannot be solved.  Finished batches are kept in OUT/.partial while the study runs, so
running the same command again after an interruption resumes it; the final files appear together.
"""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console
from rich.table import Table

from hoseline.commands.common import BAD_INPUT, OUT_HELP, QUIET_HELP, errors_to_exit_codes, fail, progress_bar, read_input


def study_command(
    study_file: Path = typer.Argument(..., help="TOML study file: a base problem or sweep file, \\[\\[vary]] "
                                                "tolerances, \\[sampling], \\[limits], \\[design], \\[reliability] "
                                                "(FORM/SORM), \\[sobol], worst_case (see docs/variation.md)"),
    out: Path = typer.Option(..., "-o", "--out", help=OUT_HELP),
    scheduler: str = typer.Option(None, "--scheduler", help="an existing Dask cluster: tcp://HOST:PORT or a scheduler "
                                                            "file (default: a LocalCluster on this machine)"),
    workers: int = typer.Option(None, "--workers", min=0, help="worker processes of the LocalCluster (default: one "
                                                               "per core; 0: in this process, without Dask)"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help=QUIET_HELP),
) -> None:
    """Sample the tolerances of a hose (and search lengths and clockings; rare failures by FORM, Sobol' indices,
    worst-case corners); write report.html, envelope.stl and tables."""
    from hoseline.procedures.variation.scheduler import ClusterError, scheduler_address

    if scheduler is not None and workers is not None:
        raise fail("--workers sets up a LocalCluster; with --scheduler the cluster's own workers run the study: "
                   "give one of them", BAD_INPUT)
    if scheduler is not None:  # at once, before the solver is even loaded
        try:
            scheduler = scheduler_address(scheduler)
        except ClusterError as exc:
            raise fail(str(exc), BAD_INPUT) from None
    from hoseline.io.study_file import StudyFileError, load_study

    study, base_text, base_path = read_input(load_study, study_file, "study file", (StudyFileError,))
    from hoseline.io.study_results import PartialStore, fingerprint  # after the input is read: a refusal needs none
    from hoseline.procedures.variation.engine import Where
    from hoseline.procedures.variation.run import run_study
    from hoseline.report.study_report import write_study_report

    text = study_file.read_text(encoding="utf-8")
    key = fingerprint(text, base_text, study)
    with errors_to_exit_codes(out):
        try:
            with progress_bar(quiet) as progress:
                outcome = run_study(study, lambda stage: PartialStore(out, stage, key),
                                    where=Where(scheduler, workers), progress=progress)
        except ClusterError as exc:
            raise fail(str(exc), BAD_INPUT) from None
        write_study_report(outcome, out, text, base_path)
    if not quiet:
        if outcome.probabilities:
            Console().print(_limits_table(outcome))
        if outcome.rare_events:
            Console().print(_rare_table(outcome))
        if outcome.worst_cases:
            Console().print(_worst_case_table(outcome))
        if outcome.precision is not None and outcome.precision.reached:  # when not, a note says so
            Console().print(f"sampled to a precision: {outcome.precision.describe()}", soft_wrap=True)
        for note in outcome.notes:
            Console().print(f"[yellow]note:[/] {note}", soft_wrap=True)
        if outcome.design is not None:
            best = outcome.design.table()[:1]
            Console().print(f"design: {len(outcome.design.ranking)} candidates meet every limit"
                            + (f"; best length {best[0]['length_mm']:g} mm, clocking {best[0]['clocking_deg']:g} deg"
                               if best else ""))
        Console().print(f"wrote {out / 'report.html'} and the data beside it")


def _limits_table(outcome) -> Table:
    """The probability of breaking each limit as a Rich table."""
    table = Table(title=f"{outcome.study.name}: {outcome.count} samples")
    for column in ("limit", "P(broken)", "95 % interval", "broken / solved", "failed"):
        table.add_column(column)
    for p in outcome.probabilities:
        style = "green" if p.broken == 0 else "bold red"
        table.add_row(p.limit.describe(), f"[{style}]{p.estimate:.4g}[/]", f"[{p.low:.3g}, {p.high:.3g}]",
                      f"{p.broken} / {p.solved}", str(p.failed))
    return table


def _rare_table(outcome) -> Table:
    """FORM, SORM and importance sampling of each limit as a Rich table."""
    table = Table(title="rare failures (FORM; design points in design_point/)")
    for column in ("limit", "beta", "FORM P", "SORM P", "importance sampling P", "95 % interval", "solves"):
        table.add_column(column)
    for event in outcome.rare_events:
        check = event.importance
        table.add_row(event.limit.describe(), f"{event.point.beta:.4g}", f"{event.form:.3g}",
                      "" if event.sorm is None else f"{event.sorm:.3g}",
                      "" if check is None else f"{check.estimate:.3g}",
                      "" if check is None else f"[{check.low:.3g}, {check.high:.3g}]", str(event.evaluations))
    union = outcome.rare_union
    if union is not None:
        check = union.importance
        table.add_row(f"any of these {len(union.limits)}", "", f"{union.form:.3g}", "",
                      "" if check is None else f"{check.estimate:.3g}",
                      "" if check is None else f"[{check.low:.3g}, {check.high:.3g}]", "")
    return table


def _worst_case_table(outcome) -> Table:
    """Each quantity's worst-case corner: the linear stack and the hose solved there, as a Rich table."""
    table = Table(title="worst case (corners in worst_case/)")
    for column in ("quantity", "nominal", "worst, first order", "worst, solved"):
        table.add_column(column)
    for case in outcome.worst_cases:
        table.add_row(f"{case.quantity.name} [{case.quantity.unit}]", f"{case.nominal:.4g}", f"{case.first_order:.4g}",
                      f"{case.solved:.4g}" if not case.reason else "not solved")
    return table
