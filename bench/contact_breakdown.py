"""Where a placement with contact spends its time: the mesh searches, the rest, and the path's parts.

Used by bench_contact_placement.py --mesh --breakdown.  A measurement harness, not a profiler: it wraps
a few entry points of the solver with wall-clock timers for one solve and restores them after, so
the figures are the solver's own calls (the wrappers add about a microsecond a call):
- mesh searches: contact_mesh.MeshArrays.pairs (the pairs of each evaluation and the step filter's
  edge lists), .station_gaps and .segment_gaps (the step filter's station and chord gaps) and
  contact_newton.swept_edges_clear (its swept check of segment-edge pairs);
- the path's parts: each call of the contact Newton by the continuation (procedures/contact), split
  into converged path steps, path steps that did not converge (the tries bracketing a fold, and
  steps halved on the way), the walks downhill (snaps, and the cushion's widening and settling) and
  the narrowings and polish at the ends of the phases;
- the evaluations of the contact Newton (contact_newton.evaluate_contact), accepted or not.
The time a placement would take were its mesh searches free is its total less their time: a bound
from below of what any faster search could give with the same path.
"""

from __future__ import annotations

import time
from collections import defaultdict
from contextlib import contextmanager

from hoseline.mechanics import contact_mesh, contact_newton
from hoseline.procedures.contact import continuation, cushion

MESH_SEARCHES = [(contact_mesh.MeshArrays, "pairs"), (contact_mesh.MeshArrays, "station_gaps"),
                 (contact_mesh.MeshArrays, "segment_gaps"), (contact_newton, "swept_edges_clear")]


def _timed(record):
    """A replacement maker (for _replaced): the original call, its seconds, result and arguments passed to record."""
    def make(original):
        def call(*args, **kwargs):
            started = time.perf_counter()
            result = original(*args, **kwargs)
            record(time.perf_counter() - started, result, args, kwargs)
            return result
        return call
    return make


def breakdown(solve_once) -> dict:
    """Time solve_once() (a placement with contact) by part; returns the figures: seconds and counts by part, the
    mesh searches' seconds within each part ("<part>: mesh searches"), and the Newton iterations."""
    seconds: dict[str, float] = defaultdict(float)
    counts: dict[str, int] = defaultdict(int)
    searching = [0.0]  # the mesh searches' seconds in the contact Newton call under way
    nested = [0]  # a mesh search inside a mesh search (station_gaps calls segment_gaps) is counted once

    def search(name):
        def record(elapsed, result, args, kwargs):
            if nested[0] == 0:
                seconds["mesh searches"] += elapsed
                searching[0] += elapsed
                counts[f"mesh search {name}"] += 1
        return record

    def path_part(kind):
        def wrapper(original):
            def call(*args, **kwargs):
                before, searching[0] = searching[0], 0.0
                started = time.perf_counter()
                result = original(*args, **kwargs)
                elapsed = time.perf_counter() - started
                report = result[1]
                if kind == "step" and "max_halvings" not in kwargs:  # continuation.polish's call
                    part = "narrowings and polish"
                elif kind == "step":
                    part = "path steps, converged" if report.converged else "path steps, not converged"
                else:
                    part = kind
                seconds[part] += elapsed
                seconds[f"{part}: mesh searches"] += searching[0]
                counts[part] += 1
                counts[f"{part}: Newton iterations"] += report.iterations
                searching[0] = before + searching[0]
                return result
            return call
        return wrapper

    def evaluation(elapsed, result, args, kwargs):
        counts["evaluations"] += 1

    def not_nested(original):
        def call(*args, **kwargs):
            nested[0] += 1
            try:
                return original(*args, **kwargs)
            finally:
                nested[0] -= 1
        return call

    timers = [(owner, name, _timed(search(name))) for owner, name in MESH_SEARCHES]
    timers.append((contact_newton, "evaluate_contact", _timed(evaluation)))
    replaced = [(continuation, "solve_with_contact", path_part("step")),
                (continuation, "minimise_with_contact", path_part("walks downhill")),
                (cushion, "solve_with_contact", path_part("narrowings and polish")),
                (cushion, "minimise_with_contact", path_part("walks downhill"))]
    # station_gaps is timed as a whole (its timer wraps it from outside), the segment_gaps it calls not again
    with _replaced([(contact_mesh.MeshArrays, "station_gaps", not_nested)]), _replaced(timers + replaced):
        started = time.perf_counter()
        result = solve_once()
        seconds["total"] = time.perf_counter() - started
    return {"seconds": dict(seconds), "counts": dict(counts), "iterations": result.iterations}


@contextmanager
def _replaced(replacements):
    """Each (owner, name, make) of `replacements`: owner.name replaced by make(original) for the block."""
    originals = [(owner, name, getattr(owner, name)) for owner, name, _ in replacements]
    for owner, name, make in replacements:
        setattr(owner, name, make(getattr(owner, name)))
    try:
        yield
    finally:
        for owner, name, original in reversed(originals):
            setattr(owner, name, original)


def failed_tries(solve_once) -> int:
    """The path steps of the contact continuation whose Newton try did not converge in solve_once() (a placement with
    contact): steps grown too long and tries that bracket or meet a fold."""
    failed = [0]

    def step(original):
        def call(*args, **kwargs):
            trial, report = original(*args, **kwargs)
            failed[0] += not report.converged
            return trial, report
        return call

    with _replaced([(continuation, "_step", step)]):
        solve_once()
    return failed[0]
