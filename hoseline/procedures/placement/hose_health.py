"""What an engineer checks on a placed hose at one pose: bend radius, twisting moment, reactions.

The same quantities as the full Result (see stations.py), computed without the stability
analysis, so a sweep can afford them at every pose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hoseline.mechanics.clipped import joint_darboux, joint_into
from hoseline.mechanics.clipped_newton import clip_arrays, segment_lengths
from hoseline.mechanics.energy import joint_moments
from hoseline.mechanics.stiffeners import HALF
from hoseline.mechanics.newton import RodProperties, end_frame_of
from hoseline.mechanics.rod import Clamps, RodState


@dataclass(frozen=True)
class Health:
    """Loads and bending along the hose at one pose.

    bend_radius: (N+1,) mm at the stations, to the inside of the bend (inf where straight).
    twisting_moment: (N+1,) N*mm, the internal moment's component along the tangent.
    start_force, end_force: (3,) N, reactions of the mounts on the hose.
    start_moment, end_moment: (3,) N*mm, the same, about the fitting tips.
    """

    bend_radius: np.ndarray
    twisting_moment: np.ndarray
    start_force: np.ndarray
    start_moment: np.ndarray
    end_force: np.ndarray
    end_moment: np.ndarray


def station_moments(props: RodProperties, clamps: Clamps, state: RodState):
    """Internal moments (N*mm, world), discrete Darboux vectors (1/mm, material) and unit
    tangents at the N+1 stations of an equilibrium `state` under `clamps`."""
    end_frame = end_frame_of(clamps, state)
    moments, darboux = joint_moments(
        state.frames, clamps.start_frame, end_frame, props.stiffness, props.segment_length, True, props.springs,
        props.rest, props.braid,
    )
    tangents = np.vstack([clamps.start_frame[2][None], state.frames[:, 2], end_frame[2][None]])
    node_tangent = tangents[:-1] + tangents[1:]
    node_tangent /= np.linalg.norm(node_tangent, axis=1)[:, None]
    if clamps.clips:  # at a clip that holds the direction: the half joint from the clip frame on
        lengths, rates = segment_lengths(props, clamps, state)
        if rates.shape[1]:  # sliding clips stretch their spans: a joint's moment and Darboux vector go as 1/length
            joint = 0.5 * (np.concatenate([[0.0], lengths]) + np.concatenate([lengths, [0.0]]))
            uniform = np.full(props.segments + 1, props.segment_length)
            uniform[[0, -1]] *= 0.5
            moments *= (uniform / joint)[:, None]
            darboux *= (uniform / joint)[:, None]
        _clip_station_moments(props, clamps, state, moments, darboux, node_tangent, lengths)
    return moments, darboux, node_tangent


def _clip_station_moments(props: RodProperties, clamps: Clamps, state: RodState, moments, darboux, node_tangent,
                          lengths) -> None:
    # the hose beyond a clip station hangs on the clip frame through a half joint: its moment on the
    # part before the station, its Darboux vector and its tangent (the mean of the clip's and the segment's: the
    # twisting moment is the moment along it; the mean of the two segments' leaked 4 % of the bending moment into
    # it, -31.6 N*mm where the twist is zero) replace those of the (absent) full joint
    nodes, _, frames, framed, _ = clip_arrays(clamps, state)
    g, haa, hab = np.empty(3), np.empty((3, 3)), np.empty((3, 3))
    for node, frame, has_frame in zip(nodes, frames, framed):
        if has_frame:
            half = 0.5 * lengths[node]
            joint_into(frame, state.frames[node], props.stiffness, half, props.springs, HALF, g, haa, hab)
            moments[node] = -g
            darboux[node] = joint_darboux(frame, state.frames[node], half)
            tangent = frame[2] + state.frames[node, 2]
            node_tangent[node] = tangent / np.linalg.norm(tangent)


def hose_health(props: RodProperties, clamps: Clamps, state: RodState, outer_radius: float) -> Health:
    """Bend radius, twisting moment and mount reactions of an equilibrium `state` under `clamps`.

    outer_radius: mm, for the bend radius to the inside of the bend.
    """
    moments, darboux, node_tangent = station_moments(props, clamps, state)
    curvature = np.hypot(darboux[:, 0], darboux[:, 1])
    with np.errstate(divide="ignore"):
        bend_radius = 1.0 / curvature - outer_radius
    start_force = -(state.end_force + props.length * clamps.line_weight)
    if clamps.clips:  # the clips carry their part
        start_force -= np.sum(state.clip_forces, axis=0) if state.clip_forces.shape == (len(clamps.clips), 3) else 0.0
    return Health(
        bend_radius=bend_radius,
        twisting_moment=np.einsum("ij,ij->i", moments, node_tangent),
        start_force=start_force,
        start_moment=-moments[0],
        end_force=state.end_force.copy(),
        end_moment=moments[-1].copy(),
    )
