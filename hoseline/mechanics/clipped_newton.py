"""Newton's method for the rod with clips (mechanics/clipped.py): the same two modes as newton.py.

newton.evaluate, newton.solve_equilibrium and newton.apply_step hand a problem with clips
(Clamps.clips not empty) to this module.  The iteration is the one of newton.py's compiled
kernels, driven from Python (a few tens of microseconds per iteration, small next to the
assembly and the factorisation at a hundred segments): tracking Newton with step halving, and
the minimising Levenberg-Marquardt variant that only walks downhill.  The border has 3 + 3c
rows (mechanics/bordered.py); the end of the rod must be clamped.

Sliding clips: each adds its arc length sigma (mm) as an unknown (clipped.stretch_terms).  Its
Hessian column couples to every segment of the two spans next to the clip, so it joins the
border instead of the band: the border is [J^T, d2L/dy dsigma] with the corner
[[0, dc/dsigma], [dc/dsigma^T, d2L/dsigma2]], and the step solves (B^T H^-1 B - C) z = ... by
banded.ldlt_solve on the m + s + 1 columns (SlidingSystem, _step).  A step vector is then the
n band unknowns followed by the s arc-length steps (mm); apply_step takes either length.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hoseline.mechanics.banded import banded_matvec, ldlt_banded, ldlt_solve
from hoseline.mechanics.bordered import kkt_solve_bordered, tangent_space_inertia
from hoseline.mechanics.clipped import clip_moments, clipped_system, stretch_terms, unknown_layout
from hoseline.mechanics.rod import Clamps, RodState
from hoseline.mechanics.rod_system import NewtonReport, RodProperties, System, relative_residual, roll_frame
from hoseline.mechanics.rotations import rotate_frames


def clip_arrays(clamps: Clamps, state: RodState):
    """The clips as kernel arrays: nodes (c,), points (c, 3) mm, frames (c, 3, 3) with the state's
    roll applied where it is free, framed (c,) bool (False: ball), roll_free (c,) bool."""
    nodes, points, base_frames, framed, roll_free = _packed(clamps.clips)
    frames = base_frames
    if roll_free.any():
        rolls = clip_rolls(clamps, state)
        frames = base_frames.copy()
        for j in np.flatnonzero(roll_free):
            frames[j] = roll_frame(base_frames[j], float(rolls[j]))
    return nodes, points, frames, framed, roll_free


_last_packed: tuple = ((), None)  # the clips last packed and their arrays: one continuation step reuses them


def _packed(clips: tuple) -> tuple:
    # the clips' arrays without the state's rolls, packed once per clips tuple (identity, not equality)
    global _last_packed
    last_clips, arrays = _last_packed
    if last_clips is clips:
        return arrays
    frames = np.empty((len(clips), 3, 3))
    for j, clip in enumerate(clips):
        frames[j] = np.eye(3) if clip.frame is None else clip.frame
    arrays = (
        np.array([clip.node for clip in clips], dtype=np.int64),
        np.array([clip.point for clip in clips], dtype=float).reshape(-1, 3),
        frames,
        np.array([clip.frame is not None for clip in clips], dtype=np.bool_),
        np.array([clip.frame is not None and clip.roll_free for clip in clips], dtype=np.bool_),
    )
    _last_packed = (clips, arrays)
    return arrays


def segment_unknowns(segments: int, clamps: Clamps) -> np.ndarray:
    """Index of each segment's first rotation unknown (N,) in the system of a rod with clips (clipped.unknown_layout)."""
    nodes, _, _, _, roll_free = _packed(clamps.clips)
    return unknown_layout(segments, nodes, roll_free, clamps.roll_free)[0]


SHORTEST_STRETCHED = 0.2  # a segment stretched below this fraction of L/N: the step went too far (refused)


@dataclass
class SlidingSystem(System):
    """System of a rod with sliding clips: the band and jac_t hold the arc lengths fixed; the
    arc-length unknowns (s of them) add stretch_grad (s,) N, mixed (n, s), stretch_hessian (s, s)
    N/mm and stretch_jac (3 + 3c, s), the derivatives of clipped.stretch_terms."""

    stretch_grad: np.ndarray
    mixed: np.ndarray
    stretch_hessian: np.ndarray
    stretch_jac: np.ndarray


