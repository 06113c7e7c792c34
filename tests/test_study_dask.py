"""The study on Dask: the same numbers in process, on a LocalCluster and on a separate scheduler with two
workers; an interrupted study resumes from the batches it wrote; failed samples are kept with their reason."""

from __future__ import annotations

import os
import subprocess
from dataclasses import replace
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from hoseline.cli import app
from hoseline.demos.thesis_hose import demo_problem
from hoseline.io.problem_file import problem_to_toml
from hoseline.io.study_results import PartialStore
from hoseline.procedures.variation import engine
from hoseline.procedures.variation.design_search import DesignGrid
from hoseline.procedures.variation.engine import Where
from hoseline.procedures.variation.quantities import Limit, quantities
from hoseline.procedures.variation.run import run_study
from hoseline.procedures.variation.scheduler import ClusterError
from hoseline.procedures.variation.samples import StudyBase
from hoseline.procedures.variation.study import Sampling, Study
from hoseline.procedures.variation.tolerances import Tolerance, Variation

DASK = Path(sys.executable).with_name("dask")
STUDY = """
name = "dask check"
base = "problem.toml"
[sampling]
method = "latin-hypercube"
samples = 20
seed = 5
batch = 3
[[vary]]
parameter = "end.point"
distribution = "sphere"
radius = 1.0
[[vary]]
parameter = "hose.bending_stiffness"
distribution = "lognormal"
factor = 2.0
[[vary]]
parameter = "end.twist"
distribution = "normal"
sigma = 5.0
[limits]
bend_radius = 35.0
"""


def _study(count: int = 20) -> Study:
    variation = Variation((Tolerance("end.point", "sphere", (1.0,)), Tolerance("hose.bending_stiffness", "lognormal", (2.0,)),
                           Tolerance("end.twist", "normal", (5.0,))))
    return Study("dask check", StudyBase(demo_problem(180.0, 30)), variation, Sampling("latin-hypercube", count, 5, 3), (),
                 sensitivities=False)


def _same(a: dict, b: dict) -> None:
    """Bit for bit, every array (NaN where the same samples failed)."""
    assert a.keys() == b.keys()
    for key in a:
        if a[key].dtype.kind == "f":
            assert np.array_equal(a[key], b[key], equal_nan=True), key
        else:
            assert np.array_equal(a[key], b[key]), key


def test_local_cluster_gives_the_numbers_of_one_process():
    """Two worker processes of a LocalCluster, batches finishing in any order: the same numbers, bit for bit,
    the design search's optimiser (one task per length) included."""
    bend = quantities(())[0]
    study = replace(_study(), limits=(Limit(bend, 30.0),),
                    design=DesignGrid((325.0, 335.0), (-40.0, 0.0, 40.0), "bend_radius", method="optimise"))
    alone = run_study(study, where=Where(workers=0))
    spread = run_study(study, where=Where(workers=2))
    _same(alone.samples, spread.samples)
    assert spread.run["where"] == "Dask LocalCluster, 2 worker processes"
    assert [(r.length, r.clocking) for r in alone.design.refined] == [(r.length, r.clocking) for r in spread.design.refined]
    assert all(np.array_equal(a.margins, b.margins) for a, b in zip(alone.design.refined, spread.design.refined))
    assert len(alone.design.refined) == 2


def _problem_dir(tmp_path: Path) -> Path:
    problem = demo_problem(180.0, 30)
    (tmp_path / "problem.toml").write_text(problem_to_toml(problem), encoding="utf-8")
    (tmp_path / "study.toml").write_text(STUDY, encoding="utf-8")
    return tmp_path


