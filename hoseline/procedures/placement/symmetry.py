"""Other equilibria of equal energy that the problem's symmetry guarantees.

If the two mounts and gravity are symmetric under a reflection (all in one plane) or,
for mounts on one axis, under a half turn about that axis, then the image of an
equilibrium is an equilibrium of the same clamped problem with the same energy and
stability.  When the image differs from the shape, the answer is not unique: the hose
can lie either way, and an engineer must know.

A reflection reverses handedness, so the image frames get d2 -> -d2 (the section axes
stay the same lines, the energy is unchanged).  The image's start frame may then differ
from the fitting frame by a roll about the tangent; for a round-section hose (EI1 = EI2)
a uniform roll of every frame costs no energy, so the image is rolled back.  The image
is accepted only if its end frame then coincides with the clamped end frame.
"""

from __future__ import annotations

import math

import numpy as np

from hoseline.mechanics.clipped_newton import clip_arrays, clip_forces
from hoseline.mechanics.newton import RodProperties
from hoseline.mechanics.rod import Clamps, RodState, centerline
from hoseline.mechanics.rotations import rotation_matrix
from hoseline.model.problem import Problem

FLIP_D2 = np.diag([1.0, -1.0, 1.0])


def _roll_angle(frame: np.ndarray, target: np.ndarray) -> float:
    """Angle (rad) about frame[2] that rolls `frame` onto `target` (same d3 assumed)."""
    return math.atan2(float(np.dot(np.cross(frame[0], target[0]), frame[2])), float(np.dot(frame[0], target[0])))


def _roll_all(frames: np.ndarray, angle: float) -> np.ndarray:
    """Roll every frame about its own d3 by `angle` (rad): d1, d2 rotate in the section plane."""
    c, s = math.cos(angle), math.sin(angle)
    body = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    return np.einsum("kl,nlj->nkj", body, frames)


def _symmetries(problem: Problem, props: RodProperties) -> list[tuple[np.ndarray, bool]]:
    """Orthogonal maps (about the start point) that map the mounts and gravity onto themselves.

    Returns (matrix, is_reflection) pairs; none for a preset hose (its natural curvature, fixed
    to the material, is not mapped onto itself).
    """
    if props.rest is not None:
        return []
    t0, t1 = problem.start.direction, -problem.end.direction
    delta = problem.end.point - problem.start.point
    tol = 1e-9
    gravity = problem.gravity * problem.hose.mass_per_length  # only the weight matters
    normal = np.cross(t0, t1)
    if np.linalg.norm(normal) < tol:
        normal = np.cross(t0, delta)
        if np.linalg.norm(normal) < tol * props.length:
            # mounts on one axis: half turn about it
            if np.linalg.norm(np.cross(gravity, t0)) > tol * (1.0 + np.linalg.norm(gravity)):
                return []
            return [(rotation_matrix(math.pi * t0), False)]
    normal = normal / np.linalg.norm(normal)
    if abs(np.dot(delta, normal)) > tol * props.length:
        return []
    if abs(np.dot(gravity, normal)) > tol * (1.0 + np.linalg.norm(gravity)):
        return []
    return [(np.eye(3) - 2.0 * np.outer(normal, normal), True)]


def _clip_images(clamps: Clamps, state: RodState, matrix: np.ndarray, body: np.ndarray, roll: float,
                 length: float) -> np.ndarray | None:
    """The clip rolls (rad) of the image of `state` under the map x -> start + matrix (x - start) (frames
    turned by `body` and rolled back by `roll`), or None when the map moves a clip: its point, its
    direction, or for a fixed clip its frame (a rotating or sliding clip's frame may roll: the image's
    roll is the angle that takes the clip frame to its image)."""
    if not clamps.clips:
        return np.zeros(0)
    _, _, frames, _, _ = clip_arrays(clamps, state)
    rolls = np.zeros(len(clamps.clips))
    for j, (clip, frame) in enumerate(zip(clamps.clips, frames)):
        point = clamps.start_point + matrix @ (clip.point - clamps.start_point)
        if np.linalg.norm(point - clip.point) > 1e-9 * length:
            return None
        if clip.frame is None:
            continue
        image = _roll_all((body @ frame @ matrix.T)[None], roll)[0]
        if np.max(np.abs(image[2] - clip.frame[2])) > 1e-6:
            return None
        rolls[j] = _roll_angle(clip.frame, image)
        if not clip.roll_free and abs(rolls[j]) > 1e-6:
            return None
    return rolls


def equivalent_states(
    problem: Problem, props: RodProperties, clamps: Clamps, state: RodState
) -> list[tuple[RodState, bool]]:
    """Images of `state` under the problem's symmetries that solve the same clamped problem but differ
    from it, each with True for a reflection (mirror image), False for a half turn."""
    images = []
    stiffness = props.stiffness
    round_section = abs(stiffness[0] - stiffness[1]) <= 1e-12 * stiffness[0]
    nodes = centerline(state.frames, clamps.start_point, props.segment_length)
    for matrix, reflection in _symmetries(problem, props):
        body = FLIP_D2 if reflection else np.eye(3)
        frames = np.einsum("kl,nlj,mj->nkm", body, state.frames, matrix)
        start_image = body @ clamps.start_frame @ matrix.T
        end_image = body @ clamps.end_frame @ matrix.T
        roll = _roll_angle(start_image[None][0], clamps.start_frame)
        if abs(roll) > 1e-12:
            if not round_section and abs(abs(roll) - math.pi) > 1e-12:
                continue
            frames = _roll_all(frames, roll)
            end_image = _roll_all(end_image[None], roll)[0]
        if np.max(np.abs(end_image - clamps.end_frame)) > 1e-6:
            continue
        clip_rolls = _clip_images(clamps, state, matrix, body, roll, props.length)
        if clip_rolls is None:
            continue
        image = RodState(frames, matrix @ state.end_force, 0.0, clip_forces(clamps, state) @ matrix.T, clip_rolls,
                         state.clip_arc_lengths.copy())
        image_nodes = centerline(frames, clamps.start_point, props.segment_length)
        if np.max(np.abs(image_nodes - nodes)) > 1e-6 * props.length:
            images.append((image, reflection))
    return images
