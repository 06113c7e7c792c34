"""Mutation testing: does a wrong version of the physics fail at least one test?

Each mutation below is one readable change of the real source (file, old text, new text).  For
each, hoseline/, tests/ and pyproject.toml are copied to a fresh temporary directory, the change
is applied there (never in the checkout), and pytest runs the physics tests against the copy:
PYTHONPATH puts the copy's hoseline ahead of the editable install (checked for every run), and
every run compiles its kernels afresh into its own NUMBA_CACHE_DIR, so no cached machine code of
another version can stand in for the mutated source.  The unmutated copy runs first: the tests
must pass there, or no verdict means anything.

    python tools/mutate.py            # all mutations (1-3 minutes each, most of it compiling)
    python tools/mutate.py --list     # what would be applied
    python tools/mutate.py --only lock-angle-clamped --only gravity-axis
    python tools/mutate.py --only twist-sign --every   # name every failing test, not just the first
    python tools/mutate.py --only twist-sign --tests tests/test_physics_references.py  # other tests

Prints a table (killed by which test, or survived) and exits 1 if any mutation survived or
could not be applied (its old text is no longer in the source).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# The tests that guard the physics, in the order they run (pytest -x stops at the first failure).
PHYSICS_TESTS = (
    "tests/test_physics_references.py",
    "tests/test_stability_margin.py",
    "tests/test_cantilever.py",
    "tests/test_second_method.py",
    "tests/test_placement.py",
    "tests/test_validation.py",
    "tests/test_calibration.py",
    "tests/test_braid.py",
)


@dataclass(frozen=True)
class Mutation:
    """One wrong version: `old` replaced once by `new` in `path` (relative to the repository)."""

    name: str
    path: str
    old: str
    new: str
    description: str


MUTATIONS = (
    Mutation("torsion-x2", "hoseline/model/hose.py",
             "return np.array([self.bending_stiffness, second, self.torsional_stiffness], dtype=float)",
             "return np.array([self.bending_stiffness, second, 2.0 * self.torsional_stiffness], dtype=float)",
             "torsional stiffness GJ scaled by 2 (the hose's stiffness vector)"),
    Mutation("torsion-x0.5", "hoseline/mechanics/energy.py",
             "k0, k1, k2 = stiffness[0], stiffness[1], stiffness[2]",
             "k0, k1, k2 = stiffness[0], stiffness[1], 0.5 * stiffness[2]",
             "torsional stiffness GJ scaled by 0.5 (the compiled joint kernel)"),
    Mutation("twist-sign", "hoseline/procedures/placement/path.py",
             "rotation_matrix(self.problem.end.direction * math.radians(twist_deg))",
             "rotation_matrix(-self.problem.end.direction * math.radians(twist_deg))",
             "end twist of the opposite sign"),
    Mutation("fitted-radius-nominal", "hoseline/procedures/scans/cylinder_fit.py",
             "fitted_radius = solution.x[6] if free_radius else radius",
             "fitted_radius = radius",
             "scan fit reports the nominal radius instead of the fitted one"),
    Mutation("gravity-axis", "hoseline/procedures/placement/path.py",
             "return problem.hose.mass_per_length * problem.gravity * 1e-3",
             "return problem.hose.mass_per_length * np.roll(problem.gravity, 1) * 1e-3",
             "gravity along the wrong axis (x, y, z -> z, x, y)"),
    Mutation("lock-angle-clamped", "hoseline/procedures/placement/sequence.py",
             "locked_frame = end_frame_of(place_path(1.0), state)",
             "locked_frame = end_frame_of(place_path(1.0), RodState(state.frames, state.end_force, "
             "state.roll + math.radians(5.0)))",
             "end fitting locked 5 deg off the torque-free roll"),
    Mutation("lock-angle-reported", "hoseline/procedures/placement/sequence.py",
             "lock_angle_deg = math.degrees(math.remainder(state.roll, 2.0 * math.pi))",
             "lock_angle_deg = math.degrees(math.remainder(state.roll, 2.0 * math.pi)) + 5.0",
             "lock angle reported 5 deg off"),
    Mutation("clamp-frame-rolled", "hoseline/procedures/placement/path.py",
             "self.start_frame = frame_from_tangent(problem.start.direction)",
             "self.start_frame = frame_from_tangent(problem.start.direction)[[1, 0, 2]] * np.array([[1.0], [-1.0], [1.0]])",
             "start clamp frame rolled by 90 deg about the hose axis"),
    Mutation("bend-radius-centreline", "hoseline/procedures/placement/stations.py",
             "min_radius = (1.0 / max_curvature - radius_outer) if max_curvature > 0.0 else math.inf",
             "min_radius = (1.0 / max_curvature) if max_curvature > 0.0 else math.inf",
             "minimum bend radius to the centreline, not the inside of the bend (result)"),
    Mutation("bend-radius-centreline-sweep", "hoseline/procedures/placement/hose_health.py",
             "bend_radius = 1.0 / curvature - outer_radius",
             "bend_radius = 1.0 / curvature",
             "bend radius to the centreline, not the inside of the bend (hose_health, per sweep pose)"),
    Mutation("margin-per-joint", "hoseline/procedures/placement/stations.py",
             "margin = float(values[0]) / h",
             "margin = float(values[0])",
             "stability margin not divided by the segment length"),
    Mutation("uncertainty-one-dof", "hoseline/procedures/scans/calibration.py",
             "relative_std = _relative_std(solution.jac, solution.fun, 2 * station_count)",
             "relative_std = _relative_std(solution.jac, solution.fun, station_count)",
             "calibration uncertainty from one degree of freedom per station instead of two"),
    Mutation("gravity-sign", "hoseline/procedures/placement/path.py",
             "return problem.hose.mass_per_length * problem.gravity * 1e-3",
             "return -problem.hose.mass_per_length * problem.gravity * 1e-3",
             "gravity pointing up"),
    Mutation("clamp-joint-length", "hoseline/mechanics/energy.py",
             "energy = joint_terms_into(start_frame, frames[0], stiffness, 0.5 * h, g, haa, hab, braid)",
             "energy = joint_terms_into(start_frame, frames[0], stiffness, h, g, haa, hab, braid)",
             "start clamp joint a whole segment long instead of half"),
    Mutation("braid-x2", "hoseline/mechanics/braid.py",
             "strands * strand_axial_stiffness / (2.0 * math.cos(beta)),",
             "strands * strand_axial_stiffness / math.cos(beta),",
             "braid strands twice as stiff (the coefficient n EA_s / (2 cos beta))"),
    Mutation("braid-twist-sign", "hoseline/mechanics/braid.py",
             "w2 += sign * twist_arm * slope_b",
             "w2 += twist_arm * slope_b",
             "both strand families stretched by twist (the sense of the family dropped from the twist gradient)"),
    Mutation("braid-bending-arm", "hoseline/mechanics/braid.py",
             "radius * math.cos(beta) ** 2,",
             "radius * math.cos(beta),",
             "a strand's bending strain with cos(beta) instead of cos^2(beta)"),
)


def _copy(destination: Path) -> None:
    shutil.copytree(ROOT / "hoseline", destination / "hoseline", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(ROOT / "tests", destination / "tests", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy2(ROOT / "pyproject.toml", destination / "pyproject.toml")


def _apply(copy: Path, mutation: Mutation) -> bool:
    """Apply `mutation` to the copy; False if its old text is not (exactly once) in the source."""
    target = copy / mutation.path
    text = target.read_text(encoding="utf-8")
    if text.count(mutation.old) != 1:
        return False
    target.write_text(text.replace(mutation.old, mutation.new), encoding="utf-8")
    return True


def _run(copy: Path, tests: tuple[str, ...], every: bool = False) -> tuple[bool, str, float]:
    """(passed, first failing test or error, seconds) of pytest -x on the copy, compiled afresh;
    every: run all the tests and name every one that fails."""
    with tempfile.TemporaryDirectory(prefix="numba-cache-") as cache:
        env = dict(os.environ, PYTHONPATH=str(copy), NUMBA_CACHE_DIR=cache, PYTHONDONTWRITEBYTECODE="1")
        imported = subprocess.run([sys.executable, "-c", "import hoseline; print(hoseline.__file__)"], cwd=copy,
                                  env=env, capture_output=True, text=True)
        if not imported.stdout.strip().startswith(str(copy)):
            raise SystemExit(f"the copy is not what gets imported: {imported.stdout.strip() or imported.stderr}")
        started = time.perf_counter()
        stop = [] if every else ["-x"]
        run = subprocess.run([sys.executable, "-m", "pytest", *stop, "-q", "-rfE", "-p", "no:cacheprovider", *tests],
                             cwd=copy, env=env, capture_output=True, text=True)
        seconds = time.perf_counter() - started
    if run.returncode == 0:
        return True, "", seconds
    found = re.findall(r"^(FAILED|ERROR) (\S+)", run.stdout, re.MULTILINE)
    if not found:
        return False, f"pytest exit {run.returncode}: {run.stdout[-300:]}", seconds
    return False, ", ".join(test + (" (error)" if kind == "ERROR" else "") for kind, test in found), seconds


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", action="append", help="run only this mutation (repeatable)")
    parser.add_argument("--list", action="store_true", help="list the mutations and exit")
    parser.add_argument("--tests", nargs="+", default=PHYSICS_TESTS, help="pytest paths or node ids to run instead")
    parser.add_argument("--every", action="store_true", help="do not stop at the first failure: name every failing test")
    args = parser.parse_args()
    chosen = [m for m in MUTATIONS if not args.only or m.name in args.only]
    if args.only and len(chosen) != len(set(args.only)):
        raise SystemExit(f"unknown mutation among {args.only}; --list shows them")
    if args.list:
        for m in chosen:
            print(f"{m.name:30} {m.path}\n    - {m.old}\n    + {m.new}\n    {m.description}")
        return 0

    with tempfile.TemporaryDirectory(prefix="hoseline-mutant-") as scratch:
        baseline = Path(scratch) / "baseline"
        _copy(baseline)
        passed, failure, seconds = _run(baseline, tuple(args.tests), args.every)
        print(f"baseline (unmutated copy, imported from {baseline}/hoseline): "
              f"{'tests pass' if passed else 'FAILS: ' + failure} ({seconds:.0f} s)", flush=True)
        if not passed:
            return 1
        rows = []
        for index, mutation in enumerate(chosen):
            copy = Path(scratch) / f"mutant-{index}"
            _copy(copy)
            if not _apply(copy, mutation):
                rows.append((mutation, "NOT APPLIED (old text not found once)", ""))
            else:
                passed, failure, seconds = _run(copy, tuple(args.tests), args.every)
                rows.append((mutation, "SURVIVED" if passed else "killed", f"{failure} ({seconds:.0f} s)" if failure
                             else f"({seconds:.0f} s)"))
            shutil.rmtree(copy)
            print(f"{mutation.name:30} {rows[-1][1]:10} {rows[-1][2]}", flush=True)

    print(f"\n| mutation | change | result | {'failing tests' if args.every else 'first failing test'} |\n| --- | --- | --- | --- |")
    for mutation, verdict, by in rows:
        print(f"| {mutation.name} | {mutation.description} ({mutation.path}) | {verdict} | {by} |")
    bad = [m.name for m, verdict, _ in rows if verdict != "killed"]
    print(f"\n{len(rows) - len(bad)} of {len(rows)} mutations killed" + (f"; not killed: {', '.join(bad)}" if bad else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
