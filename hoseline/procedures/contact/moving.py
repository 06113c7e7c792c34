"""Contact obstacles on moving bodies: their model at the bodies' poses, and a safe start for each solve.

A sweep's contact obstacles are fixed or move rigidly with a body (SweepProblem.contact_bodies).
At each pose of the bodies the contact Newton uses the obstacles moved there
(mechanics/contact_motion.moved_model, always from the design position).  Before each solve the
move from the last equilibrium is checked (mechanics/contact_motion.move_is_clear), body by body:
the obstacles of one body are one rigid group, the fixed ones (with self-contact) another; a start
is taken only if no group could have passed through the hose on the way there.  The candidates are
a prediction (the secant of the last two equilibria: a hose pushed along by an obstacle moves with
it, so the obstacle finds it where it is going) and the last equilibrium itself.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from hoseline.mechanics.contact_motion import move_is_clear, moved_model, only
from hoseline.mechanics.contact_newton import ContactModel
from hoseline.mechanics.newton import RodProperties
from hoseline.mechanics.rod import Clamps, RodState
from hoseline.model.motion import Pose


@dataclass(frozen=True)
class PlacedObstacles:
    """The contact obstacles with their bodies at some poses.

    model: what the contact Newton uses there.  poses: the pose (from design position) of each body
    an obstacle moves with.
    """

    model: ContactModel
    poses: Mapping[str, Pose]


@dataclass(frozen=True)
class MovingObstacles:
    """The contact obstacles of a sweep, each fixed or moving with a body.

    design: their ContactModel at design position (and self-contact; procedures/contact/placement.
    problem_contact_model).  bodies: the body each obstacle (design.names) moves with, None if fixed.
    """

    design: ContactModel
    bodies: tuple[str | None, ...]

    def at(self, poses: Mapping[str, Pose]) -> PlacedObstacles:
        """The obstacles with each body at poses[body] (from design position)."""
        used = {body: poses[body] for body in self.bodies if body is not None}
        return PlacedObstacles(moved_model(self.design, [None if body is None else used[body] for body in self.bodies]),
                               used)

    def start(self, props: RodProperties, before: tuple[Clamps, RodState, PlacedObstacles], clamps: Clamps,
              placed: PlacedObstacles, candidates: Sequence[RodState]) -> RodState | None:
        """The first of `candidates` (states under `clamps` with the obstacles `placed`) the hose can be carried to
        from the equilibrium `before` (clamps, state, obstacles) without crossing an obstacle; None if none."""
        for candidate in candidates:
            if self.move_is_clear(props, before, (clamps, candidate, placed)):
                return candidate
        return None

    def move_is_clear(self, props: RodProperties, before: tuple[Clamps, RodState, PlacedObstacles],
                      after: tuple[Clamps, RodState, PlacedObstacles]) -> bool:
        """Whether the hose and the obstacles can go from `before` to `after` (each: clamps, state, obstacles)
        without the hose crossing one: each body's obstacles as one rigid group, the fixed ones with self-contact."""
        (clamps_before, state_before, placed_before), (clamps_after, state_after, placed_after) = before, after
        self_contact = self.design.self_exclusion >= 0
        for body in dict.fromkeys((None, *self.bodies)):
            obstacles = [j for j, owner in enumerate(self.bodies) if owner == body]
            if not obstacles and not (body is None and self_contact):
                continue
            carry = None if body is None else placed_before.poses[body].inverse().then(placed_after.poses[body])
            group = only(placed_before.model, obstacles, self_contact=body is None)
            if not move_is_clear(props, (clamps_before, state_before), (clamps_after, state_after), group, carry):
                return False
        return True


@dataclass(frozen=True)
class ObstaclePath:
    """Contact obstacles moving along a continuation path: `obstacles` with their bodies at poses(t) at fraction t."""

    obstacles: MovingObstacles
    poses: Callable[[float], Mapping[str, Pose]]

    def at(self, t: float) -> PlacedObstacles:
        """The obstacles at fraction t of the path."""
        return self.obstacles.at(self.poses(t))
