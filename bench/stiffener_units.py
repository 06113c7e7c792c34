"""Units study: which reading of the thesis' spring tables agrees with the thesis' own statements?

    python bench/stiffener_units.py [--step 5] [--springs 16] [--scan]

The thesis' chapter IV preset (Table 6 forces, equations 17-28 deformations, 40 elements of
8.265 mm at 71 deg for the 330.6 mm hose) is read twelve ways: forces in N or mN, deformations
in mm, cm or m, the spring free at its anchor distance on the straight hose (element /
sin(angle), where the thesis' Figure 27 puts the table's zero) or at the element length.
--scan instead scales the table in newtons by 0.01-0.3 (a diagnostic: how strong would springs
have to be to meet the thesis' statements; not a reading of any unit).  For each reading
the weightless thesis hose (25x torsion, as the thesis' spring models) is placed and twisted
0 -> 180 deg in steps, and compared with the same hose without springs (same 40 segments).

Printed per reading: the largest station distance from the plain model at 0 and 180 deg, the
largest and median station movement per twist step, the jumps (twist_path.py: a step above
3x the median and 1 mm) and the verdict on the thesis' three statements:

- 0 deg nearly unchanged: the thesis' base model lies at most 2.412 mm from the 0 deg scan at
  its reference points (Table 1) and its spring models at most 1.719 mm (Tables 3, 8, 11), so
  near those points the two models lie within 2.412 + 1.719 = 4.131 mm of each other
  (triangle inequality).  We ask it of every station (stricter: the reference points were put
  where the base model deviated most).
- deviation at 180 deg reduced: changing only the spring angle (60 -> 71 deg, Table 3)
  moves the 180 deg deviation at location 5 by 8.297 - 5.011 = 3.286 mm, so the springs move
  the 180 deg shape by at least half of that, 1.643 mm, for at least one of those angles
  (|x60 - x71| <= |x60 - plain| + |x71 - plain|).  No scans are in the repository, so the
  deviations themselves cannot be recomputed; this bound is what the tables allow.
- a smooth twist path: no jump and no failure (the thesis' 16-spring model had "no sudden
  acceleration").

Prints the machine's load; takes a few minutes (each spring model's twist takes seconds).  Results and
their discussion: docs/model.md, "Stiffener springs".
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import dataclass, replace
from itertools import product
from pathlib import Path

for variable in ("NUMBA_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(variable, "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hoseline.demos.validation import EI, TRUE_FACTOR, brake_hose  # noqa: E402
from hoseline.model.stiffeners import SpringTable, table_read_as, thesis_preset  # noqa: E402
from hoseline.procedures.placement.twist_path import TwistPath, follow_twist  # noqa: E402

LENGTH = 330.6  # mm, the thesis' dialogue example
UNCHANGED_AT_0_MM = 2.412 + 1.719  # Table 1 (base model, 0 deg) + Tables 3, 8, 11 (spring models, 0 deg)
MOVED_AT_180_MM = 0.5 * (8.297 - 5.011)  # Table 3, location 5: 60 deg against 71 deg


@dataclass(frozen=True)
class Reading:
    """One reading of the spring table: force unit, deformation unit, free length (model/stiffeners.py)."""

    force_unit: str
    deformation_unit: str
    free_length: str
    force_factor: float = 1.0  # a diagnostic scale on top of the unit (--scan), not a reading of the thesis

    @property
    def label(self) -> str:
        scale = f" x {self.force_factor:g}" if self.force_factor != 1.0 else ""
        return f"F in {self.force_unit}{scale}, x in {self.deformation_unit}, free at {self.free_length}"


READINGS = tuple(Reading(*choice) for choice in product(("N", "mN"), ("mm", "cm", "m"), ("anchors", "element")))
SCAN_FACTORS = (0.01, 0.03, 0.1, 0.3)


@dataclass(frozen=True)
class Outcome:
    """A reading's twist path against the plain model's: distances in mm; verdicts on the three statements."""

    reading: Reading
    at_0: float
    at_180: float
    largest_step: float
    median_step: float
    jumps: list
    failure: str

    @property
    def unchanged_at_0(self) -> bool:
        return self.at_0 <= UNCHANGED_AT_0_MM

    @property
    def moved_at_180(self) -> bool:
        return self.at_180 >= MOVED_AT_180_MM and not self.failure

    @property
    def smooth(self) -> bool:
        return not self.jumps and not self.failure

    @property
    def survives(self) -> bool:
        return self.unchanged_at_0 and self.moved_at_180 and self.smooth


def spring_problem(reading: Reading, springs: int = 16):
    """The weightless thesis hose (25x torsion) with the preset's springs read as `reading`."""
    preset = thesis_preset(LENGTH, springs)
    stiffeners = preset.stiffeners
    table = table_read_as(stiffeners.table, reading.force_unit, reading.deformation_unit, reading.free_length,
                          preset.spring_length, preset.element_length)
    table = SpringTable(table.deformation, tuple(reading.force_factor * np.asarray(table.force)))
    return brake_hose(EI, TRUE_FACTOR, preset.segments, mass=0.0, stiffeners=replace(stiffeners, table=table))


