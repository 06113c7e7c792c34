"""Turn an equilibrium state into a Result: stations, moments, forces, reactions, margins."""

from __future__ import annotations

import math
import time

import numpy as np

from hoseline.mechanics import clipped_newton
from hoseline.mechanics.energy import elastic_energy
from hoseline.mechanics.newton import RodProperties, evaluate
from hoseline.mechanics.rod import Clamps, RodState, centerline
from hoseline.mechanics.stability import smallest_eigenpairs
from hoseline.model.mounts import single_plane_offset
from hoseline.model.problem import Problem
from hoseline.procedures.placement.hose_health import station_moments
from hoseline.procedures.placement.path import PlacementPath
from hoseline.procedures.placement.result import ClipReaction, Result

NEUTRAL_MARGIN = 1e-6  # margins below this fraction of the load scale (neutral_scale) are rounding of an exact zero


def neutral_scale(props: RodProperties, clamps: Clamps, state: RodState) -> float:
    """The size of the stability margin's terms, N (= N*mm/(rad^2*mm)): the largest of the
    stiffness scale K/L^2, the hose's weight |q| L and the end force |F|.  A heavy, soft hose's
    second variation is made of weight terms, so rounding is relative to them, not to EI/L^2."""
    weight = float(np.linalg.norm(clamps.line_weight)) * props.length
    return max(props.largest_stiffness / props.length**2, weight, float(np.linalg.norm(state.end_force)))


def _stability_margin(props: RodProperties, clamps: Clamps, state: RodState, system, events: list[str]) -> float:
    """The stability margin of `state` (N/rad^2: the smallest eigenvalue of the second variation per unit length,
    so independent of the segment count; 0 when neutral, which `events` is then told).  system: evaluate()'s."""
    h = props.segment_length
    if isinstance(system, clipped_newton.SlidingSystem):
        values = [clipped_newton.smallest_sliding_eigenvalue(system, h)]
    else:
        values, _ = smallest_eigenpairs(system.band, system.jac_t, count=1)
    margin = float(values[0]) / h
    if abs(margin) < NEUTRAL_MARGIN * neutral_scale(props, clamps, state):
        events.append(
            "neutral stability: one way of deforming costs no energy (a symmetry of the mounts, e.g. "
            "turning the whole hose about the common axis of both fittings); the shape is not unique"
        )
        return 0.0
    return margin


def build_result(
    problem: Problem,
    props: RodProperties,
    clamps: Clamps,
    state: RodState,
    lock_angle_deg: float,
    log,
    started: float,
    residual: float,
    stability: bool = True,
) -> Result:
    """Result of an equilibrium `state` under the final `clamps` (roll locked).

    lock_angle_deg: degrees.  log: ContinuationLog with counters and events.
    started: time.perf_counter() at the start of the solve.  residual: final relative residual.
    stability: False leaves the stability margin out (None; an eigenvalue problem saved), for a result whose margin
    is found otherwise (with the contact barrier: contact/placement.with_contact) or later (a studio drag).
    """
    h = props.segment_length
    if clamps.clips:  # each segment of its own length: a sliding clip stretches its spans
        lengths = clipped_newton.segment_lengths(props, clamps, state)[0]
        s, nodes = clipped_newton.station_positions(props, clamps, state)
    else:
        lengths, s = np.full(props.segments, h), h * np.arange(props.segments + 1)
        nodes = centerline(state.frames, clamps.start_point, h)
    weight_energy = float(-np.sum(lengths * ((0.5 * (nodes[1:] + nodes[:-1]) - clamps.start_point) @ clamps.line_weight)))
    moments, darboux, node_tangent = station_moments(props, clamps, state)
    twisting = np.einsum("ij,ij->i", moments, node_tangent)
    bending = np.linalg.norm(moments - twisting[:, None] * node_tangent, axis=1)
    curvature = np.hypot(darboux[:, 0], darboux[:, 1])
    internal_force = state.end_force[None, :] + (props.length - s)[:, None] * clamps.line_weight[None, :]
    clips = clip_reactions(problem, props, clamps, state)
    for clip in clips:  # the clips beyond a station hold the part beyond it too
        internal_force[s < clip.arc_length - 0.5 * float(np.min(lengths))] += clip.force
    system = evaluate(props, clamps, state)
    events = list(log.events)
    margin = _stability_margin(props, clamps, state, system, events) if stability else None
    max_curvature = float(np.max(curvature))
    radius_outer = problem.hose.outer_radius
    min_radius = (1.0 / max_curvature - radius_outer) if max_curvature > 0.0 else math.inf
    limit = problem.hose.min_bend_radius
    return Result(
        problem=problem,
        s=s,
        centerline=nodes,
        frames=state.frames.copy(),
        start_frame=clamps.start_frame.copy(),
        end_frame=clamps.end_frame.copy(),
        curvature=curvature,
        twist_rate=darboux[:, 2].copy(),
        bending_moment=bending,
        twisting_moment=twisting,
        internal_moment=moments,
        internal_force=internal_force,
        start_force=-internal_force[0],
        start_moment=-moments[0],
        end_force=state.end_force.copy(),
        end_moment=moments[-1].copy(),
        elastic_energy=float(
            system.energy - weight_energy if clips
            else elastic_energy(state.frames, clamps.start_frame, clamps.end_frame, props.stiffness, h, True, props.springs,
                                props.rest, props.braid)
        ),
        gravity_energy=weight_energy,
        stability_margin=margin,
        lock_angle_deg=lock_angle_deg,
        min_bend_radius=min_radius,
        bend_radius_margin=None if limit is None else min_radius - limit,
        single_plane_offset=single_plane_offset(problem.start, problem.end),
        length_error=abs(float(np.sum(lengths * np.linalg.norm(state.frames[:, 2], axis=1))) - props.length) / props.length,
        iterations=log.iterations,
        steps=log.steps,
        wall_time=time.perf_counter() - started,
        residual=residual,
        events=events,
        clips=clips,
    )


def clip_reactions(problem: Problem, props: RodProperties, clamps: Clamps, state: RodState) -> list[ClipReaction]:
    """The force (N) and moment (N*mm) of every clip on the hose at an equilibrium `state`."""
    if not clamps.clips:
        return []
    forces, moments = clipped_newton.clip_reactions(props, clamps, state)
    arc_lengths = clipped_newton.clip_arc_lengths(props, clamps, state)  # where sliding clips came to rest
    _, _, frames, framed, _ = clipped_newton.clip_arrays(clamps, state)  # with the rolls found
    rolls = locked_clip_rolls(problem, clamps)
    return [
        ClipReaction(clip.kind, clip.name, float(arc) if clip.slides else clip.arc_length, clip.point.copy(), force,
                     moment, frame.copy() if held else None, roll)
        for clip, force, moment, arc, frame, held, roll in zip(problem.clips, forces, moments, arc_lengths, frames,
                                                                framed, rolls)
    ]


def locked_clip_rolls(problem: Problem, clamps: Clamps) -> list[float | None]:
    """The roll (degrees, right-handed about the clip direction) at which `clamps` hold each fixed clip, measured
    from the frame the place phase carries the clip to with its roll free (PlacementPath.place(1)); None for
    the other kinds.  The placement locks a fixed clip at the torque-free roll of the end of the place phase and
    turns it by the clip's twist from there."""
    carried = PlacementPath(problem).place(1.0).clips
    return [
        math.degrees(math.atan2(float(held.frame[0] @ free.frame[1]), float(held.frame[0] @ free.frame[0])))
        if clip.kind == "fixed" else None
        for clip, held, free in zip(problem.clips, clamps.clips, carried)
    ]