def sliding_indices(clamps: Clamps) -> list[int]:
    """Indices of the sliding clips among clamps.clips."""
    return [j for j, clip in enumerate(clamps.clips) if clip.sliding]


def clip_arc_lengths(props: RodProperties, clamps: Clamps, state: RodState) -> np.ndarray:
    """The state's clip arc lengths (c,) mm, or each clip's station (node h) when they do not match."""
    count = len(clamps.clips)
    if state.clip_arc_lengths.shape == (count,):
        return state.clip_arc_lengths
    return np.array([clip.node * props.segment_length for clip in clamps.clips], dtype=float)


def segment_lengths(props: RodProperties, clamps: Clamps, state: RodState) -> tuple[np.ndarray, np.ndarray]:
    """Length of every segment (N,) mm and its rate along each sliding clip's arc length (N, s).

    The held stations (start, the clips, the end) cut the hose into spans; the segments of a span
    share its length equally.  A fixed, rotating or ball clip sits at node h, so without sliding
    clips every segment is L/N long; a sliding clip at arc length sigma on node k stretches the
    spans on either side of it."""
    n_seg, h = props.segments, props.segment_length
    sliding = {j: column for column, j in enumerate(sliding_indices(clamps))}
    if not sliding:  # every clip on its station: all segments L/N (the common case, kept cheap)
        return np.full(n_seg, h), np.zeros((n_seg, 0))
    arc = clip_arc_lengths(props, clamps, state)
    knots = [(0, 0.0, -1)] + [(clip.node, float(arc[j]) if clip.sliding else clip.node * h, sliding.get(j, -1))
                               for j, clip in enumerate(clamps.clips)] + [(n_seg, props.length, -1)]
    lengths = np.empty(n_seg)
    rates = np.zeros((n_seg, len(sliding)))
    for (node_a, s_a, slide_a), (node_b, s_b, slide_b) in zip(knots[:-1], knots[1:]):
        count = node_b - node_a
        lengths[node_a:node_b] = (s_b - s_a) / count
        if slide_a >= 0:
            rates[node_a:node_b, slide_a] -= 1.0 / count
        if slide_b >= 0:
            rates[node_a:node_b, slide_b] += 1.0 / count
    return lengths, rates


def clip_rolls(clamps: Clamps, state: RodState) -> np.ndarray:
    """The state's clip rolls (rad), zeros when they do not match the clamps' clips."""
    count = len(clamps.clips)
    return state.clip_rolls if state.clip_rolls.shape == (count,) else np.zeros(count)


def clip_forces(clamps: Clamps, state: RodState) -> np.ndarray:
    """The state's clip forces (c, 3) N, zeros when they do not match the clamps' clips."""
    count = len(clamps.clips)
    return state.clip_forces if state.clip_forces.shape == (count, 3) else np.zeros((count, 3))


def station_positions(props: RodProperties, clamps: Clamps, state: RodState) -> tuple[np.ndarray, np.ndarray]:
    """Arc length (N+1,) mm and position (N+1, 3) mm of every station, each segment of its own
    length (segment_lengths: sliding clips stretch their spans)."""
    lengths, _ = segment_lengths(props, clamps, state)
    steps = lengths[:, None] * state.frames[:, 2]
    nodes = clamps.start_point + np.concatenate([np.zeros((1, 3)), np.cumsum(steps, axis=0)])
    return np.concatenate([[0.0], np.cumsum(lengths)]), nodes


def _end_frame(clamps: Clamps, state: RodState) -> np.ndarray:
    return roll_frame(clamps.end_frame, state.roll) if clamps.roll_free else clamps.end_frame


