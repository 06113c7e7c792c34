"""What a sweep returns: the hose at every pose, its clearances, its health, and the worst cases.

Arrays have one row per pose (M poses) and, where per station, one column per station
(N+1 stations from the start to the end fitting).  Units: mm, N, N*mm, degrees.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hoseline.model.sweep import Obstacle, SweepProblem
from hoseline.procedures.placement.result import Result


@dataclass
class ObstacleClearance:
    """The nearest approach of the hose to one obstacle along the sweep.

    obstacle: the obstacle.  distance: (M,) mm from the hose surface (negative: cuts into it).
    s: (M,) mm along the hose where it comes nearest.  on_hose, on_obstacle: (M, 3) mm, the
    closest points (centreline and obstacle surface), world coordinates.
    """

    obstacle: Obstacle
    distance: np.ndarray
    s: np.ndarray
    on_hose: np.ndarray
    on_obstacle: np.ndarray

    @property
    def first_violation(self) -> int | None:
        """Index of the first pose closer than the required clearance, or None."""
        closer = np.nonzero(self.distance < self.obstacle.clearance)[0]
        return int(closer[0]) if closer.size else None

    @property
    def worst(self) -> int:
        """Index of the pose of least clearance."""
        return int(np.argmin(self.distance))


@dataclass
class SweepContact:
    """The contact of the hose with one obstacle of the problem's [contact] (or itself, name "self") along the sweep.

    name, kind: as in the problem ("plane", "sphere", "cylinder"; "self").  min_gap: (M,) mm, the smallest
    gap between the hose surface and the obstacle (>= 0; inf if never near).  total_force: (M, 3) N, the
    obstacle's push on the hose.  length_in_contact: (M,) mm, the length the hose lies on it (0 for a contact
    at a point; see placement/result.ObstacleContact).  points, forces: per pose, the contact points on the hose's
    centreline (k, 3) mm and the size of the push at each (k,) N (k may differ from pose to pose).
    """

    name: str
    kind: str
    min_gap: np.ndarray
    total_force: np.ndarray
    length_in_contact: np.ndarray
    points: list[np.ndarray] = field(default_factory=list)
    forces: list[np.ndarray] = field(default_factory=list)


@dataclass
class Snap:
    """A snap-through along the sweep: the hose jumped between two poses.

    pose: index of the pose reached after the jump.  jump: mm, largest movement of a
    station between the two poses.  events: what the continuation saw (where the stability
    was lost, within the step from pose - 1 to pose).
    """

    pose: int
    jump: float
    events: list[str]


@dataclass
class SweepResult:
    """The hose carried through a sweep.

    sweep: the sweep solved.  assembly: the placement at design position (twist locked).
    s: (N+1,) mm, arc length of the stations.
    centerlines: (M, N+1, 3) mm.  start_points, end_points: (M, 3) mm, the fitting tips;
    start_directions, end_directions: (M, 3) unit, from the fittings into the hose.
    bend_radius: (M, N+1) mm, to the inside of the bend.  twisting_moment: (M, N+1) N*mm.
    start_force, end_force: (M, 3) N; start_moment, end_moment: (M, 3) N*mm (reactions).
    single_plane_offset: (M,) mm, the end mount's distance from the plane of both
        directions (SAE J1273 measure); NaN where the directions are parallel.
    clearances: one per obstacle.
    free_centerlines: (M, N+1, 3) mm with the end fitting free to spin, or None.
    separation: (M,) mm, largest distance between stations of equal arc length of the
        locked and the free answers, or None.
    snaps: the snap-throughs.  events: everything the continuation logged along the sweep.
    iterations: (M,) Newton iterations to reach each pose.
    solve_seconds, clearance_seconds, wall_time: s, time in the solver (sweep only, the free
        run included), in the clearance queries, and in total.
    clip_forces, clip_moments: (M, c, 3) N and N*mm (about the clip point), each clip's load on the
        hose at each pose (c = 0 without clips).  clip_arc_lengths: (M, c) mm, where each clip holds
        the hose (it changes for a sliding clip).  station_arc_lengths: (M, N+1) mm, the arc length
        of the stations at each pose where a sliding clip stretches the spans next to it, else None
        (the stations are then at s).
    contacts: one per obstacle of the problem's [contact] (and "self" with self-contact); empty without contact.
    """

    sweep: SweepProblem
    assembly: Result
    s: np.ndarray
    centerlines: np.ndarray
    start_points: np.ndarray
    end_points: np.ndarray
    start_directions: np.ndarray
    end_directions: np.ndarray
    bend_radius: np.ndarray
    twisting_moment: np.ndarray
    start_force: np.ndarray
    start_moment: np.ndarray
    end_force: np.ndarray
    end_moment: np.ndarray
    single_plane_offset: np.ndarray
    clearances: list[ObstacleClearance]
    iterations: np.ndarray
    free_centerlines: np.ndarray | None = None
    separation: np.ndarray | None = None
    snaps: list[Snap] = field(default_factory=list)
    events: list[str] = field(default_factory=list)
    solve_seconds: float = 0.0
    clearance_seconds: float = 0.0
    wall_time: float = 0.0
    clip_forces: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 3)))
    clip_moments: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 3)))
    clip_arc_lengths: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    station_arc_lengths: np.ndarray | None = None
    contacts: list[SweepContact] = field(default_factory=list)

    @property
    def pose_count(self) -> int:
        """Number of poses M."""
        return int(self.centerlines.shape[0])

    @property
    def differential_torque(self) -> np.ndarray:
        """(M, N) N*mm: change of the twisting moment from one station to the next (Keil & Thomas'
        "differential torque between beam elements")."""
        return np.diff(self.twisting_moment, axis=1)

    @property
    def min_bend_radius(self) -> np.ndarray:
        """(M,) mm, the smallest inside bend radius at each pose."""
        return np.min(self.bend_radius, axis=1)

    @property
    def bend_radius_margin(self) -> np.ndarray | None:
        """(M,) mm, smallest bend radius less the catalogue minimum; None if the hose has no limit."""
        limit = self.sweep.problem.hose.min_bend_radius
        return None if limit is None else self.min_bend_radius - limit

    @property
    def max_twisting_moment(self) -> np.ndarray:
        """(M,) N*mm, the largest absolute twisting moment along the hose at each pose."""
        return np.max(np.abs(self.twisting_moment), axis=1)

    @property
    def max_differential_torque(self) -> np.ndarray:
        """(M,) N*mm, the largest absolute differential torque at each pose."""
        return np.max(np.abs(self.differential_torque), axis=1)

    def performance(self) -> dict:
        """Figures of the run: poses per second, Newton iterations and clearance time per pose."""
        count = self.pose_count
        return {
            "poses": count,
            "poses per second (solver)": count / self.solve_seconds if self.solve_seconds > 0 else float("inf"),
            "Newton iterations per pose": float(np.mean(self.iterations)),
            "clearance query per pose [ms]": 1e3 * self.clearance_seconds / count,
            "triangles in the obstacles": int(sum(len(c.obstacle.faces) for c in self.clearances)),
            "wall time incl. assembly [s]": self.wall_time,
        }

    def travel_label(self, index: int) -> str:
        """The pose as an engineer names it, e.g. "steer 12.5 deg" or "pose 3"."""
        stage = next(st for st in self.sweep.stages if st.first <= index < st.first + st.count)
        unit = f" {stage.unit}" if stage.unit else ""
        return f"{stage.name} {self.sweep.travel[index]:.4g}{unit}"

    def worst_cases(self) -> list[dict]:
        """One row per checked quantity: its worst value, the pose, the place along the hose.

        Keys: quantity, value, unit, pose, travel, s (mm along the hose, None for a mount
        quantity), limit (None if there is none), ok (None if there is no limit).
        """
        rows = []
        for clearance in self.clearances:
            k = clearance.worst
            required = clearance.obstacle.clearance
            rows.append(self._row(f"clearance to {clearance.obstacle.name}", clearance.distance[k], "mm", k,
                                  clearance.s[k], required, clearance.distance[k] >= required))
        k, j = np.unravel_index(np.argmin(self.bend_radius), self.bend_radius.shape)
        limit = self.sweep.problem.hose.min_bend_radius
        rows.append(self._row("bend radius (inside)", self.bend_radius[k, j], "mm", k, self.s[j], limit,
                              None if limit is None else self.bend_radius[k, j] >= limit))
        k, j = np.unravel_index(np.argmax(np.abs(self.twisting_moment)), self.twisting_moment.shape)
        rows.append(self._row("twisting moment", self.twisting_moment[k, j], "N*mm", k, self.s[j]))
        torque = self.differential_torque
        k, j = np.unravel_index(np.argmax(np.abs(torque)), torque.shape)
        rows.append(self._row("differential torque", torque[k, j], "N*mm", k, 0.5 * (self.s[j] + self.s[j + 1])))
        if np.any(np.isfinite(self.single_plane_offset)):
            k = int(np.nanargmax(np.abs(self.single_plane_offset)))
            rows.append(self._row("single-plane offset of the mounts", self.single_plane_offset[k], "mm", k))
        for name, values, unit in (
            ("start mount force", self.start_force, "N"),
            ("start mount moment", self.start_moment, "N*mm"),
            ("end mount force", self.end_force, "N"),
            ("end mount moment", self.end_moment, "N*mm"),
        ):
            magnitude = np.linalg.norm(values, axis=1)
            k = int(np.argmax(magnitude))
            rows.append(self._row(name, magnitude[k], unit, k))
        for contact in self.contacts:  # the hardest push and the closest approach of each [contact] obstacle
            what = "itself" if contact.name == "self" else contact.name
            force = np.linalg.norm(contact.total_force, axis=1)
            k = int(np.argmax(force))
            rows.append(self._row(f"contact force from {what}", force[k], "N", k))
            if np.any(np.isfinite(contact.min_gap)):
                k = int(np.argmin(contact.min_gap))
                rows.append(self._row(f"smallest contact gap to {what}", contact.min_gap[k], "mm", k))
        if self.separation is not None:
            k = int(np.argmax(self.separation))
            rows.append(self._row("separation from the free-roll answer", self.separation[k], "mm", k))
        return rows

    def _row(self, quantity, value, unit, pose, s=None, limit=None, ok=None) -> dict:
        return {
            "quantity": quantity,
            "value": float(value),
            "unit": unit,
            "pose": int(pose),
            "travel": self.travel_label(int(pose)),
            "s": None if s is None else float(s),
            "limit": None if limit is None else float(limit),
            "ok": None if ok is None else bool(ok),
        }
