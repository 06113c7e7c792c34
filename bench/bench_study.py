"""Benchmark: variation studies on Dask (LocalCluster on this machine).

    python bench/bench_study.py [--command 10000] [--placements 10000] [--sweeps 1000] [--scaling 1000] [--repeats 3]

0. --command samples of the thesis hose placement as an engineer runs them: the whole `hoseline study`
   command (start-up, nominal hose and sensitivities, the LocalCluster of 2 workers started and
   warmed meanwhile, the samples, the report and files written), its wall time, its stages (from
   summary.json), and the CPU time of the command and all its processes per sample.  Target: 60 s.

1. --placements Monte Carlo samples of the thesis hose placement (100 segments, to its 180 degrees
   of twist), 2 workers, each sample placed from the straight hose (start "straight") and then by
   Newton from the nominal hose (start "nominal").  Target: 60 s.
2. --sweeps samples of the demo sweep (steer and jounce, every pose, clearance to the strut),
   2 workers.  Target: 300 s.
3. Scaling: the same --scaling placement samples on 1 and on 2 workers, --repeats times each (1, 2, 1, 2, ...
   interleaved, so that a change in the machine's load falls on both), both starts; medians of samples per
   second, the ratio 2 workers / 1 worker (target 1.8), and the workers' CPU per sample of each.  Alone:
   --command 0 --placements 0 --sweeps 0.
4. With --sweeps: sensitivities of the demo sweep (every pose, the tolerances below) in this process, --repeats
   times, beside one sample of the same sweep: the median of each and their ratio (what the first
   order costs in samples).
Tolerances: the end mount within a 1 mm sphere, its direction within a 2 degree cone, the length
+-1 mm (normal) and -4..+2 % under pressure, EI by a factor 2 (lognormal), the clocking +-3 degrees.
Times are the batches from the first submission to the last result (the cluster started and the
solver warmed before), and the whole run with the cluster's start; the machine's load is printed,
and the workers' CPU time per sample, which does not depend on what else runs (on a shared machine
the wall time does), with the wall time it projects for two idle cores.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hoseline.demos.sweep import demo_sweep  # noqa: E402
from hoseline.demos.thesis_hose import demo_problem  # noqa: E402
from hoseline.procedures.variation.designs import unit_design  # noqa: E402
from hoseline.procedures.variation.engine import Engine, Where, default_batch_size  # noqa: E402
from hoseline.procedures.variation.samples import StudyBase, nominal_context  # noqa: E402
from hoseline.procedures.variation.sweep_sensitivity import sweep_sensitivities  # noqa: E402
from hoseline.io.problem_file import problem_to_toml  # noqa: E402
from hoseline.procedures.variation.tolerances import Tolerance, Variation  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]

TOLERANCES = Variation((
    Tolerance("end.point", "sphere", (1.0,)),
    Tolerance("end.direction", "cone", (2.0,)),
    Tolerance("hose.length", "normal", (1.0,)),
    Tolerance("hose.length", "uniform", (-0.04 * 330.6, 0.02 * 330.6)),
    Tolerance("hose.bending_stiffness", "lognormal", (2.0,)),
    Tolerance("end.twist", "normal", (3.0,)),
))


def timed(base: StudyBase, count: int, workers: int, warm: bool = False) -> tuple[float, float, float, int]:
    """(seconds of the batches, seconds with the cluster's start, worker CPU seconds per sample, failed samples).

    warm: every placement sample by Newton from the nominal hose (start = "nominal"), not from the straight hose.
    The CPU seconds are the workers' process time over the batches: what the samples cost whatever else runs.
    """
    context, _ = nominal_context(base, warm)
    coordinates = TOLERANCES.coordinates(unit_design("monte-carlo", count, TOLERANCES.dimensions, 1))
    failed = []
    started = time.perf_counter()
    with Engine(Where(workers=workers)) as engine:
        before = engine.client.run(time.process_time)  # every worker up and warmed (the plugin's setup ran)
        tick = time.perf_counter()
        engine.run(context, coordinates, default_batch_size(count), lambda k, arrays: failed.append(arrays["failed"].sum()))
        batches = time.perf_counter() - tick
        cpu = sum(engine.client.run(time.process_time).values()) - sum(before.values())
    return batches, time.perf_counter() - started, cpu / count, int(sum(failed))


STUDY_FILE = """
name = "bench"
base = "problem.toml"
sensitivities = true
[sampling]
method = "monte-carlo"
samples = {count}
seed = 1
[[vary]]
parameter = "end.point"
distribution = "sphere"
radius = 1.0
[[vary]]
parameter = "end.direction"
distribution = "cone"
angle = 2.0
[[vary]]
parameter = "hose.length"
distribution = "normal"
sigma = 1.0
[[vary]]
parameter = "hose.length"
distribution = "uniform"
range = [-4.0, 2.0]
unit = "%"
[[vary]]
parameter = "hose.bending_stiffness"
distribution = "lognormal"
factor = 2.0
[[vary]]
parameter = "end.twist"
distribution = "normal"
sigma = 3.0
[limits]
bend_radius = 30.0
end_torque = 2500.0
"""  # the TOLERANCES above, as a study file


def whole_command(count: int) -> tuple[float, float, dict]:
    """(wall seconds, CPU seconds of the command and every process it started, summary.json's run figures) of
    `hoseline study` on `count` samples of the thesis hose to 180 degrees (the default LocalCluster)."""
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        (folder / "problem.toml").write_text(problem_to_toml(demo_problem(180.0)), encoding="utf-8")
        (folder / "study.toml").write_text(STUDY_FILE.format(count=count), encoding="utf-8")
        command = [str(Path(sys.executable).with_name("hoseline")), "study", str(folder / "study.toml"), "-o",
                   str(folder / "out"), "-q"]
        environment = {**os.environ, "PYTHONPATH": str(ROOT)}
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        tick = time.perf_counter()
        subprocess.run(command, check=True, env=environment, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        wall = time.perf_counter() - tick
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
        run = json.loads((folder / "out" / "summary.json").read_text(encoding="utf-8"))["run"]
    return wall, cpu, run


def load() -> str:
    one, five, fifteen = os.getloadavg()
    return f"load average {one:.2f} {five:.2f} {fifteen:.2f} on {os.cpu_count()} cores"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--command", type=int, default=10_000)
    parser.add_argument("--placements", type=int, default=10_000)
    parser.add_argument("--sweeps", type=int, default=1000)
    parser.add_argument("--scaling", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=3)
    options = parser.parse_args()
    placement = StudyBase(demo_problem(180.0))
    sweep = demo_sweep()
    sweep_base = StudyBase(sweep.problem, sweep)
    print(load())

    if options.command:
        wall, cpu, run = whole_command(options.command)
        stages = ", ".join(f"{key.removeprefix('seconds, ')} {value:.1f} s" for key, value in run.items()
                           if key.startswith("seconds, ") and value is not None)
        print(f"whole command: {options.command} samples in {wall:.1f} s; CPU {1e3 * cpu / options.command:.2f} ms per "
              f"sample, all processes, start-up and report included (idle 2 cores: {cpu / 2:.1f} s); stages: {stages}; "
              f"outside the study (start-up, report) {wall - run['seconds, whole study']:.1f} s; target 60 s for 10 000: "
              f"ratio {wall / (60.0 * options.command / 10_000):.2f}   ({load()})")
    for start, warm in (("straight", False), ("nominal", True)):
        if options.scaling:
            runs = {1: [], 2: []}
            for _ in range(options.repeats):
                for workers in (1, 2):
                    runs[workers].append(timed(placement, options.scaling, workers, warm))
            rates = {}
            for workers, found in runs.items():
                walls = sorted(run[0] for run in found)
                rates[workers] = options.scaling / statistics.median(walls)
                print(f"scaling, start {start}: {options.scaling} placements on {workers} worker(s): median "
                      f"{statistics.median(walls):.2f} s of {options.repeats} ({', '.join(f'{w:.2f}' for w in walls)}), "
                      f"{rates[workers]:.0f} samples/s, worker CPU {1e3 * statistics.median(run[2] for run in found):.2f} "
                      f"ms per sample   ({load()})")
            print(f"scaling, start {start}: 2 workers / 1 worker = {rates[2] / rates[1]:.2f} (target 1.8)")
        if options.placements:
            batches, total, cpu, failed = timed(placement, options.placements, 2, warm)
            print(f"placements, start {start}: {options.placements} samples on 2 workers in {batches:.1f} s ({total:.1f} s "
                  f"with the cluster's start), {options.placements / batches:.0f} samples/s, {failed} failed, worker CPU "
                  f"{1e3 * cpu:.2f} ms per sample (idle 2 cores: {options.placements * cpu / 2:.1f} s); target 60 s for "
                  f"10 000: ratio {batches / (60.0 * options.placements / 10_000):.2f}   ({load()})")
    if options.sweeps:
        batches, total, cpu, failed = timed(sweep_base, options.sweeps, 2)
        print(f"sweeps: {options.sweeps} samples of {sweep.pose_count} poses on 2 workers in {batches:.1f} s ({total:.1f} s "
              f"with the cluster's start), {failed} failed, worker CPU {1e3 * cpu:.0f} ms per sample (idle 2 cores: "
              f"{options.sweeps * cpu / 2:.0f} s); target 300 s for 1000: ratio "
              f"{batches / (300.0 * options.sweeps / 1000):.2f}   ({load()})")
    if options.sweeps and options.repeats:
        sensitivities, sample = [], []
        for _ in range(options.repeats + 1):  # the first run loads the compiled kernels: not counted
            tick = time.perf_counter()
            sweep_sensitivities(sweep, TOLERANCES.varied)
            sensitivities.append(time.perf_counter() - tick)
            tick = time.perf_counter()
            sweep_base.read(sweep.problem)
            sample.append(time.perf_counter() - tick)
        first, one = statistics.median(sensitivities[1:]), statistics.median(sample[1:])
        print(f"sweep sensitivities: {len(TOLERANCES.varied)} coordinates over {sweep.pose_count} poses in {first:.2f} s "
              f"(median of {options.repeats}), one sample of the sweep {one:.2f} s: the first order costs "
              f"{first / one:.1f} samples   ({load()})")


if __name__ == "__main__":
    main()
