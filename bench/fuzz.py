"""The long fuzzing campaign: generated and mutated inputs through the command line, outcomes counted by kind.

    python bench/fuzz.py --count 10000 [--seed 1] [--timeout 60] [--out out/fuzz] [--kinds problem,sweep] [--jobs 2]

Runs `count` inputs, split over the kinds of tests/fuzz_cases.py by WEIGHTS, each through
the CLI in-process (as `make test`'s short run does) with a watchdog of `timeout` seconds;
with --jobs, the kinds run in that many processes at once.
Counts exit codes 0/2/3/4 and the failures (traceback, hang, other exit code, partial
output, unclear error, refused feasible input, bad exit-0 result) by kind, prints the table,
writes out/fuzz/summary.json (with a few error messages of each kind and exit code) and keeps every failing input under out/fuzz/failures/ with its
command and traceback.  Exits 1 if any input failed.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from fuzz_cases import FAILURES, KINDS, STRATEGIES, TIMEOUT_S, fresh_folder, keep, run_input  # noqa: E402
from hypothesis import HealthCheck, Phase, given, seed, settings  # noqa: E402

# share of the inputs per kind (per mille): a sweep or a scan comparison that succeeds writes its report (PNGs,
# HTML) and costs seconds, a refused input milliseconds, so the file formats get most of the inputs
WEIGHTS = {"problem": 400, "iges": 220, "feasible": 150, "sweep": 60, "poses": 50, "mesh": 50, "feasible_sweep": 20,
           "cloud": 50, "contact": 100}
# about how long one input of each kind takes, s (to start the slow kinds first)
SECONDS_PER_INPUT = {"problem": 0.05, "iges": 0.05, "feasible": 0.25, "sweep": 1.0, "poses": 1.4, "mesh": 0.4,
                     "feasible_sweep": 3.0, "cloud": 0.6, "contact": 0.15}
EXAMPLES = 8  # error messages kept per kind and exit code
OUTCOMES = ("exit 0", "exit 2", "exit 3", "exit 4") + FAILURES


def shares(count: int, kinds: list[str]) -> dict[str, int]:
    """Inputs per kind, `count` in all, in proportion to WEIGHTS."""
    total = sum(WEIGHTS[k] for k in kinds)
    split = {k: count * WEIGHTS[k] // total for k in kinds}
    split[kinds[0]] += count - sum(split.values())
    return split


def campaign(kind: str, examples: int, out: Path, timeout: int, random_seed: int) -> Counter:
    """Run `examples` inputs of `kind`; return counts[(kind, outcome)] and counts[(kind, "seconds")].

    Failing inputs are kept under out/failures/.
    """
    from hoseline.procedures.compile_kernels import compile_kernels

    # compile (or load) the solver before any input's watchdog runs: a first compilation on a cold cache
    # under load can outlast the watchdog, and an alarm inside Numba's compiler leaves it broken (seen as
    # "no compiled object yet" on the next input), which is the harness's failure, not the program's
    compile_kernels(clearance=True)
    counts: Counter = Counter()
    number = 0
    started = time.perf_counter()
    print(f"{kind}: {examples} inputs", flush=True)
    with tempfile.TemporaryDirectory(dir=out, prefix=f"run-{kind}-") as scratch:

        # generation only: every input is counted once (shrinking would re-run failures); failures are kept instead
        @seed(random_seed)
        @settings(max_examples=examples, deadline=None, database=None, suppress_health_check=list(HealthCheck),
                  phases=(Phase.generate,), print_blob=False)
        @given(STRATEGIES[kind]())
        def one(case):
            nonlocal number
            number += 1
            outcome = run_input(case, fresh_folder(Path(scratch), "case"), timeout)
            label = outcome.failure or f"exit {outcome.exit_code}"
            counts[(kind, label)] += 1
            counts[(kind, "seconds")] += outcome.seconds
            if outcome.exit_code and counts[(kind, label, "examples")] < EXAMPLES:  # messages to read in summary.json
                counts[(kind, label, "examples")] += 1
                counts[(kind, label, outcome.output.strip()[-400:])] += 1
            if outcome.failure:
                keep(case, outcome, out / "failures" / f"{kind}-{number:05d}")
                last = (outcome.detail.strip().splitlines() or [""])[-1]
                print(f"  {kind} #{number}: {outcome.failure}: {last[:200]}", flush=True)

        one()
    print(f"{kind}: done in {time.perf_counter() - started:.0f} s", flush=True)
    return counts


def table(counts: Counter, kinds: list[str]) -> str:
    """The outcome counts as a text table, one row per kind and a total."""
    columns = [o for o in OUTCOMES if o.startswith("exit ") or any(counts[(k, o)] for k in kinds)]
    rows = [["kind", "inputs", *columns, "mean s"]]
    for kind in kinds + ["total"]:
        members = kinds if kind == "total" else [kind]
        values = [sum(counts[(k, o)] for k in members) for o in columns]
        inputs = sum(counts[(k, o)] for k in members for o in OUTCOMES)
        seconds = sum(counts[(k, "seconds")] for k in members)
        rows.append([kind, str(inputs), *map(str, values), f"{seconds / max(inputs, 1):.2f}"])
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return "\n".join("  ".join(cell.rjust(w) for cell, w in zip(row, widths)) for row in rows)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--count", type=int, default=10_000, help="inputs in all")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--timeout", type=int, default=TIMEOUT_S, help="seconds after which one input is a hang")
    parser.add_argument("--out", type=Path, default=Path("out/fuzz"), help="summary and failing inputs")
    parser.add_argument("--jobs", type=int, default=1, help="processes running kinds at once")
    parser.add_argument("--kinds", default=",".join(KINDS), help=f"comma-separated, from {', '.join(KINDS)}")
    options = parser.parse_args()
    kinds = [k for k in options.kinds.split(",") if k]
    unknown = [k for k in kinds if k not in KINDS]
    if unknown or not kinds:
        parser.error(f"unknown kinds {unknown}; choose from {', '.join(KINDS)}")
    options.out.mkdir(parents=True, exist_ok=True)
    counts: Counter = Counter()
    started = time.perf_counter()
    split = shares(options.count, kinds)
    slow_first = sorted(kinds, key=lambda k: -split[k] * SECONDS_PER_INPUT[k])
    with ProcessPoolExecutor(max_workers=options.jobs) as pool:
        runs = [pool.submit(campaign, k, split[k], options.out, options.timeout, options.seed) for k in slow_first]
        for run in runs:
            counts.update(run.result())
    report = table(counts, kinds)
    failed = sum(counts[(k, f)] for k in kinds for f in FAILURES)
    summary = {
        "count": sum(counts[(k, o)] for k in kinds for o in OUTCOMES), "seed": options.seed,
        "timeout_s": options.timeout, "wall_time_s": round(time.perf_counter() - started, 1), "failed": failed,
        "by_kind": {k: {o: counts[(k, o)] for o in OUTCOMES if counts[(k, o)]} for k in kinds},
        "messages": {f"{key[0]}, {key[1]}": [] for key in counts if len(key) == 3 and key[2] != "examples"},
    }
    for key in counts:
        if len(key) == 3 and key[2] != "examples":
            summary["messages"][f"{key[0]}, {key[1]}"].append(key[2])
    (options.out / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
    (options.out / "summary.txt").write_text(report + "\n")
    print(report)
    print(f"{summary['count']} inputs in {summary['wall_time_s']:.0f} s; {failed} failed"
          + (f" (kept in {options.out / 'failures'})" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
