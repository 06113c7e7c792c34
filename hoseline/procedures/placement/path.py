"""The clamps along the placement of one problem (Keil & Thomas' sequence, placement/sequence.py): the place
phase that carries the straight hose's end onto the end mount, and the twisted end fitting."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from hoseline.mechanics.clipped_newton import clip_rolls
from hoseline.mechanics.rod import Clamps, ClipHold, RodState
from hoseline.mechanics.rotations import frame_from_tangent, perpendicular, rotation_matrix
from hoseline.model.clips import clip_node
from hoseline.model.problem import Problem


def weight_vector(problem: Problem) -> np.ndarray:
    """Weight per length of the hose as a vector, N/mm (kg/m times m/s^2 = N/m = 1e-3 N/mm)."""
    return problem.hose.mass_per_length * problem.gravity * 1e-3


def placement_rotation(problem: Problem) -> tuple[np.ndarray, float]:
    """Axis (unit) and angle (rad) of the rotation that turns the start tangent into the end tangent.

    The axis is the cross product of the tangents; for parallel or antiparallel tangents it
    is normal to the plane of the start tangent and the mount-to-mount vector (so the
    tangent turns towards the end mount), or any normal if that plane is not defined.
    """
    return tangent_turn(problem.start.direction, -problem.end.direction, problem.end.point - problem.start.point,
                        problem.hose.length)


def tangent_turn(t0: np.ndarray, t1: np.ndarray, chord: np.ndarray, length: float) -> tuple[np.ndarray, float]:
    """Axis (unit) and angle (rad) turning the unit tangent t0 into t1: about t0 x t1, or for parallel
    tangents about the normal of the plane of t0 and `chord` (mm; the hose of `length` mm turns
    towards it), or any normal if that plane is not defined."""
    cross = np.cross(t0, t1)
    angle = math.atan2(float(np.linalg.norm(cross)), float(np.dot(t0, t1)))
    if np.linalg.norm(cross) > 1e-9:
        return cross / np.linalg.norm(cross), angle
    toward = np.cross(t0, chord)
    if np.linalg.norm(toward) > 1e-9 * length:
        return toward / np.linalg.norm(toward), angle
    return perpendicular(t0), angle


class PlacementPath:
    """The clamps along the placement of one problem: the place phase and the twisted end.

    place(t): t in [0, 1] carries the end of the straight hose onto the end mount (roll free,
    weight ramped in).  twisted(locked_frame, twist_deg, clips, share): the end fitting at the end
    mount, turned by twist_deg degrees about end.direction from the locked frame (roll clamped), and
    each fixed clip turned by `share` of its own twist (Clip.twist_deg) from its locked roll.

    Clips: in the place phase every clip's station travels along a straight line from where it
    sits on the straight hose to the clip point, and a clip that holds the direction turns its
    frame from the start frame into the clip direction (about their cross product), roll free.
    After the place phase the roll of fixed clips is locked at the torque-free angle found
    (locked_clips) and, in the twist phase, turned by its twist from there; rotating and sliding
    clips stay free to roll.  A sliding clip starts at the
    station nearest its arc_length and the hose slides through it all along the path (its arc
    length is an unknown of every solve).
    """

    def __init__(self, problem: Problem):
        self.problem = problem
        self.start_frame = frame_from_tangent(problem.start.direction)
        self.straight_end = problem.start.point + problem.hose.length * problem.start.direction
        self.axis, self.angle = placement_rotation(problem)
        self.weight = weight_vector(problem)
        hose, start = problem.hose, problem.start
        self.clip_nodes = [  # a sliding clip starts at the station nearest its arc_length
            round(clip.arc_length / hose.segment_length) if clip.slides else clip_node(clip.arc_length, hose.length,
                                                                                      int(hose.segments))
            for clip in problem.clips
        ]
        self.clip_turns = [
            tangent_turn(start.direction, clip.direction, clip.point - start.point, hose.length) if clip.holds_direction
            else None
            for clip in problem.clips
        ]

    def place(self, t: float) -> Clamps:
        """Clamps at fraction t of the place phase."""
        start, h = self.problem.start, self.problem.hose.segment_length
        clips = tuple(
            ClipHold(
                node,
                (1.0 - t) * (start.point + node * h * start.direction) + t * clip.point,
                None if turn is None else self.start_frame @ rotation_matrix(turn[0] * (turn[1] * t)).T,
                turn is not None,
                clip.slides,
            )
            for clip, node, turn in zip(self.problem.clips, self.clip_nodes, self.clip_turns)
        )
        return Clamps(
            start_point=start.point,
            start_frame=self.start_frame,
            end_point=(1.0 - t) * self.straight_end + t * self.problem.end.point,
            end_frame=self.start_frame @ rotation_matrix(self.axis * (self.angle * t)).T,
            roll_free=True,
            line_weight=t * self.weight,
            clips=clips,
        )

    def locked_clips(self, state: RodState) -> tuple[tuple[ClipHold, ...], np.ndarray]:
        """The clips at the end of the place phase with the roll of fixed clips locked at the
        torque-free angle of `state`, and the clip rolls (rad) that stay free (zero where locked)."""
        placed = self.place(1.0)
        rolls = clip_rolls(placed, state)
        clips, free_rolls = [], np.zeros(len(rolls))
        for j, (clip, hold) in enumerate(zip(self.problem.clips, placed.clips)):
            if clip.kind == "fixed":
                hold = replace(hold, frame=hold.frame @ rotation_matrix(rolls[j] * hold.frame[2]).T, roll_free=False)
            elif hold.roll_free:
                free_rolls[j] = rolls[j]
            clips.append(hold)
        return tuple(clips), free_rolls

    def twisted(self, locked_frame: np.ndarray, twist_deg: float, clips: tuple[ClipHold, ...] = (),
                share: float = 1.0) -> Clamps:
        """Clamps with the end fitting turned by twist_deg (degrees) from locked_frame; `clips` as locked
        (locked_clips), each fixed clip turned by `share` (0 to 1, the twist phase's fraction) of its twist about
        its d3."""
        clips = tuple(
            replace(hold, frame=hold.frame @ rotation_matrix(hold.frame[2] * (share * math.radians(clip.twist_deg))).T)
            if clip.twist_deg else hold
            for clip, hold in zip(self.problem.clips, clips)
        )
        return Clamps(
            start_point=self.problem.start.point,
            start_frame=self.start_frame,
            end_point=self.problem.end.point,
            end_frame=locked_frame @ rotation_matrix(self.problem.end.direction * math.radians(twist_deg)).T,
            roll_free=False,
            line_weight=self.weight,
            clips=clips,
        )
