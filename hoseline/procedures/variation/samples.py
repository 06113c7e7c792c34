"""One sample of a study: the hose with its deviations placed (or swept) by the published sequence, and read.

A placement sample runs the whole placement from the straight hose (placement.sequence.place_only:
the same path, forks and lock angle as `hoseline solve`, without the uniqueness checks), or, with a
warm start, Newton from the nominal hose's equilibria (nominal.warm_start; the published sequence
where Newton does not reach a stable state; the first CHECKED_WARM_STARTS samples are placed both
ways and the distance between the answers recorded); a
sweep sample places the hose and carries it through the sweep (sweep.quasi_static.run_sweep,
the free-roll comparison, the assembly's uniqueness checks and its error estimate left out: a sample reads the
poses only).  A sample that fails (the hose does not reach its mounts,
the path cannot be followed, the final state is not stable: SOLVER_FAILURES) is kept with its
reason; any other exception is a fault of the program and stops the study.  failure_cause gives
the cause of a reason, its numbers left out, so that failures can be grouped by cause.

evaluate_batch runs a block of samples; it is what a Dask task runs, and its output depends
only on the context and the sample indices and deviations it is given.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace

import numpy as np

from hoseline.mechanics.clipped_newton import clip_reactions
from hoseline.mechanics.newton import RodProperties, node_positions
from hoseline.mechanics.rod import Clamps, RodState
from hoseline.model.problem import Problem
from hoseline.model.sweep import SweepProblem
from hoseline.procedures.placement.continuation import PlacementError
from hoseline.procedures.placement.hose_health import hose_health
from hoseline.procedures.placement.sequence import place_only
from hoseline.procedures.sweep.quasi_static import run_sweep
from hoseline.procedures.variation.fixed_obstacles import FixedObstacles
from hoseline.procedures.variation.nominal import NominalPlacement, nominal_placement, warm_start
from hoseline.procedures.variation.quantities import PoseReadings, Quantity, quantities, reaction_supports
from hoseline.procedures.variation.tolerances import perturbed

SHAPE_POSES = 12  # poses of a sweep whose centrelines each sample keeps, for the envelope
CHECKED_WARM_STARTS = 32  # the first samples of a warm-started study are also placed from the straight hose
# what a sample that cannot be built raises: the solver's PlacementError (no path, no stable state) and the model's
# ValueError (the deviated hose does not reach its mounts or clips, a ball clip given a direction; numpy's
# LinAlgError is one too)
SOLVER_FAILURES = (PlacementError, ValueError)
# a number in a reason, unless it is part of a name (clips[0], x2): what differs between samples failing alike
_NUMBER = re.compile(r"(?<![\w\[.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def failure_cause(reason: str) -> str:
    """The cause of a failed sample's reason: the reason with its numbers replaced by "#" (e.g. "ValueError:
    hose.length = # mm is not longer than the mount distance # mm ...")."""
    return _NUMBER.sub("#", reason)


@dataclass(frozen=True)
class StudyBase:
    """What is varied: a placement (sweep None) or a sweep of `problem`'s hose; obstacles: fixed obstacles a
    placement's clearance is measured to (a sweep's are its own)."""

    problem: Problem
    sweep: SweepProblem | None = None
    obstacles: FixedObstacles | None = None

    def __post_init__(self) -> None:
        if self.sweep is not None and self.obstacles is not None:
            raise ValueError("a sweep study measures the clearance to the sweep's own obstacles: give them there")

    @property
    def obstacle_names(self) -> tuple[str, ...]:
        """Names of the obstacles: the sweep's, or a placement's fixed ones."""
        if self.sweep is not None:
            return tuple(o.name for o in self.sweep.obstacles)
        return () if self.obstacles is None else self.obstacles.names

    @property
    def quantities(self) -> tuple[Quantity, ...]:
        """The judged quantities, in the order the samples store them (quantities.quantities)."""
        return quantities(self.obstacle_names, *reaction_supports(tuple(c.holds_direction for c in self.problem.clips)))

    @property
    def pose_count(self) -> int:
        """Poses per sample (1 for a placement)."""
        return 1 if self.sweep is None else self.sweep.pose_count

    def read(self, problem: Problem) -> tuple[PoseReadings, int]:
        """The readings of `problem`'s hose in this setting, and the number of snap-throughs on the way.

        Raises PlacementError or ValueError when it cannot be placed or swept.
        """
        if self.sweep is None:
            props, clamps, state, _ = place_only(problem)
            return placement_readings(problem, props, clamps, state, self.obstacles), 0
        result = run_sweep(replace(self.sweep, problem=problem, compare_free_roll=False), judge_assembly=False)
        framed = [k for k, clip in enumerate(problem.clips) if clip.holds_direction]
        readings = PoseReadings(
            centerlines=result.centerlines,
            bend_radius=result.bend_radius,
            twisting_moment=result.twisting_moment,
            end_moment=result.end_moment,
            end_direction=result.end_directions,
            clearance=np.array([c.distance for c in result.clearances]).reshape(-1, result.pose_count),
            torsional_stiffness=problem.hose.torsional_stiffness,
            forces=np.linalg.norm(np.concatenate([result.start_force[:, None], result.end_force[:, None],
                                                  result.clip_forces], axis=1), axis=2),
            moments=np.linalg.norm(np.concatenate([result.start_moment[:, None], result.end_moment[:, None],
                                                   result.clip_moments[:, framed]], axis=1), axis=2),
        )
        return readings, len(result.snaps)

    def shape_poses(self) -> np.ndarray:
        """Indexes of the poses whose centrelines samples keep: all of a placement, SHAPE_POSES spread over a sweep."""
        count = self.pose_count
        return np.unique(np.linspace(0, count - 1, min(count, SHAPE_POSES)).round().astype(int))


