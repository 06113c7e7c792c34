"""Rotations of material frames.

A frame is a 3x3 array whose ROWS are the directors d1, d2, d3 (world components);
d3 is the hose tangent.  Rotating a frame by a rotation matrix R maps every
director d to R d, i.e. frame -> frame @ R.T.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

AXIS_TIE = 1e-9  # direction components closer than this to the smallest are tied (frame_from_tangent)


@njit(cache=True)
def _rotation_entries(vx, vy, vz):
    # Rodrigues' formula for the rotation vector (vx, vy, vz): the nine entries, row by row, as scalars
    angle = math.sqrt(vx * vx + vy * vy + vz * vz)
    if angle < 1e-300:
        return 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0
    kx, ky, kz = vx / angle, vy / angle, vz / angle
    c, s = math.cos(angle), math.sin(angle)
    t = 1.0 - c
    return (
        c + kx * kx * t, kx * ky * t - kz * s, kx * kz * t + ky * s,
        ky * kx * t + kz * s, c + ky * ky * t, ky * kz * t - kx * s,
        kz * kx * t - ky * s, kz * ky * t + kx * s, c + kz * kz * t,
    )


@njit(cache=True)
def rotation_matrix(rotation_vector: np.ndarray) -> np.ndarray:
    """Rodrigues' formula: the rotation by |v| radians about v/|v| (world axes)."""
    r = _rotation_entries(rotation_vector[0], rotation_vector[1], rotation_vector[2])
    out = np.empty((3, 3))
    for x in range(3):
        for y in range(3):
            out[x, y] = r[3 * x + y]
    return out


@njit(cache=True)
def rotate_frames(frames: np.ndarray, rotation_vectors: np.ndarray) -> np.ndarray:
    """New frames after rotating frame i by the world rotation vector rotation_vectors[i] (rad)."""
    out = np.empty_like(frames)
    for i in range(frames.shape[0]):
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = _rotation_entries(
            rotation_vectors[i, 0], rotation_vectors[i, 1], rotation_vectors[i, 2]
        )
        for k in range(3):  # d_k -> R d_k, written out (3x3 BLAS calls and temporary arrays cost more than the arithmetic)
            d0, d1, d2 = frames[i, k, 0], frames[i, k, 1], frames[i, k, 2]
            out[i, k, 0] = r00 * d0 + r01 * d1 + r02 * d2
            out[i, k, 1] = r10 * d0 + r11 * d1 + r12 * d2
            out[i, k, 2] = r20 * d0 + r21 * d1 + r22 * d2
    return out


@njit(cache=True)
def extrapolate_frames(previous: np.ndarray, current: np.ndarray, ratio: float) -> np.ndarray:
    """Secant predictor on the rotation group: apply `ratio` times the rotation that took
    each frame from `previous` to `current` once more (rotations of moderate size)."""
    n = current.shape[0]
    rotations = np.empty((n, 3))
    for i in range(n):
        # world rotation R with current = previous @ R^T, i.e. R = current^T previous: its
        # trace and axial part, from the directors d_k (trace = sum_k d_k^cur . d_k^prev,
        # axial = sum_k d_k^prev x d_k^cur)
        trace = 0.0
        ax, ay, az = 0.0, 0.0, 0.0
        for k in range(3):
            c0, c1, c2 = current[i, k, 0], current[i, k, 1], current[i, k, 2]
            p0, p1, p2 = previous[i, k, 0], previous[i, k, 1], previous[i, k, 2]
            trace += c0 * p0 + c1 * p1 + c2 * p2
            ax += p1 * c2 - p2 * c1
            ay += p2 * c0 - p0 * c2
            az += p0 * c1 - p1 * c0
        cos_angle = min(1.0, max(-1.0, 0.5 * (trace - 1.0)))
        angle = math.acos(cos_angle)
        factor = (0.5 if angle < 1e-8 else 0.5 * angle / math.sin(angle)) * ratio
        rotations[i, 0], rotations[i, 1], rotations[i, 2] = ax * factor, ay * factor, az * factor
    return rotate_frames(current, rotations)


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
    Ties, common for axis-aligned CAD mounts, go to the first of x, y, z, and components within
    AXIS_TIE of the smallest count as tied, so that CAD rounding (a direction (1e-16, 1, 0)) does
    not turn d1 by 90 degrees: start direction +y or -y: d1 = +x; +x or -x: d1 = +y; +z or -z: d1 = +x.
    """
    t = np.asarray(tangent, dtype=float)
    t = t / np.linalg.norm(t)
    axis = np.zeros(3)
    size = np.abs(t)
    axis[int(np.flatnonzero(size <= size.min() + AXIS_TIE)[0])] = 1.0
    d1 = axis - np.dot(axis, t) * t
    d1 /= np.linalg.norm(d1)
    d2 = np.cross(t, d1)
    return np.array([d1, d2, t])


def perpendicular(vector: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to `vector` (deterministic)."""
    return frame_from_tangent(vector)[0]
