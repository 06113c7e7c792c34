"""Obstacles brought in after the free placement: each moved in from a clear position, pushing the hose aside.

The published placement sequence carries a straight hose from the start mount to the end mount: a
numerical path, not the way a hose is fitted among the parts of a vehicle.  A floor, a bracket or a
strut that the straight start or that path crosses would stop it, though the installed hose rests
on it.  So the sequence runs without the obstacles (with self-contact, which no path crosses: the
straight hose is clear of itself), and then every obstacle the free equilibrium touches or enters
is brought in, one at a time in the order of the problem, by a continuation of its own
(procedures/contact/continuation.follow_contact with an ObstaclePath, as a sweep moves a body's
obstacles): the obstacle starts translated back along a direction, just clear of the hose, and is
carried along it to its true place.  Every state on the way is an equilibrium that penetrates
nothing (the move check of a sweep admits each step); the mounts and clips stay where they are.
Why translation, not growth or a shrinking barrier: a rigid move of a rigid part is what the sweep
machinery already follows and checks (moving bodies), a translation keeps every obstacle's shape
(a mesh is not remeshed, a box keeps its edges), and its one free choice, the direction, is the
side the hose ends on, which is what a user must be able to choose.

Which side.  Unless the problem names it (`hose_side`, a world direction: the side of the obstacle
the hose is to end on; the obstacle then comes in along the candidate within 45 degrees of it, or it
itself, that has the shortest way in), the side is that of least penetration: among candidate directions (a
plane: its normal; a sphere: 64 directions spread over the sphere; a cylinder: 32 directions about
its axis and the 64; a box: the 64 and its six face normals; a mesh: the 64), the one along which the
obstacle has the shortest way to come in from where it clears the hose, and whose way does not pass
through a held part of the hose (the segments at the end fittings and at clips, which cannot move
aside).  The travel along a direction is found by sphere tracing: from a position where the obstacle
clears the hose by a slab, it is stepped towards its place by the smallest gap (a step shorter than
every gap cannot reach the hose) until it touches; then it is set back by a clearance (START_CLEARANCE
hose radii).  The choice is reported per obstacle (BroughtIn, result.json summary.contact.placement).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from hoseline.mechanics.contact_motion import only
from hoseline.mechanics.contact_newton import ContactModel, solve_with_contact
from hoseline.mechanics.newton import RodProperties
from hoseline.mechanics.rod import Clamps, RodState, centerline
from hoseline.model.motion import Pose
from hoseline.model.obstacles import Box, Cylinder, Mesh, Obstacle, Plane, Sphere
from hoseline.procedures.contact.continuation import CONTACT_TOLERANCE, follow_contact, hardest_push
from hoseline.procedures.contact.moving import MovingObstacles, ObstaclePath
from hoseline.procedures.placement.continuation import ContinuationLog, PlacementError, Progress, StepControl

START_CLEARANCE = 0.1  # hose radii: how far the obstacle clears the hose where it starts coming in
SPREAD_DIRECTIONS = 64  # candidate directions spread over the sphere (a Fibonacci lattice)
AROUND_AXIS = 32  # more candidates about a cylinder's axis (perpendicular to it)
TRACE_STEPS = 2000  # of one sphere trace: a trace that has not met the hose by then (grazing it) is given up
SMALLEST_TRACE_STEP = 0.02  # hose radii: the check of a held piece's way steps at least this far
HINT_COSINE = math.cos(math.radians(45.0))  # a hose_side is met by the shortest way in within 45 degrees of it
BRING_IN = "bringing in"  # the body name of the obstacle being brought in (the others are fixed)


@dataclass(frozen=True)
class BroughtIn:
    """How one obstacle came to its place after the free placement.

    name: the obstacle's.  rule: "clear" (the free equilibrium clears it: not moved), "least penetration"
    (the side chosen) or "hose_side" (the side the problem names).  hose_side: (3,) unit world direction, the
    side of the obstacle the hose is pushed to (the obstacle moved in along it); None when clear.  travel: mm,
    how far it was moved in.  free_gap: mm, the smallest gap of the free equilibrium to it (negative: inside).
    """

    name: str
    rule: str
    hose_side: np.ndarray | None
    travel: float
    free_gap: float

    def summary(self) -> dict:
        """For result.json (mm)."""
        return {"name": self.name, "rule": self.rule,
                "hose_side": None if self.hose_side is None else self.hose_side.tolist(),
                "travel_mm": float(self.travel), "free_gap_mm": float(self.free_gap)}


def spread_directions(count: int) -> np.ndarray:
    """(count, 3) unit vectors spread evenly over the sphere (a Fibonacci lattice)."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    angle = math.pi * (1.0 + math.sqrt(5.0)) * k
    ring = np.sqrt(1.0 - z * z)
    return np.column_stack([ring * np.cos(angle), ring * np.sin(angle), z])


