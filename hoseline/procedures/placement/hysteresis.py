"""The hysteresis band of a twisted hose: its shape twisted up and back down, station by station.

Two models, documented in docs/model.md (Hysteresis):

Elastic (hysteresis_band without a friction threshold).  At a given twist every stable
equilibrium is a state of the same energy landscape; the shape on the way down differs from
the shape on the way up only where the landscape has more than one stable state and the
continuation followed a different one (after a fold: a snap-through on the way up that does
not snap back at the same twist on the way down).  The placed hose is twisted from 0 up to
the largest angle and back to 0 by continuation (twist_path.follow_twist, with its stability
checks).  Without a fold the band is zero (to the solver's tolerance).

Internal friction (friction_threshold given).  Each joint is elastic-perfectly plastic: its
moment, taken as K (kappa - kappa0) (stiffness times the joint's Darboux vector relative to
its stress-free rotation, the leading-order joint moment), cannot exceed the threshold in
magnitude; where the equilibrium would exceed it, the stress-free rotation (the preset, see
model/preset.py) slides along so that the moment is brought back radially onto the threshold
(associated flow, backward Euler: the equilibrium and the return are iterated at each twist
step until no joint exceeds the threshold).  The stored preset is the state variable: the
hose keeps a set after it is twisted up and down, so it does not return to its first shape.
One parameter, the threshold in N*mm, fitted to scans taken on the way up and on the way down
(fit_friction_threshold); it is identified only when the scans show a band larger than their
scatter and the path moves some joint past the threshold.  Assumed: the placed hose at 0 deg is
the elastic shape after its joints are returned to the threshold (the friction during assembly
follows a path nobody records), a threshold equal for bending and twisting, no hardening.
The band is reported between the two ways at every twist.  Units: degrees, mm, N*mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from hoseline.mechanics.newton import RodProperties, node_positions, solve_equilibrium
from hoseline.mechanics.rod import RodState
from hoseline.model.preset import rest_rotations
from hoseline.model.problem import Problem
from hoseline.procedures.placement.path import PlacementPath
from hoseline.procedures.placement.sequence import rod_properties, solve
from hoseline.procedures.placement.twist_path import follow_twist
from hoseline.procedures.scans.deviation import closest_on_polyline

RETURN_TOLERANCE = 1e-3  # a joint may exceed the friction threshold by this fraction of it
RETURN_ITERATIONS = 500  # equilibrium-and-return rounds allowed per twist step (each takes about 8 % off the excess)
RETURN_CORRECTIONS = 2  # fixed-point steps that put a returned joint exactly on the threshold (returned_rest)
UNIDENTIFIED_RELATIVE_STD = 0.25  # a threshold less certain than this is not identified
BAND_OVER_SCATTER = 3.0  # a measured band is a band when its mean exceeds this many RMS residuals of the fit


@dataclass
class HysteresisBand:
    """The hose twisted up and down.

    twists_deg: (k,) the twists where both shapes are known, degrees, increasing from 0.
    loading, unloading: (k, N+1, 3) station positions on the way up and on the way down, mm.
    band: (k, N+1) distance between the two at each station, mm.
    events: the continuation's log (snaps met on the way).  failure: why the path stopped early
    ("" when it went up and came back to 0; else twists_deg holds only the angles reached both ways).
    """

    twists_deg: np.ndarray
    loading: np.ndarray
    unloading: np.ndarray
    band: np.ndarray
    events: list[str] = field(default_factory=list)
    failure: str = ""

    @property
    def width(self) -> np.ndarray:
        """(k,) the largest station distance at each twist, mm."""
        return self.band.max(axis=1)


def hysteresis_band(
    problem: Problem, largest_twist_deg: float, step_deg: float = 10.0, friction_threshold: float | None = None
) -> HysteresisBand:
    """Twist the placed hose of `problem` from 0 to largest_twist_deg and back (degrees, steps of step_deg).

    friction_threshold: None for the elastic model, else the joints' friction threshold, N*mm
    (module doc).  The problem's own end twist is ignored.  Raises ValueError for a step that is
    not positive or a largest twist that is not a positive multiple of it (the two ways meet at
    the same angles).
    """
    up = _twist_grid(largest_twist_deg, step_deg)
    count = up.size - 1
    if friction_threshold is None:
        path = follow_twist(problem, np.concatenate([up, up[-2::-1]]), "up and down")
        lines, events, failure = path.centerlines, path.events, path.failure
    else:
        lines, failure = friction_path(problem, friction_threshold, np.concatenate([up, up[-2::-1]]))
        events = []
    # shape i of the path is at up[i] on the way up (i <= count), at up[2 count - i] on the way down
    first = max(2 * count - (len(lines) - 1), 0)  # the smallest angle reached both ways
    kept = np.arange(first, count + 1)  # empty when the path stopped on the way up
    loading, unloading = lines[kept], lines[2 * count - kept]
    band = np.linalg.norm(loading - unloading, axis=2)
    return HysteresisBand(up[kept], loading, unloading, band, events, failure)


def _twist_grid(largest_twist_deg: float, step_deg: float) -> np.ndarray:
    """0, step, ..., largest (degrees); ValueError unless largest is a non-zero multiple of a positive step."""
    if not step_deg > 0.0:
        raise ValueError(f"step_deg = {step_deg!r}: must be a positive number of degrees")
    count = round(abs(largest_twist_deg) / step_deg)
    if count < 1 or abs(count * step_deg - abs(largest_twist_deg)) > 1e-9 * step_deg:
        raise ValueError(f"largest_twist_deg = {largest_twist_deg!r}: must be a non-zero multiple of "
                         f"step_deg = {step_deg!r}")
    return np.linspace(0.0, largest_twist_deg, count + 1)


def joint_deviation(props: RodProperties, start_frame, frames, end_frame, rest) -> tuple[np.ndarray, np.ndarray]:
    """(Q (N+1,3,3), e (N+1,3)): each joint's relative rotation Q = A B^T and the Darboux vector (1/mm,
    material) of what is left of it after its stress-free rotation R0 = H H, H^T Q H^T (mechanics/energy.py)."""
    before = np.concatenate([start_frame[None], frames])
    after = np.concatenate([frames, end_frame[None]])
    relative = np.einsum("jkx,jlx->jkl", before, after)
    left = _left_over(rest, relative)
    axial = np.stack([left[:, 2, 1] - left[:, 1, 2], left[:, 0, 2] - left[:, 2, 0], left[:, 1, 0] - left[:, 0, 1]],
                     axis=1)
    lengths = np.full(len(left), props.segment_length)
    lengths[[0, -1]] = 0.5 * props.segment_length
    c = 1.0 + np.trace(left, axis1=1, axis2=2)
    return relative, 2.0 * axial / (c * lengths)[:, None]


def _left_over(rest: np.ndarray, relative: np.ndarray) -> np.ndarray:
    """(K, 3, 3): what is left of each joint's relative rotation Q after its stress-free rotation R0 = H H, split
    evenly as the energy does (mechanics/energy.py): H^T Q H^T."""
    half = Rotation.from_rotvec(0.5 * Rotation.from_matrix(rest).as_rotvec()).as_matrix()
    return np.einsum("jmk,jml,jnl->jkn", half, relative, half)


def returned_rest(
    props: RodProperties, start_frame, frames, end_frame, rest, threshold: float
) -> tuple[np.ndarray, float]:
    """(stress-free rotations after the return, largest excess moment before it, N*mm).

    Every joint whose moment K e exceeds `threshold` (N*mm) in magnitude gets the stress-free
    rotation R0 = Q C(e')^T, where C(e') is the rotation of Darboux vector e' = e threshold / |K e|
    (model/preset.rest_rotations): its moment is brought back radially onto the threshold.  (The energy splits
    R0 evenly, H^T Q H^T with R0 = H H: what is left is then C(e') turned by H, the same angle about an axis
    turned by half the joint's set, so the moment's size is the threshold's to within that turn's effect on an
    anisotropic K, O(h kappa).)
    """
    relative, deviation = joint_deviation(props, start_frame, frames, end_frame, rest)
    moment = np.linalg.norm(deviation * props.stiffness, axis=1)
    over = moment > threshold
    if not np.any(over):
        return rest, float(np.max(moment) - threshold)
    kept = deviation * np.where(over, threshold / np.maximum(moment, 1e-300), 1.0)[:, None]
    wanted = Rotation.from_matrix(rest_rotations(kept, props.segment_length)[over]).as_rotvec()
    # R0 = exp(a) with H^T Q H^T = C(e'): a = log Q - log C to second order (the even split has no commutator
    # term); RETURN_CORRECTIONS fixed-point steps on the rotation vector left over make it exact to rounding
    turn = Rotation.from_matrix(relative[over]).as_rotvec() - wanted
    for _ in range(RETURN_CORRECTIONS):
        left = _left_over(Rotation.from_rotvec(turn).as_matrix(), relative[over])
        turn = turn - (wanted - Rotation.from_matrix(left).as_rotvec())
    new_rest = rest.copy()
    new_rest[over] = Rotation.from_rotvec(turn).as_matrix()
    return new_rest, float(np.max(moment) - threshold)


def friction_path(problem: Problem, threshold: float, twists_deg: np.ndarray) -> tuple[np.ndarray, str]:
    """Centrelines (k, N+1, 3), mm, of the friction model along `twists_deg` (degrees, from 0), and a failure message.

    threshold: the joints' friction threshold, N*mm (module doc).  Each twist step solves the
    equilibrium, returns the joints over the threshold, and repeats until none is over it by
    more than RETURN_TOLERANCE of it.  The path stops at a step that does not converge (the
    message says where); the elastic model's fold handling is not available here.
    """
    if not (math.isfinite(threshold) and threshold > 0.0):
        raise ValueError(f"friction threshold = {threshold!r}: must be a positive number of N*mm")
    if problem.clips:
        raise ValueError("the friction model of a problem with clips is not supported")
    placed = solve(replace(problem, end_twist_deg=0.0), estimate_error=False)
    props = rod_properties(problem)
    rest = props.rest if props.rest is not None else np.tile(np.eye(3), (props.segments + 1, 1, 1))
    path = PlacementPath(problem)
    state = RodState(placed.frames, placed.end_force)
    lines = []
    for twist in twists_deg:
        clamps = path.twisted(placed.end_frame, float(twist))
        for _ in range(RETURN_ITERATIONS):
            state, report = solve_equilibrium(replace(props, rest=rest), clamps, state)
            if not (report.converged and report.unstable_directions == 0):
                return np.stack(lines) if lines else np.zeros((0, props.segments + 1, 3)), (
                    f"friction model: no stable equilibrium at {twist:g} deg ({report.message or 'unstable'})")
            rest, excess = returned_rest(props, clamps.start_frame, state.frames, clamps.end_frame, rest, threshold)
            if excess <= RETURN_TOLERANCE * threshold:
                break
        else:
            return np.stack(lines) if lines else np.zeros((0, props.segments + 1, 3)), (
                f"friction model: the joints do not settle at the threshold at {twist:g} deg "
                f"({RETURN_ITERATIONS} rounds)")
        lines.append(node_positions(props, clamps, state))
    return np.stack(lines), ""


@dataclass(frozen=True)
class TwistScan:
    """A scan of the hose at a twist (degrees) reached on the way up (unloading False) or down; stations (n, 3), mm."""

    twist_deg: float
    unloading: bool
    points: np.ndarray


@dataclass
class FrictionFit:
    """The fitted friction threshold (N*mm), its standard uncertainty (None if not identified), why not, the band."""

    threshold: float
    std: float | None
    identified: bool
    note: str
    band: HysteresisBand


def fit_friction_threshold(
    problem: Problem, scans: list[TwistScan], largest_twist_deg: float, step_deg: float, initial: float
) -> FrictionFit:
    """Least-squares fit of the friction threshold (N*mm, around `initial`) to scans on the way up and down.

    The model is twisted 0 -> largest_twist_deg -> 0 in steps of step_deg (degrees); every scan's
    twist must be on that grid.  Residuals: scan stations to the closest model point, mm.  The
    threshold (in logarithm, within 1/100 and 100 times `initial`) starts from the best of a grid
    from initial/10 to 10 initial: above every joint moment of the path the model is elastic and
    the residual flat, so a local start there would not move.  Identified only when the scans
    themselves show a band: scans at the same twist on the way up and down further apart (mean
    station distance) than BAND_OVER_SCATTER times the fit's RMS residual, the threshold not at a
    bound, and its relative uncertainty at most UNIDENTIFIED_RELATIVE_STD.
    """
    up = _twist_grid(largest_twist_deg, step_deg)
    count = up.size - 1
    twists = np.concatenate([up, up[-2::-1]])
    indices = []
    for scan in scans:
        matches = np.flatnonzero(np.isclose(up, scan.twist_deg, atol=1e-9))
        if matches.size == 0:
            raise ValueError(f"scan at {scan.twist_deg:g} deg: not on the model's twist grid "
                             f"(steps of {step_deg:g} deg up to {largest_twist_deg:g}); choose step_deg so every "
                             "scan twist is a multiple of it")
        indices.append(2 * count - matches[0] if scan.unloading else matches[0])

    def residuals(x: np.ndarray) -> np.ndarray:
        lines, failure = friction_path(problem, initial * math.exp(x[0]), twists)
        if failure:
            return np.full(sum(3 * scan.points.shape[0] for scan in scans), 1e3)  # an unsolvable model: a poor fit
        return np.concatenate([(scan.points - closest_on_polyline(scan.points, lines[i])[2]).ravel()
                               for scan, i in zip(scans, indices)])

    bound = math.log(100.0)
    grid = np.linspace(-math.log(10.0), math.log(10.0), 9)
    start = grid[int(np.argmin([float(np.sum(residuals(np.array([x])) ** 2)) for x in grid]))]
    solution = least_squares(residuals, np.array([start]), bounds=(-bound, bound), diff_step=1e-3, x_scale=1.0)
    threshold = initial * math.exp(solution.x[0])
    observations = sum(2 * scan.points.shape[0] for scan in scans)  # two directions across the hose per station
    variance = float(solution.fun @ solution.fun) / max(observations - 1, 1)
    slope = float(solution.jac[:, 0] @ solution.jac[:, 0])
    relative_std = math.sqrt(variance / slope) if slope > 0.0 else math.inf
    scatter = math.sqrt(float(solution.fun @ solution.fun) / solution.fun.size)  # RMS residual component, mm
    measured = measured_band(scans)
    if measured is None:
        note = "needs scans at the same twist on the way up and on the way down"
    elif measured < BAND_OVER_SCATTER * scatter:
        note = (f"the scans show no band: up and down {measured:.3g} mm apart, within {BAND_OVER_SCATTER:g} "
                f"times their scatter ({scatter:.3g} mm); the hose behaves elastically as far as these scans tell")
    elif bound - abs(solution.x[0]) < 0.05:
        note = f"at its bound ({threshold:.4g} N*mm, 100x from the initial): the fit failed"
    elif relative_std > UNIDENTIFIED_RELATIVE_STD:
        note = "not determined by these scans (relative uncertainty above 25 %)"
    else:
        note = ""
    band = hysteresis_band(problem, largest_twist_deg, step_deg, friction_threshold=threshold)
    return FrictionFit(threshold, None if note else threshold * relative_std, not note, note, band)


def measured_band(scans: list[TwistScan]) -> float | None:
    """The largest, over twists scanned both ways, of the mean distance (mm) from the stations of the scan on
    the way down to the polyline of the one on the way up; None without such a pair."""
    bands = [float(np.mean(closest_on_polyline(down.points, up.points)[0]))
             for up in scans if not up.unloading
             for down in scans if down.unloading and abs(down.twist_deg - up.twist_deg) < 1e-9]
    return max(bands) if bands else None
