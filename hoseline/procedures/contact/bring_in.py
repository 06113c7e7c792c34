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
through a held point of the hose (the stations at the end fittings and at clips, which cannot move
aside).  The travel along a direction is found by sphere tracing: from a position where the obstacle
clears the hose by a slab, it is stepped towards its place by the smallest gap less half a clearance
(START_CLEARANCE hose radii; such a step cannot reach the hose) until the gap falls below the clearance, then
backed off by the shortfall until it clears the hose by at least half the clearance.  A way along which the
hose cannot be pushed (a span too short to pass round the obstacle, a pinch) is given up for the next side at
least 45 degrees from it (MOST_WAYS in all).  The choice is reported per obstacle (BroughtIn, result.json
summary.contact.placement).
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
from hoseline.model.obstacles import Box, Cylinder, Obstacle, Plane, Sphere
from hoseline.model.problem import Problem
from hoseline.procedures.contact.continuation import CONTACT_TOLERANCE, follow_contact, hardest_push
from hoseline.procedures.contact.moving import MovingObstacles, ObstaclePath
from hoseline.procedures.placement.continuation import ContinuationLog, PlacementError, Progress, StepControl

START_CLEARANCE = 0.1  # hose radii: how far the obstacle clears the hose where it starts coming in
SPREAD_DIRECTIONS = 64  # candidate directions spread over the sphere (a Fibonacci lattice)
AROUND_AXIS = 32  # more candidates about a cylinder's axis (perpendicular to it)
TRACE_STEPS = 2000  # of one sphere trace: a trace that has not met the hose by then (grazing it) is given up
SMALLEST_TRACE_STEP = 0.02  # hose radii: the check of a held piece's way steps at least this far
HELD_STUB = 1e-3  # hose radii: a held point is measured as a stub this long along the hose (the gaps need a segment)
HINT_COSINE = math.cos(math.radians(45.0))  # a hose_side is met by the shortest way in within 45 degrees of it
MOST_WAYS = 4  # ways in tried per obstacle (each at least 45 degrees from the ways that failed) before it is refused
BRING_IN = "bringing in"  # the body name of the obstacle being brought in (the others are fixed)


@dataclass(frozen=True)
class BroughtIn:
    """How one obstacle came to its place after the free placement.

    name: the obstacle's.  rule: "clear" (the free equilibrium clears it: not moved), "least penetration"
    (the side chosen) or "hose_side" (the side the problem names).  hose_side: (3,) unit world direction, the
    side of the obstacle the hose is pushed to (the obstacle moved in along it); None when clear.  travel: mm,
    how far it was moved in.  free_gap: mm, the smallest gap of the free equilibrium to it (negative: inside).
    ways_failed: the shorter ways in (sides at least 45 degrees apart) along which the hose could not be pushed and
    that were given up for this one (a hose too short to pass round the obstacle that way, or pinched).
    """

    name: str
    rule: str
    hose_side: np.ndarray | None
    travel: float
    free_gap: float
    ways_failed: int = 0

    def summary(self) -> dict:
        """For result.json (mm)."""
        return {"name": self.name, "rule": self.rule,
                "hose_side": None if self.hose_side is None else self.hose_side.tolist(),
                "travel_mm": float(self.travel), "free_gap_mm": float(self.free_gap), "ways_failed": self.ways_failed}


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
    return float(np.max(obstacle.triangles()[0] @ direction))  # a box or a mesh: its corners


def entry_travel(alone: ContactModel, obstacle: Obstacle, pieces: Sequence[np.ndarray], side: np.ndarray,
                 clearance: float | None = None) -> float:
    """How far (mm) `obstacle` must be moved back against `side` to clear every polyline of `pieces` (mm) by
    `clearance` (mm; None: START_CLEARANCE hose radii), coming in from beyond the slab where it clears them all; -inf
    if it clears them where it is.  alone: the contact model of this obstacle only (no self-contact).

    The obstacle moved back by s is the hose moved on by s: the hose is traced from the far slab towards its
    place by the smallest gap (sphere tracing: no step crosses the obstacle) until it touches."""
    radius = alone.hose_radius
    clearance = START_CLEARANCE * radius if clearance is None else clearance
    if isinstance(obstacle, Plane):  # the half-space behind the plane: only its normal brings it in
        depth = max(float(np.max((obstacle.point - piece) @ obstacle.normal)) for piece in pieces) + radius
        return depth + clearance if depth > -clearance else -math.inf
    lowest = min(float(np.min(piece @ side)) for piece in pieces)
    s = reach_along(obstacle, side) - lowest + radius + 2.0 * clearance  # beyond it: separated by a slab
    for _ in range(TRACE_STEPS):
        s = max(s, 0.0)
        gap = min(_gap(alone, piece + s * side, beyond=clearance) for piece in pieces)  # (a bound, where far)
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


