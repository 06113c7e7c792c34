"""What a placement returns: the equilibrium shape and everything an engineer reads off it.

All quantities in user units: mm, N, N*mm, N*mm (= mJ) for energy, degrees for angles.
Station arrays have one row per node s_i = i * L / N, i = 0..N (node 0 at the start
fitting tip, node N at the end fitting tip); frame arrays have one row per segment,
at the segment midpoints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from hoseline.model.problem import Problem
from hoseline.procedures.placement.orientation import orientation_angle_deg

if TYPE_CHECKING:
    from hoseline.procedures.placement.force_accuracy import ForceRefinement


@dataclass(frozen=True)
class OtherEquilibrium:
    """Another stable equilibrium at the same mounts, length and twist as a Result.

    origin: where it comes from (a fork of the placement path, the mounts' symmetry).
    max_distance: largest distance between corresponding stations of the two shapes, mm.
    energy_gap: its energy minus the Result's, N*mm (0: an equally likely shape).
    lock_angle_deg: the lock angle on its way, degrees.
    same_clamps: True when its end fitting is clamped exactly as the Result's (a second shape
        of one physical assembly); False when its lock angle differs, so the fitting is clocked
        differently at the same twist.
    """

    origin: str
    max_distance: float
    energy_gap: float
    lock_angle_deg: float
    same_clamps: bool

    def describe(self) -> str:
        """One sentence for reports."""
        clamps = ("the same clamping" if self.same_clamps
                  else f"the end fitting locked at {self.lock_angle_deg:.2f} deg, so clocked differently")
        return (f"another stable shape up to {self.max_distance:.3f} mm away, {self.energy_gap:+.4g} N*mm of energy, "
                f"with {clamps}: {self.origin}")

    def summary(self) -> dict:
        """For result.json (user units)."""
        return {"origin": self.origin, "max_distance_mm": self.max_distance, "energy_gap_Nmm": self.energy_gap,
                "lock_angle_deg": self.lock_angle_deg, "same_clamps": self.same_clamps}


@dataclass(frozen=True)
class ClipReaction:
    """What one clip does to the hose: kind and name (as in the problem), arc_length (mm from the
    start fitting), point (3,) mm, force (3,) N and moment (3,) N*mm about the clip point, both the
    clip's on the hose (world axes).  A rotating or sliding clip's moment has no component along
    its axis (the hose rolls freely in it); a ball clip carries a force only.  A sliding clip's
    arc_length is the one the solve found.  frame: (3, 3) the clip frame as it holds the hose
    (rows d1, d2, d3 in world components; d3 along the hose, the roll found included), None for a
    ball clip.  locked_roll_deg: a fixed clip's roll at which the placement holds it (the torque-free roll it
    locked it at, plus the clip's twist), degrees (right-handed about the clip direction, from the clip frame the
    place phase carries the start fitting's frame to: see placement/path.PlacementPath); None for the other kinds."""

    kind: str
    name: str
    arc_length: float
    point: np.ndarray
    force: np.ndarray
    moment: np.ndarray
    frame: np.ndarray | None = None
    locked_roll_deg: float | None = None

    @property
    def axial_torque(self) -> float:
        """The clip's moment on the hose about the hose tangent through the clip (the frame's d3), N*mm;
        zero (to round-off) for a rotating or sliding clip, in which the hose rolls freely, and for a ball clip."""
        return 0.0 if self.frame is None else float(self.moment @ self.frame[2])

    def summary(self) -> dict:
        """For result.json (user units)."""
        return {"type": self.kind, "name": self.name, "arc_length_mm": self.arc_length, "point_mm": self.point.tolist(),
                "force_N": self.force.tolist(), "moment_Nmm": self.moment.tolist(),
                "axial_torque_Nmm": self.axial_torque, "locked_roll_deg": self.locked_roll_deg,
                "frame": None if self.frame is None else self.frame.tolist()}


@dataclass(frozen=True)
class Touchdown:
    """A concentrated push of an obstacle on the hose: at a touch-down (lift-off) point, where the hose
    starts or stops lying on it, or the whole push of a contact too short to lie (a point contact).
    arc_length: mm from the start fitting.  point: (3,) mm on the centreline.  force: (3,) N, on the hose."""

    arc_length: float
    point: np.ndarray
    force: np.ndarray

    def summary(self) -> dict:
        """For result.json (user units)."""
        return {"arc_length_mm": self.arc_length, "point_mm": self.point.tolist(), "force_N": self.force.tolist()}