def test_separate_scheduler_and_two_workers_give_the_in_process_numbers(tmp_path):
    """`dask scheduler` and two `dask worker` processes on 127.0.0.1 run the study given by --scheduler (a
    scheduler file); samples.npz equals the in-process run's."""
    folder = _problem_dir(tmp_path)
    scheduler_file = tmp_path / "scheduler.json"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "env": env}
    processes = [subprocess.Popen([str(DASK), "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                   "--scheduler-file", str(scheduler_file)], **quiet)]
    try:
        deadline = time.monotonic() + 60.0
        while not scheduler_file.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        assert scheduler_file.exists(), "the scheduler did not start"
        for _ in range(2):
            processes.append(subprocess.Popen([str(DASK), "worker", "--scheduler-file", str(scheduler_file), "--nthreads",
                                               "1", "--nworkers", "1", "--no-dashboard", "--host", "127.0.0.1"], **quiet))
        from distributed import Client

        with Client(scheduler_file=str(scheduler_file), timeout=60) as client:
            client.wait_for_workers(2, timeout=120)
        runner = CliRunner()
        remote = runner.invoke(app, ["study", str(folder / "study.toml"), "-o", str(tmp_path / "remote"), "-q",
                                     "--scheduler", str(scheduler_file)])
        assert remote.exit_code == 0, remote.output
        local = runner.invoke(app, ["study", str(folder / "study.toml"), "-o", str(tmp_path / "local"), "-q",
                                    "--workers", "0"])
        assert local.exit_code == 0, local.output
        with np.load(tmp_path / "remote" / "samples.npz") as a, np.load(tmp_path / "local" / "samples.npz") as b:
            _same(dict(a), dict(b))
        assert "Dask cluster at" in (tmp_path / "remote" / "report.html").read_text(encoding="utf-8")
    finally:
        for process in reversed(processes):
            process.terminate()
        for process in processes:
            try:
                process.wait(timeout=20)
            except subprocess.TimeoutExpired:
                process.kill()


@pytest.mark.parametrize("scheduler, message", [
    ("tcp://127.0.0.1:9", "cannot reach the Dask scheduler at tcp://127.0.0.1:9: Connection refused (port 9 of "
                          "127.0.0.1 checked with a 1 s timeout, before any solving)"),
    ("nowhere/scheduler.json", "the scheduler file"),
    ("tcp://127.0.0.1:port", "cannot read the address"),
])
def test_an_unreachable_scheduler_is_refused_before_any_solving(tmp_path, monkeypatch, scheduler, message):
    """Nothing listens on port 9, the scheduler file does not exist, the port is no number: exit code 2 with a
    message saying so, before the nominal hose is placed (which would fail the test), nothing written."""
    import hoseline.procedures.variation.run as run

    def no_solving(*args, **kwargs):
        raise AssertionError("the nominal hose was placed before the scheduler was checked")

    monkeypatch.setattr(run, "nominal_context", no_solving)
    folder = _problem_dir(tmp_path)
    result = CliRunner().invoke(app, ["study", str(folder / "study.toml"), "-o", str(tmp_path / "out"), "-q",
                                      "--scheduler", scheduler])
    assert result.exit_code == 2, result.output
    assert message in result.output.replace("\n", " ")
    if scheduler.endswith(".json"):
        assert f"{os.path.abspath(scheduler)} does not exist" in result.output.replace("\n", "")
    assert not (tmp_path / "out" / "report.html").exists()


def test_run_study_checks_the_scheduler_before_any_solving(monkeypatch):
    """The procedure itself (not only the command) refuses an unreachable scheduler before placing the nominal
    hose."""
    import hoseline.procedures.variation.run as run

    def no_solving(*args, **kwargs):
        raise AssertionError("the nominal hose was placed before the scheduler was checked")

    monkeypatch.setattr(run, "nominal_context", no_solving)
    study = Study("unreachable", StudyBase(demo_problem(180.0, 10)), Variation((Tolerance("end.twist", "normal", (1.0,)),)),
                  Sampling(count=4), ())
    with pytest.raises(ClusterError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:9"):
        run_study(study, where=Where("tcp://127.0.0.1:9"))


class _Interrupted(Exception):
    pass


def test_an_interrupted_study_resumes_from_its_batches(tmp_path, monkeypatch):
    """A study stopped after three batches leaves them in OUT/.partial and no final files; run again it solves
    only the other batches and ends with the numbers of an uninterrupted run; .partial is then removed."""
    folder = _problem_dir(tmp_path)
    out = tmp_path / "out"
    solved = []
    original = engine.evaluate_batch

    def counting(context, indices, coordinates):
        solved.extend(int(i) for i in indices)
        if len(solved) > 9:
            raise _Interrupted()
        return original(context, indices, coordinates)

    monkeypatch.setattr(engine, "evaluate_batch", counting)
    with pytest.raises(_Interrupted):
        CliRunner().invoke(app, ["study", str(folder / "study.toml"), "-o", str(out), "-q", "--workers", "0"],
                           catch_exceptions=False)
    assert sorted(p.name for p in (out / ".partial" / "samples").glob("batch_*.npz")) == [
        "batch_00000.npz", "batch_00001.npz", "batch_00002.npz"]
    assert not (out / "report.html").exists()

    solved.clear()
    monkeypatch.setattr(engine, "evaluate_batch", lambda *args: (solved.extend(int(i) for i in args[1]), original(*args))[1])
    result = CliRunner().invoke(app, ["study", str(folder / "study.toml"), "-o", str(out), "-q", "--workers", "0"])
    assert result.exit_code == 0, result.output
    assert sorted(solved) == list(range(9, 20))
    assert not (out / ".partial").exists()
    fresh = CliRunner().invoke(app, ["study", str(folder / "study.toml"), "-o", str(tmp_path / "fresh"), "-q",
                                     "--workers", "0"])
    assert fresh.exit_code == 0
    with np.load(out / "samples.npz") as a, np.load(tmp_path / "fresh" / "samples.npz") as b:
        _same(dict(a), dict(b))


def test_batches_of_another_study_are_not_reused(tmp_path):
    """A changed study (another fingerprint) starts afresh instead of mixing in old batches."""
    store = PartialStore(tmp_path, "samples", "first")
    store.save(0, {"index": np.arange(3)})
    assert set(PartialStore(tmp_path, "samples", "first").finished()) == {0}
    assert PartialStore(tmp_path, "samples", "second").finished() == {}


def test_failed_samples_are_kept_with_their_reason():
    """A length tolerance that makes some hoses too short to reach their mounts: those samples are failed with
    the reason, left out of the spreads, and counted in the probability's upper end."""
    problem = demo_problem(0.0, 20)
    distance = float(np.linalg.norm(problem.end.point - problem.start.point))
    low = 2.0 * (distance - problem.hose.length)  # about half of the hoses shorter than the mount distance
    variation = Variation((Tolerance("hose.length", "uniform", (low, 0.0)),))
    from hoseline.procedures.variation.quantities import Limit, quantities

    limit = Limit(quantities(())[0], 1e9)  # bend radius at least 1e9 mm: every solved sample breaks it
    study = Study("short", StudyBase(problem), variation, Sampling("monte-carlo", 40, 2), (limit,), sensitivities=False)
    outcome = run_study(study, where=Where(workers=0))
    failed = outcome.samples["failed"]
    lengths = problem.hose.length + outcome.coordinates[:, 10]
    assert np.array_equal(failed, lengths <= distance)
    assert 0 < failed.sum() < len(failed)
    assert all("cannot reach" in reason for reason in outcome.samples["reason"][failed])
    probability = outcome.probabilities[0]
    assert probability.failed == failed.sum() and probability.solved == len(failed) - failed.sum()
    assert probability.estimate == 1.0 and probability.high_with_failed == 1.0
    assert outcome.spreads[0].solved == probability.solved
    # one cause, however many samples, with their indexes (the lengths differ, the cause does not)
    (cause,) = outcome.failures
    assert cause.count == failed.sum() and cause.samples == tuple(np.flatnonzero(failed))
    assert cause.cause == ("ValueError: hose.length = # mm is not longer than the mount distance # mm: an inextensible "
                           "hose cannot reach; use a hose longer than # mm")
    assert cause.example == outcome.samples["reason"][cause.samples[0]]


def test_failures_are_grouped_by_cause_and_a_fault_of_the_program_stops_the_study(monkeypatch):
    """Samples failing with the solver's own errors are grouped by cause (the numbers left out, names such as
    clips[1] kept); any other exception (here a TypeError, as a programming error would raise) is not recorded as
    a failed sample but raised."""
    from hoseline.procedures.placement.continuation import PlacementError
    from hoseline.procedures.variation import samples
    from hoseline.procedures.variation.study import failure_causes

    reasons = np.array(["", "PlacementError: phase 'twist' failed at fraction 0.7458: residual 2.29e-06",
                        "ValueError: clips[1].direction: a ball clip holds no direction to vary",
                        "PlacementError: phase 'twist' failed at fraction 0.12: residual 3e-7", "",
                        "ValueError: clips[0].direction: a ball clip holds no direction to vary"])
    causes = failure_causes(reasons, reasons != "")
    assert [(c.cause, c.count, c.samples) for c in causes] == [
        ("PlacementError: phase 'twist' failed at fraction #: residual #", 2, (1, 3)),
        ("ValueError: clips[1].direction: a ball clip holds no direction to vary", 1, (2,)),
        ("ValueError: clips[0].direction: a ball clip holds no direction to vary", 1, (5,))]

    context = samples.StudyContext(StudyBase(demo_problem(0.0, 10)), np.zeros((1, 11, 3)))
    for error, recorded in ((PlacementError("no path"), True), (ValueError("too short"), True),
                            (TypeError("a bug"), False), (IndexError("a bug"), False)):
        def read(self, problem, error=error):
            raise error

        monkeypatch.setattr(samples.StudyBase, "read", read)
        if recorded:
            out = samples.evaluate_batch(context, np.arange(2), np.zeros((2, 15)))
            assert out["failed"].all() and out["reason"][0] == f"{type(error).__name__}: {error}"
        else:
            with pytest.raises(type(error), match="a bug"):
                samples.evaluate_batch(context, np.arange(2), np.zeros((2, 15)))