def _gap(alone: ContactModel, nodes: np.ndarray, within: float = math.inf, beyond: float = math.inf) -> float:
    """The smallest gap (mm) of the capsules of the hose radius along `nodes` (mm) to the one obstacle of `alone`;
    for a mesh farther than `within` mm inf (whether the hose is that near, not how far it is), and for one bounded
    below by at least `beyond` mm that bound (a step of a sphere trace by it is safe; MeshArrays.smallest_gaps).

    The first node is counted against planes too (the solver's station-plane pairs leave out station 0, the clamped
    start point)."""
    first = (nodes[0] - alone.planes[:, :3]) @ alone.planes[:, 3:].T if alone.planes.size else np.zeros((0, 0))
    gaps = alone.smallest_gaps(nodes, within, beyond).values()
    return float(min([*gaps, *(np.diagonal(first) - alone.hose_radius)]))


def held_pieces(clamps: Clamps, radius: float) -> list[np.ndarray]:
    """The points of the hose a moving obstacle cannot push aside, each as a stub of HELD_STUB along the hose (mm):
    the end fittings' and the clips' (the segments next to them turn about the joints there, so they are not held)."""
    held = [(clamps.start_point, clamps.start_frame[2]), (clamps.end_point, clamps.end_frame[2])]
    held += [(clip.point, np.eye(3)[2] if clip.frame is None else clip.frame[2]) for clip in clamps.clips]
    return [np.array([point, point + HELD_STUB * radius * tangent]) for point, tangent in held]


@dataclass(frozen=True)
class _Entry:
    side: np.ndarray
    travel: float


def choose_entry(alone: ContactModel, obstacle: Obstacle, nodes: np.ndarray, held: Sequence[np.ndarray],
                 sides: np.ndarray, avoid: Sequence[np.ndarray] = (), clearance: float | None = None) -> _Entry | None:
    """The side (of `sides`) along which `obstacle` comes in the shortest way to clear the hose `nodes` (mm) by
    `clearance` (as entry_travel) while its way misses every held piece, leaving out the sides within 45 degrees of
    those in `avoid` (ways that failed); None if there is none."""
    clearance = START_CLEARANCE * alone.hose_radius if clearance is None else clearance
    best = None
    ordered = sides[np.argsort(-(sides @ _likely_side(obstacle, nodes, alone.hose_radius)), kind="stable")]
    for side in ordered:
        if any(side @ other >= HINT_COSINE for other in avoid):
            continue
        near = 0.5 * clearance
        if best is not None and _gap(alone, nodes + best.travel * side, near) < near:
            continue  # it still touches the hose as far back as the best way starts: this way is no shorter
        travel = entry_travel(alone, obstacle, [nodes], side, clearance)
        if best is not None and travel >= best.travel:
            continue
        if _passes_through(alone, obstacle, held, side, travel):
            continue
        best = _Entry(side, travel)
    return best


