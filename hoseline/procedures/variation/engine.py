"""Run a study's samples in batches on Dask distributed, streaming each batch back as it finishes.

The samples are cut into batches of consecutive indices (batch k holds [k B, (k + 1) B)); a
batch is one task.  The context (hose, tolerances, nominal shape) is sent to every worker once
(scatter, broadcast); every worker warms the solver once when it joins (WarmSolver: a tiny
placement and a tiny clearance query, so the compiled kernels are loaded before the first
batch, whatever the compile cache does).  Finished batches are handed to `on_batch` in the
order they finish; batches already done (a resumed study) are not run again.

Where: a LocalCluster of `workers` processes on this machine (default: one per core; loopback
only, its dashboard on a free port), an existing cluster (a scheduler address tcp://HOST:PORT or
a scheduler file), or, with workers = 0, in this process without Dask (small runs and tests).
An existing cluster's address is checked first (scheduler.scheduler_address: the file read, the
port opened within a second), so a wrong address is refused at once, before any solving, rather
than after Dask's CONNECT_SECONDS.
Since every sample depends only on its index and deviations, the numbers are the same whichever
is used.
"""

from __future__ import annotations

import logging
import math
import os
from collections.abc import Callable, Collection
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
from distributed import Client, LocalCluster, WorkerPlugin, as_completed

from hoseline.procedures.variation.samples import StudyContext, evaluate_batch
from hoseline.procedures.variation.scheduler import ClusterError, scheduler_address

CONNECT_SECONDS = 30  # waiting for an existing scheduler (once its port was seen open)
MAX_BATCH = 200  # samples per task at most (about a second of work for a placement)
BATCHES_PER_RUN = 64  # the default batch size aims at this many tasks


def default_batch_size(count: int) -> int:
    """Samples per batch for a study of `count` samples (independent of the workers, so a resumed study matches)."""
    return max(1, min(MAX_BATCH, math.ceil(count / BATCHES_PER_RUN)))


def batch_slices(count: int, size: int) -> list[slice]:
    """The batches of a study of `count` samples, `size` each (the last may be shorter)."""
    return [slice(start, min(start + size, count)) for start in range(0, count, size)]


@dataclass(frozen=True)
class Where:
    """Where the batches run: scheduler (tcp://HOST:PORT or a scheduler file path, or None for a
    LocalCluster here), workers (processes of the LocalCluster; 0: in this process, no Dask)."""

    scheduler: str | None = None
    workers: int | None = None

    def describe(self) -> str:
        """One line for the report."""
        if self.scheduler:
            return f"Dask cluster at {self.scheduler}"
        if self.workers == 0:
            return "in process (no Dask)"
        return f"Dask LocalCluster, {self.local_workers()} worker processes"

    def local_workers(self) -> int:
        """Worker processes of a LocalCluster: as asked, or one per core."""
        return self.workers if self.workers else (os.cpu_count() or 1)


def warm_up() -> None:
    """Load (or compile) the solver and clearance kernels: a tiny placement and a tiny clearance query."""
    from hoseline.model import Hose, Mount, Problem
    from hoseline.procedures.geometry.clearance import TriangleIndex
    from hoseline.procedures.placement.sequence import place_only

    hose = Hose(length=100.0, outer_diameter=5.0, bending_stiffness=1e4, torsional_stiffness=1e4, segments=8)
    problem = Problem(hose, Mount([0.0, 0.0, 0.0], [0.0, 1.0, 0.0]), Mount([60.0, 0.0, 0.0], [0.0, 1.0, 0.0]), 30.0)
    place_only(problem)
    triangle = np.array([[0.0, 0.0, 10.0], [1.0, 0.0, 10.0], [0.0, 1.0, 10.0]])
    TriangleIndex(triangle, np.array([[0, 1, 2]])).nearest(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]), 0.5)


class WarmSolver(WorkerPlugin):
    """Warms the solver once on every worker, when it joins (setup)."""

    name = "hoseline-warm-solver"

    def setup(self, worker) -> None:
        warm_up()