def mounts_frame(clamps: Clamps) -> np.ndarray:
    """(3, 3) rows: a frame carried with the mounts by a rigid motion of the problem (the start direction, the
    chord to the end mount made perpendicular to it, their cross product), so that the candidate sides, and with
    them the answer, move with the problem; the start fitting's frame where the chord is along the direction."""
    tangent = clamps.start_frame[2]
    chord = clamps.end_point - clamps.start_point
    across = chord - (chord @ tangent) * tangent
    if np.linalg.norm(across) <= 1e-9 * max(float(np.linalg.norm(chord)), 1.0):
        return clamps.start_frame
    across /= np.linalg.norm(across)
    return np.array([tangent, across, np.cross(tangent, across)])


def candidate_sides(obstacle: Obstacle, frame: np.ndarray) -> np.ndarray:
    """(k, 3) unit directions the hose may be pushed to by `obstacle` coming in along them; frame: rows, the frame
    the spread directions are laid out in (mounts_frame)."""
    if isinstance(obstacle, Plane):
        return obstacle.normal[None, :]
    spread = spread_directions(SPREAD_DIRECTIONS) @ frame
    if isinstance(obstacle, Cylinder):
        axis = (obstacle.end - obstacle.start) / np.linalg.norm(obstacle.end - obstacle.start)
        across = frame - np.outer(frame @ axis, axis)  # the frame's rows made perpendicular to the axis
        u = across[int(np.argmax(np.linalg.norm(across, axis=1)))]
        u /= np.linalg.norm(u)
        v = np.cross(axis, u)
        angles = 2.0 * math.pi * np.arange(AROUND_AXIS) / AROUND_AXIS
        return np.vstack([np.cos(angles)[:, None] * u + np.sin(angles)[:, None] * v, spread])
    if isinstance(obstacle, Box):
        return np.vstack([obstacle.axes, -obstacle.axes, spread])
    return spread


def reach_along(obstacle: Obstacle, direction: np.ndarray) -> float:
    """The largest extent (mm) of `obstacle` along `direction` (its support function); inf for a plane."""
    if isinstance(obstacle, Plane):
        return math.inf
    if isinstance(obstacle, Sphere):
        return float(obstacle.centre @ direction) + obstacle.radius
    if isinstance(obstacle, Cylinder):
        return max(float(obstacle.start @ direction), float(obstacle.end @ direction)) + obstacle.radius
    vertices = obstacle.triangles()[0] if isinstance(obstacle, (Box, Mesh)) else None
    return float(np.max(vertices @ direction))


def entry_travel(alone: ContactModel, obstacle: Obstacle, pieces: Sequence[np.ndarray], side: np.ndarray) -> float:
    """How far (mm) `obstacle` must be moved back against `side` to clear every polyline of `pieces` (mm) by
    START_CLEARANCE hose radii, coming in from beyond the slab where it clears them all; -inf if it clears them
    where it is.  alone: the contact model of this obstacle only (no self-contact).

    The obstacle moved back by s is the hose moved on by s: the hose is traced from the far slab towards its
    place by the smallest gap (sphere tracing: no step crosses the obstacle) until it touches."""
    radius = alone.hose_radius
    clearance = START_CLEARANCE * radius
    if isinstance(obstacle, Plane):  # the half-space behind the plane: only its normal brings it in
        depth = max(float(np.max((obstacle.point - piece) @ obstacle.normal)) for piece in pieces) + radius
        return depth + clearance if depth > -clearance else -math.inf
    lowest = min(float(np.min(piece @ side)) for piece in pieces)
    s = reach_along(obstacle, side) - lowest + radius + 2.0 * clearance  # beyond it: separated by a slab
    for _ in range(TRACE_STEPS):
        s = max(s, 0.0)
        gap = min(_gap(alone, piece + s * side) for piece in pieces)
        if gap < clearance:  # touched: back off by the shortfall (the gap grows by at most the move) until clear
            for _ in range(TRACE_STEPS):
                s += clearance - gap
                gap = min(_gap(alone, piece + s * side) for piece in pieces)
                if gap >= 0.5 * clearance:
                    return s
            return math.inf
        if s <= 0.0:
            return -math.inf  # at its place it clears the hose
        s -= gap - 0.5 * clearance  # >= clearance / 2: the gap stays above clearance / 2 > 0
    return math.inf