@dataclass(frozen=True)
class CarriedArc:
    """An arc on which the hose lies on an obstacle: from `start` to `end`, mm of arc length; the obstacle
    pushes the distributed force `distributed_force` (3,) N over it (in all, between its touch-downs)."""

    start: float
    end: float
    distributed_force: np.ndarray

    @property
    def length(self) -> float:
        """mm."""
        return self.end - self.start

    def summary(self) -> dict:
        """For result.json (user units)."""
        return {"start_mm": self.start, "end_mm": self.end, "length_mm": self.length,
                "distributed_force_N": self.distributed_force.tolist()}


def uniqueness_word(unique: bool | None) -> str:
    """"yes", "no" or "not checked" for Result.unique."""
    return "not checked" if unique is None else ("yes" if unique else "no")


@dataclass(frozen=True)
class ObstacleContact:
    """Where and how hard the hose presses on one obstacle (or on itself, name "self") at equilibrium.

    name, kind: as in the problem ("plane", "sphere", "cylinder", "box", "mesh"; "self" for self-contact).
    min_gap: smallest gap between the assembly's surface (the hose and its end fittings) and the obstacle, mm
    (>= 0 for the hose, which is kept out; negative where a rigid end fitting enters it; inf if never near; nan if not
    evaluated, as in the studio's result during a drag: contact/placement.with_contact, gaps=False);
    min_gap_on: where it is, "hose", "start fitting" or "end fitting"; min_gap_arc_length: mm along the assembly
    from the start outlet, at the middle of the nearest segment (negative on the start fitting, beyond the hose
    length on the end fitting; nan if not located, as in a sweep's pose reports, which give the hose's gap).
    The barrier's pairs, one row per pair with a gap below the barrier's activation distance d_hat (the
    barrier's reach, which spreads a touch-down's point force over the stations next to it, see
    docs/model.md Contact): arc_length (k,) mm of the hose point from the start fitting; point (k, 3) mm on
    the hose's centreline; surface_point (k, 3) mm on the obstacle's surface; gap (k,) mm; force (k, 3) N,
    the obstacle's push on the hose (for self-contact, on the first pass: the second gets its opposite).
    total_force: (3,) N, the sum.
    Where the force is carried (procedures/contact/extent.py): carried, the arcs the hose lies on it
    (CarriedArc: ends, distributed force); touchdowns, the point forces at their ends and those of point
    contacts (Touchdown: arc length, point, force); the distributed and the point forces sum to total_force.
    length_in_contact: mm, the length of the carried arcs (0 for point contacts only).
    """

    name: str
    kind: str
    min_gap: float
    arc_length: np.ndarray
    point: np.ndarray
    surface_point: np.ndarray
    gap: np.ndarray
    force: np.ndarray
    total_force: np.ndarray
    length_in_contact: float
    carried: tuple[CarriedArc, ...] = ()
    touchdowns: tuple[Touchdown, ...] = ()
    min_gap_on: str = "hose"
    min_gap_arc_length: float = math.nan

    def summary(self) -> dict:
        """For result.json (user units); "points" are the barrier's pairs."""
        return {"name": self.name, "kind": self.kind,
                "min_gap_mm": None if not np.isfinite(self.min_gap) else float(self.min_gap),
                "min_gap_on": self.min_gap_on,
                "min_gap_arc_length_mm": None if not np.isfinite(self.min_gap_arc_length) else float(self.min_gap_arc_length),
                "total_force_N": self.total_force.tolist(), "length_in_contact_mm": float(self.length_in_contact),
                "carried_arcs": [arc.summary() for arc in self.carried],
                "touchdowns": [touchdown.summary() for touchdown in self.touchdowns],
                "points": [{"arc_length_mm": float(s), "point_mm": p.tolist(), "surface_point_mm": q.tolist(),
                            "gap_mm": float(g), "force_N": f.tolist()}
                           for s, p, q, g, f in zip(self.arc_length, self.point, self.surface_point, self.gap, self.force)]}


