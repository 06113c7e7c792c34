"""What the benchmarks share: the median wall time of a call."""

from __future__ import annotations

import statistics
import time


def median_time(call, repeats: int) -> float:
    """Median wall time of call() in seconds over `repeats` runs (after one warm-up run)."""
    call()
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        call()
        times.append(time.perf_counter() - started)
    return statistics.median(times)