class Engine:
    """Runs batches where `where` says; a context manager (the cluster, if it started one, closes on exit).

        with Engine(Where(workers=2)) as engine:
            ...                                   # the cluster starts and warms meanwhile
            engine.run(context, coordinates, batch_size, on_batch, done=set())

    Entering starts the cluster (and warms its workers) in a background thread and returns at once, so
    the caller's own work before the first batch (the nominal hose, the sensitivities) overlaps the
    workers' start-up; `client` waits for it and raises ClusterError if it failed.  Leaving closes the
    cluster in that thread too, so the caller's work after the last batch (the statistics, the files)
    overlaps the workers' shut-down; the interpreter waits for it before it exits.
    """

    def __init__(self, where: Where = Where()) -> None:
        self.where = where
        self.cluster: LocalCluster | None = None
        self._client: Client | None = None
        self._starter: ThreadPoolExecutor | None = None
        self._started: Future | None = None

    def __enter__(self) -> "Engine":
        if self.where.scheduler is not None or self.where.workers != 0:
            self._starter = ThreadPoolExecutor(max_workers=1, thread_name_prefix="hoseline-cluster-start")
            self._started = self._starter.submit(self._start)
        return self

    def _start(self) -> None:
        """Start or reach the cluster and warm its workers (raises ClusterError)."""
        scheduler = self.where.scheduler
        try:
            if scheduler is None:
                self.cluster = LocalCluster(n_workers=self.where.local_workers(), threads_per_worker=1, processes=True,
                                            host="127.0.0.1", dashboard_address=":0", silence_logs=logging.ERROR)
                self._client = Client(self.cluster)
            else:
                self._client = Client(scheduler_address(scheduler), timeout=CONNECT_SECONDS)
        except (OSError, TimeoutError, ValueError) as exc:
            raise ClusterError(f"cannot start or reach the Dask cluster ({self.where.describe()}): {exc}") from None
        self._client.register_plugin(WarmSolver())

    def ready(self) -> None:
        """Wait until the cluster is up and its workers warm (at once without Dask); raises ClusterError if it failed."""
        if self._started is not None:
            self._started.result()

    @property
    def client(self) -> Client | None:
        """The Dask client once the cluster is ready (None without Dask)."""
        self.ready()
        return self._client

    def __exit__(self, *exc) -> None:
        if self._started is None:
            return
        self._starter.submit(self._close)  # after the start, in its thread; the caller writes its results meanwhile
        self._starter.shutdown(wait=False)  # the interpreter still waits for it before it exits

    def _close(self) -> None:
        """Close the client and the cluster this engine started."""
        if self._client is not None:
            self._client.close()
        if self.cluster is not None:
            self.cluster.close()

    def run(
        self,
        context: StudyContext,
        coordinates: np.ndarray,
        batch_size: int,
        on_batch: Callable[[int, dict[str, np.ndarray]], None],
        done: Collection[int] = (),
        first: int = 0,
    ) -> None:
        """Evaluate every batch of the samples with deviations `coordinates` (count, width) not in `done`, handing
        each to on_batch(k, arrays) (samples.evaluate_batch) as it finishes.

        batch_size: samples per batch (default_batch_size).  first: the index of the first sample (a later round
        of sampling to a precision continues the study's numbering).  Raises whatever a batch raises beyond the
        samples' own failures (which are recorded in the arrays), e.g. a worker that died.
        """
        slices = batch_slices(len(coordinates), batch_size)
        indices = first + np.arange(len(coordinates))
        todo = [k for k in range(len(slices)) if k not in done]
        if not todo:
            return
        client = self.client
        if client is None:
            for k in todo:
                on_batch(k, evaluate_batch(context, indices[slices[k]], coordinates[slices[k]]))
            return
        # hash=False: a key of its own, so that releasing an earlier stage's copy of an equal context cannot drop it
        shared = client.scatter(context, broadcast=True, hash=False)
        futures = {}
        for k in todo:
            rows = slices[k]
            futures[client.submit(evaluate_batch, shared, indices[rows], coordinates[rows], pure=False)] = k
        for future, arrays in as_completed(futures, with_results=True):
            on_batch(futures[future], arrays)

    def map(self, function: Callable, context, items: list, on_result: Callable[[int, object], None],
            done: Collection[int] = ()) -> None:
        """function(context, items[k]) for every k not in `done`, here or on the cluster (the context sent to every
        worker once), handing each result to on_result(k, result) as it finishes."""
        todo = [k for k in range(len(items)) if k not in done]
        if not todo:
            return
        client = self.client
        if client is None:
            for k in todo:
                on_result(k, function(context, items[k]))
            return
        shared = client.scatter(context, broadcast=True, hash=False)
        futures = {client.submit(function, shared, items[k], pure=False): k for k in todo}
        for future, result in as_completed(futures, with_results=True):
            on_result(futures[future], result)