def _likely_side(obstacle: Obstacle, nodes: np.ndarray, radius: float) -> np.ndarray:
    """A guess of the side of least penetration, to try first (then most other sides are ruled out by one gap each):
    from the obstacle's middle to the middle of the stations (mm) within its bounding box widened by `radius`."""
    if isinstance(obstacle, Plane):
        return obstacle.normal
    if isinstance(obstacle, Sphere):
        corners = np.array([obstacle.centre - obstacle.radius, obstacle.centre + obstacle.radius])
    elif isinstance(obstacle, Cylinder):
        ends = np.array([obstacle.start, obstacle.end])
        corners = np.array([ends.min(axis=0) - obstacle.radius, ends.max(axis=0) + obstacle.radius])
    else:
        vertices = obstacle.triangles()[0]
        corners = np.array([vertices.min(axis=0), vertices.max(axis=0)])
    near = np.all((nodes >= corners[0] - radius) & (nodes <= corners[1] + radius), axis=1)
    towards = (nodes[near] if np.any(near) else nodes).mean(axis=0) - corners.mean(axis=0)
    length = float(np.linalg.norm(towards))
    return towards / length if length > 0.0 else np.zeros(3)


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
    clearance: float | None = None,
) -> tuple[RodState, list[BroughtIn], float]:
    """(equilibrium, how each obstacle came in, its residual): the equilibrium under `clamps` with every obstacle of
    `model` in its place, from the free equilibrium `state` (which may pass through them; it clears itself with
    self-contact).

    obstacles: the problem's (model.names in order).  sides: per obstacle, the side the hose is to end on (a world
    direction) or None (least penetration).  Raises PlacementError naming the obstacle when a held part of the hose
    (an end fitting's or a clip's station) is inside it, when every way in passes through a held part, or when its
    continuation cannot go on (saying where the hose is pressed hardest).
    clearance: mm, how far each obstacle clears the hose where it starts coming in (None: START_CLEARANCE hose
    radii; the force refinement's hose, which enters by a fraction of a millimetre, starts nearer)."""
    h = props.segment_length
    present: list[int] = []
    choices: list[BroughtIn] = []
    for j, (obstacle, hint) in enumerate(zip(obstacles, sides)):
        alone = only(model, [j], self_contact=False)
        nodes = centerline(state.frames, clamps.start_point, h)
        held = held_pieces(clamps, model.hose_radius)
        free_gap = _gap(alone, nodes)
        if free_gap > 2.0 * model.activation:
            choices.append(BroughtIn(obstacle.name, "clear", None, 0.0, free_gap))
            present.append(j)
            continue
        _check_held_clear(alone, obstacle, held, clamps)
        sides_of = candidate_sides(obstacle, mounts_frame(clamps))
        rule = "least penetration" if hint is None else "hose_side"
        if hint is not None:
            hint = np.asarray(hint, dtype=float) / np.linalg.norm(hint)
            sides_of = np.vstack([hint, sides_of[sides_of @ hint >= HINT_COSINE]])
        failed: list[tuple[np.ndarray, str]] = []  # (side, why) of ways in that the hose could not be pushed along
        while len(failed) < MOST_WAYS:
            entry = choose_entry(alone, obstacle, nodes, held, sides_of, [side for side, _ in failed], clearance)
            if entry is None:
                break
            try:
                state = _carried_in(j, present, entry, props, clamps, state, model, control, log, progress)
                break
            except PlacementError as failure:
                failed.append((entry.side, str(failure)))
                if log is not None:
                    log.events.append(f"bring in {obstacle.name!r}: along {np.round(entry.side, 4).tolist()} "
                                      f"({entry.travel:.4g} mm) the hose could not be pushed ({failure}); another "
                                      "side is tried")
        else:
            entry = None
        if entry is None:
            raise PlacementError(_no_way_in(obstacle.name, hint, failed))
        side, travel = entry.side, entry.travel
        phase = f"bring in {obstacle.name!r}"
        if log is not None:
            log.events.append(f"{phase}: the free hose {'enters' if free_gap < 0 else 'touches'} it (gap "
                              f"{free_gap:.4g} mm); moved in {travel:.4g} mm along {np.round(side, 4).tolist()} "
                              f"({rule}), the hose pushed to that side")
        choices.append(BroughtIn(obstacle.name, rule, side, travel, free_gap, len(failed)))
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


def _carried_in(j: int, present: list[int], entry: _Entry, props: RodProperties, clamps: Clamps, state: RodState,
                model: ContactModel, control: StepControl, log: ContinuationLog | None,
                progress: Progress | None) -> RodState:
    """The equilibrium with obstacle j of `model` moved in along entry.side over entry.travel mm to its place (the
    obstacles of index in `present` in place), from `state`; raises PlacementError where the path cannot go on.

    Moved relative to the hose: the mounts, clips and the obstacles already in place are carried by (1 - t) travel
    side and the entering obstacle stays (the weight is uniform, so only the relative position counts, and at t = 1
    all is where it belongs); a mesh coming in is then never copied and refitted per step."""
    path_model = only(model, present + [j], self_contact=model.self_exclusion >= 0)
    moving = MovingObstacles(path_model, tuple(BRING_IN if k in present else None for k in range(len(model.names))))
    move = entry.travel * entry.side

    def poses(t: float) -> dict[str, Pose]:
        return {BRING_IN: Pose(np.eye(3), (1.0 - t) * move)}

    def path(t: float) -> Clamps:
        return shifted(clamps, (1.0 - t) * move)

    state, _ = follow_contact(f"bring in {model.names[j]!r}", path, props, state, ObstaclePath(moving, poses),
                              control=control, log=log, progress=progress)
    return state


