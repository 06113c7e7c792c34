"""Natural-parameter continuation of the rod's equilibrium along a path of clamps.

A path maps a fraction t in [0, 1] to the clamps at that fraction.  Each step starts
from the previous equilibrium; a step that does not converge is halved.  After every
converged step the stability of the equilibrium is checked (inertia of the Hessian on
the constraint tangent space).  When it is lost, the crossing is bracketed, the state is
pushed along the critical eigenvector(s) to both sides and relaxed downhill, and the
lowest stable result is followed on: the branch a real, slowly moved hose takes.
Every such event is logged.  A path that cannot be followed raises PlacementError
naming the phase, the fraction and the residual; nothing unconverged is returned.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from hoseline.mechanics.newton import (
    NewtonReport,
    RodProperties,
    apply_step,
    evaluate,
    node_positions,
    solve_equilibrium,
    total_energy,
)
from hoseline.mechanics.rod import Clamps, RodState
from hoseline.mechanics.rotations import extrapolate_frames
from hoseline.mechanics.stability import smallest_eigenpairs

Path = Callable[[float], Clamps]
Progress = Callable[[str, float], None]


class PlacementError(RuntimeError):
    """The placement could not be completed; the message says in which phase, where and why."""


EQUAL_ENERGY = 1e-9  # relative to the energy: energies closer than this are equal (rounding)


@dataclass
class Fork:
    """A fork met along a path: several distinct stable equilibria next to each other, one taken.

    phase, fraction: where (the path's name and its fraction in [0, 1]).  others: the stable
    states not taken, in order of energy.  energy_gaps: their energy above the one taken, N*mm.
    equal_energy: the nearest other is of equal energy (a symmetric fork: rounding could have
    taken either side).  step: the step (a fraction of the path) the path took on from the fork, which its
    other branches are followed with too; None where the path went on with its first step.
    """

    phase: str
    fraction: float
    others: list[RodState]
    energy_gaps: list[float]
    step: float | None = None

    @property
    def equal_energy(self) -> bool:
        return bool(self.energy_gaps) and self.energy_gaps[0] == 0.0

    def describe(self) -> str:
        """One sentence for the result's forks on the path."""
        kind = "a symmetric fork (branches of equal energy)" if self.equal_energy else "a fork"
        gaps = ", ".join(f"{gap:.4g}" for gap in self.energy_gaps)
        return (f"{self.phase} at fraction {self.fraction:.4f}: {kind}; took the branch of lowest energy, "
                f"{len(self.others)} other stable branch(es) {gaps} N*mm higher")


@dataclass
class ContinuationLog:
    """Counters, events and the forks met, accumulated over all phases."""

    iterations: int = 0
    steps: int = 0
    events: list[str] = field(default_factory=list)
    forks: list[Fork] = field(default_factory=list)

    def record_fork(self, phase: str, fraction: float, props: "RodProperties", clamps: Clamps,
                    distinct: list[RodState]) -> None:
        """Note a fork when relax_to_stable found more than one distinct stable state (the first is the one taken)."""
        if len(distinct) < 2:
            return
        energies = [total_energy(props, clamps, state) for state in distinct]
        scale = max(abs(energies[0]), 1e-300)
        gaps = [max(0.0, energy - energies[0]) for energy in energies[1:]]
        gaps = [0.0 if gap <= EQUAL_ENERGY * scale else gap for gap in gaps]
        self.forks.append(Fork(phase, fraction, distinct[1:], gaps))


@dataclass(frozen=True)
class StepControl:
    """Continuation step sizes (fractions of the path) and the Newton tolerances (relative residuals)."""

    first: float = 0.1
    largest: float = 0.25
    smallest: float = 1e-4
    tolerance: float = 1e-11  # at the end of each phase
    path_tolerance: float = 1e-8  # at the intermediate steps (they only carry the path)
    fast_iterations: int = 4  # a step that converges within this many iterations lets the next one grow
    largest_correction: float = 0.3  # of the predicted move: a larger Newton correction halves the step


def relax_to_stable(
    props: RodProperties, clamps: Clamps, candidates: list[RodState], log: ContinuationLog
) -> tuple[RodState, list[RodState]] | None:
    """Relax the candidates to equilibria; return the stable one of lowest energy and all
    distinct stable ones found (for reporting non-uniqueness), or None if none is stable.

    Plain Newton from every candidate first; only if none of them ends at a stable state is
    each walked downhill by the minimising Newton (which cannot stop at a saddle unless the
    candidate lies exactly on its symmetric ridge).
    """
    stable: list[tuple[float, RodState]] = []
    downhill: list[RodState] = []
    for candidate in candidates:  # plain Newton first: cheap, and enough when it ends at a stable state
        state, report = solve_equilibrium(props, clamps, candidate, max_iterations=12)
        log.iterations += report.iterations
        if report.converged and report.unstable_directions == 0:
            stable.append((total_energy(props, clamps, state), state))
        else:
            downhill.append(candidate)
    if not stable:  # no candidate settled on a stable state: walk downhill from each
        for candidate in downhill:
            state, report = solve_equilibrium(props, clamps, candidate, minimise=True, max_iterations=80)
            log.iterations += report.iterations
            if report.converged and report.unstable_directions == 0:
                stable.append((total_energy(props, clamps, state), state))
    if not stable:
        return None
    # lowest energy first; energies within 1e-9 count as equal and keep the candidates' order, so
    # rounding cannot decide between the two sides of a symmetric fork
    lowest = min(energy for energy, _ in stable)
    tie = EQUAL_ENERGY * max(abs(lowest), 1e-300)
    stable = [pair for _, pair in sorted(enumerate(stable), key=lambda item: (round((item[1][0] - lowest) / tie), item[0]))]
    distinct: list[tuple[float, RodState]] = []
    for energy, state in stable:
        nodes = node_positions(props, clamps, state)
        if all(np.max(np.abs(nodes - node_positions(props, clamps, other))) > 1e-6 * props.length for _, other in distinct):
            distinct.append((energy, state))
    return stable[0][1], [state for _, state in distinct]


def push_along_modes(props: RodProperties, clamps: Clamps, state: RodState, count: int) -> list[RodState]:
    """States displaced to both sides along the `count` lowest eigenvectors (0.05 rad at most)."""
    system = evaluate(props, clamps, state)
    _, vectors = smallest_eigenpairs(system.band, system.jac_t, count=count, tolerance=1e-3)  # a direction to push along
    n_rot = 3 * props.segments
    pushed = []
    for j in range(vectors.shape[1]):
        mode = vectors[:, j]
        amplitude = 0.05 / max(np.max(np.abs(mode[:n_rot])), 1e-12)
        for sign in (1.0, -1.0):
            step = sign * amplitude * mode
            pushed.append(apply_step(props, clamps, state, step, np.zeros(3)))
    return pushed


def follow(
    phase: str,
    path: Path,
    props: RodProperties,
    state: RodState,
    log: ContinuationLog,
    *,
    start: float = 0.0,
    control: StepControl = StepControl(),
    progress: Progress | None = None,
) -> RodState:
    """Follow the equilibrium from fraction `start` (where `state` is in equilibrium) to 1."""
    t = start
    dt = min(control.first, 1.0 - t)
    last_failure: NewtonReport | None = None
    previous: tuple[float, RodState] | None = None  # for the secant predictor
    while t < 1.0 - 1e-14:
        t_next = min(1.0, t + dt)
        clamps = path(t_next)
        guess = state if previous is None else secant(previous, (t, state), t_next)
        tolerance = control.tolerance if t_next == 1.0 else control.path_tolerance
        trial, report = solve_equilibrium(props, clamps, guess, tolerance=tolerance)
        if not report.converged and guess is not state:
            log.iterations += report.iterations
            trial, report = solve_equilibrium(props, clamps, state, tolerance=tolerance)
        log.iterations += report.iterations
        predicted = previous is not None
        if report.converged and predicted and dt > 4.0 * control.smallest and _moved_off(props, clamps, state, guess, trial, control):
            dt *= 0.5  # Newton went far from the prediction: a smaller step, so no branch is skipped
            continue
        if not report.converged:
            last_failure = report
            dt *= 0.5
            if dt < control.smallest:
                state = _snap_or_fail(phase, path, props, state, t, t + 2 * dt, log, last_failure)
                t = t + 2 * dt
                dt = control.first
                previous = None
            continue
        log.steps += 1
        previous = (t, state)
        forks = len(log.forks)
        if report.unstable_directions != 0:
            trial, t_next = _leave_unstable_branch(phase, path, props, state, t, trial, t_next, report, log, control)
            previous = None  # a branch switch breaks the secant
        state, t = trial, t_next
        if progress is not None:
            progress(phase, t)
        if report.iterations <= control.fast_iterations:
            dt = min(control.largest, dt * 2.0)
        if len(log.forks) > forks:
            log.forks[-1].step = dt
    return state


def _moved_off(
    props: RodProperties, clamps: Clamps, start: RodState, guess: RodState, trial: RodState, control: StepControl
) -> bool:
    """True when Newton's correction of the secant prediction is large: more than
    control.largest_correction of the predicted move (and more than 1e-3 L).  Near a fork of the
    path the prediction fails first; a smaller step then keeps the fork from being stepped over."""
    start_nodes = node_positions(props, clamps, start)
    guess_nodes = node_positions(props, clamps, guess)
    correction = float(np.max(np.abs(node_positions(props, clamps, trial) - guess_nodes)))
    predicted = float(np.max(np.abs(guess_nodes - start_nodes)))
    return correction > max(control.largest_correction * predicted, 1e-3 * props.length)


def secant(previous: tuple[float, RodState], current: tuple[float, RodState], t_next: float) -> RodState:
    """Linear extrapolation of the equilibrium path, given at two fractions (fraction, state), to t_next (frames on
    the rotation group)."""
    (t0, s0), (t1, s1) = previous, current
    ratio = (t_next - t1) / (t1 - t0)
    frames = extrapolate_frames(s0.frames, s1.frames, ratio)
    clip_forces, clip_rolls, clip_arcs = s1.clip_forces, s1.clip_rolls, s1.clip_arc_lengths
    if s0.clip_forces.shape == clip_forces.shape and s0.clip_rolls.shape == clip_rolls.shape:
        clip_forces = clip_forces + ratio * (clip_forces - s0.clip_forces)
        clip_rolls = clip_rolls + ratio * (clip_rolls - s0.clip_rolls)
    if s0.clip_arc_lengths.shape == clip_arcs.shape:  # sliding clips' arc lengths (the others stay put)
        clip_arcs = clip_arcs + ratio * (clip_arcs - s0.clip_arc_lengths)
    return RodState(frames, s1.end_force + ratio * (s1.end_force - s0.end_force), s1.roll + ratio * (s1.roll - s0.roll),
                    clip_forces, clip_rolls, clip_arcs)


def _leave_unstable_branch(phase, path, props, state, t, trial, t_next, report, log, control):
    """The step from t to t_next ended on an unstable equilibrium: bracket the loss of
    stability, then move to the lowest stable equilibrium next to it."""
    stable_t, stable_state = t, state
    unstable_t = t_next
    for _ in range(2):  # bracket the crossing (for the report) to 1/4 of the step
        middle = 0.5 * (stable_t + unstable_t)
        mid_state, mid_report = solve_equilibrium(props, path(middle), stable_state, tolerance=control.path_tolerance)
        log.iterations += mid_report.iterations
        if not mid_report.converged:
            break
        if mid_report.unstable_directions == 0:
            stable_t, stable_state = middle, mid_state
        else:
            unstable_t = middle
    # relax at the end of the step, not at the bracketed crossing: right at the crossing the new
    # branch is degenerate (zero eigenvalue) and Newton slows down; the branch is the same one.
    clamps = path(t_next)
    count = max(1, report.unstable_directions)
    candidates = push_along_modes(props, clamps, trial, count)
    relaxed = relax_to_stable(props, clamps, candidates, log)
    if relaxed is None:
        raise PlacementError(
            f"placement phase '{phase}': the equilibrium lost stability between fractions {stable_t:.4f} and "
            f"{unstable_t:.4f} and no stable equilibrium was found next to it"
        )
    best, distinct = relaxed
    log.record_fork(phase, t_next, props, clamps, distinct)
    before = node_positions(props, clamps, trial)
    after = node_positions(props, clamps, best)
    jump = float(np.max(np.linalg.norm(after - before, axis=1)))
    sides = f"{len(distinct)} stable sides; took the one of lowest energy" if len(distinct) > 1 else "one stable side"
    log.events.append(
        f"{phase}: stability lost between fractions {stable_t:.4f} and {unstable_t:.4f} "
        f"({report.unstable_directions} unstable direction(s)); moved to the stable branch along the critical "
        f"mode ({sides}); largest station movement {jump:.3f} mm"
    )
    return best, t_next


def _snap_or_fail(phase, path, props, state, t, t_target, log, failure):
    """Steps kept failing: the branch may end in a fold (the hose snaps).  Look for a stable
    equilibrium downhill at the next fraction; fail with a clear message if there is none."""
    t_target = min(1.0, t_target)
    clamps = path(t_target)
    relaxed = relax_to_stable(props, clamps, [state], log)
    if relaxed is None:
        raise PlacementError(
            f"placement phase '{phase}' failed at fraction {t_target:.4f} (last converged {t:.4f}): "
            f"Newton residual {failure.residual:.2e} after {failure.iterations} iterations ({failure.message}), "
            "and no stable equilibrium could be found by energy descent"
        )
    best, _ = relaxed
    jump = float(np.max(np.linalg.norm(node_positions(props, clamps, best) - node_positions(props, clamps, state), axis=1)))
    log.events.append(
        f"{phase}: the equilibrium branch ended near fraction {t:.4f} (fold); the hose snaps to a stable "
        f"equilibrium {jump:.3f} mm away"
    )
    return best