def evaluate(props: RodProperties, clamps: Clamps, state: RodState) -> System:
    """newton.evaluate for clamps with clips: the Lagrangian's gradient and Hessian, the 3 + 3c
    constraints (end, then each clip) and their Jacobian, and the relative residual."""
    if not clamps.end_clamped:
        raise ValueError("a rod with clips needs a clamped end (end_point and end_frame)")
    nodes, points, frames, framed, roll_free = clip_arrays(clamps, state)
    forces = np.vstack([state.end_force[None, :], clip_forces(clamps, state)])
    lengths, rates = segment_lengths(props, clamps, state)
    end_frame = _end_frame(clamps, state)
    energy, grad, band, jac_t, constraint, grad_max, gap = clipped_system(
        state.frames, clamps.start_point, clamps.start_frame, clamps.end_point, end_frame,
        clamps.roll_free, nodes, points, frames, framed, roll_free, props.stiffness, lengths, forces,
        clamps.line_weight, props.springs,
    )
    force_scale = np.array([float(np.linalg.norm(forces)), 0.0, 0.0])
    if rates.shape[1] == 0:
        residual = relative_residual(grad_max, gap, force_scale, clamps.line_weight, props.largest_stiffness, props.length)
        return System(energy, grad, band, jac_t, constraint, residual, True)
    if props.springs is not None:
        raise ValueError("a sliding clip with stiffener springs is not supported: the springs' length law is not modelled")
    stretch_grad, mixed, stretch_hessian, stretch_jac = stretch_terms(
        state.frames, clamps.start_point, clamps.start_frame, end_frame, clamps.roll_free, nodes, frames, framed,
        roll_free, props.stiffness, lengths, rates, forces, clamps.line_weight,
    )
    # an arc-length gradient (N) times a segment length is a moment like the others
    grad_max = max(grad_max, float(np.max(np.abs(stretch_grad))) * props.segment_length)
    residual = relative_residual(grad_max, gap, force_scale, clamps.line_weight, props.largest_stiffness, props.length)
    if np.min(lengths) < SHORTEST_STRETCHED * props.segment_length:
        residual = np.inf  # a sliding clip ran onto its neighbour: the step is refused (halved)
    return SlidingSystem(energy, grad, band, jac_t, constraint, residual, True, stretch_grad, mixed, stretch_hessian,
                         stretch_jac)


def apply_step(props: RodProperties, clamps: Clamps, state: RodState, step: np.ndarray, force_step: np.ndarray) -> RodState:
    """newton.apply_step for clamps with clips: step in the chain's unknown order (clipped.py),
    then (optionally) the sliding clips' arc-length steps (mm); force_step (3 + 3c,) N for the end
    and clip forces (or (3,) for the end force alone)."""
    nodes, _, _, _, roll_free = _packed(clamps.clips)
    segment_index, clip_roll_index, end_roll_index, n = unknown_layout(props.segments, nodes, roll_free, clamps.roll_free)
    arc = clip_arc_lengths(props, clamps, state).copy()
    if step.size > n:
        arc[sliding_indices(clamps)] += step[n:]
    rotations = step[segment_index[:, None] + np.arange(3)[None, :]]
    rolls = clip_rolls(clamps, state) + np.where(clip_roll_index >= 0, step[np.maximum(clip_roll_index, 0)], 0.0)
    end_roll = state.roll + (float(step[end_roll_index]) if end_roll_index >= 0 else 0.0)
    forces = np.zeros(3 + 3 * len(clamps.clips))
    forces[: force_step.size] = force_step
    return RodState(
        rotate_frames(state.frames, rotations), state.end_force + forces[:3], end_roll,
        clip_forces(clamps, state) + forces[3:].reshape(-1, 3), rolls, arc,
    )