def plain_problem():
    """The same hose without springs, at the preset's segment count."""
    return brake_hose(EI, TRUE_FACTOR, thesis_preset(LENGTH).segments, mass=0.0)


def outcome(reading: Reading, path: TwistPath, plain: TwistPath) -> Outcome:
    """Compare a reading's twist path with the plain model's (at the twists both reached)."""
    distance = np.linalg.norm(path.centerlines - plain.centerlines[: len(path.centerlines)], axis=2).max(axis=1)
    at_180 = float(distance[-1]) if not path.failure else float("nan")
    return Outcome(reading, float(distance[0]), at_180, float(path.steps.max()), float(np.median(path.steps)),
                   path.jumps, path.failure)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--step", type=float, default=5.0, help="twist step, degrees")
    parser.add_argument("--springs", type=int, default=16, choices=(8, 16))
    parser.add_argument("--scan", action="store_true",
                        help="instead of the readings: forces in N scaled by 0.01-0.3 (diagnostic: how strong would fit?)")
    args = parser.parse_args()
    readings = READINGS if not args.scan else tuple(Reading("N", "mm", "anchors", f) for f in SCAN_FACTORS)
    twists = np.arange(0.0, 180.0 + 0.5 * args.step, args.step)
    begun = time.perf_counter()
    plain = follow_twist(plain_problem(), twists, "plain")
    print(f"plain 25x model: largest step {plain.steps.max():.2f} mm, median {np.median(plain.steps):.2f} mm")
    print(f"bounds: 0 deg <= {UNCHANGED_AT_0_MM:.3f} mm from plain; 180 deg >= {MOVED_AT_180_MM:.3f} mm; no jump")
    print(f"{'reading':<47} {'0 deg':>7} {'180 deg':>8} {'step max':>9} {'median':>7}  jumps / verdict")
    for reading in readings:
        path = follow_twist(spring_problem(reading, args.springs), twists, reading.label)
        result = outcome(reading, path, plain)
        jumps = ", ".join(f"{t:g} deg {m:.1f} mm" for t, m in result.jumps) or "none"
        verdict = "SURVIVES" if result.survives else "fails: " + ", ".join(
            name for name, ok in (("0 deg", result.unchanged_at_0), ("180 deg", result.moved_at_180),
                                  ("smooth", result.smooth)) if not ok)
        print(f"{reading.label:<47} {result.at_0:7.3f} {result.at_180:8.3f} {result.largest_step:9.2f} "
              f"{result.median_step:7.2f}  {jumps}; {verdict}" + (f" [{result.failure}]" if result.failure else ""))
    print(f"{args.springs} springs, steps of {args.step:g} deg; {time.perf_counter() - begun:.0f} s; "
          f"load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