def _no_way_in(name: str, hint: np.ndarray | None, failed: Sequence[tuple[np.ndarray, str]]) -> str:
    """The message of an obstacle that no way in brings to its place: why each way tried failed, and what to do."""
    towards = "" if hint is None else f" towards hose_side {np.round(hint, 4).tolist()}"
    if not failed:
        return (f"placement with contact: obstacle {name!r} cannot be brought to its place{towards}: the free hose "
                "passes through it, and every way in passes through the hose where an end fitting or a clip holds it. "
                + ("Choose another hose_side, or leave it out (the side of least penetration)" if hint is not None else
                   "Move the obstacle or the mounts or clips, or give it a hose_side"))
    tried = "; ".join(f"along {np.round(side, 3).tolist()}: {_first_clause(why)}" for side, why in failed)
    return (f"placement with contact: obstacle {name!r} cannot be brought to its place{towards}: the free hose passes "
            f"through it, and the hose could not be pushed aside on any of {len(failed)} ways in ({tried}). The hose may "
            "be too short to pass round it, or be pinched against another obstacle or itself: "
            + ("choose another hose_side, or " if hint is not None else "give it a hose_side, ")
            + "move it or the mounts, or give the hose more length")


def _first_clause(message: str) -> str:
    """A path failure's message up to where it says where the hose is pressed (the part that differs by way)."""
    return message.split(". Where the path last reached")[0].split(" (the contact Newton")[0]


def shifted(clamps: Clamps, move: np.ndarray) -> Clamps:
    """`clamps` translated by `move` (mm): the mounts' and the clips' points."""
    return replace(clamps, start_point=clamps.start_point + move, end_point=clamps.end_point + move,
                   clips=tuple(replace(clip, point=clip.point + move) for clip in clamps.clips))


def _check_held_clear(alone: ContactModel, obstacle: Obstacle, held: Sequence[np.ndarray], clamps: Clamps) -> None:
    """Raise PlacementError if a held piece of the hose (at an end fitting or a clip) is inside `obstacle` where it
    is: no placement keeps the hose out of it."""
    names = ["the start fitting", "the end fitting"] + [f"the clip at station {clip.node}" for clip in clamps.clips]
    inside = held_inside(alone, obstacle.name, held, names)
    if inside is not None:
        raise PlacementError(f"placement with contact: {inside}")


def held_inside(alone: ContactModel, name: str, held: Sequence[np.ndarray], names: Sequence[str]) -> str | None:
    """What is held inside the obstacle `name` (the one of `alone`), for a message: the first of the held pieces
    (mm, named by `names`) within the hose radius of it; None if none is."""
    for what, piece in zip(names, held):
        gap = _gap(alone, piece)
        if gap <= 0.0:
            return (f"the hose at {what} is held inside obstacle {name!r} (by {-gap:.4g} mm within the hose radius "
                    "of its surface): no placement keeps the hose out of it. Move the obstacle or the mount or clip, "
                    "or remove the obstacle and read its clearance")
    return None


def mounts_inside(problem: Problem) -> str | None:
    """Where a mount or clip point of `problem` lies within the hose radius of an obstacle (as held_inside says
    it), for the problem file's check before any solve; None if every one is clear."""
    from hoseline.procedures.contact.placement import problem_contact_model  # its model, as the solve builds it

    if not problem.contact:
        return None
    model = problem_contact_model(problem)
    stub = HELD_STUB * model.hose_radius
    held = [(problem.start.point, problem.start.direction, "the start fitting"),
            (problem.end.point, -problem.end.direction, "the end fitting")]
    held += [(clip.point, np.eye(3)[2] if clip.direction is None else clip.direction,
              f"clip {clip.name or k + 1!r} (clips[{k}])") for k, clip in enumerate(problem.clips)]
    pieces = [np.array([point, point + stub * tangent]) for point, tangent, _ in held]
    for j, obstacle in enumerate(problem.contact):
        inside = held_inside(only(model, [j], self_contact=False), obstacle.name, pieces, [name for *_, name in held])
        if inside is not None:
            return inside
    return None
