"""Newton's method for the rod's equilibrium: stationary energy under the end-position constraint.

Unknowns: a small world rotation of every segment frame (plus the end roll when it is
free) and the end-mount force mu (Lagrange multiplier of x_N = end point).  Each
iteration solves the bordered banded system of banded.py, so the cost is linear in N.

Two modes:
- tracking (the default for continuation): plain Newton steps, halved while they do not
  reduce the residual;
- minimising: when the Hessian on the constraint tangent space has negative directions,
  a multiple of the identity is added until it has none (inertia correction), and steps
  must lower the augmented Lagrangian; this walks downhill to a stable equilibrium instead
  of converging to a saddle (used to leave an unstable branch).

Convergence is on the force and moment balance: the largest moment residual divided by a
moment scale, and the end-position error divided by the length, both below `tolerance`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from hoseline.mechanics.banded import banded_matvec, kkt_solve, ldlt_banded, ldlt_solve
from hoseline.mechanics.energy import BANDWIDTH, assemble
from hoseline.mechanics.rod import Clamps, RodState, centerline, constraint_jacobian_t, segment_loads
from hoseline.mechanics.rotations import rotate_frames
from hoseline.mechanics.rod_system import (NewtonReport, RodProperties, System, end_frame_of, relative_residual,
                                           roll_frame)


@njit(cache=True)
def _system_kernel(
    frames, start_point, start_frame, end_point, end_frame, stiffness, h, force, line_weight, roll_free, end_clamped,
    springs, rest, braid,
):
    """One pass over the rod: loads, energy, gradient, banded Hessian, constraint and its Jacobian."""
    n_seg = frames.shape[0]
    n = 3 * n_seg + (1 if roll_free else 0)
    grad = np.empty(n)
    band = np.empty((n, BANDWIDTH + 1))
    loads = segment_loads(frames, force, line_weight, h)
    elastic, _ = assemble(frames, start_frame, end_frame, stiffness, h, loads, roll_free, grad, band, end_clamped,
                          springs, rest, braid)
    jac_t = np.zeros((n, 3))
    tip = start_point.copy()
    weight_potential = 0.0
    for i in range(n_seg):
        for k in range(3):
            weight_potential -= h * line_weight[k] * (tip[k] - start_point[k] + 0.5 * h * frames[i, 2, k])
            tip[k] += h * frames[i, 2, k]
    if end_clamped:
        block = constraint_jacobian_t(frames, h)
        for r in range(3 * n_seg):  # element by element: a slice assignment compiles Numba's shape-error messages
            for k in range(3):
                jac_t[r, k] = block[r, k]
        constraint = tip - end_point
    else:
        constraint = np.zeros(3)
        for k in range(3):
            weight_potential -= force[k] * (tip[k] - start_point[k])  # potential of the dead tip load
    grad_max = 0.0
    for value in grad:
        grad_max = max(grad_max, abs(value))
    gap = max(abs(constraint[0]), abs(constraint[1]), abs(constraint[2]))
    return elastic + weight_potential, grad, band, jac_t, constraint, grad_max, gap


def evaluate(props: RodProperties, clamps: Clamps, state: RodState) -> System:
    """Assemble the Lagrangian's gradient and Hessian, the constraint and the residual at a state."""
    if clamps.clips:
        from hoseline.mechanics import clipped_newton  # it builds on this module

        _refuse_preset_with_clips(props)
        return clipped_newton.evaluate(props, clamps, state)
    roll_free = clamps.roll_free and clamps.end_clamped
    force = state.end_force if clamps.end_clamped else clamps.end_load
    end_point = clamps.end_point if clamps.end_clamped else clamps.start_point
    energy, grad, band, jac_t, constraint, grad_max, gap = _system_kernel(
        state.frames,
        clamps.start_point,
        clamps.start_frame,
        end_point,
        end_frame_of(clamps, state),
        props.stiffness,
        props.segment_length,
        force,
        clamps.line_weight,
        roll_free,
        clamps.end_clamped,
        props.springs,
        props.rest,
        props.braid,
    )
    force = state.end_force if clamps.end_clamped else clamps.end_load
    residual = relative_residual(grad_max, gap, force, clamps.line_weight, props.largest_stiffness, props.length)
    return System(energy, grad, band, jac_t, constraint, residual, clamps.end_clamped)


