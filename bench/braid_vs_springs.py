"""The continuous braid term against the thesis' stiffener springs: their twist paths on the thesis hose.

    python bench/braid_vs_springs.py [--step 5]

The weightless thesis hose (330.6 mm, EI = 292.7985 N/mm^2 x 510.8053 mm^4, 25x torsion, r = 5.05 mm, the
chapter IV preset's 40 segments) is placed and twisted 0 -> 180 deg in steps, plain, with the preset's 16
springs (forces read in newtons as written, and scaled by 0.03: the strength at which they meet the thesis'
statements, bench/stiffener_units.py --scan) and with braids ([hose.braid], model/braid.py): the thesis'
braid at 38 deg to the axis with 0.5 % slack, and the springs' own geometry as a braid (19 deg to the axis,
8 strands per family on the springs' radius of 3.7 mm, taut at the springs' 2.2 % = 0.19 mm / 8.74 mm) at
the springs' stiffness (n EA_s = 2e6 N: 2500 N over their first 0.01 mm, times 8.74 mm) and at 1/10 and
1/100 and 1/1000 of it.  Printed per model: the largest station distance from the plain model at 0 and 180
deg, the largest and median station movement per step, the jumps (twist_path.py) and the verdict on the thesis' three statements (bench/stiffener_units.py: 0 deg within 4.131 mm of plain, 180 deg
moved by at least 1.643 mm, no jump).  Results and discussion: docs/model.md, "The continuous counterpart".
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

for variable in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(variable, "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from stiffener_units import MOVED_AT_180_MM, UNCHANGED_AT_0_MM, Reading, plain_problem, spring_problem  # noqa: E402

from hoseline.model.braid import Braid  # noqa: E402
from hoseline.procedures.placement.twist_path import follow_twist  # noqa: E402

SPRING_RADIUS_MM = 3.7  # the 16-spring octagon's circumradius for the 330.6 mm hose (docs/model.md)
SPRING_SLACK = 0.19 / 8.7412  # the springs' table is zero up to 0.19 mm of their 8.7412 mm free length
SPRING_STIFFNESS_N = 2e6  # n EA_s of the springs: 2500 N over 0.01 mm, times 8.74 mm (docs/model.md)


def models() -> list[tuple[str, object]]:
    """(label, problem) of every model compared with the plain hose."""
    plain = plain_problem()

    def braided(braid: Braid):
        return replace(plain, hose=replace(plain.hose, braid=braid))

    rows = [(f"springs, F in N{' x ' + format(f, 'g') if f != 1.0 else ''}", spring_problem(Reading("N", "mm", "anchors", f)))
            for f in (1.0, 0.03)]
    rows.append(("braid 38 deg, n EA_s 1.8e4 N, slack 0.5 %", braided(Braid(38.0, 12, 1500.0, 0.005, SPRING_RADIUS_MM))))
    for share in (1.0, 0.1, 0.01, 0.001):
        stiffness = share * SPRING_STIFFNESS_N
        rows.append((f"braid 19 deg, n EA_s {stiffness:.0e} N, slack 2.2 %",
                     braided(Braid(19.0, 8, stiffness / 8, SPRING_SLACK, SPRING_RADIUS_MM))))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--step", type=float, default=5.0, help="twist step, degrees")
    args = parser.parse_args()
    twists = np.arange(0.0, 180.0 + 0.5 * args.step, args.step)
    begun = time.perf_counter()
    plain = follow_twist(plain_problem(), twists, "plain")
    print(f"plain 25x model: largest step {plain.steps.max():.2f} mm, median {np.median(plain.steps):.2f} mm")
    print(f"{'model':<46} {'0 deg':>7} {'180 deg':>8} {'step max':>9} {'median':>7}  jumps / verdict")
    for label, problem in models():
        path = follow_twist(problem, twists, label)
        distance = np.linalg.norm(path.centerlines - plain.centerlines[: len(path.centerlines)], axis=2).max(axis=1)
        at_0, at_180 = float(distance[0]), float(distance[-1]) if not path.failure else float("nan")
        verdict = [name for name, ok in (("0 deg", at_0 <= UNCHANGED_AT_0_MM), ("180 deg", at_180 >= MOVED_AT_180_MM),
                                         ("smooth", path.smooth)) if not ok]
        jumps = ", ".join(f"{t:g} deg {m:.1f} mm" for t, m in path.jumps) or "none"
        print(f"{label:<46} {at_0:7.3f} {at_180:8.3f} {path.steps.max():9.2f} {np.median(path.steps):7.2f}  "
              f"{jumps}; {'fails: ' + ', '.join(verdict) if verdict else 'meets all three'}"
              + (f" [{path.failure}]" if path.failure else ""))
    print(f"steps of {args.step:g} deg; {time.perf_counter() - begun:.0f} s; load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