@dataclass
class Result:
    """Static equilibrium of a hose placed between two mounts.

    problem: the problem solved.
    s: (N+1,) arc length of the stations, mm.
    centerline: (N+1, 3) station positions, mm.
    frames: (N, 3, 3) material frame of each segment; frames[i, k] is director d_(k+1)
        (d3 = tangent, d1 and d2 the section axes), world components.
    start_frame, end_frame: (3, 3) frames of the two fittings as clamped (rows d1, d2, d3;
        d3 along the hose tangent, so end_frame[2] = -end.direction), the end frame including
        the lock angle and the twist.  With `frames` and `end_force` they are the state from
        which a later solve (e.g. a sweep of moving mounts) continues.
    curvature: (N+1,) bending curvature at the stations, 1/mm.
    twist_rate: (N+1,) rate of twist at the stations, rad/mm.
    bending_moment: (N+1,) magnitude of the bending moment, N*mm.
    twisting_moment: (N+1,) twisting moment (component along the tangent), N*mm.
    internal_moment: (N+1, 3) internal moment vector (exerted by the part s' > s on the part s' < s), N*mm.
    internal_force: (N+1, 3) internal force vector, same convention, N.
    start_force, start_moment: reaction of the start mount on the hose, N and N*mm (moment about the start point).
    end_force, end_moment: reaction of the end mount on the hose, N and N*mm (moment about the end point).
    elastic_energy, gravity_energy: N*mm (gravity energy relative to the straight start position... see docs).
    stability_margin: smallest eigenvalue of the second variation of the energy over rotation
        fields compatible with the clamps, per unit length (the discrete Hessian's eigenvalue
        divided by the segment length, so it converges under refinement), N*mm/(rad^2*mm) = N/rad^2;
        > 0 means stable; None if not evaluated (the studio's result during a drag: build_result, stability=False).
    lock_angle_deg: torque-free roll angle of the end fitting found in the placement, degrees.
    min_bend_radius: smallest inside bend radius reached (centreline radius - outer radius), mm.
    bend_radius_margin: min_bend_radius - hose.min_bend_radius, mm; None if the hose has no limit.
    single_plane_offset: mm, distance of the end mount from the plane of both directions; None if undefined.
    length_error: relative error of the centreline length (exact inextensibility: rounding only).
    iterations: Newton iterations in total; steps: continuation steps in total.
    wall_time: seconds for the whole placement.
    unique: True when no other stable equilibrium was found at the same mounts, length and twist:
        none at the mounts' symmetry images, none with the end fitting turned the other way round
        (at a twist of half a turn or more) and none at the end of the branches not taken at forks
        of the path; False also for a neutral margin (a continuous family of shapes); None ("not
        checked") when one of those could not be followed to the end, so the answer is not known.
    unchecked: why unique is None: the candidates that could not be followed ("" otherwise).
    other_equilibria: the other stable equilibria found (OtherEquilibrium: origin, distance, energy).
    path_forks: the forks met along the placement path, whether or not their branches meet again.
    alternatives: the other stable equilibria as Results, when asked for.
    discretisation_error: estimated largest station error from the segment count, mm (Richardson
        extrapolation from one solve with half the segments); None if not estimated.
    clips: the load of every clip on the hose (ClipReaction), in the order of problem.clips.
    contacts: with contact in the problem, one ObstacleContact per obstacle (in the order of
        problem.contact) and one named "self" with self-contact; empty without.
    obstacle_placement: with obstacles brought in after the free placement (contact_placement "bring_in"), how
        each came to its place (procedures/contact/bring_in.BroughtIn: the rule, the side, the travel); empty else.
    force_refinement: with a force accuracy asked for (solve's force_accuracy), how the segments were refined for it
        (procedures/placement/force_accuracy.ForceRefinement); None else.
    events: human-readable log of what happened along the continuation (bifurcations, branch switches).
    residual: final relative residual of the force and moment balance.
    """

    problem: Problem
    s: np.ndarray
    centerline: np.ndarray
    frames: np.ndarray
    start_frame: np.ndarray
    end_frame: np.ndarray
    curvature: np.ndarray
    twist_rate: np.ndarray
    bending_moment: np.ndarray
    twisting_moment: np.ndarray
    internal_moment: np.ndarray
    internal_force: np.ndarray
    start_force: np.ndarray
    start_moment: np.ndarray
    end_force: np.ndarray
    end_moment: np.ndarray
    elastic_energy: float
    gravity_energy: float
    stability_margin: float | None
    lock_angle_deg: float
    min_bend_radius: float
    bend_radius_margin: float | None
    single_plane_offset: float | None
    length_error: float
    iterations: int
    steps: int
    wall_time: float
    residual: float
    unique: bool | None = True
    unchecked: str = ""
    other_equilibria: list[OtherEquilibrium] = field(default_factory=list)
    path_forks: list[str] = field(default_factory=list)
    alternatives: list["Result"] = field(default_factory=list)
    events: list[str] = field(default_factory=list)
    discretisation_error: float | None = None
    clips: list[ClipReaction] = field(default_factory=list)
    contacts: list[ObstacleContact] = field(default_factory=list)
    obstacle_placement: list = field(default_factory=list)
    force_refinement: ForceRefinement | None = None

    @property
    def stable(self) -> bool | None:
        """True when the equilibrium is a local minimum of the energy (margin 0: neutral, e.g. free to turn); None
        when the margin was not computed (a result built without it, as the studio's drag frames are)."""
        return None if self.stability_margin is None else self.stability_margin >= 0.0

    @property
    def max_twisting_moment(self) -> float:
        """Largest absolute twisting moment along the hose, N*mm."""
        return float(np.max(np.abs(self.twisting_moment)))

    def summary(self) -> dict:
        """Scalars for reports and result.json (user units); "clips" only when the problem has clips, the
        lengths and "end_fittings" only when it has end fittings, "contact" only when it has contact."""
        clips = {"clips": [clip.summary() for clip in self.clips]} if self.clips else {}
        if self.contacts:
            gaps = [contact.min_gap for contact in self.contacts if np.isfinite(contact.min_gap)]
            clips["contact"] = {"min_gap_mm": float(min(gaps)) if gaps else None,
                                "obstacles": [contact.summary() for contact in self.contacts],
                                "placement": [choice.summary() for choice in self.obstacle_placement]}
            if self.force_refinement is not None:
                clips["contact"]["force_accuracy"] = self.force_refinement.summary()
        clips |= fittings_summary(self.problem)
        orientation = orientation_angle_deg(self.problem, self.start_frame, self.end_frame)
        if orientation is not None:
            clips["elbow_orientation_angle_deg"] = orientation
        return {
            "name": self.problem.name,
            "length_mm": self.problem.hose.length,
            "segments": self.problem.hose.segments,
            "end_twist_deg": self.problem.end_twist_deg,
            "lock_angle_deg": self.lock_angle_deg,
            "elastic_energy_Nmm": self.elastic_energy,
            "gravity_energy_Nmm": self.gravity_energy,
            "stability_margin_N_per_rad2": None if self.stability_margin is None else float(self.stability_margin),
            "stable": None if self.stable is None else bool(self.stable),
            "unique": None if self.unique is None else bool(self.unique),
            "uniqueness": uniqueness_word(self.unique),
            **({"uniqueness_not_checked": self.unchecked} if self.unique is None else {}),
            "other_equilibria": [other.summary() for other in self.other_equilibria],
            "path_forks": list(self.path_forks),
            "discretisation_error_mm": self.discretisation_error,
            "min_bend_radius_mm": self.min_bend_radius,
            "bend_radius_margin_mm": self.bend_radius_margin,
            "single_plane_offset_mm": self.single_plane_offset,
            "max_twisting_moment_Nmm": self.max_twisting_moment,
            "max_bending_moment_Nmm": float(np.max(self.bending_moment)),
            "start_force_N": self.start_force.tolist(),
            "start_moment_Nmm": self.start_moment.tolist(),
            "end_force_N": self.end_force.tolist(),
            "end_moment_Nmm": self.end_moment.tolist(),
            "length_error": self.length_error,
            "residual": self.residual,
            "iterations": self.iterations,
            "continuation_steps": self.steps,
            "wall_time_s": self.wall_time,
            "events": list(self.events),
        } | clips


def fittings_summary(problem: Problem) -> dict:
    """Free and overall length (mm) and each fitting's port, outlet and lengths, for result.json; {} without fittings."""
    fittings = problem.fittings
    if fittings is None:
        return {}
    ends = {}
    for name, port, fitting in fittings.pieces():
        outlet = fitting.outlet(port)
        ends[name] = {"port_mm": port.point.tolist(), "port_direction": port.direction.tolist(),
                      "outlet_mm": outlet.point.tolist(), "outlet_direction": outlet.direction.tolist(),
                      "bend_angle_deg": fitting.bend_angle_deg, "clocking_deg": fitting.clocking_deg,
                      "centreline_length_mm": fitting.centreline_length, "length_allowance_mm": fitting.length_allowance}
    return {"free_length_mm": problem.hose.length, "overall_length_mm": fittings.overall_length(problem.hose.length),
            "end_fittings": ends}