@njit(cache=True)
def _step_kernel(band, jac_t, grad, constraint, shift, constrained):
    lower, diag, negative, tiny = ldlt_banded(band, shift)
    if constrained:
        step, force_step, unstable = kkt_solve(lower, diag, negative, jac_t, grad, constraint)
        return step, force_step, unstable, tiny
    step = -ldlt_solve(lower, diag, grad)
    return step, np.zeros(3), negative, tiny


def total_energy(props: RodProperties, clamps: Clamps, state: RodState) -> float:
    """Elastic plus gravity energy, N*mm."""
    return evaluate(props, clamps, state).energy


def apply_step(props: RodProperties, clamps: Clamps, state: RodState, step: np.ndarray, force_step: np.ndarray) -> RodState:
    """A new state: every frame rotated by its part of `step` (rad), roll advanced, force updated (N)."""
    if clamps.clips:
        from hoseline.mechanics import clipped_newton

        return clipped_newton.apply_step(props, clamps, state, step, force_step)
    n_seg = props.segments
    frames = rotate_frames(state.frames, step[: 3 * n_seg].reshape(n_seg, 3))
    roll = state.roll + (float(step[3 * n_seg]) if step.size > 3 * n_seg else 0.0)
    return RodState(frames, state.end_force + force_step, roll)


def solve_equilibrium(
    props: RodProperties,
    clamps: Clamps,
    state: RodState,
    *,
    tolerance: float = 1e-11,
    max_iterations: int = 25,
    minimise: bool = False,
) -> tuple[RodState, NewtonReport]:
    """Newton iterations from `state` to an equilibrium under `clamps`.

    Returns the final state and a report; the state is only meaningful when report.converged.
    tolerance: relative residual of force and moment balance.  minimise: see module doc.
    With clips (clamps.clips) the iteration is that of mechanics/clipped_newton.py.
    """
    try:
        return _solve_equilibrium(props, clamps, state, tolerance, max_iterations, minimise)
    except ZeroDivisionError:  # compiled code raises it where a joint or the system is exactly singular
        return state, NewtonReport(False, 0, math.inf, -1, "division by zero (an exactly singular joint or system)")


def _solve_equilibrium(props, clamps, state, tolerance, max_iterations, minimise):
    """solve_equilibrium without the guard."""
    if clamps.clips:
        from hoseline.mechanics import clipped_newton

        _refuse_preset_with_clips(props)
        return clipped_newton.solve_equilibrium(
            props, clamps, state, tolerance=tolerance, max_iterations=max_iterations, minimise=minimise
        )
    kernel = _minimise_kernel if minimise else _track_kernel
    roll_free = clamps.roll_free and clamps.end_clamped
    frames, force, roll, converged, iterations, residual, unstable, failure = kernel(
        state.frames,
        state.end_force if clamps.end_clamped else clamps.end_load,
        state.roll,
        clamps.start_point,
        clamps.start_frame,
        clamps.end_point if clamps.end_clamped else clamps.start_point,
        clamps.end_frame if clamps.end_clamped else np.eye(3),
        props.stiffness,
        props.segment_length,
        clamps.line_weight,
        roll_free,
        clamps.end_clamped,
        props.largest_stiffness,
        tolerance,
        max_iterations,
        props.springs,
        props.rest,
        props.braid,
    )
    message = ("", "non-finite residual", "no acceptable step found", "iteration limit reached")[failure]
    new_state = RodState(frames, force if clamps.end_clamped else state.end_force, roll)
    return new_state, NewtonReport(bool(converged), int(iterations), float(residual), int(unstable), message)


