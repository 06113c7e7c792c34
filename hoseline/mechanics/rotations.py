"""Rotations of material frames.

A frame is a 3x3 array whose ROWS are the directors d1, d2, d3 (world components);
d3 is the hose tangent.  Rotating a frame by a rotation matrix R maps every
director d to R d, i.e. frame -> frame @ R.T.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def rotation_matrix(rotation_vector: np.ndarray) -> np.ndarray:
    """Rodrigues' formula: the rotation by |v| radians about v/|v| (world axes)."""
    angle = math.sqrt(rotation_vector[0] ** 2 + rotation_vector[1] ** 2 + rotation_vector[2] ** 2)
    out = np.eye(3)
    if angle < 1e-300:
        return out
    kx, ky, kz = rotation_vector[0] / angle, rotation_vector[1] / angle, rotation_vector[2] / angle
    c, s = math.cos(angle), math.sin(angle)
    t = 1.0 - c
    out[0, 0] = c + kx * kx * t
    out[0, 1] = kx * ky * t - kz * s
    out[0, 2] = kx * kz * t + ky * s
    out[1, 0] = ky * kx * t + kz * s
    out[1, 1] = c + ky * ky * t
    out[1, 2] = ky * kz * t - kx * s
    out[2, 0] = kz * kx * t - ky * s
    out[2, 1] = kz * ky * t + kx * s
    out[2, 2] = c + kz * kz * t
    return out


@njit(cache=True)
def rotate_frames(frames: np.ndarray, rotation_vectors: np.ndarray) -> np.ndarray:
    """New frames after rotating frame i by the world rotation vector rotation_vectors[i] (rad)."""
    out = np.empty_like(frames)
    for i in range(frames.shape[0]):
        rotation = rotation_matrix(rotation_vectors[i])
        for k in range(3):  # d_k -> R d_k, written out (3x3 BLAS calls cost more than the arithmetic)
            for x in range(3):
                out[i, k, x] = (
                    rotation[x, 0] * frames[i, k, 0] + rotation[x, 1] * frames[i, k, 1] + rotation[x, 2] * frames[i, k, 2]
                )
    return out


@njit(cache=True)
def extrapolate_frames(previous: np.ndarray, current: np.ndarray, ratio: float) -> np.ndarray:
    """Secant predictor on the rotation group: apply `ratio` times the rotation that took
    each frame from `previous` to `current` once more (rotations of moderate size)."""
    out = np.empty_like(current)
    for i in range(current.shape[0]):
        rel = current[i].T @ previous[i]  # world rotation R with current = previous @ R^T
        cos_angle = min(1.0, max(-1.0, 0.5 * (rel[0, 0] + rel[1, 1] + rel[2, 2] - 1.0)))
        angle = math.acos(cos_angle)
        factor = 0.5 if angle < 1e-8 else 0.5 * angle / math.sin(angle)
        omega = np.array([rel[2, 1] - rel[1, 2], rel[0, 2] - rel[2, 0], rel[1, 0] - rel[0, 1]]) * (factor * ratio)
        out[i] = current[i] @ rotation_matrix(omega).T
    return out


def rotation_vector(matrix: np.ndarray) -> np.ndarray:
    """Inverse of Rodrigues' formula: the rotation vector (rad) of a rotation matrix, angle in [0, pi]."""
    cos_angle = np.clip(0.5 * (np.trace(matrix) - 1.0), -1.0, 1.0)
    angle = math.acos(cos_angle)
    axial = 0.5 * np.array([matrix[2, 1] - matrix[1, 2], matrix[0, 2] - matrix[2, 0], matrix[1, 0] - matrix[0, 1]])
    if angle < 1e-8:
        return axial
    if angle < math.pi - 1e-6:
        return axial * (angle / math.sin(angle))
    # near pi: axis from the symmetric part
    sym = 0.5 * (matrix + matrix.T) - cos_angle * np.eye(3)
    axis = sym[np.argmax(np.diag(sym))]
    axis = axis / np.linalg.norm(axis)
    if np.dot(axis, axial) < 0.0:
        axis = -axis
    return axis * angle


def frame_from_tangent(tangent: np.ndarray) -> np.ndarray:
    """A right-handed frame (rows d1, d2, d3) with d3 = tangent.

    d1 is the world axis least aligned with the tangent, made perpendicular to it;
    a deterministic choice so that a problem always starts from the same material frame.
    """
    t = np.asarray(tangent, dtype=float)
    t = t / np.linalg.norm(t)
    axis = np.zeros(3)
    axis[int(np.argmin(np.abs(t)))] = 1.0
    d1 = axis - np.dot(axis, t) * t
    d1 /= np.linalg.norm(d1)
    d2 = np.cross(t, d1)
    return np.array([d1, d2, t])


def perpendicular(vector: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to `vector` (deterministic)."""
    return frame_from_tangent(vector)[0]