def _step(system: System, shift: float, arc_shift: float = 0.0):
    """(step, force step, unstable directions) of the bordered Newton system, H shifted by `shift`
    (and the arc-length block by `arc_shift`, for sliding clips; see the module doc)."""
    lower, diag, negative, _ = ldlt_banded(system.band, shift)
    if not isinstance(system, SlidingSystem):
        return kkt_solve_bordered(lower, diag, negative, system.jac_t, system.grad, system.constraint)
    m, s = system.jac_t.shape[1], system.mixed.shape[1]
    border = np.hstack([system.jac_t, system.mixed])
    solved = ldlt_solve(lower, diag, np.hstack([border, system.grad[:, None]]))
    corner = np.zeros((m + s, m + s))
    corner[:m, m:] = system.stretch_jac
    corner[m:, :m] = system.stretch_jac.T
    corner[m:, m:] = system.stretch_hessian + arc_shift * np.eye(s)
    schur = border.T @ solved[:, :-1] - corner
    rhs = border.T @ solved[:, -1] - np.concatenate([system.constraint, system.stretch_grad])
    mu = np.linalg.solve(schur, rhs)
    step = np.concatenate([solved[:, :-1] @ mu - solved[:, -1], -mu[m:]])
    # the constraint rows over the band's unknowns and the arc lengths: the count is on their independent rows
    positive, independent = tangent_space_inertia(schur, np.vstack([system.jac_t, system.stretch_jac.T]))
    return step, mu[:m], int(negative + positive - independent)


def _quadratic(system: System, step: np.ndarray) -> float:
    """The Newton model's change grad . step + step H step / 2 (with the arc-length unknowns if any)."""
    n = system.grad.size
    value = float(system.grad @ step[:n] + 0.5 * (step[:n] @ banded_matvec(system.band, np.ascontiguousarray(step[:n]))))
    if isinstance(system, SlidingSystem):
        arc = step[n:]
        value += float(system.stretch_grad @ arc + step[:n] @ system.mixed @ arc + 0.5 * arc @ system.stretch_hessian @ arc)
    return value


def solve_equilibrium(
    props: RodProperties, clamps: Clamps, state: RodState, *, tolerance: float, max_iterations: int, minimise: bool
) -> tuple[RodState, NewtonReport]:
    """newton.solve_equilibrium for clamps with clips (same arguments and result)."""
    state = RodState(state.frames, state.end_force, state.roll if clamps.roll_free else 0.0,
                     clip_forces(clamps, state), clip_rolls(clamps, state), clip_arc_lengths(props, clamps, state))
    iterate = _minimise if minimise else _track
    return iterate(props, clamps, state, tolerance, max_iterations)


def _report(converged: bool, iterations: int, residual: float, unstable: int, failure: int) -> NewtonReport:
    message = ("", "non-finite residual", "no acceptable step found", "iteration limit reached")[failure]
    return NewtonReport(converged, iterations, float(residual), int(unstable), message)


def _newton(props, clamps, state, tolerance, max_iterations, improve):
    # the iteration both modes share; improve(state, system, step, force_step, unstable) returns the
    # accepted (state, system) or None when it finds no acceptable step
    system = evaluate(props, clamps, state)
    for iteration in range(max_iterations + 1):
        if not np.isfinite(system.residual):
            return state, _report(False, iteration, system.residual, -1, 1)
        step, force_step, unstable = _step(system, 0.0)
        if system.residual <= tolerance:
            return state, _report(True, iteration, system.residual, unstable, 0)
        if iteration == max_iterations:
            break
        moved = improve(state, system, step, force_step, unstable)
        if moved is None:
            return state, _report(False, iteration + 1, system.residual, unstable, 2)
        state, system = moved
    return state, _report(False, max_iterations, system.residual, -1, 3)


def _track(props, clamps, state, tolerance, max_iterations):
    # plain Newton with step halving (newton._track_kernel)
    def halving(state, system, step, force_step, unstable):
        alpha = 1.0
        for _ in range(8):
            trial = apply_step(props, clamps, state, alpha * step, alpha * force_step)
            trial_system = evaluate(props, clamps, trial)
            if trial_system.residual < (1.0 - 1e-4 * alpha) * system.residual or trial_system.residual <= tolerance:
                return trial, trial_system
            alpha *= 0.5
        return None

    return _newton(props, clamps, state, tolerance, max_iterations, halving)


def _minimise(props, clamps, state, tolerance, max_iterations):
    # Levenberg-Marquardt / trust-region Newton accepting only descent of the penalised Lagrangian
    # (newton._minimise_kernel, where the method is described)
    descent = _Descent(props, clamps, tolerance, evaluate(props, clamps, state))
    return _newton(props, clamps, state, tolerance, max_iterations, descent.improve)