def _refuse_preset_with_clips(props: RodProperties) -> None:
    """The clipped rod (mechanics/clipped.py) has no preset or braid terms: refuse rather than ignore them."""
    if props.rest is not None:
        raise ValueError("a preset hose with clips is not implemented: remove the preset keys or the clips")
    if props.braid is not None:
        raise ValueError("a braided hose with clips is not implemented: remove [hose.braid] or the clips")


@njit(cache=True)
def _state_system(
    frames, force, roll, start_point, start_frame, end_point, end_frame, stiffness, h, line_weight,
    roll_free, end_clamped, largest_stiffness, springs, rest, braid,
):
    """_system_kernel at a state with the end frame turned by `roll`, plus its relative residual."""
    energy, grad, band, jac_t, constraint, grad_max, gap = _system_kernel(
        frames, start_point, start_frame, end_point, roll_frame(end_frame, roll), stiffness, h, force, line_weight,
        roll_free, end_clamped, springs, rest, braid,
    )
    residual = relative_residual(grad_max, gap, force, line_weight, largest_stiffness, h * frames.shape[0])
    return energy, grad, band, jac_t, constraint, residual


@njit(cache=True)
def _track_kernel(
    frames, force, roll, start_point, start_frame, end_point, end_frame, stiffness, h, line_weight,
    roll_free, end_clamped, largest_stiffness, tolerance, max_iterations, springs, rest, braid,
):
    """Plain Newton iterations with step halving, all in compiled code (see solve_equilibrium).

    Returns (frames, force, roll, converged, iterations, residual, unstable, failure) with
    failure 0 = none, 1 = non-finite, 2 = line search failed, 3 = iteration limit.
    """
    n_seg = frames.shape[0]
    _, grad, band, jac_t, constraint, residual = _state_system(
        frames, force, roll, start_point, start_frame, end_point, end_frame, stiffness, h, line_weight,
        roll_free, end_clamped, largest_stiffness, springs, rest, braid,
    )
    unstable = -1
    for iteration in range(max_iterations + 1):
        if not np.isfinite(residual):
            return frames, force, roll, False, iteration, residual, -1, 1
        step, force_step, unstable, _ = _step_kernel(band, jac_t, grad, constraint, 0.0, end_clamped)
        if residual <= tolerance:
            return frames, force, roll, True, iteration, residual, unstable, 0
        if iteration == max_iterations:
            break
        alpha = 1.0
        accepted = False
        for _ in range(8):
            trial_frames = rotate_frames(frames, (alpha * step[: 3 * n_seg]).reshape(n_seg, 3))
            trial_force = force + alpha * force_step
            trial_roll = roll + (alpha * step[3 * n_seg] if roll_free else 0.0)
            _, t_grad, t_band, t_jac_t, t_constraint, trial_residual = _state_system(
                trial_frames, trial_force, trial_roll, start_point, start_frame, end_point, end_frame, stiffness, h,
                line_weight, roll_free, end_clamped, largest_stiffness, springs, rest, braid,
            )
            if trial_residual < (1.0 - 1e-4 * alpha) * residual or trial_residual <= tolerance:
                accepted = True
                break
            alpha *= 0.5
        if not accepted:
            return frames, force, roll, False, iteration + 1, residual, unstable, 2
        frames, force, roll = trial_frames, trial_force, trial_roll
        grad, band, jac_t, constraint, residual = t_grad, t_band, t_jac_t, t_constraint, trial_residual
    return frames, force, roll, False, max_iterations, residual, -1, 3


