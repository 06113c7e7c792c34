"""Where the first run's compile time goes: every kernel Numba compiles for one placement, with its time.

    python bench/bench_compile_profile.py [--segments 100] [--depth 3] [--threshold 0.15]

Runs in a fresh, empty kernel cache (a temporary NUMBA_CACHE_DIR; this process only), places the
thesis brake hose (180 degrees of twist) once and records Numba's "numba:compile" events: for each
compilation, the kernel, its argument types and the seconds it took, including the kernels it
called that compiled inside it (inclusive) and without them (exclusive).  Prints the total, the
kernels compiled at the top (those the Python code calls), the call tree down to --depth for
compilations longer than --threshold seconds, and the kernels compiled for more than one set of
argument types.  Numba's own implementations (numba.np.*, numba.cpython.*: NumPy functions used
inside kernels) count too: some cost a second or more each.
"""

from __future__ import annotations

import argparse
import collections
import os
import tempfile
import time


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--segments", type=int, default=100)
    parser.add_argument("--depth", type=int, default=3, help="levels of the call tree printed")
    parser.add_argument("--threshold", type=float, default=0.15, help="seconds: shorter compilations are not printed")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as cache:
        os.environ["NUMBA_CACHE_DIR"] = cache  # before numba is imported: nothing comes from an earlier cache
        profile(args.segments, args.depth, args.threshold)


def profile(segments: int, depth: int, threshold: float) -> None:
    """Place the thesis hose with a cold cache and print where the compile time went."""
    from numba.core import event

    from hoseline.model import Hose, Mount, Problem
    from hoseline.procedures.placement.sequence import solve

    records = []  # (depth, kernel, argument types, inclusive seconds, exclusive seconds), in the order they ended

    class Recorder(event.Listener):
        def __init__(self) -> None:
            self.open: list[list] = []  # [kernel, types, started, seconds of the compilations inside]

        def on_start(self, happened) -> None:
            function = happened.data["dispatcher"].py_func
            self.open.append([f"{function.__module__}.{function.__name__}", str(happened.data["args"]),
                              time.perf_counter(), 0.0])

        def on_end(self, happened) -> None:
            kernel, types, started, inner = self.open.pop()
            seconds = time.perf_counter() - started
            if self.open:
                self.open[-1][3] += seconds
            records.append((len(self.open), kernel, types, seconds, seconds - inner))

    event.register("numba:compile", Recorder())
    hose = Hose(length=330.6, outer_diameter=10.1, bending_stiffness=149563.0, torsional_stiffness=2454930.0,
                segments=segments)
    problem = Problem(hose, Mount([-13.0, 0.0, -11.25], [0.0, 1.0, 0.0]), Mount([-173.064, -7.0, -11.25], [1.0, 0.0, 0.0]),
                      180.0)
    wall, cpu = time.perf_counter(), time.process_time()
    solve(problem)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    print(f"first placement, cold cache: {wall:.2f} s wall, {cpu:.2f} s CPU, load average {os.getloadavg()[0]:.1f}; "
          f"{len(records)} compilations, {sum(r[4] for r in records):.2f} s in all")
    print("\nkernels compiled at the top (called from Python), inclusive seconds:")
    for level, kernel, types, seconds, _ in sorted(records, key=lambda r: -r[3]):
        if level == 0:
            print(f"  {seconds:7.2f}  {kernel}")
    print(f"\nthe call tree (reversed: callees first, then their caller), compilations over {threshold} s, "
          "inclusive / exclusive seconds:")
    for level, kernel, _, seconds, own in records:
        if seconds > threshold and level < depth:
            print(f"  {'    ' * level}{seconds:6.2f} / {own:5.2f}  {kernel}")
    print("\nexclusive seconds by module:")
    by_module = collections.Counter()
    for _, kernel, _, _, own in records:
        by_module[kernel.rsplit(".", 1)[0]] += own
    for module, seconds in by_module.most_common(12):
        print(f"  {seconds:7.2f}  {module}")
    counts = collections.Counter(kernel for _, kernel, _, _, _ in records if kernel.startswith("hoseline"))
    repeated = {kernel: count for kernel, count in counts.items() if count > 1}
    print("\nhoseline kernels compiled for more than one set of argument types:", repeated or "none")


if __name__ == "__main__":
    main()
