"""Benchmark: a rare failure by FORM, SORM and importance sampling, counting the placements.

    python bench/bench_rare.py [--limit 10500] [--quantity end_torque] [--importance 100] [--segments 100]

The thesis hose placement (to its 180 degrees of twist) with the tolerances of bench_study.py but the length
normal (the end mount within a 1 mm sphere, its direction within a 2 degree cone, the length +-1 mm and 1 %
(normal), EI by a factor 2 (lognormal), the clocking +-3 degrees); the limit set so that the failure
probability is near 1e-6.  Runs in this process ([reliability] method = "sorm") and counts every placement
from the straight hose (placement.sequence.place_only): FORM's and SORM's (a solve with sensitivities places
the hose twice when it is twisted: with and without the twist, to rebuild both equilibria) and the importance
samples'.  Prints beta, the probabilities, the counts, the importance estimate with its 95 % interval, the wall
time and the machine's load.  Target: a FORM probability at 1e-6 with <= 200 placements.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import hoseline.procedures.variation.nominal as nominal  # noqa: E402
import hoseline.procedures.variation.samples as samples  # noqa: E402
from hoseline.demos.thesis_hose import demo_problem  # noqa: E402
from hoseline.procedures.variation.engine import Where  # noqa: E402
from hoseline.procedures.variation.quantities import Limit, quantities  # noqa: E402
from hoseline.procedures.variation.rare import Reliability  # noqa: E402
from hoseline.procedures.variation.run import run_study  # noqa: E402
from hoseline.procedures.variation.samples import StudyBase  # noqa: E402
from hoseline.procedures.variation.study import Sampling, Study  # noqa: E402
from hoseline.procedures.variation.tolerances import Tolerance, Variation  # noqa: E402

TOLERANCES = Variation((
    Tolerance("end.point", "sphere", (1.0,)),
    Tolerance("end.direction", "cone", (2.0,)),
    Tolerance("hose.length", "normal", (1.0,)),
    Tolerance("hose.length", "normal", (0.01 * 330.6,)),
    Tolerance("hose.bending_stiffness", "lognormal", (2.0,)),
    Tolerance("end.twist", "normal", (3.0,)),
))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quantity", default="end_torque")
    parser.add_argument("--limit", type=float, default=10500.0)
    parser.add_argument("--importance", type=int, default=100)
    parser.add_argument("--segments", type=int, default=100)
    args = parser.parse_args()
    counts = {"placements": 0}

    def counted(original):
        def place_only(problem):
            counts["placements"] += 1
            return original(problem)
        return place_only

    nominal.place_only = counted(nominal.place_only)  # FORM's and SORM's solves
    samples.place_only = counted(samples.place_only)  # the importance samples (and the study's one sample)
    quantity = {q.name: q for q in quantities(())}[args.quantity]
    study = Study("rare", StudyBase(demo_problem(180.0, args.segments)), TOLERANCES, Sampling("monte-carlo", 1),
                  (Limit(quantity, args.limit),), sensitivities=False,
                  reliability=Reliability("sorm", importance_samples=args.importance, seed=1))
    load = os.getloadavg()[0]
    started = time.perf_counter()
    outcome = run_study(study, where=Where(workers=0))
    seconds = time.perf_counter() - started
    event = outcome.rare_events[0]
    form_solves = event.point.evaluations
    print(f"{event.limit.describe()}: beta {event.point.beta:.4f}, FORM P {event.form:.3g}, SORM P {event.sorm:.3g}"
          f" (converged {event.point.converged})")
    print(f"FORM: {form_solves} solves with sensitivities; SORM: {event.evaluations - form_solves} more")
    check = event.importance
    if check is not None:
        print(f"importance sampling: P {check.estimate:.3g}, 95 % interval [{check.low:.3g}, {check.high:.3g}], "
              f"c.o.v. {check.coefficient_of_variation:.2f}, {check.samples} samples ({check.failed} failed)")
    print(f"placements from the straight hose: {counts['placements']} in all (nominal 1, the study's sample 1, "
          f"importance {args.importance}, FORM and SORM the rest); {seconds:.1f} s wall at load {load:.1f}")


if __name__ == "__main__":
    main()
