"""What the Newton iterations share (mechanics/newton.py, and mechanics/clipped_newton.py with clips): the rod's
properties, its assembled system at one state, the report of one solve, the end frame with its free roll and the
relative residual."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from hoseline.mechanics.rod import Clamps, RodState
from hoseline.mechanics.rotations import rotation_matrix


@dataclass(frozen=True)
class RodProperties:
    """Internal-unit properties of the discrete rod: stiffness (EI1, EI2, GJ) N*mm^2, segment length h mm, count N.

    springs: the joint model.  None (default): the elastic joints of energy.py alone; else
    the stiffener springs added at every joint, as packed by mechanics.stiffeners.spring_set.
    rest: the preset.  None (default): the hose is straight and untwisted when unloaded; else
    (N+1, 3, 3) stress-free relative rotations of the joints (model/preset.py, energy.py).
    braid: the braid coupling.  None (default): none; else the data of mechanics.braid.braid_coefficients,
    added to every joint.
    """

    stiffness: np.ndarray
    segment_length: float
    segments: int
    springs: tuple | None = None
    rest: np.ndarray | None = None
    braid: np.ndarray | None = None

    @property
    def length(self) -> float:
        return self.segment_length * self.segments

    @property
    def largest_stiffness(self) -> float:
        return float(max(self.stiffness))


@dataclass
class NewtonReport:
    """Outcome of one equilibrium solve."""

    converged: bool
    iterations: int
    residual: float
    unstable_directions: int
    message: str = ""
    factored: tuple | None = None  # where a contact solve converged, (Jc^T, the pivots of its last KKT solve), from
    # which contact_newton.tangent_log_det gives the log |det| of the tangent Hessian without another factorisation
    # (procedures/contact/continuation.FoldWatch watches it for folds); else None


@dataclass
class System:
    """Energy, derivatives and constraint of the rod at one state (internal units)."""

    energy: float  # elastic + gravity, N*mm
    grad: np.ndarray  # gradient of the Lagrangian, N*mm per rad
    band: np.ndarray  # banded Hessian of the Lagrangian
    jac_t: np.ndarray  # (n, 3)
    constraint: np.ndarray  # x_N - end point, mm (zero for a free tip)
    residual: float
    constrained: bool  # False for a free tip


def end_frame_of(clamps: Clamps, state: RodState) -> np.ndarray:
    """The end fitting frame including the free roll accumulated in the state (identity for a free tip)."""
    if not clamps.end_clamped:
        return np.eye(3)
    if not clamps.roll_free:
        return clamps.end_frame
    return roll_frame(clamps.end_frame, state.roll)


@njit(cache=True)
def roll_frame(frame, roll):
    """The frame turned by `roll` (rad) about its own d3."""
    if roll == 0.0:
        return frame
    turn = rotation_matrix(roll * frame[2])
    out = np.empty((3, 3))
    for k in range(3):  # every director d -> turn d, written out (a matrix product compiles Numba's BLAS glue)
        for x in range(3):
            out[k, x] = turn[x, 0] * frame[k, 0] + turn[x, 1] * frame[k, 1] + turn[x, 2] * frame[k, 2]
    return out


@njit(cache=True)
def relative_residual(grad_max, gap, force, line_weight, largest_stiffness, length):
    """The residual relative to the rod's scales: the largest moment residual (N*mm) over the moment scale of the
    stiffness, the end force (N) and the weight (N/mm), or the end-position gap (mm) over the length, the larger."""
    weight = math.sqrt(line_weight[0] ** 2 + line_weight[1] ** 2 + line_weight[2] ** 2)
    scale = largest_stiffness / length + (math.sqrt(force[0] ** 2 + force[1] ** 2 + force[2] ** 2) + weight * length) * length
    return max(grad_max / scale, gap / length)