@njit(cache=True)
def _minimise_kernel(
    frames, force, roll, start_point, start_frame, end_point, end_frame, stiffness, h, line_weight,
    roll_free, end_clamped, largest_stiffness, tolerance, max_iterations, springs, rest, braid,
):
    """Levenberg-Marquardt / trust-region Newton that only accepts steps lowering the energy.

    The Hessian is shifted by sigma*I, sigma at least large enough for a positive definite
    Hessian on the tangent space; sigma shrinks after good steps (ratio of actual to predicted
    decrease > 0.75) and grows after poor ones, so the method ends as plain Newton at a
    stable minimum.  The merit is the Lagrangian (with the current end force) plus a penalty
    on the end-position error large enough that the predicted change is a decrease.
    Returns like _track_kernel; failure 2 means no descent step was found.
    """
    n_seg = frames.shape[0]
    energy, grad, band, jac_t, constraint, residual = _state_system(
        frames, force, roll, start_point, start_frame, end_point, end_frame, stiffness, h, line_weight,
        roll_free, end_clamped, largest_stiffness, springs, rest, braid,
    )
    diag_scale = 0.0
    for i in range(band.shape[0]):
        diag_scale = max(diag_scale, abs(band[i, 0]))
    sigma_floor = 1e-10 * diag_scale
    sigma = 0.0
    penalty = 0.0
    for iteration in range(max_iterations + 1):
        if not np.isfinite(residual):
            return frames, force, roll, False, iteration, residual, -1, 1
        step, force_step, unstable, _ = _step_kernel(band, jac_t, grad, constraint, 0.0, end_clamped)
        if residual <= tolerance:
            return frames, force, roll, True, iteration, residual, unstable, 0
        if iteration == max_iterations:
            break
        plain_newton = unstable == 0 and sigma == 0.0 and residual < 1e-6
        base_constraint = constraint[0] ** 2 + constraint[1] ** 2 + constraint[2] ** 2
        accepted = False
        for _ in range(40):
            if not plain_newton and (sigma > 0.0 or unstable != 0):
                sigma = max(sigma, sigma_floor)
                step, force_step, shifted_unstable, _ = _step_kernel(band, jac_t, grad, constraint, sigma, end_clamped)
                if shifted_unstable != 0:
                    sigma *= 10.0
                    continue
            trial_frames = rotate_frames(frames, step[: 3 * n_seg].reshape(n_seg, 3))
            trial_force = force + force_step
            trial_roll = roll + (step[3 * n_seg] if roll_free else 0.0)
            t_energy, t_grad, t_band, t_jac_t, t_constraint, trial_residual = _state_system(
                trial_frames, trial_force, trial_roll, start_point, start_frame, end_point, end_frame, stiffness, h,
                line_weight, roll_free, end_clamped, largest_stiffness, springs, rest, braid,
            )
            if plain_newton:
                # close to a stable minimum: plain Newton, judged by the residual
                if trial_residual < residual:
                    accepted = True
                    break
                plain_newton = False
                sigma = sigma_floor
                continue
            model = grad @ step + 0.5 * (step @ banded_matvec(band, step))
            if base_constraint > 0.0:
                penalty = max(penalty, 2.0 * max(model, 0.0) / base_constraint + 1e-8 * diag_scale)
            predicted = model - 0.5 * penalty * base_constraint
            base = energy - force @ constraint + 0.5 * penalty * base_constraint
            trial_constraint = t_constraint[0] ** 2 + t_constraint[1] ** 2 + t_constraint[2] ** 2
            actual = t_energy - force @ t_constraint + 0.5 * penalty * trial_constraint - base
            rounding = 1e-13 * (abs(base) + diag_scale)
            if predicted < -rounding:
                ratio = actual / predicted
            else:
                ratio = 1.0 if actual <= rounding else -1.0
            if ratio > 0.1 or trial_residual <= tolerance:
                if ratio > 0.75:
                    sigma = 0.0 if sigma <= sigma_floor * 4.0 else sigma / 4.0
                accepted = True
                break
            sigma = max(4.0 * sigma, 1e-4 * diag_scale)
        if not accepted:
            return frames, force, roll, False, iteration + 1, residual, unstable, 2
        frames, force, roll = trial_frames, trial_force, trial_roll
        energy, grad, band, jac_t, constraint, residual = t_energy, t_grad, t_band, t_jac_t, t_constraint, trial_residual
    return frames, force, roll, False, max_iterations, residual, -1, 3


def node_positions(props: RodProperties, clamps: Clamps, state: RodState) -> np.ndarray:
    """Centreline nodes (N+1, 3), mm."""
    return centerline(state.frames, clamps.start_point, props.segment_length)