def placement_readings(problem: Problem, props: RodProperties, clamps: Clamps, state: RodState,
                       obstacles: FixedObstacles | None = None) -> PoseReadings:
    """The readings of one equilibrium `state` of `problem`'s hose under `clamps` (one pose), with the clearance to
    `obstacles` (none when None)."""
    health = hose_health(props, clamps, state, problem.hose.outer_radius)
    nodes = node_positions(props, clamps, state)
    forces, moments = [health.start_force, health.end_force], [health.start_moment, health.end_moment]
    if clamps.clips:
        clip_forces, clip_moments = clip_reactions(props, clamps, state)
        forces.extend(clip_forces)
        moments.extend(m for m, clip in zip(clip_moments, problem.clips) if clip.holds_direction)
    return PoseReadings(
        centerlines=nodes[None],
        bend_radius=health.bend_radius[None],
        twisting_moment=health.twisting_moment[None],
        end_moment=health.end_moment[None],
        end_direction=-clamps.end_frame[2][None],
        clearance=np.zeros((0, 1)) if obstacles is None else obstacles.clearance(problem, nodes),
        torsional_stiffness=problem.hose.torsional_stiffness,
        forces=np.linalg.norm(forces, axis=1)[None],
        moments=np.linalg.norm(moments, axis=1)[None],
    )


@dataclass(frozen=True)
class StudyContext:
    """What every task needs: the base, the nominal hose's centrelines (M, N+1, 3) mm, and for a warm start
    (placements only) the nominal placement's equilibria."""

    base: StudyBase
    nominal: np.ndarray
    warm: NominalPlacement | None = None


def nominal_context(base: StudyBase, warm: bool = False) -> tuple[StudyContext, PoseReadings]:
    """The context of a study and the nominal hose's readings (raises when the nominal hose cannot be solved).

    warm: start every placement sample by Newton from the nominal equilibria (ignored for sweeps).
    """
    if warm and base.sweep is None:
        placed = nominal_placement(base.problem)
        readings = placement_readings(base.problem, placed.props, placed.final, placed.state, base.obstacles)
        return StudyContext(base, readings.centerlines, placed), readings
    readings, _ = base.read(base.problem)
    return StudyContext(base, readings.centerlines), readings


def _read(context: StudyContext, index: int, deviation: np.ndarray) -> tuple[PoseReadings, int, bool, float]:
    """(readings, snap-throughs, warm-started, distance from the published sequence's answer: NaN unless checked)."""
    base = context.base
    problem = perturbed(base.problem, deviation)
    started = None if context.warm is None else warm_start(context.warm, deviation)
    if started is None:
        readings, snaps = base.read(problem)
        return readings, snaps, False, np.nan
    readings = placement_readings(*started, base.obstacles)
    if index >= CHECKED_WARM_STARTS:
        return readings, 0, True, np.nan
    published, _ = base.read(problem)
    return readings, 0, True, float(np.max(np.linalg.norm(published.centerlines - readings.centerlines, axis=2)))


def evaluate_batch(context: StudyContext, indices: np.ndarray, coordinates: np.ndarray) -> dict[str, np.ndarray]:
    """Solve and read the samples `indices` with the deviations `coordinates` (b, width) from the base problem.

    Raises what is not one of SOLVER_FAILURES (a fault of the program, not of the sample).
    Returns arrays with one row per sample: index, failed (bool), reason (text, "" when solved),
    snaps (snap-throughs along a sweep), warm (started by Newton from the nominal hose), branch_distance
    (mm from the published sequence's answer, for the first CHECKED_WARM_STARTS warm-started samples;
    NaN otherwise), values (b, quantities; NaN when failed), station_deviation (b, N+1), shapes
    (b, P, N+1, 3) at base.shape_poses(), and per pose: clearance (b, O, M), pose_bend_radius and
    pose_end_torque (b, M).
    """
    base = context.base
    count = len(indices)
    stations = base.problem.hose.segments + 1
    poses = base.pose_count
    keep = base.shape_poses()
    out = {
        "index": np.asarray(indices, dtype=np.int64),
        "failed": np.zeros(count, dtype=bool),
        "reason": np.full(count, "", dtype=object),
        "snaps": np.zeros(count, dtype=np.int64),
        "warm": np.zeros(count, dtype=bool),
        "branch_distance": np.full(count, np.nan),
        "values": np.full((count, len(base.quantities)), np.nan),
        "station_deviation": np.full((count, stations), np.nan),
        "shapes": np.full((count, len(keep), stations, 3), np.nan),
        "clearance": np.full((count, len(base.obstacle_names), poses), np.nan),
        "pose_bend_radius": np.full((count, poses), np.nan),
        "pose_end_torque": np.full((count, poses), np.nan),
    }
    for row in range(count):
        try:
            readings, snaps, out["warm"][row], out["branch_distance"][row] = _read(context, int(indices[row]),
                                                                                  coordinates[row])
        except SOLVER_FAILURES as exc:  # a hose that cannot be built: recorded with its reason, none is dropped
            out["failed"][row] = True
            out["reason"][row] = f"{type(exc).__name__}: {exc}"
            continue
        per_pose = readings.per_pose()
        out["snaps"][row] = snaps
        out["values"][row] = readings.values(context.nominal)
        out["station_deviation"][row] = readings.station_deviation(context.nominal)
        out["shapes"][row] = readings.centerlines[keep]
        out["clearance"][row] = readings.clearance
        out["pose_bend_radius"][row] = per_pose["bend_radius"]
        out["pose_end_torque"][row] = per_pose["end_torque"]
    out["reason"] = out["reason"].astype(str)
    return out