def _gap(alone: ContactModel, nodes: np.ndarray) -> float:
    """The smallest gap (mm) of the capsules of the hose radius along `nodes` (mm) to the one obstacle of `alone`."""
    return float(min(alone.smallest_gaps(nodes).values()))


def held_pieces(props: RodProperties, clamps: Clamps, nodes: np.ndarray) -> list[np.ndarray]:
    """The parts of the hose a moving obstacle cannot push aside (mm): the segments at each end fitting and at
    every clip (a clip that holds the direction: both segments at it; a ball clip: its station)."""
    pieces = [nodes[:2], nodes[-2:]]
    for clip in clamps.clips:
        k = clip.node
        pieces.append(nodes[max(k - 1, 0):k + 2] if clip.frame is not None else nodes[k:k + 1].repeat(2, axis=0))
    return pieces


@dataclass(frozen=True)
class _Entry:
    side: np.ndarray
    travel: float


def choose_entry(alone: ContactModel, obstacle: Obstacle, nodes: np.ndarray, held: Sequence[np.ndarray],
                 sides: np.ndarray) -> _Entry | None:
    """The side (of `sides`) along which `obstacle` comes in the shortest way to clear the hose `nodes` (mm) while
    its way misses every held piece; None if every way passes through one."""
    best = None
    for side in sides:
        if best is not None and _gap(alone, nodes + best.travel * side) < 0.5 * START_CLEARANCE * alone.hose_radius:
            continue  # it still touches the hose as far back as the best way starts: this way is no shorter
        travel = entry_travel(alone, obstacle, [nodes], side)
        if best is not None and travel >= best.travel:
            continue
        if _passes_through(alone, obstacle, held, side, travel):
            continue
        best = _Entry(side, travel)
    return best


def _passes_through(alone: ContactModel, obstacle: Obstacle, held: Sequence[np.ndarray], side: np.ndarray,
                    travel: float) -> bool:
    """Whether `obstacle`, moved in along `side` over `travel` mm to its place, meets a held piece on the way."""
    if not math.isfinite(travel):
        return True
    for piece in held:
        if isinstance(obstacle, Plane):  # a half-space sweeping along its normal: the piece's deepest point decides
            if float(np.max((obstacle.point - piece) @ obstacle.normal)) + alone.hose_radius > 0.0:
                return True
            continue
        s = travel
        while s > 0.0:
            gap = _gap(alone, piece + s * side)
            if gap <= 0.0:
                return True
            s -= max(gap, SMALLEST_TRACE_STEP * alone.hose_radius)
        if _gap(alone, piece) <= 0.0:
            return True
    return False


