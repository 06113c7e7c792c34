"""Obstacles fixed in the world that a placement study measures the hose's clearance to (a feature it must keep
clear of, not one it touches: the placement does not see them).

The clearance is measured as a sweep measures it at one pose (sweep.quasi_static): the nearest approach of the
hose surface and its end fittings to the obstacle's triangles (geometry.clearance.nearest_with_fittings), mm.
"""

from __future__ import annotations

import numpy as np

from hoseline.model.problem import Problem
from hoseline.model.sweep import Obstacle
from hoseline.procedures.geometry.clearance import TriangleIndex, nearest_with_fittings


class FixedObstacles:
    """Named obstacles (model.sweep.Obstacle, body None) with their triangle indexes built once."""

    def __init__(self, obstacles: tuple[Obstacle, ...]) -> None:
        for obstacle in obstacles:
            if obstacle.body is not None:
                raise ValueError(f"obstacle {obstacle.name!r}: body = {obstacle.body!r}: a placement study's obstacles "
                                 "are fixed; remove body (or study a sweep file, whose obstacles move with bodies)")
        self.obstacles = tuple(obstacles)
        self.indexes = tuple(TriangleIndex(o.vertices, o.faces) for o in obstacles)

    @property
    def names(self) -> tuple[str, ...]:
        """The obstacles' names, in order."""
        return tuple(o.name for o in self.obstacles)

    def clearance(self, problem: Problem, nodes: np.ndarray) -> np.ndarray:
        """(O, 1) mm: the least clearance of `problem`'s hose with centreline `nodes` (N+1, 3) mm and its end
        fittings to each obstacle."""
        fittings = problem.fittings
        lines = (None, None)
        if fittings is not None:
            lines = tuple(None if fitting is None else (fitting.centreline(port), fitting.radius(problem.hose.outer_diameter))
                          for fitting, port in ((fittings.start, fittings.start_port), (fittings.end, fittings.end_port)))
        return np.array([[nearest_with_fittings(index, nodes, problem.hose.outer_radius, lines).distance]
                         for index in self.indexes]).reshape(-1, 1)