class _Descent:
    """The shift sigma and the constraint penalty of the minimising mode, kept between iterations."""

    def __init__(self, props, clamps, tolerance, first: System):
        self.props, self.clamps, self.tolerance = props, clamps, tolerance
        self.diag_scale = float(np.max(np.abs(first.band[:, 0])))
        self.arc_scale = 1.0 / props.segment_length**2  # the shift on an arc length (mm) per shift on a rotation
        self.sigma_floor = 1e-10 * self.diag_scale
        self.sigma = self.penalty = 0.0

    def improve(self, state, system, step, force_step, unstable):
        props, clamps, tolerance, diag_scale = self.props, self.clamps, self.tolerance, self.diag_scale
        plain_newton = unstable == 0 and self.sigma == 0.0 and system.residual < 1e-6
        base_constraint = float(system.constraint @ system.constraint)
        multipliers = np.concatenate([state.end_force, clip_forces(clamps, state).reshape(-1)])
        for _ in range(40):
            if not plain_newton and (self.sigma > 0.0 or unstable != 0):
                self.sigma = max(self.sigma, self.sigma_floor)
                step, force_step, shifted_unstable = _step(system, self.sigma, self.sigma * self.arc_scale)
                if shifted_unstable != 0:
                    self.sigma *= 10.0
                    continue
            trial = apply_step(props, clamps, state, step, force_step)
            trial_system = evaluate(props, clamps, trial)
            if plain_newton:
                if trial_system.residual < system.residual:
                    return trial, trial_system
                plain_newton = False
                self.sigma = self.sigma_floor
                continue
            model = _quadratic(system, step)
            if base_constraint > 0.0:
                self.penalty = max(self.penalty, 2.0 * max(model, 0.0) / base_constraint + 1e-8 * diag_scale)
            predicted = model - 0.5 * self.penalty * base_constraint
            base = system.energy - multipliers @ system.constraint + 0.5 * self.penalty * base_constraint
            trial_constraint = float(trial_system.constraint @ trial_system.constraint)
            actual = trial_system.energy - multipliers @ trial_system.constraint + 0.5 * self.penalty * trial_constraint - base
            rounding = 1e-13 * (abs(base) + diag_scale)
            ratio = actual / predicted if predicted < -rounding else (1.0 if actual <= rounding else -1.0)
            if ratio > 0.1 or trial_system.residual <= tolerance:
                if ratio > 0.75:
                    self.sigma = 0.0 if self.sigma <= self.sigma_floor * 4.0 else self.sigma / 4.0
                return trial, trial_system
            self.sigma = max(4.0 * self.sigma, 1e-4 * diag_scale)
        return None


def clip_reactions(props: RodProperties, clamps: Clamps, state: RodState) -> tuple[np.ndarray, np.ndarray]:
    """Force (c, 3) N and moment (c, 3) N*mm (about the clip point, world) of each clip on the hose."""
    nodes, _, frames, framed, _ = clip_arrays(clamps, state)
    lengths, _ = segment_lengths(props, clamps, state)
    moments = clip_moments(state.frames, nodes, frames, framed, props.stiffness, lengths, props.springs)
    return clip_forces(clamps, state).copy(), moments


def smallest_sliding_eigenvalue(system: SlidingSystem, segment_length: float) -> float:
    """The smallest eigenvalue (N*mm/rad^2) of the Hessian on the constraint tangent space with the
    arc lengths free, each measured in segments (sigma / h, like a rotation in rad).  Dense: the
    arc-length columns are dense; a sliding clip's hose is a few hundred unknowns (milliseconds)."""
    import scipy.linalg

    from hoseline.mechanics.banded import band_to_dense

    h = segment_length
    hess = np.block([[band_to_dense(system.band), h * system.mixed],
                     [h * system.mixed.T, h * h * system.stretch_hessian]])
    basis = scipy.linalg.null_space(np.hstack([system.jac_t.T, h * system.stretch_jac]))
    return float(np.linalg.eigvalsh(basis.T @ hess @ basis)[0])