def bring_in(
    obstacles: Sequence[Obstacle],
    sides: Sequence[np.ndarray | None],
    props: RodProperties,
    clamps: Clamps,
    state: RodState,
    model: ContactModel,
    *,
    control: StepControl = StepControl(),
    log: ContinuationLog | None = None,
    progress: Progress | None = None,
) -> tuple[RodState, list[BroughtIn], float]:
    """(equilibrium, how each obstacle came in, its residual): the equilibrium under `clamps` with every obstacle of
    `model` in its place, from the free equilibrium `state` (which may pass through them; it clears itself with
    self-contact).

    obstacles: the problem's (model.names in order).  sides: per obstacle, the side the hose is to end on (a world
    direction) or None (least penetration).  Raises PlacementError naming the obstacle when a held part of the hose
    (an end fitting's or a clip's segment) is inside it, when every way in passes through a held part, or when its
    continuation cannot go on (saying where the hose is pressed hardest)."""
    h = props.segment_length
    present: list[int] = []
    choices: list[BroughtIn] = []
    self_contact = model.self_exclusion >= 0
    for j, (obstacle, hint) in enumerate(zip(obstacles, sides)):
        alone = only(model, [j], self_contact=False)
        nodes = centerline(state.frames, clamps.start_point, h)
        held = held_pieces(props, clamps, nodes)
        free_gap = _gap(alone, nodes)
        if free_gap > 2.0 * model.activation:
            choices.append(BroughtIn(obstacle.name, "clear", None, 0.0, free_gap))
            present.append(j)
            continue
        _check_held_clear(alone, obstacle, held, clamps)
        if hint is not None:
            hint = np.asarray(hint, dtype=float) / np.linalg.norm(hint)
            sides = candidate_sides(obstacle, mounts_frame(clamps))
            entry = choose_entry(alone, obstacle, nodes, held, np.vstack([hint, sides[sides @ hint >= HINT_COSINE]]))
            if entry is None:
                raise PlacementError(
                    f"placement with contact: obstacle {obstacle.name!r} brought in towards hose_side "
                    f"{np.round(hint, 4).tolist()} would pass through the hose where an end fitting or a clip holds "
                    "it: choose another hose_side for it, or leave hose_side out (the side of least penetration)")
            rule = "hose_side"
        else:
            entry = choose_entry(alone, obstacle, nodes, held, candidate_sides(obstacle, mounts_frame(clamps)))
            if entry is None:
                raise PlacementError(
                    f"placement with contact: obstacle {obstacle.name!r} cannot be brought to its place: the free "
                    "hose passes through it, and every way in passes through the hose where an end fitting or a clip "
                    "holds it. Move the obstacle or the mounts or clips, or give it a hose_side")
            rule = "least penetration"
        # Moved relative to the hose: the mounts, clips and the obstacles already in place are carried by
        # (1 - t) travel side and the entering obstacle stays (the weight is uniform, so only the relative position
        # counts, and at t = 1 all is where it belongs); a mesh coming in is then never copied and refitted per step
        path_model = only(model, present + [j], self_contact=self_contact)
        bodies = tuple(BRING_IN if k in present else None for k in range(len(model.names)))
        moving = MovingObstacles(path_model, bodies)
        travel, side = entry.travel, entry.side

        def poses(t: float, travel=travel, side=side) -> dict[str, Pose]:
            return {BRING_IN: Pose(np.eye(3), (1.0 - t) * travel * side)}

        def path(t: float, travel=travel, side=side) -> Clamps:
            return shifted(clamps, (1.0 - t) * travel * side)

        phase = f"bring in {obstacle.name!r}"
        try:
            state, _ = follow_contact(phase, path, props, state, ObstaclePath(moving, poses), control=control,
                                      log=log, progress=progress)
        except PlacementError as failure:
            raise PlacementError(
                f"{failure} (obstacle {obstacle.name!r} was being moved in {travel:.4g} mm along "
                f"{np.round(side, 4).tolist()}, the side of {rule}, after the placement without it: the hose cannot "
                "be pushed there; give it another hose_side, or move it or the mounts)") from None
        if log is not None:
            log.events.append(f"{phase}: the free hose {'enters' if free_gap < 0 else 'touches'} it (gap "
                              f"{free_gap:.4g} mm); moved in {travel:.4g} mm along {np.round(side, 4).tolist()} "
                              f"({rule}), the hose pushed to that side")
        choices.append(BroughtIn(obstacle.name, rule, side, travel, free_gap))
        present.append(j)
    state, report = solve_with_contact(props, clamps, state, model, tolerance=max(control.tolerance, CONTACT_TOLERANCE))
    if log is not None:
        log.iterations += report.iterations
    if not report.converged or report.unstable_directions != 0:
        raise PlacementError(
            f"placement with contact: the equilibrium with every obstacle in place is not a converged stable state "
            f"(residual {report.residual:.2e}, {report.unstable_directions} unstable directions)"
            + hardest_push(props, clamps, state, model))
    return state, choices, report.residual


def shifted(clamps: Clamps, move: np.ndarray) -> Clamps:
    """`clamps` translated by `move` (mm): the mounts' and the clips' points."""
    return replace(clamps, start_point=clamps.start_point + move, end_point=clamps.end_point + move,
                   clips=tuple(replace(clip, point=clip.point + move) for clip in clamps.clips))


def _check_held_clear(alone: ContactModel, obstacle: Obstacle, held: Sequence[np.ndarray], clamps: Clamps) -> None:
    """Raise PlacementError if a held piece of the hose (at an end fitting or a clip) is inside `obstacle` where it
    is: no placement keeps the hose out of it."""
    names = ["the start fitting", "the end fitting"] + [f"the clip at station {clip.node}" for clip in clamps.clips]
    for name, piece in zip(names, held):
        gap = _gap(alone, piece)
        if gap <= 0.0:
            raise PlacementError(
                f"placement with contact: the hose at {name} is held inside obstacle {obstacle.name!r} (by "
                f"{-gap:.4g} mm within the hose radius of its surface): no placement keeps the hose out of it. Move "
                "the obstacle or the mount or clip, or remove the obstacle and read its clearance")

